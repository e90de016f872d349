"""A fast driver for the FMI 2.0 DryFrictionOscillator FMU: :class:`OscillatorFMU2`; the FMI 3.0
one is :class:`~dryfriction.drivers.oscillator3.OscillatorFMU3`.

The FMU is unzipped and instantiated once through :mod:`dryfriction.fmi.fmi2`; every run then
costs only reset, setup, the parameter values and the steps. Every FMI status is checked: an error
is raised as :class:`~dryfriction.errors.FMUCallError` naming the function, the status and the
FMU's own logged sentence. Names, value references, scheme names, effect bits and defaults come
from the model description (:mod:`dryfriction.model`).
"""

from __future__ import annotations

import ctypes
import os
import shutil
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, fields
from operator import attrgetter
from typing import Any

import numpy as np

from .. import model, paths
from .base import Driver, Run, Switch, grid
from ..errors import FMUCallError, FMUError
from ..fmi import fmi2
from ..fmi._base import State
from ..model import default_fmu_path
from ..params import Oscillator

__all__ = ["FMUError", "FMUCallError", "OscillatorFMU2", "Run", "Switch",
           "Settings", "Restarts", "State", "default_fmu_path", "TRAJECTORY_OUTPUTS", "OBSERVABLE_OUTPUTS", "SCHEMES",
           "EFFECT_BITS"]

#: scheme name -> enumeration value and effect bit -> name, both read from the model description
#: on first use (derived, not copies: ``model.default().schemes`` / ``.effects``)
SCHEMES: Mapping[str, int] = model.LazyMapping(lambda: model.default().schemes)
EFFECT_BITS: Mapping[int, str] = model.LazyMapping(lambda: {e.bit: e.name for e in model.default().effects})
TRAJECTORY_OUTPUTS = ("x", "v", "a", "F_friction", "mode")
#: the in-FMU observables (computed with ``observe = true``; read with it off the FMU gives NaN, -1 for
#: ``transitions``, and this driver refuses to ask for them)
OBSERVABLE_OUTPUTS = ("x_max", "x_min", "stick_fraction", "transitions", "E_friction")


def _start(name: str) -> Any:
    return model.default().var(name).start


def _scheme_start() -> str:
    md = model.default()
    value = md.var("scheme").start
    return next(n for n, v in md.schemes.items() if v == value)


@dataclass
class Settings:
    """Numerical and scene settings of one run (FMU variable names; defaults: the model's starts, except
    ``observe``: off unless a run reads the observables, so that runs which do not pay nothing for them
    per step; :meth:`OscillatorFMU2.observables` and the scenes that read them turn it on)."""

    h: float | None = None            # internal step, s (None: period / 1000; 0: the FMU derives it)
    alpha: float = field(default_factory=lambda: float(_start("alpha")))
    scheme: str = field(default_factory=_scheme_start)
    frictionUpdates: int = field(default_factory=lambda: int(_start("frictionUpdates")))
    observe: bool = False             # the FMU's start is true (every read computed, for any host)
    t_obs_start: float = field(default_factory=lambda: float(_start("t_obs_start")))
    t_obs_stop: float = field(default_factory=lambda: float(_start("t_obs_stop")))
    fastPaths: bool = field(default_factory=lambda: bool(_start("fastPaths")))
    # the sliding friction law (docs/belt.md): 1 coulomb, 2 stribeck with v_s (m/s) and delta
    friction_law: int = field(default_factory=lambda: int(_start("friction_law")))
    v_s: float = field(default_factory=lambda: float(_start("v_s")))
    delta: float = field(default_factory=lambda: float(_start("delta")))
    extra: dict[str, Any] = field(default_factory=dict)


_OSC_FIELDS = tuple(f.name for f in fields(Oscillator))
_SETTINGS_REALS = ("h", "alpha", "t_obs_start", "t_obs_stop", "v_s", "delta")


