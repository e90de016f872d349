"""Running a :class:`~dryfriction.system.structure.System` through the FMI 3.0 ``DryFrictionSystem``
FMU (docs/system.md).

The structure's sizes ``n`` and ``nc`` are set in Configuration Mode, its values
(:meth:`~dryfriction.system.structure.System.start_values`) in Initialization Mode, then the FMU
steps on the host's points with
the outputs ``x``, ``v``, ``a`` (n), ``f``, ``mode``, ``s`` (nc) and ``E_friction`` read at each, and
the in-FMU observables ``x_max``, ``x_min`` (n) and ``stick_fraction`` (nc) read at the end of the
run. Their observation window is a run's option, as the oscillator's drivers take it (not the
system's): ``observe`` (default true, the FMU's), ``t_obs_start`` (default the run's start) and
``t_obs_stop`` (default the FMU's 1e300, open)::

    from dryfriction import System, Contact
    sys = System(M=[[1.0]], K=[[100.0]], contacts=[Contact(dof=0, N=1.0, mu_s=0.4, mu_k=0.3)],
                 F_c=[1.0], omega=5.0)
    run = sys.run(t_end=10.0, dt=0.01)          # run.x [nt, n], run.f [nt, nc], run.E_friction [nt]
    with SystemFMU3(sys) as fmu:                # or the driver, to run again or to step by hand
        run = fmu.run(10.0, 0.01, inputs={"F_ext": [0.5]})

Inputs (``F_ext`` n values, ``N_ext`` and ``v_belt`` nc values; one number counts for every
element) are given as values held from the start, or as a function ``(t, outputs) -> values``
called before every step, as the chain's driver takes them. The driver runs on the package's FMI
layer (:mod:`dryfriction.fmi`): an FMU error is an :class:`~dryfriction.errors.FMUCallError` with
the FMU's sentence, a warning the FMU logs (the slip ``s`` of a rigid contact read, not computed)
a :class:`~dryfriction.errors.DryFrictionWarning`.
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .. import paths
from ..errors import FMUFileError
from ..fmi import fmi3
from .base import Driver, grid
from .chain import expand

if TYPE_CHECKING:
    from ..system.structure import System
    from ..system.structure import System as Structure  # (the annotations' name: the API reference links it)

__all__ = ["SystemFMU3", "SystemRun", "INPUTS", "OUTPUTS", "OBSERVABLES", "T_OBS_STOP", "JACOBIAN", "default_system_fmu3", "run",
           "trajectory"]

#: the inputs and their sizes (``n`` per degree of freedom, ``nc`` per contact)
INPUTS = {"F_ext": "n", "N_ext": "nc", "v_belt": "nc"}
#: the outputs recorded, in the order the FMU is read
OUTPUTS = ("x", "v", "a", "f", "s", "E_friction", "mode")
#: the in-FMU observables, read at the end of a run: x_max, x_min (n), stick_fraction (nc)
OBSERVABLES = ("x_max", "x_min", "stick_fraction")
#: the FMU's default end of the observation window (open)
T_OBS_STOP = 1e300
#: the located map's Jacobian blocks (``sensitivity``): (name, rows, columns) of d(x, v, s)/d(x0, v0, s0)
JACOBIAN = (("dx_dx0", "x", "x0"), ("dx_dv0", "x", "v0"), ("dx_ds0", "x", "s0"),
            ("dv_dx0", "v", "x0"), ("dv_dv0", "v", "v0"), ("dv_ds0", "v", "s0"),
            ("ds_dx0", "s", "x0"), ("ds_dv0", "s", "v0"), ("ds_ds0", "s", "s0"))
_REALS = (("x", "n"), ("v", "n"), ("a", "n"), ("f", "nc"), ("s", "nc"), ("E_friction", None))

Inputs = Mapping[str, Any] | Callable[[float, Mapping[str, np.ndarray]], Mapping[str, Any]]


def default_system_fmu3() -> Path:
    """The FMI 3.0 system FMU: ``$DFO_SYSTEM_FMU3``, else the installed package's, else the build
    tree's (:func:`dryfriction.paths.fmu_path`; FMUFileError if there is none or it is not that FMU)."""
    return paths.fmu_path(paths.SYSTEM3)


