"""The chain's belts (input v_belt[i]) and site springs and dampers (k_site[i], c_site[i]: each
block tied to the ground frame, the Burridge-Knopoff model's springs) through the FMUs: the
located scheme second order against the event-driven reference (dryfriction.references.chain) and,
at n = 1, belt_reference, with belts changed at a communication point; a Burridge-Knopoff chain of
64; bits (a site spring = a wall spring, belts at 0 = none); the step rule; the errors; FMI 3.0 =
FMI 2.0; the belts of a restored FMU state (the Stribeck jerk). And the reference itself with belts and the Stribeck law: n = 1 against belt_reference,
the closed-form limit cycle, energy balances. Numbers in docs/chain.md ("Site springs and
dampers; belts")."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from dryfriction.drivers.chain import ChainFMU2, ChainFMU3
from dryfriction.references.chain import Chain, solve_chain
from dryfriction.errors import FMUCallError
from chain_cases import belt_run as _belt_run
from helpers import assert_rounding_apart

PERIODS = 6

# three blocks, unit masses and couplings, each on a site spring (one without), the middle one
# damped to the ground; friction on every block, chi < 1 and > 1, stick-slip throughout
SITE = Chain.make(3, omega=0.6, k=[1.0, 0.8, 1.2], c=[0.0, 0.05, 0.0], k_end=0.5,
                  k_site=[0.7, 0.0, 1.5], c_site=[0.0, 0.12, 0.03],
                  N=[0.5, 0.4, 0.6], chi=[0.7, 1.3, 0.6], P0=[1.2, 0.0, 0.6], phi=[0.0, 0.0, 0.8],
                  v0=[0.2, 0.0, -0.1])


@pytest.fixture(scope="module")
def ref():
    return solve_chain(SITE, PERIODS * SITE.period)


def _fmu_x(ch: Chain, h: float, t: np.ndarray) -> np.ndarray:
    with ChainFMU3(n=ch.n) as fmu:
        run = fmu.run(t_stop=float(t[-1]), dt=float(t[1] - t[0]), params={**ch.fmu_params(), "h": h})
    assert np.allclose(run.t, t, rtol=0, atol=1e-9)
    return run.x


def test_reference_energy_balance_with_site_terms(ref) -> None:
    """E(t) - E(0) = W_applied + W_friction - D_damping, E with the site springs' energy and D with
    the site dampers' dissipation: the reference's accounts close to 1e-9."""
    r = ref.evaluate(np.linspace(0.0, PERIODS * SITE.period, 2001))
    E = ref.energy(r["x"], r["v"])
    res = E - E[0] - r["W_applied"] - r["W_friction"] + r["D_damping"]
    assert np.max(np.abs(res)) < 1e-9 * max(1.0, np.max(np.abs(r["W_applied"])))
    assert r["D_damping"][-1] > 1e-3  # the site dampers dissipate
    assert len(ref.events) > 20


def test_reference_site_spring_is_a_wall_spring() -> None:
    """One block on k_site = 1.3, c_site = 0.2 (k = c = 0) moves as on the wall spring k = 1.3,
    c = 0.2 (two independent assemblies of K and C)."""
    a = Chain.make(1, omega=0.7, k=0.0, c=0.0, k_site=1.3, c_site=0.2, N=0.6, P0=1.0)
    b = Chain.make(1, omega=0.7, k=1.3, c=0.2, N=0.6, P0=1.0)
    t = np.linspace(0.0, 5 * a.period, 801)
    xa = solve_chain(a, t[-1]).evaluate(t)["x"]
    xb = solve_chain(b, t[-1]).evaluate(t)["x"]
    assert np.max(np.abs(xa - xb)) < 1e-10


def test_located_second_order_with_site_springs(ref) -> None:
    """max |x - x_ref| of the FMU's located scheme over 6 periods falls 4x (3.4 ... 4.6) per
    halving of h from T/400 to T/1600 (measured 3.46e-4, 8.66e-5, 2.17e-5), and is below 4e-5 at
    T/1600."""
    T = SITE.period
    t = np.linspace(0.0, PERIODS * T, PERIODS * 40 + 1)
    xr = ref.evaluate(t)["x"]
    e = np.array([np.max(np.abs(_fmu_x(SITE, T / s, t) - xr)) for s in (400, 800, 1600)])
    ratios = e[:-1] / e[1:]
    assert np.all((ratios > 3.4) & (ratios < 4.6)), (e, ratios)
    assert e[-1] < 4e-5, e


def test_site_spring_equals_wall_spring_bits() -> None:
    """n = 1: the block on k_site (k = 0) is the block on its wall spring k, bit for bit (the same
    diagonal of K and C, the same derived step)."""
    base = dict(N=0.6, P0=1.0, omega=0.7, mu_s=0.5, chi=0.7)
    with ChainFMU3(n=1) as fmu:
        a = fmu.run(t_stop=20.0, dt=0.05, params={**base, "k": 0.0, "c": 0.0, "k_site": 1.3, "c_site": 0.2})
        b = fmu.run(t_stop=20.0, dt=0.05, params={**base, "k": 1.3, "c": 0.2})
    assert np.array_equal(a.x, b.x) and np.array_equal(a.v, b.v) and np.array_equal(a.mode, b.mode)
    assert np.count_nonzero(np.diff(a.mode[:, 0])) > 4  # stick-slip


def test_step_rule_counts_site_springs() -> None:
    """h = 0 derives the step from the Gershgorin bound of M^-1 K with the site springs on the
    diagonal: a stiff site spring (k_site = 1e4 on a unit chain) shortens the step to 1/1000 of
    2 pi / sqrt(max row sum), here 2 pi / sqrt(1e4 + 2 + 2) / 1000 for the middle block."""
    with ChainFMU3(n=3) as fmu:
        fmu.start(params={"k": 1.0, "k_end": 1.0, "k_site": [0.0, 1e4, 0.0], "omega": 0.5, "h": 0.0})
        h = float(fmu.get("h_used"))
        fmu.start(params={"k": 1.0, "k_end": 1.0, "omega": 0.5, "h": 0.0})
        h0 = float(fmu.get("h_used"))
    assert h == pytest.approx(2 * np.pi / np.sqrt(1e4 + 4.0) / 1000, rel=1e-14)
    assert h0 == pytest.approx(2 * np.pi / np.sqrt(4.0) / 1000, rel=1e-14)


@pytest.mark.parametrize("name,value,valid", [("k_site", -1.0, r"in \[0, 1e\+100\]"), ("c_site", -0.5, ">= 0"),
                                              ("k_site", np.inf, "finite"), ("c_site", np.nan, "finite")])
def test_bad_site_values_rejected_by_the_fmu(name: str, value: float, valid: str) -> None:
    """The FMU's sentence names the element and the valid range (set raw: past the Python checks)."""
    with ChainFMU3(n=3) as fmu:
        fmu._begin(0.0)
        with pytest.raises(FMUCallError, match=rf"invalid value {value:g} for {name}\[2\].*valid range: {valid}"):
            fmu.set_raw(name, [0.0, value, 0.0])


