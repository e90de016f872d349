"""The package's one scalar root finder: Brent's method on a bracket.

Every Python caller that looks for a zero of a function of one variable uses this module: the
exact reference's stop search, the belt reference's breakaway, the self-excited belt's section
crossing and Hopf speed, and the continuation's location of a bifurcation.

**The method.** Brent's (Brent 1973, *Algorithms for Minimization without Derivatives*, ch. 4; the
variant of SciPy's ``brentq``: inverse quadratic extrapolation from the last three points, secant
when only two are usable, bisection otherwise). A bracket [a, b] with f(a), f(b) of opposite signs
is kept at every step, so the method converges whatever f is, continuous or not: an interpolated
step is taken only when it is shorter than half the step before the last one and falls well inside
the bracket, otherwise the bracket is halved, so the steps shrink at least geometrically (at most
about k^2 evaluations, k those of bisection; on a smooth simple root the order is about 1.8).
It gives SciPy ``brentq``'s iterates (tested), so the callers that used it keep their bits, with two
guards added: the signs of f are compared, not their product (which underflows to 0 when both
values are below about 1e-162, and passes for a bracket or hides one), and a step that would not land strictly inside the
bracket bisects instead. It needs no SciPy.

Why this one: Illinois (regula falsi with halving, what the continuation had) is of order 1.44 and
is bounded only through a bisection fallback; Chandrupatla's method needs about as many evaluations
on smooth roots, but its steps are bounded below only by the tolerance, so without an added
safeguard its worst case is no multiple of bisection's; TOMS 748 (Alefeld-Potra-Shi) has the better
worst case but spends two or three evaluations per step and no fewer on smooth roots. Brent's is
the standard with a proven bound, and it is what three of the callers used.

**The tolerance convention (one for every caller).** The search stops when

- f(x) == 0 at an evaluated point x (the root is x), or
- the bracket [lo, hi] holding the sign change is narrower than ``xtol + rtol * |x|``, x the end of
  the bracket with the smaller |f|, or
- lo and hi are neighbouring doubles (no double between them: located to rounding, whatever the
  tolerance asked).

The root returned is x: an evaluated point, so f(x) is known, and the true zero (or the jump of a
discontinuous f) lies within the bracket. ``rtol`` defaults to ``RTOL = 4 eps`` (a few units of the
last place), ``xtol`` to 0; give ``xtol`` > 0 for a root that may sit at or near 0.

**Errors.** A bracket whose ends have f of one sign (neither zero) raises :class:`BracketError` (a
ValueError) naming both values; a NaN from f, or an end that is not finite, a ValueError; a search
that has not converged after ``maxiter`` evaluations, :class:`RootError` (a RuntimeError) with the
bracket reached.

**Two ways to call it.** :func:`find_root` (the root) and :func:`solve` (a :class:`Root`: the root,
the last bracket, the evaluations) call f themselves. :class:`RootSearch` hands the points to the
caller instead (``x``, then ``tell(f(x))``): for an f that is expensive, may fail, or needs state
between calls (the continuation corrects a branch point at each trial); the bracket so far is
available at every step.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

__all__ = ["BracketError", "RootError", "Root", "RootSearch", "find_root", "solve", "RTOL", "MAXITER"]

#: the relative tolerance by default: 4 units of rounding (as SciPy's brentq)
RTOL = 4.0 * 2.220446049250313e-16
#: evaluations allowed by default (a bisection from 1e300 down to 4 eps takes about 1050)
MAXITER = 2000


class BracketError(ValueError):
    """The two ends of the interval do not bracket a root: f has the same sign (not zero) at both."""


class RootError(RuntimeError):
    """The search did not converge within its evaluations."""


@dataclass(frozen=True)
class Root:
    """The outcome of a search: the root ``x`` (an evaluated point) and ``f`` = f(x); the last bracket
    ``lo`` <= ``hi`` with f's values there (``f_lo``, ``f_hi``: opposite signs, or one of them 0);
    ``evaluations`` of f made by the search; ``converged``: within the tolerance (module doc)."""

    x: float
    f: float
    lo: float
    hi: float
    f_lo: float
    f_hi: float
    evaluations: int
    converged: bool


def _value(fx: float, x: float) -> float:
    v = float(fx)
    if math.isnan(v):
        raise ValueError(f"the function is NaN at x = {x!r}: no root can be bracketed there")
    return v


def _opposite(fa: float, fb: float) -> bool:
    """f changes sign between two nonzero values (by their signs: a product could underflow)."""
    return (fa < 0.0) != (fb < 0.0)


class RootSearch:
    """Brent's method with the caller evaluating f (module doc): read ``x``, evaluate f there and
    ``tell`` the value, until ``done``; then ``result()``.

    ``a``, ``b`` (finite, in either order) with ``fa`` = f(a), ``fb`` = f(b) of opposite signs or one
    of them 0 (then that end is the root and the search is done at once); ``xtol``, ``rtol``: the
    tolerance (module doc); ``maxiter``: evaluations allowed (``tell`` calls), after which ``done``
    is set with ``converged`` false."""

    def __init__(self, a: float, b: float, fa: float, fb: float, *, xtol: float = 0.0, rtol: float = RTOL,
                 maxiter: int = MAXITER) -> None:
        a, b = float(a), float(b)
        if not (math.isfinite(a) and math.isfinite(b)):
            raise ValueError(f"the bracket's ends must be finite, not [{a!r}, {b!r}]")
        if not (math.isfinite(xtol) and xtol >= 0.0 and math.isfinite(rtol) and rtol >= 0.0):
            raise ValueError(f"xtol and rtol must be finite and >= 0, not xtol = {xtol!r}, rtol = {rtol!r}")
        if not (isinstance(maxiter, int) and maxiter >= 0):
            raise ValueError(f"maxiter must be an integer >= 0, not {maxiter!r}")
        fa, fb = _value(fa, a), _value(fb, b)
        self.xtol, self.rtol, self.maxiter = float(xtol), float(rtol), maxiter
        self.evaluations = 0
        self.converged = False
        self.done = False
        #: the next point to evaluate (NaN once done)
        self.x = math.nan
        # Brent's state: cur the best end of the bracket [cur, blk], pre the point before cur; spre,
        # scur the steps before the last and the last
        self._pre, self._fpre = a, fa
        self._cur, self._fcur = b, fb
        self._blk, self._fblk = a, fa
        self._spre = self._scur = b - a
        if fa == 0.0 or fb == 0.0:
            if fa == 0.0:
                self._cur, self._fcur, self._blk, self._fblk = a, fa, b, fb
            self._finish(True)
            return
        if not _opposite(fa, fb):
            raise BracketError(f"f({a!r}) = {fa:.6g} and f({b!r}) = {fb:.6g} have the same sign: "
                               f"[{min(a, b)!r}, {max(a, b)!r}] brackets no root")
        if a == b:
            raise ValueError(f"the bracket's ends are one point ({a!r}) with f = {fa:.6g} != 0 there")
        self._advance()

    def _finish(self, converged: bool) -> None:
        self.done, self.converged, self.x = True, converged, math.nan

    def _advance(self) -> None:
        """From the evaluated cur (and pre, blk): stop, or set the next point x."""
        if _opposite(self._fpre, self._fcur):
            # the sign change is now between pre and cur: pre becomes the far end of the bracket
            self._blk, self._fblk = self._pre, self._fpre
            self._spre = self._scur = self._cur - self._pre
        if abs(self._fblk) < abs(self._fcur):
            # cur is always the end with the smaller |f|
            self._pre, self._fpre = self._cur, self._fcur
            self._cur, self._fcur = self._blk, self._fblk
            self._blk, self._fblk = self._pre, self._fpre
        cur, blk = self._cur, self._blk
        delta = 0.5 * (self.xtol + self.rtol * abs(cur))
        sbis = 0.5 * (blk - cur)
        if self._fcur == 0.0 or abs(sbis) < delta:
            self._finish(True)
            return
        mid = cur + sbis
        if mid == cur or mid == blk:            # neighbouring doubles: located to rounding
            self._finish(True)
            return
        if self.evaluations >= self.maxiter:
            self._finish(False)
            return
        fcur, fpre, pre = self._fcur, self._fpre, self._pre
        step = sbis
        if abs(self._spre) > delta and abs(fcur) < abs(fpre):
            if pre == blk:                      # two points: the secant
                stry = -fcur * (cur - pre) / (fcur - fpre)
            else:                               # three points: inverse quadratic extrapolation
                fblk = self._fblk
                dpre = (fpre - fcur) / (pre - cur)
                dblk = (fblk - fcur) / (blk - cur)
                stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
            if 2.0 * abs(stry) < min(abs(self._spre), 3.0 * abs(sbis) - delta):
                self._spre, step = self._scur, stry      # a short step: taken
            else:
                self._spre = sbis
        else:
            self._spre = sbis
        self._scur = step
        self._pre, self._fpre = cur, fcur
        x = cur + step if abs(step) > delta else cur + math.copysign(delta, sbis)
        if not (min(cur, blk) < x < max(cur, blk)):
            x = mid                             # a step of rounding size that does not move
        self.x = x

    def tell(self, fx: float) -> bool:
        """f at the point ``x`` last given; returns ``done``."""
        if self.done:
            raise RuntimeError("the root search is done: nothing to tell")
        x = self.x
        self._cur, self._fcur = x, _value(fx, x)
        self.evaluations += 1
        self._advance()
        return self.done

    @property
    def best(self) -> tuple[float, float]:
        """(x, f(x)) of the bracket's end with the smaller |f| (the root when done)."""
        return self._cur, self._fcur

    @property
    def bracket(self) -> tuple[float, float, float, float]:
        """(lo, f(lo), hi, f(hi)) of the bracket so far, lo <= hi."""
        a, fa, b, fb = self._cur, self._fcur, self._blk, self._fblk
        return (a, fa, b, fb) if a <= b else (b, fb, a, fa)

    def result(self) -> Root:
        """The outcome so far (final once ``done``)."""
        lo, flo, hi, fhi = self.bracket
        return Root(self._cur, self._fcur, lo, hi, flo, fhi, self.evaluations, self.converged)