@dataclass
class SystemRun:
    """The outputs at the output times: ``t`` [nt]; ``x``, ``v``, ``a`` [nt, n]; ``f``, ``s``,
    ``mode`` [nt, nc] (mode -1 backward slip, 0 stuck, +1 forward slip; ``s`` NaN for a rigid
    contact); ``E_friction`` [nt], the energy the contacts have taken since the start; the in-FMU
    observables at the end of the run over its observation window: ``x_max``, ``x_min`` [n], the
    largest and smallest position of each degree of freedom (sampled at every internal step and
    switch), ``stick_fraction`` [nc], the share of the window each contact spent stuck (all NaN
    when the run was made with ``observe=False``), ``transitions`` [nc], each contact's mode
    changes in the window (-1 each with ``observe=False``)."""

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    a: np.ndarray
    f: np.ndarray
    s: np.ndarray
    E_friction: np.ndarray
    mode: np.ndarray
    x_max: np.ndarray
    x_min: np.ndarray
    stick_fraction: np.ndarray
    transitions: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))

    @property
    def n(self) -> int:
        """The number of degrees of freedom."""
        return int(self.x.shape[1])

    @property
    def nc(self) -> int:
        """The number of contacts."""
        return int(self.f.shape[1])

    def stick_share(self, t_from: float = -np.inf) -> np.ndarray:
        """The share of the output times at or after ``t_from`` at which each contact is stuck (of
        the output times only; :attr:`stick_fraction` is the FMU's, over the whole window)."""
        return np.mean(self.mode[self.t >= t_from] == 0, axis=0)

    def __getitem__(self, name: str) -> np.ndarray:
        return getattr(self, "t" if name == "time" else name)