def test_bad_site_values_rejected_by_the_driver() -> None:
    with ChainFMU3(n=3) as fmu:
        with pytest.raises(ValueError, match=r"invalid value inf for c_site\[2\]; valid range: finite"):
            fmu.start(params={"c_site": [0.0, np.inf, 0.0]})
        with pytest.raises(ValueError, match=r"k_site needs 3 values"):
            fmu.start(params={"k_site": [1.0, 2.0]})


def test_fmi3_equals_fmi2_with_site_terms(chain_fmu2: Path) -> None:
    with ChainFMU2(fmu_path=chain_fmu2) as f2:
        n = f2.n
        p = dict(k_site=np.linspace(0.3, 1.1, n).tolist(), c_site=[0.05] * n, N=0.5, P0=1.0, omega=0.6)
        r2 = f2.run(t_stop=15.0, dt=0.05, params=p)
    with ChainFMU3(n=n) as f3:
        r3 = f3.run(t_stop=15.0, dt=0.05, params=p)
    assert np.array_equal(r2.x, r3.x) and np.array_equal(r2.v, r3.v) and np.array_equal(r2.mode, r3.mode)
    assert np.count_nonzero(np.diff(r3.mode, axis=0)) > 4


# ---- the reference with belts and the Stribeck law ----------------------------------------------

