"""Continuation of a structure's periodic orbits in a parameter, with their bifurcations
(docs/system_orbits.md, "Continuation").

The project's continuation engine (:mod:`dryfriction.analysis.continuation`: pseudo-arclength
predictor and corrector, step control, the location of folds, period doublings and grazings between
two branch points, the switch onto a doubled branch) walks the fixed points of the located scheme's
map of a :class:`~dryfriction.system.structure.System`
(:mod:`dryfriction.analysis.system_orbits`). What is the structure's own: the unknowns u = (S^-1 z,
q), z = (x, v, the Jenkins sliders) at the section, S the start orbit's scales, q the parameter
scaled as the oscillator's; G_y from the FMU's Jacobian; G_q a central difference in q (as the
oscillator's); at each branch point the cycle's amplitude per DOF, stuck share per contact and
mode changes (the grazing test: each contact's mode changes per cycle, the FMU's count, and whether it
sticks and slides in it). The
internal step h is the start structure's for the whole branch. The section stays where the start
orbit's was (the oscillator's walk moves its section off a stick phase; a structure's is chosen
once, :func:`~dryfriction.analysis.system_orbits.find_system_orbits`'s), each Jenkins slider started
there in the start orbit's mode. A symmetric orbit of one period (every harmonic force changes sign
over half a period, and Coulomb friction is odd: x(t + T/2) = -x(t), the sliders too) is continued
on the half-period map H = -P^{1/2}, as the oscillator's, so that its symmetry breaking (a multiplier
of H through -1) is located and the two mirror branches are followed off it.

Parameters (:data:`SYSTEM_PARAMETERS`): ``omega`` (rad/s), ``N`` (every contact's normal force),
``mu_s``, ``mu_k`` (every contact's), ``force`` (the excitation's scale: F_c and F_s times it).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from .continuation import (BIFURCATION_TYPES, SYMMETRIC, Continuation, CorrectorFailure, _BranchMap, _Eval, _Run,
                           check_walk)
from .shooting import classify, multipliers
from .system_orbits import NEUTRAL, SystemOrbit, _h_of, _Map, _scales, find_system_orbits

if TYPE_CHECKING:
    from ..drivers.system import SystemFMU3
    from ..system.structure import System as Structure  # (the annotations' name: the API reference links it)

__all__ = ["continue_system_orbits", "SYSTEM_PARAMETERS", "set_system_parameter"]

#: the parameters a structure's orbits are continued in: name -> unit
SYSTEM_PARAMETERS = {"omega": "rad/s", "N": "N", "mu_s": "1", "mu_k": "1", "force": "1"}


def set_system_parameter(base: "Structure", name: str, value: float) -> "Structure":
    """``base`` with the parameter ``name`` at ``value`` (``force``: F_c and F_s scaled by it); a
    ValueError names a value the structure refuses."""
    if name == "omega":
        return base.replace(omega=float(value))
    if name == "force":
        return base.replace(F_c=base.F_c * float(value), F_s=base.F_s * float(value))
    if name in ("N", "mu_s", "mu_k"):
        return base.replace(contacts=[dataclasses.replace(c, **{name: float(value)}) for c in base.contacts])
    raise ValueError(f"unknown continuation parameter {name!r}; valid: {', '.join(SYSTEM_PARAMETERS)}")


class _SystemBranchMap(_BranchMap):
    """The fixed points of a structure's branch map (module doc) as the engine's problem."""

    def __init__(self, fmu: "SystemFMU3", base: "Structure", name: str, p_a: float, p_s: float, K: int, kind: str,
                 phase: float, S: np.ndarray, fd_step: float, counter: list[int], slide: np.ndarray) -> None:
        self.counter = counter
        self.fmu, self.base, self.name, self.p_a, self.p_s = fmu, base, name, p_a, p_s
        self.K, self.kind, self.phase, self.fd = K, kind, phase, fd_step
        self.S = np.asarray(S, dtype=float)
        self.slide = np.asarray(slide, dtype=int)  # the Jenkins sliders' modes at the section (the map's start)

    def osc(self, q: float) -> Any:  # (the engine's name: the structure at q)
        return set_system_parameter(self.base, self.name, self.param(q))

    def period(self, p: Any) -> float:
        return 2.0 * math.pi / float(p.omega)

    def span(self, p: Any) -> float:
        return self.period(p) / 2.0 if self.kind == "symmetric" else self.K * self.period(p)

    def map_of(self, p: Any) -> _Map:
        """The structure p's map over this branch map's K periods, its sliders started in their modes."""
        self.fmu.system = p
        M = _Map(self.fmu, p, self.K)
        M.slide[:] = self.slide
        return M

    def raw(self, z: np.ndarray, p: Any) -> tuple[np.ndarray, np.ndarray, int]:
        M = self.map_of(p)
        Pz, J, _ = M(M.project(z), self.t_s(p), span=self.span(p))
        self.counter[0] += 1
        if self.kind == "symmetric":  # H = -P^{1/2}: x, v and the sliders mirrored
            return -Pz, -J, 1
        return Pz, J, 1

    def check(self, u: np.ndarray, du: np.ndarray) -> None:
        if np.max(np.abs(du[:-1])) > 10.0 * max(1.0, float(np.max(np.abs(u[:-1])))):
            raise CorrectorFailure("the corrector diverged")


class _SystemRun(_Run):
    """The engine's walk on a structure's branches: its maps, branch points' descriptions and events."""

    def __init__(self, fmu: "SystemFMU3", p0: "Structure", S: np.ndarray, *args: Any) -> None:
        self.S0 = S
        self.slide = np.zeros(p0.nc, dtype=int)  # the sliders' modes at the section (the start orbit's)
        super().__init__(fmu, p0, *args)

    def init_scales(self, p0: Any) -> None:
        self.xs, self.w = 1.0, 1.0  # (the structure's scales are per unknown: self.S0)

    def param_unit(self) -> str:
        return SYSTEM_PARAMETERS[self.name]

    def new_map(self, K: int, kind: str, phase: float, slide: np.ndarray | None = None) -> _BranchMap:
        return _SystemBranchMap(self.fmu, self.p0, self.name, self.start, self.p_s, K, kind, phase, self.S0, self.fd,
                                self.counter, self.slide if slide is None else slide)

    def _cycle(self, m: _BranchMap, e: _Eval) -> tuple[_Map, np.ndarray, dict[str, np.ndarray]]:
        """The branch point's map, its state at the section and the cycle's observables (one run of
        the whole K-cycle, on a symmetric branch too)."""
        p = e.p
        z = m.S * e.u[:-1]
        assert isinstance(m, _SystemBranchMap)
        M = m.map_of(p)
        _, _, obs = M(M.project(z), m.t_s(p), jacobian=False)
        obs["transitions"] = self.fmu.transitions()  # (the grazing test's: read for this run only)
        self.evaluations += 1
        return M, z, obs

    def describe(self, m: _BranchMap, e: _Eval) -> dict[str, Any]:
        p = e.p
        M, z, obs = self._cycle(m, e)
        t_s = m.t_s(p)
        z0 = z if t_s == 0.0 else M(M.project(z), t_s, jacobian=False, span=M.KT - t_s)[0]
        self.evaluations += int(t_s != 0.0)
        n = M.n
        mu = multipliers(m.full_jacobian(e.J))
        x_max, x_min = np.asarray(obs["x_max"]), np.asarray(obs["x_min"])
        info: dict[str, Any] = {
            "x0": z0[:n].copy(), "v0": z0[n:2 * n].copy(),
            "amplitude": 0.5 * (x_max - x_min), "offset": 0.5 * (x_max + x_min),
            "stick_fraction": np.asarray(obs["stick_fraction"]), "transitions": int(np.sum(obs["transitions"])),
            "mu": mu, "stable": classify(mu, NEUTRAL)[1],
            "section": t_s, "cycle": None,
        }
        info.update(self.tests(m, e))
        info["signature"] = self._signature(obs)
        return info

    @staticmethod
    def _signature(obs: dict[str, np.ndarray]) -> tuple[tuple[tuple[int, bool, bool], ...], bool]:
        """The grazing test's events (module doc) from the cycle's observables (the FMU's, exact in
        time: a count of sampled mode changes would alias short phases): per contact its mode changes
        in the cycle (a stop that turns into a direct reversal changes them while the contact still
        sticks elsewhere in the cycle) and whether it sticks some of the cycle and slides some of it;
        and whether any contact sticks."""
        share = np.asarray(obs["stick_fraction"])
        trans = np.asarray(obs["transitions"])
        sticks, slides = share > 0.0, share < 1.0
        per = tuple((int(t), bool(a), bool(b)) for t, a, b in zip(trans, sticks, slides))
        return per, bool(np.any(sticks))

    def signature(self, m: _BranchMap, e: _Eval) -> tuple[tuple[tuple[int, bool, bool], ...], bool]:
        return self._signature(self._cycle(m, e)[2])

    def start_map(self, o: Any) -> tuple[_BranchMap, np.ndarray]:
        """The start orbit's map: its section and sliders' modes there; where the orbit is symmetric
        (H(z) = z within SYMMETRIC, K = 1) the symmetric map H = -P^{1/2} (module doc of the engine)."""
        if not isinstance(o, SystemOrbit):
            raise CorrectorFailure("a structure's branch starts from a SystemOrbit")
        T = 2.0 * math.pi / set_system_parameter(self.p0, self.name, self.start).omega
        KT = o.period * T
        slide = np.asarray(o.section_slide, dtype=int) if np.size(o.section_slide) == self.p0.nc \
            else np.zeros(self.p0.nc, dtype=int)
        self.slide = slide
        t_s = o.section % KT
        m = self.new_map(o.period, "full", t_s / KT)
        z = np.asarray(o.section_state, dtype=float)
        if z.shape != m.S.shape or not np.all(np.isfinite(z)):
            raise CorrectorFailure("the start orbit has no section state")
        if self.use_symmetry and o.period == 1:
            # the section in the second half: the state (and the sliders' modes) half a period before
            # is the mirror image
            second = t_s >= T / 2.0
            h = self.new_map(1, "symmetric", (t_s % (T / 2.0)) / (T / 2.0), -slide if second else slide)
            u = np.array([*((-z if second else z) / h.S), 0.0])
            try:
                if h.evaluate(u).residual() <= SYMMETRIC:
                    self.slide = h.slide
                    return h, u
            except CorrectorFailure:
                pass
        return m, np.array([*(z / m.S), 0.0])

    def maybe_move_section(self, m: _BranchMap, pt: Any) -> tuple[_BranchMap, Any]:
        return m, pt  # (module doc: the start orbit's section for the whole branch)


