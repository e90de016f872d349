"""Driving the chain of n blocks (``DryFrictionChain.fmu``, docs/chain.md) from Python.

fmpy's ``simulate_fmu`` cannot set a structural parameter, so the number of blocks ``n`` of the
FMI 3.0 chain is set here: instantiate, Configuration Mode, ``n``, then the arrays and scalars in
Initialization Mode, then steps on the host's grid ``k dt`` with the outputs read at every point::

    from dryfriction.drivers.chain import ChainFMU3
    with ChainFMU3(n=8, params={"mu_s": 0.3, "P0": [1.0] + [0.0] * 7, "omega": 0.5}) as chain:
        run = chain.run(t_stop=20.0, dt=0.05)      # run.x, run.v, run.a, run.F_friction, run.mode: [nt, n]
    print(run.stick_share())                      # share of the points each block is stuck

A scalar for an array parameter sets every block; a sequence must hold n values. The FMI 2.0
chain (:class:`ChainFMU2`, ``n`` fixed when it was built, structured names ``m[1]``, ``x[1]``, ...)
has the same interface; ``t_end`` is a deprecated name of ``t_stop``. Both run on the package's FMI layer
(:mod:`dryfriction.fmi`); the stepping loop reads every point's outputs with one typed call per
type straight into the rows of preallocated numpy arrays (the layer's ``bulk_get``). Every name
and value reference comes from the FMU's model description (:mod:`dryfriction.model`); an FMU
error is an :class:`~dryfriction.errors.FMUCallError` carrying
the FMU's logged sentence.
"""

from __future__ import annotations

import os
import shutil
import xml.etree.ElementTree as ET
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .. import paths
from .base import Driver, grid
from ..errors import FMUFileError
from ..fmi import fmi2, fmi3

__all__ = ["ARRAY_PARAMS", "SCALAR_PARAMS", "INPUTS", "OUTPUTS", "ChainRun",
           "ChainFMU2", "ChainFMU3", "default_chain_fmu", "default_chain_fmu3", "expand", "open_chain"]

#: per-block parameters (arrays of n), inputs and outputs, and the chain's scalars (docs/chain.md)
ARRAY_PARAMS = ("m", "k", "c", "P0", "phi", "N", "mu_s", "chi", "x0", "v0", "k_site", "c_site", "v_s", "delta")
SCALAR_PARAMS = ("k_end", "c_end", "omega", "h", "alpha", "scheme", "friction_law")
#: the enumerations among the scalars: parameter -> its type's name in the model description
_ENUMS = {"scheme": "Scheme", "friction_law": "FrictionLaw"}
INPUTS = ("F_ext", "N_ext", "v_belt")
OUTPUTS = ("x", "v", "a", "F_friction", "mode")
_REAL_OUTPUTS = ("x", "v", "a", "F_friction")

Inputs = Mapping[str, Any] | Callable[[float, Mapping[str, np.ndarray]], Mapping[str, Any]]


def default_chain_fmu3() -> Path:
    """The FMI 3.0 chain: ``$DFO_CHAIN_FMU3``, else the installed package's, else the build tree's
    (:func:`dryfriction.paths.fmu_path`; FMUFileError if there is none or it is not that FMU)."""
    return paths.fmu_path(paths.CHAIN3)


def default_chain_fmu() -> Path:
    """The FMI 2.0 chain: ``$DFO_CHAIN_FMU``, else the installed package's, else the build tree's
    (:func:`dryfriction.paths.fmu_path`)."""
    return paths.fmu_path(paths.CHAIN)


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
        """The number of blocks."""
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


