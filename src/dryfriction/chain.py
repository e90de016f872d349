"""Driving the chain of n blocks (``DryFrictionChain.fmu``, docs/chain.md) from Python.

fmpy's ``simulate_fmu`` cannot set a structural parameter, so the number of blocks ``n`` of the
FMI 3.0 chain is set here: instantiate, Configuration Mode, ``n``, then the arrays and scalars in
Initialization Mode, then steps on the host's grid ``k dt`` with the outputs read at every point:

    from dryfriction.chain import ChainFMU
    with ChainFMU(n=8, params={"mu_s": 0.3, "P0": [1.0] + [0.0] * 7, "omega": 0.5}) as chain:
        run = chain.run(t_end=20.0, dt=0.05)       # run.x, run.v, run.a, run.F_friction, run.mode: [nt, n]
    print(run.stick_share())                      # share of the points each block is stuck

A scalar for an array parameter sets every block; a sequence must hold n values. The FMI 2.0
chain (:class:`ChainFMU2`, ``n`` fixed when it was built, structured names ``m[1]``, ``x[1]``, ...)
has the same interface. Every name and value reference comes from the FMU's model description;
an FMU error is a :class:`ChainError` carrying the FMU's logged sentence.
"""

from __future__ import annotations

import ctypes
import os
import re
import shutil
import tempfile
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from . import locate
from .diagnostics import DryFrictionWarning, emit

__all__ = ["ARRAY_PARAMS", "SCALAR_PARAMS", "INPUTS", "OUTPUTS", "ChainError", "ChainRun", "ChainFMU",
           "ChainFMU2", "default_chain_fmu", "default_chain_fmu3", "expand", "open_chain"]

#: per-block parameters (arrays of n), inputs and outputs, and the chain's scalars (docs/chain.md)
ARRAY_PARAMS = ("m", "k", "c", "P0", "phi", "N", "mu_s", "chi", "x0", "v0")
SCALAR_PARAMS = ("k_end", "c_end", "omega", "h", "alpha", "scheme")
INPUTS = ("F_ext", "N_ext")
OUTPUTS = ("x", "v", "a", "F_friction", "mode")
_REAL_OUTPUTS = ("x", "v", "a", "F_friction")

Inputs = Mapping[str, Any] | Callable[[float, Mapping[str, np.ndarray]], Mapping[str, Any]]


class ChainError(RuntimeError):
    """The chain FMU refused a call; the message is the FMU's logged sentence (or the call)."""


def default_chain_fmu3() -> Path:
    """The FMI 3.0 chain: ``$DFO_CHAIN_FMU3``, else the installed package's, else the build tree's
    (:func:`dryfriction.locate.fmu_path`; FMUFileError if there is none or it is not that FMU)."""
    return locate.fmu_path(locate.CHAIN3)


def default_chain_fmu() -> Path:
    """The FMI 2.0 chain: ``$DFO_CHAIN_FMU``, else the installed package's, else the build tree's
    (:func:`dryfriction.locate.fmu_path`)."""
    return locate.fmu_path(locate.CHAIN)


def expand(name: str, value: Any, n: int) -> np.ndarray:
    """The n values of the array parameter or input ``name``: a scalar sets every block, a
    sequence must hold n finite numbers (ValueError with one sentence otherwise)."""
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number or a list of {n} numbers, not {value!r}") from None
    if a.ndim == 0:
        a = np.full(n, float(a))
    elif a.ndim != 1 or a.size != n:
        got = a.size if a.ndim == 1 else f"an array of shape {a.shape}"
        raise ValueError(f"{name} needs {n} values (one per block, n = {n}) or one value for every block, not {got}")
    bad = np.flatnonzero(~np.isfinite(a))
    if bad.size:
        raise ValueError(f"invalid value {a[bad[0]]} for {name}[{bad[0] + 1}]; valid range: finite")
    return a


