"""The chain's Stribeck law (friction_law = stribeck, v_s[i], delta[i]) through the FMUs: the located
scheme second order against the event-driven reference (dryfriction.references.chain, which shares
no code with the FMU) on chains of 2 and 3 blocks with belts changed at a communication point and
site springs; n = 1 the oscillator bit for bit without a belt; FMI 3.0 = FMI 2.0; the refusals
(bad values, delta < 1, schemes paper and consistent); the outputs' derivative with respect to
N_ext. Numbers in docs/chain.md ("Stribeck friction"). The n = 1 cases on belts are in
tests/test_belt_chain.py."""

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
from refcache import RefCache

# (chain, belts from the start, belts from the communication point at half the run, periods);
# T = 2 pi / 0.6 where the chain is unforced
CASES = {
    # three coupled blocks on site springs, a damper, velocity weakening of three widths (delta 1)
    "n3-site-d1": (Chain.make(3, omega=0.6, k=[1.0, 0.8, 1.2], c=[0.0, 0.05, 0.0], k_end=0.5,
                              k_site=[0.7, 0.0, 1.5], N=[0.5, 0.4, 0.6], chi=[0.7, 0.6, 0.6], P0=[0.6, 0.0, 0.3],
                              phi=[0.0, 0.0, 0.8], law="stribeck", v_s=[0.1, 0.2, 0.15], delta=1.0),
                   [0.3, -0.2, 0.1], [-0.1, 0.25, 0.0], 6),
    # two blocks, a Gaussian fall (delta 2), one on a site spring
    "n2-site-d2": (Chain.make(2, omega=0.7, k=[1.0, 1.5], c=[0.05, 0.0], k_site=[0.0, 0.6], N=[1.0, 0.8],
                              mu_s=0.5, chi=[0.5, 0.7], P0=[0.8, 0.3], phi=[0.0, 1.0], law="stribeck", v_s=0.05,
                              delta=2.0),
                   [0.25, -0.15], [-0.2, 0.3], 6),
    # a Burridge-Knopoff chain of three in its driver plate's frame (unforced, belts at -v_p)
    "n3-burridge-knopoff": (Chain.make(3, omega=0.0, k=[0.0, 2.0, 2.0], c=0.0, c_site=0.02, P0=0.0, k_site=0.5,
                                       N=1.0, mu_s=0.6, chi=0.5, x0=[-0.3, 0.1, 0.4], law="stribeck", v_s=0.1,
                                       delta=1.0),
                            [-0.2] * 3, [-0.1] * 3, 3),
}


def _period(ch: Chain) -> float:
    return ch.period if ch.omega > 0 else 2 * np.pi / 0.6




@pytest.mark.parametrize("case", list(CASES))
def test_stribeck_chain_second_order_against_reference(case: str, refcache: RefCache) -> None:
    """max |x - x_ref| falls 4x per halving of h (3.6 ... 4.4) from T/400 to T/3200 (measured, in
    docs/chain.md: n3-site-d1 1.15e-3 ... 1.83e-5, ratios 3.97 3.98 3.99; n2-site-d2 8.58e-4 ...
    1.38e-5, 3.93 3.98 3.99; Burridge-Knopoff 3.09e-2 ... 5.18e-4, 3.86 3.90 3.98), with stick-slip
    on every block; stuck blocks ride their belts exactly, and the sliding friction is -sign(v_rel)
    N mu(|v_rel|) at the step's end."""
    ch, vb0, vb1, periods = CASES[case]
    T = _period(ch)
    npts = 40 * periods
    t = np.linspace(0.0, periods * T, npts + 1)
    half = npts // 2
    ref = refcache.call(solve_chain, replace(ch, v_belt=np.array(vb0)), t[-1], belt_changes=[(t[half], vb1)])
    xr = ref.evaluate(t)["x"]
    e = []
    with ChainFMU3(n=ch.n) as fmu:
        for s in (400, 800, 1600, 3200):
            r = _belt_run(fmu, ch, T / s, t, vb0, {half: vb1})
            e.append(np.max(np.abs(r["x"] - xr)))
    e = np.array(e)
    ratios = e[:-1] / e[1:]
    assert np.all((ratios > 3.6) & (ratios < 4.4)), (e, ratios)
    mode = r["mode"]
    assert (mode == 0).any() and (mode != 0).any() and len(ref.events) > 20
    for i in range(ch.n):  # every block sticks and slips (the reference's events)
        assert {e[3] for e in ref.events if e[1] == i} >= {0} and any(e[3] != 0 for e in ref.events if e[1] == i), i
    vb = np.where(np.arange(t.size)[:, None] <= half, vb0, vb1)
    stuck = mode == 0
    assert np.array_equal(r["v"][stuck], vb[stuck])
    slide = mode != 0
    vrel = np.abs(r["v"] - vb)
    assert ch.v_s is not None and ch.delta is not None
    mu = ch.mu_k + (ch.mu_s - ch.mu_k) * np.exp(-(vrel / ch.v_s) ** ch.delta)
    F = -mode * ch.N * mu
    assert np.allclose(r["F_friction"][slide], F[slide], rtol=0, atol=1e-12)