def _one_block(law: str, vb: float, **kw):
    """The same block as a chain of one (chain_reference) and as belt_reference's Belt."""
    from dryfriction.references.belt import Belt

    p = dict(m=1.0, k=1.0, c=0.05, N=1.0, mu_s=0.5, chi=0.6, P0=0.3, omega=0.7, phi=0.2, x0=0.1, v0=0.0)
    p.update(kw)
    extra = dict(v_s=0.3, delta=1.0) if law == "stribeck" else {}
    ch = Chain.make(1, omega=p["omega"], k=p["k"], c=p["c"], m=p["m"], N=p["N"], mu_s=p["mu_s"], chi=p["chi"],
                    P0=p["P0"], phi=p["phi"], x0=p["x0"], v0=p["v0"], v_belt=vb, law=law, **extra)
    b = Belt(m=p["m"], k=p["k"], c=p["c"], N=p["N"], mu_s=p["mu_s"], mu_k=p["chi"] * p["mu_s"], P0=p["P0"],
             omega=p["omega"], phi=p["phi"], x0=p["x0"], v0=p["v0"], law=law, **extra)
    return ch, b


@pytest.mark.parametrize("law", ["coulomb", "stribeck"])
def test_reference_one_block_equals_belt_reference(law: str) -> None:
    """n = 1 with a belt (0.4 m/s, changed to -0.2 m/s at t = 9 and to 0.25 at 17): the chain's
    reference is belt_reference's (an independent state machine: closed-form stick phases,
    bisected breakaways) within 1e-10 (measured 2.0e-12 in x, 2.3e-12 in v), with stick-slip on
    every belt."""
    from dryfriction.references.belt import simulate

    ch, b = _one_block(law, 0.4)
    changes = [(9.0, -0.2), (17.0, 0.25)]
    t = np.linspace(0.0, 25.0, 2501)
    r = solve_chain(ch, t[-1], belt_changes=[(tc, [vb]) for tc, vb in changes]).evaluate(t)
    br = simulate(b, t, v_belt=0.4, changes=changes)
    assert np.max(np.abs(r["x"][:, 0] - br.x)) < 1e-10
    assert np.max(np.abs(r["v"][:, 0] - br.v)) < 1e-10
    vb = np.where(t < 9.0, 0.4, np.where(t < 17.0, -0.2, 0.25))
    stuck = r["mode"][:, 0] == 0
    assert np.max(np.abs(r["v"][stuck, 0] - vb[stuck])) < 1e-12  # stuck: on the belt
    for a, b_ in ((0.0, 9.0), (9.0, 17.0), (17.0, 25.0)):
        seg = r["mode"][(t > a) & (t < b_), 0]
        assert (seg == 0).any() and (seg != 0).any(), (a, b_)


def test_reference_closed_form_limit_cycle() -> None:
    """The undamped, unforced Coulomb block on a belt at 0.3 m/s from rest at the catch point
    (2 F_k - F_s) / k moving with the belt: period, stick and slip times of the closed form within
    1e-11 over five cycles (measured 4.8e-13), the extremes within 1e-6 (sampled on a grid)."""
    from dryfriction.references.belt import limit_cycle

    lc = limit_cycle(1.0, 2.0, 1.0, 0.5, 0.3, 0.3)
    ch = Chain.make(1, omega=0.0, k=2.0, c=0.0, N=1.0, mu_s=0.5, chi=0.6, P0=0.0, x0=lc.x_stick_start,
                    v0=0.3, v_belt=0.3)
    sol = solve_chain(ch, 5 * lc.period + 0.1)
    brk = [e[0] for e in sol.events if e[2] == 0]
    stop = [e[0] for e in sol.events if e[3] == 0]
    assert len(brk) == 5 and len(stop) >= 5
    assert np.allclose(np.diff(brk), lc.period, rtol=0, atol=1e-11)
    assert brk[0] == pytest.approx(lc.t_stick, abs=1e-11)
    assert stop[0] - brk[0] == pytest.approx(lc.t_slip, abs=1e-11)
    x = sol.evaluate(np.linspace(0.0, 5 * lc.period, 20001))["x"][:, 0]
    assert x.max() == pytest.approx(lc.x_max, abs=1e-6) and x.min() == pytest.approx(lc.x_min, abs=1e-6)


