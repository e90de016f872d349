"""A lean batch runner: many runs of the FMU through one reused instance.

Every run goes through the FMU's own FMI 2.0 functions (fmi2Reset, fmi2SetupExperiment,
fmi2SetReal/Integer/Boolean, fmi2Enter/ExitInitializationMode, one fmi2DoStep to the stop time,
fmi2GetReal/Integer of the in-FMU observables). The functions are the ones fmpy loaded from the
FMU's shared library (``FMU2Slave``), re-typed here to take raw addresses so that each run passes
rows of pre-built numpy arrays instead of building ctypes arrays: about 10 microseconds of Python
per run instead of about 100 (see ``scripts/bench_sweep.py``).

The observables are the FMU's (``observe = true`` with the window ``t_obs_start``..``t_obs_stop``):
no trajectory is sampled, a run is one doStep.
"""

from __future__ import annotations

import atexit
import ctypes
import hashlib
import os
import tempfile
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ..fmu import SCHEMES, FMUError, OscillatorFMU

__all__ = [
    "PARAM_COLUMNS",
    "REAL_OUTPUTS",
    "OUTPUT_COLUMNS",
    "BatchRunner",
    "runner_for",
    "run_batch",
    "run_batch_timed",
]

#: Per-run real inputs, in the order of the columns of a parameter table. ``t_stop`` is the
#: communication point of the single doStep; the others are FMU variables.
PARAM_COLUMNS: tuple[str, ...] = (
    "m", "k", "c", "P0", "omega", "phi", "N", "mu_s", "chi", "x0", "v0",
    "h", "alpha", "t_obs_start", "t_obs_stop", "t_stop",
)
#: Real observables read after the run.
REAL_OUTPUTS: tuple[str, ...] = ("x_max", "x_min", "stick_fraction", "E_friction")
#: Columns of a result table: the real observables, then ``transitions`` and ``status``
#: (0: ok, 1: the FMU reported an error; the observables are then nan).
OUTPUT_COLUMNS: tuple[str, ...] = REAL_OUTPUTS + ("transitions", "status")

_FMI_OK_OR_WARNING = 1  # fmi2OK = 0, fmi2Warning = 1


