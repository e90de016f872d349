"""Self-excited motion on a belt (dryfriction.analysis.self_excited): periodic orbits of the autonomous system
(T an unknown), steady sliding's stability, the Hopf belt speed located from the model, the branch
in v_belt; against independent references that use none of the FMU's code:

- the closed-form stick-slip limit cycle of the undamped, unforced Coulomb belt oscillator
  (belt_reference.limit_cycle): period, extremes, stick time, to the located scheme's second order;
- a long transient of the event-driven reference (belt_reference.simulate, DOP853 at rtol 1e-12):
  the damped Coulomb orbit's period, amplitude and stick share; the branch's end (stick-slip just
  below the grazing speed, decay just above it);
- the Hopf formula v* = v_s ln(N (mu_s - mu_k) / (c v_s)) (Stribeck, delta = 1);
- the section map of the sliding motion integrated here by scipy (DOP853, event x = x_eq): the
  fixed point, the period and the multiplier by a central difference of that map.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from dryfriction.references.belt import Belt, limit_cycle, simulate
from dryfriction.errors import FMUError
from dryfriction.drivers.oscillator import OscillatorFMU2
from dryfriction.params import Oscillator
from dryfriction.analysis.self_excited import (BeltProblem, Branch, continue_orbits, equilibrium, find_orbit, hopf_formula,
                                      locate_hopf, self_excited)
from refcache import RefCache

MU_S, CHI = 0.5, 0.6                       # mu_k = 0.3
UNDAMPED = Oscillator(m=1.0, k=1.0, c=0.0, P0=0.0, omega=0.0, N=1.0, mu_s=MU_S, chi=CHI, x0=0.0, v0=0.0)
DAMPED = UNDAMPED.with_(c=0.05)
STRIB = UNDAMPED.with_(c=0.1)              # with v_s = 0.1: v* = 0.1 ln(20) = 0.29957
V_S = 0.1


def stribeck(vb: float, **kw: float) -> BeltProblem:
    return BeltProblem(STRIB, vb, law="stribeck", v_s=V_S, delta=1.0, **kw)


# ---- undamped Coulomb: the closed-form limit cycle -------------------------------------------------

def test_undamped_coulomb_orbit_is_the_closed_form_limit_cycle_second_order(fmu: OscillatorFMU2) -> None:
    lc = limit_cycle(1.0, 1.0, 1.0, MU_S, 0.3, 0.2)
    errs = []
    for h in (2e-3, 1e-3):
        r = self_excited(BeltProblem(UNDAMPED, 0.2, h=h), fmu=fmu)
        o = r.orbit
        assert r.motion == "stick-slip" and o is not None and o.converged and o.stable
        assert o.residual <= 1e-10 and o.transitions == 2
        assert o.multipliers[1] == 0.0 and abs(o.multipliers[0] - 1.0) < 1e-5    # rank one: exactly 0
        assert o.x_eq == pytest.approx(0.3, abs=1e-15)
        # the extremes are sampled at the steps' ends: within |a| h^2 / 2 of the turning points (|a| = 0.28
        # there), no clean order (measured 9.9e-9 / 2.0e-8 at x_max)
        assert abs(o.x_max - lc.x_max) < 0.15 * h * h and abs(o.x_min - lc.x_min) < 0.15 * h * h
        errs.append((abs(o.period - lc.period), abs(o.stick_fraction * o.period - lc.t_stick)))
        # the centre of the undamped slide is neutral, neither stable nor unstable
        assert r.equilibrium.neutral and not r.equilibrium.stable
    # measured: period 2.16e-6 / 5.40e-7 (ratio 4.00); stick time 1.2e-9 / 1.5e-10
    (p1, s1), (p2, s2) = errs
    assert p2 < 1e-6 and 4.0 / 1.15 < p1 / p2 < 4.0 * 1.15, errs
    assert s1 < 1e-8 and s2 < 1e-8, errs


def test_belt_backwards_is_the_mirror_image(fmu: OscillatorFMU2) -> None:
    a = self_excited(BeltProblem(DAMPED, 0.2), fmu=fmu).orbit
    b = self_excited(BeltProblem(DAMPED, -0.2), fmu=fmu).orbit
    assert a is not None and b is not None and a.converged and b.converged
    assert b.v0 > 0 > a.v0
    assert b.period == pytest.approx(a.period, rel=1e-9)
    assert b.x_max == pytest.approx(-a.x_min, rel=1e-9) and b.x_min == pytest.approx(-a.x_max, rel=1e-9)
    assert b.stick_fraction == pytest.approx(a.stick_fraction, abs=1e-9)


def test_exact_scheme_on_the_closed_form_cycle(fmu: OscillatorFMU2) -> None:
    """With scheme exact the Jacobian is the FMU's sensitivity: the cycle to 1e-12, when the FMU's
    exact scheme runs on a moving belt; this FMU's refusal otherwise is a readable error."""
    lc = limit_cycle(1.0, 1.0, 1.0, MU_S, 0.3, 0.2)
    prob = BeltProblem(UNDAMPED, 0.2, scheme="exact")
    try:
        r = self_excited(prob, fmu=fmu)
    except FMUError as e:
        assert "scheme exact supports v_belt = 0 only" in str(e)
        pytest.skip("this FMU's exact scheme refuses a moving belt")
    o = r.orbit
    assert o is not None and o.converged and o.jacobian == "sensitivity"
    assert abs(o.period - lc.period) < 1e-12 * lc.period
    assert abs(o.x_max - lc.x_max) < 1e-12 and abs(o.x_min - lc.x_min) < 1e-12
    assert abs(o.stick_fraction * o.period - lc.t_stick) < 1e-11
    assert o.multipliers[1] == 0.0


