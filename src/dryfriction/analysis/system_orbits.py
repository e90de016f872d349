"""Periodic orbits of a structure with friction contacts (:class:`~dryfriction.system.structure.System`)
by Newton shooting on the located scheme's stroboscopic map (docs/system_orbits.md).

The map P^K: z = (x, v, s) at the section time t_s -> z at t_s + K T, T = 2 pi / omega, s the
Jenkins contacts' sliders, is one run of the ``DryFrictionSystem`` FMU from t_s (its start state
set: ``x0``, ``v0`` and each Jenkins spring's force ``f0 = -k_t (w_j . x - s_j)``, its slider
stuck). Its Jacobian is the FMU's own (``sensitivity = true``): the product of the step matrices in
the contacts' modes, with the switch time's derivative at every located switch and the consistent
restart after it; a rigid contact stuck at the section removes its direction (its slip's derivative
0). Never a finite difference.

Newton solves (J - I) dz = -r, r = P^K(z) - z, with a backtracking line search on the scaled
residual; converged when the residual is at most ``tol`` relative: ``|S^-1 r|_inf / max(1,
|S^-1 z|_inf)``, S the structure's own scales (each DOF's motion in the guess's cycle, its velocity
that times omega). The orbit's error is the scheme's (second order in h): the orbit is solved again
at h / 2 from the one at h (chord steps with the h orbit's Jacobian, on map runs without one: the
orbits differ by O(h^2); its multipliers are the h orbit's), its amplitude extrapolated (Richardson)
and the difference reported as the estimated error; with ``accuracy`` the step is halved until that
estimate is within it.

Section: where the map is smooth in the state, chosen from the guess's cycle: the middle of the
longest stretch in which every rigid contact slides (a stuck contact's velocity is held at its
belt's, the map not smooth in it) and every Jenkins slider is stuck (the map's start holds each
slider stuck: a sliding one would wait for its static limit), else of the longest stretch with the
sliders stuck, else t = 0 with each slider started in its mode there (``slide0``: a sliding slider
where its kinetic force puts it). The state at t = 0 mod K T (``x0``, ``v0``, ``s0``) is read from a
run of the converged orbit.

With a cyclic symmetry (:class:`~dryfriction.system.symmetry.CyclicSymmetry`, N sectors: ``x_{dofs[i]}(t
+ T / N) = x_i(t)``) the map is the sector map G: one run of T / N from t_s, its end state relabelled
(state i the end's ``dofs[i]``; the sliders and their modes by ``contacts``), so that a fixed point
solves z(T / N) = P z(0), an orbit of the full structure; the period's map is G^N (the N sector runs
are relabelled copies of one another), so the multipliers are G's to the power N; the observables
of the run are combined over the relabelling (a DOF's extremes over the DOFs whose motion it takes, a
contact's stuck share their mean); the section lies in [0, T / N); the residual is N times G's (about
the period's map's: ``tol`` means the same distance to the orbit).
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from ..errors import FMUCallError
from .shooting import STABILITY_MARGIN, OrbitRecord, classify, multipliers, newton

if TYPE_CHECKING:
    from ..drivers.system import SystemFMU3
    from ..system.structure import System as Structure  # (the annotations' name: the API reference links it)
    from ..system.symmetry import CyclicSymmetry

__all__ = ["SystemOrbit", "find_system_orbits", "system_map", "stuck_start", "stiffest_rate", "STABILITY_MARGIN", "NEUTRAL"]

#: a multiplier this close to 1 is a neutral one (a continuum of orbits: a stuck slider's rest positions,
#: a free rigid-body mode held only by friction)
NEUTRAL = 1e-6
#: samples per excitation period of the guess's cycle (the section's choice)
SAMPLES = 256
#: a warm section whose stretch moved: the samples (at SAMPLES a period) either side of it searched
#: for the stretch before the whole cycle is sampled
WINDOW = 16
#: scaled distance under which two converged orbits are the same
SAME = 1e-6
#: step halvings at most in search of ``accuracy``
MAX_HALVINGS = 10
#: with ``accuracy`` and the FMU's derived step: the orbits start at 1/COARSE_STEPS of the period
COARSE_STEPS = 32
#: a run with the Jacobian costing more than this many runs without: the line search's trials without it
EXPENSIVE = 4.0
#: a contact's stuck force amplitude within this share of its limit: the stuck start is taken
STUCK_MARGIN = 1e-6
#: the error estimate's chord steps (the coarser orbit's Jacobian): at most CHORD_STEPS, each cutting
#: the residual to CHORD_RATE of the last at least
CHORD_STEPS, CHORD_RATE = 8, 0.25
#: a Newton solve that fails where the stiffest mode (the contacts stuck) has fewer than this many steps
#: a period says so in its reason: a smaller h may converge (the located map steps such a mode stably
#: but coarsely, and the ringing it leaves at every switch can make the map rough at Newton's scale)
RESOLVED_STEPS = 4.0
#: Newton steps at most after the residual is within tol, while the step (the distance left) is not
POLISH = 2
#: a map of this many unknowns or more: its Jacobian taken as costly until both kinds of run are timed
LAZY_SIZE = 32


@dataclass
class SystemOrbit(OrbitRecord):
    """One periodic orbit of K excitation periods (``period``) of a structure, its state at
    t = 0 mod K T. Read as ``orbit.x0`` or ``orbit["x0"]``; ``orbit.mu_max`` the largest |multiplier|."""

    period: int
    x0: np.ndarray                   # n positions at t = 0 mod K T, m
    v0: np.ndarray                   # n velocities, m/s
    s0: np.ndarray                   # nc sliders (NaN for a rigid contact), m
    slide0: np.ndarray               # nc: each Jenkins slider's mode at t = 0 (0 stuck, -1 / +1 sliding; the
    #                                  FMU's slide0 that starts the orbit); 0 for a rigid contact
    multipliers: np.ndarray          # eigenvalues of the K-period map's Jacobian (|mu| descending; with a
    #                                  symmetry the sector map's to the power ``sectors``: the same numbers)
    stable: bool                     # every |mu| < 1 - STABILITY_MARGIN (a neutral orbit's multipliers 1 aside)
    residual: float                  # the scaled Newton residual at the section
    amplitude: np.ndarray            # n: (x_max - x_min) / 2 over the cycle (the FMU's observables), m
    offset: np.ndarray               # n: (x_max + x_min) / 2, m
    stick_fraction: np.ndarray       # nc: each contact's stuck share of the cycle
    converged: bool
    reason: str = ""                 # why not converged ("" when converged)
    h: float = float("nan")          # the internal step of the orbit, s
    error: float = float("nan")      # the amplitude's estimated error (max over DOFs), m (NaN: not estimated)
    amplitude_extrapolated: np.ndarray = field(default_factory=lambda: np.zeros(0))  # Richardson's, n
    section: float = 0.0             # the section time t_s in [0, K T / sectors) of the Newton solve, s
    section_state: np.ndarray = field(default_factory=lambda: np.zeros(0))  # z = (x, v, s_jenkins) there
    section_slide: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))  # nc: each Jenkins
    #                                  slider's mode at the section (the map's slide0 there), 0 for a rigid contact
    jacobian: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # of the map Newton solved at the
    #                                  section: P^K, or with a symmetry the sector map (module doc)
    iterations: int = 0
    # the error estimate's first halving at the section: z(h / 2) - z(h) (empty without the estimate)
    section_shift: np.ndarray = field(default_factory=lambda: np.zeros(0))
    neutral: bool = False            # a multiplier 1: a continuum of orbits (a Jenkins slider stuck all
    #                                  cycle rests anywhere within its limits; a free mode held by friction)
    sectors: int = 1                 # the cyclic symmetry's sectors the orbit was solved with (1: none)


class _Map:
    """The stroboscopic map of one structure at one step h through one FMU instance: z = (x, v,
    s_jenkins) at t_s -> z at t_s + K T, its Jacobian and the cycle's observables."""

    def __init__(self, fmu: "SystemFMU3", system: "Structure", K: int,
                 symmetry: "CyclicSymmetry | None" = None) -> None:
        self.fmu = fmu
        self.system = system
        self.K = K
        self.n = system.n
        self.jenk = np.flatnonzero(system.k_t > 0.0)
        self.KT = K * 2.0 * np.pi / system.omega
        # with a cyclic symmetry the map is one sector's share of the period, its end relabelled
        # (module doc): span the run's length, perm the unknowns' and cperm the contacts' relabelling
        self.symmetry = symmetry
        self.span = self.KT / symmetry.sectors if symmetry is not None else self.KT
        if symmetry is not None:
            pos = np.full(system.nc, -1)
            pos[self.jenk] = np.arange(self.jenk.size)
            n = self.n
            self.perm = np.concatenate([symmetry.dofs, n + symmetry.dofs, 2 * n + pos[symmetry.contacts[self.jenk]]])
            self.cperm = symmetry.contacts
            self._dof_orbits = symmetry.orbits(symmetry.dofs)
            self._contact_orbits = symmetry.orbits(symmetry.contacts)
        self.evaluations = 0
        # CPU seconds and counts of the runs with and without the Jacobian (expensive_jacobian)
        self._cost = {True: [0.0, 0], False: [0.0, 0]}
        self.slide = np.zeros(system.nc, dtype=int)  # each Jenkins slider's mode at the section (0: stuck)
        # the Jenkins contacts' rows, stiffnesses, limits and kinetic forces (read once: a System's
        # per-contact arrays are built at each access)
        j = self.jenk
        self._Wj, self._kt = system.W[j], system.k_t[j]
        self._lim = np.maximum(system.mu_s, system.mu_k)[j] * system.N[j]
        self._fk = system.mu_k[j] * system.N[j]

    @property
    def size(self) -> int:
        return 2 * self.n + self.jenk.size

    def expensive_jacobian(self) -> bool:
        """Whether a run with the Jacobian has cost more than EXPENSIVE times one without (both
        measured, per period): on a large structure the tangent's columns outweigh the run (the
        bladed disk's 216 columns: some 50 runs' worth); before both are timed, whether the map has
        LAZY_SIZE unknowns or more."""
        (tj, nj), (tp, np_) = self._cost[True], self._cost[False]
        if not (nj and np_):  # (not both timed yet: by the size)
            return self.size >= LAZY_SIZE
        return bool(tj / nj > EXPENSIVE * (tp / np_))

    def f0(self, z: np.ndarray) -> np.ndarray:
        """The Jenkins springs' forces of z (0 for the rigid contacts), clamped to their limits."""
        f = np.zeros(self.system.nc)
        if self.jenk.size:
            g = self._Wj @ z[:self.n]
            f[self.jenk] = np.clip(-self._kt * (g - z[2 * self.n:]), -self._lim, self._lim)
        return f

    def project(self, z: np.ndarray) -> np.ndarray:
        """z with each stuck slider within its limit, each sliding one where its kinetic force puts it."""
        if not self.jenk.size:
            return z
        out = z.copy()
        g = self._Wj @ z[:self.n]
        m = self.slide[self.jenk]
        out[2 * self.n:] = np.where(m != 0, g - m * self._fk / self._kt, g + self.f0(z)[self.jenk] / self._kt)
        return out

    def __call__(self, z: np.ndarray, t_s: float, jacobian: bool = True, span: float | None = None,
                 wrap: bool | None = None) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
        """P(z) from t_s over ``span`` (default the map's: K T, or one sector's share of it with a
        symmetry), its Jacobian (NaN when not asked) and the observables of that stretch (x_max,
        x_min, stick_fraction; with a symmetry, of the whole cycle: each DOF's extremes over the DOFs
        whose motion it takes, each contact's stuck share their mean; each contact's mode changes, the
        FMU's transitions, are read where wanted, after the run: SystemFMU3.transitions). ``wrap``
        (default: the map's own span): the end state, its Jacobian's rows and the contacts' modes
        relabelled by the symmetry (the state a sector earlier, a run that ends on a sector's end)."""
        n = self.n
        f = self.fmu
        if wrap is None:
            wrap = span is None
        span = self.span if span is None else span
        c0 = time.process_time()
        f.start(t_s, observe=True, t_obs_start=t_s, t_obs_stop=t_s + span, sensitivity=jacobian,
                x0=z[:n], v0=z[n:2 * n], f0=self.f0(z), slide0=self.slide)
        f.do_step(span)
        cost = self._cost[bool(jacobian)]
        cost[0] += (time.process_time() - c0) * self.KT / span
        cost[1] += 1
        self.evaluations += 1
        out = f.outputs()
        self.last_mode = np.asarray(out["mode"], dtype=int)
        Pz = np.concatenate([out["x"], out["v"], out["s"][self.jenk]])
        J = np.full((self.size, self.size), np.nan)
        if jacobian:
            full = f.jacobian()
            keep = np.concatenate([np.arange(2 * n), 2 * n + self.jenk])
            J = full[np.ix_(keep, keep)]
        x_max, x_min, share = f.observables()
        if self.symmetry is not None:
            if wrap:
                Pz, self.last_mode = Pz[self.perm], self.last_mode[self.cperm]
                J = J[self.perm]
            if span == self.span:  # (the sector's stretch: the cycle's by the symmetry)
                x_max = np.max(np.asarray(x_max)[self._dof_orbits], axis=0)
                x_min = np.min(np.asarray(x_min)[self._dof_orbits], axis=0)
                share = np.mean(np.asarray(share)[self._contact_orbits], axis=0)
        return Pz, J, {"x_max": x_max, "x_min": x_min, "stick_fraction": share}

    def transient(self, z: np.ndarray, periods: int) -> np.ndarray:
        """The state ``periods`` K-periods after z at t = 0 (sliders in M.slide's modes, projected
        onto their limits): one run, without the Jacobian."""
        if periods <= 0:
            return z
        Pz, _, _ = self(self.project(z), 0.0, jacobian=False, span=periods * self.KT)
        return Pz

    def cycle(self, z: np.ndarray, t_s: float, samples: int = SAMPLES) -> tuple[np.ndarray, np.ndarray]:
        """The modes over the map's span (K T; with a symmetry one sector's share of it) from z at
        t_s, sampled ``samples`` times per period (at least as many per span): (t, mode [nt, nc])."""
        n = self.n
        f = self.fmu
        f.start(t_s, observe=False, x0=z[:n], v0=z[n:2 * n], f0=self.f0(z), slide0=self.slide)
        t = t_s + np.linspace(0.0, self.span, self.K * samples + 1)
        return t, f.modes_at(t)