class OscillatorFMU2(Driver):
    """One loaded, instantiated FMI 2.0 oscillator FMU, reused across runs (not thread-safe: one
    per thread/worker). :meth:`start` sets an :class:`Oscillator` and :class:`Settings`, then
    :meth:`do_step` / :meth:`step_to` / :meth:`run` step and :meth:`get` reads.

    Parameters
    ----------
    fmu_path
        The FMU; default: the environment's ``DFO_FMU``, the installed package's, the checkout's
        ``build/`` (:mod:`dryfriction.paths`).
    logging
        Switch the FMU's debug logging on (its messages become warnings and log records).

    Raises
    ------
    dryfriction.FMUFileError
        ``fmu_path`` is not the FMI 2.0 oscillator FMU (one sentence says why).
    dryfriction.FMUCallError
        A call the FMU refuses, with the FMU's sentence (the instance stays usable).

    Examples
    --------
    >>> from dryfriction import Oscillator, OscillatorFMU2, Settings
    >>> block = Oscillator.physical(m=0.5, k=2000, zeta=0.003, P0=10, f=10, N=20, mu_s=0.3, mu_k=0.2)
    >>> with OscillatorFMU2() as fmu:
    ...     obs = fmu.observables(block, t_stop=100 * block.period, t_obs_start=99 * block.period)
    ...     traj = fmu.trajectory(block, [i * block.period / 100 for i in range(101)], Settings(h=0))
    """

    KIND = paths.OSCILLATOR

    def __init__(self, fmu_path: str | os.PathLike[str] | None = None, logging: bool = False) -> None:
        # the FMI 2.0 oscillator FMU: fmu_path, else $DFO_FMU, the package's, the build tree's;
        # checked (paths.FMUFileError if it is not that FMU)
        self._open(fmu_path, "dfo-fmu-")
        try:
            self.inst = fmi2.Instance(self.unzip_dir, self.md.guid, self.md.model_identifier, "dfo", logging)
        except BaseException:
            shutil.rmtree(self.unzip_dir, ignore_errors=True)
            raise
        #: the FMI layer's instance (:class:`dryfriction.fmi.fmi2.Instance`)
        self.fmi = self.inst
        self.vars = self.md.variables
        self._get_plans: dict[tuple[str, ...], list[tuple[str, Any, Any, Any, list[str]]]] = {}
        #: the initialisation-mode FMU states of :class:`Restarts`, one per set of Real parameters
        #: set per run and of Integer and Boolean values (freed with the instance)
        self._restart_templates: dict[tuple[Any, ...], Any] = {}
        self._prepare_start()

    def __enter__(self) -> "OscillatorFMU2":
        return self

    # ---- values ----
    def set(self, values: Mapping[str, Any]) -> None:
        """Set variables by name, grouped per type, with the FMU's checks."""
        groups: dict[str, tuple[list[int], list[Any]]] = {"Real": ([], []), "Integer": ([], []), "Boolean": ([], [])}
        for name, value in values.items():
            var = self.vars.get(name)
            if var is None:
                raise FMUError(f"unknown variable {name!r}")
            if var.type == "Enumeration" and isinstance(value, str):
                try:
                    value = self.md.scheme_value(value)
                except ValueError as e:
                    raise FMUError(str(e)) from None
            vrs, vals = groups[var.call_type]
            vrs.append(var.vr)
            vals.append(value)
        for kind, (vrs, vals) in groups.items():
            if vrs:
                self.fmi.set(kind, vrs, vals)

    def get(self, names: str | Sequence[str]) -> Any:
        """Read variables by name: one FMI call per type, with the arrays cached per name list (a
        single name: its value)."""
        if isinstance(names, str):
            return self.get((names,))[names]
        key = tuple(names)
        plan = self._get_plans.get(key)
        if plan is None:
            plan = self._get_plans[key] = self._plan_get(key)
        inst = self.fmi
        c, out, mark = inst.component, {}, len(inst.messages)
        for fname, fn, vrs, buf, group in plan:
            st = fn(c, vrs, len(group), buf)
            if st:
                inst.check(fname, st, mark)
            out.update(zip(group, buf))
        return {name: out[name] for name in key}

    def _plan_get(self, names: tuple[str, ...]) -> list[tuple[str, Any, Any, Any, list[str]]]:
        groups: dict[str, list[str]] = {"Real": [], "Integer": [], "Boolean": []}
        for name in names:
            var = self.vars.get(name)
            if var is None:
                raise FMUError(f"unknown variable {name!r}")
            groups[var.call_type].append(name)
        ctype = {"Real": ctypes.c_double, "Integer": ctypes.c_int, "Boolean": ctypes.c_int}
        plan = []
        for kind, group in groups.items():
            if group:
                vrs = (ctypes.c_uint * len(group))(*[self.vars[g].vr for g in group])
                plan.append((f"fmi2Get{kind}", getattr(self.fmi.f, f"Get{kind}"), vrs, (ctype[kind] * len(group))(),
                             group))
        return plan

    def last_successful_time(self) -> float:
        """The time the last ``fmi2DoStep`` reached (``fmi2GetRealStatus``), s."""
        return self.fmi.last_successful_time()

    def reset(self) -> None:
        """Reset the instance to its instantiated state (``fmi2Reset``), time 0."""
        self.fmi.reset()
        self.time = 0.0

    def set_debug_logging(self, on: bool, categories: Sequence[str] = ()) -> None:
        """Switch the FMU's logging on or off for the given log categories (all when none is given)."""
        self.fmi.set_debug_logging(on, categories)

    # ---- runs ----
    def _prepare_start(self) -> None:
        """Value-reference and value arrays of the standard parameters, built once: the Real
        parameters of the model are the Oscillator's fields and the Real settings."""
        md = self.md
        reals = _OSC_FIELDS + _SETTINGS_REALS
        declared = {n for n, v in md.variables.items() if v.causality == "parameter" and v.type == "Real"}
        if set(reals) != declared:
            raise FMUError(f"the FMU's Real parameters {sorted(declared)} are not those of this package "
                           f"{sorted(reals)}")
        self._osc_values = attrgetter(*_OSC_FIELDS)
        self._rvr = (ctypes.c_uint * len(reals))(*[md.vr(n) for n in reals])
        self._rval = (ctypes.c_double * len(reals))()
        self._ivr = (ctypes.c_uint * 3)(md.vr("scheme"), md.vr("frictionUpdates"), md.vr("friction_law"))
        self._ival = (ctypes.c_int * 3)()
        self._bvr = (ctypes.c_uint * 2)(md.vr("observe"), md.vr("fastPaths"))
        self._bval = (ctypes.c_int * 2)()
        self._schemes = md.schemes

    def start(self, p: Oscillator, settings: Settings | None = None, t0: float = 0.0) -> None:
        """Reset, set every parameter and initialise: the FMU is then at t0 in step mode.

        The standard parameters go through the FMU's C functions with value arrays built once
        (a few microseconds of host time per run); ``settings.extra`` through :meth:`set`."""
        st = settings or Settings()
        scheme = self._schemes.get(st.scheme)
        if scheme is None:
            raise FMUError(f"scheme must be one of {', '.join(self._schemes)}, not {st.scheme!r}")
        h = st.h if st.h is not None else (p.period / 1000.0 if p.omega > 0 else 0.0)
        self._rval[:] = self._osc_values(p) + (h, st.alpha, st.t_obs_start, st.t_obs_stop, st.v_s, st.delta)
        self._ival[0], self._ival[1], self._ival[2] = scheme, st.frictionUpdates, st.friction_law
        self._bval[0], self._bval[1] = int(bool(st.observe)), int(bool(st.fastPaths))
        inst = self.fmi
        f, c, n = inst.f, inst.component, len(inst.messages)
        if s := f.Reset(c):
            inst.check("fmi2Reset", s, n)
        if s := f.SetupExperiment(c, 0, 0.0, float(t0), 0, 0.0):
            inst.check("fmi2SetupExperiment", s, n)
        if s := f.SetReal(c, self._rvr, len(self._rval), self._rval):
            inst.check("fmi2SetReal", s, n)
        if s := f.SetInteger(c, self._ivr, 3, self._ival):
            inst.check("fmi2SetInteger", s, n)
        if s := f.SetBoolean(c, self._bvr, 2, self._bval):
            inst.check("fmi2SetBoolean", s, n)
        if st.extra:
            self.set(st.extra)
        if s := f.EnterInitializationMode(c):
            inst.check("fmi2EnterInitializationMode", s, n)
        if s := f.ExitInitializationMode(c):
            inst.check("fmi2ExitInitializationMode", s, n)
        self.time = t0

    def restarts(self, p: Oscillator, settings: Settings | None = None, reals: Sequence[str] = ("x", "v"),
                 ints: Sequence[str] = ()) -> "Restarts":
        """Repeated runs of ``p`` with ``settings`` from varying initial states and start times, the
        FMU's calls of :meth:`start` with every value array filled once (:class:`Restarts`)."""
        return Restarts(self, p, settings or Settings(), reals, ints)

    def do_step(self, dt: float, *legacy: float) -> None:
        """One fmi2DoStep of length ``dt`` from the current communication point :attr:`time`
        (checked); :attr:`time` is then time + dt.

        Compatibility: the signature ``do_step(t, dt)`` is accepted too, ``t`` being the
        current communication point as the host counts it (``k dt`` rather than the sum of the
        steps; the FMU checks that it is its own time, to its grid's tolerance, and refuses it
        otherwise); :attr:`time` is then t + dt."""
        t = self.time
        if legacy:
            t, dt = dt, legacy[0]
        self.fmi.do_step(t, dt)
        self.time = t + dt

    def step_to(self, t: float) -> None:
        """Step from the current time to ``t`` in one ``fmi2DoStep`` (FMUCallError with the FMU's sentence if
        it fails)."""
        inst = self.fmi
        mark = len(inst.messages)
        if s := inst.f.DoStep(inst.component, float(self.time), float(t - self.time), 1):
            inst.check("fmi2DoStep", s, mark)
        self.time = t

    def run(self, t_stop: float, dt: float, outputs: Sequence[str] = ("x", "v", "mode"), *,
            p: Oscillator | None = None, settings: Settings | None = None) -> Run:
        """Step from the current time t0 (after :meth:`start` with ``p`` and ``settings`` when
        ``p`` is given) to ``t_stop`` on the grid ``t0 + k dt`` (the last step shortened), sampling
        ``outputs`` at t0 and every point: a :class:`~dryfriction.drivers.base.Run` (FMI 2.0 has no early
        return: no switches)."""
        if p is not None:
            self.start(p, settings)
        times = grid(self.time, t_stop, dt)
        return Run(times, self._sample(times, outputs))

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
        st = settings or Settings()
        if not st.observe and set(outputs) & set(OBSERVABLE_OUTPUTS):
            raise ValueError(f"the observables {', '.join(sorted(set(outputs) & set(OBSERVABLE_OUTPUTS)))} "
                             "need Settings(observe=True)")
        self.start(p, st, float(t[0]))
        res: dict[str, np.ndarray] = {"t": t}
        res.update(self._sample(t, outputs))
        return res

    def _sample(self, t: np.ndarray, outputs: Sequence[str]) -> dict[str, np.ndarray]:
        """Step through the points ``t`` (the first is the current time) reading ``outputs`` at
        each; :attr:`time` is then t[-1]."""
        reals = [i for i, n in enumerate(outputs) if self.md.var(n).type == "Real"]
        ints = [i for i, n in enumerate(outputs) if self.md.var(n).type != "Real"]
        rows_r: list[list[float]] = []
        rows_i: list[list[int]] = []
        # the C functions with buffers built once: a sample costs one doStep and two gets
        inst = self.fmi
        comp, check, msgs = inst.component, inst.check, inst.messages
        do_step, get_real, get_int = inst.f.DoStep, inst.f.GetReal, inst.f.GetInteger
        rv = (ctypes.c_uint * len(reals))(*[self.vr(outputs[i]) for i in reals])
        iv = (ctypes.c_uint * len(ints))(*[self.vr(outputs[i]) for i in ints])
        rbuf = (ctypes.c_double * len(reals))()
        ibuf = (ctypes.c_int * len(ints))()
        nr, ni = len(reals), len(ints)
        tl = t.tolist()
        for j in range(t.size):
            mark = len(msgs)
            if j:
                if s := do_step(comp, tl[j - 1], tl[j] - tl[j - 1], 1):
                    self.time = tl[j - 1]
                    check("fmi2DoStep", s, mark)
            if nr:
                if s := get_real(comp, rv, nr, rbuf):
                    check("fmi2GetReal", s, mark)
                rows_r.append(rbuf[:])
            if ni:
                if s := get_int(comp, iv, ni, ibuf):
                    check("fmi2GetInteger", s, mark)
                rows_i.append(ibuf[:])
        self.time = tl[-1]
        out = np.empty((t.size, len(outputs)))
        if nr:
            out[:, reals] = np.array(rows_r)
        if ni:
            out[:, ints] = np.array(rows_i)
        return {n: out[:, i] for i, n in enumerate(outputs)}

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
        """Names of the effects the current run simulates (the model's vendor annotation)."""
        name = self.md.effects_variable or "effects"
        return self.md.effect_names(int(self.get([name])[name]))


