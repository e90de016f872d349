"""An independent 40-digit reference for the oscillator with inputs that vary as polynomials (FMI input
derivatives), written for tests/test_exact_poly.py:

    m x'' + c x' + k x = P0 cos(omega t + phi) + F_ext(t) + F,   Coulomb friction F (mu_s, mu_k = chi mu_s),
    F_ext(t) = F0 + F1 t + F2 t^2 / 2,   normal force N(t) = max(N + Next0 + N1 t + N2 t^2 / 2, 0).

It shares nothing with the FMU's exact scheme (fmu_src/models/oscillator/exact.c) but the physics:

- a slide in direction s is the textbook closed form (mpmath, 40 digits): the homogeneous solution on
  the roots of m r^2 + c r + k (a double root: e^{r t}, t e^{r t}), the harmonic particular solution
  Re[P0 e^{i (omega t + phi)} / (k - m omega^2 + i c omega)], and a polynomial particular solution of
  the polynomial force F_ext(t) - s mu_k N(t) (degree 2 for k > 0, 3 for k = 0 < c, 4 for k = c = 0)
  found by solving the triangular system of its coefficients;
- stops found on a sampled grid (CELLS points per excitation period, per free period and per decay
  time): a sign change of s v refined by the Illinois method; a local minimum of s v inside a cell (a
  sign change of s a) refined, then taken as a touch within TOUCH of the velocity's scale, or
  bracketing the first of two zeros when below;
- breakaways on the same grid: the first cell where |S(t)| - F_b(t) becomes positive, S = P(t) +
  F_ext(t) - k x, F_b = max(mu_s, mu_k) N(t), refined by Illinois (a local maximum inside a cell that
  crosses the limit is refined too);
- the rules of method.md section 1: stuck while |S| <= F_b; at a stop, stick inside the limit, else
  slide along S; a slide from rest that cannot start leaves the block stuck;
- phases are cut at the zeros of N + N_ext(t) (the normal force's kink); without friction on a piece
  the motion is one slide (the mode is the sign of v).

The friction work is mu_k int N(t) |v| dt by mpmath's quadrature of the closed form."""

from __future__ import annotations

from dataclasses import dataclass

import mpmath as mp
from mp_roots import first_stop, illinois as _illinois

mp.mp.dps = 40
CELLS = 128  # grid cells per excitation period, free period and decay time


@dataclass
class Segment:
    t0: mp.mpf
    t1: mp.mpf
    mode: int  # -1, 0 (stuck), +1 (without friction: the sign of v, evaluated)
    x0: mp.mpf
    v0: mp.mpf
    s: int     # the friction direction of the slide's closed form (0: stuck, or no friction)
    free: bool = False  # a piece without friction (one slide)


