"""The master (:class:`~dryfriction.cosim.system.System`): FMUs under instance names, joined by connections and coupling
elements (docs/coupling.md).

    sys = System()
    sys.add("b1", fmu1)                          # started drivers, in step mode at the same time
    sys.add("b2", fmu2)
    sys.couple(SpringDamper("b1", "b2", k=1.0, c=0.1))
    res = sys.run(t_stop=60.0, H=0.05, inputs="extrapolate")

Per macro step H the inputs are ``u = G y`` (:func:`~dryfriction.cosim.coupling.coupling_matrix`)
from the outputs y, either all from the outputs at the step's start (Jacobi) or unit after unit,
each from the newest outputs (Gauss-Seidel). The inputs over the step:

- ``hold``: the value at the start, held (zero-order hold; first order in H),
- ``extrapolate``: held at the mean over the step of the Taylor polynomial of u from the outputs'
  time derivatives (outputs that are derivatives: x' = v, x'' = a, v' = a; or the FMU's output
  derivatives; second order in H with held inputs),
- ``derivatives``: the polynomial itself, sent as input derivatives (FMI 2.0
  fmi2SetRealInputDerivatives; FMI 3.0: the polynomial's value set at every intermediate update).

``correction=True`` (Jacobi, held inputs) adds the interface-Jacobian correction: after a first pass the
master solves ``(I - G S) du = G y(t+H) - u(t+H)`` with ``S = d y(t+H) / d u`` (from extra FMU
steps, ``jacobian="steps"``, or the FMU's directional derivatives of its outputs and their
derivative outputs, ``jacobian="directional"``), goes back to the saved FMU states and steps again
with ``u + du``: linearly implicit, stable for couplings much stiffer than the units.

``tol``: an error estimate per step, the largest difference between the inputs predicted for the
step's end and those computed from the outputs there; above ``tol`` the step is rejected, the FMU
states restored and the step halved (at most ``max_halvings`` times; below ``tol / 4`` it grows back).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..diagnostics import emit
from ..errors import FMUError
from .coupling import Connection, SpringDamper, coupling_matrix, split
from .result import CosimResult
from .unit import Unit

__all__ = ["System", "METHODS", "INPUT_MODES", "JACOBIANS"]

METHODS = ("jacobi", "gauss-seidel")
INPUT_MODES = ("hold", "extrapolate", "derivatives")
JACOBIANS = ("steps", "directional")
DERIVATIVE_SOURCES = ("auto", "outputs", "fmu")
_CAUSALITY_NAMES = {"input": "an input", "output": "an output", "local": "a local variable"}


class System:
    """FMUs coupled through named ports ``"instance.variable"``.

    Add started drivers with :meth:`add`, couple them with :meth:`couple` (a
    :class:`~dryfriction.cosim.coupling.SpringDamper` or a :class:`~dryfriction.cosim.coupling.Connection`)
    and :meth:`run` the master: Jacobi or Gauss-Seidel, inputs held, extrapolated or sent as input
    derivatives, an interface-Jacobian correction, rollback with FMU states.

    Raises
    ------
    ValueError
        A bad coupling element (negative or non-finite k or c, an unknown instance).
    dryfriction.FMUError
        A port that is not a real scalar of its FMU.

    Examples
    --------
    >>> from dryfriction import OscillatorFMU2, Settings
    >>> from dryfriction.cosim import System
    >>> from dryfriction.cosim.split import split_chain2
    >>> chain = dict(m=1.0, k=1.0, c=[0.05, 0.1], P0=[1.0, 0.0], N=[0.8, 0.5], mu_s=0.5, chi=0.7, omega=0.6)
    >>> b1, b2, spring = split_chain2(chain)
    >>> with OscillatorFMU2() as f1, OscillatorFMU2() as f2:
    ...     f1.start(b1, Settings(h=0.0)); f2.start(b2, Settings(h=0.0))
    ...     system = System()
    ...     _ = system.add("b1", f1); _ = system.add("b2", f2)
    ...     system.couple(spring)                 # F on b1.F_ext, -F on b2.F_ext
    ...     res = system.run(t_stop=104.7, H=0.105, inputs="derivatives")
    >>> round(float(res["b1.x"][-1]), 4)     # block 1's position at t = 104.7, m
    1.1841
    """

    def __init__(self) -> None:
        self.units: dict[str, Unit] = {}
        self.elements: list[Connection | SpringDamper] = []

    # ---- building ---------------------------------------------------------------------------------
    def add(self, name: str, driver: Any, derivatives: Mapping[str, tuple[str, ...]] | None = None) -> Unit:
        """Add a started driver under ``name``; ``derivatives`` maps an output to the outputs that
        are its time derivatives (default: x -> v, a and v -> a)."""
        if not name or "." in name:
            raise ValueError(f"an instance name is non-empty without a dot, not {name!r}")
        if name in self.units:
            raise ValueError(f"there is already an instance named {name!r}")
        unit = Unit(name, driver, derivatives)
        self.units[name] = unit
        return unit

    def connect(self, source: str, target: str, gain: float = 1.0) -> None:
        """``target`` (an input port) = ``gain`` * ``source`` (an output port)."""
        self.couple(Connection(source, target, gain))

    def couple(self, element: Connection | SpringDamper) -> None:
        """Add a coupling element (checked now: ValueError or FMUError for a bad one)."""
        element.terms()  # checked now
        self.elements.append(element)

    def _port(self, port: str, *causalities: str) -> tuple[Unit, int]:
        """The unit and value reference of ``port`` (``instance.variable``), a variable of one of
        ``causalities``."""
        uname, var = split(port)
        unit = self.units.get(uname)
        if unit is None:
            raise ValueError(f"{port}: no instance named {uname!r} (instances: {', '.join(self.units) or 'none'})")
        vr = unit.vr(var)
        if unit.causality(var) not in causalities:
            kinds = " or ".join(_CAUSALITY_NAMES.get(c, c) for c in causalities)
            raise ValueError(f"{port} is not {kinds} (its causality is {unit.causality(var)})")
        return unit, vr

    # ---- running ----------------------------------------------------------------------------------
    def run(self, t_stop: float, H: float, *, method: str = "jacobi", inputs: str = "hold", order: int = 2,
            input_order: int = 1, source: str = "auto", correction: bool = False, jacobian: str = "steps",
            tol: float | None = None, max_halvings: int = 8, record: Sequence[str] = (),
            progress: bool = False) -> CosimResult:
        """Co-simulate from the units' common time to ``t_stop`` with macro step ``H`` (the last
        shortened); see the module's text for the options. ``order``: the highest output
        derivative used to extrapolate (1 or 2); ``input_order``: the highest input derivative
        sent (``inputs="derivatives"``, FMI 2.0: 1 or 2); ``source``: where output derivatives
        come from (``outputs``: outputs that are derivatives, ``fmu``: the FMU's own output
        derivatives, ``auto``: the first where known); ``record``: more ports to keep, outputs or local variables
        (the oscillator's Jacobian ``dx_dx0`` ..., read by value reference)."""
        plan = _Plan(self, t_stop, H, method, inputs, order, input_order, source, correction, jacobian, tol,
                     max_halvings, record)
        return plan.run(progress)


class _Plan:
    """One run's arrays and loop."""

    def __init__(self, sys: System, t_stop: float, H: float, method: str, inputs: str, order: int,
                 input_order: int, source: str, correction: bool, jacobian: str, tol: float | None,
                 max_halvings: int, record: Sequence[str]) -> None:
        for name, value, allowed in (("method", method, METHODS), ("inputs", inputs, INPUT_MODES),
                                     ("jacobian", jacobian, JACOBIANS), ("source", source, DERIVATIVE_SOURCES)):
            if value not in allowed:
                raise ValueError(f"{name} must be one of {', '.join(allowed)}, not {value!r}")
        if order not in (1, 2):
            raise ValueError(f"order must be 1 or 2, not {order!r}")
        if input_order not in (1, 2):
            raise ValueError(f"input_order must be 1 or 2, not {input_order!r}")
        if not (isinstance(H, (int, float)) and math.isfinite(H) and H > 0):
            raise ValueError(f"H must be a finite number > 0, not {H!r}")
        if tol is not None and not (math.isfinite(tol) and tol > 0):
            raise ValueError(f"tol must be a finite number > 0 or None, not {tol!r}")
        if not (isinstance(max_halvings, int) and 0 <= max_halvings <= 30):
            raise ValueError(f"max_halvings must be an integer in 0 .. 30, not {max_halvings!r}")
        if correction and method != "jacobi":
            raise ValueError("the interface-Jacobian correction couples every unit at once: method='jacobi'")
        if correction and inputs != "hold":
            # measured: extrapolating the force of a stiff coupling from its outputs' derivatives
            # amplifies the fast mode the correction is there to damp (docs/coupling.md)
            raise ValueError("the interface-Jacobian correction is linearly implicit on held inputs: inputs='hold'")
        if not sys.units:
            raise ValueError("the system has no units")
        if not sys.elements:
            raise ValueError("the system has no connections")
        self.sys, self.method, self.mode, self.order = sys, method, inputs, order
        self.input_order, self.correction, self.jac, self.tol = input_order, correction, jacobian, tol
        self.units = list(sys.units.values())
        times = {u.name: float(u.driver.time) for u in self.units}
        self.t0 = self.units[0].driver.time
        if any(abs(t - self.t0) > 1e-12 * max(1.0, abs(self.t0)) for t in times.values()):
            raise ValueError(f"the units are not at one time: {times}")
        if not (math.isfinite(t_stop) and t_stop > self.t0):
            raise ValueError(f"t_stop must be finite and after the units' time {self.t0!r}, not {t_stop!r}")
        self.t_stop = float(t_stop)
        self.levels = max_halvings if tol is not None else 0
        self.unit_dt = H / 2 ** self.levels
        self.end_pos = max(1, int(math.ceil((self.t_stop - self.t0) / self.unit_dt - 1e-9)))
        self.H = float(H)

        in_ports, out_ports, self.G = coupling_matrix(sys.elements)
        self.in_ports, self.out_ports = in_ports, out_ports
        # each unit's inputs (rows of G) and outputs (columns), with value references
        self.u_in: dict[str, tuple[np.ndarray, list[int]]] = {}
        self.u_out: dict[str, tuple[np.ndarray, list[int]]] = {}
        for store, ports, causality in ((self.u_in, in_ports, "input"), (self.u_out, out_ports, "output")):
            idx: dict[str, tuple[list[int], list[int]]] = {}
            for i, p in enumerate(ports):
                unit, vr = sys._port(p, causality)
                ii, vv = idx.setdefault(unit.name, ([], []))
                ii.append(i)
                vv.append(vr)
            for name, (ii, vv) in idx.items():
                store[name] = (np.array(ii, dtype=int), vv)
        self.record = [p for p in dict.fromkeys(record) if p not in out_ports]
        self.rec_vr = {p: sys._port(p, "output", "local") for p in self.record}
        # where each output's derivatives come from: per unit, per derivative order, a list of
        # (output column, vr, from_fmu)
        self.need_derivs = inputs != "hold"
        self.dsrc: dict[str, list[list[tuple[int, int, bool]]]] = {}
        if self.need_derivs:
            for unit in self.units:
                if unit.name in self.u_out:
                    self.dsrc[unit.name] = self._derivative_sources(unit, source)
        self._check_inputs_mode()
        if correction or tol is not None:
            for unit in self.units:
                if not unit.capabilities.can_get_and_set_state:
                    what = "the correction" if correction else "rollback (tol)"
                    raise FMUError(f"{what} goes back to saved FMU states: {unit.name} does not declare "
                                   "canGetAndSetFMUstate=\"true\"")
        self.y = np.zeros(len(out_ports))
        self.d = np.zeros((2, len(out_ports)))   # first and second time derivatives
        self.ty = np.zeros(len(out_ports))       # the time each column was read at
        self.fmu_steps = 0
        self._grid: dict[str, tuple[float, float]] = {}  # FMI 3.0: the units' input points (last, spacing)

    # ---- set-up checks ----------------------------------------------------------------------------
    def _derivative_sources(self, unit: Unit, source: str) -> list[list[tuple[int, int, bool]]]:
        cols, vrs = self.u_out[unit.name]
        fmu_order = unit.capabilities.max_output_derivative_order
        per_order: list[list[tuple[int, int, bool]]] = [[], []]
        for col, vr in zip(cols, vrs):
            var = split(self.out_ports[col])[1]
            alias = unit.derivative_outputs(var)
            for k in range(self.order):
                if source != "fmu" and k < len(alias):
                    per_order[k].append((int(col), unit.vr(alias[k]), False))
                elif (source == "fmu" or (source == "auto" and not alias)) and k < fmu_order:
                    # auto: the FMU's own only for outputs with no derivative output (v'' would
                    # fail at a step ending on a switch, where a jumps)
                    per_order[k].append((int(col), vr, True))
                elif k == 0:
                    why = (f"{unit.name} declares maxOutputDerivativeOrder={fmu_order}" if source != "outputs"
                           else "source='outputs'")
                    raise FMUError(f"cannot extrapolate {self.out_ports[col]}: no output of {unit.name} is its "
                                   f"time derivative and {why}")
                # a second derivative that is not there: extrapolated to first order
        return per_order

    def _check_inputs_mode(self) -> None:
        if self.mode != "derivatives":
            return
        for name, (rows, vrs) in self.u_in.items():
            unit = self.sys.units[name]
            cap = unit.capabilities
            if not unit.fmi3 and not cap.can_interpolate_inputs:
                raise FMUError(f"inputs='derivatives': {name} declares canInterpolateInputs=\"false\" (it takes no "
                               f"input derivatives for {', '.join(self.in_ports[r] for r in rows)})")
            if unit.fmi3:
                missing = [self.in_ports[r] for r, vr in zip(rows, vrs) if vr not in cap.intermediate_vrs]
                if missing or not cap.intermediate_update:
                    raise FMUError(f"inputs='derivatives': {name} (FMI 3.0) takes inputs during a step only through "
                                   "intermediate updates, and does not declare them for "
                                   f"{', '.join(missing or [self.in_ports[r] for r in rows])}")

    # ---- reading and applying ---------------------------------------------------------------------
    def _read(self, unit: Unit, t: float) -> None:
        entry = self.u_out.get(unit.name)
        if entry is None:
            return
        cols, vrs = entry
        self.y[cols] = unit.get(vrs)
        self.ty[cols] = t
        if self.need_derivs:
            for k, srcs in enumerate(self.dsrc[unit.name]):
                self.d[k, cols] = 0.0
                alias = [(c, vr) for c, vr, fmu in srcs if not fmu]
                own = [(c, vr) for c, vr, fmu in srcs if fmu]
                if alias:
                    self.d[k, [c for c, _ in alias]] = unit.get([vr for _, vr in alias])
                if own:
                    self.d[k, [c for c, _ in own]] = unit.output_derivatives([vr for _, vr in own], k + 1)

    def _coefficients(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The inputs' Taylor coefficients about t (value, first and second derivative)."""
        delta = self.ty - t
        c0 = self.y - self.d[0] * delta + 0.5 * self.d[1] * delta ** 2
        c1 = self.d[0] - self.d[1] * delta
        c2 = self.d[1]
        return self.G @ c0, self.G @ c1, self.G @ c2

    def _inputs(self, t: float, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(value applied, its derivatives 1 and 2 sent, the value predicted at t + dt)."""
        if self.mode == "hold":
            u = self.G @ self.y
            zero = np.zeros_like(u)
            return u, zero, zero, u
        u0, u1, u2 = self._coefficients(t)
        end = u0 + u1 * dt + 0.5 * u2 * dt * dt
        if self.mode == "extrapolate":
            return u0 + 0.5 * u1 * dt + u2 * dt * dt / 6.0, np.zeros_like(u0), np.zeros_like(u0), end
        return u0, u1, (u2 if self.input_order == 2 else np.zeros_like(u2)), end

    def _intermediate(self, unit: Unit, t: float, t_end: float, vrs: list[int], a0: np.ndarray, a1: np.ndarray,
                      a2: np.ndarray) -> None:
        """FMI 3.0: the FMU holds an input set at an intermediate update until its next input
        point (the package's FMUs: the ends of their internal steps, a uniform grid), so each value
        set is the polynomial's at the middle of the interval to the next point; the grid is
        learnt from the points seen: its spacing is the smallest gap between two (before two were
        seen, u(t) at the start and the value at the point itself)."""
        grid = self._grid  # unit -> [last point, spacing]

        def poly(tt: float) -> np.ndarray:
            s = tt - t
            return a0 + a1 * s + 0.5 * a2 * s * s

        last, step = grid.get(unit.name, (math.nan, 0.0))
        nxt = t_end
        if step > 0:
            nxt = min(t_end, last + step * math.floor((t - last) / step + 1.0 + 1e-9))
        unit.set(vrs, poly(0.5 * (t + nxt)) if step > 0 else a0)

        def inputs(tt: float) -> tuple[list[int], np.ndarray]:
            last, step = grid.get(unit.name, (math.nan, 0.0))
            gap = tt - last  # a multiple of the spacing (NaN at the first point, < 0 after a rollback)
            if gap > 1e-12 * max(1.0, abs(tt)):
                step = gap if step == 0.0 else min(step, gap)
            grid[unit.name] = (tt, step)
            return vrs, poly(0.5 * (tt + min(tt + step, t_end)) if step > 0 else tt)

        unit.inst.set_intermediate_inputs(inputs)

    def _apply(self, unit: Unit, t: float, u: np.ndarray, u1: np.ndarray, u2: np.ndarray,
               t_end: float = math.inf) -> None:
        entry = self.u_in.get(unit.name)
        if entry is None:
            return
        rows, vrs = entry
        unit.set(vrs, u[rows])
        if self.mode != "derivatives":
            return
        if unit.fmi3:
            self._intermediate(unit, t, t_end, vrs, u[rows].copy(), u1[rows].copy(), u2[rows].copy())
        else:
            unit.set_input_derivatives(vrs, [u1[rows]] + ([u2[rows]] if self.input_order == 2 else []))

    def _step(self, unit: Unit, t: float, dt: float) -> None:
        self.fmu_steps += 1
        unit.step(t, dt)

    # ---- one macro step ---------------------------------------------------------------------------
    def _macro(self, t: float, dt: float) -> tuple[np.ndarray, float]:
        """One macro step from t; the inputs applied and the error estimate."""
        if self.method == "gauss-seidel":
            applied = np.zeros(len(self.in_ports))
            pred = np.zeros(len(self.in_ports))
            for unit in self.units:
                u, u1, u2, end = self._inputs(t, dt)
                rows = self.u_in.get(unit.name, (np.zeros(0, dtype=int), []))[0]
                applied[rows], pred[rows] = u[rows], end[rows]
                self._apply(unit, t, u, u1, u2, t + dt)
                self._step(unit, t, dt)
                self._read(unit, t + dt)
            return applied, float(np.max(np.abs(pred - self.G @ self.y), initial=0.0))
        u, u1, u2, end = self._inputs(t, dt)
        S = self._directional(dt) if self.correction and self.jac == "directional" else None
        for unit in self.units:
            self._apply(unit, t, u, u1, u2, t + dt)
            self._step(unit, t, dt)
        y0, d0, ty0 = self.y.copy(), self.d.copy(), self.ty.copy()
        for unit in self.units:
            self._read(unit, t + dt)
        r = self.G @ self.y - end
        err = float(np.max(np.abs(r), initial=0.0))
        if not self.correction:
            return u, err
        ystar = self.y.copy()
        if S is None:
            S = self._by_steps(t, dt, u, u1, u2, ystar)
        du = np.linalg.solve(np.eye(len(u)) - self.G @ S, r)
        self.y, self.d, self.ty = y0, d0, ty0
        for unit in self.units:
            unit.restore(t)
            self._apply(unit, t, u + du, u1, u2, t + dt)
            self._step(unit, t, dt)
        for unit in self.units:
            self._read(unit, t + dt)
        return u + du, err

    def _by_steps(self, t: float, dt: float, u: np.ndarray, u1: np.ndarray, u2: np.ndarray,
                  ystar: np.ndarray) -> np.ndarray:
        """S = d y(t + dt) / d u by one extra step per input from the saved states (a difference
        of relative size 1e-6: exact to rounding while no unit changes mode)."""
        S = np.zeros((len(self.out_ports), len(self.in_ports)))
        for unit in self.units:
            rows, _ = self.u_in.get(unit.name, (np.zeros(0, dtype=int), []))
            cols, ovrs = self.u_out.get(unit.name, (np.zeros(0, dtype=int), []))
            for r in rows:
                delta = 1e-6 * max(1.0, abs(u[r]))
                up = u.copy()
                up[r] += delta
                unit.restore(t)
                self._apply(unit, t, up, u1, u2, t + dt)
                self._step(unit, t, dt)
                if len(cols):
                    S[cols, r] = (unit.get(ovrs) - ystar[cols]) / delta
        return S

    def _directional(self, dt: float) -> np.ndarray:
        """S from the FMUs' directional derivatives at the step's start: d y/du + dt d y'/du +
        dt^2/2 d y''/du, with y', y'' the outputs that are y's derivatives (x' = v, x'' = a)."""
        S = np.zeros((len(self.out_ports), len(self.in_ports)))
        for unit in self.units:
            rows, ivrs = self.u_in.get(unit.name, (np.zeros(0, dtype=int), []))
            cols, ovrs = self.u_out.get(unit.name, (np.zeros(0, dtype=int), []))
            if not len(rows) or not len(cols):
                continue
            for c, vr in zip(cols, ovrs):
                var = split(self.out_ports[c])[1]
                names = unit.derivative_outputs(var)
                unknowns = [vr] + [unit.vr(n) for n in names]
                J = unit.jacobian(unknowns, ivrs)
                weights = np.array([1.0, dt, 0.5 * dt * dt][:len(unknowns)])
                S[c, rows] = weights @ J
        return S

    # ---- the loop ---------------------------------------------------------------------------------
    def _time(self, pos: int) -> float:
        return self.t_stop if pos >= self.end_pos else self.t0 + pos * self.unit_dt

    def run(self, progress: bool) -> CosimResult:
        units = self.units
        saving = self.correction or self.tol is not None
        for unit in units:
            self._read(unit, self.t0)
        times = [self.t0]
        outs = [self.y.copy()]
        recs = [self._recorded()]
        applied: list[np.ndarray] = []
        pos, level, rejected, unmet, max_err = 0, 0, 0, 0, 0.0
        bar = None
        if progress:
            from tqdm import tqdm

            bar = tqdm(total=self.t_stop - self.t0, unit="s", desc="cosim", leave=False)
        try:
            while pos < self.end_pos:
                width = 2 ** (self.levels - level)
                nxt = min(pos + width, self.end_pos)
                t, t1 = self._time(pos), self._time(nxt)
                if saving:
                    for unit in units:
                        unit.save()
                    keep = (self.y.copy(), self.d.copy(), self.ty.copy())
                u, err = self._macro(t, t1 - t)
                if self.tol is not None and err > self.tol and level < self.levels:
                    rejected += 1
                    level += 1
                    self.y, self.d, self.ty = (a.copy() for a in keep)
                    for unit in units:
                        unit.restore(t)
                    continue
                if self.tol is not None:
                    if err > self.tol:
                        unmet += 1
                    max_err = max(max_err, err)
                    # grow back on the coarser grid when the estimate is well below the tolerance
                    if err < 0.25 * self.tol and level > 0 and nxt % (2 * width) == 0:
                        level -= 1
                applied.append(u)
                times.append(t1)
                outs.append(self.y.copy())
                recs.append(self._recorded())
                if bar is not None:
                    bar.update(t1 - t)
                pos = nxt
        finally:
            if bar is not None:
                bar.close()
            for unit in units:
                unit.free_state()
                if unit.fmi3 and self.mode == "derivatives":
                    unit.inst.set_intermediate_inputs(None)
        if unmet:
            emit([f"cosim: the interface error estimate was above tol = {self.tol:g} at {unmet} step(s) taken at the "
                  f"smallest step allowed, H/2^{self.levels} = {self.H / 2 ** self.levels:g} s (largest {max_err:g})"],
                 stacklevel=3)
        return self._result(times, outs, recs, applied, rejected, unmet, max_err if self.tol is not None else math.nan)

    def _recorded(self) -> np.ndarray:
        if not self.record:
            return np.zeros(0)
        return np.array([unit.get([vr])[0] for unit, vr in (self.rec_vr[p] for p in self.record)])

    def _result(self, times: list[float], outs: list[np.ndarray], recs: list[np.ndarray],
                applied: list[np.ndarray], rejected: int, unmet: int, max_err: float) -> CosimResult:
        Y = np.array(outs)
        R = np.array(recs) if self.record else np.zeros((len(times), 0))
        U = np.vstack([np.array(applied).reshape(-1, len(self.in_ports)), np.full((1, len(self.in_ports)), np.nan)])
        outputs = {p: Y[:, j].copy() for j, p in enumerate(self.out_ports)}
        outputs.update({p: R[:, j].copy() for j, p in enumerate(self.record)})
        settings = {"H": self.H, "method": self.method, "inputs": self.mode, "order": self.order,
                    "correction": self.correction, "jacobian": self.jac, "tol": self.tol}
        return CosimResult(np.array(times), outputs, {p: U[:, i].copy() for i, p in enumerate(self.in_ports)},
                           steps=len(applied), rejected=rejected, unmet=unmet, max_error=max_err,
                           fmu_steps=self.fmu_steps, settings=settings)