def solve(f: Callable[[float], float], a: float, b: float, *, fa: float | None = None, fb: float | None = None,
          xtol: float = 0.0, rtol: float = RTOL, maxiter: int = MAXITER) -> Root:
    """The root of f in [a, b] (module doc: the method, the tolerance, the errors) with its bracket
    and the number of evaluations. ``fa``, ``fb``: f(a), f(b) when the caller has them (not
    evaluated again). RootError when not converged within ``maxiter`` evaluations."""
    n = 0
    if fa is None:
        fa, n = f(a), n + 1
    if fb is None:
        fb, n = f(b), n + 1
    s = RootSearch(a, b, fa, fb, xtol=xtol, rtol=rtol, maxiter=maxiter)
    while not s.done:
        s.tell(f(s.x))
    r = s.result()
    if not r.converged:
        raise RootError(f"no root located to xtol = {xtol:g}, rtol = {rtol:g} in {maxiter} evaluations: the bracket "
                        f"is [{r.lo!r}, {r.hi!r}] (f = {r.f_lo:.6g}, {r.f_hi:.6g})")
    return Root(r.x, r.f, r.lo, r.hi, r.f_lo, r.f_hi, r.evaluations + n, True)


def find_root(f: Callable[[float], float], a: float, b: float, *, fa: float | None = None,
              fb: float | None = None, xtol: float = 0.0, rtol: float = RTOL, maxiter: int = MAXITER) -> float:
    """The root of f in [a, b]: :func:`solve`'s ``x``."""
    return solve(f, a, b, fa=fa, fb=fb, xtol=xtol, rtol=rtol, maxiter=maxiter).x
