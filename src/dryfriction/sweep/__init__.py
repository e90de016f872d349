"""Sweeps of the FMU on Dask: lean batch runner, chunked engine with restart, labelled datasets."""

from .datasets import observables_dataset, read_netcdf, write_netcdf
from .engine import Engine, EngineOptions, SweepInterrupted, SweepSpec, SweepStats
from .runner import OUTPUT_COLUMNS, PARAM_COLUMNS, BatchRunner, run_batch
from .table import nondim_table

__all__ = [
    "BatchRunner",
    "Engine",
    "EngineOptions",
    "OUTPUT_COLUMNS",
    "PARAM_COLUMNS",
    "SweepInterrupted",
    "SweepSpec",
    "SweepStats",
    "nondim_table",
    "observables_dataset",
    "read_netcdf",
    "run_batch",
    "write_netcdf",
]