def test_reference_belt_chain_energy_balance() -> None:
    """A Burridge-Knopoff chain (n = 6, site springs, every belt at -0.2 m/s, Stribeck velocity
    weakening; the plate frame): E(t) - E(0) = W_applied + W_friction - D_damping within 1e-9,
    the friction's work including that on the blocks the belts carry, with slip events."""
    ch = Chain.make(6, omega=0.0, k=[0.0] + [2.0] * 5, c=0.02, P0=0.0, k_site=0.5, N=1.0, mu_s=0.6, chi=0.5,
                    x0=np.linspace(-0.3, 0.2, 6), v_belt=-0.2, law="stribeck", v_s=0.1, delta=1.0)
    sol = solve_chain(ch, 40.0)
    r = sol.evaluate(np.linspace(0.0, 40.0, 2001))
    E = sol.energy(r["x"], r["v"])
    res = E - E[0] - r["W_applied"] - r["W_friction"] + r["D_damping"]
    assert np.max(np.abs(res)) < 1e-9 * max(1.0, np.max(np.abs(r["W_friction"])))
    assert len([e for e in sol.events if e[2] == 0]) > 10  # breakaways: slip events


# ---- belts through the FMUs (coulomb) -----------------------------------------------------------

BELT = Chain.make(3, omega=0.6, k=[1.0, 0.8, 1.2], c=[0.0, 0.05, 0.0], k_end=0.5, k_site=[0.7, 0.0, 1.5],
                  N=[0.5, 0.4, 0.6], chi=[0.7, 0.6, 0.6], P0=[0.6, 0.0, 0.3], phi=[0.0, 0.0, 0.8])
VB0, VB1 = [0.3, -0.2, 0.1], [-0.1, 0.25, 0.0]




def test_located_second_order_with_belts() -> None:
    """Belts 0.3, -0.2, 0.1 m/s under three coupled blocks on site springs, changed to -0.1, 0.25,
    0 at the communication point 3T: max |x - x_ref| over 6 periods falls 4x (3.6 ... 4.4) per
    halving of h from T/400 to T/3200 (measured 4.09e-4, 1.03e-4, 2.58e-5, 6.46e-6); stuck
    blocks ride their belts exactly."""
    T = BELT.period
    t = np.linspace(0.0, 6 * T, 241)
    ref = solve_chain(replace(BELT, v_belt=np.array(VB0)), t[-1], belt_changes=[(3 * T, VB1)])
    assert len(ref.events) > 30
    xr = ref.evaluate(t)["x"]
    e = []
    with ChainFMU3(n=3) as fmu:
        for s in (400, 800, 1600, 3200):
            r = _belt_run(fmu, BELT, T / s, t, VB0, {120: VB1})
            e.append(np.max(np.abs(r["x"] - xr)))
    e = np.array(e)
    ratios = e[:-1] / e[1:]
    assert np.all((ratios > 3.6) & (ratios < 4.4)), (e, ratios)
    assert e[-1] < 1e-5, e
    vb = np.where(np.arange(t.size)[:, None] <= 120, VB0, VB1)
    stuck = r["mode"] == 0
    assert stuck.any() and np.array_equal(r["v"][stuck], vb[stuck])


def test_one_block_belt_against_belt_reference() -> None:
    """n = 1, a belt at 0.4 m/s changed to -0.2 at t = 9 (a communication point): the located
    scheme against belt_reference, second order (3.6 ... 4.4 per halving from h = 0.01)."""
    from dryfriction.references.belt import Belt, simulate

    ch = Chain.make(1, omega=0.7, k=1.0, c=0.05, N=1.0, mu_s=0.5, chi=0.6, P0=0.3, phi=0.2, x0=0.1)
    b = Belt(m=1.0, k=1.0, c=0.05, N=1.0, mu_s=0.5, mu_k=0.3, P0=0.3, omega=0.7, phi=0.2, x0=0.1)
    t = np.linspace(0.0, 18.0, 361)
    br = simulate(b, t, v_belt=0.4, changes=[(9.0, -0.2)])
    assert len(br.events) >= 4  # stops, breakaways (one by the belt change while stuck)
    with ChainFMU3(n=1) as fmu:
        e = np.array([np.max(np.abs(_belt_run(fmu, ch, h, t, [0.4], {180: [-0.2]})["x"][:, 0] - br.x))
                      for h in (0.01, 0.005, 0.0025)])
    ratios = e[:-1] / e[1:]
    assert np.all((ratios > 3.6) & (ratios < 4.4)), (e, ratios)


