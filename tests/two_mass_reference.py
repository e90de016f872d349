"""An independent event-driven reference for two masses with two friction contacts, written for
tests/test_two_mass.py:

    M x'' + C x' + K x = P(t) + F_ext + W' f,   x = (x1, x2),
    M = diag(m1, m2),  K = [[k1 + k12, -k12], [-k12, k2 + k12]],  C likewise with c1, c2, c12,
    P(t) = (P1, P2) cos(omega t + phi),
    contact g (mass 1 on the ground): w_g = (1, 0), slip x1',
    contact c (mass 2 on mass 1):     w_c = (1, -1), slip x1' - x2',
    per contact j: sliding f_j = -sign(slip_j) mu_k_j N_j; stuck slip_j = 0, |f_j| <= Fb_j,
    Fb_j = max(mu_s_j, mu_k_j) N_j (the breakaway limit of method.md section 1).

It shares nothing with the FMU's engine but the physics: the motion is integrated piecewise, one
mode set (each contact stuck or sliding either way) at a time, by scipy's DOP853 at tight
tolerances (rtol 1e-12); every switch is an event located by solve_ivp (Brent on the dense
output):

- a sliding contact stops where its slip crosses 0 (against its direction);
- a stuck contact breaks away where its holding force reaches its limit, |f_j| = Fb_j.

In a mode set the accelerations and the stuck contacts' holding forces solve the saddle-point
system [[M, -W_s'], [W_s, 0]] (a, f_s) = (applied forces + W_k' f_k, 0) (W_s the stuck rows, f_k
the sliding contacts' kinetic forces), exactly the constrained dynamics: a stuck ground contact
freezes x1, a stuck contact between the masses makes the pair move as one, both stuck freeze both.

At a switch the new mode set follows the rest rule of contacts at rest together (method.md section
13): every contact at rest (its slip 0: the one that stopped, and those stuck) is first held; the
holding forces are solved jointly; among the contacts that just came to rest, the one most beyond
its limit starts to slide the way it is driven (against its holding force), and the rest are solved
again, until all of them are within their limits; then a stuck contact the new set drives beyond
its limit breaks away the same way. A stuck contact that reaches its limit breaks away too. The
start at t0 takes the same rule for the contacts whose slip is 0.

Positions, velocities and the modes are available at any time (dense output); the switches are
listed with their times, contacts and modes."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

RTOL = 1e-13
ATOL_REL = 1e-15      # absolute tolerance relative to the motion's scale
MAX_PHASES = 100_000
CONTACTS = ("ground", "between")


@dataclass(frozen=True)
class TwoMass:
    """Parameters of the two-mass model (SI units). Contact g: mass 1 on the ground; contact c:
    mass 2 on mass 1. F1, F2: external forces held constant."""

    m1: float = 1.0
    m2: float = 0.5
    k1: float = 100.0
    k2: float = 0.0
    k12: float = 50.0
    c1: float = 0.0
    c2: float = 0.0
    c12: float = 0.0
    P1: float = 1.0
    P2: float = 0.0
    omega: float = 5.0
    phi: float = 0.0
    N_g: float = 1.5
    mu_s_g: float = 0.4
    mu_k_g: float = 0.3
    N_c: float = 1.0
    mu_s_c: float = 0.3
    mu_k_c: float = 0.2
    F1: float = 0.0
    F2: float = 0.0
    x1_0: float = 0.0
    x2_0: float = 0.0
    v1_0: float = 0.0
    v2_0: float = 0.0

    def with_(self, **kw: float) -> "TwoMass":
        """A copy with some fields changed."""
        return replace(self, **kw)

    @property
    def mass(self) -> np.ndarray:
        """M = diag(m1, m2)."""
        return np.diag([self.m1, self.m2])

    @property
    def stiffness(self) -> np.ndarray:
        """K."""
        return np.array([[self.k1 + self.k12, -self.k12], [-self.k12, self.k2 + self.k12]])

    @property
    def damping(self) -> np.ndarray:
        """C."""
        return np.array([[self.c1 + self.c12, -self.c12], [-self.c12, self.c2 + self.c12]])

    @property
    def rows(self) -> np.ndarray:
        """W: the contact rows w_g = (1, 0), w_c = (1, -1)."""
        return np.array([[1.0, 0.0], [1.0, -1.0]])

    @property
    def kinetic(self) -> np.ndarray:
        """mu_k N per contact."""
        return np.array([self.mu_k_g * self.N_g, self.mu_k_c * self.N_c])

    @property
    def breakaway(self) -> np.ndarray:
        """Fb = max(mu_s, mu_k) N per contact."""
        return np.array([max(self.mu_s_g, self.mu_k_g) * self.N_g, max(self.mu_s_c, self.mu_k_c) * self.N_c])

    def applied(self, t: float, x: np.ndarray, v: np.ndarray) -> np.ndarray:
        """P(t) + F_ext - K x - C v."""
        P = np.array([self.P1, self.P2]) * math.cos(self.omega * t + self.phi)
        return P + np.array([self.F1, self.F2]) - self.stiffness @ x - self.damping @ v


@dataclass
class Switch:
    """One contact's change of mode at time t (mode -1, 0 stuck, +1)."""

    t: float
    contact: int
    before: int
    after: int