@pytest.mark.slow
def test_exact_scheme_damped_orbit_against_the_reference(fmu: OscillatorFMU2, refcache: RefCache) -> None:
    """Damped Coulomb with scheme exact (where the FMU has it on a belt): the reference's period to
    1e-9 (measured 6.5849654 both), against the located one's 5.7e-6."""
    prob = BeltProblem(DAMPED, 0.2, scheme="exact")
    try:
        o = find_orbit(prob, -0.26, 6.6, fmu=fmu)
    except FMUError as e:
        assert "scheme exact supports v_belt = 0 only" in str(e)
        pytest.skip("this FMU's exact scheme refuses a moving belt")
    belt = Belt(m=1.0, k=1.0, c=0.05, N=1.0, mu_s=MU_S, mu_k=0.3, x0=prob.x_eq, v0=0.2)
    ref = refcache.call(simulate, belt, np.arange(0.0, 60.0, 1e-3), v_belt=0.2)
    br = ref.times("breakaway")
    assert o.converged and o.jacobian == "sensitivity" and o.multipliers[1] == 0.0
    assert abs(o.period - (br[-1] - br[-2])) < 1e-9 * o.period


# ---- damped Coulomb against a long transient of the reference ---------------------------------------

def test_damped_coulomb_orbit_against_a_long_reference_transient(fmu: OscillatorFMU2, refcache: RefCache) -> None:
    prob = BeltProblem(DAMPED, 0.2)
    r = self_excited(prob, fmu=fmu)
    o = r.orbit
    assert r.motion == "stick-slip" and o is not None and o.stable and o.multipliers[1] == 0.0
    belt = Belt(m=1.0, k=1.0, c=0.05, N=1.0, mu_s=MU_S, mu_k=0.3, x0=prob.x_eq, v0=0.2)
    ref = refcache.call(simulate, belt, np.arange(0.0, 60.0, 1e-3), v_belt=0.2)
    br, st = ref.times("breakaway"), ref.times("stop")
    T = br[-1] - br[-2]
    assert np.ptp(np.diff(br)[-4:]) < 1e-9                 # the reference is on its cycle
    i = (ref.t >= br[-2]) & (ref.t <= br[-1])
    amp = (ref.x[i].max() - ref.x[i].min()) / 2.0
    stick = (br[-1] - st[st < br[-1]][-1]) / T
    # measured at h = T0 / 2000: period 5.7e-6 (8.6e-7 relative), amplitude 5.0e-8, stick share 1.4e-7
    assert abs(o.period - T) < 2e-6 * T
    assert abs(o.amplitude - amp) < 5e-7
    assert abs(o.stick_fraction - stick) < 1e-6
    # the damped slide is stable here (Coulomb: no falling friction)
    assert r.equilibrium.stable and r.equilibrium.growth_rate == pytest.approx(-0.025, rel=1e-4)


