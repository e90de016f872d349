"""Root finding shared by the 40-digit references (tests/free_reference.py, tests/poly_reference.py):
the Illinois method and the first stop of a slide on a sampled grid. mpmath only; nothing from the
FMU's code."""

from __future__ import annotations

from typing import Callable, Union

import mpmath as mp

TOUCH = mp.mpf("1e-14")
Stop = Union[mp.mpf, None, str]


def illinois(f: Callable, a, b, fa, fb, tol):
    """A zero of f in [a, b] with fa > 0 >= fb (or the reverse)."""
    side = 0
    for _ in range(400):
        c = (a * fb - b * fa) / (fb - fa)
        if not (min(a, b) < c < max(a, b)):
            c = (a + b) / 2
        fc = f(c)
        if fc == 0 or abs(b - a) <= tol:
            return c
        if (fc > 0) == (fa > 0):
            a, fa = c, fc
            if side == -1:
                fb /= 2
            side = -1
        else:
            b, fb = c, fc
            if side == 1:
                fa /= 2
            side = 1
    return (a + b) / 2


def first_stop(v: Callable, a: Callable, s: int, ta, t_end, va, h, scale) -> tuple[Stop, bool]:
    """The first stop of a slide in direction s in (ta, t_end], its velocity v(t) and acceleration
    a(t) given: (time, touch?), (None, False) without a stop, ("null", False) when a slide from rest
    (va = 0) cannot start. Stops are sign changes of s v on the grid of cells h, refined by Illinois;
    a local minimum of s v inside a cell (a sign change of s a) is refined, then taken as a touch
    when within TOUCH of the velocity's scale (scale: its start value, grown by every sample), or
    bracketing the first of two zeros when below."""
    g = lambda t: s * v(t)
    ga = lambda t: s * a(t)
    t = ta
    if va == 0:
        eps = h * mp.mpf(10) ** -12
        if not g(ta + eps) > 0:
            return "null", False
        t = ta + eps
    g0, a0 = g(t), ga(t)
    tol = mp.mpf(10) ** -36 * (1 + abs(t_end))
    while t < t_end:
        t1 = min(t + h, t_end)
        g1, a1 = g(t1), ga(t1)
        scale = max(scale, abs(g1))
        if g1 <= 0:
            return illinois(g, t, t1, g0, g1, tol), False
        if a0 < 0 < a1:  # a local minimum of s v inside the cell
            tm = illinois(ga, t, t1, a0, a1, tol)
            gm = g(tm)
            if gm <= TOUCH * scale:
                if gm < -TOUCH * scale:
                    return illinois(g, t, tm, g0, gm, tol), False
                return tm, True
        t, g0, a0 = t1, g1, a1
    return None, False