def test_one_block_stribeck_is_the_oscillator(fmu_path: Path) -> None:
    """n = 1 on a fixed support with Stribeck (delta 1, 2 and 1.5, chi < 1 and > 1): x, v, a,
    F_friction and mode are the oscillator FMU's: the modes equal, the rest to rounding
    (helpers.CHAIN_N1_REL: the chain's one-row solve is friction.h's dfo_stribeck_speed, the
    oscillator's Bossak schemes step through the friction engine, their arithmetic ordered
    otherwise)."""
    from dryfriction.drivers.oscillator import OscillatorFMU2, Settings
    from dryfriction.params import Oscillator

    base = dict(m=1.0, k=1.0, c=0.05, P0=0.8, omega=0.7, phi=0.2, N=1.0, mu_s=0.5, chi=0.6, x0=0.1, v0=0.0)
    cases = [(base, 0.1, 1.0, 0.005), (base, 0.05, 2.0, 0.002), ({**base, "chi": 1.3, "c": 0.0}, 0.2, 1.5, 0.004)]
    t = np.arange(401) * 0.05
    names = ("x", "v", "a", "F_friction", "mode")
    for p, vs, dl, h in cases:
        osc = OscillatorFMU2(fmu_path=fmu_path)
        osc.start(Oscillator(**p), Settings(h=h, scheme="located", extra=dict(friction_law=2, v_s=vs, delta=dl)))
        ro = {k: [] for k in names}
        for k in range(1, t.size):
            osc.step_to(float(t[k]))
            for n in names:
                ro[n].append(float(osc.get(n)))
        osc.close()
        with ChainFMU3(n=1) as fmu:
            rc = fmu.run(t_stop=float(t[-1]), dt=0.05,
                         params={**p, "h": h, "friction_law": "stribeck", "v_s": vs, "delta": dl})
        for n in names:
            got = np.asarray(getattr(rc, n))[1:, 0].astype(float)
            if n == "mode":
                assert np.array_equal(got, np.array(ro[n])), (p, n)
            else:
                assert_rounding_apart(got, np.array(ro[n]), (p, n))
        assert np.count_nonzero(np.diff(rc.mode[:, 0])) >= 4


def test_fmi3_equals_fmi2_with_stribeck_and_belts(chain_fmu2: Path) -> None:
    with ChainFMU2(fmu_path=chain_fmu2) as f2:
        n = f2.n
        ch = Chain.make(n, omega=0.6, k_site=0.4, N=0.5, P0=1.0, law="stribeck", v_s=np.linspace(0.05, 0.2, n),
                        delta=np.linspace(1.0, 2.0, n))
        t = np.linspace(0.0, 15.0, 301)
        vb0, vb1 = np.linspace(-0.2, 0.3, n).tolist(), np.linspace(0.1, -0.1, n).tolist()
        r2 = _belt_run(f2, ch, 0.0, t, vb0, {150: vb1})
    with ChainFMU3(n=n) as f3:
        r3 = _belt_run(f3, ch, 0.0, t, vb0, {150: vb1})
    for k in ("x", "v", "a", "F_friction", "mode"):
        assert np.array_equal(r2[k], r3[k]), k
    assert np.count_nonzero(np.diff(r3["mode"], axis=0)) > 4


