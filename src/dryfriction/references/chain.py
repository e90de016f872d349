"""Event-driven reference solution of the chain of n blocks with dry friction (method.md section 9).

    wall -k[0],c[0]- m[0] -k[1],c[1]- m[1] - ... - m[n-1] -k_end,c_end- wall
    (each block i also tied to the ground by the site spring k_site[i] and damper c_site[i])
    M x'' + C x' + K x = P(t) + F_ext + F,   P_i = P0_i cos(omega t + phi_i),
    F_i = -s_i mu_k_i N_i sliding in direction s_i,  |F_i| <= max(mu_s_i, mu_k_i) N_i stuck.

Between events the mode set is fixed and the motion is smooth: scipy's DOP853 integrates the
sliding (and friction-free) blocks at a tight tolerance with the stuck ones held, and stops at the
first block event (a sliding block's velocity reaching 0; a stuck block's net force reaching its
breakaway limit). That block's mode is decided there by the rest rule (stick if its own net
applied force is within its limit, else slide that way: M is diagonal, so the decision involves
no other block's acceleration), every block is checked again, and the integration restarts. The
solution is therefore exact up to the ODE tolerance, which the tests show by tolerance convergence,
by the energy balance, and by reproducing the exact single-block solution on decoupled blocks.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Optional, Sequence

import numpy as np
from scipy.integrate import solve_ivp


@dataclass(frozen=True)
class Chain:
    """Parameters of a chain (SI units); per-block arrays have length n."""

    m: np.ndarray
    k: np.ndarray
    c: np.ndarray
    P0: np.ndarray
    phi: np.ndarray
    N: np.ndarray
    mu_s: np.ndarray
    chi: np.ndarray
    x0: np.ndarray
    v0: np.ndarray
    omega: float = 1.0
    k_end: float = 0.0
    c_end: float = 0.0
    F_ext: Optional[np.ndarray] = None
    k_site: Optional[np.ndarray] = None  # springs from each block to the ground (None: none)
    c_site: Optional[np.ndarray] = None  # dampers from each block to the ground (None: none)
    v_belt: Optional[np.ndarray] = None  # belt speed under each block (None: at rest)
    law: str = "coulomb"                 # friction law: "coulomb" or "stribeck"
    v_s: Optional[np.ndarray] = None     # Stribeck velocity of each block (> 0)
    delta: Optional[np.ndarray] = None   # Stribeck exponent of each block (> 0)

    @classmethod
    def make(cls, n: int, omega: float = 1.0, k_end: float = 0.0, c_end: float = 0.0,
             **arrays: Any) -> "Chain":
        """A chain of n blocks; each array given as a scalar (every block) or a sequence of n.
        Defaults: m = k = 1, c = 0, P0 = 1 on block 0 only, phi = 0, N = 0.8, mu_s = 0.5,
        chi = 0.7, x0 = v0 = 0."""
        defaults = {"m": 1.0, "k": 1.0, "c": 0.0, "P0": None, "phi": 0.0, "N": 0.8, "mu_s": 0.5,
                    "chi": 0.7, "x0": 0.0, "v0": 0.0}
        extra = ("k_site", "c_site", "v_belt", "v_s", "delta")
        unknown = set(arrays) - set(defaults) - {"F_ext", "law", *extra}
        if unknown:
            raise ValueError(f"unknown chain parameters {sorted(unknown)}")
        vals: dict[str, Any] = {}
        for name, d in defaults.items():
            v = arrays.get(name, d)
            if v is None:
                a = np.zeros(n)
                a[0] = 1.0
            else:
                a = np.broadcast_to(np.asarray(v, dtype=float), (n,)).copy()
            vals[name] = a
        F_ext = arrays.get("F_ext")
        if F_ext is not None:
            F_ext = np.broadcast_to(np.asarray(F_ext, dtype=float), (n,)).copy()
        site = {name: None if arrays.get(name) is None
                else np.broadcast_to(np.asarray(arrays[name], dtype=float), (n,)).copy()
                for name in extra}
        ch = cls(omega=float(omega), k_end=float(k_end), c_end=float(c_end), F_ext=F_ext,
                 law=str(arrays.get("law", "coulomb")), **vals, **site)
        ch.validate()
        return ch

    @property
    def n(self) -> int:
        """The number of blocks."""
        return int(self.m.size)

    @property
    def mu_k(self) -> np.ndarray:
        """The kinetic friction coefficients, chi mu_s, per block."""
        return self.chi * self.mu_s

    def mu(self, u: np.ndarray) -> np.ndarray:
        """The sliding coefficient of each block at the relative speeds u >= 0 (n values)."""
        if self.law == "coulomb":
            return self.mu_k + 0.0 * u
        assert self.v_s is not None and self.delta is not None
        return self.mu_k + (self.mu_s - self.mu_k) * np.exp(-(u / self.v_s) ** self.delta)

    @property
    def Fb(self) -> np.ndarray:
        """Breakaway limits max(mu_s, mu_k) N."""
        return np.maximum(self.mu_s, self.mu_k) * self.N

    @property
    def period(self) -> float:
        """The excitation period 2 pi / omega, s."""
        return 2.0 * np.pi / self.omega

    def validate(self) -> None:
        """Check every array's length and every value (ValueError naming the first bad one)."""
        for name in ("m", "k", "c", "P0", "phi", "N", "mu_s", "chi", "x0", "v0"):
            a = getattr(self, name)
            if a.shape != (self.n,) or not np.all(np.isfinite(a)):
                raise ValueError(f"{name} must hold {self.n} finite values")
        for name, lo_ok in (("m", self.m > 0), ("k", self.k >= 0), ("c", self.c >= 0),
                            ("N", self.N >= 0), ("mu_s", self.mu_s >= 0), ("chi", self.chi >= 0)):
            bad = np.flatnonzero(~lo_ok)
            if bad.size:
                i = int(bad[0])
                raise ValueError(f"invalid value {getattr(self, name)[i]} for {name}[{i + 1}]")
        for name in ("k_site", "c_site"):
            a = getattr(self, name)
            if a is None:
                continue
            bad = np.flatnonzero(~(np.isfinite(a) & (a >= 0)))
            if a.shape != (self.n,) or bad.size:
                raise ValueError(f"{name} must hold {self.n} finite values >= 0")
        if self.v_belt is not None and (self.v_belt.shape != (self.n,) or not np.all(np.isfinite(self.v_belt))):
            raise ValueError(f"v_belt must hold {self.n} finite values")
        if self.law not in ("coulomb", "stribeck"):
            raise ValueError(f"law must be 'coulomb' or 'stribeck', not {self.law!r}")
        if self.law == "stribeck":
            for name in ("v_s", "delta"):
                a = getattr(self, name)
                if a is None or a.shape != (self.n,) or not np.all(np.isfinite(a) & (a > 0)):
                    raise ValueError(f"the Stribeck law needs {name}: {self.n} finite values > 0")
        if not (self.omega >= 0 and self.k_end >= 0 and self.c_end >= 0):
            raise ValueError("omega, k_end and c_end must be >= 0")

    def matrices(self) -> tuple[np.ndarray, np.ndarray]:
        """The tridiagonal stiffness and damping matrices K, C (dense, n x n), the site springs and
        dampers on their diagonals."""
        K, C = _tridiag(self.k, self.k_end), _tridiag(self.c, self.c_end)
        if self.k_site is not None:
            K += np.diag(self.k_site)
        if self.c_site is not None:
            C += np.diag(self.c_site)
        return K, C

    def driver_args(self) -> list[str]:
        """Arguments of tests/c/chain_driver for these parameters."""
        args = [f"n={self.n}", f"omega={self.omega!r}", f"k_end={self.k_end!r}",
                f"c_end={self.c_end!r}"]
        for name in ("m", "k", "c", "P0", "phi", "N", "mu_s", "chi", "x0", "v0"):
            args.append(f"{name}=" + ",".join(repr(float(v)) for v in getattr(self, name)))
        if self.F_ext is not None:
            args.append("F_ext=" + ",".join(repr(float(v)) for v in self.F_ext))
        if any(getattr(self, a) is not None for a in ("k_site", "c_site", "v_belt")) or self.law != "coulomb":
            raise ValueError("tests/c/chain_driver has no site springs, dampers, belts or Stribeck law: run the FMU")
        return args

    def fmu_params(self) -> dict[str, Any]:
        """The chain FMU's parameters for these values (dryfriction.drivers.chain; F_ext is an input)."""
        p: dict[str, Any] = {name: getattr(self, name).tolist()
                             for name in ("m", "k", "c", "P0", "phi", "N", "mu_s", "chi", "x0", "v0")}
        p.update(omega=self.omega, k_end=self.k_end, c_end=self.c_end)
        if self.v_belt is not None:
            raise ValueError("the chain FMU takes v_belt as an input (ChainFMU3.run(inputs=...)), not as a parameter")
        for name in ("k_site", "c_site"):
            if getattr(self, name) is not None:
                p[name] = getattr(self, name).tolist()
        if self.law != "coulomb":
            assert self.v_s is not None and self.delta is not None
            p.update(friction_law=self.law, v_s=self.v_s.tolist(), delta=self.delta.tolist())
        return p


