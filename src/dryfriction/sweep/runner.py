"""A lean batch runner: many runs of the FMU through one reused instance.

Every run goes through the FMU's own FMI 2.0 functions (fmi2Reset, fmi2SetupExperiment,
fmi2SetReal/Integer/Boolean, fmi2Enter/ExitInitializationMode, one fmi2DoStep to the stop time,
fmi2GetReal/Integer of the in-FMU observables), called through the package's one FMI layer
(:mod:`dryfriction.fmi.fmi2`, the instance of an :class:`~dryfriction.drivers.oscillator.OscillatorFMU2`): each run
passes rows of pre-built numpy arrays by address instead of building ctypes arrays, about 10
microseconds of Python per run (see ``bench/host_overhead.py``), and every status is checked.

The observables are the FMU's (``observe = true`` with the window ``t_obs_start``..``t_obs_stop``):
no trajectory is sampled, a run is one doStep.
"""

from __future__ import annotations

import atexit
import hashlib
import os
import tempfile
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any, Generic, TypeVar

import numpy as np

from .. import model
from ..atomic import atomic_write_bytes
from ..errors import FMUError
from ..drivers.oscillator import OscillatorFMU2

__all__ = [
    "PARAM_COLUMNS",
    "REAL_OUTPUTS",
    "OUTPUT_COLUMNS",
    "BatchRunner",
    "runner_for",
    "run_batch",
    "run_batch_timed",
]

#: Per-run real inputs, in the order of the columns of a parameter table: the Real parameters of
#: the model description, in its order, then ``t_stop``, the communication point of the single
#: doStep.
PARAM_COLUMNS: Sequence[str] = model.LazySequence(lambda: tuple(
    n for n, v in model.default().variables.items() if v.causality == "parameter" and v.type == "Real") + ("t_stop",))
#: Real observables read after the run.
REAL_OUTPUTS: tuple[str, ...] = ("x_max", "x_min", "stick_fraction", "E_friction")
#: Columns of a result table: the real observables, then ``transitions`` and ``status``
#: (0: ok, 1: the FMU reported an error; the observables are then nan).
OUTPUT_COLUMNS: tuple[str, ...] = REAL_OUTPUTS + ("transitions", "status")