class PolyReference:
    def __init__(self, m, k, c, P0, omega, phi, N, mu_s, chi, x0=0.0, v0=0.0,
                 F=(0.0, 0.0, 0.0), Next=(0.0, 0.0, 0.0)):
        f = mp.mpf
        self.m, self.k, self.c, self.P0, self.w, self.phi = f(m), f(k), f(c), f(P0), f(omega), f(phi)
        self.x0, self.v0 = f(x0), f(v0)
        mu_k = float(chi) * float(mu_s)  # as the FMU: mu_k = chi mu_s, limit max(mu_s, mu_k) N
        self.mu_k, self.mu_b = f(mu_k), f(max(float(mu_s), mu_k))
        self.Fp = [f(F[0]), f(F[1]), f(F[2])]
        self.Np = [f(N) + f(Next[0]), f(Next[1]), f(Next[2])]
        den = self.k - self.m * self.w ** 2 + 1j * self.c * self.w
        if den == 0:
            raise ValueError("resonance without damping: not covered by this reference")
        self.Z = self.P0 * mp.expj(self.phi) / den
        d = self.c ** 2 - 4 * self.m * self.k
        if d == 0:
            self.roots = None
            self.r = -self.c / (2 * self.m)
        else:
            sq = mp.sqrt(mp.mpc(d))
            self.roots = ((-self.c + sq) / (2 * self.m), (-self.c - sq) / (2 * self.m))
        times = [2 * mp.pi / self.w] if self.w != 0 else []
        for r in (self.roots or (self.r,)):
            if mp.im(r) != 0:
                times.append(2 * mp.pi / abs(mp.im(r)))
            if mp.re(r) != 0:  # a real root's mode is monotone: a coarser grid of its decay time
                times.append((1 if mp.im(r) != 0 else 8) / abs(mp.re(r)))
        self.cell = (min(times) if times else mp.mpf(1)) / CELLS
        self.segments: list[Segment] = []

    # ---- forces
    @staticmethod
    def _p(c, t):
        return c[0] + c[1] * t + c[2] * t ** 2 / 2

    def F(self, t):
        return self._p(self.Fp, t)

    def N(self, t):
        return max(self._p(self.Np, t), mp.mpf(0))

    def P(self, t):
        return self.P0 * mp.cos(self.w * t + self.phi)

    def S(self, t, x):
        return self.P(t) + self.F(t) - self.k * x

    def Fb(self, t):
        return self.mu_b * self.N(t)

    def _friction(self, ta, tb):
        """Whether the piece (ta, tb) (no zero of N + N_ext inside) has friction."""
        return self.mu_b > 0 and self._p(self.Np, (ta + tb) / 2) > 0

    # ---- the closed form of a slide
    def _particular(self, s, fric):
        """Monomial coefficients (in t) of the polynomial particular solution."""
        G = [self.Fp[0] - (s * self.mu_k * self.Np[0] if fric else 0),
             self.Fp[1] - (s * self.mu_k * self.Np[1] if fric else 0),
             (self.Fp[2] - (s * self.mu_k * self.Np[2] if fric else 0)) / 2]
        lo = 0 if self.k != 0 else (1 if self.c != 0 else 2)
        js = [lo, lo + 1, lo + 2]

        def L(j, i):  # coefficient of t^i in m (t^j)'' + c (t^j)' + k t^j
            v = mp.mpf(0)
            if i == j:
                v += self.k
            if i == j - 1:
                v += self.c * j
            if i == j - 2:
                v += self.m * j * (j - 1)
            return v
        A = mp.matrix(3, 3)
        for i in range(3):
            for n, j in enumerate(js):
                A[i, n] = L(j, i)
        sol = mp.lu_solve(A, mp.matrix(G))
        coef = [mp.mpf(0)] * 5
        for n, j in enumerate(js):
            coef[j] = sol[n]
        return coef

    def slide(self, s, ta, xa, va, fric=True):
        """(x(t), v(t), a(t)) of the slide with friction -s mu_k N(t) from (ta, xa, va)."""
        pc = self._particular(s, fric)
        w, Z = self.w, self.Z

        def xp(t):
            return sum(pc[j] * t ** j for j in range(5)) + mp.re(Z * mp.expj(w * t))

        def vp(t):
            return sum(j * pc[j] * t ** (j - 1) for j in range(1, 5)) + mp.re(1j * w * Z * mp.expj(w * t))

        def ap(t):
            return sum(j * (j - 1) * pc[j] * t ** (j - 2) for j in range(2, 5)) - w ** 2 * mp.re(Z * mp.expj(w * t))
        dx, dv = xa - xp(ta), va - vp(ta)
        if self.roots:
            r1, r2 = self.roots
            B = (dv - r1 * dx) / (r2 - r1)
            A = dx - B

            def h(t, d):
                tau = t - ta
                return A * r1 ** d * mp.exp(r1 * tau) + B * r2 ** d * mp.exp(r2 * tau)
        else:
            r = self.r
            A, B = dx, dv - r * dx  # (A + B tau) e^{r tau}

            def h(t, d):
                tau = t - ta
                e = mp.exp(r * tau)
                if d == 0:
                    return (A + B * tau) * e
                if d == 1:
                    return (B + r * (A + B * tau)) * e
                return (2 * r * B + r ** 2 * (A + B * tau)) * e
        return (lambda t: xp(t) + mp.re(h(t, 0)), lambda t: vp(t) + mp.re(h(t, 1)),
                lambda t: ap(t) + mp.re(h(t, 2)))

    # ---- events
    def _breakaway(self, ta, t_end, x):
        """(time, direction) of the first |S| > F_b in [ta, t_end), or (None, 0)."""
        S0 = self.S(ta, x)
        if abs(S0) > self.Fb(ta):
            return ta, int(mp.sign(S0))
        g = lambda t: abs(self.S(t, x)) - self.Fb(t)
        tol = mp.mpf(10) ** -36 * (1 + abs(t_end))
        t, g0 = ta, g(ta)
        while t < t_end:
            t1 = min(t + self.cell, t_end)
            g1 = g(t1)
            if g1 > 0:
                tb = _illinois(g, t, t1, g0, g1, tol)
                return tb, int(mp.sign(self.S(tb, x)))
            # a maximum inside the cell above the limit
            tm = (t + t1) / 2
            gm = g(tm)
            if gm > 0:
                tb = _illinois(g, t, tm, g0, gm, tol)
                return tb, int(mp.sign(self.S(tb, x)))
            t, g0 = t1, g1
        return None, 0

    def _stop(self, s, ta, t_end, xa, va):
        """The first stop of the slide in (ta, t_end]: time, None, or 'null' (a slide from rest that cannot start)."""
        _, v, a = self.slide(s, ta, xa, va)
        h = self.cell
        scale = abs(va) + abs(self.P0 / self.m) * h + abs(s * a(ta)) * h
        return first_stop(v, a, s, ta, t_end, va, h, scale)[0]

    def _pieces(self, t_end):
        """The times 0 < ... < t_end cutting the run at the zeros of N + N_ext(t)."""
        a, b, c = self.Np[2] / 2, self.Np[1], self.Np[0]
        zs = []
        if a != 0:
            d = b * b - 4 * a * c
            if d > 0:
                zs = [(-b - mp.sqrt(d)) / (2 * a), (-b + mp.sqrt(d)) / (2 * a)]
        elif b != 0:
            zs = [-c / b]
        cuts = sorted(z for z in zs if 0 < z < t_end)
        return cuts + [t_end]

    def solve(self, t_end):
        t_end = mp.mpf(t_end)
        t, x, v = mp.mpf(0), self.x0, self.v0
        ends = self._pieces(t_end)
        fric0 = self._friction(t, ends[0])
        if v != 0 or not fric0:
            mode = int(mp.sign(v)) if v != 0 else 1
        else:
            S0 = self.S(t, x)
            mode = 0 if abs(S0) <= self.Fb(t) else int(mp.sign(S0))
        segs = self.segments = []
        for tn in ends:
            fric = self._friction(t, tn)
            skip_until = None
            if not fric:
                xf, vf, _ = self.slide(0, t, x, v, fric=False)
                segs.append(Segment(t, tn, 1, x, v, 0, True))
                x, v, t = xf(tn), vf(tn), tn
                mode = int(mp.sign(v)) if v != 0 else 0
                continue
            if mode != 0 and v == 0:  # (from a piece without friction, at rest)
                S = self.S(t, x)
                mode = 0 if abs(S) <= self.Fb(t) else int(mp.sign(S))
            while t < tn:
                if mode == 0:
                    tb, d = self._breakaway(t if skip_until is None else skip_until, tn, x)
                    skip_until = None
                    if tb is None:
                        segs.append(Segment(t, tn, 0, x, mp.mpf(0), 0))
                        t = tn
                        break
                    if tb > t:
                        segs.append(Segment(t, tb, 0, x, mp.mpf(0), 0))
                    t, v, mode = tb, mp.mpf(0), d
                    continue
                s = mode
                ts = self._stop(s, t, tn, x, v)
                if ts == "null":
                    mode = 0
                    skip_until = t + self.cell * mp.mpf(10) ** -9
                    continue
                xf, vf, _ = self.slide(s, t, x, v)
                if ts is None:
                    segs.append(Segment(t, tn, s, x, v, s))
                    x, v, t = xf(tn), vf(tn), tn
                    break
                segs.append(Segment(t, ts, s, x, v, s))
                x, v, t = xf(ts), mp.mpf(0), ts
                S = self.S(t, x)
                mode = 0 if abs(S) <= self.Fb(t) else int(mp.sign(S))
        return segs

    def _funcs(self, seg):
        return self.slide(seg.s, seg.t0, seg.x0, seg.v0, fric=not seg.free)

    def events(self):
        """(time, from, to) of every change of mode between consecutive segments (with friction)."""
        out = []
        for a, b in zip(self.segments, self.segments[1:]):
            if a.mode != b.mode and not a.free and not b.free:
                out.append((float(b.t0), a.mode, b.mode))
        return out

    def evaluate(self, times):
        """x, v, mode at the times (floats)."""
        xs, vs, ms = [], [], []
        j = 0
        for tf in times:
            t = mp.mpf(tf)
            while j + 1 < len(self.segments) and self.segments[j].t1 < t:
                j += 1
            seg = self.segments[j]
            if seg.mode == 0:
                xs.append(float(seg.x0))
                vs.append(0.0)
                ms.append(0)
                continue
            xf, vf, _ = self._funcs(seg)
            xs.append(float(xf(t)))
            vv = vf(t)
            vs.append(float(vv))
            ms.append(int(mp.sign(vv)) if seg.free else seg.mode)
        return xs, vs, ms

    def friction_work(self, t0=None, t1=None):
        """mu_k int N(t) |v| dt over the run, or over the window [t0, t1]."""
        W = mp.mpf(0)
        for seg in self.segments:
            if seg.mode == 0 or seg.free:
                continue
            a = seg.t0 if t0 is None else max(seg.t0, mp.mpf(t0))
            b = seg.t1 if t1 is None else min(seg.t1, mp.mpf(t1))
            if not b > a:
                continue
            _, vf, _ = self._funcs(seg)
            n = max(1, int((b - a) / (self.cell * CELLS / 4)) + 1)  # quarter periods
            pts = [a + (b - a) * i / n for i in range(n + 1)]
            W += self.mu_k * mp.quad(lambda t: self.N(t) * abs(vf(t)), pts)
        return W

    def extremes(self):
        """x_max, x_min over the run (x is monotone in a slide with friction: its ends; without friction also
        its turning points)."""
        xs = []
        for seg in self.segments:
            xs.append(seg.x0)
            if seg.mode != 0:
                xf, vf, _ = self._funcs(seg)
                xs.append(xf(seg.t1))
                if seg.free:  # without friction x turns where v changes sign: on the grid, refined
                    t, v0 = seg.t0, vf(seg.t0)
                    while t < seg.t1:
                        t1 = min(t + self.cell, seg.t1)
                        v1 = vf(t1)
                        if (v0 > 0) != (v1 > 0) and v0 != 0:
                            xs.append(xf(_illinois(vf, t, t1, v0, v1, mp.mpf(10) ** -36)))
                        t, v0 = t1, v1
        return max(xs), min(xs)

    def stuck_time(self):
        return sum((seg.t1 - seg.t0 for seg in self.segments if seg.mode == 0), mp.mpf(0))


@dataclass
class Solved:
    """A reference solved up to t_end with what the tests read of it (the whole run's events,
    extremes, stuck time and friction work; the friction work of given windows) computed once."""

    ref: PolyReference
    events: list
    extremes: tuple
    stuck_time: mp.mpf
    friction_work: mp.mpf
    window_work: dict


def solve_case(params: dict, F, Next, t_end, windows=()) -> Solved:
    """PolyReference(**params, F=F, Next=Next) solved up to t_end, with its events, extremes, stuck
    time, friction work over the run and over each (t0, t1) of windows; a function of its arguments
    alone (tests keep it: refcache.py)."""
    ref = PolyReference(**params, F=F, Next=Next)
    ref.solve(t_end)
    return Solved(ref, ref.events(), ref.extremes(), ref.stuck_time(), ref.friction_work(),
                  {w: ref.friction_work(*w) for w in windows})

