"""An event-driven reference solution of a structure with friction contacts (method.md section 13),
independent of the engine and of every FMU:

    M x'' + C x' + K x = F_c cos(omega t) + F_s sin(omega t) + F_ext + W' f,    g = W x

It shares nothing with the engine but the physics. The motion is integrated piecewise, one mode
set at a time (each contact stuck, 0, or sliding, -1 / +1), by scipy's DOP853 at tight tolerances
(rtol 1e-12 by default, atol 1e-15 of the motion's scale), each switch an event found by
``solve_ivp``'s event functions and then refined by Brent's method on the motion integrated again
from the last accepted step (the dense interpolant alone places switches up to about 1e-9 of a
period off).

Each contact's surface moves at a constant speed ``v_belt_j`` (a belt; 0 by default): the slip
velocity is ``w_j x' - v_belt_j``.

**Rigid contacts** (k_t = 0). Sliding in direction ``s`` (the sign of the slip velocity):
``f_j = -s mu_k N``. Stuck: the slip velocity stays 0; the stuck set H's holding forces and the accelerations solve the constrained
(KKT) system ``M a = F + W_H' f_H``, ``W_H a = 0`` (F the applied, spring, damper and sliding
forces), by its Schur complement: ``D f_H = -W_H M^-1 F``, ``D = W_H M^-1 W_H'`` (the Delassus
matrix; where the stuck rows are dependent the forces are not unique, and the rule below picks them,
the accelerations unique all the same). All stuck contacts' forces are solved together.

**Jenkins contacts** (k_t > 0): a spring k_t in series with a massless slider at ``s_j`` (part of
the state), ``f_j = -k_t (g_j - s_j)``. Stuck: ``s_j' = v_belt_j``. Sliding in direction ``s`` (the
sign of ``g_j' - v_belt_j``): ``|f_j| = mu_k N``, ``f_j = -s mu_k N`` and ``s_j' = g_j'``. A Jenkins contact never constrains the structure.

**Events.** A sliding rigid contact stops where its slip velocity reaches 0 (against its
direction); a stuck one breaks away where its holding force reaches ``F_b = max(mu_s, mu_k) N``;
a sliding slider sticks where ``g_j'`` reaches ``v_belt_j``; a stuck slider breaks away where its spring force
reaches ``F_b``, and its force drops to ``mu_k N`` at once: the slider jumps by
``(F_b - mu_k N) / k_t`` the way it slides.

**Friction dissipation** ``E_friction``, integrated with the motion: ``mu_k N |slip velocity|`` per
sliding contact (a sliding slider's ``-f_j s_j'``), plus the spring energy ``(F_b^2 - (mu_k
N)^2) / 2 k_t`` a slider's breakaway releases.

**The rest rule** (the mode set at an event; the engine's and tests/two_mass_reference.py's):
every rigid contact at rest is held: the ones that came to rest (a stop, its slip set to exactly 0
by the momentum-consistent projection onto the at-rest set) and the stuck ones. The holding forces
are solved together; among the contacts that came to rest, the one most beyond its limit (largest
``|f_j| - F_b``) is released, to slide the way it is driven (against its holding force, ``s =
-sign(f_j)``), the forces are solved again, and so on until every one of them is within its limit.
Then a contact stuck before that the new set drives beyond its limit breaks away the same way (the
most beyond first, the forces solved again after each). Last, the set is made consistent: a contact
that left rest at the event but whose slip would then accelerate against the way it slides (a later
breakaway took its load) is held again where its holding force is within its limit beyond rounding
(the first in contact order, the set checked again). A contact whose holding force reaches its
limit is released first and the others are checked by the second part. A contact without friction
(``F_b = 0``) is never held. At t = 0 the rigid contacts whose slip is 0 count as come to rest;
the sliders start stuck with their springs relaxed (``s = g``). With ``mu_s > mu_k`` and contacts
coupled through ``M`` another mode set can be consistent too (method.md section 13): this rule,
the causal cascade from "all at rest held", picks one.

**Dependent rows.** Where the held rigid contacts' rows are dependent (two contacts on one row,
or more held contacts than independent directions) the holding forces are not unique (the
accelerations are): the reference, as the engine, takes the ones that minimise
``sum_j sqrt(D_jj) f_j^2 / F_b,j``, so that contacts along one direction (rows multiples of one
another) each carry the same share of their limits, reach them together and break away together:
the group holds up to the sum of its limits. Where one of them is still released while others hold
its row (dependent rows that are not parallel), it cannot slip, the rest rule does not settle, and
the reference stops with an error naming those contacts.

Not modelled here: time-varying inputs (``F_ext`` and ``v_belt`` are constant), the Stribeck law.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from itertools import combinations
from typing import Any, Callable, Optional, Sequence

import numpy as np
from scipy.integrate import solve_ivp

from ..roots import find_root
from ..system.structure import System

__all__ = ["Switch", "Phase", "SystemSolution", "SystemResult", "simulate"]

RTOL = 1e-12
ATOL_REL = 1e-15          # absolute tolerance relative to the motion's scale
MAX_PHASES = 200_000
STEPS_PER_PERIOD = 32.0   # at most this fraction of the shortest time scale per ODE step


@dataclass(frozen=True)
class Switch:
    """One contact's change of mode at time t (mode -1, 0 stuck, +1)."""

    t: float
    contact: int
    before: int
    after: int


