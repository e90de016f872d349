"""The chain of n blocks (fmu_src/chain.[ch], driven by tests/c/chain_driver) against the
event-driven reference (dryfriction.references.chain), and the reference against the exact
single-block solution. Numbers in docs/chain.md."""

from __future__ import annotations

import subprocess

import numpy as np
import pytest

from dryfriction.references.chain import Chain, solve_chain
from dryfriction.references.exact import solve_exact
from dryfriction.params import Oscillator

from chain_cases import CASES, DRIVER, PERIODS, convergence, run_driver


# two decoupled blocks (coupling spring and damper 0), each on its own wall spring: block 1 on
# k[0], block 2 on k_end; chi < 1 and chi > 1, the second damped
OMEGA = 0.5
BLOCKS = [dict(k=1.0, c=0.0, P0=1.0, phi=0.0, N=0.8, chi=0.7),
          dict(k=2.0, c=0.1, P0=0.7, phi=0.4, N=0.5, chi=1.4)]
DECOUPLED = Chain.make(2, omega=OMEGA, k=[1.0, 0.0], k_end=2.0, c=[0.0, 0.0], c_end=0.1,
                       P0=[1.0, 0.7], phi=[0.0, 0.4], N=[0.8, 0.5], chi=[0.7, 1.4])


def _exact(i: int, t_end: float):
    return solve_exact(Oscillator(m=1.0, omega=OMEGA, mu_s=0.5, **BLOCKS[i]), t_end)


# ---- the reference ------------------------------------------------------------------------------

def test_reference_decoupled_equals_exact() -> None:
    T = DECOUPLED.period
    sol = solve_chain(DECOUPLED, PERIODS * T)
    t = np.linspace(0.0, PERIODS * T, 4001)
    r = sol.evaluate(t)
    for i in range(2):
        x, v, _, mode = _exact(i, PERIODS * T).evaluate(t)
        assert np.max(np.abs(r["x"][:, i] - x)) < 1e-9
        assert np.max(np.abs(r["v"][:, i] - v)) < 1e-9
        sw = _exact(i, PERIODS * T).switch_times()
        far = np.all(np.abs(t[:, None] - sw[None, :]) > 1e-6, axis=1)
        assert np.array_equal(r["mode"][far, i], mode[far])
    assert len([e for e in sol.events if e[1] == 1]) > 10


@pytest.mark.parametrize("case", list(CASES))
def test_reference_tolerance_convergence(case: str, refs: dict) -> None:
    """Looser references (rtol 1e-8, 1e-10, steps up to a quarter period) approach the default one
    (rtol 1e-12, a 32nd) by the factor of the tolerance: the reference is converged."""
    ch = CASES[case]
    t = np.linspace(0.0, PERIODS * ch.period, 1001)
    x = refs[case].evaluate(t)["x"]
    d = []
    for tol in (1e-8, 1e-10):
        loose = solve_chain(ch, PERIODS * ch.period, rtol=tol, atol=tol * 1e-2, steps_per_period=4)
        d.append(np.max(np.abs(loose.evaluate(t)["x"] - x)))
    assert d[1] < d[0] / 20, d
    assert d[0] < 1e-6, d


@pytest.mark.parametrize("case", list(CASES))
def test_reference_energy_balance(case: str, refs: dict) -> None:
    ch, sol = CASES[case], refs[case]
    r = sol.evaluate(np.linspace(0.0, PERIODS * ch.period, 2001))
    E = sol.energy(r["x"], r["v"])
    res = E - E[0] - r["W_applied"] - r["W_friction"] + r["D_damping"]
    assert np.max(np.abs(res)) < 1e-9 * max(1.0, np.max(np.abs(r["W_applied"])))
    assert len(sol.events) > 20


# ---- the C chain -------------------------------------------------------------------------------

@pytest.mark.parametrize("case", list(CASES))
def test_located_second_order(case: str, refs: dict) -> None:
    """max |x - x_ref| falls 4x (+-10 %) per halving of h from T/400 to T/3200 over 10 periods."""
    e, ratios = convergence(CASES[case], ref=refs[case])
    assert np.all((ratios > 3.6) & (ratios < 4.4)), (e, ratios)
    assert e[-1] < 2e-4


@pytest.mark.parametrize("case", list(CASES))
def test_located_second_order_random_steps(case: str, refs: dict) -> None:
    """The same with communication steps drawn in [0.1 h, 3 h] (shortened steps re-based)."""
    e, ratios = convergence(CASES[case], ref=refs[case], random_dt=11)
    assert np.all((ratios > 3.4) & (ratios < 4.6)), (e, ratios)