def test_belts_at_rest_are_the_fixed_support_bits() -> None:
    """v_belt set to 0 on every block: the run of a never-set v_belt, bit for bit."""
    p = {**SITE.fmu_params(), "h": SITE.period / 500}
    with ChainFMU3(n=3) as fmu:
        a = fmu.run(t_stop=30.0, dt=0.1, params=p)
        b = fmu.run(t_stop=30.0, dt=0.1, params=p, inputs={"v_belt": [0.0, 0.0, 0.0]})
    assert np.array_equal(a.x, b.x) and np.array_equal(a.v, b.v) and np.array_equal(a.F_friction, b.F_friction)


def test_burridge_knopoff_chain_slips() -> None:
    """n = 64 (unit masses, couplings 2, site springs 0.5, N = 1, mu_s 0.6, mu_k 0.3, every belt at
    -0.2 m/s: the chain in its driver plate's frame, from a random start): slip events throughout,
    stuck blocks exactly on their belts, held forces within their limits, and the chain against
    the event-driven reference over 20 s within 1e-4 at h = 1e-3."""
    rng = np.random.default_rng(7)
    n = 64
    ch = Chain.make(n, omega=0.0, k=[0.0] + [2.0] * (n - 1), c=0.0, c_site=0.01, P0=0.0, k_site=0.5, N=1.0,
                    mu_s=0.6, chi=0.5, x0=rng.uniform(-0.6, 0.6, n))
    t = np.linspace(0.0, 20.0, 201)
    with ChainFMU3(n=n) as fmu:
        r = _belt_run(fmu, ch, 1e-3, t, [-0.2] * n, {})
    stuck = r["mode"] == 0
    assert np.all(r["v"][stuck] == -0.2)
    assert np.all(np.abs(r["F_friction"][stuck]) <= 0.6 + 1e-12)
    slips = np.count_nonzero((r["mode"][1:] != 0) & (r["mode"][:-1] == 0))
    assert slips > 50, slips
    ref = solve_chain(replace(ch, v_belt=np.full(n, -0.2)), t[-1])
    assert np.max(np.abs(r["x"] - ref.evaluate(t)["x"])) < 1e-4


def test_bad_belt_values_rejected() -> None:
    with ChainFMU3(n=3) as fmu:
        fmu.start(params={"N": 0.5})
        with pytest.raises(FMUCallError, match=r"invalid value inf for v_belt\[2\].*valid range: finite"):
            fmu.set_raw("v_belt", [0.0, np.inf, 0.0])


def test_fmi3_equals_fmi2_with_belts(chain_fmu2: Path) -> None:
    with ChainFMU2(fmu_path=chain_fmu2) as f2:
        n = f2.n
        ch = Chain.make(n, omega=0.6, k_site=0.4, N=0.5, P0=1.0)
        t = np.linspace(0.0, 15.0, 301)
        vb0, vb1 = np.linspace(-0.2, 0.3, n).tolist(), np.linspace(0.1, -0.1, n).tolist()
        r2 = _belt_run(f2, ch, 0.0, t, vb0, {150: vb1})
    with ChainFMU3(n=n) as f3:
        r3 = _belt_run(f3, ch, 0.0, t, vb0, {150: vb1})
    for k in ("x", "v", "a", "F_friction", "mode"):
        assert np.array_equal(r2[k], r3[k]), k
    assert np.count_nonzero(np.diff(r3["mode"], axis=0)) > 4