def test_slow_belt_long_stick_phases(fmu: OscillatorFMU2, refcache: RefCache) -> None:
    """v_belt = 1e-3: stuck 99 % of a 388 s cycle (the guess's transient covers five such cycles)."""
    prob = BeltProblem(DAMPED, 1e-3)
    o = self_excited(prob, fmu=fmu).orbit
    assert o is not None and o.converged and o.stick_fraction > 0.99
    belt = Belt(m=1.0, k=1.0, c=0.05, N=1.0, mu_s=MU_S, mu_k=0.3, x0=prob.x_eq, v0=1e-3)
    ref = refcache.call(simulate, belt, np.arange(0.0, 1300.0, 0.05), v_belt=1e-3)
    br = ref.times("breakaway")
    assert br.size >= 3 and abs(br[-1] - br[-2] - (br[-2] - br[-3])) < 1e-8
    # measured 9.8e-8 relative
    assert abs(o.period - (br[-1] - br[-2])) < 1e-6 * o.period


# ---- Stribeck: the Hopf, stability, multipliers -------------------------------------------------------

def test_stribeck_below_and_above_the_hopf(fmu: OscillatorFMU2) -> None:
    vs = hopf_formula(stribeck(0.2))
    assert vs == pytest.approx(0.1 * math.log(20.0), rel=1e-15)
    low = self_excited(stribeck(0.8 * vs), fmu=fmu)
    assert low.motion == "stick-slip" and low.orbit is not None and low.orbit.stable
    assert not low.equilibrium.stable and low.equilibrium.growth_rate > 0
    # above v* steady sliding is stable; the stick-slip orbit still coexists with it up to the grazing
    # speed (the Hopf is subcritical): far above, only steady sliding
    mid = self_excited(stribeck(1.2 * vs), fmu=fmu)
    assert mid.equilibrium.stable and mid.motion == "stick-slip"
    high = self_excited(stribeck(3.0 * vs), fmu=fmu)
    assert high.motion == "steady sliding" and high.orbit is None and high.equilibrium.stable
    # the equilibrium's multipliers over one natural period: |mu| = exp(-(c + N mu'(v_belt)) tau / (2 m)),
    # to second order in h (measured relative errors 4.39e-7, 1.10e-7 at h = 2e-3, 1e-3)
    c_eff = 0.1 - (MU_S - 0.3) / V_S * math.exp(-3.0 * vs / V_S)
    e = [equilibrium(stribeck(3.0 * vs, h=h), fmu=fmu) for h in (2e-3, 1e-3)]
    err = [abs(q.mu_max / math.exp(-c_eff / 2.0 * q.tau) - 1.0) for q in e]
    assert err[1] < 2e-7 and 4.0 / 1.15 < err[0] / err[1] < 4.0 * 1.15, err


def test_hopf_located_from_the_model(fmu: OscillatorFMU2) -> None:
    # measured relative errors: 3.2e-9 at h = T0 / 2000 (3.1e-3), 7.0e-10 at 2e-3, 1.4e-11 at 1e-3 (the
    # differences' floor about 1e-10 at finer steps); the frequency there is w0 = 1 (c + N mu' = 0: undamped), to the
    # scheme's second order (measured -1.08e-6, -4.38e-7, -1.10e-7)
    for h, tol, ftol in ((None, 2e-8, 2e-6), (1e-3, 2e-9, 2e-7)):
        hp = locate_hopf(stribeck(0.2, h=h), 0.05, 1.0, fmu=fmu)
        assert hp.bracket[0] < hp.formula < hp.bracket[1]
        assert hp.relative_error < tol, (h, hp)
        assert abs(hp.frequency - 1.0) < ftol and np.all(np.abs(np.abs(hp.multipliers) - 1.0) < 1e-8)
        assert hp.multipliers[0] == np.conj(hp.multipliers[1]) and abs(hp.multipliers[0].imag) > 0.99
    with pytest.raises(RuntimeError, match="does not change stability"):
        locate_hopf(stribeck(0.2), 0.4, 1.0, fmu=fmu)