class SystemFMU3(Driver):
    """One instance of the FMI 3.0 ``DryFrictionSystem`` FMU running ``system``, as a context
    manager; every :meth:`~dryfriction.drivers.system.SystemFMU3.start` (and so every
    :meth:`~dryfriction.drivers.system.SystemFMU3.run`) resets it, sets ``n``, ``nc`` in
    Configuration Mode and the system's values in Initialization Mode.

    Parameters
    ----------
    system
        The structure (:class:`~dryfriction.system.structure.System`).
    fmu_path
        The FMU; default: ``$DFO_SYSTEM_FMU3``, the installed package's, the checkout's
        ``build/fmi3/``. A structure's own FMU (:meth:`~dryfriction.system.structure.System.fmu`) runs too.
    logging
        Switch the FMU's debug logging on.

    Raises
    ------
    dryfriction.FMUFileError
        ``fmu_path`` is not the FMI 3.0 system FMU.
    dryfriction.FMUCallError
        A structure or a call the FMU refuses, with its sentence.

    Examples
    --------
    >>> from dryfriction import System, Contact
    >>> sys = System(M=[[1.0]], K=[[100.0]], contacts=[Contact(dof=0, N=1.0, mu_s=0.4, mu_k=0.3)],
    ...              F_c=[1.0], omega=5.0)
    >>> with SystemFMU3(sys) as fmu:
    ...     run = fmu.run(t_stop=4.0, dt=0.01)
    >>> run.x.shape, run.mode.shape
    ((401, 1), (401, 1))
    """

    KIND = paths.SYSTEM3
    TERMINATE_ON_CLOSE = True

    def __init__(self, system: "Structure", fmu_path: str | os.PathLike[str] | None = None, *,
                 logging: bool = False) -> None:
        from ..system.structure import System

        if not isinstance(system, System):
            raise TypeError(f"SystemFMU3 needs a dryfriction.System, not {type(system).__name__}")
        self.system = system
        self.n, self.nc = system.n, system.nc
        self._open(fmu_path, "dfo_system3_")
        try:
            self.vars = self.md.variables
            for name in ("n", "nc"):
                v = self.vars.get(name)
                if v is None or v.causality != "structuralParameter":
                    raise FMUFileError(f"{self.path} has no structural parameter {name}: not the FMI 3.0 system FMU")
            self.inst = fmi3.Instance(self.unzip_dir, self.md.guid, self.md.model_identifier, "system", logging)
        except BaseException:
            shutil.rmtree(self.unzip_dir, ignore_errors=True)
            raise
        self._fresh = True
        #: Initialization Mode states of the starts (fmi3GetFMUState) of up to four start times,
        #: each with the start values it holds, restored by a start at the same time (a shooting
        #: method's map evaluations); for another system of these sizes restored with only the
        #: values that differ set (omega along a sweep), then kept again
        self._init: dict[float, tuple[Any, dict[str, Any]]] = {}
        self._values: tuple[Any, dict[str, Any]] = (None, {})  # (system, its start values)
        self._step = self.inst.step_function()
        sizes = {"n": self.n, "nc": self.nc, None: 1}
        self._nreal = sum(sizes[d] for _, d in _REALS)
        self._get_reals = self.inst.bulk_get("Float64", [self.vars[k].vr for k, _ in _REALS], self._nreal)
        mode = self.vars["mode"]
        self._mode_dtype = fmi3.DTYPES[mode.call_type]
        self._get_modes = self.inst.bulk_get(mode.call_type, [mode.vr], self.nc) if self.nc else None
        obs = [self.vars[k].vr for k in OBSERVABLES]
        self._get_obs = self.inst.bulk_get("Float64", obs, 2 * self.n + self.nc)
        tr = self.vars["transitions"]
        self._tr_dtype = fmi3.DTYPES[tr.call_type]
        self._get_tr = self.inst.bulk_get(tr.call_type, [tr.vr], self.nc) if self.nc else None
        self._observe = True
        self.time = 0.0
        # the Jacobian's nine blocks: one bulk read, each block's rows and columns in J
        n, nc = self.n, self.nc
        size = {"x": n, "v": n, "s": nc, "x0": n, "v0": n, "s0": nc}
        at = {"x": 0, "v": n, "s": 2 * n, "x0": 0, "v0": n, "s0": 2 * n}
        blocks = [(name, r, c) for name, r, c in JACOBIAN if size[r] * size[c]]
        self._njac = sum(size[r] * size[c] for _, r, c in blocks)
        self._get_jac = self.inst.bulk_get("Float64", [self.vars[name].vr for name, _, _ in blocks], self._njac)
        self._jac_at = [(slice(at[r], at[r] + size[r]), slice(at[c], at[c] + size[c])) for _, r, c in blocks]
        ends = np.cumsum([size[r] * size[c] for _, r, c in blocks]).tolist()
        self._jac_cut = list(zip([0, *ends[:-1]], ends))
        self._cuts = np.cumsum([n, n, n, nc, nc]).tolist()

    def array_size(self, name: str) -> int:
        """The size of an array variable for this system (n, nc, n x n, nc x n or nc x nc)."""
        dims = {"M": self.n * self.n, "C": self.n * self.n, "K": self.n * self.n, "W": self.nc * self.n}
        if name in dims:
            return dims[name]
        square = {"dx_dx0", "dx_dv0", "dv_dx0", "dv_dv0"}
        if name in square:
            return self.n * self.n
        if name in {"dx_ds0", "dv_ds0", "ds_dx0", "ds_dv0"}:
            return self.n * self.nc
        if name == "ds_ds0":
            return self.nc * self.nc
        per = {"F_c", "F_s", "x0", "v0", "F_ext", "x", "v", "a", "x_max", "x_min"}
        return self.n if name in per else self.nc

    def _size_token(self) -> int:
        return self.n * 4096 + self.nc

    # ---- a run ----------------------------------------------------------------------------------
    def _inputs(self, values: Mapping[str, Any]) -> list[tuple[int, list[float]]]:
        """The inputs by value reference, checked (ValueError naming the input)."""
        todo = []
        for name, value in values.items():
            if name not in INPUTS:
                raise ValueError(f"the system's inputs are {', '.join(INPUTS)}, not {name!r}")
            size = self.n if INPUTS[name] == "n" else self.nc
            if size:
                todo.append((self.vars[name].vr, expand(name, value, size).tolist()))
        return todo

    def set_inputs(self, values: Mapping[str, Any]) -> None:
        """Set ``F_ext`` (n values), ``N_ext`` and/or ``v_belt`` (nc values; one number for every
        element); they hold until set again."""
        for vr, vals in self._inputs(values):
            self.inst.set("Float64", [vr], vals)

    def start(self, start_time: float = 0.0, inputs: Mapping[str, Any] | None = None, *, observe: bool = True,
              t_obs_start: float | None = None, t_obs_stop: float | None = None, sensitivity: bool = False,
              x0: Any = None, v0: Any = None, f0: Any = None, slide0: Any = None) -> None:
        """A fresh run of the system from ``start_time``: reset (after the first), ``n`` and ``nc``
        in Configuration Mode, the system's values, ``inputs`` and the observation window in
        Initialization Mode. ``observe``: compute the observables x_max, x_min, stick_fraction
        (default true; false saves their cost and they read NaN); their window from ``t_obs_start``
        (default ``start_time``) to ``t_obs_stop`` (default :data:`T_OBS_STOP`, open; >= t_obs_start).
        ``sensitivity``: propagate the located map's Jacobian (read with
        :meth:`~dryfriction.drivers.system.SystemFMU3.jacobian`). ``x0``, ``v0`` (n values) and ``f0``
        (nc: each Jenkins spring's initial force, its slider stuck at ``w_j . x0 + f0_j / k_t``) and
        ``slide0`` (nc: -1 or +1 a Jenkins slider sliding that way at the start, its force the kinetic
        one; 0 stuck) start the run from another state than the system's."""
        todo = self._inputs(inputs or {})  # checked before the FMU is touched
        state = {name: expand(name, value, size).tolist()
                 for name, value, size in (("x0", x0, self.n), ("v0", v0, self.n), ("f0", f0, self.nc))
                 if value is not None and size}
        w0 = float(start_time) if t_obs_start is None else float(t_obs_start)
        w1 = T_OBS_STOP if t_obs_stop is None else float(t_obs_stop)
        if not (np.isfinite(w0) and np.isfinite(w1) and w1 >= w0):
            raise ValueError(f"the observation window [t_obs_start, t_obs_stop] = [{w0!r}, {w1!r}] must be finite "
                             "with t_obs_stop >= t_obs_start")
        inst = self.inst
        if self._values[0] is not self.system:
            self._values = (self.system, self.system.start_values())
        values = self._values[1]
        key = float(start_time)
        kept = self._init.get(key)
        if kept is not None:
            # a kept Initialization Mode state at this start time restored (its values bit for bit
            # what setting them anew gives); where it holds another system's, the values that differ
            # set (n and nc are this instance's) and the state kept again; then this run's own values
            kept_state, held = kept
            inst.set_state(kept_state)
            if held is not values:
                self._set_start_values({name: value for name, value in values.items() if held.get(name) != value})
                self._init[key] = (inst.get_state(kept_state), values)
        else:
            if not self._fresh:
                inst.reset()
            self._fresh = False
            inst.enter_configuration_mode()
            inst.set("UInt64", [self.vars["n"].vr, self.vars["nc"].vr], [self.n, self.nc])
            inst.exit_configuration_mode()
            inst.enter_initialization_mode(float(start_time))
            self._set_start_values({name: value for name, value in values.items() if name not in ("n", "nc")})
            # (a shooting method alternates a few start times: 4 kept, a fifth replaces the one
            # kept first, its memory reused)
            into = self._init.pop(next(iter(self._init)))[0] if len(self._init) >= 4 else None
            self._init[key] = (inst.get_state(into), values)
        # (the window and the run's state in one call: their value references and values in order)
        vrs, vals = [self.vars["t_obs_start"].vr, self.vars["t_obs_stop"].vr], [w0, w1]
        for name, values in state.items():
            vrs.append(self.vars[name].vr)
            vals.extend(values)
        inst.set("Float64", vrs, vals)
        inst.set("Boolean", [self.vars["observe"].vr, self.vars["sensitivity"].vr], [bool(observe), bool(sensitivity)])
        self._observe = bool(observe)
        if slide0 is not None and self.nc:
            v = self.vars["slide0"]
            inst.set(v.call_type, [v.vr], [int(m) for m in np.broadcast_to(np.asarray(slide0), (self.nc,))])
        for vr, vals in todo:
            inst.set("Float64", [vr], vals)
        inst.exit_initialization_mode()
        self.time = float(start_time)

    def _set_start_values(self, values: Mapping[str, Any]) -> None:
        """Some of :meth:`~dryfriction.system.structure.System.start_values` set (Initialization
        Mode): one call per type, the variables in the order given."""
        calls: dict[str, tuple[list[int], list[Any]]] = {}
        for name, value in values.items():
            v = self.vars[name]
            vals = [value] if np.ndim(value) == 0 else value
            if len(vals):
                vrs, all_vals = calls.setdefault(v.call_type, ([], []))
                vrs.append(v.vr)
                all_vals.extend(vals)
        for kind, (vrs, all_vals) in calls.items():
            self.inst.set(kind, vrs, all_vals)

    def outputs(self) -> dict[str, np.ndarray]:
        """The current outputs (x, v, a, f, s, mode arrays; E_friction a 0-d array)."""
        reals = np.empty(self._nreal)
        modes = np.zeros(self.nc, dtype=self._mode_dtype)
        self._get_reals(reals.ctypes.data)
        if self._get_modes is not None:
            self._get_modes(modes.ctypes.data)
        return dict(zip(OUTPUTS, (*self._split(reals), modes.astype(np.int8)), strict=True))

    def jacobian(self) -> np.ndarray:
        """The located map's Jacobian d(x, v, s)/d(x0, v0, s0) since the run's start, (2 n + nc)
        square (rows and columns: x, v, then each contact's slider; a rigid contact's row and column
        0), of a run started with ``sensitivity=True``; NaN where the FMU did not compute it (it logs
        why: a :class:`~dryfriction.errors.DryFrictionWarning`)."""
        vals = np.empty(self._njac)
        self._get_jac(vals.ctypes.data)  # (the nine blocks in one call, row-major each)
        self.inst.flush_warnings()
        J = np.zeros((2 * self.n + self.nc, 2 * self.n + self.nc))
        for (rows, cols), (a, b) in zip(self._jac_at, self._jac_cut):
            J[rows, cols] = vals[a:b].reshape(rows.stop - rows.start, cols.stop - cols.start)
        return J

    def _split(self, reals: np.ndarray) -> list[np.ndarray]:
        """x, v, a, f, s, E_friction of the FMU's values (along the last axis)."""
        parts = np.split(reals, self._cuts, axis=-1)
        parts[-1] = parts[-1][..., 0]
        return parts

    def do_step(self, dt: float) -> None:
        """One communication step of ``dt`` from the current time."""
        if not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be a finite number > 0, not {dt!r}")
        self._step(self.time, dt)
        self.time = self.time + dt

    def record_at(self, times: Iterable[float] | np.ndarray, inputs: Inputs | None = None) -> SystemRun:
        """Step from the current time through ``times`` (strictly increasing; the first is the
        current time), reading the outputs at each. ``inputs``: values held from now on, or a
        function ``(t, outputs) -> values`` called before each step."""
        t, reals, modes = self._walk(times, inputs, True)
        assert reals is not None
        x, v, a, f, s, E = self._split(reals)
        x_max, x_min, sf = self.observables()
        return SystemRun(t, x, v, a, f, s, E, modes, x_max, x_min, sf, self.transitions())

    def modes_at(self, times: Iterable[float] | np.ndarray) -> np.ndarray:
        """Step as :meth:`record_at` does, reading only the contacts' modes at each time: [nt, nc]
        int8 (-1, 0, +1), its ``mode`` without the other outputs (a section's sampled cycle)."""
        return self._walk(times, None, False)[2]

    def _walk(self, times: Iterable[float] | np.ndarray, inputs: Inputs | None,
              with_reals: bool) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
        """Step through ``times`` (checked), reading the modes and, ``with_reals``, the real outputs
        at each: (t, reals [nt, *] or None, modes [nt, nc] int8)."""
        t = np.asarray(list(times) if not isinstance(times, np.ndarray) else times, dtype=float)
        if t.ndim != 1 or t.size < 1 or not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
            raise ValueError("the output times must be a non-empty, finite, strictly increasing 1-D sequence")
        if t[0] != self.time:
            raise ValueError(f"the first output time {t[0]!r} must be the current time {self.time!r}")
        if inputs is not None and not callable(inputs):
            self.set_inputs(inputs)
        reals = np.empty((t.size, self._nreal)) if with_reals else None
        modes = np.zeros((t.size, self.nc), dtype=self._mode_dtype)
        get_reals = self._get_reals if with_reals else None
        get_modes, step = self._get_modes, self._step
        base_r, row_r = (reals.ctypes.data, reals.strides[0]) if reals is not None else (0, 0)
        base_m, row_m = modes.ctypes.data, modes.strides[0]
        if get_reals is not None:
            get_reals(base_r)
        if get_modes is not None:
            get_modes(base_m)
        tl = t.tolist()
        for i in range(1, t.size):
            if callable(inputs):
                self.set_inputs(inputs(self.time, self.outputs()))
            step(self.time, tl[i] - self.time)
            self.time = tl[i]
            if get_reals is not None:
                get_reals(base_r + i * row_r)
            if get_modes is not None:
                get_modes(base_m + i * row_m)
        self.inst.flush_warnings()
        return t, reals, modes.astype(np.int8)

    def observables(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The in-FMU observables now: x_max, x_min (n) and stick_fraction (nc) over the observation
        window up to the current time (NaN each when the run was started with ``observe=False``)."""
        n, nc = self.n, self.nc
        if not self._observe:
            return np.full(n, np.nan), np.full(n, np.nan), np.full(nc, np.nan)
        vals = np.empty(2 * n + nc)
        self._get_obs(vals.ctypes.data)
        self.inst.flush_warnings()
        return vals[:n].copy(), vals[n:2 * n].copy(), vals[2 * n:].copy()

    def transitions(self) -> np.ndarray:
        """Each contact's mode changes in the observation window up to the current time (a stop, a
        breakaway, a direct reversal: one each), nc integers; -1 each when the run was started with
        ``observe=False``."""
        out = np.zeros(self.nc, dtype=self._tr_dtype)
        if self._get_tr is not None:
            self._get_tr(out.ctypes.data)
            self.inst.flush_warnings()
        return out.astype(np.int64)

    def run(self, t_stop: float, dt: float, inputs: Inputs | None = None, start_time: float = 0.0, *,
            observe: bool = True, t_obs_start: float | None = None, t_obs_stop: float | None = None) -> SystemRun:
        """A fresh run (:meth:`start`, with the observation window's options) to ``t_stop`` on the
        grid ``start_time + k dt`` (the last step shortened). Inputs given as values are set in
        Initialization Mode and held."""
        times = grid(float(start_time), float(t_stop), float(dt))
        held = None if inputs is None or callable(inputs) else inputs
        self.start(start_time, held, observe=observe, t_obs_start=t_obs_start, t_obs_stop=t_obs_stop)
        return self.record_at(times, inputs if callable(inputs) else None)

    def trajectory(self, times: Iterable[float] | np.ndarray, inputs: Inputs | None = None, *, observe: bool = True,
                   t_obs_start: float | None = None, t_obs_stop: float | None = None) -> SystemRun:
        """A fresh run (:meth:`start` at ``times[0]``, with the observation window's options) with
        the outputs at ``times``."""
        t = np.asarray(list(times) if not isinstance(times, np.ndarray) else times, dtype=float)
        if t.ndim != 1 or t.size < 1:
            raise ValueError("the output times must be a non-empty 1-D sequence")
        held = None if inputs is None or callable(inputs) else inputs
        self.start(float(t[0]), held, observe=observe, t_obs_start=t_obs_start, t_obs_stop=t_obs_stop)
        return self.record_at(t, inputs if callable(inputs) else None)

    def __enter__(self) -> "SystemFMU3":
        return self


def run(system: "Structure", t_end: float, dt: float | None = None, inputs: Inputs | None = None, *,
        start_time: float = 0.0, fmu_path: str | os.PathLike[str] | None = None, observe: bool = True,
        t_obs_start: float | None = None, t_obs_stop: float | None = None) -> SystemRun:
    """``system`` through the FMI 3.0 FMU from ``start_time`` to ``t_end``, the outputs every ``dt``
    (default: 1/100 of the excitation's period, or of the time span without one); the observation
    window's options as :meth:`SystemFMU3.start`'s."""
    if dt is None:
        span = float(t_end) - float(start_time)
        dt = 2.0 * np.pi / system.omega / 100.0 if system.omega > 0 else span / 100.0
        dt = min(dt, span) if span > 0 else 1.0
    with SystemFMU3(system, fmu_path) as fmu:
        return fmu.run(t_end, dt, inputs, start_time, observe=observe, t_obs_start=t_obs_start,
                       t_obs_stop=t_obs_stop)


def trajectory(system: "Structure", times: Iterable[float] | np.ndarray, inputs: Inputs | None = None, *,
               fmu_path: str | os.PathLike[str] | None = None, observe: bool = True,
               t_obs_start: float | None = None, t_obs_stop: float | None = None) -> SystemRun:
    """``system`` through the FMI 3.0 FMU with the outputs at ``times`` (the first: the start); the
    observation window's options as :meth:`SystemFMU3.start`'s."""
    with SystemFMU3(system, fmu_path) as fmu:
        return fmu.trajectory(times, inputs, observe=observe, t_obs_start=t_obs_start, t_obs_stop=t_obs_stop)