def test_stribeck_tends_to_coulomb_as_v_s_falls() -> None:
    """The same run with friction_law coulomb and stribeck differs (the law is used), and less and
    less as v_s falls (the fall of mu narrower than the slides: 0.1, 0.01, 0.001)."""
    p = dict(N=0.5, P0=1.0, omega=0.6, k=1.0, mu_s=0.5, chi=0.6, h=1e-3)
    with ChainFMU3(n=2) as fmu:
        c = fmu.run(t_stop=10.0, dt=0.1, params=p)
        d = [np.max(np.abs(c.x - fmu.run(t_stop=10.0, dt=0.1, params={**p, "friction_law": 2, "v_s": vs}).x))
             for vs in (0.1, 0.01, 0.001)]
    assert d[0] > 1e-2 and d[1] < d[0] / 3 and d[2] < d[1] / 3, d


@pytest.mark.parametrize("name,value,valid", [("v_s", -1.0, "> 0"), ("v_s", 0.0, "> 0"), ("delta", 0.0, "> 0"),
                                              ("v_s", np.inf, "finite|normal")])
def test_bad_stribeck_values_rejected_by_the_fmu(name: str, value: float, valid: str) -> None:
    with ChainFMU3(n=3) as fmu:
        fmu._begin(0.0)
        with pytest.raises(FMUCallError, match=rf"invalid value {value:g} for {name}\[2\].*valid range: ({valid})"):
            fmu.set_raw(name, [0.1, value, 0.1])


def test_bad_friction_law_rejected() -> None:
    with ChainFMU3(n=2) as fmu:
        with pytest.raises(ValueError, match=r"friction_law must be one of 1 \(coulomb\), 2 \(stribeck\), not 3"):
            fmu.start(params={"friction_law": 3})
        with pytest.raises(ValueError, match=r"friction_law must be one of coulomb, stribeck, not 'dahl'"):
            fmu.start(params={"friction_law": "dahl"})
        fmu._begin(0.0)
        with pytest.raises(FMUCallError, match=r"friction_law"):
            fmu._set_enum("friction_law", 3)


def test_delta_below_one_refused_at_initialisation() -> None:
    with ChainFMU3(n=3) as fmu:
        with pytest.raises(FMUCallError, match=r"friction_law = stribeck supports delta >= 1 only, not 0.5 for "
                                               r"delta\[3\]"):
            fmu.start(params={"friction_law": "stribeck", "delta": [1.0, 2.0, 0.5]})
        fmu.start(params={"friction_law": "coulomb", "delta": [1.0, 2.0, 0.5]})  # unused: accepted


@pytest.mark.parametrize("scheme", ["paper", "consistent"])
def test_stribeck_needs_the_located_scheme(scheme: str) -> None:
    with ChainFMU3(n=2) as fmu:
        with pytest.raises(FMUCallError, match=r"friction_law = stribeck needs scheme located"):
            fmu.start(params={"friction_law": "stribeck", "scheme": scheme})


def test_directional_derivative_of_friction_by_normal_force() -> None:
    """A sliding block's dF_friction/dN_ext = -mode mu(|v - v_belt|) (the Stribeck coefficient at its
    relative speed), against the formula from the state and a central difference of F_friction."""
    p = dict(N=0.5, P0=1.0, omega=0.6, k=1.0, mu_s=0.5, chi=0.6, h=2e-3, friction_law="stribeck", v_s=0.2,
             delta=1.0)
    with ChainFMU3(n=2) as fmu:
        fmu.start(params=p, inputs={"v_belt": [0.1, -0.05]})
        for _ in range(60):
            fmu.step_to(fmu.time + 0.05)
            o = fmu.outputs()
            if np.all(o["mode"] != 0):
                break
        assert np.all(o["mode"] != 0)
        vr = np.abs(o["v"] - np.array([0.1, -0.05]))
        mu = 0.3 + 0.2 * np.exp(-vr / 0.2)
        vrs = [fmu.vars["N_ext"].vr]
        d = fmu.inst.get_directional_derivative([fmu.vars["F_friction"].vr], vrs, [1.0, 0.0], 2)
        assert d[0] == pytest.approx(-o["mode"][0] * mu[0], rel=1e-12)
        eps = 1e-6
        fmu.set_inputs({"N_ext": [eps, 0.0]})
        Fp = fmu.outputs()["F_friction"][0]
        fmu.set_inputs({"N_ext": [-eps, 0.0]})
        Fm = fmu.outputs()["F_friction"][0]
        assert (Fp - Fm) / (2 * eps) == pytest.approx(d[0], rel=1e-8)