@dataclass
class Phase:
    """A stretch with the modes constant: [t0, t1], its dense solution of (x1, x2, v1, v2)."""

    t0: float
    t1: float
    modes: tuple[int, int]
    sol: object


def _friction(p: TwoMass, modes: tuple[int, int]) -> np.ndarray:
    """The friction forces of the sliding contacts (0 for stuck ones: unknown)."""
    kin = p.kinetic
    return np.array([-modes[j] * kin[j] if modes[j] != 0 else 0.0 for j in range(2)])


def accelerations(p: TwoMass, modes: tuple[int, int], t: float, x: np.ndarray,
                  v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Accelerations and contact forces (sliding: kinetic; stuck: holding) in the mode set."""
    W = p.rows
    F = p.applied(t, x, v) + W.T @ _friction(p, modes)
    Fb = p.breakaway
    stuck = [j for j in range(2) if modes[j] == 0 and Fb[j] > 0.0]  # no friction: no constraint
    f = _friction(p, modes)
    if not stuck:
        return F / np.array([p.m1, p.m2]), f
    Ws = W[stuck]
    ns = len(stuck)
    A = np.zeros((2 + ns, 2 + ns))
    A[:2, :2] = p.mass
    A[:2, 2:] = -Ws.T
    A[2:, :2] = Ws
    sol = np.linalg.solve(A, np.r_[F, np.zeros(ns)])
    a = sol[:2].copy()
    # the constraints exactly: a stuck ground contact holds x1, a stuck pair moves as one
    if 0 in stuck:
        a[0] = 0.0
    if 1 in stuck:
        a[1] = a[0]
    for i, j in enumerate(stuck):
        f[j] = sol[2 + i]
    return a, f


def rest_rule(p: TwoMass, t: float, x: np.ndarray, v: np.ndarray, modes: list[int], rest: list[bool]) -> list[int]:
    """The modes after a switch. The contacts at rest (rest[j]: its slip 0 now) are decided together
    with the held ones: all held first, then the resting one most beyond its limit released
    against its holding force, again until every resting one is within its limit. Then a held
    contact that the new set drives beyond its limit breaks away against its holding force (one
    after the other, the forces solved again after each), until all held ones are within."""
    modes = [0 if rest[j] else modes[j] for j in range(2)]
    Fb = p.breakaway
    for _ in range(3):
        _, f = accelerations(p, tuple(modes), t, x, v)
        excess = [abs(f[j]) - Fb[j] if rest[j] and modes[j] == 0 else -math.inf for j in range(2)]
        worst = int(np.argmax(excess))
        if not excess[worst] > 0.0:
            break
        modes[worst] = -int(np.sign(f[worst]))
    for _ in range(3):
        _, f = accelerations(p, tuple(modes), t, x, v)
        beyond = [j for j in range(2) if modes[j] == 0 and Fb[j] > 0.0 and abs(f[j]) > Fb[j]]
        if not beyond:
            break
        for j in beyond:
            _, f = accelerations(p, tuple(modes), t, x, v)
            modes[j] = -int(np.sign(f[j]))
    return modes


def _slip(p: TwoMass, v: np.ndarray) -> np.ndarray:
    return p.rows @ v


def _refine(rhs, event, ta: float, ya: np.ndarray, te: float, atol: np.ndarray) -> tuple[float, np.ndarray]:
    """The event's time and state by Brent's method on the motion integrated from (ta, ya) (the
    dense output's interpolant is less accurate than the steps: its event times are off by up to
    1e-9 of the period, and a switch placed late shifts all that follows)."""
    def at(t: float) -> np.ndarray:
        if t <= ta:
            return np.asarray(ya, dtype=float)
        return solve_ivp(rhs, (ta, t), ya, method="DOP853", rtol=RTOL, atol=atol).y[:, -1]

    def g(t: float) -> float:
        return event(t, at(t))

    span = te - ta
    lo, hi = te, te
    d = 1e-7 * span
    for _ in range(40):
        lo = max(ta, te - d)
        hi = te + d
        if g(lo) * event.direction < 0.0 <= g(hi) * event.direction or lo == ta:
            break
        d *= 4.0
    glo, ghi = g(lo), g(hi)
    if not (glo * event.direction < 0.0 <= ghi * event.direction):
        return te, at(te)
    t_root = brentq(g, lo, hi, xtol=1e-16 * max(abs(te), 1.0), rtol=4 * np.finfo(float).eps)
    return t_root, at(t_root)


def simulate(p: TwoMass, t_end: float) -> "TwoMassSolution":
    """The motion on [0, t_end] from (x1_0, x2_0, v1_0, v2_0)."""
    x = np.array([p.x1_0, p.x2_0], dtype=float)
    v = np.array([p.v1_0, p.v2_0], dtype=float)
    # the motion's scale: the static deflection under the loads, the initial state
    w_max = math.sqrt(max(np.linalg.eigvals(np.linalg.solve(p.mass, p.stiffness)).real.max(), 0.0))
    scale = (abs(p.P1) + abs(p.P2) + abs(p.F1) + abs(p.F2)) / max(p.k1 + p.k2, 1e-300)
    scale = max(scale, np.max(np.abs(x)), np.max(np.abs(v)) / max(w_max, p.omega), 1e-300)
    atol = ATOL_REL * scale * np.array([1.0, 1.0, max(w_max, p.omega), max(w_max, p.omega)])
    s0 = _slip(p, v)
    modes = [int(np.sign(s0[j])) for j in range(2)]
    has_friction = p.breakaway > 0.0
    rest = [bool(s0[j] == 0.0 and has_friction[j]) for j in range(2)]
    modes = rest_rule(p, 0.0, x, v, modes, rest)
    phases: list[Phase] = []
    switches: list[Switch] = []
    t = 0.0
    for _ in range(MAX_PHASES):
        md = tuple(modes)

        def rhs(tt: float, y: np.ndarray, md: tuple[int, int] = md) -> np.ndarray:
            a, _ = accelerations(p, md, tt, y[:2], y[2:])
            return np.r_[y[2:], a]

        events = []
        kinds = []
        for j in range(2):
            if not has_friction[j]:
                continue
            if md[j] != 0:
                def stop(tt: float, y: np.ndarray, j: int = j, s: int = md[j]) -> float:
                    return s * float(p.rows[j] @ y[2:])
                stop.terminal = True
                stop.direction = -1
                events.append(stop)
                kinds.append(("stop", j))
            else:
                def brk(tt: float, y: np.ndarray, j: int = j, md: tuple[int, int] = md) -> float:
                    _, f = accelerations(p, md, tt, y[:2], y[2:])
                    return abs(f[j]) - p.breakaway[j]
                brk.terminal = True
                brk.direction = 1
                events.append(brk)
                kinds.append(("break", j))
        sol = solve_ivp(rhs, (t, t_end), np.r_[x, v], method="DOP853", rtol=RTOL, atol=atol,
                        events=events or None, dense_output=True)
        if sol.status == -1:
            raise RuntimeError(f"two-mass reference: integration failed at t = {t}: {sol.message}")
        t1 = float(sol.t[-1])
        phases.append(Phase(t, t1, md, sol.sol))
        y = sol.y[:, -1]
        if sol.status == 0:
            return TwoMassSolution(p, phases, switches)
        hit = [i for i in range(len(events)) if sol.t_events[i].size]
        kind, j = kinds[hit[0]]
        # the event again on the integrated (not interpolated) motion from the last accepted step
        t1, y = _refine(rhs, events[hit[0]], float(sol.t[-2]), sol.y[:, -2], t1, atol)
        phases[-1] = Phase(t, t1, md, sol.sol)
        x, v = y[:2].copy(), y[2:].copy()
        rest = [False, False]
        if kind == "stop":
            # at rest exactly: the slip 0 with the momentum kept
            held = [md[i] == 0 and has_friction[i] for i in range(2)]
            if j == 0:
                v[0] = 0.0
                if held[1]:
                    v[1] = 0.0
            else:
                vm = (p.m1 * v[0] + p.m2 * v[1]) / (p.m1 + p.m2)
                if held[0]:
                    vm = 0.0
                v[:] = vm
            rest[j] = True
            new = list(md)
        else:
            _, f = accelerations(p, md, t1, x, v)
            new = list(md)
            new[j] = -int(np.sign(f[j]))
        new = rest_rule(p, t1, x, v, new, rest)
        for i in range(2):
            if new[i] != md[i]:
                switches.append(Switch(t1, i, md[i], new[i]))
        modes = new
        t = t1
    raise RuntimeError(f"two-mass reference: more than {MAX_PHASES} phases before t = {t_end}")


@dataclass
class TwoMassSolution:
    """The reference motion: its phases (modes constant) and switches."""

    params: TwoMass
    phases: list[Phase]
    switches: list[Switch] = field(default_factory=list)

    def evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """x (n, 2), v (n, 2) and the modes (n, 2) at the times t (at a switch the later phase)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        starts = np.array([ph.t0 for ph in self.phases])
        idx = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(self.phases) - 1)
        x = np.empty((t.size, 2))
        v = np.empty((t.size, 2))
        modes = np.empty((t.size, 2), dtype=int)
        for i in np.unique(idx):
            sel = idx == i
            ph = self.phases[int(i)]
            y = ph.sol(t[sel])
            x[sel] = y[:2].T
            v[sel] = y[2:].T
            modes[sel] = ph.modes
        return x, v, modes

    def mode_sets(self) -> set[tuple[int, int]]:
        """The mode sets the motion went through."""
        return {ph.modes for ph in self.phases}