def test_decoupled_chain_has_the_single_block_error() -> None:
    """Decoupled blocks: each block's error against the exact solution is the single-block error."""
    T = DECOUPLED.period
    for ppp in (400, 1600):
        run = run_driver(DECOUPLED, PERIODS * T, T / ppp, dt=T / 100)
        for i, b in enumerate(BLOCKS):
            x = _exact(i, PERIODS * T).evaluate(run["t"])[0]
            one = Chain.make(1, omega=OMEGA, k=[b["k"]], c=[b["c"]], P0=[b["P0"]], phi=[b["phi"]],
                             N=[b["N"]], chi=[b["chi"]])
            single = run_driver(one, PERIODS * T, T / ppp, dt=T / 100)
            e_chain = np.max(np.abs(run["x"][:, i] - x))
            e_single = np.max(np.abs(single["x"][:, 0] - x))
            assert 0.95 < e_chain / e_single < 1.05, (ppp, i, e_chain, e_single)
            assert e_single < 5e-4 * (400 / ppp) ** 2


@pytest.mark.parametrize("scheme", [2, 3])
def test_breakaway_limit_below_rounding(scheme: int) -> None:
    """A block at rest at x0 = P0 / k (static force P0 (cos w t - 1): 0 at t = 0) with a breakaway
    limit of 5e-24 N, below the rounding of P0: it breaks away backward at once (the exact solution:
    at 5e-13 T) and follows the exact motion. (The chain's stick test reads the force at the step's
    end before the closed-form breakaway, whose acos argument is -1 here; the oscillator's did not.)"""
    ch = Chain.make(1, omega=8.0, k=[64.0], P0=[1.0], N=[1e-23], mu_s=[0.5], chi=[1.0], x0=[1.0 / 64.0])
    p = Oscillator(m=1.0, k=64.0, P0=1.0, omega=8.0, N=1e-23, mu_s=0.5, chi=1.0, x0=1.0 / 64.0)
    T = ch.period
    run = run_driver(ch, 2 * T, T / 4000, scheme=scheme)
    assert run["mode"][0, 0] == 0 and run["mode"][1, 0] == -1
    x = solve_exact(p, 2 * T).evaluate(run["t"])[0]
    err = np.max(np.abs(run["x"][:, 0] - x))
    assert err <= 2e-5 * p.P0 / p.k, err  # 1.07e-5 P0/k measured (the single block's error)


def test_energy_balance_second_order() -> None:
    """E - E0 - W_applied - W_friction + D_damping at every point, O(h^2)."""
    ch = CASES["damped-walled"]
    T = ch.period
    res = []
    for ppp in (400, 800, 1600):
        run = run_driver(ch, 5 * T, T / ppp, dt=T / 100)
        r = run["E"] - run["E"][0] - run["W_applied"] - run["W_friction"] + run["D_damping"]
        res.append(np.max(np.abs(r)))
    ratios = np.array(res[:-1]) / np.array(res[1:])
    assert np.all((ratios > 3.3) & (ratios < 4.7)), (res, ratios)


def test_invariants_along_a_run() -> None:
    ch = CASES["chi-mixed"]
    run = run_driver(ch, 5 * ch.period, ch.period / 500, dt=ch.period / 137)
    stuck = run["mode"] == 0
    assert stuck.any() and (~stuck).any()
    assert np.all(run["v"][stuck] == 0.0)
    limit = np.broadcast_to(ch.Fb * (1 + 1e-12), run["F"].shape)
    assert np.all(np.abs(run["F"][stuck]) <= limit[stuck])
    mukN = np.broadcast_to(ch.mu_k * ch.N, run["F"].shape)
    assert np.array_equal(run["F"][~stuck], (-run["mode"] * mukN)[~stuck])


def test_driver_rejects_bad_input() -> None:
    r = subprocess.run([str(DRIVER), "n=3", "m=1,-1,1"], capture_output=True, text=True)
    assert r.returncode == 2
    assert "invalid value -1 for m[2]" in r.stderr and r.stderr.count("\n") == 1


def test_long_chain_clusters_second_order() -> None:
    """16 blocks: a switch re-steps only a cluster of w blocks either side (energy=0); the error
    against the reference falls 4x per halving of h, as on the whole-chain split (energy=1), and
    the two errors agree within 10 %."""
    n = 16
    i = np.arange(n)
    ch = Chain.make(n, omega=0.7, k_end=1.0, P0=np.where(i % 3 == 0, 1.0, 0.0), phi=0.3 * i,
                    N=0.5 + 0.3 * np.sin(i), chi=0.7)
    T = ch.period
    ref = solve_chain(ch, 5 * T)
    assert len(ref.events) > 100
    errs = {}
    for energy in (0, 1):
        e = []
        for ppp in (400, 800, 1600):
            args = [str(DRIVER), *ch.driver_args(), f"t_end={5 * T!r}", f"h={T / ppp!r}",
                    f"dt={T / 100!r}", f"energy={energy}"]
            out = subprocess.run(args, capture_output=True, text=True, check=True)
            a = np.loadtxt(out.stdout.splitlines(), delimiter=",")
            x = a[:, 1:1 + 4 * n].reshape(-1, n, 4)[:, :, 0]
            e.append(np.max(np.abs(x - ref.evaluate(a[:, 0])["x"])))
        errs[energy] = np.array(e)
        ratios = errs[energy][:-1] / errs[energy][1:]
        assert np.all((ratios > 3.6) & (ratios < 4.4)), (energy, errs[energy], ratios)
    assert np.all(np.abs(errs[0] / errs[1] - 1.0) < 0.1), errs
