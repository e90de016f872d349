"""A fast fmpy driver for the DryFrictionOscillator FMU.

The FMU is unzipped and instantiated once; every run then costs only reset, setup, the parameter
values and the steps (method used by fmpy's ``simulate_fmu(..., fmu_instance=...)``, without its
per-call bookkeeping). Errors of the FMU are raised as :class:`FMUError` with the FMU's own logged
sentence.
"""

from __future__ import annotations

import ctypes
import os
import shutil
import tempfile
import threading
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)
from fmpy.fmi1 import calloc, free

from .params import Oscillator

SCHEMES = {"paper": 1, "consistent": 2, "located": 3, "exact": 4}
TRAJECTORY_OUTPUTS = ("x", "v", "a", "F_friction", "mode")
OBSERVABLE_OUTPUTS = ("x_max", "x_min", "stick_fraction", "transitions", "E_friction")
EFFECT_BITS = {
    1: "friction LCP",
    2: "coefficient update",
    4: "damping",
    8: "input F_ext",
    16: "input N_ext",
    32: "observables",
}


_LOAD_LOCK = threading.Lock()


class FMUError(RuntimeError):
    """An FMI call returned an error; the message is the FMU's logged sentence."""


def default_fmu_path() -> Path:
    """The FMU built by CMake (``DFO_FMU`` overrides)."""
    env = os.environ.get("DFO_FMU")
    if env:
        return Path(env)
    return Path(__file__).resolve().parents[2] / "build" / "DryFrictionOscillator.fmu"


@dataclass
class Settings:
    """Numerical and scene settings of one run (FMU variable names)."""

    h: float | None = None            # internal step, s (None: period / 1000)
    alpha: float = -0.1
    scheme: str = "located"
    frictionUpdates: int = 1
    observe: bool = False
    t_obs_start: float = 0.0
    t_obs_stop: float = 1e300
    fastPaths: bool = True
    extra: dict[str, Any] = field(default_factory=dict)


