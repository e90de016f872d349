"""Continuation of periodic orbits in a parameter, with their bifurcations
(docs/orbits.md, "Continuation and bifurcations").

Pseudo-arclength continuation of the fixed points of the exact stroboscopic map (dryfriction.analysis.orbits)
in one oscillator parameter p. Unknowns u = (y, q): y = S^-1 z the state at a section time (scaled
as find_orbits scales it, S = diag(x_s, x_s w) of the branch's first oscillator), q = (p - p_a) / p_s
the parameter (p_a the start, p_s = max(|p_a|, |p_b|, |p_b - p_a|)). Residual G(y, q) = S^-1 (M(S y; p)
- S y) with M the map of the branch:

- ``P^K``: K excitation periods from the section time t_s (``kind = "full"``);
- ``H = -P^{1/2}`` for an orbit invariant under the system's symmetry (x, v)(t) -> -(x, v)(t + T/2)
  (``kind = "symmetric"``, K = 1): P = H o H, its fixed points are the symmetric orbits; a
  multiplier of H through -1 is the symmetry-breaking pitchfork (P's multiplier through +1 without a
  fold of the symmetric branch), through +1 a fold of the symmetric branch.

dG/dy is the FMU's exact Jacobian (``sensitivity = true``); dG/dq is a central finite difference
(step ``fd_step`` in q). The section time is a fixed share of the map's span (so it moves with
omega): ``t_s = phase * span``; when a stick phase comes near it (within ``SECTION_MARGIN`` of the
span) it is chosen again at the middle of the longest slide, as find_orbits does.

**The engine** (also the self-excited belt branch's, dryfriction.analysis.self_excited): for any
problem G(u) = 0, u in R^(n+1), that supplies the small interface :class:`ArclengthProblem` (the
residual, its derivatives, its norm, a check of a Newton step): the predictor u + ds t (t the unit
tangent, the null vector of [G_y | G_q], :func:`tangent`); the corrector :func:`correct`, Newton on
[G(u); t . (u - u_prev) - ds] (or with one unknown held fixed), the derivatives asked only for a
Newton step or a tangent. Each problem walks its own branch with it. Here: halve the step on a
failed corrector or a turn of the tangent by more than ``max_turn`` radians, grow it by 1.5 after a
corrector of at most 3 steps, within [ds_min, ds_max].

Bifurcations, located between two branch points on the arclength s of the step by Brent's method
(:class:`dryfriction.roots.RootSearch`; bisection for grazing, whose test is the events per cycle),
each trial point corrected with the step's constraint; the root finder's tolerance in s is
``ptol`` max(1, |p|) in the parameter over the larger |dp/ds| of the step's two ends; the orbit at the
located parameter is the corrector's solution there:

- fold: det(J - I) changes sign (J the Jacobian of the branch's map) and so does dp/ds;
- period doubling: det(J_P + I) changes sign (J_P of P^K); then the doubled branch is continued
  (period 2K, from the located orbit along the -1 eigenvector);
- symmetry breaking (symmetric branches): det(J_H + I) changes sign; then both asymmetric branches
  are continued (period 1, along the eigenvector);
- grazing: the orbit's events per cycle change (the FMU's count of mode changes, ``transitions``, or
  whether it sticks at all, stick_fraction > 0).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from ..drivers.oscillator import OscillatorFMU2, Settings
from .orbits import JACOBIAN, Orbit, _Map, _slide_section, find_orbits, scales
from .shooting import STABILITY_MARGIN, multipliers
from ..params import Oscillator
from ..roots import RootSearch

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["Bifurcation", "Branch", "Continuation", "continue_orbits", "PARAMETERS", "set_parameter",
           "get_parameter", "ArclengthProblem", "Evaluation", "CorrectorFailure", "correct", "tangent", "ARC_TOL",
           "check_walk"]

#: a stick phase nearer to the section than this share of the map's span: choose the section again
SECTION_MARGIN = 0.03
#: an orbit is symmetric when |H(z) - z| (scaled, relative) is at most this
SYMMETRIC = 1e-8
#: past a corner of the branch the new point must lie within this many steps of the last one (else
#: the corrector went off to another branch)
KINK_REACH = 3.0
#: past a corner where the arclength corrector fails: orbits at a fixed parameter these shares of ds0 along the tangent
CORNER_STEPS = (1e-3, 1e-2, 1e-1)
#: and such an orbit within this many of those steps of the last point (the branch's slope jumps at the
#: corner: the one-DOF structure's grazing lands 8.6 steps away at every step length)
CORNER_REACH = 20.0
#: corrector steps allowed at the trial points of a location
LOCATE_ITERATIONS = 60
#: trial points of one location, at most
LOCATE_POINTS = 200
BIFURCATION_TYPES = ("fold", "period_doubling", "symmetry_breaking", "grazing")

# ---- the parameters -----------------------------------------------------------------------------


def _lam(p: Oscillator, v: float) -> Oscillator:
    if not p.k > 0:
        raise ValueError("lam = omega / w0 needs a spring (k > 0)")
    return p.with_(omega=v * p.w0)


def _zeta(p: Oscillator, v: float) -> Oscillator:
    return p.with_(c=2.0 * v * math.sqrt(p.k * p.m))


def _mu_k(p: Oscillator, v: float) -> Oscillator:
    if not p.mu_s > 0:
        raise ValueError("mu_k is chi mu_s: it needs mu_s > 0")
    return p.with_(chi=v / p.mu_s)


def _mu_s_sigma(p: Oscillator, v: float) -> Oscillator:
    if not (p.mu_s > 0 and p.P0 != 0):
        raise ValueError("mu_s_sigma = mu_s N / P0 needs mu_s > 0 and P0 != 0")
    return p.with_(N=v * abs(p.P0) / p.mu_s)


#: every parameter a branch can be continued in: name -> (description with unit, setter); the fields
#: of Oscillator set directly, the others through the field they define (the rest held fixed)
PARAMETERS: dict[str, tuple[str, Callable[[Oscillator, float], Oscillator]]] = {
    **{n: (d, (lambda n: lambda p, v: p.with_(**{n: v}))(n)) for n, d in (
        ("m", "mass, kg"), ("k", "stiffness, N/m"), ("c", "viscous damping, N s/m"),
        ("P0", "excitation amplitude, N"), ("omega", "excitation frequency, rad/s"), ("phi", "phase, rad"),
        ("N", "normal force, N"), ("mu_s", "static friction coefficient (mu_k = chi mu_s follows)"),
        ("chi", "mu_k / mu_s"))},
    "f": ("excitation frequency, Hz (omega = 2 pi f)", lambda p, v: p.with_(omega=2.0 * math.pi * v)),
    "lam": ("frequency ratio omega / w0 (omega set, k and m fixed)", _lam),
    "zeta": ("damping ratio (c = 2 zeta sqrt(k m))", _zeta),
    "mu_k": ("kinetic friction coefficient (chi = mu_k / mu_s)", _mu_k),
    "mu_s_sigma": ("mu_s N / |P0| (N set)", _mu_s_sigma),
    "sigma": ("N / |P0| (N set)", lambda p, v: p.with_(N=v * abs(p.P0))),
}


def set_parameter(p: Oscillator, name: str, value: float) -> Oscillator:
    """p with the parameter ``name`` (a key of PARAMETERS) set to ``value`` (checked: the error names
    the field and its valid range)."""
    if name not in PARAMETERS:
        raise ValueError(f"unknown continuation parameter {name!r}; valid: {', '.join(PARAMETERS)}")
    return PARAMETERS[name][1](p, float(value))


def get_parameter(p: Oscillator, name: str) -> float:
    """The value of the parameter ``name`` (a key of PARAMETERS) of p."""
    if name == "f":
        return p.f_hz
    if name == "mu_s_sigma":
        return p.mu_s * p.N / abs(p.P0)
    return float(getattr(p, name))


# ---- results ------------------------------------------------------------------------------------


@dataclass
class Bifurcation:
    """A located bifurcation: ``type`` in BIFURCATION_TYPES, at ``param``, on the orbit (x0, v0) at
    t = 0 mod K T of the branch ``branch``."""

    type: str
    param: float
    period: int
    x0: float                        # (a structure's: arrays over its DOFs, as v0, amplitude_m, offset_m)
    v0: float
    multipliers: np.ndarray          # of P^K at the located orbit (|mu| descending)
    branch: int
    bracket: tuple[float, float]     # the parameters of the last bracket of the location
    test: float                      # the test function at the located point (0 at a smooth one)
    note: str = ""                   # e.g. which events changed, or "non-smooth: the multiplier jumps"
    children: list[int] = field(default_factory=list)   # branches started here (doubled, asymmetric)
    events: tuple[Any, Any] | None = None   # grazing: the events per cycle before/after (the oscillator's
    #                                          (transitions, sticks); a structure's per contact, and sticks)
    half_multipliers: np.ndarray | None = None           # of H on a symmetric branch
    amplitude_m: float = math.nan                         # of the located orbit, m
    offset_m: float = math.nan

    def as_dict(self) -> dict[str, Any]:
        """The bifurcation as a JSON-ready dict (multipliers as [real, imaginary] pairs)."""
        def plain(v: Any) -> Any:  # (a structure's x0, v0, amplitude: arrays over its DOFs)
            return np.asarray(v).tolist() if np.ndim(v) else v

        return {"type": self.type, "param": self.param, "period": self.period, "x0": plain(self.x0),
                "v0": plain(self.v0),
                "multipliers": [[float(m.real), float(m.imag)] for m in self.multipliers],
                "branch": self.branch, "bracket": list(self.bracket), "test": self.test, "note": self.note,
                "children": list(self.children), "amplitude_m": plain(self.amplitude_m),
                "offset_m": plain(self.offset_m)}


@dataclass
class Branch:
    """One branch of a continuation, as a record: its ``id`` (the Dataset's ``branch``), ``period`` K,
    ``kind`` (``"full"``: fixed points of P^K; ``"symmetric"``: of H = -P^{1/2}), the ``parent`` branch
    it was switched from (None for a start), the ``points`` it holds in the Dataset and why it
    ``stopped``. Its points are rows of :attr:`Continuation.dataset`; the self-excited belt's branch,
    one branch with its points, is :class:`dryfriction.analysis.self_excited.BeltBranch`."""

    id: int
    period: int
    kind: str                        # "full" (P^K) or "symmetric" (H = -P^{1/2})
    parent: int | None
    points: int = 0
    stopped: str = ""                # why the continuation of this branch ended

    def as_dict(self) -> dict[str, Any]:
        """The branch as a JSON-ready dict."""
        return {"id": self.id, "period": self.period, "kind": self.kind, "parent": self.parent,
                "points": self.points, "stopped": self.stopped}


@dataclass
class Continuation:
    """The result of :func:`continue_orbits`: the parameter's name, every point of every branch as an
    xarray Dataset (dimension ``point``: param, x0, v0, amplitude_m, offset_m, stick_fraction,
    transitions, mu_max, the multipliers, stable, converged, reason, bifurcation, branch, period,
    kind, residual, section_s, arclength), the located bifurcations, the branches, the map's runs."""

    param: str
    dataset: xr.Dataset
    bifurcations: list[Bifurcation]
    branches: list[Branch]
    evaluations: int                 # runs of the map (each one FMU doStep over the map's span)

    def as_dict(self) -> dict[str, Any]:
        """The branches and the bifurcations as a JSON-ready dict (the Dataset left out)."""
        return {"param": self.param, "branches": [b.as_dict() for b in self.branches],
                "bifurcations": [b.as_dict() for b in self.bifurcations]}


# ---- the engine ---------------------------------------------------------------------------------
#
# Pseudo-arclength continuation of G(u) = 0, u in R^(n+1) (scaled unknowns), for any problem with
# the small interface ArclengthProblem: the forced orbits (_BranchMap below) and the self-excited
# belt orbit (dryfriction.analysis.self_excited.branch). The engine owns the corrector (from the
# predictor the walk gives it) and the tangent; each problem its unknowns, its residual and its walk
# (the step control, what a branch point means, where a branch ends).

#: the corrector's arclength constraint holds to this (scaled)
ARC_TOL = 1e-13


class CorrectorFailure(Exception):
    """A corrector that did not converge, or a residual the problem could not evaluate: the step is
    refused (the walk halves it)."""


@dataclass
class Evaluation:
    """The residual G at u; ``Gy`` = dG/du[:n] and ``Gq`` = dG/du[n] once the problem derived them
    (None before). A problem keeps what else it needs in a subclass."""

    u: np.ndarray
    G: np.ndarray
    Gy: np.ndarray | None = None
    Gq: np.ndarray | None = None

    @property
    def A(self) -> np.ndarray:
        """[Gy | Gq], n x (n + 1)."""
        assert self.Gy is not None and self.Gq is not None
        return np.hstack([self.Gy, self.Gq[:, None]])


class ArclengthProblem(Protocol):
    """What the engine needs of a problem (module doc, "the engine"): all may raise CorrectorFailure."""

    def evaluate(self, u: np.ndarray) -> Evaluation:
        """The residual at u."""

    def derive(self, e: Evaluation, parameter: bool) -> None:
        """Set e.Gy, and with ``parameter`` e.Gq too (nothing when set already)."""

    def norm(self, e: Evaluation) -> float:
        """The residual's size, against the corrector's tolerance."""

    def check(self, u: np.ndarray, du: np.ndarray) -> None:
        """CorrectorFailure when the Newton step du from u diverges or leaves the problem's domain."""


def correct(problem: ArclengthProblem, u: np.ndarray, row: np.ndarray | None, anchor: np.ndarray | None,
            c: float, *, tol: float, max_iter: int, arc_tol: float = ARC_TOL) -> tuple[Evaluation, int]:
    """Newton on [G(u); row . (u - anchor) - c] = 0 from u: ``row`` the unit tangent t, ``anchor`` the
    last point and c the step ds (pseudo-arclength), or ``row`` None: the last unknown held fixed.
    Converged when norm(G) <= tol and the constraint holds to ``arc_tol``; the derivatives are
    asked only for a Newton step. (Evaluation, Newton steps taken), or CorrectorFailure."""
    u = np.array(u, dtype=float)
    norm = math.nan
    for it in range(max_iter + 1):
        e = problem.evaluate(u)
        arc = 0.0 if row is None else float(row @ (u - anchor) - c)
        norm = problem.norm(e)
        if norm <= tol and abs(arc) <= arc_tol:
            return e, it
        if it == max_iter:
            break
        problem.derive(e, parameter=row is not None)
        if row is None:
            A, rhs = e.Gy, -e.G
        else:
            A = np.vstack([e.A, row[None, :]])
            rhs = -np.concatenate([e.G, [arc]])
        try:
            du = np.linalg.solve(A, rhs)
        except np.linalg.LinAlgError:
            raise CorrectorFailure("singular corrector matrix") from None
        if row is None:
            du = np.concatenate([du, [0.0]])
        if not np.all(np.isfinite(du)):
            raise CorrectorFailure("the corrector diverged")
        problem.check(u, du)
        u = u + du
    raise CorrectorFailure(f"no convergence in {max_iter} corrector steps (residual {norm:.3g})")


def tangent(problem: ArclengthProblem, e: Evaluation, orient: np.ndarray | None = None) -> np.ndarray:
    """The unit null vector of [Gy | Gq] at e (the branch's direction), pointing along ``orient`` when
    given (t . orient >= 0)."""
    problem.derive(e, parameter=True)
    A = e.A
    if A.shape == (2, 3):
        t = np.cross(A[0], A[1])
        n = float(np.linalg.norm(t))
        t = t / n if n > 0 else t
    else:
        t = np.linalg.svd(A)[2][-1]
        t = t / np.linalg.norm(t)
    if orient is not None and float(t @ orient) < 0:
        t = -t
    return t


# ---- the branch's map ---------------------------------------------------------------------------


@dataclass
class _Eval(Evaluation):
    """The map at u: residual G, G_y (from J), G_q (None until derived), the map's Jacobian J (raw,
    in z), the mode at the end."""

    p: Oscillator | None = None
    J: np.ndarray = field(default_factory=lambda: np.full((2, 2), np.nan))
    mode: int = 0

    def residual(self) -> float:
        return float(np.max(np.abs(self.G)) / max(1.0, float(np.max(np.abs(self.u[:-1])))))


class _BranchMap:
    """The fixed points of a branch's map as an :class:`ArclengthProblem` (module doc)."""

    def __init__(self, fmu: OscillatorFMU2, base: Oscillator, name: str, p_a: float, p_s: float,
                 K: int, kind: str, phase: float, xs: float, w: float, fd_step: float,
                 counter: list[int]) -> None:
        self.counter = counter      # shared count of map runs
        self.fmu, self.base, self.name, self.p_a, self.p_s = fmu, base, name, p_a, p_s
        self.K, self.kind, self.phase, self.fd = K, kind, phase, fd_step
        self.S = np.array([xs, xs * w])
        self.settings = Settings(scheme="exact", extra={"sensitivity": True})

    def param(self, q: float) -> float:
        return self.p_a + q * self.p_s

    def osc(self, q: float) -> Oscillator:
        return set_parameter(self.base, self.name, self.param(q))

    def period(self, p: Oscillator) -> float:
        """The excitation period of the branch's oscillator p, s."""
        return p.period

    def span(self, p: Oscillator) -> float:
        return p.period / 2.0 if self.kind == "symmetric" else self.K * p.period

    def t_s(self, p: Oscillator) -> float:
        return self.phase * self.span(p)

    def raw(self, z: np.ndarray, p: Oscillator) -> tuple[np.ndarray, np.ndarray, int]:
        t_s = self.t_s(p)
        f = self.fmu
        f.start(p.with_(x0=float(z[0]), v0=float(z[1])), self.settings, t0=t_s)
        f.step_to(t_s + self.span(p))
        out = f.get(("x", "v", "mode") + JACOBIAN)
        self.counter[0] += 1
        J = np.array([out[n] for n in JACOBIAN], dtype=float).reshape(2, 2)
        Mz = np.array([out["x"], out["v"]])
        if self.kind == "symmetric":
            return -Mz, -J, int(out["mode"])
        return Mz, J, int(out["mode"])

    def G(self, u: np.ndarray, p: Oscillator) -> tuple[np.ndarray, np.ndarray, int]:
        z = self.S * u[:-1]
        Mz, J, md = self.raw(z, p)
        return (Mz - z) / self.S, J, md

    def evaluate(self, u: np.ndarray) -> _Eval:
        """The residual at u with G_y (the FMU's Jacobian); CorrectorFailure when the parameter leaves
        its valid range or the Jacobian is not available."""
        try:
            p = self.osc(float(u[-1]))
            G, J, md = self.G(u, p)
        except ValueError as err:       # the parameter left its valid range
            raise CorrectorFailure(str(err)) from None
        if not np.all(np.isfinite(J)):
            raise CorrectorFailure("the FMU's Jacobian is not available (NaN: e.g. a tangential breakaway)")
        Gy = (J - np.eye(J.shape[0])) * self.S[None, :] / self.S[:, None]
        return _Eval(np.array(u, dtype=float), G, Gy, None, p, J, md)

    def derive(self, e: Evaluation, parameter: bool) -> None:
        if parameter and e.Gq is None:
            assert isinstance(e, _Eval)
            try:
                self.derivative(e)
            except ValueError as err:
                raise CorrectorFailure(str(err)) from None
            assert e.Gq is not None
            if not np.all(np.isfinite(e.Gq)):
                raise CorrectorFailure("dG/dparam is not finite")

    def norm(self, e: Evaluation) -> float:
        assert isinstance(e, _Eval)
        return e.residual()

    def check(self, u: np.ndarray, du: np.ndarray) -> None:
        if np.max(np.abs(du)) > 10.0 * max(1.0, float(np.max(np.abs(u[:-1])))):
            raise CorrectorFailure("the corrector diverged")

    def derivative(self, e: _Eval) -> None:
        """e.Gq by a central difference in q (one-sided at the edge of the parameter's valid range)."""
        h, u = self.fd, e.u
        side: list[np.ndarray | None] = []
        for sgn in (1.0, -1.0):
            try:
                side.append(self.G(u, self.osc(float(u[-1]) + sgn * h))[0])
            except ValueError:
                side.append(None)
        Gp, Gm = side
        if Gp is not None and Gm is not None:
            e.Gq = (Gp - Gm) / (2.0 * h)
        elif Gp is not None:
            e.Gq = (Gp - e.G) / h
        elif Gm is not None:
            e.Gq = (e.G - Gm) / h
        else:
            raise ValueError(f"{self.name} cannot be varied by {h * self.p_s:g} either way")

    def full_jacobian(self, J: np.ndarray) -> np.ndarray:
        """The Jacobian of P^K from that of the branch's map (P = H o H on a symmetric branch)."""
        return J @ J if self.kind == "symmetric" else J


@dataclass
class _Point:
    e: _Eval
    t: np.ndarray                    # unit tangent
    s: float                         # arclength from the branch's start
    info: dict[str, Any]             # the cycle's observables, multipliers, tests


# ---- the continuation ---------------------------------------------------------------------------


def check_walk(start: float, stop: float, period: int, ds: float, ds_min: float, ds_max: float) -> None:
    """A continuation's range, period and arclength steps checked (ValueError with one sentence);
    an oscillator's and a structure's alike."""
    for n, v in (("start", start), ("stop", stop)):
        if not (isinstance(v, (int, float)) and math.isfinite(v)):
            raise ValueError(f"{n} must be a finite number, not {v!r}")
    if start == stop:
        raise ValueError(f"start and stop must differ (both {start!r})")
    if not (isinstance(period, int) and period >= 1):
        raise ValueError(f"period must be an integer >= 1 (excitation periods), not {period!r}")
    if not (0 < ds_min <= ds <= ds_max):
        raise ValueError(f"need 0 < ds_min <= ds <= ds_max (ds_min = {ds_min}, ds = {ds}, ds_max = {ds_max})")


def continue_orbits(oscillator: Oscillator, param: str, start: float, stop: float, *, period: int = 1,
                    orbit: Orbit | Sequence[Orbit] | None = None,
                    guesses: Iterable[Sequence[float]] | None = None,
                    ds: float = 0.02, ds_min: float = 1e-6, ds_max: float = 1.0, max_points: int = 400,
                    tol: float = 1e-11, ptol: float = 1e-10, max_turn: float = 0.3, fd_step: float = 1e-6,
                    max_iter: int = 8, switch: bool = True, max_branches: int = 8, symmetric: bool = True,
                    detect: Sequence[str] = BIFURCATION_TYPES,
                    fmu: OscillatorFMU2 | None = None,
                    progress: Callable[[int], None] | None = None) -> Continuation:
    """Continue the periodic orbits of ``period`` K excitation periods of ``oscillator`` in the
    parameter ``param`` (a key of :data:`PARAMETERS`) from ``start`` to ``stop`` (module doc).

    The branches start from ``orbit`` (one or more :class:`~dryfriction.analysis.orbits.Orbit` of the
    oscillator with ``param = start``), else from every orbit find_orbits finds there (from
    ``guesses``: states at t = 0, and its own). ``ds``, ``ds_min``, ``ds_max``: arclength steps in the
    scaled unknowns (state in static deflections, parameter over p_s); ``tol``: the corrector's scaled
    residual; ``ptol``: the location of a bifurcation, relative to max(1, |p|). ``switch``: continue
    the doubled branch of every period doubling and the two asymmetric branches of every symmetry
    breaking (at most ``max_branches`` branches in all). ``symmetric``: continue a symmetric
    period-1 orbit as a fixed point of H = -P^{1/2}. ``progress``: called with the number of points
    so far. Every DryFrictionWarning the FMU emits reaches the caller.

    Returns
    -------
    Continuation
        The branches' points (an xarray Dataset: parameter, state, amplitude, multipliers, stability),
        the bifurcations located on them and the branches.

    Raises
    ------
    ValueError
        An unknown ``param`` or bifurcation type, ``start`` equal to ``stop``, steps out of order,
        no orbit (or none that converged) to start from.

    Examples
    --------
    >>> from dryfriction import Oscillator, continue_orbits
    >>> p = Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.6, chi=0.8)
    >>> c = continue_orbits(p, "chi", 0.8, 0.22)
    >>> [b["type"] for b in c.as_dict()["bifurcations"]]
    ['symmetry_breaking', 'grazing', 'period_doubling', 'grazing', 'period_doubling']

    A structure (:class:`~dryfriction.system.structure.System`) in place of the oscillator: its orbits on the located
    map, continued by the same engine
    (:func:`dryfriction.analysis.system_continuation.continue_system_orbits`; ``param`` one of
    ``omega``, ``N``, ``mu_s``, ``mu_k``, ``force``; a symmetric orbit on the half-period map as here).
    """
    from ..system.structure import System

    if isinstance(oscillator, System):
        from .system_continuation import continue_system_orbits

        return continue_system_orbits(oscillator, param, start, stop, period=period, orbit=orbit,  # type: ignore[arg-type]
                                      ds=ds, ds_min=ds_min, ds_max=min(ds_max, 0.5), max_points=max_points,
                                      tol=max(tol, 1e-8), ptol=max(ptol, 1e-8), max_turn=max_turn, fd_step=fd_step,
                                      max_iter=max_iter, switch=switch, max_branches=max_branches,
                                      detect=detect, symmetric=symmetric, progress=progress)
    if param not in PARAMETERS:
        raise ValueError(f"unknown continuation parameter {param!r}; valid: {', '.join(PARAMETERS)}")
    check_walk(start, stop, period, ds, ds_min, ds_max)
    if not (isinstance(max_points, int) and max_points >= 2):
        raise ValueError(f"max_points must be an integer >= 2, not {max_points!r}")
    bad = [d for d in detect if d not in BIFURCATION_TYPES]
    if bad:
        raise ValueError(f"unknown bifurcation type(s) {bad}; valid: {', '.join(BIFURCATION_TYPES)}")
    p0 = set_parameter(oscillator, param, start)
    set_parameter(oscillator, param, stop)            # both ends valid (the error names the field)
    own = fmu is None
    f = OscillatorFMU2() if own else fmu
    try:
        if orbit is None:
            starts = find_orbits(p0, period, guesses, fmu=f)
            if not starts:
                raise ValueError(f"no orbit of period {period} found at {param} = {start!r} to continue")
        else:
            starts = [orbit] if isinstance(orbit, Orbit) else list(orbit)
        run = _Run(f, p0, param, float(start), float(stop), ds, ds_min, ds_max, max_points, tol, ptol,
                   max_turn, fd_step, max_iter, switch, max_branches, symmetric, tuple(detect), progress)
        for o in starts:
            if not o.converged:
                raise ValueError(f"the start orbit did not converge ({o.reason}): nothing to continue")
            run.queue.append((o, None, None))
        run.go()
        return run.result()
    finally:
        if own:
            f.close()


class _Run:
    def __init__(self, fmu: OscillatorFMU2, p0: Oscillator, name: str, start: float, stop: float, ds: float,
                 ds_min: float, ds_max: float, max_points: int, tol: float, ptol: float, max_turn: float,
                 fd_step: float, max_iter: int, switch: bool, max_branches: int, symmetric: bool,
                 detect: tuple[str, ...], progress: Callable[[int], None] | None) -> None:
        self.fmu, self.p0, self.name, self.start, self.stop = fmu, p0, name, start, stop
        self.lo, self.hi = min(start, stop), max(start, stop)
        self.ds0, self.ds_min, self.ds_max, self.max_points = ds, ds_min, ds_max, max_points
        self.tol, self.ptol, self.max_turn, self.fd, self.max_iter = tol, ptol, max_turn, fd_step, max_iter
        self.switch, self.max_branches, self.use_symmetry, self.detect = switch, max_branches, symmetric, detect
        self.progress = progress
        self.p_s = max(abs(start), abs(stop), abs(stop - start))
        self.init_scales(p0)
        # (start orbit or None, (map, u, tangent) of a switch or None, parent branch id)
        self.queue: list[tuple[Orbit | None, tuple[_BranchMap, np.ndarray, np.ndarray] | None, int | None]] = []
        self.branches: list[Branch] = []
        self.rows: list[dict[str, Any]] = []
        self.bifs: list[Bifurcation] = []
        self.pending: list[tuple[float, _Point, str]] = []   # located orbits of one step, to record
        self.counter = [0]         # runs of a map (each one FMU doStep over its span)
        self.evaluations = 0       # other runs (cycles, event counts)

    # -- helpers (a model's: a structure's run overrides them, dryfriction.analysis.system_continuation) --
    def init_scales(self, p0: Any) -> None:
        """The unknowns' scales of the branches (the oscillator's static deflection and rate)."""
        self.xs, self.w = scales(p0)

    def new_map(self, K: int, kind: str, phase: float) -> _BranchMap:
        return _BranchMap(self.fmu, self.p0, self.name, self.start, self.p_s, K, kind, phase, self.xs, self.w,
                          self.fd, self.counter)

    def in_range(self, q: float) -> bool:
        v = self.start + q * self.p_s
        return self.lo - 1e-12 * self.p_s <= v <= self.hi + 1e-12 * self.p_s

    def correct(self, m: _BranchMap, u: np.ndarray, t: np.ndarray | None, u_prev: np.ndarray | None,
                ds: float, max_iter: int | None = None) -> tuple[_Eval, int]:
        """The engine's corrector on m (t None: the parameter fixed). Next to a corner of the branch
        (an event changes) dG/dq is a mix of both sides: Newton then converges only linearly, so the
        location of a bifurcation allows more steps."""
        e, it = correct(m, u, t, u_prev, ds, tol=self.tol, max_iter=self.max_iter if max_iter is None else max_iter)
        assert isinstance(e, _Eval)
        return e, it

    def describe(self, m: _BranchMap, e: _Eval) -> dict[str, Any]:
        """The cycle's observables, multipliers and test functions at a converged point."""
        p = e.p
        z = m.S * e.u[:-1]
        t_s = m.t_s(p)
        cm = _Map(self.fmu, p, m.K)
        cyc = cm.cycle(z, t_s)
        self.evaluations += 1
        KT = m.K * p.period
        t = cyc["t"]
        i0 = int(np.argmin(np.abs(t - KT * math.floor((t_s + KT) / KT + 1e-12))))
        sticks = float(cyc["stick_fraction"]) > 0.0 or bool(np.any(cyc["mode"] == 0))
        JP = m.full_jacobian(e.J)
        mu = multipliers(JP, sticks)
        info: dict[str, Any] = {
            "x0": float(cyc["x"][i0]), "v0": float(cyc["v"][i0]),
            "amplitude": (float(cyc["x_max"]) - float(cyc["x_min"])) / 2.0,
            "offset": (float(cyc["x_max"]) + float(cyc["x_min"])) / 2.0,
            "stick_fraction": float(cyc["stick_fraction"]), "transitions": int(cyc["transitions"]),
            "mu": mu, "stable": bool(np.all(np.abs(mu) < 1.0 - STABILITY_MARGIN)),
            "section": t_s, "cycle": cyc,
        }
        info.update(self.tests(m, e))
        info["signature"] = (info["transitions"], info["stick_fraction"] > 0.0)
        return info

    def tests(self, m: _BranchMap, e: _Eval) -> dict[str, float]:
        """The test functions at a converged point (module doc)."""
        J = e.J
        JP = m.full_jacobian(J)
        eye = np.eye(J.shape[0])
        out = {"fold": float(np.linalg.det(J - eye)), "period_doubling": float(np.linalg.det(JP + eye))}
        out["symmetry_breaking"] = float(np.linalg.det(J + eye)) if m.kind == "symmetric" else math.nan
        return out

    def signature(self, m: _BranchMap, e: _Eval) -> tuple[int, bool]:
        """(transitions, sticks) over one K-cycle: one run with the FMU's observables."""
        p = e.p
        z = m.S * e.u[:-1]
        t_s = m.t_s(p)
        KT = m.K * p.period
        st = Settings(scheme="exact", observe=True, t_obs_start=t_s, t_obs_stop=t_s + KT)
        self.fmu.start(p.with_(x0=float(z[0]), v0=float(z[1])), st, t0=t_s)
        self.fmu.step_to(t_s + KT)
        o = self.fmu.get(("stick_fraction", "transitions"))
        self.evaluations += 1
        return int(o["transitions"]), float(o["stick_fraction"]) > 0.0

    def record(self, b: Branch, m: _BranchMap, pt: _Point | None, q: float, converged: bool,
               reason: str = "", bifurcation: str = "") -> None:
        row: dict[str, Any] = {"branch": b.id, "period": m.K, "kind": m.kind, "param": self.start + q * self.p_s,
                               "converged": converged, "reason": reason, "bifurcation": bifurcation}
        if pt is not None:
            i = pt.info
            row.update(x0=i["x0"], v0=i["v0"], amplitude_m=i["amplitude"], offset_m=i["offset"],
                       stick_fraction=i["stick_fraction"], transitions=i["transitions"],
                       mu=i["mu"], stable=i["stable"], section_s=i["section"], residual=pt.e.residual(),
                       arclength=pt.s)
        self.rows.append(row)
        b.points += 1
        if self.progress is not None:
            self.progress(len(self.rows))

    # -- the branches --
    def go(self) -> None:
        while self.queue and len(self.branches) < self.max_branches:
            orbit, sw, parent = self.queue.pop(0)
            try:
                self.branch(orbit, sw, parent)
            except CorrectorFailure as err:
                self.branches[-1].stopped = f"could not start: {err}"

    def start_map(self, o: Orbit) -> tuple[_BranchMap, np.ndarray]:
        KT = o.period * self.p0.period
        t_s = o.section % KT
        z = np.array(o.section_state, dtype=float)
        if not np.all(np.isfinite(z)):
            raise CorrectorFailure("the start orbit has no section state")
        kind = "full"
        if self.use_symmetry and o.period == 1 and not o.stuck:
            T = self.p0.period
            h = self.new_map(1, "symmetric", (t_s % (T / 2.0)) / (T / 2.0))
            if t_s >= T / 2.0:          # the section in the second half: the state half a period before
                z0 = -z
            else:
                z0 = z
            u = np.array([*(z0 / h.S), 0.0])
            e = h.evaluate(u)
            if e.residual() <= SYMMETRIC:
                return h, u
        m = self.new_map(o.period, kind, t_s / KT)
        return m, np.array([*(z / m.S), 0.0])

    def branch(self, orbit: Orbit | None, sw: tuple[_BranchMap, np.ndarray, np.ndarray] | None,
               parent: int | None) -> None:
        if orbit is not None:
            b = Branch(len(self.branches), orbit.period, "full", parent)
            self.branches.append(b)
            if getattr(orbit, "stuck", False) and getattr(orbit, "rest_interval", None) is not None:
                lo, hi = orbit.rest_interval
                raise CorrectorFailure(f"the start orbit is the block at rest, one of the interval of rest positions "
                               f"[{lo:.6g}, {hi:.6g}] m (|k x| <= F_b - |P0|, a multiplier exactly 1): a continuum, "
                               "not a branch to follow; it holds while |P0| <= F_b")
            m, u = self.start_map(orbit)
            b.kind = m.kind
            e, _ = self.correct(m, u, None, None, 0.0)
            t = tangent(m, e)
            if t[-1] * (self.stop - self.start) < 0:
                t = -t
            if abs(t[-1]) < 1e-12:
                raise CorrectorFailure("the start orbit is at a fold in the parameter (dp/ds = 0)")
            pt = _Point(e, t, 0.0, self.describe(m, e))
            self.record(b, m, pt, float(e.u[-1]), True)
        else:
            assert sw is not None
            m, u, t = sw
            b = Branch(len(self.branches), m.K, m.kind, parent)
            self.branches.append(b)
            # the first step off the parent along the eigenvector: the parent's orbit is the branch
            # point; the new branch starts one step away
            e0 = m.evaluate(u)
            pt = _Point(e0, t, 0.0, self.describe(m, e0))
            pt = self.first_step(b, m, pt)
            if pt is None:
                return
            self.record(b, m, pt, float(pt.e.u[-1]), True)
        self.walk(b, m, pt)

    def first_step(self, b: Branch, m: _BranchMap, pt: _Point) -> _Point | None:
        ds = self.ds0
        while ds >= self.ds_min:
            try:
                e, _ = self.correct(m, pt.e.u + ds * pt.t, pt.t, pt.e.u, ds)
                gap = float(np.max(np.abs(e.u[:-1] - pt.e.u[:-1])))
                if gap >= 0.1 * ds:
                    t = tangent(m, e, pt.t)
            except CorrectorFailure:
                ds /= 2.0
                continue
            if gap < 0.1 * ds:              # fell back onto the parent branch
                ds *= 2.0
                if ds > self.ds_max * 4:
                    break
                continue
            return _Point(e, t, ds, self.describe(m, e))
        b.stopped = "the switch found no branch off the bifurcation point"
        return None

    def walk(self, b: Branch, m: _BranchMap, pt: _Point) -> None:
        ds = self.ds0
        while True:
            if b.points >= self.max_points:
                b.stopped = f"max_points ({self.max_points}) reached at {self.name} = {self.param(pt):.10g}"
                return
            if ds < self.ds_min:
                b.stopped = (f"the step fell below ds_min = {self.ds_min:g} at {self.name} = "
                             f"{self.param(pt):.10g}: {last}")
                crossed = self.cross_corner(b, m, pt) if "grazing" in self.detect else None
                if crossed is not None:
                    pt, ds, b.stopped = crossed, self.ds0 * CORNER_STEPS[-1], ""
                    continue
                self.record(b, m, None, float(pt.e.u[-1] + self.ds_min * pt.t[-1]), False, last)
                return
            u_pred = pt.e.u + ds * pt.t
            if not self.in_range(float(u_pred[-1])):
                # the step would leave the range: solve at its end, at a fixed parameter (a
                # parameter's valid range may end there, e.g. N = 0)
                end = self.end_point(m, pt, u_pred)
                s_end = float(pt.t @ (end.e.u - pt.e.u)) if end is not None else 0.0
                if end is not None and s_end > 0:
                    self.locate_all(b, m, pt, end, s_end)
                    b.stopped = f"reached the end of the range at {self.name} = {self.param(end):.10g}"
                    self.record(b, m, end, float(end.e.u[-1]), True)
                    return
            try:
                try:
                    e, it = self.correct(m, u_pred, pt.t, pt.e.u, ds)
                except CorrectorFailure:
                    if ds > 1e-2 * self.ds0:
                        raise
                    # a short step that does not converge fast: next to a corner of the branch, where
                    # dG/dq straddles it (see correct)
                    e, it = self.correct(m, pt.e.u + ds * pt.t, pt.t, pt.e.u, ds, max_iter=LOCATE_ITERATIONS)
                if float(np.linalg.norm(e.u - pt.e.u)) > KINK_REACH * ds:
                    # (the arclength constraint holds along the tangent only: Newton may land far
                    # across it, on another branch, whatever the tangent there)
                    raise CorrectorFailure("the corrector went off to another branch")
                t = tangent(m, e, pt.t)
                turn = math.acos(max(-1.0, min(1.0, float(t @ pt.t))))
                if turn > self.max_turn and ds > self.ds_min * 1.0001:
                    if self.signature(m, e) == pt.info["signature"]:
                        raise CorrectorFailure(f"the tangent turned by {turn:.3g} rad")
                    # an event changed: the branch has a corner there (grazing); go on along the new
                    # tangent, pointing away from the last point
                    t = tangent(m, e, e.u - pt.e.u)
                if int(e.mode) == 0 and ds > self.ds_min * 1.0001:
                    raise CorrectorFailure("the orbit is stuck at the section")
            except CorrectorFailure as err:
                last = str(err)
                ds /= 2.0
                continue
            new = _Point(e, t, pt.s + ds, self.describe(m, e))
            if not self.in_range(float(e.u[-1])):
                self.locate_all(b, m, pt, new, ds)
                end = self.end_point(m, pt, new)
                b.stopped = f"reached the end of the range at {self.name} = {self.param(end or new):.10g}"
                self.record(b, m, end or new, float((end or new).e.u[-1]), True)
                return
            self.locate_all(b, m, pt, new, ds)
            self.record(b, m, new, float(e.u[-1]), True)
            pt = new
            m, pt = self.maybe_move_section(m, pt)
            if it <= 3:
                ds = min(self.ds_max, 1.5 * ds)

    def cross_corner(self, b: Branch, m: _BranchMap, pt: _Point) -> _Point | None:
        """Past a corner of the branch (an event changes: a grazing) the arclength corrector may not
        converge at any step (dG/dq straddles the corner, and a located scheme's discrete map bends
        there): from the last point pt, orbits at a fixed parameter a step CORNER_STEPS ds0 along the
        tangent; the first whose events per cycle differ from pt's is a point past the corner: the
        grazing is located between the two (at fixed parameters) and the walk goes on from it. None
        where no such orbit is found."""
        for frac in CORNER_STEPS:
            step = frac * self.ds0
            try:
                e, _ = self.correct(m, pt.e.u + step * pt.t, None, None, 0.0, max_iter=LOCATE_ITERATIONS)
            except CorrectorFailure:
                continue
            dist = float(np.linalg.norm(e.u - pt.e.u))
            if not 0.0 < dist <= CORNER_REACH * step:
                continue
            info = self.describe(m, e)
            if info["signature"] == pt.info["signature"]:
                continue
            new = _Point(e, tangent(m, e, e.u - pt.e.u), pt.s + dist, info)
            self.locate(b, m, pt, new, dist, "grazing", True)
            self.record(b, m, new, float(e.u[-1]), True)
            return new
        return None

    def end_point(self, m: _BranchMap, a: _Point, c: _Point | np.ndarray) -> _Point | None:
        """The orbit at the end of the range (start or stop) between a (inside) and c (a point or a
        predicted u outside), or None."""
        uc = c if isinstance(c, np.ndarray) else c.e.u
        qa, qc = float(a.e.u[-1]), float(uc[-1])
        v = self.start + qc * self.p_s
        q_end = (self.stop if abs(v - self.stop) < abs(v - self.start) else self.start) - self.start
        q_end /= self.p_s
        if qc == qa:
            return None
        u = a.e.u + (q_end - qa) / (qc - qa) * (uc - a.e.u)
        u[-1] = q_end
        try:
            e, _ = self.correct(m, u, None, None, 0.0)
            t = tangent(m, e, a.t)
        except CorrectorFailure:
            return None
        # Newton at the fixed end may land on another branch: refused as a step of the walk would be
        # (too far, or the tangent turned too much); the walk then steps on towards the end
        if float(np.linalg.norm(e.u - a.e.u)) > KINK_REACH * float(np.linalg.norm(uc - a.e.u)) or \
                math.acos(max(-1.0, min(1.0, float(t @ a.t)))) > self.max_turn:
            return None
        return _Point(e, t, a.s + float(np.linalg.norm(e.u - a.e.u)), self.describe(m, e))

    def param(self, pt: _Point) -> float:
        return self.start + float(pt.e.u[-1]) * self.p_s

    def param_unit(self) -> str:
        """The continued parameter's unit (the oscillator's PARAMETERS)."""
        return PARAMETERS[self.name][0]

    def maybe_move_section(self, m: _BranchMap, pt: _Point) -> tuple[_BranchMap, _Point]:
        """Choose the section again when a stick phase is near it (module doc)."""
        cyc = pt.info["cycle"]
        t, mode = cyc["t"], cyc["mode"]
        p = pt.e.p
        span = m.span(p)
        t_s = m.t_s(p)
        stuck = mode == 0
        if not stuck.any():
            return m, pt
        KT = m.K * p.period
        d = np.abs(((t[stuck] - t_s) + KT / 2.0) % KT - KT / 2.0)
        if m.kind == "symmetric":
            d = np.minimum(d, np.abs(((t[stuck] - t_s - span) + KT / 2.0) % KT - KT / 2.0))
        if float(d.min()) > SECTION_MARGIN * span:
            return m, pt
        t_new = _slide_section(t, mode, t_s, KT)
        if t_new is None or math.isnan(t_new):
            return m, pt
        if abs(pt.t[-1]) < 1e-3:         # near a fold the orientation is not safe to carry over: keep it
            return m, pt
        i = int(np.argmin(np.abs(t - t_new)))
        t_i = float(t[i])
        z = np.array([cyc["x"][i], cyc["v"][i]])
        off = t_i % span
        if m.kind == "symmetric" and int(round((t_i - off) / span)) % 2:
            z = -z          # half a period on: the mirror image
        m2 = self.new_map(m.K, m.kind, off / span)
        try:
            e, _ = self.correct(m2, np.array([*(z / m2.S), pt.e.u[-1]]), None, None, 0.0)
            tn = tangent(m2, e)
        except CorrectorFailure:
            return m, pt
        if tn[2] * pt.t[-1] < 0:
            tn = -tn
        return m2, _Point(e, tn, pt.s, self.describe(m2, e))

    # -- bifurcations between two points --
    def locate_all(self, b: Branch, m: _BranchMap, a: _Point, c: _Point, ds: float) -> None:
        """Locate every bifurcation between a and c; their orbits join the branch's points, in order."""
        self.pending = []
        self._locate_all(b, m, a, c, ds)
        for s, pt, typ in sorted(self.pending, key=lambda x: x[0]):
            pt.s = s
            self.record(b, m, pt, float(pt.e.u[-1]), True, bifurcation=typ)

    def _locate_all(self, b: Branch, m: _BranchMap, a: _Point, c: _Point, ds: float) -> None:
        ia, ic = a.info, c.info
        tests: list[str] = []
        if "fold" in self.detect and _flip(ia["fold"], ic["fold"]):
            tests.append("fold")
        elif "fold" in self.detect and _flip(float(a.t[-1]), float(c.t[-1])):
            self.corner_fold(b, m, a, c)
        if "period_doubling" in self.detect and _flip(ia["period_doubling"], ic["period_doubling"]):
            tests.append("period_doubling")
        if "symmetry_breaking" in self.detect and m.kind == "symmetric" and \
                _flip(ia["symmetry_breaking"], ic["symmetry_breaking"]):
            tests.append("symmetry_breaking")
        for kind in tests:
            self.locate(b, m, a, c, ds, kind)
        if "grazing" in self.detect and ia["signature"] != ic["signature"]:
            # at fixed parameter values, unless the step holds a fold too; if a corrector fails
            # there, again along the step's arclength
            natural = not _flip(float(a.t[-1]), float(c.t[-1])) and abs(c.e.u[-1] - a.e.u[-1]) > 1e-3 * ds
            self.locate(b, m, a, c, ds, "grazing", natural)
            if natural and self.bifs[-1].note.startswith("located only to the bracket"):
                self.bifs.pop()
                self.pending.pop()
                self.locate(b, m, a, c, ds, "grazing", False)

    def locate(self, b: Branch, m: _BranchMap, a: _Point, c: _Point, ds: float, kind: str,
               natural: bool = False) -> None:
        key = kind
        cache: dict[float, tuple[_Eval, Any]] = {}

        def at(s: float) -> tuple[_Eval, Any]:
            if s not in cache:
                if natural:
                    # a corner of the branch: at a fixed parameter (Newton in the state with the exact
                    # Jacobian only; the finite difference in q would straddle the corner)
                    u = a.e.u + (s / ds) * (c.e.u - a.e.u)
                    e, _ = self.correct(m, u, None, None, 0.0, max_iter=LOCATE_ITERATIONS)
                else:
                    u = a.e.u + s * a.t
                    e, _ = self.correct(m, u, a.t, a.e.u, s, max_iter=LOCATE_ITERATIONS)
                cache[s] = (e, self.signature(m, e) if kind == "grazing" else self.tests(m, e)[key])
            return cache[s]

        g0 = a.info["signature"] if kind == "grazing" else a.info[key]
        g1 = c.info["signature"] if kind == "grazing" else c.info[key]
        sig0, sig1 = g0, g1

        def value(s: float) -> float:
            """The test at s (grazing: -1 with the events of a, +1 with others)."""
            g = at(s)[1]
            if kind == "grazing":
                return -1.0 if g == sig0 else 1.0
            return float(g)

        # the tolerance in s: ptol in the parameter over the larger |dp/ds| of the two ends (on a line
        # of fixed parameters, natural, p is linear in s); a grazing to 1e-6 of the step too
        p_a, p_c = self.param(a), self.param(c)
        slope = abs(p_c - p_a) / ds if natural else self.p_s * max(abs(float(a.t[-1])), abs(float(c.t[-1])))
        xtol = self.ptol * max(1.0, abs(p_a), abs(p_c)) / slope if slope > 0 else ds
        if kind == "grazing":
            xtol = min(xtol, 1e-6 * ds)
        search = RootSearch(0.0, ds, -1.0 if kind == "grazing" else g0, 1.0 if kind == "grazing" else g1,
                            xtol=max(xtol, 1e-14), rtol=0.0, maxiter=LOCATE_POINTS)
        note = ""
        try:
            while not search.done:
                search.tell(value(search.x))
            if not search.converged:
                note = f"located only to the bracket ({LOCATE_POINTS} trial points)"
        except CorrectorFailure as err:
            note = f"located only to the bracket (a corrector failed: {err})"
        s0, _, s1, _ = search.bracket
        if kind == "grazing":
            # s0 keeps the events of a, s1 has the others (a bracket of a step function)
            sig1 = cache[s1][1] if s1 in cache else g1
            s_best = s1 if s1 in cache else s0
        else:
            s_best = min((s for s in (s0, s1) if s in cache), key=lambda s: abs(cache[s][1]),
                         default=None)  # type: ignore[arg-type]
        if s_best is None or s_best not in cache:
            e = c.e if kind == "grazing" else (a.e if abs(a.info.get(key, 1.0)) < abs(c.info.get(key, 1.0)) else c.e)
        else:
            e = cache[s_best][0]
        e0 = cache[s0][0] if s0 in cache else a.e
        e1 = cache[s1][0] if s1 in cache else c.e
        bracket = tuple(sorted((self.start + float(e0.u[-1]) * self.p_s, self.start + float(e1.u[-1]) * self.p_s)))
        info = self.describe(m, e)
        test = 0.0 if kind == "grazing" else float(info[key])
        mu = info["mu"]
        typ = kind
        if kind == "grazing":
            note = (note + "; " if note else "") + (f"events per cycle (transitions, sticks): {sig0} -> {sig1}")
        else:
            target = {"fold": 1.0, "period_doubling": -1.0, "symmetry_breaking": -1.0}[kind]
            mus = np.linalg.eigvals(m.full_jacobian(e.J) if kind == "period_doubling" else e.J)
            gap = float(np.min(np.abs(mus - target)))
            if gap > 1e-4:
                note = (note + "; " if note else "") + (f"non-smooth: the multiplier jumps across {target:+g} "
                                                       f"(nearest {gap:.2g} away; an event changes there)")
            if kind == "fold" and not _flip(float(a.t[-1]), float(c.t[-1])):
                note = (note + "; " if note else "") + "dp/ds keeps its sign: a branch point, not a fold"
        bif = Bifurcation(type=typ, param=self.start + float(e.u[-1]) * self.p_s, period=m.K, x0=info["x0"],
                          v0=info["v0"], multipliers=mu, branch=b.id, bracket=(float(bracket[0]), float(bracket[1])),
                          test=test, note=note,
                          events=(sig0, sig1) if kind == "grazing" else None,
                          half_multipliers=np.linalg.eigvals(e.J) if m.kind == "symmetric" else None,
                          amplitude_m=info["amplitude"], offset_m=info["offset"])
        self.bifs.append(bif)
        self.pending.append((a.s + float(np.linalg.norm(e.u - a.e.u)), _Point(e, a.t, 0.0, info), typ))
        if self.switch and kind in ("period_doubling", "symmetry_breaking") and "non-smooth" not in note:
            self.spawn(b, m, e, bif, kind)

    def corner_fold(self, b: Branch, m: _BranchMap, a: _Point, c: _Point) -> None:
        """dp/ds changes sign between a and c but no multiplier crosses +1: the branch turns at a
        corner (a non-smooth fold). Reported at the point of the two with the extreme parameter, not
        located (the tangent's orientation at trial points past a corner is not known)."""
        pa, pc = self.param(a), self.param(c)
        # q (and p: p_s > 0) grew at a when a.t[-1] > 0: the extreme is then the larger parameter
        pt = a if (a.t[-1] > 0) == (pa >= pc) else c
        i = pt.info
        self.bifs.append(Bifurcation(
            type="fold", param=self.param(pt), period=m.K, x0=i["x0"], v0=i["v0"], multipliers=i["mu"],
            branch=b.id, bracket=(min(pa, pc), max(pa, pc)), test=float(i["fold"]),
            note=("non-smooth: dp/ds changes sign but no multiplier crosses +1 (a corner); not located, "
                  "the extreme of the two branch points around it"),
            amplitude_m=i["amplitude"], offset_m=i["offset"]))

    def spawn(self, b: Branch, m: _BranchMap, e: _Eval, bif: Bifurcation, kind: str) -> None:
        p = e.p
        z = m.S * e.u[:-1]
        if kind == "period_doubling":
            JP = m.full_jacobian(e.J)
            w, V = np.linalg.eig(JP)
            j = int(np.argmin(np.abs(w + 1.0)))
            vec = np.real(V[:, j])
            K2 = 2 * m.K
            t_s = m.t_s(p)
            m2 = self.new_map(K2, "full", t_s / (K2 * m.period(p)))
            dirs = [1.0]
        else:
            w, V = np.linalg.eig(e.J)
            j = int(np.argmin(np.abs(w + 1.0)))
            vec = np.real(V[:, j])
            t_s = m.t_s(p)
            m2 = self.new_map(1, "full", t_s / m.period(p))
            dirs = [1.0, -1.0]
        v = vec / m2.S
        v = v / float(np.linalg.norm(v))
        for sgn in dirs:
            if len(self.branches) + len([x for x in self.queue if x[1] is not None]) >= self.max_branches:
                bif.note = (bif.note + "; " if bif.note else "") + f"max_branches ({self.max_branches}) reached: not switched"
                return
            u = np.array([*(z / m2.S), e.u[-1]])
            t = np.array([*(sgn * v), 0.0])
            bif.children.append(len(self.branches) + len([x for x in self.queue if x[1] is not None]))
            self.queue.append((None, (m2, u, t), b.id))

    # -- output --
    def result(self) -> Continuation:
        import xarray as xr

        rows = self.rows
        n = len(rows)

        def col(k: str, default: Any = math.nan) -> np.ndarray:
            return np.array([r.get(k, default) for r in rows])

        width = max([len(r["mu"]) for r in rows if "mu" in r] + [2])
        mu = np.full((n, width), np.nan, dtype=complex)
        for i, r in enumerate(rows):
            if "mu" in r:
                mu[i, :len(r["mu"])] = r["mu"]
        # per point a number (the oscillator) or an array over the structure's DOFs / contacts
        shaped: dict[str, Any] = {}
        for k, dim in (("x0", "dof"), ("v0", "dof"), ("amplitude_m", "dof"), ("offset_m", "dof"),
                       ("stick_fraction", "contact")):
            sizes = [np.size(r[k]) for r in rows if k in r]
            if sizes and (max(sizes) > 1 or any(np.ndim(r[k]) > 0 for r in rows if k in r)):
                a = np.full((n, max(sizes)), np.nan)
                for i, r in enumerate(rows):
                    if k in r:
                        a[i] = r[k]
                shaped[k] = (("point", dim), a)
            else:
                shaped[k] = ("point", col(k).astype(float))
        mag = np.abs(mu)
        mu_max = np.where(np.isnan(mag).all(axis=1), np.nan, np.where(np.isnan(mag), -np.inf, mag).max(axis=1)) \
            if n else np.zeros(0)
        ds = xr.Dataset(
            {
                "param": ("point", col("param").astype(float)),
                **shaped,
                "transitions": ("point", col("transitions", -1).astype(np.int64)),
                "mu_max": ("point", mu_max),
                "multiplier_re": (("point", "multiplier"), mu.real),
                "multiplier_im": (("point", "multiplier"), mu.imag),
                "stable": ("point", col("stable", False).astype(bool)),
                "converged": ("point", col("converged", False).astype(bool)),
                "reason": ("point", col("reason", "").astype(str)),
                "bifurcation": ("point", col("bifurcation", "").astype(str)),
                "branch": ("point", col("branch", -1).astype(np.int64)),
                "period": ("point", col("period", 0).astype(np.int64)),
                "kind": ("point", col("kind", "").astype(str)),
                "residual": ("point", col("residual").astype(float)),
                "section_s": ("point", col("section_s").astype(float)),
                "arclength": ("point", col("arclength").astype(float)),
            },
            coords={"point": np.arange(n), "multiplier": np.arange(width)},
        )
        ds["param"].attrs["long_name"] = f"{self.name} ({self.param_unit()})"
        ds["x0"].attrs["units"], ds["v0"].attrs["units"] = "m", "m/s"
        ds["amplitude_m"].attrs["units"] = ds["offset_m"].attrs["units"] = "m"
        ds["mu_max"].attrs["long_name"] = "largest |Floquet multiplier| of P^K"
        ds.attrs.update(param=self.name, start=self.start, stop=self.stop,
                        dp_dparam="central finite difference", dP_dz="the FMU's exact Jacobian (sensitivity)")
        return Continuation(self.name, ds, self.bifs, self.branches, self.evaluations + self.counter[0])


def _flip(a: float, b: float) -> bool:
    """Whether a test function changes sign from a to b."""
    return bool(math.isfinite(a) and math.isfinite(b) and (a > 0) != (b > 0))