def _reference_section_map(vb: float, xe: float, v0: float) -> tuple[float, float]:
    """(v, t) at the next crossing of x = x_eq downwards: the sliding motion integrated here (it must
    not reach the belt's speed)."""
    b = Belt(m=1.0, k=1.0, c=0.1, N=1.0, mu_s=MU_S, mu_k=0.3, law="stribeck", v_s=V_S)

    def rhs(t: float, y: np.ndarray) -> list[float]:
        assert y[1] < vb
        return [y[1], -0.1 * y[1] - y[0] + b.mu(vb - y[1])]

    def cross(t: float, y: np.ndarray) -> float:
        return y[0] - xe
    cross.direction = -1  # type: ignore[attr-defined]
    sol = solve_ivp(rhs, (0.0, 9.0), [xe, v0], method="DOP853", rtol=1e-13, atol=1e-14, events=cross)
    k = next(i for i, t in enumerate(sol.t_events[0]) if t > 1.0)
    return float(sol.y_events[0][k][1]), float(sol.t_events[0][k])


def test_unstable_slip_orbit_and_its_multiplier_against_the_reference_map(fmu: OscillatorFMU2) -> None:
    """Above v* the orbit that never sticks is unstable (subcritical Hopf): Newton finds it all the same;
    its period, section velocity and nontrivial multiplier against the reference's section map."""
    prob = stribeck(0.45)
    o = find_orbit(prob, -0.385, 6.3, fmu=fmu)
    assert o.converged and o.stick_fraction == 0.0 and not o.stable
    xe = prob.x_eq
    v_ref = brentq(lambda v: _reference_section_map(0.45, xe, v)[0] - v, -0.40, -0.37, xtol=1e-14)
    T_ref = _reference_section_map(0.45, xe, v_ref)[1]
    d = 1e-6
    lam = (_reference_section_map(0.45, xe, v_ref + d)[0] - _reference_section_map(0.45, xe, v_ref - d)[0]) / (2 * d)
    # measured: lam 2.2340856 (reference) against 2.2340827; period 6.6e-6, v0 4.2e-8
    assert lam > 1.0
    assert abs(o.multipliers[1] - lam) < 1e-5 * lam
    assert abs(o.section_multiplier - lam) < 1e-5 * lam
    assert abs(o.multipliers[0] - 1.0) < 1e-5                # the trivial one
    assert abs(o.period - T_ref) < 2e-6 * T_ref and abs(o.v0 - v_ref) < 1e-6


# ---- the branch in v_belt -----------------------------------------------------------------------------

@pytest.fixture(scope="module")
def branch(fmu: OscillatorFMU2) -> tuple[Branch, float]:
    vs = hopf_formula(stribeck(0.2))
    return continue_orbits(stribeck(0.2), 0.5 * vs, 0.05, 2.0, fmu=fmu), vs


def test_branch_stick_slip_leg_turns_at_the_grazing_and_ends_at_the_hopf(branch: tuple[Branch, float]) -> None:
    br, vs = branch
    a = br.arrays()
    stick = a["stick_fraction"] > 0
    k = int(np.argmax(a["v_belt"]))
    # stick-slip up to the turning point, stable (multiplier 0); then orbits that never stick, unstable
    assert stick[: k + 1].all() and not stick[k + 1:].any()
    assert np.all(a["stable"][stick] == 1) and np.all(a["mu_nontrivial"][stick] == 0.0)
    assert np.all(a["mu_nontrivial"][~stick] > 1.0) and np.all(a["stable"][~stick] == 0)
    assert np.all(np.diff(a["v_belt"][: k + 1]) > 0) and np.all(np.diff(a["v_belt"][k + 1:]) < 0)
    # the legs meet: the grazing speed from either side (measured 0.6025172 and 0.6025163)
    assert br.turning_points == [br.grazing]
    assert abs(a["v_belt"][k + 1] - br.grazing) < 1e-5 and a["stick_fraction"][k] < 0.01
    # the slip leg shrinks onto the equilibrium at the Hopf, above v* (subcritical)
    assert a["amplitude"][-1] < 0.011 and 0 < a["v_belt"][-1] - vs < 1e-3
    assert abs(br.hopf - vs) < 2e-8 * vs


@pytest.mark.slow
def test_branch_end_against_reference_transients(branch: tuple[Branch, float], refcache: RefCache) -> None:
    """Just below the grazing speed the motion from riding on the belt stays stick-slip; just above it
    it decays (the reference: event-driven, none of the FMU's code)."""
    br, _ = branch
    for fac, sticks in ((0.995, True), (1.005, False)):
        vb = fac * br.grazing
        prob = stribeck(vb)
        belt = Belt(m=1.0, k=1.0, c=0.1, N=1.0, mu_s=MU_S, mu_k=0.3, law="stribeck", v_s=V_S, x0=prob.x_eq, v0=vb)
        ref = refcache.call(simulate, belt, np.arange(0.0, 120.0, 0.01), v_belt=vb)
        stops = ref.times("stop")
        late = ref.t > 90.0
        if sticks:
            assert stops.size > 15 and stops[-1] > 110.0
            assert np.ptp(ref.x[late]) / 2 > 0.6
        else:
            assert stops.size == 0
            assert np.ptp(ref.x[late]) / 2 < 0.05


