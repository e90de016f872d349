"""The benchmark structures (dryfriction.system.cases) against independent numbers: the two-mass
case's linear limits against the 2 x 2 closed forms; the bladed disk without its ring against the
natural frequencies pyHarm's tutorial 006 prints (its code's blade masses); the bladed disk with
its ring, contacts stuck and sliding, against the cyclic-symmetry reduction (a sector's 4 x 4
eigenproblem at each nodal diameter gives the full 96-DOF structure's frequencies); the damping,
the engine-order excitation and the normal load as documented; the builders' refusals."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.linalg import eigh

from dryfriction import UsageError
from dryfriction.system import bladed_disk, cases, two_mass_jenkins

# pyHarm tutorial 006's printed natural frequencies of the tuned blisk (Hz, its cell 6, all 72)
TUTORIAL_HZ = [
    88.26374399, 169.3441295, 169.3441295, 189.3018526, 189.3018526, 193.0496227, 193.0496227, 194.33310084,
    194.33310084, 194.91823247, 194.91823247, 195.23065575, 195.23065575, 195.41408815, 195.41408815,
    195.52784525, 195.52784525, 195.59979933, 195.59979933, 195.64415084, 195.64415084, 195.66835088,
    195.66835088, 195.67605066, 249.31165161, 335.56537939, 335.56537939, 555.31017863, 555.31017863,
    615.15017797, 615.15017797, 616.585022, 616.585022, 616.96341859, 616.96341859, 617.12696788,
    617.12696788, 617.21324764, 617.21324764, 617.2635722, 617.2635722, 617.29423701, 617.29423701,
    617.31270821, 617.31270821, 617.32265229, 617.32265229, 617.32579659, 619.34330474, 619.82021678,
    619.82021678, 626.2025859, 626.2025859, 810.0067968, 810.0067968, 1044.51877441, 1044.51877441,
    1264.6832341, 1264.6832341, 1464.72871426, 1464.72871426, 1640.60424871, 1640.60424871, 1789.01493852,
    1789.01493852, 1907.27068187, 1907.27068187, 1993.2626374, 1993.2626374, 2045.47055708, 2045.47055708,
    2062.97567761]


def _frequencies(M: np.ndarray, K: np.ndarray) -> np.ndarray:
    return np.sqrt(np.maximum(eigh(K, M, eigvals_only=True), 0.0))


def _stuck_K(sys) -> np.ndarray:
    """K with every Jenkins contact's spring k_t on its row (the contacts held)."""
    return sys.K + (sys.W.T * sys.k_t) @ sys.W


# ---- the two-mass case ----------------------------------------------------------------------------

def test_two_mass_matrices_and_contact() -> None:
    s = two_mass_jenkins()
    assert (s.n, s.nc, s.omega, s.scheme) == (2, 1, 1.0, "located")
    np.testing.assert_array_equal(s.M, np.diag([1.0, 0.5]))
    np.testing.assert_array_equal(s.K, [[3.0, -1.0], [-1.0, 1.0]])
    np.testing.assert_allclose(s.C, [[0.08, -0.02], [-0.02, 0.03]], rtol=0, atol=1e-15)
    np.testing.assert_array_equal(s.F_c, [1.0, 0.0])
    np.testing.assert_array_equal(s.F_s, [0.0, 0.0])
    np.testing.assert_array_equal(s.W, [[1.0, -1.0]])
    assert (s.N[0], s.mu_s[0], s.mu_k[0], s.k_t[0]) == (0.6, 0.5, 0.5, 20.0)
    t = two_mass_jenkins(N=0.3, mu_s=0.6, mu_k=0.4, k_t=5.0, omega=2.5)
    assert (t.N[0], t.mu_s[0], t.mu_k[0], t.k_t[0], t.omega, t.breakaway[0]) == (0.3, 0.6, 0.4, 5.0, 2.5,
                                                                                   pytest.approx(0.18))


@pytest.mark.parametrize("k_t", [20.0, 3.0])
def test_two_mass_linear_limits_closed_form(k_t: float) -> None:
    """Sliding freely: w^4 - 5 w^2 + 4 = 0 (w = 1, 2); stuck: w^4 - (5 + 3 k_t) w^2 + 4 (1 + k_t) = 0."""
    s = two_mass_jenkins(k_t=k_t)
    np.testing.assert_allclose(_frequencies(s.M, s.K), [1.0, 2.0], rtol=1e-13)
    b, c = 5.0 + 3.0 * k_t, 4.0 * (1.0 + k_t)
    closed = np.sqrt([(b - math.sqrt(b * b - 4 * c)) / 2, (b + math.sqrt(b * b - 4 * c)) / 2])
    np.testing.assert_allclose(_frequencies(s.M, _stuck_K(s)), closed, rtol=1e-12)
    if k_t == 20.0:
        np.testing.assert_allclose(closed, [1.14851049, 7.98003281], rtol=1e-8)


def test_two_mass_refusals() -> None:
    with pytest.raises(UsageError, match="N"):
        two_mass_jenkins(N=-1.0)
    with pytest.raises(UsageError, match="k_t"):
        two_mass_jenkins(k_t=-2.0)


# ---- the bladed disk --------------------------------------------------------------------------------