def _scales(system: "Structure", x_max: np.ndarray, x_min: np.ndarray, jenk: np.ndarray) -> np.ndarray:
    """Each unknown's scale: a DOF's motion (its half range in the cycle, at least 1e-9 of the largest
    one and of the structure's static deflection), its velocity that times omega, a slider's its DOFs'."""
    amp = 0.5 * np.abs(np.asarray(x_max) - np.asarray(x_min))
    amp = np.where(np.isfinite(amp), amp, 0.0)
    force = float(np.max(np.abs(np.concatenate([system.F_c, system.F_s])))) if system.n else 0.0
    kmax = float(np.max(np.abs(np.diag(system.K)))) if system.n else 0.0
    static = force / kmax if kmax > 0 else 0.0
    floor = max(1e-9 * float(np.max(amp, initial=0.0)), 1e-9 * static, 1e-300)
    xs = np.maximum(amp, floor)
    w = max(system.omega, 1e-300)
    ss = np.array([float(np.max(np.abs(system.W[j]) * xs)) for j in jenk]) if jenk.size else np.zeros(0)
    return np.concatenate([xs, w * xs, np.maximum(ss, floor)])


def _longest(good: np.ndarray) -> tuple[int, int] | None:
    """The first and last index of the longest run of True in ``good`` (None: none)."""
    best, start, run = 0, -1, None
    for k in range(good.size + 1):
        on = k < good.size and bool(good[k])
        if on and start < 0:
            start = k
        elif not on and start >= 0:
            if k - start > best:
                best, run = k - start, (start, k - 1)
            start = -1
    return run