class _Chain(Driver):
    """What the FMI 3.0 and FMI 2.0 chains share: parameters by name, the stepping loop."""

    n: int
    schemes: dict[str, int]
    defaults: dict[str, Any]
    params: dict[str, Any]
    _mode_dtype: type = np.int32
    # the fast path, made for the current n: outputs read into buffers, one step
    _get_reals: Callable[[int], None]
    _get_modes: Callable[[int], None]
    _step: Callable[[float, float], int]

    # ---- to be provided by the FMI version ----
    def _set_reals(self, name: str, values: np.ndarray) -> None:
        raise NotImplementedError

    def _set_scheme(self, value: int) -> None:
        raise NotImplementedError

    def _set_enum(self, name: str, value: int) -> None:
        raise NotImplementedError

    def _begin(self, start_time: float) -> None:
        raise NotImplementedError

    def _end_init(self) -> None:
        self.inst.exit_initialization_mode()  # its warnings: emitted by the FMI layer

    # ---- the fast path ----
    def _read_into(self, reals: int, modes: int) -> None:
        """x, v, a, F_friction (4n doubles) to address ``reals``, mode (n of _mode_dtype) to ``modes``."""
        self._get_reals(reals)
        self._get_modes(modes)

    def _read(self) -> tuple[np.ndarray, np.ndarray]:
        """x, v, a, F_friction as a [4, n] array, and mode [n]."""
        r = np.empty((4, self.n))
        m = np.empty(self.n, dtype=self._mode_dtype)
        self._read_into(r.ctypes.data, m.ctypes.data)
        return r, m.astype(np.int8)

    def _do_step(self, t: float, dt: float) -> None:
        self._step(t, dt)

    def array_size(self, name: str) -> int:
        return self.n

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

    def enum_items(self, name: str) -> dict[str, int]:
        """The items (name -> value) of the enumeration parameter ``name``, from the model description."""
        if name == "scheme":
            return self.schemes
        cache: dict[str, dict[str, int]] = self.__dict__.setdefault("_enum_cache", {})
        if name not in cache:
            root = ET.parse(Path(self.unzip_dir) / "modelDescription.xml").getroot()
            items: dict[str, int] = {}
            for st in list(root.iterfind("TypeDefinitions/SimpleType")) + list(
                    root.iterfind("TypeDefinitions/EnumerationType")):
                if st.get("name") == _ENUMS[name]:
                    e = st.find("Enumeration")
                    items = {i.get("name", ""): int(i.get("value", "0"))
                             for i in (e if e is not None else st).iterfind("Item")}
            cache[name] = items
        return cache[name]

    def enum_value(self, name: str, value: str | int) -> int:
        """The number of an enumeration parameter's value given by name or number (ValueError else)."""
        if name == "scheme":
            return self.scheme_value(value)
        items = self.enum_items(name)
        if isinstance(value, str):
            if value not in items:
                raise ValueError(f"{name} must be one of {', '.join(items)}, not {value!r}")
            return items[value]
        if isinstance(value, bool) or int(value) != value or int(value) not in items.values():
            raise ValueError(f"{name} must be one of {', '.join(f'{v} ({k})' for k, v in items.items())}, "
                             f"not {value!r}")
        return int(value)

    def check(self, params: Mapping[str, Any]) -> list[tuple[str, Any]]:
        """The values to set (arrays of n, the scheme's number), or ValueError with one sentence for
        an unknown name, an array of the wrong length, a non-number or an unknown scheme."""
        todo: list[tuple[str, Any]] = []
        for name, value in params.items():
            if name in ARRAY_PARAMS or name in INPUTS:
                todo.append((name, expand(name, value, self.n)))
            elif name in _ENUMS:
                todo.append((name, self.enum_value(name, value)))
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
            elif name in _ENUMS:
                self._set_enum(name, int(value))
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
        """F_ext, N_ext and/or v_belt (a scalar for every block or n values), held until set again."""
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

    def do_step(self, dt: float) -> None:
        """One step of length ``dt`` from the current time (:attr:`time` is then time + dt)."""
        if not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be a finite number > 0, not {dt!r}")
        self._do_step(self.time, dt)
        self.time = self.time + dt

    def run(self, t_stop: float | None = None, dt: float | None = None, params: Mapping[str, Any] | None = None,
            inputs: Inputs | None = None, start_time: float = 0.0, *, t_end: float | None = None) -> ChainRun:
        """Start afresh (:meth:`start` with ``params``), then :meth:`record` to ``t_stop``. Inputs
        given as values are set in Initialization Mode and held; a function is called before every
        step (the first one after initialisation, with the outputs at the start). ``t_end`` is a
        deprecated name of ``t_stop``."""
        t_stop = _stop_time(t_stop, t_end)
        if dt is None:
            raise TypeError("run() needs dt, the communication step")
        if not (np.isfinite(t_stop) and t_stop > start_time):
            raise ValueError(f"t_end must be finite and after the start time {start_time!r}, not {t_stop!r}")
        if not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be a finite number > 0, not {dt!r}")
        held = None if inputs is None or callable(inputs) else inputs
        self.start(params, start_time, held)
        return self.record(t_stop, dt, inputs if callable(inputs) else None)

    def record(self, t_stop: float | None = None, dt: float | None = None, inputs: Inputs | None = None, *,
               t_end: float | None = None) -> ChainRun:
        """Step from the current time t0 to ``t_stop`` on the grid ``t0 + k dt`` (the last step
        shortened), reading the outputs at t0 and every point. ``inputs``: values of F_ext / N_ext
        held from t0, or a function ``(t, outputs) -> values`` called before each step with the
        outputs at t."""
        t_stop = _stop_time(t_stop, t_end)
        if dt is None:
            raise TypeError("record() needs dt, the communication step")
        if not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be a finite number > 0, not {dt!r}")
        t0 = self.time
        if not (np.isfinite(t_stop) and t_stop > t0):
            raise ValueError(f"t_end must be finite and after the current time {t0!r}, not {t_stop!r}")
        times = grid(t0, t_stop, dt)
        n = self.n
        reals = np.empty((times.size, 4, n))
        modes = np.empty((times.size, n), dtype=self._mode_dtype)
        # the FMU writes each point's values straight into its rows (addresses, no ctypes objects)
        base_r, base_m, row_r, row_m = reals.ctypes.data, modes.ctypes.data, reals.strides[0], modes.strides[0]
        if inputs is not None and not callable(inputs):
            self.set_inputs(inputs)
        get_reals, get_modes, step = self._get_reals, self._get_modes, self._step
        get_reals(base_r)
        get_modes(base_m)
        tl = times.tolist()
        for i in range(1, times.size):
            if callable(inputs):
                self.set_inputs(inputs(self.time, self.outputs()))
            step(self.time, tl[i] - self.time)
            self.time = tl[i]
            get_reals(base_r + i * row_r)
            get_modes(base_m + i * row_m)
        modes = modes.astype(np.int8)
        params = {k: (v.tolist() if isinstance(v, np.ndarray) and v.size > 1 else
                      (float(v[0]) if isinstance(v, np.ndarray) else v)) for k, v in self.params.items()}
        return ChainRun(times, reals[:, 0], reals[:, 1], reals[:, 2], reals[:, 3], modes, params)

    def __enter__(self) -> Any:
        return self