def test_blisk_frequencies_are_pyharm_tutorials() -> None:
    """Without the ring, the 72 natural frequencies pyHarm's tutorial prints (code's blade masses)."""
    np.testing.assert_allclose(cases.bladed_disk_modes(), TUTORIAL_HZ, rtol=2e-9)
    s = bladed_disk(ring=False)
    assert (s.n, s.nc) == (72, 0)
    np.testing.assert_allclose(_frequencies(s.M, s.K) / (2 * math.pi), TUTORIAL_HZ, rtol=2e-9)
    # the table's blade masses (3.5e-3, 2.5e-3 kg) give other frequencies: the code's are followed
    assert abs(cases.bladed_disk_modes(mb1=3.5e-3, mb2=2.5e-3)[1] - TUTORIAL_HZ[1]) > 1.0


@pytest.mark.parametrize("stuck", [True, False], ids=["stuck", "sliding"])
def test_bladed_disk_cyclic_reduction(stuck: bool) -> None:
    """The 96 frequencies of the full structure (contacts held: k_t on; sliding: off) are the union
    over the nodal diameters k = 0..12 of the sector's 4 x 4 eigenproblems (k = 1..11 twice)."""
    s = bladed_disk()
    assert (s.n, s.nc) == (96, 24)
    full = _frequencies(s.M, _stuck_K(s) if stuck else s.K)
    reduced = []
    for k in range(13):
        Mk, Kk = cases.bladed_disk_sector(k, stuck)
        f = _frequencies(Mk, Kk)
        reduced.extend(f if k in (0, 12) else np.repeat(f, 2))
    np.testing.assert_allclose(full, np.sort(reduced), rtol=1e-9)
    # the ring's sliding limit leaves the blisk's frequencies and adds the free ring's
    if not stuck:
        assert np.min(np.abs(full[:, None] / (2 * math.pi) - np.array(TUTORIAL_HZ)[None, :]), axis=0).max() < 1e-6


def test_bladed_disk_contacts_load_and_excitation() -> None:
    s = bladed_disk(engine_order=3)
    w_nd1 = 2 * math.pi * 169.3441295                      # the tutorial's pd_diam freq iloc[1]
    N = 20e-4 * 0.1 * (w_nd1 / 2) ** 2                       # N0 = mr R Omega^2
    np.testing.assert_allclose(s.N, N, rtol=1e-9)
    assert N == pytest.approx(56.60698, rel=1e-6)
    np.testing.assert_array_equal(s.mu_s, 0.1)
    np.testing.assert_array_equal(s.mu_k, 0.1)
    np.testing.assert_array_equal(s.k_t, 1e8)
    for j in range(24):                                      # ring sector j on disk mass j
        row = np.zeros(96)
        row[72 + j], row[3 * j] = 1.0, -1.0
        np.testing.assert_array_equal(s.W[j], row)
    phase = 2 * math.pi * 3 * np.arange(24) / 24
    tips = 3 * np.arange(24) + 2
    np.testing.assert_allclose(s.F_c[tips], np.cos(phase), atol=1e-15)
    np.testing.assert_allclose(s.F_s[tips], np.sin(phase), atol=1e-15)
    assert np.count_nonzero(s.F_c) + np.count_nonzero(s.F_s) == np.count_nonzero(s.F_c[tips]) + \
        np.count_nonzero(s.F_s[tips])
    # the default omega: the first family at the engine order's diameter (EO 3: the tutorial's 193.05 Hz)
    assert s.omega / (2 * math.pi) == pytest.approx(193.0496227, rel=1e-9)
    assert bladed_disk().omega / (2 * math.pi) == pytest.approx(169.3441295, rel=1e-9)
    assert bladed_disk(omega=1100.0, N=10.0, mu=0.2, k_t=1e7).omega == 1100.0


def test_bladed_disk_damping_is_modal_on_the_blisk() -> None:
    s = bladed_disk()
    Mb, Kb, Cb = s.M[:72, :72], s.K[:72, :72], s.C[:72, :72]
    lam, phi = eigh(Kb, Mb)
    modal = phi.T @ Cb @ phi
    np.testing.assert_allclose(np.diag(modal), 2e-3 * np.sqrt(lam), rtol=1e-8)
    off = modal - np.diag(np.diag(modal))
    assert np.max(np.abs(off)) < 1e-9 * np.max(np.abs(modal))
    assert not np.any(s.C[72:, :]) and not np.any(s.C[:, 72:])      # the ring undamped
    # the ring on its neighbours and the ground, nothing else
    assert s.K[72, 72] == pytest.approx(2e7 + 1e4) and s.K[72, 73] == -1e7 and s.K[72, 95] == -1e7


def test_bladed_disk_refusals() -> None:
    with pytest.raises(UsageError, match="engine_order"):
        bladed_disk(engine_order=13)
    with pytest.raises(UsageError, match="no parameter 'm3'"):
        bladed_disk(m3=1.0)
    with pytest.raises(UsageError, match="mb1"):
        bladed_disk(mb1=0.0)
    with pytest.raises(UsageError, match="ring=True"):
        bladed_disk(ring=False, N=3.0)
    with pytest.raises(UsageError, match="N"):
        bladed_disk(N=-1.0)