class BatchRunner:
    """One instantiated FMU that runs parameter tables, row by row, through the FMI functions.

    Not thread-safe: one per process (Dask worker processes each hold their own, see
    :func:`runner_for`).
    """

    def __init__(self, fmu_path: str | os.PathLike[str], settings: Mapping[str, Any] | None = None) -> None:
        self.fmu = OscillatorFMU2(fmu_path)
        self.path = self.fmu.path
        self.md = self.fmu.md
        vr = self.md.vr
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
        md = self.md
        scheme = md.scheme_value(settings.get("scheme", md.var("scheme").start))
        updates = settings.get("frictionUpdates", md.var("frictionUpdates").start)
        md.check("frictionUpdates", updates)
        self._ints[:] = (scheme, int(updates))
        self._bools[:] = (1, 1 if settings.get("fastPaths", md.var("fastPaths").start) else 0)

    def close(self) -> None:
        """Free the FMU instance."""
        self.fmu.close()

    def run(self, params: np.ndarray, strict: bool = False) -> np.ndarray:
        """Run every row of ``params`` (columns :data:`PARAM_COLUMNS`); returns a float array with
        columns :data:`OUTPUT_COLUMNS`. A run the FMU rejects gets nan observables and status 1
        (``strict``: raise :class:`FMUError` instead)."""
        P = np.ascontiguousarray(params, dtype=np.float64)
        if P.ndim != 2 or P.shape[1] != len(PARAM_COLUMNS):
            raise ValueError(f"params must have shape (n, {len(PARAM_COLUMNS)})")
        n = P.shape[0]
        res = np.empty((n, len(OUTPUT_COLUMNS)))
        inst = self.fmu.fmi
        c, f, check = inst.component, inst.f, inst.check
        reset, setup, set_real, set_int, set_bool = f.Reset, f.SetupExperiment, f.SetReal, f.SetInteger, f.SetBoolean
        enter, exit_, do_step, get_real, get_int = (f.EnterInitializationMode, f.ExitInitializationMode, f.DoStep,
                                                    f.GetReal, f.GetInteger)
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
            # every status is looked at; a non-zero one goes to check(), which passes a warning
            # and raises FMUError (function, status, the FMU's sentence) otherwise
            try:
                if s := reset(c):
                    check("fmi2Reset", s, mark)
                if s := setup(c, 0, 0.0, 0.0, 0, 0.0):
                    check("fmi2SetupExperiment", s, mark)
                if s := set_real(c, vr_p, npar, row):
                    check("fmi2SetReal", s, mark)
                if s := set_int(c, vr_i, 2, ints):
                    check("fmi2SetInteger", s, mark)
                if s := set_bool(c, vr_b, 2, bools):
                    check("fmi2SetBoolean", s, mark)
                if s := enter(c):
                    check("fmi2EnterInitializationMode", s, mark)
                if s := exit_(c):
                    check("fmi2ExitInitializationMode", s, mark)
                if s := do_step(c, 0.0, t_stops[i], 1):
                    check("fmi2DoStep", s, mark)
                if s := get_real(c, vr_o, nout, out):
                    check("fmi2GetReal", s, mark)
                if s := get_int(c, vr_t, 1, trans):
                    check("fmi2GetInteger", s, mark)
            except FMUError as err:
                del msgs[mark:]
                if strict:
                    raise FMUError(f"run {i}: {err.message}", err.function, err.status) from None
                res[i, :nout + 1] = np.nan
                res[i, nout + 1] = 1.0
                continue
            res[i, :nout] = self._out
            res[i, nout] = self._trans[0]
            res[i, nout + 1] = 0.0
            if len(msgs) > mark:  # warnings: keep the list from growing over a long sweep
                del msgs[mark:]
        return res


# ---- one runner per process (Dask workers) ---------------------------------------------------

def _materialise(fmu: str | bytes) -> str:
    """A local path of the FMU: the path itself, or the bytes written once to a temp file named
    by their hash (for workers on other machines)."""
    if isinstance(fmu, str):
        return fmu
    digest = hashlib.sha256(fmu).hexdigest()[:16]
    path = Path(tempfile.gettempdir()) / f"dfo-sweep-{digest}.fmu"
    if not path.is_file():
        atomic_write_bytes(path, fmu)
    return str(path)


T = TypeVar("T")


class PerProcess(Generic[T]):
    """One object per FMU in this process (a Dask worker), made on first use from the FMU's local
    path (``fmu`` given as a path or as the FMU's bytes), closed when the process ends."""

    def __init__(self, factory: Callable[[str], T]) -> None:
        self._factory = factory
        self._items: dict[str, T] = {}
        atexit.register(self.close_all)

    def get(self, fmu: str | bytes) -> T:
        """The process's object for this FMU (a path or the binary's bytes), made on first use."""
        key = fmu if isinstance(fmu, str) else hashlib.sha256(fmu).hexdigest()
        item = self._items.get(key)
        if item is None:
            item = self._items[key] = self._factory(_materialise(fmu))
        return item

    def close_all(self) -> None:
        """Free the instances and remove their unzipped FMUs (best effort: at exit)."""
        while self._items:
            _, item = self._items.popitem()
            try:
                item.close()  # type: ignore[attr-defined]
            except Exception:  # noqa: BLE001 - best effort at exit
                pass


_RUNNERS: PerProcess[BatchRunner] = PerProcess(BatchRunner)


def runner_for(fmu: str | bytes) -> BatchRunner:
    """The process-wide runner of this FMU (loaded and instantiated on first use)."""
    return _RUNNERS.get(fmu)


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
