"""The chain's site springs and dampers k_site[i], c_site[i] (each block tied to the ground frame;
the Burridge-Knopoff model's springs): the FMU's located scheme against the event-driven
reference (dryfriction.chain_reference with the site terms on K's and C's diagonals), the
reference's own energy balance, a site spring equal to a wall spring bit for bit, the step rule's
bound, the errors, FMI 3.0 = FMI 2.0. Numbers in docs/chain.md ("Site springs and dampers")."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from dryfriction.chain import ChainFMU2, ChainFMU3
from dryfriction.chain_reference import Chain, solve_chain
from dryfriction.errors import FMUCallError

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


@pytest.mark.parametrize("name,value", [("k_site", -1.0), ("c_site", -0.5), ("k_site", np.inf)])
def test_bad_site_values_rejected(name: str, value: float) -> None:
    with ChainFMU3(n=3) as fmu:
        with pytest.raises((FMUCallError, ValueError), match=rf"{name}(\[2\])?.*valid"):
            fmu.start(params={name: [0.0, value, 0.0]})


def test_fmi3_equals_fmi2_with_site_terms(chain_fmu2: Path) -> None:
    with ChainFMU2(fmu_path=chain_fmu2) as f2:
        n = f2.n
        p = dict(k_site=np.linspace(0.3, 1.1, n).tolist(), c_site=[0.05] * n, N=0.5, P0=1.0, omega=0.6)
        r2 = f2.run(t_stop=15.0, dt=0.05, params=p)
    with ChainFMU3(n=n) as f3:
        r3 = f3.run(t_stop=15.0, dt=0.05, params=p)
    assert np.array_equal(r2.x, r3.x) and np.array_equal(r2.v, r3.v) and np.array_equal(r2.mode, r3.mode)
    assert np.count_nonzero(np.diff(r3.mode, axis=0)) > 4
