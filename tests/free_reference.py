"""An independent 40-digit reference for the free mass on a rough support (k = 0), written for
tests/test_exact_free.py:

    m x'' + c x' = P0 cos(omega t + phi) + F_ext + F,   Coulomb friction F (mu_s, mu_k = chi mu_s, N).

It shares nothing with the FMU's exact scheme (fmu_src/exact_free.c) but the physics:

- the textbook closed form of a slide (mpmath, 40 digits, where its cancellations are harmless):
  c > 0: v = f0/b + Re[A e^{i theta}/(b + i omega)] + (v_a - v_p(t_a)) e^{-b tau}, x its integral;
  c = 0: v = v_a + f0 tau + Re[A (e^{i theta} - e^{i theta_a}) / (i omega)], x its integral;
- stops found on a sampled grid (64 points per excitation period and per damping time): a sign
  change of s v, refined by the Illinois method; a local minimum of s v inside a cell (a sign change
  of s a) refined, then taken as a touch when it is within 1e-14 of the velocity's scale, or
  bracketing the first of two zeros when below;
- breakaways on the grid of the excitation's extrema (the static force P + F_ext is monotone
  between two of them, so a crossing of the limit is bracketed there), refined by Illinois;
- the rules of method.md section 1: stuck while |P + F_ext| <= max(mu_s, mu_k) N; at a stop, stick
  inside the limit, else slide along the static force; a slide from rest that cannot start (s v < 0
  right after) leaves the block stuck.

F_ext may be a schedule held over communication steps (phases restart at each step's start).
Without friction (mu_s N = 0) the motion is one slide from t0 (the mode is the sign of v)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import mpmath as mp
from mp_roots import first_stop, illinois as _illinois

mp.mp.dps = 40
CELLS = 64          # grid cells per excitation period and per damping time


@dataclass
class Segment:
    t0: mp.mpf
    t1: mp.mpf
    mode: int          # -1, 0 (stuck), +1
    x0: mp.mpf
    v0: mp.mpf
    F: mp.mpf          # F_ext held over the segment


class FreeReference:
    def __init__(self, m, c, P0, omega, phi, N, mu_s, chi, x0=0.0, v0=0.0, F_ext=0.0):
        f = mp.mpf
        self.m, self.c, self.P0, self.w, self.phi = f(m), f(c), f(P0), f(omega), f(phi)
        self.N, self.x0, self.v0 = f(N), f(x0), f(v0)
        mu_k = float(chi) * float(mu_s)            # as the FMU: mu_k = chi mu_s, limit max(mu_s, mu_k) N
        self.muk_N = f(mu_k) * self.N
        self.Fb = f(max(float(mu_s), mu_k)) * self.N
        self.friction = self.Fb > 0
        self.b = self.c / self.m
        self.F_default = f(F_ext)
        self.segments: list[Segment] = []

    # ---- forces and the closed form of a slide
    def P(self, t):
        return self.P0 * mp.cos(self.w * t + self.phi)

    def S(self, t, F):
        return self.P(t) + F

    def slide(self, s, ta, xa, va, F):
        """(x(t), v(t), a(t)) of the slide in direction s from (ta, xa, va)."""
        b, w, m = self.b, self.w, self.m
        f0 = (F - s * self.muk_N) / m
        A = self.P0 / m
        if w == 0:                    # a constant excitation
            f0 += A * mp.cos(self.phi)
            A = mp.mpf(0)
            w = mp.mpf(1)
        th = lambda t: w * t + self.phi
        E = lambda t: mp.expj(th(t))
        if b > 0:
            vp = lambda t: f0 / b + mp.re(A * E(t) / (b + 1j * w))
            xp = lambda t: f0 / b * t + mp.re(A * E(t) / ((b + 1j * w) * 1j * w))
            d = va - vp(ta)

            def v(t):
                return vp(t) + d * mp.exp(-b * (t - ta))

            def x(t):
                return xa + xp(t) - xp(ta) + d * (1 - mp.exp(-b * (t - ta))) / b
        else:
            Ea = E(ta)

            def v(t):
                return va + f0 * (t - ta) + mp.re(A * (E(t) - Ea) / (1j * w))

            def x(t):
                tau = t - ta
                return (xa + va * tau + f0 * tau ** 2 / 2 + mp.re(A * (E(t) - Ea) / (1j * w) ** 2)
                        - mp.re(A * Ea / (1j * w)) * tau)

        def a(t):
            return A * mp.cos(th(t)) + f0 - b * v(t)
        return x, v, a

    # ---- phases
    def _cell(self):
        T = 2 * mp.pi / self.w if self.w > 0 else mp.mpf(1)
        if self.b > 0:
            T = min(T, 1 / self.b)
        return T / CELLS

    def _breakaway(self, ta, t_end, x, F):
        """(time, direction) of the first |P + F| > Fb in [ta, t_end), or (None, 0)."""
        S0 = self.S(ta, F)
        if abs(S0) > self.Fb:
            return ta, int(mp.sign(S0))
        if self.w == 0 or self.P0 == 0:
            return None, 0
        # the extrema of cos(omega t + phi) after ta
        k = mp.ceil((self.w * ta + self.phi) / mp.pi)
        t_prev = ta
        while t_prev < t_end:
            t_k = min((k * mp.pi - self.phi) / self.w, t_end)
            if t_k > t_prev:
                S1 = self.S(t_k, F)
                if abs(S1) > self.Fb:
                    sgn = int(mp.sign(S1))
                    g = lambda t: sgn * self.S(t, F) - self.Fb
                    tb = _illinois(g, t_prev, t_k, g(t_prev), g(t_k), mp.mpf(10) ** -36 * (1 + abs(t_k)))
                    return tb, sgn
                t_prev = t_k
            k += 1
        return None, 0

    def _stop(self, s, ta, t_end, xa, va, F):
        """The first stop of the slide in (ta, t_end]: (time, touch?) or (None, False); 'null' when a
        slide from rest cannot start."""
        _, v, a = self.slide(s, ta, xa, va, F)
        h = self._cell()
        scale = abs(va) + abs(self.P0) / self.m / max(self.w, self.b, mp.mpf(10) ** -30) + abs(F - s * self.muk_N) / self.m * h
        return first_stop(v, a, s, ta, t_end, va, h, scale)

    def solve(self, t_end, schedule=None):
        """Segments up to t_end; schedule: [(t_i, F_i)], F_i held from t_i (t_0 = 0)."""
        t_end = mp.mpf(t_end)
        sched = [(mp.mpf(0), self.F_default)] if schedule is None else [(mp.mpf(t), mp.mpf(F)) for t, F in schedule]
        sched.append((t_end, None))
        t, x, v = mp.mpf(0), self.x0, self.v0
        if not self.friction:
            mode = 1 if v >= 0 else -1
        elif v != 0:
            mode = int(mp.sign(v))
        else:
            S0 = self.S(t, sched[0][1])
            mode = 0 if abs(S0) <= self.Fb else int(mp.sign(S0))
        segs = self.segments = []
        for (tc, F), (tn, _) in zip(sched, sched[1:]):
            t = tc
            skip_until = None
            while t < tn:
                if mode == 0:
                    tb, d = self._breakaway(t if skip_until is None else skip_until, tn, x, F)
                    skip_until = None
                    if tb is None:
                        segs.append(Segment(t, tn, 0, x, mp.mpf(0), F))
                        t = tn
                        break
                    if tb > t:
                        segs.append(Segment(t, tb, 0, x, mp.mpf(0), F))
                    t, v, mode = tb, mp.mpf(0), d
                    continue
                s = mode
                if not self.friction:
                    segs.append(Segment(t, tn, s, x, v, F))
                    xf, vf, _ = self.slide(s, t, x, v, F)
                    x, v, t = xf(tn), vf(tn), tn
                    break
                ts, _touch = self._stop(s, t, tn, x, v, F)
                if ts == "null":
                    mode = 0
                    skip_until = t + self._cell() * mp.mpf(10) ** -9
                    continue
                xf, vf, _ = self.slide(s, t, x, v, F)
                if ts is None:
                    segs.append(Segment(t, tn, s, x, v, F))
                    x, v, t = xf(tn), vf(tn), tn
                    break
                segs.append(Segment(t, ts, s, x, v, F))
                x, v, t = xf(ts), mp.mpf(0), ts
                S = self.S(t, F)
                mode = 0 if abs(S) <= self.Fb else int(mp.sign(S))
        return segs

    def events(self):
        """(time, from, to) of every change of mode between consecutive segments."""
        out = []
        for a, b in zip(self.segments, self.segments[1:]):
            if a.mode != b.mode:
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
            else:
                xf, vf, _ = self.slide(seg.mode, seg.t0, seg.x0, seg.v0, seg.F)
                xs.append(float(xf(t)))
                vs.append(float(vf(t)))
            ms.append(seg.mode)
        return xs, vs, ms


def reference_for(p, F_ext=0.0) -> FreeReference:
    """The reference of an Oscillator p (k = 0)."""
    assert p.k == 0.0
    return FreeReference(p.m, p.c, p.P0, p.omega, p.phi, p.N, p.mu_s, p.chi, p.x0, p.v0, F_ext)


def solved_reference(p, F_ext=0.0, t_end=1.0, schedule=None) -> FreeReference:
    """The reference of an Oscillator p (k = 0) under F_ext, solved up to t_end (schedule: as
    FreeReference.solve's); a function of its arguments alone (tests keep it: refcache.py)."""
    ref = reference_for(p, F_ext)
    ref.solve(t_end, schedule=schedule)
    return ref


def period_of(p) -> float:
    return 2.0 * math.pi / p.omega if p.omega > 0 else 1.0