def _stop_time(t_stop: float | None, t_end: float | None) -> float:
    if t_stop is not None and t_end is not None:
        raise TypeError("give t_stop or its former name t_end, not both")
    value = t_stop if t_stop is not None else t_end
    if value is None:
        raise TypeError("run() needs t_stop, the end of the run")
    return float(value)


# ---- FMI 3.0 ------------------------------------------------------------------------------------

class ChainFMU3(_Chain):
    """The FMI 3.0 chain (``build/fmi3/DryFrictionChain.fmu``) with ``n`` blocks (set in
    Configuration Mode at every :meth:`ChainFMU3.start`); one instance, reused by every :meth:`ChainFMU3.run` (reset
    between runs).

    Parameters
    ----------
    n
        The number of blocks, 1 to 4096.
    params
        The chain's values by name: a scalar sets every block, a sequence gives one value per block.
    fmu_path
        The FMU; default: the environment's ``DFO_CHAIN_FMU3``, the installed package's, the
        checkout's ``build/fmi3/``.

    Raises
    ------
    ValueError
        A list of the wrong length, an unknown name or scheme (before anything is set).
    dryfriction.FMUCallError
        A value the FMU refuses, with its sentence (``invalid value -1 for m[3]``).
    dryfriction.FMUFileError
        ``fmu_path`` is not the FMI 3.0 chain FMU.

    Examples
    --------
    >>> from dryfriction import ChainFMU3
    >>> params = {"P0": [1.0] + [0.0] * 7, "k": 1.0, "N": 0.6, "mu_s": 0.5, "omega": 0.5, "h": 0.01}
    >>> with ChainFMU3(n=8, params=params) as chain:
    ...     run = chain.run(t_stop=60.0, dt=0.1)        # run.x, .v, .a, .F_friction, .mode: [601, 8]
    >>> print(run.stick_share().round(2))
    [0.14 0.45 0.56 0.67 1.   1.   1.   1.  ]
    """

    KIND = paths.CHAIN3
    TERMINATE_ON_CLOSE = True

    def __init__(self, n: int = 2, params: Mapping[str, Any] | None = None,
                 fmu_path: str | os.PathLike[str] | None = None) -> None:
        self._open(fmu_path, "dfo_chain3_")
        try:
            self.vars = self.md.variables
            nvar = self.vars.get("n")
            if nvar is None or nvar.causality != "structuralParameter":
                raise FMUFileError(f"{self.path} has no structural parameter n: not the FMI 3.0 chain")
            self.n_min = int(nvar.min) if nvar.min is not None else 1
            self.n_max = int(nvar.max) if nvar.max is not None else 2**63
            self.n = self._check_n(n)
            self.schemes = dict(self.md.schemes)
            self.inst = fmi3.Instance(self.unzip_dir, self.md.guid, self.md.model_identifier, "chain")
        except BaseException:
            shutil.rmtree(self.unzip_dir, ignore_errors=True)
            raise
        self._fresh = True
        self._real_vrs = [self.vars[k].vr for k in _REAL_OUTPUTS]
        mvar = self.vars["mode"]
        self._mode_kind = mvar.call_type
        self._mode_dtype = fmi3.DTYPES[self._mode_kind]
        self._mode_vr = mvar.vr
        self._step = self.inst.step_function()
        self._made_for = -1
        self._make_fast_path()
        self.time = 0.0
        self.params: dict[str, Any] = {}
        self.defaults: dict[str, Any] = dict(params or {})
        self.check(self.defaults)

    def _make_fast_path(self) -> None:
        if self._made_for != self.n:
            self._get_reals = self.inst.bulk_get("Float64", self._real_vrs, 4 * self.n)
            self._get_modes = self.inst.bulk_get(self._mode_kind, [self._mode_vr], self.n)
            self._made_for = self.n

    def _check_n(self, n: Any) -> int:
        """A whole number; its range ([n_min, n_max] of the model description) is the FMU's to
        check, in Configuration Mode (its error is an FMUCallError naming n)."""
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or int(n) < 0:
            raise ValueError(f"invalid value {n!r} for n (number of blocks); valid range: "
                             f"a whole number in [{self.n_min}, {self.n_max}]")
        return int(n)

    def set_n(self, n: int) -> None:
        """A new number of blocks for the next :meth:`start` (Configuration Mode then)."""
        self.n = self._check_n(n)

    def _begin(self, start_time: float) -> None:
        inst = self.inst
        if not self._fresh:
            inst.reset()
        self._fresh = False
        inst.enter_configuration_mode()
        inst.set("UInt64", [self.vars["n"].vr], [self.n])
        inst.exit_configuration_mode()
        inst.enter_initialization_mode(float(start_time))
        self._make_fast_path()

    def _set_reals(self, name: str, values: np.ndarray) -> None:
        self.inst.set("Float64", [self.vars[name].vr], np.asarray(values, dtype=float).tolist())

    def _set_scheme(self, value: int) -> None:
        v = self.vars["scheme"]
        self.inst.set(v.call_type, [v.vr], [value])

    def _set_enum(self, name: str, value: int) -> None:
        v = self.vars[name]
        self.inst.set(v.call_type, [v.vr], [value])

    def set_raw(self, name: str, values: Sequence[float]) -> None:
        """fmi3SetFloat64 of ``name`` with exactly these values (no length check here: the FMU's)."""
        self._set_reals(name, np.asarray(values, dtype=float))

    def __enter__(self) -> "ChainFMU3":
        return self