#: the warnings the chain FMUs log (e.g. an internal step h that does not resolve the dynamics): the
#: package's one category, :class:`dryfriction.diagnostics.DryFrictionWarning`
ChainWarning = DryFrictionWarning


@dataclass
class ChainRun:
    """Outputs at every communication point: ``t`` [nt], the rest [nt, n] (mode: -1 backward slip,
    0 stuck, +1 forward slip)."""

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    a: np.ndarray
    F_friction: np.ndarray
    mode: np.ndarray
    params: dict[str, Any] = field(default_factory=dict)

    @property
    def n(self) -> int:
        return int(self.x.shape[1])

    def stick_share(self, t_from: float = -np.inf) -> np.ndarray:
        """Share of the points at or after ``t_from`` at which each block is stuck."""
        sel = self.t >= t_from
        return np.mean(self.mode[sel] == 0, axis=0)

    def amplitude(self, t_from: float = -np.inf) -> np.ndarray:
        """Half the peak-to-peak of each block's x over the points at or after ``t_from``."""
        x = self.x[self.t >= t_from]
        return 0.5 * (x.max(axis=0) - x.min(axis=0))

    def to_dataset(self) -> Any:
        """An xarray Dataset (dims time, block; block numbered from 1 as the FMU's names)."""
        import xarray as xr

        units = {"x": "m", "v": "m/s", "a": "m/s2", "F_friction": "N", "mode": "1"}
        data = {k: (("time", "block"), getattr(self, k), {"units": units[k]}) for k in OUTPUTS}
        ds = xr.Dataset(data, coords={"time": ("time", self.t, {"units": "s"}),
                                      "block": np.arange(1, self.n + 1)})
        ds["mode"].attrs["long_name"] = "-1 backward slip, 0 stuck, +1 forward slip"
        for k, v in self.params.items():
            ds.attrs[f"param_{k}"] = (np.asarray(v).tolist() if np.ndim(v) else v)
        return ds


