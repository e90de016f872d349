"""Continuation of periodic orbits and their bifurcations (dryfriction.analysis.continuation), against
independent references: the closed-form harmonic response without friction, Den Hartog's exact
non-stop solution and its stick condition (the grazing), find_orbits on either side of a located
fold or period doubling, separate FMU runs of the located orbits, and the brute-force numbers of
the Fig. 8/9 band (docs/chaos.md, docs/studies.md)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dryfriction import Oscillator
from dryfriction.analysis.continuation import (PARAMETERS, Continuation, CorrectorFailure, Evaluation,
                                               continue_orbits, correct, get_parameter, set_parameter, tangent)
from dryfriction.drivers.oscillator import OscillatorFMU2, Settings
from dryfriction.analysis.orbits import find_orbits, scales
from dryfriction.references.steady import den_hartog_amplitude

EXACT = Settings(scheme="exact")


def end_state(fmu: OscillatorFMU2, p: Oscillator, x: float, v: float, t1: float) -> np.ndarray:
    """(x, v) at t1 of a separate FMU run (scheme exact) from (x, v) at t = 0."""
    fmu.start(p.with_(x0=x, v0=v), EXACT)
    fmu.step_to(t1)
    y = fmu.get(("x", "v"))
    return np.array([y["x"], y["v"]])


def scaled_gap(p: Oscillator, a: np.ndarray, b: np.ndarray) -> float:
    xs, w = scales(p)
    S = np.array([xs, xs * w])
    return float(np.max(np.abs(a - b) / S) / max(1.0, float(np.max(np.abs(b) / S))))


def branch(c: Continuation, i: int):  # noqa: ANN201 - an xarray Dataset
    return c.dataset.where(c.dataset.branch == i, drop=True)


def of_type(c: Continuation, kind: str) -> list:
    return [b for b in c.bifurcations if b.type == kind]


# ---- the engine, on a problem with a closed form ----------------------------------------------------

class Circle:
    """G(u) = |u|^2 - 1 over u = (y, q): a branch with two folds in q (at q = +-1), for the engine's
    interface; counts its evaluations and derivatives."""

    def __init__(self) -> None:
        self.evaluations = self.derivatives = 0

    def evaluate(self, u: np.ndarray) -> Evaluation:
        self.evaluations += 1
        return Evaluation(np.array(u, dtype=float), np.array([u[0] ** 2 + u[1] ** 2 - 1.0]))

    def derive(self, e: Evaluation, parameter: bool) -> None:
        if e.Gy is None:
            self.derivatives += 1
            e.Gy = np.array([[2.0 * e.u[0]]])
        if parameter and e.Gq is None:
            e.Gq = np.array([2.0 * e.u[1]])

    def norm(self, e: Evaluation) -> float:
        return float(abs(e.G[0]))

    def check(self, u: np.ndarray, du: np.ndarray) -> None:
        if np.max(np.abs(du)) > 10.0:
            raise CorrectorFailure("the corrector diverged")


def test_engine_follows_a_circle_through_both_folds() -> None:
    """Pseudo-arclength steps around the unit circle: the constraint t . (u - u_prev) = ds along the
    unit tangent at u_prev puts the next point sin(dphi) = ds further, so after n steps the angle is
    exactly n asin(ds); every point on the circle to the tolerance; through the folds at q = +-1
    (where a natural continuation in q stops), around once."""
    c = Circle()
    u = np.array([1.0, 0.0])
    e, it = correct(c, u, None, None, 0.0, tol=1e-14, max_iter=8)
    assert it == 0 and c.derivatives == 0            # converged: no derivative asked
    t = tangent(c, e, np.array([0.0, 1.0]))
    assert np.allclose(t, [0.0, 1.0], atol=1e-15)    # the circle's tangent, oriented
    ds = 0.1
    n = int(2.0 * math.pi / math.asin(ds))
    q = []
    for _ in range(n):
        e, _ = correct(c, e.u + ds * t, t, e.u, ds, tol=1e-15, max_iter=8)
        t = tangent(c, e, t)
        assert abs(np.hypot(*e.u) - 1.0) <= 1e-15
        q.append(e.u[1])
    phi = math.atan2(e.u[1], e.u[0]) % (2.0 * math.pi)
    assert abs(phi - n * math.asin(ds)) <= 1e-12
    assert max(q) > 0.998 and min(q) < -0.998         # both folds passed
    assert 2.0 * math.pi - phi < math.asin(ds)        # once around


def test_engine_corrector_at_a_fixed_parameter_and_its_failures() -> None:
    c = Circle()
    e, it = correct(c, np.array([0.9, 0.6]), None, None, 0.0, tol=1e-15, max_iter=8)
    assert e.u[1] == 0.6 and abs(e.u[0] - 0.8) <= 1e-15 and 3 <= it <= 6     # Newton, quadratic
    assert c.derivatives == it and e.Gq is None       # Gy for each Newton step, G_q never
    with pytest.raises(CorrectorFailure, match="no convergence in 2 corrector steps"):
        correct(c, np.array([0.9, 0.6]), None, None, 0.0, tol=1e-15, max_iter=2)
    with pytest.raises(CorrectorFailure, match="singular corrector matrix"):
        correct(c, np.array([0.0, 0.6]), None, None, 0.0, tol=1e-15, max_iter=8)   # dG/dy = 0 there
    with pytest.raises(CorrectorFailure, match="diverged"):
        correct(c, np.array([1e-3, 0.6]), None, None, 0.0, tol=1e-15, max_iter=8)


# ---- the parameters --------------------------------------------------------------------------------

def test_parameters_set_the_fields_they_name() -> None:
    p = Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.6, chi=0.7)
    assert set_parameter(p, "lam", 0.8).lam == pytest.approx(0.8, rel=1e-15)
    assert set_parameter(p, "f", 2.0).omega == pytest.approx(4 * math.pi, rel=1e-15)
    assert set_parameter(p, "mu_s_sigma", 0.3).to_nondimensional()["mu_s_sigma"] == pytest.approx(0.3, rel=1e-15)
    assert set_parameter(p, "mu_k", 0.1).mu_k == pytest.approx(0.1, rel=1e-15)
    assert set_parameter(p, "zeta", 0.02).zeta == pytest.approx(0.02, rel=1e-15)
    for name in PARAMETERS:
        assert get_parameter(set_parameter(p, name, 0.37), name) == pytest.approx(0.37, rel=1e-14), name
    with pytest.raises(ValueError, match="unknown continuation parameter 'q'.*valid: m, k"):
        set_parameter(p, "q", 1.0)
    with pytest.raises(ValueError, match="N"):
        set_parameter(p, "N", -1.0)


def test_bad_arguments_are_one_clear_error(fmu: OscillatorFMU2) -> None:
    p = Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.6, chi=0.7)
    with pytest.raises(ValueError, match="start and stop must differ"):
        continue_orbits(p, "chi", 0.5, 0.5, fmu=fmu)
    with pytest.raises(ValueError, match="unknown continuation parameter"):
        continue_orbits(p, "colour", 0.5, 0.6, fmu=fmu)
    with pytest.raises(ValueError, match="ds_min <= ds <= ds_max"):
        continue_orbits(p, "chi", 0.5, 0.6, ds=2.0, fmu=fmu)
    with pytest.raises(ValueError, match="period must be an integer >= 1"):
        continue_orbits(p, "chi", 0.5, 0.6, period=0, fmu=fmu)
    with pytest.raises(ValueError, match="unknown bifurcation type"):
        continue_orbits(p, "chi", 0.5, 0.6, detect=("hopf",), fmu=fmu)


# ---- no friction: the closed form -------------------------------------------------------------------

def test_no_friction_through_resonance_is_the_closed_form(fmu: OscillatorFMU2) -> None:
    p = Oscillator(m=1.0, k=1.0, c=0.1, N=0.0, P0=1.0, omega=0.5, phi=0.0, mu_s=0.5, chi=1.0)
    c = continue_orbits(p, "omega", 0.5, 1.6, ds=0.05, ds_max=0.2, fmu=fmu)
    ds = c.dataset
    assert [b.stopped.startswith("reached the end of the range at omega = 1.6") for b in c.branches] == [True]
    assert c.bifurcations == []
    assert bool(ds.converged.all()) and bool(ds.stable.all())
    w = ds.param.values
    assert w[0] == 0.5 and w[-1] == pytest.approx(1.6, abs=1e-14) and np.all(np.diff(w) > 0)
    X = p.P0 / np.hypot(p.k - p.m * w ** 2, p.c * w)
    err = np.abs(ds.amplitude_m.values - X) / X
    assert err.max() <= 1e-10, err.max()          # seen 3.5e-12
    assert np.abs(ds.offset_m.values).max() <= 1e-10 * X.max()
    # the multipliers: |mu| = exp(-c T / (2 m)) for the underdamped oscillator
    assert np.abs(ds.mu_max.values - np.exp(-p.c / (2 * p.m) * 2 * np.pi / w)).max() <= 1e-12
    assert ds.point.size >= 20 and X.max() > 9.9    # through the peak (X = 10.01 at w = 0.9975)


# ---- a fold in frequency (stick-slip) -------------------------------------------------------------

FOLD_CASE = Oscillator.from_nondimensional(lam=0.15, mu_s_sigma=0.6, chi=0.7, phi=0.7)


def four_stop_orbit(fmu: OscillatorFMU2):  # noqa: ANN201
    """The four-stop motion of Fig. 11/14 at lambda = 0.15 (coexisting with a two-stop one)."""
    (o,) = [o for o in find_orbits(FOLD_CASE, fmu=fmu) if o.events["transitions"] == 8]
    return o


def test_fold_in_frequency_located_and_reproducible(fmu: OscillatorFMU2) -> None:
    o = four_stop_orbit(fmu)
    found = []
    for ds in (0.02, 0.0137):
        c = continue_orbits(FOLD_CASE, "lam", 0.15, 0.2, ds=ds, ds_max=0.05, orbit=o, max_points=20, fmu=fmu)
        (f,) = of_type(c, "fold")
        assert f.note == "" and f.period == 1
        assert abs(f.multipliers[0] - 1.0) <= 1e-6 and abs(f.multipliers[1]) == 0.0   # a stick phase: rank one
        found.append(f)
        b = branch(c, 0)
        lam = b.param.values
        i = int(np.argmax(lam))
        assert abs(lam[i] - f.param) < 1e-3 and lam.max() <= f.param + 1e-12   # the branch turns back there
        assert bool(b.stable[0]) and not bool(b.stable[-1])                        # stable -> unstable
    assert abs(found[0].param - found[1].param) <= 1e-8, (found[0].param, found[1].param)   # seen 3e-14
    lam_f = found[0].param
    assert lam_f == pytest.approx(0.1725095929, abs=1e-9)
    # independent: find_orbits finds the four-stop motion just below the fold, and not above it
    below = [q for q in find_orbits(FOLD_CASE.with_(omega=(lam_f - 1e-4) * FOLD_CASE.w0), fmu=fmu)
             if q.events["transitions"] == 8]
    above = [q for q in find_orbits(FOLD_CASE.with_(omega=(lam_f + 1e-4) * FOLD_CASE.w0), fmu=fmu,
                                    guesses=[(found[0].x0, found[0].v0)])
             if q.events["transitions"] == 8]
    assert below and below[0].stable and not above
    # the located orbit is periodic: a separate run of one period returns to it
    p_f = FOLD_CASE.with_(omega=lam_f * FOLD_CASE.w0)
    z = np.array([found[0].x0, found[0].v0])
    assert scaled_gap(p_f, end_state(fmu, p_f, *z, p_f.period), z) <= 1e-10


# ---- the Fig. 8/9 band: symmetry breaking, grazing, period doubling and the doubled branch -----------

@pytest.fixture(scope="module")
def band(fmu: OscillatorFMU2) -> Continuation:
    p = Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.6, chi=0.8)
    return continue_orbits(p, "chi", 0.8, 0.22, ds=0.02, ds_max=0.2, fmu=fmu)


def test_fig8_9_symmetry_breaking_against_the_sweep(band: Continuation, fmu: OscillatorFMU2) -> None:
    (sb,) = of_type(band, "symmetry_breaking")
    # the brute-force sweep: symmetric for chi >= 0.56, the mirror pair at 0.54 (Lyapunov scan, steps 0.02)
    assert 0.54 < sb.param < 0.56, sb.param
    assert sb.branch == 0 and band.branches[0].kind == "symmetric"
    assert abs(sb.half_multipliers[np.argmin(np.abs(sb.half_multipliers + 1))] + 1) <= 1e-6   # H's through -1
    assert abs(sb.multipliers[0] - 1.0) <= 1e-6
    a, b = (branch(band, i) for i in sb.children)
    assert int(a.period[0]) == 1 and int(b.period[0]) == 1
    # the mirror pair: one branch's offset is minus the other's at the same chi (chi = 0.22 ends both)
    assert float(a.offset_m[-1]) == pytest.approx(-float(b.offset_m[-1]), rel=1e-9)
    assert abs(float(a.offset_m[-1])) > 1e-3
    # independent: find_orbits just above has one symmetric stable orbit, just below a stable mirror pair
    p = Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.6, chi=sb.param + 2e-3)
    q = Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.6, chi=sb.param - 2e-3)
    up = [o for o in find_orbits(p, fmu=fmu) if o.stable]
    down = [o for o in find_orbits(q, fmu=fmu) if o.stable]
    assert len(up) == 1 and abs(up[0].offset) < 1e-12
    assert len(down) == 2 and down[0].offset == pytest.approx(-down[1].offset, rel=1e-9)


def test_fig8_9_grazing_on_the_asymmetric_branches(band: Continuation, fmu: OscillatorFMU2) -> None:
    g = of_type(band, "grazing")
    assert len(g) == 2 and {x.branch for x in g} == set(of_type(band, "symmetry_breaking")[0].children)
    # both mirror branches: one stop turns into a reversal at the same chi
    assert abs(g[0].param - g[1].param) <= 1e-8
    assert all(x.events == ((4, True), (3, True)) for x in g)
    # independent: find_orbits 1e-6 either side sees the two event counts
    for d, tr in ((1e-6, 4), (-1e-6, 3)):
        p = Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.6, chi=g[0].param + d)
        assert {o.events["transitions"] for o in find_orbits(p, fmu=fmu) if o.stable} == {tr}


def test_fig8_9_period_doubling_and_the_doubled_branch(band: Continuation, fmu: OscillatorFMU2) -> None:
    pd = of_type(band, "period_doubling")
    assert len(pd) == 2                                     # one on each asymmetric branch
    assert abs(pd[0].param - pd[1].param) <= 1e-8
    chi = pd[0].param
    assert abs(chi - 0.2365) <= 0.0005, chi                 # brute force: 0.2365 +- 0.0005 (docs/chaos.md)
    for x in pd:
        assert abs(x.multipliers[0] + 1.0) <= 1e-6 and x.period == 1
        (child,) = x.children
        d = branch(band, child)
        assert int(d.period[0]) == 2 and bool(d.converged.all())
        # the doubled branch exists on the side below the period doubling, stable there
        assert float(d.param.min()) < chi - 0.01 and float(d.param.max()) <= chi + 1e-6
        i = int(np.argmin(d.param.values))
        assert bool(d.stable[i])
        # a true 2-period orbit: a separate run of 2 periods returns, one period does not
        p = Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.6, chi=float(d.param[i]))
        z = np.array([float(d.x0[i]), float(d.v0[i])])
        assert scaled_gap(p, end_state(fmu, p, *z, 2 * p.period), z) <= 1e-10
        assert scaled_gap(p, end_state(fmu, p, *z, p.period), z) > 1e-2
    # chi = 0.22: the doubled branch's multiplier is find_orbits' period-2 one (0.704)
    p = Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.6, chi=0.22)
    ref = [o for o in find_orbits(p, period=2, fmu=fmu) if o.stable and o.period == 2]
    end = branch(band, pd[0].children[0])
    assert float(end.param[-1]) == pytest.approx(0.22, abs=1e-14)
    assert ref and float(end.mu_max[-1]) == pytest.approx(ref[0].mu_max, abs=1e-8)
    # independent: the period-1 orbit is stable above the located point and unstable below
    for d, stable in ((1e-4, True), (-1e-4, False)):
        q = Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.6, chi=chi + d)
        o = find_orbits(q, fmu=fmu, guesses=[(pd[0].x0, pd[0].v0)])
        asym = [x for x in o if x.period == 1 and abs(x.offset) > 1e-3]
        assert asym and all(x.stable is stable for x in asym), (d, [(x.stable, x.multipliers) for x in asym])


def test_every_point_is_converged_or_says_why(band: Continuation) -> None:
    ds = band.dataset
    assert bool(ds.converged.all())
    assert all(b.stopped.startswith("reached the end of the range at chi = 0.22") for b in band.branches)
    assert set(np.unique(ds.branch.values)) == {b.id for b in band.branches}
    for name in ("param", "x0", "v0", "amplitude_m", "offset_m", "stick_fraction", "mu_max", "multiplier_re",
                 "multiplier_im", "stable", "branch", "period"):
        assert name in ds
    assert ds.residual.max() <= 1e-11
    # the located orbits are points of their branches, marked with their type
    marked = ds.where(ds.bifurcation != "", drop=True)
    assert sorted(str(v) for v in marked.bifurcation.values) == sorted(b.type for b in band.bifurcations)
    pd = marked.where(marked.bifurcation == "period_doubling", drop=True)
    assert np.all(np.abs(pd.multiplier_re.values[:, 0] + 1.0) <= 1e-6) and not bool(pd.stable.any())


def test_a_branch_that_ends_early_says_why(fmu: OscillatorFMU2) -> None:
    """Past the fold of the four-stop motion the unstable branch runs into a tangential breakaway
    (its multiplier grows without bound near lambda = 0.1648): the step shrinks below ds_min and the
    continuation says so, with one not-converged point."""
    c = continue_orbits(FOLD_CASE, "lam", 0.15, 0.2, ds=0.02, ds_max=0.05, orbit=four_stop_orbit(fmu),
                        max_points=400, fmu=fmu)
    (b,) = c.branches
    assert b.stopped.startswith("the step fell below ds_min") or b.stopped.startswith("max_points")
    ds = c.dataset
    if b.stopped.startswith("the step fell"):
        assert not bool(ds.converged[-1]) and str(ds.reason[-1]) != ""
        assert bool(ds.converged[:-1].all())
    assert float(ds.mu_max.max()) > 100


# ---- grazing: the stick phase appears (Den Hartog's stick condition) ---------------------------------

def test_grazing_where_den_hartog_stops_holding(fmu: OscillatorFMU2) -> None:
    """Undamped, mu_s = mu_k, lambda = 0.8, continued in mu_s sigma = mu_s N / P0: Den Hartog's
    non-stop solution holds while k X lambda^2 > mu_s N; it ends where f = mu_s sigma solves
    X k / P0 = sqrt(V^2 - f^2 U^2) = f / lambda^2, f* = |V| / sqrt(U^2 + lambda^-4)."""
    r = 0.8
    p = Oscillator.from_nondimensional(lam=r, mu_s_sigma=0.3, chi=1.0)
    V, U = 1.0 / (1.0 - r * r), math.tan(math.pi / (2 * r)) / r
    f_star = abs(V) / math.sqrt(U * U + r ** -4)
    c = continue_orbits(p, "mu_s_sigma", 0.3, 0.9, ds=0.05, fmu=fmu)
    (g,) = of_type(c, "grazing")
    assert abs(g.param - f_star) <= 1e-8, (g.param, f_star)    # seen 5.6e-11
    assert g.events == ((2, False), (4, True))
    ds = c.dataset
    nonstop = ds.where(ds.stick_fraction == 0, drop=True)
    assert float(nonstop.param.max()) < f_star < float(ds.where(ds.stick_fraction > 0, drop=True).param.min())
    for q, a in zip(nonstop.param.values, nonstop.amplitude_m.values):
        ref = float(den_hartog_amplitude(Oscillator.from_nondimensional(lam=r, mu_s_sigma=float(q), chi=1.0)))
        assert abs(a - ref) <= 1e-10 * ref, (q, a, ref)        # seen up to 4e-13
    # the orbit just below: at its turning points (v = 0) the net applied force P(t) - k x, which is
    # k X lambda^2 there, touches the static limit mu_s N
    pg = Oscillator.from_nondimensional(lam=r, mu_s_sigma=g.param - 1e-9, chi=1.0)
    (o,) = find_orbits(pg, fmu=fmu)
    assert o.stick_fraction == 0.0
    assert abs(pg.k * o.amplitude * r * r - pg.mu_s * pg.N) <= 1e-7 * pg.P0


def test_down_to_the_edge_of_the_valid_range(fmu: OscillatorFMU2) -> None:
    """The README's block at 10 Hz continued in N from 20 N down to 0 (the edge of N's valid range):
    the branch ends exactly at N = 0 on the closed-form harmonic response, and starts on find_orbits'
    orbit (0.2356 m, the transient method's number)."""
    block = Oscillator.physical(m=0.5, k=2000, zeta=0.003, P0=10, f=10, N=20, mu_s=0.3, mu_k=0.2)
    c = continue_orbits(block, "N", 20.0, 0.0, fmu=fmu)
    (b,) = c.branches
    assert b.stopped == "reached the end of the range at N = 0"
    ds = c.dataset
    assert bool(ds.converged.all()) and float(ds.param[-1]) == 0.0
    (o,) = find_orbits(block, fmu=fmu)
    assert float(ds.amplitude_m[0]) == pytest.approx(o.amplitude, rel=1e-10)
    assert o.amplitude == pytest.approx(0.2356, abs=5e-5)
    w = block.omega
    X = block.P0 / math.hypot(block.k - block.m * w * w, block.c * w)
    assert abs(float(ds.amplitude_m[-1]) - X) <= 1e-10 * X, (float(ds.amplitude_m[-1]), X)
    assert float(ds.stick_fraction[0]) == 0.0 and np.all(np.diff(ds.amplitude_m.values) > 0)


def test_a_block_at_rest_is_not_a_branch(fmu: OscillatorFMU2) -> None:
    """P0 below the breakaway force (mu_s sigma 1.2): find_orbits gives the block at rest (one of an
    interval of rest positions, a multiplier exactly 1); the continuation does not start from it as
    from a fold (not 'the start orbit is at a fold in the parameter'): its branch says it is
    the block at rest and gives the interval, and the Dataset's flags are bools even when empty."""
    p = Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=1.2, chi=1.0, zeta=0.05)
    c = continue_orbits(p, "mu_s_sigma", 1.2, 0.8, fmu=fmu)
    (b,) = c.branches
    assert b.stopped.startswith("could not start: the start orbit is the block at rest, one of the interval of "
                                "rest positions [-0.002, 0.002] m"), b.stopped
    assert c.dataset.sizes["point"] == 0
    assert c.dataset["stable"].dtype == bool and c.dataset["converged"].dtype == bool