class OscillatorFMU:
    """One loaded, instantiated FMU, reused across runs (not thread-safe: one per thread/worker)."""

    def __init__(self, fmu_path: str | os.PathLike[str] | None = None, logging: bool = False) -> None:
        path = Path(fmu_path) if fmu_path is not None else default_fmu_path()
        if not path.is_file():
            raise FileNotFoundError(f"FMU not found: {path} (build it with: cmake -S . -B build && cmake --build build)")
        self.path = path
        self.md = read_model_description(str(path))
        self._dir = extract(str(path), unzipdir=tempfile.mkdtemp(prefix="dfo-fmu-"))
        self.vars = {v.name: v for v in self.md.modelVariables}
        self.messages: list[tuple[int, str, str]] = []
        # keep the ctypes callbacks alive as long as the instance
        self._callbacks = fmi2CallbackFunctions()
        self._callbacks.logger = fmi2CallbackLoggerTYPE(self._log)
        self._callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self._callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        # fmpy's loader changes the process's working directory while it loads the library, so
        # loading is serialised (instances load from threads too); the instances themselves are
        # independent
        with _LOAD_LOCK:
            self.slave = FMU2Slave(
                guid=self.md.guid,
                unzipDirectory=self._dir,
                modelIdentifier=self.md.coSimulation.modelIdentifier,
                instanceName="dfo",
            )
        self.slave.instantiate(callbacks=self._callbacks, loggingOn=logging)
        self._lean_calls: _Lean | None = None
        self._get_plans: dict[tuple[str, ...], list[tuple[Any, Any, Any, list[str]]]] = {}
        self._closed = False

    # ---- plumbing ----
    def _log(self, env: Any, name: bytes, status: int, category: bytes, message: bytes) -> None:
        self.messages.append((status, category.decode(), message.decode(errors="replace")))

    def vr(self, name: str) -> int:
        try:
            return self.vars[name].valueReference
        except KeyError:
            raise KeyError(f"the FMU has no variable {name!r}") from None

    def _error(self, e: Exception, since: int) -> FMUError:
        errors = [m for s, _, m in self.messages[since:] if s >= 3]
        return FMUError(errors[-1] if errors else str(e))

    def _call(self, fn: Any, *args: Any) -> Any:
        n = len(self.messages)
        try:
            return fn(*args)
        except FMICallException as e:
            raise self._error(e, n) from None

    def _raw(self, name: str) -> Any:
        """The FMU's C function itself (status returned, not raised)."""
        return self.slave._functions[name]

    def close(self) -> None:
        if not self._closed:
            self._closed = True
            try:
                self.slave.freeInstance()
            finally:
                shutil.rmtree(self._dir, ignore_errors=True)

    def __enter__(self) -> "OscillatorFMU":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ---- values ----
    def set(self, values: Mapping[str, Any]) -> None:
        """Set variables by name, grouped per type, with the FMU's checks."""
        reals: dict[int, float] = {}
        ints: dict[int, int] = {}
        bools: dict[int, bool] = {}
        for name, value in values.items():
            var = self.vars.get(name)
            if var is None:
                raise FMUError(f"unknown variable {name!r}")
            if var.type == "Real":
                reals[var.valueReference] = float(value)
            elif var.type == "Boolean":
                bools[var.valueReference] = bool(value)
            else:
                if name == "scheme" and isinstance(value, str):
                    if value not in SCHEMES:
                        raise FMUError(f"scheme must be one of {', '.join(SCHEMES)}, not {value!r}")
                    value = SCHEMES[value]
                ints[var.valueReference] = int(value)
        s = self.slave
        if reals:
            self._call(s.setReal, list(reals), list(reals.values()))
        if ints:
            self._call(s.setInteger, list(ints), list(ints.values()))
        if bools:
            self._call(s.setBoolean, list(bools), list(bools.values()))

    def get(self, names: Sequence[str]) -> dict[str, float]:
        """Read variables by name: one FMI call per type, with the arrays cached per name list."""
        key = tuple(names)
        plan = self._get_plans.get(key)
        if plan is None:
            plan = self._get_plans[key] = self._plan_get(key)
        c, n, out = self.slave.component, len(self.messages), {}
        for fn, vrs, buf, group in plan:
            if fn(c, vrs, len(group), buf) > 1:
                raise self._error(RuntimeError(f"reading {', '.join(group)} failed"), n)
            out.update(zip(group, buf))
        return {name: out[name] for name in key}

    def _plan_get(self, names: tuple[str, ...]) -> list[tuple[Any, Any, Any, list[str]]]:
        groups: dict[str, list[str]] = {"Real": [], "Integer": [], "Boolean": []}
        for name in names:
            var = self.vars.get(name)
            if var is None:
                raise FMUError(f"unknown variable {name!r}")
            groups["Real" if var.type == "Real" else "Boolean" if var.type == "Boolean" else "Integer"].append(name)
        ctype = {"Real": ctypes.c_double, "Integer": ctypes.c_int, "Boolean": ctypes.c_int}
        plan = []
        for kind, group in groups.items():
            if group:
                vrs = (ctypes.c_uint * len(group))(*[self.vars[g].valueReference for g in group])
                plan.append((self._raw(f"fmi2Get{kind}"), vrs, (ctype[kind] * len(group))(), group))
        return plan

    # ---- runs ----
    def _lean(self) -> "_Lean":
        if self._lean_calls is None:
            self._lean_calls = _Lean(self)
        return self._lean_calls

    def start(self, p: Oscillator, settings: Settings | None = None, t0: float = 0.0) -> None:
        """Reset, set every parameter and initialise: the FMU is then at t0 in step mode.

        The standard parameters go through the FMU's C functions with value arrays built once
        (a few microseconds of host time per run); ``settings.extra`` through :meth:`set`."""
        st = settings or Settings()
        if st.scheme not in SCHEMES:
            raise FMUError(f"scheme must be one of {', '.join(SCHEMES)}, not {st.scheme!r}")
        L = self._lean()
        h = st.h if st.h is not None else p.period / 1000.0
        L.rval[:] = (p.m, p.k, p.c, p.P0, p.omega, p.phi, p.N, p.mu_s, p.chi, p.x0, p.v0, h, st.alpha,
                     st.t_obs_start, st.t_obs_stop)
        L.ival[0], L.ival[1] = SCHEMES[st.scheme], st.frictionUpdates
        L.bval[0], L.bval[1] = int(bool(st.observe)), int(bool(st.fastPaths))
        c, n = L.comp, len(self.messages)
        if (L.reset(c) > 1 or L.setup(c, 0, 0.0, float(t0), 0, 0.0) > 1
                or L.set_real(c, L.rvr, len(L.rval), L.rval) > 1 or L.set_int(c, L.ivr, 2, L.ival) > 1
                or L.set_bool(c, L.bvr, 2, L.bval) > 1):
            raise self._error(RuntimeError("setting the parameters failed"), n)
        if st.extra:
            self.set(st.extra)
        if L.enter(c) > 1 or L.exit(c) > 1:
            raise self._error(RuntimeError("initialisation failed"), n)
        self.time = t0

    def step_to(self, t: float) -> None:
        L, n = self._lean(), len(self.messages)
        if L.do_step(L.comp, float(self.time), float(t - self.time), 1) > 1:
            raise self._error(RuntimeError(f"fmi2DoStep failed at t = {self.time}"), n)
        self.time = t

    def trajectory(
        self,
        p: Oscillator,
        times: Iterable[float] | np.ndarray,
        settings: Settings | None = None,
        outputs: Sequence[str] = TRAJECTORY_OUTPUTS,
    ) -> dict[str, np.ndarray]:
        """Outputs at the communication points ``times`` (the first is the start time)."""
        t = np.asarray(list(times) if not isinstance(times, np.ndarray) else times, dtype=float)
        if t.ndim != 1 or t.size < 1 or np.any(np.diff(t) <= 0):
            raise ValueError("times must be a non-empty, strictly increasing 1-D sequence")
        self.start(p, settings, float(t[0]))
        vrs = [self.vr(n) for n in outputs]
        reals = [i for i, n in enumerate(outputs) if self.vars[n].type == "Real"]
        ints = [i for i, n in enumerate(outputs) if self.vars[n].type != "Real"]
        rows_r: list[list[float]] = []
        rows_i: list[list[int]] = []
        # the C functions with buffers built once: a sample costs one doStep and two gets
        comp = self.slave.component
        do_step, get_real, get_int = self._raw("fmi2DoStep"), self._raw("fmi2GetReal"), self._raw("fmi2GetInteger")
        rv = (ctypes.c_uint * len(reals))(*[vrs[i] for i in reals])
        iv = (ctypes.c_uint * len(ints))(*[vrs[i] for i in ints])
        rbuf = (ctypes.c_double * len(reals))()
        ibuf = (ctypes.c_int * len(ints))()
        nr, ni = len(reals), len(ints)
        for j in range(t.size):
            if j:
                n = len(self.messages)
                if do_step(comp, float(t[j - 1]), float(t[j] - t[j - 1]), 1) > 1:
                    self.time = float(t[j - 1])
                    raise self._error(RuntimeError(f"fmi2DoStep failed at t = {t[j - 1]}"), n)
            if nr:
                get_real(comp, rv, nr, rbuf)
                rows_r.append(rbuf[:])
            if ni:
                get_int(comp, iv, ni, ibuf)
                rows_i.append(ibuf[:])
        self.time = float(t[-1])
        out = np.empty((t.size, len(outputs)))
        if nr:
            out[:, reals] = np.array(rows_r)
        if ni:
            out[:, ints] = np.array(rows_i)
        res = {"t": t}
        for i, n in enumerate(outputs):
            res[n] = out[:, i]
        return res

    def observables(self, p: Oscillator, t_stop: float, t_obs_start: float, t_obs_stop: float | None = None,
                    settings: Settings | None = None) -> dict[str, float]:
        """Run to t_stop in one communication step and read the in-FMU observables."""
        st = settings or Settings()
        st = Settings(**{**st.__dict__, "observe": True, "t_obs_start": t_obs_start,
                         "t_obs_stop": t_stop if t_obs_stop is None else t_obs_stop})
        self.start(p, st)
        self.step_to(t_stop)
        return self.get(OBSERVABLE_OUTPUTS)

    def effects(self) -> list[str]:
        """Names of the effects the current run simulates (from the 'effects' parameter)."""
        mask = int(self.get(["effects"])["effects"])
        return [name for bit, name in EFFECT_BITS.items() if mask & bit]