class _Chain:
    """What the FMI 3.0 and FMI 2.0 chains share: parameters by name, the stepping loop."""

    n: int
    schemes: dict[str, int]
    path: Path

    # ---- to be provided by the FMI layer ----
    def _set_reals(self, name: str, values: np.ndarray) -> None:
        raise NotImplementedError

    def _set_scheme(self, value: int) -> None:
        raise NotImplementedError

    _mode_dtype: type = np.int32

    def _read_into(self, reals: int, modes: int) -> None:
        """x, v, a, F_friction (4n doubles) to address ``reals``, mode (n of _mode_dtype) to ``modes``."""
        raise NotImplementedError

    def _read(self) -> tuple[np.ndarray, np.ndarray]:
        """x, v, a, F_friction as a [4, n] array, and mode [n]."""
        r = np.empty((4, self.n))
        m = np.empty(self.n, dtype=self._mode_dtype)
        self._read_into(r.ctypes.data, m.ctypes.data)
        return r, m.astype(np.int8)

    def _do_step(self, t: float, dt: float) -> None:
        raise NotImplementedError

    def _begin(self, start_time: float) -> None:
        raise NotImplementedError

    def _end_init(self) -> None:
        raise NotImplementedError

    # ---- shared ----
    def scheme_value(self, scheme: str | int) -> int:
        if isinstance(scheme, str):
            if scheme not in self.schemes:
                raise ValueError(f"scheme must be one of {', '.join(self.schemes)}, not {scheme!r}")
            return self.schemes[scheme]
        if isinstance(scheme, bool) or int(scheme) != scheme or int(scheme) not in self.schemes.values():
            raise ValueError(f"scheme must be one of {', '.join(f'{v} ({k})' for k, v in self.schemes.items())}, "
                             f"not {scheme!r}")
        return int(scheme)

    def check(self, params: Mapping[str, Any]) -> list[tuple[str, Any]]:
        """The values to set (arrays of n, the scheme's number), or ValueError with one sentence for
        an unknown name, an array of the wrong length, a non-number or an unknown scheme."""
        todo: list[tuple[str, Any]] = []
        for name, value in params.items():
            if name in ARRAY_PARAMS or name in INPUTS:
                todo.append((name, expand(name, value, self.n)))
            elif name == "scheme":
                todo.append((name, self.scheme_value(value)))
            elif name in SCALAR_PARAMS:
                try:
                    x = float(value)
                except (TypeError, ValueError):
                    raise ValueError(f"{name} must be a number, not {value!r}") from None
                todo.append((name, np.array([x])))
            else:
                raise ValueError(f"the chain has no parameter {name!r}; its parameters are "
                                 f"{', '.join(ARRAY_PARAMS + SCALAR_PARAMS)} and its inputs {', '.join(INPUTS)}")
        return todo

    def _apply(self, params: Mapping[str, Any]) -> dict[str, Any]:
        """Check every value before the first one is set, then set them (the FMU checks ranges)."""
        todo = self.check(params)
        for name, value in todo:
            if name == "scheme":
                self._set_scheme(int(value))
            else:
                self._set_reals(name, value)
        return dict(todo)

    def start(self, params: Mapping[str, Any] | None = None, start_time: float = 0.0,
              inputs: Mapping[str, Any] | None = None) -> None:
        """A fresh run from ``start_time``: the instance's parameters (given when it was made)
        updated with ``params``, the others at their start values; ``inputs`` (F_ext, N_ext) set
        in Initialization Mode, so that the start state (its modes and accelerations) sees them."""
        merged = {**self.defaults, **(params or {})}
        if inputs is not None and set(inputs) - set(INPUTS):
            raise ValueError(f"the chain's inputs are {', '.join(INPUTS)}, not "
                             f"{', '.join(sorted(set(inputs) - set(INPUTS)))}")
        self.check(merged)  # every value checked before the FMU is touched
        self._begin(start_time)
        self.params = self._apply(merged)
        if inputs:
            self._apply(inputs)
        self._end_init()
        self.time = float(start_time)

    def set_inputs(self, values: Mapping[str, Any]) -> None:
        """F_ext and/or N_ext (a scalar for every block or n values), held until set again."""
        unknown = set(values) - set(INPUTS)
        if unknown:
            raise ValueError(f"the chain's inputs are {', '.join(INPUTS)}, not {', '.join(sorted(unknown))}")
        self._apply(values)

    def outputs(self) -> dict[str, np.ndarray]:
        """The current x, v, a, F_friction, mode (n values each)."""
        r, mode = self._read()
        out = {k: r[i].copy() for i, k in enumerate(_REAL_OUTPUTS)}
        out["mode"] = mode.copy()
        return out

    def step_to(self, t: float) -> None:
        if not t > self.time:
            raise ValueError(f"the next communication point {t!r} must be after the current time {self.time!r}")
        self._do_step(self.time, t - self.time)
        self.time = float(t)

    def run(self, t_end: float, dt: float, params: Mapping[str, Any] | None = None, inputs: Inputs | None = None,
            start_time: float = 0.0) -> ChainRun:
        """Start afresh (:meth:`start` with ``params``), then :meth:`record` to ``t_end``. Inputs
        given as values are set in Initialization Mode and held; a function is called before every
        step (the first one after initialisation, with the outputs at the start)."""
        if not (np.isfinite(t_end) and t_end > start_time):
            raise ValueError(f"t_end must be finite and after the start time {start_time!r}, not {t_end!r}")
        if not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be a finite number > 0, not {dt!r}")
        held = None if inputs is None or callable(inputs) else inputs
        self.start(params, start_time, held)
        return self.record(t_end, dt, inputs if callable(inputs) else None)

    def record(self, t_end: float, dt: float, inputs: Inputs | None = None) -> ChainRun:
        """Step from the current time t0 to ``t_end`` on the grid ``t0 + k dt`` (the last step
        shortened), reading the outputs at t0 and every point. ``inputs``: values of F_ext / N_ext
        held from t0, or a function ``(t, outputs) -> values`` called before each step with the
        outputs at t."""
        if not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be a finite number > 0, not {dt!r}")
        t0 = self.time
        if not (np.isfinite(t_end) and t_end > t0):
            raise ValueError(f"t_end must be finite and after the current time {t0!r}, not {t_end!r}")
        k_end = max(1, int(np.ceil((t_end - t0) / dt - 1e-9)))
        times = np.minimum(t0 + np.arange(k_end + 1) * dt, t_end)
        times[-1] = t_end
        n = self.n
        reals = np.empty((times.size, 4, n))
        modes = np.empty((times.size, n), dtype=self._mode_dtype)
        # the FMU writes each point's values straight into its rows (addresses, no ctypes objects)
        base_r, base_m, row_r, row_m = reals.ctypes.data, modes.ctypes.data, reals.strides[0], modes.strides[0]
        if inputs is not None and not callable(inputs):
            self.set_inputs(inputs)
        self._read_into(base_r, base_m)
        for i in range(1, times.size):
            if callable(inputs):
                self.set_inputs(inputs(self.time, self.outputs()))
            self._do_step(self.time, times[i] - self.time)
            self.time = float(times[i])
            self._read_into(base_r + i * row_r, base_m + i * row_m)
        modes = modes.astype(np.int8)
        params = {k: (v.tolist() if isinstance(v, np.ndarray) and v.size > 1 else
                      (float(v[0]) if isinstance(v, np.ndarray) else v)) for k, v in self.params.items()}
        return ChainRun(times, reals[:, 0], reals[:, 1], reals[:, 2], reals[:, 3], modes, params)

    def __enter__(self) -> "_Chain":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        raise NotImplementedError