def _tridiag(s: np.ndarray, s_end: float) -> np.ndarray:
    n = s.size
    right = np.append(s[1:], s_end)
    A = np.diag(s + right)
    if n > 1:
        A -= np.diag(s[1:], 1) + np.diag(s[1:], -1)
    return A


@dataclass
class _Phase:
    t0: float
    t1: float
    modes: np.ndarray
    sol: Any  # OdeSolution over [t0, t1] of (x, v, W_applied, W_friction, D_damping), or None
    y0: np.ndarray


@dataclass
class ChainSolution:
    """The reference solution: phases of fixed mode set, each with its dense output."""

    chain: Chain
    phases: list[_Phase] = field(default_factory=list)
    events: list[tuple[float, int, int, int]] = field(default_factory=list)  # t, block, from, to

    @property
    def t_end(self) -> float:
        """The time the solution ends, s."""
        return self.phases[-1].t1

    def evaluate(self, t: Sequence[float]) -> dict[str, np.ndarray]:
        """x, v, mode (len(t) x n) and the energy accounts at the times t."""
        t = np.asarray(t, dtype=float)
        n = self.chain.n
        starts = np.array([p.t0 for p in self.phases])
        idx = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(self.phases) - 1)
        Y = np.empty((t.size, 2 * n + 3))
        modes = np.empty((t.size, n), dtype=int)
        for j in np.unique(idx):
            sel = np.flatnonzero(idx == j)
            ph = self.phases[int(j)]
            if ph.sol is None:
                Y[sel] = ph.y0
            else:
                Y[sel] = ph.sol(np.clip(t[sel], ph.t0, ph.t1)).T
            modes[sel] = ph.modes
        return {"x": Y[:, :n], "v": Y[:, n:2 * n], "mode": modes, "W_applied": Y[:, 2 * n],
                "W_friction": Y[:, 2 * n + 1], "D_damping": Y[:, 2 * n + 2]}

    def energy(self, x: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Mechanical energy (kinetic + springs) of states x, v (rows)."""
        K, _ = self.chain.matrices()
        kinetic = 0.5 * np.einsum("ij,j,ij->i", v, self.chain.m, v)
        return kinetic + 0.5 * np.einsum("ij,jk,ik->i", x, K, x)


def solve_chain(ch: Chain, t_end: float, rtol: float = 1e-12, atol: float = 1e-14,
                max_events: int = 100000, steps_per_period: float = 32.0,
                F_ext_t: Optional[Callable[[float], np.ndarray]] = None,
                N_ext_t: Optional[Callable[[float], np.ndarray]] = None,
                belt_changes: Sequence[tuple[float, Sequence[float]]] = ()) -> ChainSolution:
    """The event-driven reference on [0, t_end] (see the module docstring). The ODE steps are at
    most 1/steps_per_period of the shortest time scale (natural or forcing period). F_ext_t, when
    given, is a smooth time-varying external force (n values at time t) added to ch.F_ext: a
    polynomial or harmonic input of a coupled run; it enters the stuck blocks' breakaway events
    as the excitation does. N_ext_t likewise adds a time-varying normal force (the normal force
    max(N + N_ext_t(t), 0), its limits following it in the motion and in the events); which
    blocks have friction is decided at t = 0.

    Belts: block i's friction acts on v_rel = v_i - v_belt_i (ch.v_belt, then the n speeds of
    belt_changes (t, speeds) from each t on, sorted by t). Stuck means v_i = v_belt_i (x_i moves
    with the belt) while the held force is within max(mu_s, mu_k) N_i; sliding, the friction is
    -sign(v_rel) N_i mu(|v_rel|) (ch.mu: Coulomb or Stribeck). A belt change while stuck keeps
    the velocity: the block slides the way v_rel points (stays stuck if v_rel is 0)."""
    if not (np.isfinite(t_end) and t_end > 0):
        raise ValueError(f"t_end must be finite and > 0, got {t_end}")
    n = ch.n
    K, C = ch.matrices()
    m, Fb0 = ch.m, ch.Fb
    mu_b = np.maximum(ch.mu_s, ch.mu_k)
    changes = sorted((float(tc), np.asarray(vc, dtype=float)) for tc, vc in belt_changes)
    for tc, vc in changes:
        if vc.shape != (n,) or not np.all(np.isfinite(vc)) or not (0.0 < tc):
            raise ValueError(f"a belt change needs a time > 0 and {n} finite speeds, not ({tc}, {vc})")

    def belt(t: float) -> np.ndarray:
        vb = np.zeros(n) if ch.v_belt is None else ch.v_belt
        for tc, vc in changes:
            if t >= tc:
                vb = vc
        return vb

    def normal(t: float) -> np.ndarray:
        return ch.N if N_ext_t is None else np.maximum(ch.N + np.asarray(N_ext_t(t), dtype=float), 0.0)

    def limits(t: float) -> tuple[np.ndarray, np.ndarray]:
        """Breakaway limits and the kinetic magnitudes at rest relative to the belt (mu(0) N) at t."""
        if N_ext_t is None and ch.law == "coulomb":
            return Fb0, ch.mu_k * ch.N
        N = normal(t)
        return mu_b * N, ch.mu(np.zeros(n)) * N

    Fb, mukN = limits(0.0)
    u = np.zeros(n) if ch.F_ext is None else ch.F_ext
    fric = Fb > 0
    Pc, Ps = ch.P0 * np.cos(ch.phi), ch.P0 * np.sin(ch.phi)

    def applied(t: float) -> np.ndarray:
        P = Pc * np.cos(ch.omega * t) - Ps * np.sin(ch.omega * t) + u
        return P if F_ext_t is None else P + np.asarray(F_ext_t(t), dtype=float)

    def net(t: float, x: np.ndarray, v: np.ndarray) -> np.ndarray:
        return applied(t) - K @ x - C @ v

    w_max = max(float(np.sqrt(np.max(np.abs(np.linalg.eigvals(K / m[:, None]))))), ch.omega, 1e-300)
    max_step = 2.0 * np.pi / w_max / steps_per_period
    sol = ChainSolution(ch)
    t = 0.0
    vb = belt(0.0)
    x, v = ch.x0.astype(float).copy(), ch.v0.astype(float).copy()
    acc = np.zeros(3)
    modes = np.where(fric & (v == vb), 0, np.sign(v - vb)).astype(int)
    S0 = net(0.0, x, v)
    for i in np.flatnonzero(fric & (v == vb)):
        modes[i] = 0 if abs(S0[i]) <= Fb[i] else int(np.sign(S0[i]))

    def settle(t: float, x: np.ndarray, v: np.ndarray, modes: np.ndarray) -> None:
        """Make the mode set consistent at t: stops and breakaways due now (one block at a time)."""
        Fb, mukN = limits(t)
        vb = belt(t)
        for _ in range(4 * n + 4):
            S = net(t, x, v)
            changed = False
            for i in np.flatnonzero(fric):
                s = modes[i]
                if s != 0 and s * (v[i] - vb[i]) < 0.0:
                    v[i] = vb[i]
                tol = 1e-12 * (abs(S[i]) + mukN[i])
                if s != 0 and v[i] == vb[i] and s * (S[i] - s * mukN[i]) < -tol:
                    # at rest on the belt and decelerating (not a breakaway at chi >= 1, which
                    # starts with zero acceleration): the rest rule decides
                    new = 0 if abs(S[i]) <= Fb[i] else int(np.sign(S[i]))
                elif s == 0 and abs(S[i]) > Fb[i]:
                    new = int(np.sign(S[i]))
                else:
                    continue
                if new != s:
                    sol.events.append((t, int(i), int(s), new))
                    modes[i] = new
                    changed = True
                    break
            if not changed:
                return

    settle(t, x, v, modes)
    grace: set[int] = set()  # blocks whose stop event needs a margin for one phase (grazing)
    for _ in range(max_events):
        stuck = fric & (modes == 0)
        free = ~stuck
        vb = belt(t)
        t_stop = min([tc for tc, _ in changes if tc > t] + [t_end])
        fmodes = np.where(fric, -modes, 0).astype(float)

        def rhs(tt: float, y: np.ndarray, free: np.ndarray = free, stuck: np.ndarray = stuck,
                fmodes: np.ndarray = fmodes, vb: np.ndarray = vb) -> np.ndarray:
            xx, vv = y[:n], y[n:2 * n]
            N = normal(tt)
            Ff = fmodes * ch.mu(np.abs(vv - vb)) * N
            P = applied(tt)
            Sn = P - K @ xx - C @ vv
            a = np.where(free, (Sn + Ff) / m, 0.0)
            vd = np.where(free, vv, vb)
            Fs = np.where(free, Ff, -Sn)  # a stuck block's friction holds it on its belt
            return np.concatenate([vd, a, [P @ vd, Fs @ vd, vd @ C @ vd]])

        events: list[Callable[..., float]] = []
        owners: list[int] = []
        for i in np.flatnonzero(fric):
            if modes[i] != 0:
                s = int(modes[i])
                # a grazing restart (|S| at the limit, a stop found at once and no mode change):
                # the next stop must go below a velocity margin of rounding size
                dv = 1e-12 * (1.0 + float(np.max(np.abs(v)))) if int(i) in grace else 0.0
                ev = (lambda tt, y, i=i, s=s, dv=dv, vbi=float(vb[i]): s * (y[n + i] - vbi) + dv)
                ev.terminal, ev.direction = True, -1  # type: ignore[attr-defined]
                events.append(ev)
                owners.append(int(i))
            else:
                for side in (1.0, -1.0):
                    ev = (lambda tt, y, i=i, side=side:
                          limits(tt)[0][i] - side * (applied(tt)[i] - K[i] @ y[:n] - C[i] @ y[n:2 * n]))
                    ev.terminal, ev.direction = True, -1  # type: ignore[attr-defined]
                    events.append(ev)
                    owners.append(int(i))
        y0 = np.concatenate([x, v, acc])
        # the event functions of stuck blocks move with the forcing even when nothing else does:
        # steps no longer than a fraction of the shortest time scale, so no crossing hides in a step
        r = solve_ivp(rhs, (t, t_stop), y0, method="DOP853", rtol=rtol, atol=atol,
                      events=events or None, dense_output=True, max_step=max_step)
        if r.status < 0:
            raise RuntimeError(f"reference integration failed at t = {t}: {r.message}")
        t1 = float(r.t[-1])
        sol.phases.append(_Phase(t, t1, modes.copy(), r.sol, y0))
        y1 = r.y[:, -1]
        x, v, acc = y1[:n].copy(), y1[n:2 * n].copy(), y1[2 * n:].copy()
        v[stuck] = vb[stuck]
        if t1 >= t_end:
            return sol
        Fb, mukN = limits(t1)
        n_events = len(sol.events)
        grazing: list[int] = []
        if any(tc == t1 for tc, _ in changes):
            # a belt change at t1: stuck blocks keep their velocity and slide the way v_rel points,
            # sliding ones take the sign of their new v_rel (the rest rule when it is 0)
            vb1 = belt(t1)
            S = net(t1, x, v)
            for i in np.flatnonzero(fric):
                vr = v[i] - vb1[i]
                if vr != 0.0:
                    new = int(np.sign(vr))
                elif modes[i] == 0:
                    continue
                else:
                    new = 0 if abs(S[i]) <= Fb[i] else int(np.sign(S[i]))
                if new != modes[i]:
                    sol.events.append((t1, int(i), int(modes[i]), new))
                    modes[i] = new
        if r.status == 1:
            fired = [j for j, te in enumerate(r.t_events) if te.size and te[-1] == t1]
            grazing = [owners[j] for j in fired if modes[owners[j]] != 0]
            for j in fired:
                i = owners[j]
                if modes[i] != 0:
                    v[i] = vb[i]
                    S = net(t1, x, v)
                    new = 0 if abs(S[i]) <= Fb[i] else int(np.sign(S[i]))
                else:
                    S = net(t1, x, v)
                    new = int(np.sign(S[i])) if S[i] != 0 else int(modes[i])
                if new != modes[i]:
                    sol.events.append((t1, i, int(modes[i]), new))
                    modes[i] = new
        settle(t1, x, v, modes)
        stalled = len(sol.events) == n_events and t1 <= t + 1e-12 * (1.0 + abs(t))
        grace = set(grazing) if stalled else set()
        t = t1
    raise RuntimeError(f"more than {max_events} events before t = {t_end}")