def test_consistent_scheme_with_belts_converges() -> None:
    """The consistent scheme (first order) on the belt case: 3.8e-3, 2.2e-3, 4.8e-4 at T/400, T/800,
    T/1600 (asserted: the last below a quarter of the first, and below 1e-3)."""
    T = BELT.period
    t = np.linspace(0.0, 6 * T, 241)
    xr = solve_chain(replace(BELT, v_belt=np.array(VB0)), t[-1], belt_changes=[(3 * T, VB1)]).evaluate(t)["x"]
    with ChainFMU3(n=3, params={"scheme": "consistent"}) as fmu:
        e = [np.max(np.abs(_belt_run(fmu, BELT, T / s, t, VB0, {120: VB1})["x"] - xr)) for s in (400, 800, 1600)]
    assert e[2] < e[0] / 4 and e[2] < 1e-3, e


def test_paper_scheme_refuses_a_belt() -> None:
    with ChainFMU3(n=3, params={"scheme": "paper"}) as fmu:
        with pytest.raises(FMUCallError, match="v_belt is set but the paper scheme has no moving belt"):
            fmu.run(t_stop=1.0, dt=0.1, inputs={"v_belt": [0.1, 0.0, 0.0]})
        fmu.start()
        fmu.set_inputs({"v_belt": [0.0, 0.2, 0.0]})
        with pytest.raises(FMUCallError, match="fmi3DoStep: v_belt is set but the paper scheme"):
            fmu.step_to(0.1)


def test_belt_derivatives_refused(chain_fmu2: Path) -> None:
    with ChainFMU2(fmu_path=chain_fmu2) as f2:
        f2.start()
        vr = f2._vrs["v_belt"][0]
        with pytest.raises(FMUCallError, match=r"v_belt \(value reference \d+\) takes no derivatives"):
            f2.inst.set_real_input_derivatives([vr], 1, [0.1])


# n = 1 is the oscillator to rounding (helpers.CHAIN_N1_REL; the same modes): (parameters, friction law or None, h, belt speeds set at
# communication points {index: speed}, end time); communication step 0.05
_OSC = dict(m=1.0, k=1.0, c=0.05, P0=0.3, omega=0.7, phi=0.2, N=1.0, mu_s=0.5, chi=0.6, x0=0.1, v0=0.0)
ONE_BLOCK_CASES = {
    "coulomb": (_OSC, None, 0.005, {0: 0.4, 180: -0.2}, 20.0),
    "coulomb-chi>1": ({**_OSC, "chi": 1.2}, None, 0.004, {0: 0.15, 120: 0.0, 200: 0.3}, 20.0),
    "stribeck-d1": (_OSC, (0.1, 1.0), 0.005, {0: 0.4, 180: -0.2}, 20.0),
    "stribeck-d2-undamped": ({**_OSC, "c": 0.0, "P0": 0.5}, (0.05, 2.0), 0.002, {0: -0.25, 150: 0.4, 300: 0.1}, 25.0),
    "stribeck-fixed-support": ({**_OSC, "P0": 0.8}, (0.1, 1.0), 0.005, {}, 20.0),
    "stribeck-chi0.2": ({**_OSC, "chi": 0.2, "P0": 0.45, "c": 0.1}, (0.02, 1.0), 0.001, {0: 0.05, 100: -0.05}, 15.0),
}
_OUT = ("x", "v", "a", "F_friction", "mode")


def _oscillator_series(fmi: int, fmu_path: Path, p: dict, law, h: float, changes: dict, t: np.ndarray) -> dict:
    from dryfriction.drivers.oscillator import OscillatorFMU2, Settings
    from dryfriction.drivers.oscillator3 import OscillatorFMU3
    from dryfriction.params import Oscillator

    extra: dict = {} if law is None else {"friction_law": 2, "v_s": law[0], "delta": law[1]}
    if 0 in changes:
        extra["v_belt"] = changes[0]
    if fmi == 2:
        osc = OscillatorFMU2(fmu_path=fmu_path)
        osc.start(Oscillator(**p), Settings(h=h, scheme="located", extra=extra))
    else:
        osc = OscillatorFMU3(params={**p, "h": h, "scheme": 3, **extra})
    try:
        out = {k: [float(osc.get(k))] for k in _OUT}
        for k in range(1, t.size):
            if k - 1 in changes and k > 1:
                osc.set({"v_belt": changes[k - 1]})
            if fmi == 2:
                osc.step_to(float(t[k]))
            else:
                osc.do_step(float(t[k] - t[k - 1]))
            for name in _OUT:
                out[name].append(float(osc.get(name)))
    finally:
        osc.close()
    return {k: np.array(v) for k, v in out.items()}


