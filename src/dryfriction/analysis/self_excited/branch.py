"""The orbit branch in the belt speed, continued with the engine of
:mod:`dryfriction.analysis.continuation` (dryfriction.analysis.self_excited)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ...drivers.oscillator import OscillatorFMU2
from ...errors import FMUError
from ..continuation import CorrectorFailure, Evaluation, correct, tangent
from .flow import _fmu, _Flow
from .hopf import locate_hopf
from .motion import self_excited
from .orbit import _Orbit
from .problem import FD_STEP, TRIVIAL, BeltProblem

#: Newton steps of the corrector at most
CORRECTOR_STEPS = 11


@dataclass
class BranchPoint:
    """One orbit of the branch: the belt speed (m/s), the period (s), v0 on the section (m/s), the
    amplitude (m), the share of the cycle stuck, the (trivial, nontrivial) multipliers, whether it is
    stable, and the corrector's scaled residual."""

    v_belt: float
    period: float
    v0: float
    amplitude: float
    stick_fraction: float
    multipliers: np.ndarray
    stable: bool
    residual: float


@dataclass
class BeltBranch:
    """The orbit branch continued in the belt speed: the stick-slip leg from low speed up to its
    turning point, then (``slip_leg``) the orbits that never stick, from there down to the Hopf.

    One branch with its points, unlike :class:`dryfriction.analysis.continuation.Branch` (the record
    of one branch in a tree of branches whose points are the continuation's Dataset); also importable
    as ``Branch`` from :mod:`dryfriction.analysis.self_excited`."""

    points: list[BranchPoint]        # in order along the branch
    turning_points: list[float]      # belt speeds where the branch turns (v_belt's direction reverses)
    end: str                         # why it stopped
    end_v_belt: float                # the last belt speed
    grazing: float = math.nan        # the stick-slip leg's last belt speed, where its stick phase vanishes
    hopf: float = math.nan           # where the slip leg was seeded (the located Hopf), m/s

    def arrays(self) -> dict[str, np.ndarray]:
        """The points' fields as arrays (and ``mu_nontrivial``, |nontrivial multiplier|)."""
        keys = ("v_belt", "period", "v0", "amplitude", "stick_fraction", "stable", "residual")
        out = {k: np.array([getattr(p, k) for p in self.points], dtype=float) for k in keys}
        out["mu_nontrivial"] = np.array([abs(p.multipliers[1]) for p in self.points])
        return out

    @property
    def fold(self) -> float:
        """The largest belt speed of the branch (its turning point), m/s."""
        v = np.array([p.v_belt for p in self.points])
        return float(v[np.argmax(np.abs(v))]) if v.size else math.nan


#: the name of the belt's branch in this package (the forced continuation has its own Branch)
Branch = BeltBranch


@dataclass
class _BeltEvaluation(Evaluation):
    """R at u with the FMU's run behind it (its end values) and the orbit solver of that belt speed."""

    end: dict[str, float] = field(default_factory=dict)
    solver: _Orbit | None = None