def _section(M: _Map, z: np.ndarray) -> float:  # noqa: C901 (the rule's cases, in order)
    """The section time (module doc): where the map is smooth in the state, from the modes of the
    guess's cycle: every rigid contact with friction sliding (a stuck one's velocity is not a smooth
    variable of the map) and every Jenkins slider stuck (the map's start holds each slider stuck);
    the middle of the longest such stretch, or of the longest stretch with the sliders stuck, else
    t = 0 with each slider started in its mode there (M.slide: sliding sliders start sliding)."""
    sysm = M.system
    M.slide[:] = 0
    live = sysm.N * np.maximum(sysm.mu_s, sysm.mu_k) > 0.0
    if not live.any():
        return 0.0
    t, mode = M.cycle(z, 0.0)
    jenk = [j for j in M.jenk if live[j]]
    rigid = [j for j in range(sysm.nc) if live[j] and not sysm.k_t[j] > 0.0]
    sliders_stuck = np.all(mode[:, jenk] == 0, axis=1) if jenk else np.ones(t.size, dtype=bool)
    rigid_slide = np.all(mode[:, rigid] != 0, axis=1) if rigid else np.ones(t.size, dtype=bool)
    for good in (sliders_stuck & rigid_slide, sliders_stuck):
        if good[0] and good[-1] and good.all():
            return 0.0
        run = _longest(good[:-1])  # (the last sample is the first one a cycle later)
        if run is not None and run[1] - run[0] >= 2:
            return float(0.5 * (t[run[0]] + t[run[1]]) % M.span)
    # some slider slides at every time (e.g. a travelling wave over many contacts): the map starts
    # where no contact's mode changes for longest (the middle of the longest stretch of constant
    # modes, rigid contacts sliding where such a stretch exists), each slider in its mode there
    same = np.all(mode[1:, live] == mode[:-1, live], axis=1)       # sample k to k + 1 without a change
    k = 0
    for good in (same & rigid_slide[:-1] & rigid_slide[1:], same):
        run = _longest(good)
        if run is not None:
            k = (run[0] + run[1] + 1) // 2
            break
    for j in jenk:
        M.slide[j] = int(mode[k, j])
    return float(t[k] % M.span)