@dataclass
class Phase:
    """A stretch [t0, t1] with the modes constant; ``sol`` its dense solution of (x, v, s of the
    Jenkins contacts, E_friction) (None for a phase of zero length: the state ``y0``)."""

    t0: float
    t1: float
    modes: tuple[int, ...]
    sol: Any
    y0: np.ndarray


class _Model:
    """The system's arrays in the form the integration uses."""

    def __init__(self, sys: System, F_ext: Optional[Sequence[float]], v_belt: Optional[Sequence[float]]) -> None:
        self.sys = sys
        self.n, self.nc = sys.n, sys.nc
        self.M, self.C, self.K, self.W = (np.array(a) for a in (sys.M, sys.C, sys.K, sys.W))
        self.Minv = np.linalg.inv(self.M)
        self.Minv = 0.5 * (self.Minv + self.Minv.T)
        self.Fb = np.array(sys.breakaway)
        self.Fk = np.array(sys.mu_k) * np.array(sys.N)
        self.kt = np.array(sys.k_t)
        self.jenkins = self.kt > 0.0
        self.active = self.Fb > 0.0
        self.jidx = np.flatnonzero(self.jenkins)            # contact index of each slider state
        self.slot = {int(j): i for i, j in enumerate(self.jidx)}
        self.F_ext = np.zeros(self.n) if F_ext is None else np.asarray(F_ext, dtype=float).reshape(self.n)
        self.vb = np.zeros(self.nc) if v_belt is None else np.asarray(v_belt, dtype=float).reshape(self.nc)
        self.omega = sys.omega
        Kj = self.K + (self.W.T * self.kt) @ self.W
        lam = np.linalg.eigvals(self.Minv @ Kj).real
        self.w_max = max(math.sqrt(max(float(lam.max()), 0.0)), self.omega, 1e-300)
        self.cache: dict[tuple[int, ...], tuple[np.ndarray, ...]] = {}

    def applied(self, t: float, x: np.ndarray, v: np.ndarray) -> np.ndarray:
        """F_c cos + F_s sin + F_ext - K x - C v."""
        return self.sys.excitation(t) + self.F_ext - self.K @ x - self.C @ v

    def held(self, modes: Sequence[int]) -> np.ndarray:
        """The held rigid contacts of a mode set."""
        return np.array([j for j in range(self.nc) if modes[j] == 0 and self.active[j] and not self.jenkins[j]],
                        dtype=int)

    def _ops(self, modes: tuple[int, ...]) -> tuple[np.ndarray, ...]:
        """The operators of a mode set (cached): the sliding forces (nc, 0 elsewhere), the stuck
        sliders (contacts, their stiffnesses, rows, state indices), the held rigid contacts H,
        M^-1 W_H' and D^+ W_H M^-1."""
        ops = self.cache.get(modes)
        if ops is None:
            md = np.array(modes, dtype=float)
            f0 = np.where(self.active & (md != 0), -md * self.Fk, 0.0)
            J = np.array([j for j in self.jidx if self.active[j] and modes[j] == 0], dtype=int)
            H = self.held(modes)
            WH = self.W[H]
            A = self.Minv @ WH.T
            P = self._shares(H, WH @ A) @ WH @ self.Minv if H.size else np.zeros((0, self.n))
            ops = (f0, J, self.kt[J], self.W[J], 2 * self.n + np.array([self.slot[int(j)] for j in J], dtype=int),
                   H, A, P)
            self.cache[modes] = ops
        return ops

    def _shares(self, H: np.ndarray, D: np.ndarray) -> np.ndarray:
        """The operator from the held contacts' slip accelerations to their holding forces, D^+ where
        their rows are independent; where they are dependent the forces that minimise
        ``sum_j sqrt(D_jj) f_j^2 / F_b,j`` among all that hold (the module docstring)."""
        S = 1.0 / np.sqrt(np.sqrt(np.diag(D)) / self.Fb[H])
        return S[:, None] * np.linalg.pinv(D * S[None, :])

    def forces(self, modes: tuple[int, ...], t: float, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The accelerations (n) and the contact forces (nc: sliding kinetic, stuck holding, a
        slider's spring) in the mode set at state y = (x, v, s, E_friction)."""
        n = self.n
        x, v = y[:n], y[n:2 * n]
        f0, J, kJ, WJ, iJ, H, A, P = self._ops(modes)
        f = f0.copy()
        if J.size:
            f[J] = -kJ * (WJ @ x - y[iJ])
        F = self.applied(t, x, v) + self.W.T @ f
        a = self.Minv @ F
        if H.size:
            fH = -(P @ F)
            a = a + A @ fH
            f[H] = fH
        return a, f

    def rhs(self, modes: tuple[int, ...]) -> Callable[[float, np.ndarray], np.ndarray]:
        n = self.n
        stuck_slider = np.array([self.active[j] and modes[j] == 0 for j in self.jidx], dtype=bool)
        Wj = self.W[self.jidx]
        vbj = self.vb[self.jidx]
        sliding = np.array([j for j in range(self.nc) if self.active[j] and modes[j] != 0], dtype=int)
        Ws, Fks, vbs = self.W[sliding], self.Fk[sliding], self.vb[sliding]

        def f(t: float, y: np.ndarray) -> np.ndarray:
            a, _ = self.forces(modes, t, y)
            v = y[n:2 * n]
            sd = np.where(stuck_slider, vbj, Wj @ v)
            return np.concatenate([v, a, sd, [float(Fks @ np.abs(Ws @ v - vbs))]])

        return f

    def project_rest(self, y: np.ndarray, rest: np.ndarray) -> None:
        """Sets the slip velocities of the rigid contacts ``rest`` relative to their belts to exactly 0
        by the momentum-consistent projection v -= M^-1 W_R' D_R^+ (W_R v - v_belt,R) (in place)."""
        if not rest.size:
            return
        n = self.n
        WR = self.W[rest]
        v = y[n:2 * n]
        A = self.Minv @ WR.T
        v -= A @ (np.linalg.pinv(WR @ A) @ (WR @ v - self.vb[rest]))
        y[n:2 * n] = v

    def stopped_with(self, y: np.ndarray, at_rest: Sequence[int], modes: Sequence[int]) -> list[int]:
        """The sliding rigid contacts that stop with the contacts ``at_rest`` (their slip 0 then): rows
        that depend on the at-rest rows, with the belt speed those rows give them."""
        W = self.W[list(at_rest)]
        v = y[self.n:2 * self.n]
        out = []
        for i in range(self.nc):
            if i in at_rest or modes[i] == 0 or not self.active[i] or self.jenkins[i]:
                continue
            coef, *_ = np.linalg.lstsq(W.T, self.W[i], rcond=None)
            if (np.linalg.norm(W.T @ coef - self.W[i]) <= 1e-12 * np.linalg.norm(self.W[i])
                    and abs(coef @ self.vb[list(at_rest)] - self.vb[i]) <= 1e-12 * (1.0 + abs(self.vb[i]))):
                out.append(i)
        return out

    def rest_rule(self, t: float, y: np.ndarray, modes: list[int], rest: Sequence[int],
                  was: Sequence[int] | None = None) -> list[int]:
        """The rest rule of the module docstring: the contacts ``rest`` (slip 0) held with the stuck
        ones; among ``rest`` the one most beyond its limit released, again until all of them are
        within; then a held contact the new set drives beyond its limit breaks away (the most
        beyond first, again until all held ones are within); then the set made consistent
        (:meth:`_consistent`)."""
        modes = list(modes)
        before = list(was if was is not None else modes)  # the modes before the event
        for j in rest:
            modes[j] = 0
        for candidates in (np.array(sorted(rest), dtype=int), None):
            for _ in range(self.nc + 1):
                _, f = self.forces(tuple(modes), t, y)
                H = self.held(modes)
                if candidates is not None:
                    H = np.intersect1d(H, candidates)
                if not H.size:
                    break
                excess = np.abs(f[H]) - self.Fb[H]
                k = int(np.argmax(excess))
                if not excess[k] > 0.0:
                    break
                j = int(H[k])
                modes[j] = -int(np.sign(f[j]))
        return self._consistent(t, y, modes, [j for j in range(self.nc) if modes[j] != 0 and (j in rest or
                                                                                               before[j] == 0)])

    def _consistent(self, t: float, y: np.ndarray, modes: list[int], left: list[int]) -> list[int]:
        """The cascade's mode set made consistent: a contact that left rest at this event (``left``)
        whose slip would accelerate against the way it slides once the others are decided (a later
        breakaway took its load) is held again where its holding force is then within its limit,
        the first such in contact order, and the set is checked again; one whose holding force would
        be at or beyond its limit (to rounding, 1e-9 of it) keeps sliding (the cascade's choice
        stands)."""
        modes = list(modes)
        left = [j for j in left if not self.jenkins[j]]
        for _ in range(self.nc + 1):
            a, _ = self.forces(tuple(modes), t, y)
            bad = [j for j in left if modes[j] != 0 and modes[j] * (float(self.W[j] @ a)) < 0.0]
            changed = False
            for j in bad:
                trial = list(modes)
                trial[j] = 0
                _, f = self.forces(tuple(trial), t, y)
                if abs(f[j]) < (1.0 - 1e-9) * self.Fb[j]:  # (within beyond rounding: a breakaway at the limit,
                    # chi > 1's tangential start, keeps sliding)
                    modes = trial
                    left.remove(j)
                    changed = True
                    break
            if not changed:
                break
        return modes

    def events(self, modes: tuple[int, ...]) -> list[Callable[[float, np.ndarray], float]]:
        """The event functions of a mode set (terminal; their contact as ``.contact``)."""
        n = self.n
        out = []
        for j in range(self.nc):
            if not self.active[j]:
                continue
            if modes[j] != 0:
                def ev(t: float, y: np.ndarray, j: int = j, s: int = modes[j]) -> float:
                    return s * (float(self.W[j] @ y[n:2 * n]) - self.vb[j])
                ev.direction = -1  # type: ignore[attr-defined]
            elif self.jenkins[j]:
                def ev(t: float, y: np.ndarray, j: int = j) -> float:
                    return abs(self.kt[j] * (self.W[j] @ y[:n] - y[2 * n + self.slot[j]])) - self.Fb[j]
                ev.direction = 1  # type: ignore[attr-defined]
            else:
                def ev(t: float, y: np.ndarray, j: int = j) -> float:
                    return abs(self.forces(modes, t, y)[1][j]) - self.Fb[j]
                ev.direction = 1  # type: ignore[attr-defined]
            ev.terminal = True  # type: ignore[attr-defined]
            ev.contact = j  # type: ignore[attr-defined]
            out.append(ev)
        return out


def _unsettled(m: _Model, modes: tuple[int, ...]) -> str:
    """Why the rest rule did not settle: the rigid contacts with dependent rows, if any."""
    rigid = [j for j in range(m.nc) if m.active[j] and not m.jenkins[j]]
    groups = [list(g) for size in (2, 3) for g in combinations(rigid, size)] if len(rigid) <= 12 else []
    for group in groups + [rigid]:
        if len(group) > 1 and np.linalg.matrix_rank(m.W[group]) < len(group):
            return (f"the rigid contacts {', '.join(map(str, group))} have dependent rows, so one of them "
                    "released while the others hold cannot slip: the reference needs such contacts' rows "
                    "independent or parallel")
    return f"the rest rule does not settle the mode set {modes}"


def _refine(rhs: Callable, event: Callable, ta: float, ya: np.ndarray, te: float, rtol: float,
            atol: np.ndarray) -> tuple[float, np.ndarray]:
    """The event's time and state by Brent's method on the motion integrated from (ta, ya)."""
    def at(t: float) -> np.ndarray:
        if t <= ta:
            return np.array(ya, dtype=float)
        return solve_ivp(rhs, (ta, t), ya, method="DOP853", rtol=rtol, atol=atol).y[:, -1]

    def g(t: float) -> float:
        return event.direction * event(t, at(t))

    d = 1e-8 * max(te - ta, abs(te) * 1e-8, 1e-300)
    lo = hi = te
    glo = ghi = g(te)
    for _ in range(60):
        lo, hi = max(ta, te - d), te + d
        glo, ghi = g(lo), g(hi)
        if (glo < 0.0 <= ghi) or lo == ta:
            break
        d *= 4.0
    if not glo < 0.0 <= ghi:
        return te, at(te)
    t_root = find_root(g, lo, hi, fa=glo, fb=ghi, xtol=0.0, rtol=4.0 * float(np.finfo(float).eps))
    return t_root, at(t_root)


@dataclass
class SystemSolution:
    """The reference motion: its phases (modes constant) and switches, evaluated at any time."""

    system: System
    phases: list[Phase]
    switches: list[Switch] = field(default_factory=list)
    F_ext: Optional[np.ndarray] = None
    v_belt: Optional[np.ndarray] = None

    @property
    def t_end(self) -> float:
        """The time the solution ends, s."""
        return self.phases[-1].t1

    def evaluate(self, t: Any) -> dict[str, np.ndarray]:
        """x, v, a (len(t) x n), f, mode, s (len(t) x nc; s NaN for a rigid contact) and E_friction
        (len(t)) at the times t (at a switch time the later phase)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        m = _Model(self.system, self.F_ext, self.v_belt)
        n, nc = m.n, m.nc
        starts = np.array([p.t0 for p in self.phases])
        idx = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(self.phases) - 1)
        Y = np.empty((t.size, 2 * n + m.jidx.size + 1))
        modes = np.empty((t.size, nc), dtype=int)
        for i in np.unique(idx):
            sel = np.flatnonzero(idx == i)
            ph = self.phases[int(i)]
            Y[sel] = ph.y0 if ph.sol is None else ph.sol(np.clip(t[sel], ph.t0, ph.t1)).T
            modes[sel] = ph.modes
        f = np.empty((t.size, nc))
        a = np.empty((t.size, n))
        for k in range(t.size):
            a[k], f[k] = m.forces(tuple(int(c) for c in modes[k]), float(t[k]), Y[k])
        s = np.full((t.size, nc), np.nan)
        s[:, m.jidx] = Y[:, 2 * n:2 * n + m.jidx.size]
        return {"x": Y[:, :n], "v": Y[:, n:2 * n], "a": a, "f": f, "mode": modes, "s": s, "E_friction": Y[:, -1]}


@dataclass
class SystemResult:
    """The reference sampled at the times ``t``: ``x``, ``v``, ``a`` (len(t) x n), ``f``, ``mode``,
    ``s`` (len(t) x nc), ``E_friction`` (len(t): the energy friction dissipated since t = 0), the
    ``switches`` (every contact's change of mode) and the whole ``solution``."""

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    a: np.ndarray
    f: np.ndarray
    mode: np.ndarray
    s: np.ndarray
    E_friction: np.ndarray
    switches: list[Switch]
    solution: SystemSolution

    @property
    def switch_times(self) -> np.ndarray:
        """The distinct times at which some contact changed mode, s."""
        return np.unique([sw.t for sw in self.switches]) if self.switches else np.zeros(0)


def simulate(system: System, t_end: float, t_eval: Any = None, F_ext: Optional[Sequence[float]] = None,
             v_belt: Optional[Sequence[float]] = None, rtol: float = RTOL, atol_rel: float = ATOL_REL,
             max_phases: int = MAX_PHASES) -> SystemResult:
    """The reference motion of ``system`` on [0, t_end] from its x0, v0 (see the module docstring),
    sampled at ``t_eval`` (default: 101 points). ``F_ext`` a constant external force (n values),
    ``v_belt`` the constant speeds of the contacts' surfaces (nc values; default at rest).

    Raises ValueError for a t_end that is not finite and > 0 or a Stribeck contact (not modelled
    here), RuntimeError when the integration fails or more than ``max_phases`` phases (or a loop of
    switches at one time) occur."""
    if not (math.isfinite(t_end) and t_end > 0):
        raise ValueError(f"t_end must be finite and > 0, not {t_end!r}")
    stribeck = [j for j, c in enumerate(system.contacts) if c.law != "coulomb"]
    if stribeck:
        raise ValueError(f"system reference: contacts[{stribeck[0]}] has the Stribeck law, which this reference "
                         "does not model (Coulomb contacts only)")
    m = _Model(system, F_ext, v_belt)
    n, nc = m.n, m.nc
    t_eval = np.linspace(0.0, t_end, 101) if t_eval is None else np.asarray(t_eval, dtype=float)
    # the motion's scale: the static deflection under the loads (or the initial state)
    force = max(float(np.max(np.abs(system.F_c) + np.abs(system.F_s) + np.abs(m.F_ext))),
                float(np.max(m.Fb, initial=0.0)))
    k_scale = max(float(np.max(np.abs(np.linalg.eigvalsh(system.K)))), float(np.max(np.diag(system.M)))
                  * m.omega ** 2, 1e-300)
    speed = max(float(np.max(np.abs(system.v0))), float(np.max(np.abs(m.vb), initial=0.0)))
    scale = max(force / k_scale, float(np.max(np.abs(system.x0))), speed / m.w_max, 1e-300)
    atol = atol_rel * scale * np.concatenate([np.ones(n), np.full(n, m.w_max), np.ones(m.jidx.size), [force]])
    max_step = 2.0 * math.pi / m.w_max / STEPS_PER_PERIOD
    if m.omega > 0:
        max_step = min(max_step, 2.0 * math.pi / m.omega / STEPS_PER_PERIOD)

    y = np.concatenate([system.x0, system.v0, (m.W @ system.x0)[m.jidx], [0.0]])
    slip = m.W @ system.v0 - m.vb
    rest = [j for j in range(nc) if m.active[j] and not m.jenkins[j] and slip[j] == 0.0]
    m.project_rest(y, np.array(rest, dtype=int))
    modes = [0 if m.jenkins[j] or not m.active[j] else int(np.sign(slip[j])) for j in range(nc)]
    modes = m.rest_rule(0.0, y, modes, rest)
    sol = SystemSolution(system, [], [], None if F_ext is None else m.F_ext, None if v_belt is None else m.vb)
    t = 0.0
    stalled = 0
    for _ in range(max_phases):
        md = tuple(modes)
        rhs = m.rhs(md)
        events = m.events(md)
        r = solve_ivp(rhs, (t, t_end), y, method="DOP853", rtol=rtol, atol=atol, events=events or None,
                      dense_output=True, max_step=max_step)
        if r.status == -1:
            raise RuntimeError(f"system reference: the integration failed at t = {t}: {r.message}")
        if r.status == 0:
            sol.phases.append(Phase(t, float(r.t[-1]), md, r.sol, y.copy()))
            break
        hits = [i for i in range(len(events)) if r.t_events[i].size]
        first = min(hits, key=lambda i: r.t_events[i][0])
        ev = events[first]
        te = float(r.t_events[first][0])
        if r.t.size >= 2:
            t1, y1 = _refine(rhs, ev, float(r.t[-2]), r.y[:, -2], te, rtol, atol)
        else:
            t1, y1 = te, r.y[:, -1]
        sol.phases.append(Phase(t, t1, md, r.sol if t1 > t else None, y.copy()))
        y = np.array(y1, dtype=float)
        j = int(ev.contact)  # type: ignore[attr-defined]
        new = list(md)
        if m.jenkins[j]:
            x = y[:n]
            if md[j] != 0:                                   # the slider sticks
                new[j] = 0
            else:                                            # the slider breaks away and jumps
                fj = -m.kt[j] * (m.W[j] @ x - y[2 * n + m.slot[j]])
                s = -int(np.sign(fj))
                new[j] = s
                y[2 * n + m.slot[j]] = m.W[j] @ x - s * m.Fk[j] / m.kt[j]
                y[-1] += (m.Fb[j] ** 2 - m.Fk[j] ** 2) / (2.0 * m.kt[j])   # the spring energy released
        else:
            if md[j] != 0:                                   # a stop: the rest rule
                at_rest = [i for i in range(nc) if i == j or (m.active[i] and not m.jenkins[i] and md[i] == 0)]
                m.project_rest(y, np.array(at_rest, dtype=int))
                stops = [j] + m.stopped_with(y, at_rest, md)
                new = m.rest_rule(t1, y, new, stops)
            else:                                            # a breakaway, then the others checked
                _, f = m.forces(md, t1, y)
                new[j] = -int(np.sign(f[j]))
                new = m.rest_rule(t1, y, new, [], was=md)
        for i in range(nc):
            if new[i] != md[i]:
                sol.switches.append(Switch(t1, i, md[i], new[i]))
        stalled = stalled + 1 if t1 <= t else 0
        if stalled > 4 * nc + 4:
            raise RuntimeError(f"system reference: {stalled} switches at t = {t1} without time passing: "
                               f"{_unsettled(m, md)}")
        modes = new
        t = t1
    else:
        raise RuntimeError(f"system reference: more than {max_phases} phases before t = {t_end}")
    out = sol.evaluate(t_eval)
    return SystemResult(t_eval, out["x"], out["v"], out["a"], out["f"], out["mode"], out["s"], out["E_friction"],
                        sol.switches, sol)