# ---- FMI 3.0 ------------------------------------------------------------------------------------

class ChainFMU(_Chain):
    """The FMI 3.0 chain (``build/fmi3/DryFrictionChain.fmu``) with ``n`` blocks, through fmpy's
    ``FMU3Slave``; one instance, reused by every :meth:`run` (reset between runs)."""

    def __init__(self, n: int = 2, params: Mapping[str, Any] | None = None,
                 fmu_path: str | os.PathLike[str] | None = None) -> None:
        from fmpy import extract, read_model_description
        from fmpy.fmi3 import FMU3Slave, fmi3LogMessageCallback  # noqa: F401

        path = locate.fmu_path(locate.CHAIN3, fmu_path)
        self.path = path
        self.md = read_model_description(str(path))
        self.vars = {v.name: v for v in self.md.modelVariables}
        nvar = self.vars.get("n")
        if nvar is None or nvar.causality != "structuralParameter":
            raise ChainError(f"{path} has no structural parameter n: not the FMI 3.0 chain")
        self.n_min, self.n_max = _n_range(path)
        self.n = self._check_n(n)
        self.schemes = _schemes(self.md, "scheme")
        self.messages: list[tuple[int, str]] = []
        self._warnings: list[str] = []
        self._dir = extract(str(path), tempfile.mkdtemp(prefix="dfo_chain3_"))
        self.slave = FMU3Slave(guid=self.md.guid, unzipDirectory=self._dir,
                               modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName="chain")
        self.slave.instantiate(loggingOn=False, logMessage=self._log)
        self._hot = _Hot3(self._dir, self.md.coSimulation.modelIdentifier)
        self._fresh = True
        self._state = "instantiated"
        self._real_vrs = (ctypes.c_uint32 * 4)(*[self.vars[k].valueReference for k in _REAL_OUTPUTS])
        mvar = self.vars["mode"]
        self._mode_int32 = mvar.type == "Int32"
        self._mode_dtype = np.int32 if self._mode_int32 else np.int64
        self._mode_vr = (ctypes.c_uint32 * 1)(mvar.valueReference)
        self.time = 0.0
        self.params: dict[str, Any] = {}
        self.defaults: dict[str, Any] = dict(params or {})
        self.check(self.defaults)

    def _check_n(self, n: Any) -> int:
        """A whole number; its range ([n_min, n_max] of the model description) is the FMU's to
        check, in Configuration Mode (its error is a ChainError naming n)."""
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or int(n) < 0:
            raise ValueError(f"invalid value {n!r} for n (number of blocks); valid range: "
                             f"a whole number in [{self.n_min}, {self.n_max}]")
        return int(n)

    def _log(self, env: Any, status: int, category: bytes, message: bytes) -> None:
        text = (message or b"").decode(errors="replace")
        self.messages.append((int(status), text))
        del self.messages[:-100]
        if status == 1:  # fmi3Warning: emitted when the call returns
            self._warnings.append(text)

    def _flush(self) -> None:
        if self._warnings:
            pending, self._warnings = self._warnings, []
            emit(pending, stacklevel=5)

    def _call(self, what: str, fn: Callable[..., Any], *args: Any) -> Any:
        from fmpy.fmi1 import FMICallException

        mark = len(self.messages)
        try:
            out = fn(*args)
        except FMICallException as e:
            said = [m for s, m in self.messages[mark:] if s >= 2] or [m for _, m in self.messages[mark:]]
            self._flush()
            raise ChainError(said[-1] if said else f"{what} failed ({e})") from None
        self._flush()
        return out

    def set_n(self, n: int) -> None:
        """A new number of blocks for the next :meth:`start` (Configuration Mode then)."""
        self.n = self._check_n(n)

    def _begin(self, start_time: float) -> None:
        s = self.slave
        if not self._fresh:
            self._call("fmi3Reset", s.reset)
        self._fresh = False
        self._call("fmi3EnterConfigurationMode", s.enterConfigurationMode)
        self._call("setting n", s.setUInt64, [self.vars["n"].valueReference], [self.n])
        self._call("fmi3ExitConfigurationMode", s.exitConfigurationMode)
        self._call("fmi3EnterInitializationMode", s.enterInitializationMode, None, float(start_time), None)

    def _end_init(self) -> None:
        self._call("fmi3ExitInitializationMode", self.slave.exitInitializationMode)

    def _set_reals(self, name: str, values: np.ndarray) -> None:
        self._call(f"setting {name}", self.slave.setFloat64, [self.vars[name].valueReference],
                   [float(x) for x in values])

    def _set_scheme(self, value: int) -> None:
        v = self.vars["scheme"]
        setter = self.slave.setInt32 if v.type == "Int32" else self.slave.setInt64
        self._call("setting scheme", setter, [v.valueReference], [value])

    def set_raw(self, name: str, values: Sequence[float]) -> None:
        """fmi3SetFloat64 of ``name`` with exactly these values (no length check here: the FMU's)."""
        self._set_reals(name, np.asarray(values, dtype=float))

    def _read_into(self, reals: int, modes: int) -> None:
        n, hot, comp = self.n, self._hot, self.slave.component
        st = hot.get_float64(comp, self._real_vrs, 4, reals, 4 * n)
        if st:
            self._failed("fmi3GetFloat64", st)
        st = (hot.get_int32 if self._mode_int32 else hot.get_int64)(comp, self._mode_vr, 1, modes, n)
        if st:
            self._failed("getting mode", st)

    def _do_step(self, t: float, dt: float) -> None:
        hot = self._hot
        st = hot.do_step(self.slave.component, t, dt, True, hot.event, hot.terminate, hot.early, hot.last)
        if st:
            self._failed("fmi3DoStep", st)

    def _failed(self, what: str, status: int) -> None:
        """A non-OK status of a hot call: a warning is emitted, anything else is a ChainError."""
        self._flush()
        if status == 1:
            return
        said = [m for s, m in self.messages if s >= 2]
        self.messages.clear()  # a later failure reports its own sentence, not this one
        raise ChainError(said[-1] if said else f"{what} returned status {status}")

    def get(self, name: str) -> np.ndarray | float:
        """Any Float64 variable by name (an array of n for the arrays)."""
        v = self.vars[name]
        size = self.n if v.dimensions else 1
        vals = self._call(f"reading {name}", self.slave.getFloat64, [v.valueReference], size)
        return np.array(vals) if v.dimensions else float(vals[0])

    def close(self) -> None:
        if getattr(self, "slave", None) is None:
            return
        try:
            self.slave.terminate()
        except Exception:  # noqa: BLE001 - terminate is not allowed in every state: free anyway
            pass
        self.slave.freeInstance()
        self.slave = None
        shutil.rmtree(self._dir, ignore_errors=True)