class _Shooting:
    """A structure's :class:`~dryfriction.analysis.shooting.ShootingMap`: its map M with the Jacobian,
    the residual in the scales S, the minimum-norm Newton step in the scaled unknowns (a multiplier 1,
    a continuum of orbits: a stuck slider's rest positions, a free mode held by friction, leaves J - I
    singular, and the step then moves along none of its null directions), each iterate projected onto
    the sliders' limits (:meth:`_Map.project`); no bound on the iterates."""

    #: a trial state the FMU refuses: a shorter step
    refused: tuple[type[BaseException], ...] = (FMUCallError,)

    def __init__(self, M: _Map, S: np.ndarray) -> None:
        self.M, self.S = M, S

    def evaluate(self, z: np.ndarray, t_s: float, final: bool,
                 jacobian: bool = True) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
        """(P(z), its Jacobian (NaN without ``jacobian``), the observables of the run)."""
        return self.M(z, t_s, jacobian=jacobian)

    def expensive_jacobian(self) -> bool:
        """The map's measured costs (:meth:`_Map.expensive_jacobian`)."""
        return self.M.expensive_jacobian()

    def residual(self, z: np.ndarray, Pz: np.ndarray) -> float:
        """``|S^-1 r|_inf / max(1, |S^-1 z|_inf)`` (module doc); with a symmetry of N sectors N times
        the sector map's: about the period's map's residual at the same state (near the orbit the
        period's map is G^N, and along its slow directions, multipliers near 1, each of the N sector
        maps adds the same), so that ``tol`` bounds the distance to the orbit as without the
        symmetry (the sector map's residual alone would allow N times that distance)."""
        S = self.S
        N = self.M.symmetry.sectors if self.M.symmetry is not None else 1
        return N * float(np.max(np.abs((Pz - z) / S)) / max(1.0, float(np.max(np.abs(z / S)))))

    def step(self, z: np.ndarray, Pz: np.ndarray, J: np.ndarray) -> tuple[np.ndarray | None, str]:
        """The minimum-norm Newton step in the scaled unknowns."""
        if not (np.all(np.isfinite(J)) and np.all(np.isfinite(Pz))):
            return None, "the map's Jacobian was not computed (a switch it could not follow)"
        S = self.S
        A = (J - np.eye(J.shape[0])) * S[None, :] / S[:, None]
        return S * np.linalg.lstsq(A, -(Pz - z) / S, rcond=1e-10)[0], ""

    def move(self, z: np.ndarray, dz: np.ndarray, lam: float) -> np.ndarray:
        """z + lam dz within the sliders' limits."""
        return self.M.project(z + lam * dz)

    def step_size(self, z: np.ndarray, dz: np.ndarray) -> float:
        """The scaled step relative to the scaled state (at least 1)."""
        S = self.S
        return float(np.max(np.abs(dz / S)) / max(1.0, float(np.max(np.abs(z / S)))))

    def outside(self, z: np.ndarray, first: bool) -> str:
        """No bound on a structure's iterates."""
        return ""


def _newton(M: _Map, z: np.ndarray, t_s: float, S: np.ndarray | None, tol: float,
            max_iter: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, int, str, dict[str, np.ndarray],
                                    np.ndarray]:
    """Newton on P(z) - z from z at t_s (:func:`~dryfriction.analysis.shooting.newton`, 12 halvings of a
    step, any decrease accepted): (z, P(z), J, scaled residual, iterations, reason, observables, the
    scales S: given, or those of the first evaluation's cycle)."""
    z = M.project(z)
    first = M(z, t_s)
    if S is None:
        S = _scales(M.system, first[2]["x_max"], first[2]["x_min"], M.jenk)
    # (POLISH steps: with a multiplier near 1 a residual within tol leaves a distance of about
    # tol / (1 - mu) to the orbit, the Newton step's size; stepped on while that is above tol)
    n = newton(_Shooting(M, S), z, t_s, tol, max_iter, halvings=12, armijo=0.0, first=first, polish=POLISH)
    reason = n.reason
    if not reason and not (np.all(np.isfinite(n.J)) and np.all(np.isfinite(n.Pz))):
        reason = "the map's Jacobian was not computed (a switch it could not follow)"
    if reason:
        reason += _coarse_hint(M.system)
    return n.z, n.Pz, n.J, n.residual, n.iterations, reason, n.aux, S


def stiffest_rate(system: "Structure") -> float:
    """The structure's fastest natural rate with every Jenkins element stuck (rad/s): the square root
    of the largest eigenvalue of (K + sum_j k_t,j w_j w_j', M), the stiffness the FMU's derived step
    resolves (its ``h`` parameter's rule, without the damping and omega terms)."""
    from scipy.linalg import eigh

    if system.n == 0:
        return 0.0
    Kt = np.array(system.K, dtype=float)
    for j in np.flatnonzero(system.k_t > 0.0):
        Kt += system.k_t[j] * np.outer(system.W[j], system.W[j])
    lam = eigh(Kt, system.M, eigvals_only=True, subset_by_index=[system.n - 1, system.n - 1])
    return float(np.sqrt(max(float(lam[-1]), 0.0)))