def continue_system_orbits(system: "Structure", param: str, start: float, stop: float, *, period: int = 1,
                           orbit: SystemOrbit | Sequence[SystemOrbit] | None = None,
                           ds: float = 0.02, ds_min: float = 1e-6, ds_max: float = 0.5, max_points: int = 400,
                           tol: float = 1e-8, ptol: float = 1e-8, max_turn: float = 0.3, fd_step: float = 1e-6,
                           max_iter: int = 8, switch: bool = True, max_branches: int = 8,
                           detect: Sequence[str] = ("fold", "period_doubling", "symmetry_breaking", "grazing"),
                           symmetric: bool = True, progress: Callable[[int], None] | None = None) -> Continuation:
    """Continue the periodic orbits of ``period`` K excitation periods of ``system`` in ``param`` (a key
    of :data:`SYSTEM_PARAMETERS`) from ``start`` to ``stop`` with the project's continuation engine
    (module doc): the branches start from ``orbit`` (SystemOrbits of the structure with ``param =
    start``), else from the orbits :func:`~dryfriction.analysis.system_orbits.find_system_orbits`
    finds there. The result's Dataset has per point the parameter, the state at t = 0 and the
    amplitude and offset per DOF (dimension ``dof``), the stuck share per contact (``contact``),
    the multipliers and stability; the folds, period doublings, symmetry breakings and grazings are
    located on it (a period doubling's doubled branch and a symmetry breaking's two mirror branches
    continued with ``switch``). ``symmetric``: continue a symmetric orbit (K = 1) on the half-period
    map (module doc)."""
    from ..drivers.system import SystemFMU3
    from ..system.structure import System

    if not isinstance(system, System):
        raise TypeError(f"continue_system_orbits needs a dryfriction.System, not {type(system).__name__}")
    if param not in SYSTEM_PARAMETERS:
        raise ValueError(f"unknown continuation parameter {param!r} of a structure; valid: "
                         f"{', '.join(SYSTEM_PARAMETERS)}")
    check_walk(start, stop, period, ds, ds_min, ds_max)
    bad = [d for d in detect if d not in BIFURCATION_TYPES]
    if bad:
        raise ValueError(f"bifurcation type(s) {bad} not detected; valid: {', '.join(BIFURCATION_TYPES)}")
    p_start = set_system_parameter(system, param, start)
    set_system_parameter(system, param, stop)  # (both ends valid: the error names the field)
    with SystemFMU3(p_start) as fmu:
        h = _h_of(fmu, p_start)
        base = system.replace(h=h)
        p0 = set_system_parameter(base, param, start)
        if orbit is None:
            starts = find_system_orbits(p0, period, estimate_error=False, tol=tol)
            if not starts:
                raise ValueError(f"no orbit of period {period} found at {param} = {start!r} to continue")
        else:
            starts = [orbit] if isinstance(orbit, SystemOrbit) else list(orbit)
        o0 = starts[0]
        x_max = o0.offset + o0.amplitude
        x_min = o0.offset - o0.amplitude
        jenk = np.flatnonzero(p0.k_t > 0.0)
        S = _scales(p0, x_max, x_min, jenk)
        run = _SystemRun(fmu, base, S, param, float(start), float(stop), ds, ds_min, ds_max, max_points, tol, ptol,
                         max_turn, fd_step, max_iter, switch, max_branches, bool(symmetric), tuple(detect), progress)
        for o in starts:
            if not o.converged:
                raise ValueError(f"the start orbit did not converge ({o.reason}): nothing to continue")
            if o.neutral:
                raise ValueError(f"the start orbit at {param} = {start!r} is neutral (a multiplier 1: a continuum of "
                                 "orbits, e.g. a Jenkins slider stuck all cycle at any of its rest positions), not a "
                                 "branch to follow: start where every slider slides some of the cycle")
            run.queue.append((o, None, None))
        run.go()
        return run.result()