@pytest.mark.parametrize("case", list(ONE_BLOCK_CASES))
def test_one_block_chain_is_the_oscillator_on_a_belt(case: str, fmu_path: Path) -> None:
    """n = 1, located scheme, belts changed at communication points, Coulomb and Stribeck: the chain
    FMU's mode is the oscillator FMU's (FMI 2.0 and 3.0) at every point, through stick-slip, and its
    x, v, a and F_friction to rounding (helpers.CHAIN_N1_REL: the chain steps on the velocity
    relative to the belt, the stuck block riding on it, as the oscillator, whose Bossak schemes step
    through the friction engine, their arithmetic ordered otherwise)."""
    p, law, h, changes, T = ONE_BLOCK_CASES[case]
    t = np.arange(int(round(T / 0.05)) + 1) * 0.05
    params = {**p, "h": h}
    if law is not None:
        params.update(friction_law="stribeck", v_s=law[0], delta=law[1])
    with ChainFMU3(n=1) as fmu:
        fmu.start(params=params, inputs={"v_belt": [changes[0]]} if 0 in changes else None)
        o = fmu.outputs()
        ch = {k: [o[k][0]] for k in _OUT}
        for k in range(1, t.size):
            if k - 1 in changes and k > 1:
                fmu.set_inputs({"v_belt": [changes[k - 1]]})
            fmu.step_to(float(t[k]))
            o = fmu.outputs()
            for name in _OUT:
                ch[name].append(o[name][0])
    for fmi in (2, 3):
        osc = _oscillator_series(fmi, fmu_path, p, law, h, changes, t)
        for name in _OUT:
            if name == "mode":
                assert np.array_equal(np.array(ch[name], dtype=float), osc[name]), (fmi, name)
            else:
                assert_rounding_apart(np.array(ch[name], dtype=float), osc[name], (fmi, name))
    modes = np.array(ch["mode"])
    assert np.count_nonzero(np.diff(modes)) >= 4 and (modes == 0).any() and (modes != 0).any()


def test_stribeck_jerk_on_belts_survives_a_state_restore() -> None:
    """A Stribeck chain on belts: the second derivative of v (fmi3GetOutputDerivatives, the jerk,
    which reads N mu'(|v - v_belt|)) after restoring an FMU state, in memory or deserialised, is the
    one read when the state was taken, bit for bit: a restore rebuilds the physics, and the belts
    the state is on come with the state, not with the model."""
    ch = Chain.make(3, omega=0.6, k=[1.0, 0.8, 1.2], N=[0.5, 0.4, 0.6], chi=[0.7, 0.6, 0.5], P0=[1.2, 0.0, 0.6])
    params = {**ch.fmu_params(), "h": ch.period / 400, "friction_law": "stribeck", "v_s": [0.5, 0.5, 0.5]}
    vb = [0.2, -0.1, 0.3]
    with ChainFMU3(n=3) as fmu:
        v_vr = fmu.vars["v"].vr
        fmu.start(params=params, inputs={"v_belt": vb})
        fmu.step_to(2.7)
        out = fmu.outputs()
        sliding = (out["mode"] != 0) & (out["v"] != np.array(vb))
        assert np.any(sliding), out  # a block slides relative to its belt: its jerk reads the belt
        jerk0 = fmu.inst.get_output_derivatives([v_vr], 2, 3)
        state = fmu.inst.get_state()
        data = fmu.inst.serialize_state(state)
        fmu.step_to(5.0)
        fmu.inst.set_state(state)
        jerk1 = fmu.inst.get_output_derivatives([v_vr], 2, 3)
        fmu.inst.set_state(fmu.inst.deserialize_state(data))
        jerk2 = fmu.inst.get_output_derivatives([v_vr], 2, 3)
    assert jerk1.tobytes() == jerk0.tobytes(), (jerk0, jerk1)
    assert jerk2.tobytes() == jerk0.tobytes(), (jerk0, jerk2)