class BatchRunner:
    """One instantiated FMU that runs parameter tables, row by row, through the FMI functions.

    Not thread-safe: one per process (Dask worker processes each hold their own, see
    :func:`runner_for`).
    """

    def __init__(self, fmu_path: str | os.PathLike[str], settings: Mapping[str, Any] | None = None) -> None:
        self.fmu = OscillatorFMU(fmu_path)
        self.path = self.fmu.path
        slave = self.fmu.slave
        self._c = slave.component
        dll = slave.dll
        vp, sz, dbl, i32 = ctypes.c_void_p, ctypes.c_size_t, ctypes.c_double, ctypes.c_int

        def fn(name: str, *argtypes: Any) -> Any:
            f = dll[name]  # a fresh function pointer: fmpy's own, typed copies stay untouched
            f.argtypes = [vp, *argtypes]
            f.restype = i32
            return f

        self._reset = fn("fmi2Reset")
        self._setup = fn("fmi2SetupExperiment", i32, dbl, dbl, i32, dbl)
        self._set_real = fn("fmi2SetReal", vp, sz, vp)
        self._set_int = fn("fmi2SetInteger", vp, sz, vp)
        self._set_bool = fn("fmi2SetBoolean", vp, sz, vp)
        self._enter = fn("fmi2EnterInitializationMode")
        self._exit = fn("fmi2ExitInitializationMode")
        self._do_step = fn("fmi2DoStep", dbl, dbl, i32)
        self._get_real = fn("fmi2GetReal", vp, sz, vp)
        self._get_int = fn("fmi2GetInteger", vp, sz, vp)

        vr = self.fmu.vr
        self._param_vr = np.array([vr(n) for n in PARAM_COLUMNS[:-1]], dtype=np.uint32)
        self._out_vr = np.array([vr(n) for n in REAL_OUTPUTS], dtype=np.uint32)
        self._trans_vr = np.array([vr("transitions")], dtype=np.uint32)
        self._int_vr = np.array([vr("scheme"), vr("frictionUpdates")], dtype=np.uint32)
        self._bool_vr = np.array([vr("observe"), vr("fastPaths")], dtype=np.uint32)
        self._ints = np.zeros(2, dtype=np.int32)
        self._bools = np.zeros(2, dtype=np.int32)  # fmi2Boolean is int
        self._out = np.zeros(len(REAL_OUTPUTS))
        self._trans = np.zeros(1, dtype=np.int32)
        self.configure(settings or {})

    def configure(self, settings: Mapping[str, Any]) -> None:
        """The settings shared by all runs: scheme, frictionUpdates, fastPaths (observe is on)."""
        scheme = settings.get("scheme", "located")
        if isinstance(scheme, str):
            if scheme not in SCHEMES:
                raise ValueError(f"scheme must be one of {', '.join(SCHEMES)}, not {scheme!r}")
            scheme = SCHEMES[scheme]
        self._ints[:] = (int(scheme), int(settings.get("frictionUpdates", 1)))
        self._bools[:] = (1, 1 if settings.get("fastPaths", True) else 0)

    def close(self) -> None:
        self.fmu.close()

    def _fail(self, n_messages: int, what: str) -> FMUError:
        errors = [m for s, _, m in self.fmu.messages[n_messages:] if s >= 3]
        del self.fmu.messages[n_messages:]
        return FMUError(errors[-1] if errors else f"{what} failed")

    def run(self, params: np.ndarray, strict: bool = False) -> np.ndarray:
        """Run every row of ``params`` (columns :data:`PARAM_COLUMNS`); returns a float array with
        columns :data:`OUTPUT_COLUMNS`. A run the FMU rejects gets nan observables and status 1
        (``strict``: raise :class:`FMUError` instead)."""
        P = np.ascontiguousarray(params, dtype=np.float64)
        if P.ndim != 2 or P.shape[1] != len(PARAM_COLUMNS):
            raise ValueError(f"params must have shape (n, {len(PARAM_COLUMNS)})")
        n = P.shape[0]
        res = np.empty((n, len(OUTPUT_COLUMNS)))
        c = self._c
        reset, setup, set_real, set_int, set_bool = (self._reset, self._setup, self._set_real,
                                                     self._set_int, self._set_bool)
        enter, exit_, do_step, get_real, get_int = (self._enter, self._exit, self._do_step,
                                                    self._get_real, self._get_int)
        npar = len(PARAM_COLUMNS) - 1
        vr_p = self._param_vr.ctypes.data
        vr_i, ints = self._int_vr.ctypes.data, self._ints.ctypes.data
        vr_b, bools = self._bool_vr.ctypes.data, self._bools.ctypes.data
        vr_o, out = self._out_vr.ctypes.data, self._out.ctypes.data
        vr_t, trans = self._trans_vr.ctypes.data, self._trans.ctypes.data
        nout = len(REAL_OUTPUTS)
        base, stride = P.ctypes.data, P.strides[0]
        t_stops = P[:, -1].tolist()
        msgs = self.fmu.messages
        for i in range(n):
            mark = len(msgs)
            row = base + i * stride
            ok = (reset(c) <= _FMI_OK_OR_WARNING
                  and setup(c, 0, 0.0, 0.0, 0, 0.0) <= _FMI_OK_OR_WARNING
                  and set_real(c, vr_p, npar, row) <= _FMI_OK_OR_WARNING
                  and set_int(c, vr_i, 2, ints) <= _FMI_OK_OR_WARNING
                  and set_bool(c, vr_b, 2, bools) <= _FMI_OK_OR_WARNING
                  and enter(c) <= _FMI_OK_OR_WARNING
                  and exit_(c) <= _FMI_OK_OR_WARNING
                  and do_step(c, 0.0, t_stops[i], 1) <= _FMI_OK_OR_WARNING
                  and get_real(c, vr_o, nout, out) <= _FMI_OK_OR_WARNING
                  and get_int(c, vr_t, 1, trans) <= _FMI_OK_OR_WARNING)
            if ok:
                res[i, :nout] = self._out
                res[i, nout] = self._trans[0]
                res[i, nout + 1] = 0.0
            else:
                err = self._fail(mark, f"run {i}")
                if strict:
                    raise err
                res[i, :nout + 1] = np.nan
                res[i, nout + 1] = 1.0
            if len(msgs) > mark:  # warnings: keep the list from growing over a long sweep
                del msgs[mark:]
        return res


# ---- one runner per process (Dask workers) ---------------------------------------------------

_RUNNERS: dict[str, BatchRunner] = {}


def _materialise(fmu: str | bytes) -> str:
    """A local path of the FMU: the path itself, or the bytes written once to a temp file named
    by their hash (for workers on other machines)."""
    if isinstance(fmu, str):
        return fmu
    digest = hashlib.sha256(fmu).hexdigest()[:16]
    path = Path(tempfile.gettempdir()) / f"dfo-sweep-{digest}.fmu"
    if not path.is_file():
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_bytes(fmu)
        os.replace(tmp, path)
    return str(path)


@atexit.register
def _close_runners() -> None:
    """Free the instances and remove their unzipped FMUs when the process ends."""
    while _RUNNERS:
        _, r = _RUNNERS.popitem()
        try:
            r.close()
        except Exception:  # noqa: BLE001 - best effort at exit
            pass


def runner_for(fmu: str | bytes) -> BatchRunner:
    """The process-wide runner of this FMU (loaded and instantiated on first use)."""
    key = fmu if isinstance(fmu, str) else hashlib.sha256(fmu).hexdigest()
    r = _RUNNERS.get(key)
    if r is None:
        r = _RUNNERS[key] = BatchRunner(_materialise(fmu))
    return r


def run_batch(fmu: str | bytes, settings: Mapping[str, Any], params: np.ndarray) -> np.ndarray:
    """Task body: run a parameter table on this process's FMU instance."""
    r = runner_for(fmu)
    r.configure(settings)
    return r.run(params)


def run_batch_timed(fmu: str | bytes, settings: Mapping[str, Any], params: np.ndarray) -> tuple[np.ndarray, float, float]:
    """:func:`run_batch` plus the task's CPU and wall seconds (for the sweep's statistics)."""
    c0, w0 = time.process_time(), time.perf_counter()
    out = run_batch(fmu, settings, params)
    return out, time.process_time() - c0, time.perf_counter() - w0