@pytest.mark.slow
def test_coulomb_branch_ends_at_its_grazing(fmu: OscillatorFMU2, refcache: RefCache) -> None:
    """Damped Coulomb: no Hopf (steady sliding is stable at every speed), no slip orbits; the stick-slip
    leg ends where its catch of the belt grazes, with a stick phase still there (measured v_g =
    0.3322743, stick share 0.095); the reference from the belt: stick-slip at 0.995 v_g, decay at 1.005."""
    br = continue_orbits(BeltProblem(DAMPED, 0.1), 0.1, 0.01, 2.0, fmu=fmu)
    a = br.arrays()
    assert np.all(a["stick_fraction"] > 0.09) and np.all(a["stable"] == 1) and np.all(np.diff(a["v_belt"]) > 0)
    assert br.turning_points == [] and math.isnan(br.hopf) and "no slip leg" in br.end
    assert br.grazing == a["v_belt"][-1] and 0.33 < br.grazing < 0.335
    for fac, sticks in ((0.995, True), (1.005, False)):
        vb = fac * br.grazing
        belt = Belt(m=1.0, k=1.0, c=0.05, N=1.0, mu_s=MU_S, mu_k=0.3, x0=BeltProblem(DAMPED, vb).x_eq, v0=vb)
        ref = refcache.call(simulate, belt, np.arange(0.0, 120.0, 0.01), v_belt=vb)
        stops = ref.times("stop")
        assert (stops.size > 15 and stops[-1] > 105.0) if sticks else stops.size == 0


# ---- input errors -----------------------------------------------------------------------------------

@pytest.mark.parametrize("kw, match", [
    (dict(oscillator=UNDAMPED.with_(P0=1.0, omega=2.0)), "needs no excitation"),
    (dict(v_belt=0.0), "v_belt .* must be nonzero"),
    (dict(v_belt=math.nan), "v_belt must be a finite"),
    (dict(law="viscous"), "law .* must be one of coulomb, stribeck"),
    (dict(law="stribeck", delta=0.5), "delta .* must be >= 1"),
    (dict(law="stribeck", v_s=0.0), "v_s .* must be > 0"),
    (dict(law="stribeck", scheme="exact"), "scheme exact supports law coulomb only"),
    (dict(scheme="paper"), "scheme must be one of located, exact"),
    (dict(h=-1e-3), "h .* must be > 0"),
    (dict(oscillator=UNDAMPED.with_(k=0.0)), "k .* must be > 0"),
])
def test_bad_problems_are_refused_with_a_sentence(kw: dict, match: str) -> None:
    args = dict(oscillator=UNDAMPED, v_belt=0.2)
    args.update(kw)
    with pytest.raises(ValueError, match=match):
        BeltProblem(**args)


def test_constant_force_shifts_the_orbit(fmu: OscillatorFMU2) -> None:
    """F_ext (or P0 with omega = 0) moves the equilibrium and the cycle by F / k, nothing else."""
    a = self_excited(BeltProblem(DAMPED, 0.2), fmu=fmu).orbit
    b = self_excited(BeltProblem(DAMPED, 0.2, F_ext=0.7), fmu=fmu).orbit
    c = self_excited(BeltProblem(DAMPED.with_(P0=0.35, phi=math.pi / 3), 0.2), fmu=fmu).orbit
    assert a is not None and b is not None and c is not None
    assert b.period == pytest.approx(a.period, rel=1e-9) and c.period == pytest.approx(a.period, rel=1e-9)
    assert b.offset - a.offset == pytest.approx(0.7, abs=1e-8)
    assert c.offset - a.offset == pytest.approx(0.35 * 0.5, abs=1e-8)
    assert equilibrium(BeltProblem(DAMPED, 0.2, F_ext=0.7), fmu=fmu).x_eq == pytest.approx(1.0, abs=1e-15)