class _BeltBranchProblem:
    """R(v0, T; v_belt) = 0 as the continuation engine's problem
    (:class:`dryfriction.analysis.continuation.ArclengthProblem`): unknowns u = (v0, T, v_belt) / S,
    S = (V, T0, V); dR/d(v0, T) from the orbit's Newton (``_Orbit.dR``), dR/dv_belt by central
    differences (the section moves with x_eq); and the walk of a leg of the branch."""

    def __init__(self, f: OscillatorFMU2, prob: BeltProblem, tol: float, ds: float, ds_min: float, ds_max: float,
                 v_range: tuple[float, float], progress: Callable[[BranchPoint], None] | None) -> None:
        self.f, self.prob, self.tol = f, prob, tol
        self.ds, self.ds_min, self.ds_max = ds, ds_min, ds_max
        self.X, self.V = prob.scales
        self.S = np.array([self.V, prob.natural_period, self.V])
        self.sgn = float(prob.direction)
        self.lo, self.hi = sorted(abs(v) for v in v_range)
        self.progress = progress

    def solver(self, vb: float) -> _Orbit:
        return _Orbit(_Flow(self.f, self.prob.with_(v_belt=float(vb))), self.tol, 30)

    def u(self, y: np.ndarray) -> np.ndarray:
        """The scaled unknowns of y = (v0, T, v_belt)."""
        return np.asarray(y, dtype=float) / self.S

    def y(self, u: np.ndarray) -> np.ndarray:
        return u * self.S

    def _R(self, y: np.ndarray) -> tuple[np.ndarray, dict[str, float], _Orbit]:
        s = self.solver(float(y[2]))
        try:
            r, e = s.residual(float(y[0]), float(y[1]))
        except (FloatingPointError, FMUError) as exc:      # a point the FMU cannot run
            raise CorrectorFailure(str(exc)) from None
        return r, e, s

    # -- the engine's interface --
    def evaluate(self, u: np.ndarray) -> _BeltEvaluation:
        r, e, s = self._R(self.y(u))
        return _BeltEvaluation(np.array(u, dtype=float), r, end=e, solver=s)

    def derive(self, e: Evaluation, parameter: bool) -> None:
        assert isinstance(e, _BeltEvaluation) and e.solver is not None
        y = self.y(e.u)
        try:
            if e.Gy is None:
                e.Gy = e.solver.dR(float(y[0]), float(y[1]), e.end) * self.S[:2]
            if parameter and e.Gq is None:
                d = FD_STEP * self.V
                rp = self._R(y + np.array([0.0, 0.0, d]))[0]
                rm = self._R(y - np.array([0.0, 0.0, d]))[0]
                e.Gq = (rp - rm) / (2 * d) * self.S[2]
        except FloatingPointError as exc:
            raise CorrectorFailure(str(exc)) from None

    def norm(self, e: Evaluation) -> float:
        return float(np.max(np.abs(e.G)))

    def check(self, u: np.ndarray, du: np.ndarray) -> None:
        y = self.y(u + du)
        if not (y[1] > 0 and -self.sgn * y[0] > 0 and y[2] * self.sgn > 0):
            raise CorrectorFailure("the Newton step leaves the orbits (T > 0, v0 against the belt, v_belt's sign)")

    # -- the branch --
    def point(self, e: Evaluation, report: bool = True) -> BranchPoint:
        y = self.y(e.u)
        nr = self.norm(e)
        o = self.solver(float(y[2])).finish(float(y[0]), float(y[1]), nr, 0, "")
        p = BranchPoint(float(y[2]), o.period, o.v0, o.amplitude, o.stick_fraction, o.multipliers, o.stable, nr)
        if report and self.progress:
            self.progress(p)
        return p

    def leg(self, u: np.ndarray, tan: np.ndarray, max_points: int, amplitude_min: float,
            accept: Callable[[BranchPoint], bool]) -> tuple[list[BranchPoint], list[float], str, np.ndarray]:
        """Points from u along tan until the amplitude falls under amplitude_min X, the belt speed
        leaves the range, max_points, or the corrector fails at the smallest step. A corrected point
        that ``accept`` refuses (the leg's kind of orbit: with a stick phase or without), or that is
        steady sliding itself (|v0| < TRIVIAL X w0), counts as a failed corrector: the step is halved
        (so a leg ends at its grazing, approached in ever smaller steps)."""
        pts: list[BranchPoint] = []
        turning: list[float] = []
        h, last_dir = self.ds, 0.0
        end = f"{max_points} points"
        while len(pts) < max_points:
            vb = float(self.y(u)[2])
            try:
                e, _ = correct(self, u + h * tan, tan, u, h, tol=self.tol, max_iter=CORRECTOR_STEPS)
                cand = self.point(e, report=False)
                ok = abs(cand.v0) >= TRIVIAL * self.V and accept(cand)
                if ok:
                    tn = tangent(self, e, e.u - u)           # oriented along the secant
            except CorrectorFailure:
                h *= 0.5
                if h < self.ds_min:
                    end = f"the corrector failed at the smallest step (v_belt {vb:.8g})"
                    break
                continue
            if not ok:
                h *= 0.5
                if h < self.ds_min:
                    end = f"the next point is not on this leg at the smallest step (v_belt {vb:.8g})"
                    break
                continue
            d = float(np.sign(cand.v_belt - vb))
            if last_dir and d and d != last_dir:
                turning.append(vb)
            last_dir = d or last_dir
            u, tan = e.u, tn
            pts.append(cand)
            if self.progress:
                self.progress(cand)
            h = min(h * 1.5, self.ds_max)
            if cand.amplitude < amplitude_min * self.X:
                end = f"amplitude below {amplitude_min:g} X: the orbit shrinks onto the equilibrium (the Hopf)"
                break
            if not (self.lo <= abs(cand.v_belt) <= self.hi):
                end = "left the belt speed range"
                break
        return pts, turning, end, u

    def seed_at_fixed_v0(self, v0: float, T: float, vb: float) -> Evaluation | None:
        """The orbit through (x_eq, v0) with T and v_belt the unknowns (Newton from T, vb)."""
        u = self.u(np.array([v0, T, vb]))
        try:
            return correct(self, u, np.array([1.0, 0.0, 0.0]), u, 0.0, tol=self.tol, max_iter=CORRECTOR_STEPS)[0]
        except CorrectorFailure:
            return None


#: how a leg ends at its edge (the sentences of _BeltBranchProblem.leg)
EDGE = ("the corrector failed at the smallest step", "the next point is not on this leg")
#: the slip leg meets the stick-slip leg when its last belt speed is within MEET of the grazing (relative)
MEET = 1e-4


