"""Labelled results: sweep outputs as xarray datasets, written atomically to NetCDF.

Displacements are non-dimensional, z = k x / P0 (method.md (2)); the mean amplitude and the
asymmetry of method.md section 6 are (z_max - z_min) / 2 and (z_max + z_min) / 2.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from ..atomic import atomic_write_bytes
from .runner import OUTPUT_COLUMNS

__all__ = ["observables_dataset", "write_netcdf", "read_netcdf"]

_ATTRS = {
    "z_max": ("largest z = k x / P0 in the observation window", "1"),
    "z_min": ("smallest z = k x / P0 in the observation window", "1"),
    "amplitude": ("mean amplitude (z_max - z_min) / 2", "1"),
    "asymmetry": ("asymmetry (z_max + z_min) / 2", "1"),
    "stick_fraction": ("share of the observation window spent stuck", "1"),
    "stiction_percent": ("time stuck in the observation window, percent of its length", "%"),
    "transitions": ("number of stick/slip mode changes in the observation window", "1"),
    "e_friction": ("energy dissipated by friction in the window, over P0^2 / k", "1"),
    "status": ("0: run ok; 1: the FMU reported an error (observables nan)", "1"),
}


def observables_dataset(
    out: np.ndarray,
    coords: Mapping[str, Sequence[float] | np.ndarray],
    k: float = 100.0,
    P0: float = 1.0,
    attrs: Mapping[str, Any] | None = None,
) -> xr.Dataset:
    """Dataset of a sweep's outputs (rows in C order of ``coords``) on the grid ``coords``."""
    dims = tuple(coords)
    shape = tuple(len(np.asarray(coords[d])) for d in dims)
    if int(np.prod(shape)) != out.shape[0]:
        raise ValueError(f"{out.shape[0]} runs do not fill a grid of shape {shape}")
    col = {n: out[:, i].reshape(shape) for i, n in enumerate(OUTPUT_COLUMNS)}
    scale = k / P0
    z_max = col["x_max"] * scale
    z_min = col["x_min"] * scale
    data = {
        "z_max": z_max,
        "z_min": z_min,
        "amplitude": 0.5 * (z_max - z_min),
        "asymmetry": 0.5 * (z_max + z_min),
        "stick_fraction": col["stick_fraction"],
        "transitions": col["transitions"],
        "e_friction": col["E_friction"] * k / (P0 * P0),
        "status": col["status"].astype(np.int8),
    }
    ds = xr.Dataset(
        {n: (dims, v, {"long_name": _ATTRS[n][0], "units": _ATTRS[n][1]}) for n, v in data.items()},
        coords={d: np.asarray(coords[d], dtype=float) for d in dims},
    )
    if attrs:
        ds.attrs.update(attrs)
    return ds


def _clean_attrs(attrs: Mapping[str, Any]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, v in attrs.items():
        if isinstance(v, bool):
            out[key] = int(v)
        elif isinstance(v, (list, tuple)):
            out[key] = np.asarray(v)
        elif isinstance(v, dict):
            out[key] = repr(v)
        else:
            out[key] = v
    return out


def write_netcdf(ds: xr.Dataset, path: str | os.PathLike[str]) -> Path:
    """Write ``ds`` to ``path`` (NetCDF-4 via h5netcdf): serialised in memory first, then its bytes
    to a temp file and a rename. A full disk or an unwritable folder is an :class:`OSError` of one
    line naming the file and the cause (HDF5 never writes to the disk, so it cannot fail there),
    and an earlier ``path`` is left as it was."""
    path = Path(path)
    ds = ds.copy()
    ds.attrs = _clean_attrs(ds.attrs)
    for v in ds.variables.values():
        v.attrs = _clean_attrs(v.attrs)
    data = _netcdf_bytes(ds)
    try:
        atomic_write_bytes(path, data)
    except OSError as e:
        raise OSError(f"cannot write {path}: {e.strerror or e}") from None
    return path


def _netcdf_bytes(ds: xr.Dataset) -> bytes:
    """The NetCDF-4 file of ``ds`` as bytes, built in memory by h5netcdf (an HDF5 file on a
    BytesIO: xarray's own ``to_netcdf(None, engine="h5netcdf")`` exists only in its newest
    releases)."""
    import io

    import dask
    import h5netcdf
    from xarray.backends import H5NetCDFStore

    buf = io.BytesIO()
    with dask.config.set(scheduler="synchronous"):  # a live Dask client's locks are not for bytes in memory
        store = H5NetCDFStore(h5netcdf.File(buf, "w"), mode="w")
        try:
            ds.dump_to_store(store)
        finally:
            store.close()
    return buf.getvalue()


def read_netcdf(path: str | os.PathLike[str]) -> xr.Dataset:
    """Load a dataset fully into memory (the file is closed on return)."""
    with xr.open_dataset(path, engine="h5netcdf") as ds:
        return ds.load()