# ---- FMI 2.0 ------------------------------------------------------------------------------------

class ChainFMU2(_Chain):
    """The FMI 2.0 chain (``build/DryFrictionChain.fmu``): n fixed when it was built (read from the
    model description: the number of ``m[i]``), structured names ``m[1]`` ... ``x[n]``.

    Parameters
    ----------
    params
        The chain's values by name: a scalar sets every block, a sequence gives one value per block.
    fmu_path
        The FMU; default: the environment's ``DFO_CHAIN_FMU``, the installed package's, the checkout's
        ``build/``.
    n
        The number of blocks expected (checked against the FMU's; None: the FMU's).

    Raises
    ------
    ValueError
        A list of the wrong length, an unknown name or scheme, an ``n`` that is not the FMU's.
    dryfriction.FMUCallError
        A value the FMU refuses, with its sentence.
    dryfriction.FMUFileError
        ``fmu_path`` is not the FMI 2.0 chain FMU.

    Examples
    --------
    >>> from dryfriction import ChainFMU2
    >>> with ChainFMU2({"P0": [1.0, 0.0], "N": 0.6, "mu_s": 0.5, "omega": 0.5}) as chain:
    ...     run = chain.run(t_stop=20.0, dt=0.1)
    >>> run.x.shape
    (201, 2)
    """

    KIND = paths.CHAIN

    def __init__(self, params: Mapping[str, Any] | None = None, fmu_path: str | os.PathLike[str] | None = None,
                 n: int | None = None) -> None:
        self._open(fmu_path, "dfo_chain2_")
        try:
            arrays = self._arrays
            if "m" not in arrays:
                raise FMUFileError(f"{self.path} has no variables m[1], m[2], ...: not the FMI 2.0 chain")
            #: array name -> the indices of its structured names (1 ... n)
            self.index: dict[str, list[int]] = {k: list(range(1, len(v) + 1)) for k, v in arrays.items()}
            self.n = len(arrays["m"])
            if n is not None and n != self.n:
                raise ValueError(f"this FMI 2.0 chain has n = {self.n} blocks (fixed when it was built), not {n}")
            self.schemes = dict(self.md.schemes)
            self._vrs = {k: [self.md.vr(f"{k}[{i}]") for i in range(1, self.n + 1)]
                         for k in ARRAY_PARAMS + INPUTS + OUTPUTS}
            self.inst = fmi2.Instance(self.unzip_dir, self.md.guid, self.md.model_identifier, name="chain")
        except BaseException:
            shutil.rmtree(self.unzip_dir, ignore_errors=True)
            raise
        self._fresh = True
        self._mode_dtype = fmi2.DTYPES["Integer"]
        self._get_reals = self.inst.bulk_get("Real", [vr for k in _REAL_OUTPUTS for vr in self._vrs[k]])
        self._get_modes = self.inst.bulk_get("Integer", self._vrs["mode"])
        self._step = self.inst.step_function()
        self.time = 0.0
        self.params: dict[str, Any] = {}
        self.defaults: dict[str, Any] = dict(params or {})
        self.check(self.defaults)

    def _begin(self, start_time: float) -> None:
        if not self._fresh:
            self.inst.reset()
        self._fresh = False
        self.inst.setup_experiment(start_time)
        self.inst.enter_initialization_mode()

    def _set_reals(self, name: str, values: np.ndarray) -> None:
        vrs = self._vrs[name] if name in self._vrs else [self.md.vr(name)]
        self.inst.set("Real", vrs, [float(x) for x in values])

    def _set_scheme(self, value: int) -> None:
        self.inst.set("Integer", [self.md.vr("scheme")], [value])

    def _set_enum(self, name: str, value: int) -> None:
        self.inst.set("Integer", [self.md.vr(name)], [value])

    def __enter__(self) -> "ChainFMU2":
        return self


def open_chain(n: int, fmi: int = 3, fmu_path: str | os.PathLike[str] | None = None) -> _Chain:
    """The chain of n blocks through FMI 3.0 (``fmi=3``) or the FMI 2.0 build (``fmi=2``, n must
    be its built n)."""
    if fmi == 3:
        return ChainFMU3(n, fmu_path=fmu_path)
    if fmi == 2:
        return ChainFMU2(fmu_path=fmu_path, n=n)
    raise ValueError(f"fmi must be 2 or 3, not {fmi!r}")