class _Hot3:
    """The three calls of the stepping loop, typed once on the FMU's library (the one fmpy loaded:
    the same handle), called with numpy buffers and reused out-arguments; fmpy's wrappers build
    ctypes objects at every call (about 25 us per communication point against 5)."""

    def __init__(self, unzip_dir: str, model_identifier: str) -> None:
        from ctypes import POINTER, byref, c_bool, c_double, c_int, c_size_t, c_uint32, c_void_p

        from fmpy import platform_tuple, sharedLibraryExtension

        lib = ctypes.CDLL(str(Path(unzip_dir, "binaries", platform_tuple, model_identifier + sharedLibraryExtension)))
        self.do_step = lib.fmi3DoStep
        self.do_step.restype = c_int
        self.do_step.argtypes = [c_void_p, c_double, c_double, c_bool, POINTER(c_bool), POINTER(c_bool),
                                 POINTER(c_bool), POINTER(c_double)]
        self.get_float64, self.get_int32, self.get_int64 = lib.fmi3GetFloat64, lib.fmi3GetInt32, lib.fmi3GetInt64
        for f in (self.get_float64, self.get_int32, self.get_int64):
            f.restype = c_int
            f.argtypes = [c_void_p, POINTER(c_uint32), c_size_t, c_void_p, c_size_t]
        self._out = (c_bool(), c_bool(), c_bool(), c_double())
        self.event, self.terminate, self.early, self.last = (byref(x) for x in self._out)


