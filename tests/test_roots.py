"""The one root finder (dryfriction.roots): known roots, the tolerance convention, the bracket's
edges, discontinuous and flat functions, the errors, the caller-driven form, the evaluations
counted, and the same iterates as SciPy's brentq (which the callers used before)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dryfriction.roots import RTOL, BracketError, RootError, RootSearch, find_root, solve

EPS = float(np.finfo(float).eps)


class Counted:
    """f with its calls counted independently of the finder."""

    def __init__(self, f):
        self.f, self.calls, self.xs = f, 0, []

    def __call__(self, x: float) -> float:
        self.calls += 1
        self.xs.append(x)
        return self.f(x)


def bisections(width: float, tol: float) -> int:
    """Halvings of bisection from ``width`` to below ``tol``."""
    return math.ceil(math.log2(width / tol))


@pytest.mark.parametrize("f, a, b, root", [
    (lambda x: x * x - 2.0, 0.0, 2.0, math.sqrt(2.0)),
    (lambda x: x ** 3 - 2.0 * x - 5.0, 2.0, 3.0, 2.0945514815423265),        # Wallis's cubic
    (lambda x: (x - 1.0) * (x - 2.0) * (x - 3.0), 1.5, 2.7, 2.0),
    (lambda x: math.cos(x) - x, 0.0, 1.0, 0.7390851332151607),               # the Dottie number
    (lambda x: 1e-30 * (x - 0.25), 0.0, 1.0, 0.25),                          # tiny values
    (lambda x: 1e-200 * (x - 0.3), 0.0, 1.0, 0.3),      # f(a) f(b) underflows to 0: the signs still count
    (lambda x: 1e300 * (x - 0.125) + 1e299 * (x - 0.125) ** 2, -1.0, 1.0, 0.125),  # huge values: no overflow
])
def test_known_roots_to_the_tolerance(f, a, b, root):
    c = Counted(f)
    r = solve(c, a, b)
    assert r.converged
    assert abs(r.x - root) <= 4.0 * RTOL * abs(root)
    # the convention: the returned root is an end of the last bracket, the bracket holds the sign
    # change and is narrower than xtol + rtol |x|
    assert r.x in (r.lo, r.hi) and r.f == f(r.x)
    assert r.f_lo == 0.0 or r.f_hi == 0.0 or (r.f_lo < 0) != (r.f_hi < 0)
    assert r.f == 0.0 or r.hi - r.lo < RTOL * abs(r.x) or math.nextafter(r.lo, math.inf) == r.hi
    assert r.evaluations == c.calls
    # superlinear on a smooth simple root: 3 to 18 evaluations here, where bisection needs 50 to 60
    assert 2 * r.evaluations <= 40 < bisections(abs(b - a), RTOL * abs(root))
    assert find_root(f, a, b) == r.x


def test_absolute_tolerance_for_a_root_at_zero():
    # rtol |x| vanishes at 0: xtol gives the bracket's width there
    r = solve(lambda x: math.sin(x) + 1e-3 * x, -1.0, 2.0, xtol=1e-9, rtol=0.0)
    assert abs(r.x) <= 1e-9 and r.hi - r.lo < 1e-9 and r.lo <= 0.0 <= r.hi


def test_loose_tolerance_stops_early():
    tight = solve(lambda x: x ** 3 - 2.0, 0.0, 4.0)
    loose = solve(lambda x: x ** 3 - 2.0, 0.0, 4.0, xtol=1e-3, rtol=0.0)
    assert abs(loose.x - 2.0 ** (1.0 / 3.0)) < 1e-3 and loose.hi - loose.lo < 1e-3
    assert loose.evaluations < tight.evaluations


@pytest.mark.parametrize("which", ["a", "b"])
def test_root_at_a_bracket_end(which):
    f = Counted(lambda x: x - 1.0)
    a, b = (1.0, 3.0) if which == "a" else (-2.0, 1.0)
    r = solve(f, a, b)
    assert r.x == 1.0 and r.f == 0.0 and r.evaluations == 2 == f.calls
    # with f's ends given, no evaluation at all
    r2 = solve(f, a, b, fa=f.f(a), fb=f.f(b))
    assert r2.x == 1.0 and r2.evaluations == 0 and f.calls == 2


def test_given_end_values_are_not_evaluated_again():
    f = Counted(lambda x: math.exp(x) - 2.0)
    r = solve(f, 0.0, 1.0, fa=-1.0, fb=math.e - 2.0)
    assert abs(r.x - math.log(2.0)) <= 2 * RTOL and 0.0 not in f.xs and 1.0 not in f.xs
    assert r.evaluations == f.calls


def test_discontinuous_sign_change():
    # a jump at 1/3 without a zero: the root is the jump, located to the tolerance; the steps are
    # bisections (every interpolation falls outside), so as many as bisection needs, plus at most 2
    jump = 1.0 / 3.0
    f = Counted(lambda x: -1.0 if x < jump else 2.0)
    r = solve(f, 0.0, 1.0, xtol=1e-12, rtol=0.0)
    assert r.lo < jump <= r.hi and r.hi - r.lo < 1e-12 and abs(r.x - jump) < 1e-12
    assert f.calls == r.evaluations <= bisections(1.0, 1e-12) + 2 + 2
    # 1/x crosses from -inf to +inf at 0: a pole is a sign change too (and no NaN on the way)
    p = solve(lambda x: 1.0 / x if x != 0.0 else math.inf, -1.0, 3.0, xtol=1e-10, rtol=0.0)
    assert abs(p.x) < 1e-10


def test_discontinuous_to_rounding():
    # with no tolerance the bracket closes on two neighbouring doubles around the jump
    jump = 0.1
    r = solve(lambda x: -1.0 if x < jump else 1.0, 0.0, 1.0, xtol=0.0, rtol=0.0)
    assert math.nextafter(r.lo, math.inf) == r.hi and r.lo < jump <= r.hi
    assert r.evaluations <= 60


def test_flat_function():
    # (x - 0.3)^9 is below 1e-300 over about 1e-33 either side of its root and has no useful slope
    # for the secant: Brent's bound (at most about k^2, k bisections) holds, and the root is found
    # to the bracket's tolerance
    f = Counted(lambda x: (x - 0.3) ** 9)
    r = solve(f, 0.0, 1.0, xtol=1e-12, rtol=0.0)
    assert abs(r.x - 0.3) < 1e-12 and r.lo <= 0.3 <= r.hi
    k = bisections(1.0, 1e-12)
    assert f.calls == r.evaluations <= k * k
    # f exactly 0 on a whole interval: any point of it is a root, and the search stops at the first
    g = Counted(lambda x: min(0.0, x - 0.4) + max(0.0, x - 0.6))
    r2 = solve(g, 0.0, 1.0)
    assert 0.4 <= r2.x <= 0.6 and r2.f == 0.0 and r2.evaluations <= 4


def test_not_a_bracket():
    with pytest.raises(BracketError, match=r"f\(0.0\) = -2 and f\(1.0\) = -1 have the same sign: "
                                           r"\[0.0, 1.0\] brackets no root"):
        solve(lambda x: x - 2.0, 0.0, 1.0)
    # tiny values of one sign: no product that underflows to 0 and passes for a bracket
    with pytest.raises(BracketError):
        solve(lambda x: 1e-200, 0.0, 1.0)
    with pytest.raises(BracketError):
        RootSearch(0.0, 1.0, -1e-200, -1e-200)
    assert issubclass(BracketError, ValueError)


def test_bad_input_errors():
    with pytest.raises(ValueError, match=r"the function is NaN at x = 0.7\d+: no root can be bracketed there"):
        solve(lambda x: x - 0.75 if x in (0.0, 1.0) else math.nan, 0.0, 1.0)
    with pytest.raises(ValueError, match="finite"):
        solve(lambda x: x, -math.inf, 1.0)
    with pytest.raises(ValueError, match="xtol and rtol"):
        solve(lambda x: x, -1.0, 1.0, xtol=-1.0)
    with pytest.raises(ValueError, match="one point"):
        RootSearch(1.0, 1.0, -1.0, 1.0)


def test_no_convergence_is_an_error():
    with pytest.raises(RootError, match=r"in 3 evaluations: the bracket is \["):
        solve(lambda x: x ** 3 - 2.0, 0.0, 4.0, maxiter=3)
    s = RootSearch(0.0, 4.0, -2.0, 62.0, maxiter=3)
    for _ in range(3):
        s.tell(s.x ** 3 - 2.0)
    r = s.result()
    assert s.done and not r.converged and r.evaluations == 3 and r.lo < 2 ** (1 / 3) < r.hi


def test_caller_driven_search_gives_the_same_points():
    f = Counted(lambda x: math.tanh(10.0 * (x - 0.2)) + 0.01 * x)
    r = solve(f, -1.0, 2.0)
    s = RootSearch(-1.0, 2.0, f.f(-1.0), f.f(2.0))
    xs = []
    widths = []
    while not s.done:
        xs.append(s.x)
        s.tell(f.f(s.x))
        lo, flo, hi, fhi = s.bracket
        assert (flo < 0) != (fhi < 0) or 0.0 in (flo, fhi)
        widths.append(hi - lo)
    assert xs == f.xs[2:] and s.result() == r.__class__(**{**r.__dict__, "evaluations": r.evaluations - 2})
    assert widths == sorted(widths, reverse=True)          # the bracket never widens
    with pytest.raises(RuntimeError, match="done"):
        s.tell(0.0)


def test_same_iterates_as_scipy_brentq():
    """The callers used SciPy's brentq: the same points (and so the same root bits) on smooth,
    steep, one-sided and discontinuous functions, at the callers' tolerances."""
    from scipy.optimize import brentq

    rng = np.random.default_rng(7)
    fams = [
        lambda c: (lambda x: x ** 3 - c),
        lambda c: (lambda x: math.copysign(abs(x - c) ** 0.2, x - c)),
        lambda c: (lambda x: math.tanh(50.0 * (x - c)) + 1e-3 * (x - c)),
        lambda c: (lambda x: math.exp(x) - math.exp(c)),
        lambda c: (lambda x: (1.0 if x > c else -1.0) * (1.0 + abs(x))),
    ]
    n = 0
    for fam in fams:
        for c in rng.uniform(-2.0, 2.0, 40):
            f = fam(float(c))
            for xtol, rtol in ((1e-300, 4 * EPS), (1e-15, 1e-15), (1e-9, 4 * EPS)):
                old = Counted(f)
                x_old = brentq(old, -3.0, 3.5, xtol=xtol, rtol=rtol, maxiter=500)
                new = Counted(f)
                r = solve(new, -3.0, 3.5, xtol=xtol, rtol=rtol)
                assert r.x == x_old and new.xs == old.xs
                n += 1
    assert n == 5 * 40 * 3