def _coarse_hint(system: "Structure") -> str:
    """What a failed solve's reason adds where the step resolves the stiffest mode by fewer than
    RESOLVED_STEPS steps a period ("" otherwise)."""
    h = float(system.h)
    rate = stiffest_rate(system) if h > 0 else 0.0
    if not (rate > 0.0) or 2.0 * np.pi / (rate * h) >= RESOLVED_STEPS:
        return ""
    return (f"; the stiffest mode ({rate:.4g} rad/s, the contacts stuck) has {2.0 * np.pi / (rate * h):.2g} steps a "
            f"period at h = {h:.6g}: the map may be rough at Newton's scale there, a smaller h (at least "
            f"{RESOLVED_STEPS:g} steps a period of that mode, h <= {2.0 * np.pi / (RESOLVED_STEPS * rate):.3g}) may "
            "converge")


def _make_orbit(M: _Map, z: np.ndarray, Pz: np.ndarray, J: np.ndarray, r: float, it: int, reason: str,
                obs: dict[str, np.ndarray], t_s: float, h: float, at_zero: bool = True) -> SystemOrbit:
    """The orbit of the converged z at t_s: its multipliers, observables and, ``at_zero``, its state at
    t = 0 mod K T (:func:`_read_zero`; else NaN until read)."""
    n, sysm = M.n, M.system
    slide_s = np.zeros(sysm.nc, dtype=int)
    slide_s[M.jenk] = M.slide[M.jenk]
    mult = multipliers(J)
    if M.symmetry is not None:  # (the period's map is the sector map's sectors-th power at the orbit)
        mult = mult ** M.symmetry.sectors
    x_max, x_min = np.asarray(obs["x_max"]), np.asarray(obs["x_min"])
    ok = not reason
    one, inside = classify(mult, NEUTRAL)
    nan_n = np.full(n, np.nan)
    orbit = SystemOrbit(period=M.K, x0=nan_n, v0=nan_n.copy(), s0=np.full(sysm.nc, np.nan),
                        slide0=slide_s.copy(), multipliers=mult, stable=ok and inside, residual=r,
                        neutral=ok and one, amplitude=0.5 * (x_max - x_min), offset=0.5 * (x_max + x_min),
                        stick_fraction=np.asarray(obs["stick_fraction"]), converged=ok, reason=reason, h=h,
                        section=t_s, section_state=z.copy(), section_slide=slide_s, jacobian=J, iterations=it,
                        sectors=1 if M.symmetry is None else M.symmetry.sectors)
    if at_zero:
        _read_zero(M, orbit)
    return orbit


def _read_zero(M: _Map, orbit: SystemOrbit) -> None:
    """The orbit's state at t = 0 mod K T (x0, v0, s0, slide0) in place: its section state run to the
    next multiple of K T (M the orbit's map, the FMU on M's system)."""
    n, t_s, z0 = M.n, orbit.section, orbit.section_state
    slide0 = orbit.section_slide.copy()
    if t_s != 0.0:
        slide = M.slide.copy()
        M.slide[:] = orbit.section_slide
        z0, _, _ = M(z0, t_s, jacobian=False, span=M.span - t_s, wrap=True)
        M.slide[:] = slide
        slide0[M.jenk] = M.last_mode[M.jenk]
    orbit.x0, orbit.v0 = z0[:n].copy(), z0[n:2 * n].copy()
    orbit.s0 = np.full(M.system.nc, np.nan)
    orbit.s0[M.jenk] = z0[2 * n:]
    orbit.slide0 = slide0


def _h_of(fmu: "SystemFMU3", system: "Structure", accuracy: float | None = None) -> float:
    """The internal step of the orbits: the system's h; else the FMU's derived one (1/1000 of the
    fastest period), or with ``accuracy`` a coarse start that the error estimate refines: the least
    of 1/32 of the excitation period and 1/RESOLVED_STEPS of the fastest period (a coarser step
    steps that mode stably but may leave the map rough at Newton's scale: _coarse_hint)."""
    if system.h > 0:
        return float(system.h)
    fmu.system = system
    fmu.start(0.0, observe=False)
    h = float(fmu.inst.get("Float64", [fmu.vars["h_used"].vr])[0])
    if accuracy is None:
        return h
    return min(2.0 * np.pi / system.omega / COARSE_STEPS, 1000.0 * h / RESOLVED_STEPS)