# ---- FMI 2.0 ------------------------------------------------------------------------------------

_INDEXED = re.compile(r"^(\w+)\[(\d+)\]$")


class ChainFMU2(_Chain):
    """The FMI 2.0 chain (``build/DryFrictionChain.fmu``): n fixed when it was built (read from the
    model description: the number of ``m[i]``), structured names ``m[1]`` ... ``x[n]``."""

    def __init__(self, params: Mapping[str, Any] | None = None, fmu_path: str | os.PathLike[str] | None = None,
                 n: int | None = None) -> None:
        from fmpy import extract

        from . import fmi2, model

        path = locate.fmu_path(locate.CHAIN, fmu_path)
        self.path = path
        self.md = model.from_fmu(path)
        self.index: dict[str, list[int]] = {}
        for name in self.md.variables:
            m = _INDEXED.match(name)
            if m:
                self.index.setdefault(m.group(1), []).append(int(m.group(2)))
        if "m" not in self.index:
            raise ChainError(f"{path} has no variables m[1], m[2], ...: not the FMI 2.0 chain")
        self.n = len(self.index["m"])
        if n is not None and n != self.n:
            raise ValueError(f"this FMI 2.0 chain has n = {self.n} blocks (fixed when it was built), not {n}")
        self.schemes = dict(self.md.schemes)
        self._vrs = {k: [self.md.vr(f"{k}[{i}]") for i in range(1, self.n + 1)]
                     for k in ARRAY_PARAMS + INPUTS + OUTPUTS}
        self._dir = extract(str(path), tempfile.mkdtemp(prefix="dfo_chain2_"))
        self.inst = fmi2.Instance(self._dir, self.md.guid, self.md.model_identifier, name="chain")
        self._fresh = True
        reals = [vr for k in _REAL_OUTPUTS for vr in self._vrs[k]]
        self._real_vrs = (ctypes.c_uint * len(reals))(*reals)
        self._mode_vrs = (ctypes.c_uint * self.n)(*self._vrs["mode"])
        self.time = 0.0
        self.params: dict[str, Any] = {}
        self.defaults: dict[str, Any] = dict(params or {})
        self.check(self.defaults)

    def _call(self, fn: Callable[..., Any], *args: Any) -> Any:
        from .fmi2 import FMUError

        try:
            return fn(*args)
        except FMUError as e:
            raise ChainError(e.message) from None

    def _begin(self, start_time: float) -> None:
        if not self._fresh:
            self._call(self.inst.reset)
        self._fresh = False
        self._call(self.inst.setup_experiment, start_time)
        self._call(self.inst.enter_initialization_mode)

    def _end_init(self) -> None:
        self._call(self.inst.exit_initialization_mode)  # its warnings: emitted by the fmi2 layer

    def _set_reals(self, name: str, values: np.ndarray) -> None:
        vrs = self._vrs[name] if name in self._vrs else [self.md.vr(name)]
        self._call(self.inst.set, "Real", vrs, [float(x) for x in values])

    def _set_scheme(self, value: int) -> None:
        self._call(self.inst.set, "Integer", [self.md.vr("scheme")], [value])

    def _read_into(self, reals: int, modes: int) -> None:
        inst = self.inst
        st = inst.f.GetReal(inst.component, self._real_vrs, 4 * self.n, reals)
        if st:
            self._call(inst.check, "fmi2GetReal", st)
        st = inst.f.GetInteger(inst.component, self._mode_vrs, self.n, modes)
        if st:
            self._call(inst.check, "fmi2GetInteger", st)

    def _do_step(self, t: float, dt: float) -> None:
        self._call(self.inst.do_step, t, dt)

    def get(self, name: str) -> np.ndarray | float:
        if name in self._vrs:
            return np.array(self._call(self.inst.get, "Real", self._vrs[name]))
        return float(self._call(self.inst.get, "Real", [self.md.vr(name)])[0])

    def close(self) -> None:
        if getattr(self, "inst", None) is None:
            return
        self.inst.free()
        self.inst = None
        shutil.rmtree(self._dir, ignore_errors=True)