def continue_orbits(prob: BeltProblem, v_from: float, v_min: float, v_max: float, *,
                    fmu: OscillatorFMU2 | None = None, ds: float = 0.02, ds_min: float = 1e-5,
                    ds_max: float = 0.1, max_points: int = 200, amplitude_min: float = 2e-3,
                    slip_leg: bool = True, seed_amplitude: float = 0.02, tol: float | None = None,
                    progress: Callable[[BranchPoint], None] | None = None) -> BeltBranch:
    """The orbit branch through the stable orbit at ``v_from`` (found by :func:`~dryfriction.analysis.self_excited.motion.self_excited`), continued
    by pseudo-arclength towards larger |v_belt| while it stays in [v_min, v_max] (same sign), until it
    turns, its amplitude falls under ``amplitude_min`` X, or ``max_points``. Arclength in the scaled
    unknowns (v0 / V, T / T0, v_belt / V); ``ds`` its first step, halved on a failed corrector down to
    ``ds_min``, grown by 1.5 up to ``ds_max``.

    The stick-slip leg has no smooth fold (its nontrivial multiplier is 0): it ends where the catch
    of the belt becomes tangential (a grazing: beyond it the motion no longer reaches the belt's
    speed), ``grazing``, the last belt speed where the corrector still finds a stick-slip orbit (steps
    halved down to ``ds_min``). With Stribeck friction the branch turns there, with a corner, onto
    orbits that never stick; the corrector cannot turn that corner, so with ``slip_leg`` the other
    leg is continued from its other end instead: the Hopf located from the model (:func:`locate_hopf`
    in [v_min, grazing]), seeded by the orbit through (x_eq, v0) with |v0| = ``seed_amplitude`` V (T
    and v_belt solved for) and continued up to where it would stick; its points are appended in the
    order of the branch (from the corner down to the Hopf), and the grazing is a turning point when
    the legs meet there (within MEET). Without a Hopf in the range (Coulomb) the branch ends at the
    grazing."""
    t = (1e-12 if prob.scheme == "exact" else 1e-10) if tol is None else tol
    with _fmu(fmu) as f:
        se = self_excited(prob.with_(v_belt=v_from), fmu=f)
        if se.orbit is None or not se.orbit.converged:
            raise RuntimeError(f"no orbit at the start v_belt = {v_from:g}: {se.reason}")
        c = _BeltBranchProblem(f, prob, t, ds, ds_min, ds_max, (v_min, v_max), progress)
        o = se.orbit
        try:
            e = c.evaluate(c.u(np.array([o.v0, o.period, float(v_from)])))
            first = c.point(e)
            tan = tangent(c, e)
        except CorrectorFailure as exc:
            raise RuntimeError(f"the orbit at the start v_belt = {v_from:g} cannot be continued: {exc}") from None
        if tan[2] * c.sgn < 0:
            tan = -tan
        sticks = first.stick_fraction > 0.0

        def same_kind(p: BranchPoint) -> bool:
            return (p.stick_fraction > 0.0) == sticks

        pts, turning, end, _ = c.leg(e.u, tan, max_points - 1, amplitude_min, same_kind)
        pts.insert(0, first)
        grazing = math.nan
        if sticks and end.startswith(EDGE):          # the stick-slip orbits end there (the catch grazes)
            grazing = pts[-1].v_belt
        hopf = math.nan
        if slip_leg and math.isfinite(grazing):
            try:
                hp = locate_hopf(prob, v_min, grazing, fmu=f)
            except RuntimeError as exc:
                end += f"; no slip leg: {exc}"
            else:
                hopf = hp.v_belt
                seed = c.seed_at_fixed_v0(-c.sgn * seed_amplitude * c.V, prob.natural_period, hopf)
                if seed is not None:
                    try:
                        tan = tangent(c, seed)
                    except CorrectorFailure:
                        seed = None
                if seed is None:
                    end += f"; no slip leg: no orbit with |v0| = {seed_amplitude:g} V near the Hopf {hopf:.6g}"
                else:
                    p0 = c.point(seed)
                    if tan[0] * -c.sgn < 0:               # towards larger |v0| (larger orbits)
                        tan = -tan

                    def slides(p: BranchPoint) -> bool:
                        return p.stick_fraction == 0.0

                    more, turn2, end2, _ = c.leg(seed.u, tan, max_points, 0.0, slides)
                    leg2 = [p0] + more
                    pts += leg2[::-1]
                    turning += turn2
                    meet = abs(leg2[-1].v_belt - grazing) <= MEET * abs(grazing)
                    if meet:
                        turning.append(grazing)
                    end = (f"the stick-slip leg ends at its grazing (v_belt {grazing:.8g}, {end}); the slip leg "
                           f"from the Hopf {hopf:.8g} up to v_belt {leg2[-1].v_belt:.8g} ({end2}); "
                           + ("they meet: the branch turns at the grazing" if meet else
                              "they do not meet: two branches"))
        return BeltBranch(pts, turning, end, pts[-1].v_belt, grazing, hopf)