class _Lean:
    """The FMU's C functions and value arrays for the standard parameters, built once."""

    REALS = ("m", "k", "c", "P0", "omega", "phi", "N", "mu_s", "chi", "x0", "v0", "h", "alpha",
             "t_obs_start", "t_obs_stop")

    def __init__(self, fmu: OscillatorFMU) -> None:
        f = fmu._raw
        self.comp = fmu.slave.component
        self.reset, self.setup = f("fmi2Reset"), f("fmi2SetupExperiment")
        self.set_real, self.set_int, self.set_bool = f("fmi2SetReal"), f("fmi2SetInteger"), f("fmi2SetBoolean")
        self.enter, self.exit, self.do_step = f("fmi2EnterInitializationMode"), f("fmi2ExitInitializationMode"), f("fmi2DoStep")
        self.rvr = (ctypes.c_uint * len(self.REALS))(*[fmu.vr(n) for n in self.REALS])
        self.rval = (ctypes.c_double * len(self.REALS))()
        self.ivr = (ctypes.c_uint * 2)(fmu.vr("scheme"), fmu.vr("frictionUpdates"))
        self.ival = (ctypes.c_int * 2)()
        self.bvr = (ctypes.c_uint * 2)(fmu.vr("observe"), fmu.vr("fastPaths"))
        self.bval = (ctypes.c_int * 2)()