def _n_range(path: Path) -> tuple[int, int]:
    """min and max of the structural parameter n (read from the XML: fmpy leaves them out)."""
    import zipfile
    from xml.etree import ElementTree as ET

    root = ET.fromstring(zipfile.ZipFile(path).read("modelDescription.xml"))
    el = root.find("ModelVariables/UInt64[@name='n']")
    lo = el.get("min") if el is not None else None
    hi = el.get("max") if el is not None else None
    return int(lo or 1), int(hi or 2**63)


def _schemes(md: Any, var: str) -> dict[str, int]:
    """Item name -> value of the enumeration type of ``var`` in an fmpy model description."""
    v = next((x for x in md.modelVariables if x.name == var), None)
    if v is None or v.declaredType is None or not getattr(v.declaredType, "items", None):
        return {}
    return {item.name: int(item.value) for item in v.declaredType.items}


def open_chain(n: int, fmi: int = 3, fmu_path: str | os.PathLike[str] | None = None) -> _Chain:
    """The chain of n blocks through FMI 3.0 (``fmi=3``) or the FMI 2.0 build (``fmi=2``, n must
    be its built n)."""
    if fmi == 3:
        return ChainFMU(n, fmu_path=fmu_path)
    if fmi == 2:
        return ChainFMU2(fmu_path=fmu_path, n=n)
    raise ValueError(f"fmi must be 2 or 3, not {fmi!r}")