def system_map(system: "Structure", z: Sequence[float], period: int = 1, t_s: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """P^K(z) and its Jacobian for ``system`` (located scheme): z = (x, v, the Jenkins sliders) at
    t_s, the map over ``period`` excitation periods (one FMU run; the Jacobian the FMU's)."""
    from ..drivers.system import SystemFMU3

    with SystemFMU3(system) as fmu:
        M = _Map(fmu, system, int(period))
        z = np.asarray(z, dtype=float)
        if z.shape != (M.size,):
            raise ValueError(f"z needs 2 n + (Jenkins contacts) = {M.size} values, not {z.size}")
        Pz, J, _ = M(z, float(t_s))
    return Pz, J


def find_system_orbits(system: "Structure", period: int = 1, guesses: Iterable[Sequence[float]] | None = None, *,
                       transients: int = 40, tol: float = 1e-8, max_iter: int = 30,
                       accuracy: float | None = None, estimate_error: bool = True,
                       keep_failed: bool = False, fmu: "SystemFMU3 | None" = None,
                       symmetry: "CyclicSymmetry | None" = None) -> list[SystemOrbit]:
    """The periodic orbits of ``period`` (K) excitation periods of ``system`` (scheme located, the
    Coulomb law) found by Newton shooting on the located map with the FMU's Jacobian (module doc),
    from:

    - the linear steady response with every contact stuck, where no contact's force reaches its
      limit in it (:func:`stuck_start`: then an orbit),
    - the end state of a transient of ``transients`` K-periods from the system's x0, v0 (the
      attractor it reaches),
    - ``guesses``: states z = (x, v, the Jenkins contacts' sliders) at t = 0 mod K T.

    ``tol``: the scaled Newton residual (default 1e-8: far below the scheme's own error at the
    default h, and above the map's rounding through many switches, measured up to 6e-10). The
    error against the time step: with ``estimate_error``
    (default) each orbit is solved again at h / 2, its ``amplitude`` is the h / 2 one, ``error`` the
    estimate |A(h / 2) - A(h)| / 3 (max over DOFs) and ``amplitude_extrapolated`` Richardson's;
    ``accuracy`` (m) starts from a coarse h where the system's is derived (1/32 of the period, or
    a quarter of the fastest one) and halves it until ``error`` is within it (at most 10 halvings; an orbit
    that does not get there says so in ``reason``). Orbits that did not converge are dropped unless
    ``keep_failed``. Stable orbits first, then by the largest amplitude. ``fmu``: an open
    :class:`~dryfriction.drivers.system.SystemFMU3` of a structure of the same sizes to run the map
    on (loading the FMU costs more than a map run of a small structure), else one is opened and
    closed. ``symmetry``: a :class:`~dryfriction.system.symmetry.CyclicSymmetry` of the structure and
    its excitation (checked; ``period`` 1): the orbits that share it, by Newton on one sector's share
    of the period (module doc), ``sectors`` times fewer steps a run and a Jacobian; an orbit that breaks
    the symmetry is not found this way.
    """
    from ..drivers.system import SystemFMU3
    from ..system.structure import System

    if not isinstance(system, System):
        raise TypeError(f"find_system_orbits needs a dryfriction.System, not {type(system).__name__}")
    K = int(period)
    if K < 1:
        raise ValueError(f"period must be an integer >= 1, not {period!r}")
    if not (system.omega > 0):
        raise ValueError(f"orbits need an excitation frequency omega > 0, not {system.omega!r}")
    if system.scheme != "located":
        raise ValueError(f"orbits use the located scheme's map, and the system's scheme is {system.scheme!r}: "
                         "System.replace(scheme='located')")
    if np.any(np.asarray(system.friction_law) != 1):
        raise ValueError("orbits need the Coulomb law on every contact (the map's Jacobian is not propagated with "
                         "the Stribeck law)")
    if not (tol > 0):
        raise ValueError(f"tol must be > 0, not {tol!r}")
    if accuracy is not None and not (accuracy > 0):
        raise ValueError(f"accuracy must be > 0, not {accuracy!r}")
    _check_symmetry(system, symmetry, K)
    orbits: list[SystemOrbit] = []
    if fmu is not None and not isinstance(fmu, SystemFMU3):
        raise TypeError(f"fmu must be an open SystemFMU3 for a structure, not {type(fmu).__name__}")
    if fmu is not None and (fmu.n, fmu.nc) != (system.n, system.nc):
        raise ValueError(f"the fmu runs a structure of n = {fmu.n}, nc = {fmu.nc}, not n = {system.n}, nc = {system.nc}")
    with (SystemFMU3(system) if fmu is None else contextlib.nullcontext(fmu)) as fmu:
        h0 = _h_of(fmu, system, accuracy)
        sysh = system.replace(h=h0)
        fmu.system = sysh
        M = _Map(fmu, sysh, K, symmetry)
        starts: list[np.ndarray] = []
        stuck = stuck_start(sysh)
        if stuck is not None:  # (an orbit with every contact stuck: one Newton step)
            starts.append(stuck)
        if transients > 0:
            starts.append(M.transient(np.concatenate([system.x0, system.v0, system.W[M.jenk] @ system.x0]),
                                      transients))
        for g in guesses or ():
            g = np.asarray(g, dtype=float)
            if g.shape != (M.size,):
                raise ValueError(f"a guess needs 2 n + (Jenkins contacts) = {M.size} values (x, v, sliders), "
                                 f"not {g.size}")
            starts.append(g)
        for z in starts:
            orbit = _solve(M, fmu, z, tol, max_iter, h0, estimate_error, accuracy)
            if not orbit.converged and not keep_failed:
                continue
            if any(_same(orbit, o) for o in orbits):
                continue
            orbits.append(orbit)
    orbits.sort(key=lambda o: (not o.stable, -float(np.max(o.amplitude, initial=0.0))))
    return orbits


def _check_symmetry(system: "Structure", symmetry: "CyclicSymmetry | None", K: int) -> None:
    """Raise where ``symmetry`` is not a CyclicSymmetry of the structure (its check's error) or K > 1."""
    if symmetry is None:
        return
    from ..system.symmetry import CyclicSymmetry

    if not isinstance(symmetry, CyclicSymmetry):
        raise TypeError(f"symmetry must be a dryfriction.system.CyclicSymmetry, not {type(symmetry).__name__}")
    if K != 1:
        raise ValueError(f"a cyclic symmetry finds orbits of one period (its shift is a share of T), not period = {K}")
    symmetry.check(system)


def stuck_start(system: "Structure") -> np.ndarray | None:
    """The steady response with every contact that has friction held (rigid contacts fixed at their
    start, Jenkins sliders at rest with their springs relaxed on average), as a state z = (x, v,
    sliders) at t = 0: the linear closed form of (K + sum k_t w w' - omega^2 M + i omega C) X = F
    with the rigid contacts' constraints. When every contact's force stays within its breakaway
    limit over the cycle (its amplitude below max(mu_s, mu_k) N, by STUCK_MARGIN), this is a periodic
    orbit of the structure (of the located map to the scheme's O(h^2)): Newton converges from it in
    one step. None where some contact would slip or the system is singular at omega."""
    sysm = system
    n, om = sysm.n, float(sysm.omega)
    lim = np.maximum(sysm.mu_s, sysm.mu_k) * sysm.N
    W, kt = sysm.W, sysm.k_t
    live = lim > 0.0
    jenk = np.flatnonzero(kt > 0.0)
    held_j = jenk[live[jenk]]
    rigid = np.flatnonzero(live & ~(kt > 0.0))
    D = sysm.K - om * om * sysm.M + 1j * om * sysm.C
    if held_j.size:
        D = D + (W[held_j].T * kt[held_j]) @ W[held_j]
    m = rigid.size
    A = np.zeros((n + m, n + m), dtype=complex)
    A[:n, :n] = D
    A[:n, n:] = -W[rigid].T
    A[n:, :n] = W[rigid]
    rhs = np.concatenate([sysm.F_c - 1j * sysm.F_s, np.zeros(m)])
    try:
        sol = np.linalg.solve(A, rhs)
    except np.linalg.LinAlgError:
        return None
    if not np.all(np.isfinite(sol)):
        return None
    X = sol[:n]
    force = np.zeros(sysm.nc, dtype=complex)
    force[held_j] = -kt[held_j] * (W[held_j] @ X)
    force[rigid] = sol[n:]
    if np.any(np.abs(force[live]) >= (1.0 - STUCK_MARGIN) * lim[live]):
        return None
    sliders = np.zeros(jenk.size)  # (a slider without friction: its spring relaxed, as the map's start)
    free = ~live[jenk]
    sliders[free] = (W[jenk[free]] @ X).real
    return np.concatenate([X.real, -om * X.imag, sliders])


def _same(a: SystemOrbit, b: SystemOrbit) -> bool:
    """Whether two orbits are one: the same state at t = 0 and amplitudes, or both stuck all cycle
    with the same amplitudes (one continuum of rest positions, told apart only by where the contacts
    rest)."""
    if not (a.converged and b.converged) or a.period != b.period:
        return False
    scale = max(float(np.max(np.abs(a.amplitude), initial=0.0)), 1e-300)
    if not np.max(np.abs(a.amplitude - b.amplitude)) <= SAME * scale:
        return False
    if np.all(a.stick_fraction >= 1.0) and np.all(b.stick_fraction >= 1.0):
        return True
    return bool(np.max(np.abs(a.x0 - b.x0)) <= SAME * scale)


def _warm_section(M: _Map, z: np.ndarray, phase: float, slide: np.ndarray | None = None,
                  slide0: np.ndarray | None = None) -> tuple[float, np.ndarray] | None:
    """The section at ``phase`` (a fraction of M's period: a neighbouring orbit's section, whose
    sliders had the modes ``slide`` there: default all stuck) when the modes there are still that
    section's (each live Jenkins slider in its mode, every rigid contact sliding), and the state z
    (at t = 0, its sliders in the modes ``slide0``: default stuck) carried to it, M.slide set to
    those modes. Where they differ, the stretch of such modes has moved
    along the cycle with the parameters: the middle of the longest one within WINDOW samples either
    side (sampled as :func:`_section` does, from z at t = 0), and z carried there. None when the
    phase is 0 or no such stretch is near: then :func:`_section` samples the whole cycle. One run to
    the section (without the Jacobian) instead of the guess's sampled cycle: it carries the
    neighbour's state under this structure's forces, a better start than the neighbour's own state
    at the section where a Newton step (with the Jacobian) costs several runs."""
    t_s = phase * M.KT
    if not (0.0 < t_s < M.span):
        return None
    sysm = M.system
    live = sysm.N * np.maximum(sysm.mu_s, sysm.mu_k) > 0.0
    jenk = sysm.k_t > 0.0
    want = np.zeros(sysm.nc, dtype=int) if slide is None or np.size(slide) != sysm.nc else np.asarray(slide, dtype=int)
    start = np.zeros(sysm.nc, dtype=int)
    if slide0 is not None and np.size(slide0) == sysm.nc:
        start[jenk] = np.asarray(slide0, dtype=int)[jenk]

    def good(mode: np.ndarray) -> np.ndarray:
        """The samples (rows of modes) with the section's modes."""
        return (np.all(mode[..., live & jenk] == want[live & jenk], axis=-1)
                & np.all(mode[..., live & ~jenk] != 0, axis=-1))

    M.slide[:] = start
    z = M.project(z)
    try:
        zs, _, _ = M(z, 0.0, jacobian=False, span=t_s)
        if not good(M.last_mode):
            dt = M.span / (M.K * SAMPLES)
            t = t_s + dt * np.arange(-WINDOW, WINDOW + 1)
            t = t[(t > 0.0) & (t < M.span)]
            f = M.fmu
            f.start(0.0, observe=False, x0=z[:M.n], v0=z[M.n:2 * M.n], f0=M.f0(z), slide0=M.slide)
            run = _longest(good(f.modes_at(np.concatenate([[0.0], t]))[1:]))
            if run is None or run[1] - run[0] < 2:
                return None
            t_s = float(0.5 * (t[run[0]] + t[run[1]]))
            zs, _, _ = M(z, 0.0, jacobian=False, span=t_s)
    except FMUCallError:
        return None
    M.slide[jenk] = want[jenk]
    return t_s, zs


def _solve(M: _Map, fmu: "SystemFMU3", z: np.ndarray, tol: float, max_iter: int, h0: float, estimate_error: bool,
           accuracy: float | None, phase: float | None = None, slide: np.ndarray | None = None,
           shift: np.ndarray | None = None, slide0: np.ndarray | None = None, at_section: bool = False) -> SystemOrbit:
    """The orbit from z (at t = 0) at h0, then at h0 / 2, h0 / 4 ... as the error estimate asks
    (module doc); ``phase``: a neighbouring orbit's section (a fraction of the period; ``slide`` its
    sliders' modes there), tried first (:func:`_warm_section`); where it is kept, ``shift`` (that
    orbit's section_shift) starts the orbit at h0 / 2 from this one's at h0 plus the neighbour's
    difference. ``at_section``: z is the state at that section already (sliders in the modes
    ``slide``), Newton starts there."""
    warm: tuple[float, np.ndarray] | None
    if at_section and phase is not None and slide is not None:
        M.slide[:] = 0
        M.slide[M.jenk] = np.asarray(slide, dtype=int)[M.jenk]
        warm = (phase * M.KT, M.project(z))
    else:
        warm = _warm_section(M, z, phase, slide, slide0) if phase is not None else None
    if warm is not None:
        t_s, z = warm
    else:
        try:
            t_s = _section(M, z)
        except ValueError as e:
            return _failed(M, z, str(e), h0)
        if t_s != 0.0:  # the guess's state at the section (from t = 0 with its sliders started stuck, as the guess's cycle)
            slide, M.slide[:] = M.slide.copy(), 0
            z, _, _ = M(M.project(z), 0.0, jacobian=False, span=t_s)
            M.slide[:] = slide
    z, Pz, J, r, it, reason, obs, S = _newton(M, z, t_s, None, tol, max_iter)
    refine = estimate_error or accuracy is not None
    # (the state at t = 0 read of the orbit returned only: the finest one where h is halved)
    orbit = _make_orbit(M, z, Pz, J, r, it, reason, obs, t_s, h0, at_zero=not refine)
    if not orbit.converged or not refine:
        if not orbit.converged and refine:
            _read_zero(M, orbit)
        return orbit
    h, prev, prev_map, first_shift = h0, orbit, M, np.zeros(0)
    if warm is None or warm[0] != phase * M.KT or shift is None or np.size(shift) != M.size:
        shift = None  # (the neighbour's shift belongs to its section)
    for halving in range(MAX_HALVINGS):
        h *= 0.5
        Mh = _Map(fmu, M.system.replace(h=h), M.K, M.symmetry)
        Mh.slide[:] = M.slide  # (the same section, its sliders started as at h)
        fmu.system = Mh.system
        # (steps with the coarser orbit's Jacobian)
        fine, zc = _chord(Mh, prev, t_s, S, tol, h, shift if halving == 0 else None)
        if fine is None:  # (a full Newton solve at h, the Jacobian's too, from where the chord got)
            zh, Ph, Jh, rh, ith, why, obsh, _ = _newton(Mh, zc, t_s, S, tol, max_iter)
            fine = _make_orbit(Mh, zh, Ph, Jh, rh, ith, why, obsh, t_s, h, at_zero=False)
        if not fine.converged:
            prev.reason = f"the error estimate's solve at h = {h:.6g} did not converge: {why}"
            break
        if halving == 0:
            first_shift = fine.section_state - orbit.section_state
        fine.section_shift = first_shift
        diff = fine.amplitude - prev.amplitude
        fine.error = float(np.max(np.abs(diff)) / 3.0)
        fine.amplitude_extrapolated = fine.amplitude + diff / 3.0
        prev, prev_map = fine, Mh
        if accuracy is None or fine.error <= accuracy:
            break
    else:
        prev.reason = (f"the estimated error {prev.error:.3g} is above the accuracy {accuracy:g} after "
                       f"{MAX_HALVINGS} halvings of h")
        prev.converged = False
    fmu.system = prev_map.system
    _read_zero(prev_map, prev)
    fmu.system = M.system
    return prev


def _chord(M: _Map, coarse: SystemOrbit, t_s: float, S: np.ndarray, tol: float,
           h: float, shift: np.ndarray | None = None) -> tuple[SystemOrbit | None, np.ndarray]:
    """The orbit at the finer step of M from the coarser one by chord steps (Newton with the coarser
    orbit's Jacobian: the two orbits differ by the scheme's O(h^2), and each step cuts the residual by
    about the two Jacobians' difference, O(h^2) too) on map evaluations without the Jacobian, while
    each step cuts the residual to CHORD_RATE of the last at least (at most CHORD_STEPS steps); its
    multipliers the coarser orbit's (they differ by O(h^2) too). (orbit, its state), or (None, the
    last state reached) where the chord does not get there (then a full Newton solve from that state).
    ``shift``: added to the coarser orbit's state for the first iterate (a neighbouring orbit's
    difference between the two steps)."""
    J = coarse.jacobian
    z = M.project(coarse.section_state if shift is None else coarse.section_state + shift)
    if not np.all(np.isfinite(J)):
        return None, z
    sh = _Shooting(M, S)
    last = np.inf
    for it in range(CHORD_STEPS + 1):
        try:
            Pz, _, obs = M(z, t_s, jacobian=False)
        except FMUCallError:
            return None, M.project(coarse.section_state)
        r = sh.residual(z, Pz)
        dz, _ = sh.step(z, Pz, J)
        # (converged where the residual and the step to the orbit, the distance left, are within tol:
        # the coarser orbit's state has a residual within tol at a finer step whenever its distance to
        # the finer orbit times 1 - mu is, and that distance is the error estimate's whole subject)
        if r <= tol and (dz is None or sh.step_size(z, dz) <= tol):
            orbit = _make_orbit(M, z, Pz, J, r, it, "", obs, t_s, h, at_zero=False)
            orbit.multipliers = coarse.multipliers
            orbit.stable, orbit.neutral = coarse.stable, coarse.neutral
            return orbit, z
        if it == CHORD_STEPS or not (r <= CHORD_RATE * last or r <= tol):
            return None, z
        last = r
        if dz is None:
            return None, z
        z = sh.move(z, dz, 1.0)
    return None, z


def _failed(M: _Map, z: np.ndarray, reason: str, h: float) -> SystemOrbit:
    n, nc = M.n, M.system.nc
    nan_n, nan_c = np.full(n, np.nan), np.full(nc, np.nan)
    return SystemOrbit(period=M.K, x0=z[:n].copy(), v0=z[n:2 * n].copy(), s0=nan_c.copy(),
                       slide0=np.zeros(nc, dtype=int), multipliers=np.zeros(0), stable=False,
                       residual=float("nan"), amplitude=nan_n,
                       offset=nan_n.copy(), stick_fraction=nan_c, converged=False, reason=reason, h=h)