class Restarts:
    """Runs of one oscillator and one :class:`Settings` from varying initial states (x0, v0) at
    varying start times t0, through one :class:`OscillatorFMU2`, for a host that runs the same model
    from many states, e.g. a shooting method's map evaluations (a few microseconds of host time per
    run).

    The first run makes :meth:`OscillatorFMU2.start`'s calls up to initialisation mode (reset, setup
    at time 0, every parameter, ``settings.extra`` included, enter initialisation) and keeps that
    FMU state (fmi2GetFMUstate, one per FMU instance, set of Reals and Integer and Boolean values); every
    run restores it, sets the Real parameters (one call, the arrays built once) and leaves
    initialisation: four FMI calls fewer than a reset. The FMU's clock starts at 0 at every run: a
    run "from t0" starts the excitation at its phase at t0 (``phi`` + ``omega`` t0 in place of
    ``phi``: the same motion, shifted in time; the observation window is [0, t_end - t0]).

    After :meth:`run`, :attr:`real` holds the values of ``reals`` at t_end, :attr:`int` those of
    ``ints``, :attr:`mid` (x, v) at the intermediate stop when one was asked for (else None); the
    driver's :attr:`OscillatorFMU2.time` is the FMU's clock, t_end - t0. :meth:`retarget` moves it
    to another oscillator with the same settings. Every FMI status is checked as in
    :meth:`OscillatorFMU2.start`."""

    def __init__(self, fmu: OscillatorFMU2, p: Oscillator, settings: Settings, reals: Sequence[str],
                 ints: Sequence[str]) -> None:
        st = settings
        self.fmu, self.settings = fmu, st
        scheme = fmu._schemes.get(st.scheme)
        if scheme is None:
            raise FMUError(f"scheme must be one of {', '.join(fmu._schemes)}, not {st.scheme!r}")
        md = fmu.md
        # the standard arrays of start, then settings.extra grouped per type (a name of the standard
        # arrays given again in extra: its value replaces the standard one, as start's later set does)
        rnames = list(_OSC_FIELDS + _SETTINGS_REALS)
        inames, bnames = ["scheme", "frictionUpdates", "friction_law"], ["observe", "fastPaths"]
        ivals: list[int] = [scheme, st.frictionUpdates, st.friction_law]
        bvals: list[int] = [int(bool(st.observe)), int(bool(st.fastPaths))]
        self._extra_reals: dict[str, float] = {}
        for name, value in st.extra.items():
            var = fmu.vars.get(name)
            if var is None:
                raise FMUError(f"unknown variable {name!r}")
            if var.call_type == "Real":
                if name not in rnames:
                    rnames.append(name)
                self._extra_reals[name] = float(value)
                continue
            if var.type == "Enumeration" and isinstance(value, str):
                try:
                    value = md.scheme_value(value)
                except ValueError as e:
                    raise FMUError(str(e)) from None
            names, vals = (inames, ivals) if var.call_type == "Integer" else (bnames, bvals)
            if name in names:
                vals[names.index(name)] = int(value)
            else:
                names.append(name)
                vals.append(int(value))
        self._rnames = rnames
        #: (index, value) of the Real extras, written over the standard values at each retarget
        self._extra_at = [(rnames.index(n), v) for n, v in self._extra_reals.items()]
        self._rvr = (ctypes.c_uint * len(rnames))(*[md.vr(n) for n in rnames])
        self._rval = (ctypes.c_double * len(rnames))()
        self._nr = len(rnames)
        self._ivr = (ctypes.c_uint * len(inames))(*[md.vr(n) for n in inames])
        self._ival = (ctypes.c_int * len(inames))(*ivals)
        self._ni = len(inames)
        self._bvr = (ctypes.c_uint * len(bnames))(*[md.vr(n) for n in bnames])
        self._bval = (ctypes.c_int * len(bnames))(*bvals)
        self._nb = len(bnames)
        self._ix0, self._iv0 = rnames.index("x0"), rnames.index("v0")
        self._its, self._ite = rnames.index("t_obs_start"), rnames.index("t_obs_stop")
        self._iphi = rnames.index("phi")
        # the template state holds every Integer and Boolean value and the Reals a run does not set
        # (at their start values only if the template's maker set the same Reals: part of the key)
        self._key = (tuple(rnames), tuple(inames), tuple(ivals), tuple(bnames), tuple(bvals))
        self._state: Any = None             # the template (made at the first run)
        self._observe = bool(st.observe)
        for name in reals:
            if md.var(name).call_type != "Real":
                raise FMUError(f"{name!r} is not a Real variable")
        for name in ints:
            if md.var(name).call_type != "Integer":
                raise FMUError(f"{name!r} is not an Integer variable")
        if not st.observe and set(reals) & set(OBSERVABLE_OUTPUTS):
            raise ValueError(f"the observables {', '.join(sorted(set(reals) & set(OBSERVABLE_OUTPUTS)))} "
                             "need Settings(observe=True)")
        self.reals, self.ints = tuple(reals), tuple(ints)
        self._nor, self._noi = len(self.reals), len(self.ints)
        f = fmu.fmi.f
        self._fns = (f.Reset, f.SetupExperiment, f.SetReal, f.SetInteger, f.SetBoolean, f.EnterInitializationMode)
        self._run_fns = (f.SetFMUstate, f.SetReal, f.ExitInitializationMode, f.DoStep, f.GetReal, f.GetInteger)
        self._ovr = (ctypes.c_uint * len(reals))(*[md.vr(n) for n in reals])
        self._oval = (ctypes.c_double * len(reals))()
        self._oivr = (ctypes.c_uint * len(ints))(*[md.vr(n) for n in ints])
        self._oival = (ctypes.c_int * len(ints))()
        self._xvvr = (ctypes.c_uint * 2)(md.vr("x"), md.vr("v"))
        self._xv = (ctypes.c_double * 2)()
        #: the values of ``reals`` / ``ints`` at the end of the last run, (x, v) at its intermediate stop
        self.real: list[float] = []
        self.int: list[int] = []
        self.mid: tuple[float, float] | None = None
        self.retarget(p)

    def retarget(self, p: Oscillator) -> None:
        """Use the oscillator ``p`` (its x0, v0 replaced at each run) with the same settings."""
        st = self.settings
        h = st.h if st.h is not None else (p.period / 1000.0 if p.omega > 0 else 0.0)
        vals = self.fmu._osc_values(p) + (h, st.alpha, st.t_obs_start, st.t_obs_stop, st.v_s, st.delta)
        rv = self._rval
        rv[:len(vals)] = vals
        for i, value in self._extra_at:
            rv[i] = value
        self._phi, self._omega = p.phi, p.omega

    def _template(self) -> Any:
        """The FMU state in initialisation mode with this object's Integer and Boolean values (made
        by the calls of :meth:`OscillatorFMU2.start` once per instance and set of values)."""
        fmu = self.fmu
        inst = fmu.fmi
        state = fmu._restart_templates.get(self._key)
        if state is not None and not state.freed:
            return state
        c, n = inst.component, len(inst.messages)
        reset, setup, set_real, set_int, set_bool, enter = self._fns
        if s := reset(c):
            inst.check("fmi2Reset", s, n)
        if s := setup(c, 0, 0.0, 0.0, 0, 0.0):
            inst.check("fmi2SetupExperiment", s, n)
        if s := set_real(c, self._rvr, self._nr, self._rval):
            inst.check("fmi2SetReal", s, n)
        if s := set_int(c, self._ivr, self._ni, self._ival):
            inst.check("fmi2SetInteger", s, n)
        if s := set_bool(c, self._bvr, self._nb, self._bval):
            inst.check("fmi2SetBoolean", s, n)
        if s := enter(c):
            inst.check("fmi2EnterInitializationMode", s, n)
        state = fmu._restart_templates[self._key] = inst.get_state()
        return state

    def run(self, x0: float, v0: float, t0: float, t_end: float, t_mid: float | None = None) -> None:
        """Start from (x0, v0) at t0 (with ``observe``, the observation window is the run), step to
        t_mid (if given: (x, v) there in :attr:`mid`) and on to t_end in one communication step
        each, and read the outputs (:attr:`real`, :attr:`int`). The FMU's clock runs from 0 to
        t_end - t0 (the class's doc)."""
        fmu = self.fmu
        inst = fmu.fmi
        c, n = inst.component, len(inst.messages)
        set_state, set_real, exit_, do_step, get_real, get_int = self._run_fns
        template = self._state
        if template is None or not template.handle:
            template = self._state = self._template()
        rv = self._rval
        rv[self._ix0], rv[self._iv0] = x0, v0
        rv[self._iphi] = self._phi + self._omega * t0
        t_stop = t_end - t0
        if self._observe:
            rv[self._its], rv[self._ite] = 0.0, t_stop
        if s := set_state(c, template.handle):
            inst.check("fmi2SetFMUstate", s, n)
        if s := set_real(c, self._rvr, self._nr, rv):
            inst.check("fmi2SetReal", s, n)
        if s := exit_(c):
            inst.check("fmi2ExitInitializationMode", s, n)
        fmu.time = t = 0.0
        if t_mid is None:
            self.mid = None
        else:
            t = t_mid - t0
            if s := do_step(c, 0.0, t, 1):
                inst.check("fmi2DoStep", s, n)
            fmu.time = t
            xv = self._xv
            if s := get_real(c, self._xvvr, 2, xv):
                inst.check("fmi2GetReal", s, n)
            self.mid = (xv[0], xv[1])
        if s := do_step(c, t, t_stop - t, 1):
            inst.check("fmi2DoStep", s, n)
        fmu.time = t_stop
        if self._nor:
            if s := get_real(c, self._ovr, self._nor, self._oval):
                inst.check("fmi2GetReal", s, n)
            self.real = self._oval[:]
        if self._noi:
            if s := get_int(c, self._oivr, self._noi, self._oival):
                inst.check("fmi2GetInteger", s, n)
            self.int = self._oival[:]

