"""Orbits of a structure of identical sectors under a travelling wave by its cyclic symmetry
(dryfriction.system.symmetry, find_system_orbits' ``symmetry``): checked against the full period's
map, against the sector runs composed without the relabelling, and the refusals."""

from __future__ import annotations

import numpy as np
import pytest

from dryfriction import Contact, System, UsageError
from dryfriction.analysis.system_orbits import _Map, find_system_orbits
from dryfriction.analysis.system_response import system_frequency_response
from dryfriction.drivers.system import SystemFMU3
from dryfriction.system import CyclicSymmetry, cases


def ring(ns: int = 5, eo: int = 1, N: float = 0.4, k_t: float = 3.0, omega: float = 1.3, steps: int = 250,
         m_blade: float = 0.3) -> System:
    """ns sectors of a disk mass (on the ground, on its neighbours) and a blade mass on it, a Jenkins
    element between each blade and its disk, the blades driven at engine order eo (odd ns: no two
    contacts in antiphase, whose switches would coincide)."""
    n = 2 * ns
    M = np.diag([1.0, m_blade] * ns)
    K = np.zeros((n, n))
    for s in range(ns):
        d, b, dn = 2 * s, 2 * s + 1, 2 * ((s + 1) % ns)
        K[d, d] += 1.0
        K[np.ix_([d, b], [d, b])] += 0.5 * np.array([[1.0, -1.0], [-1.0, 1.0]])
        K[np.ix_([d, dn], [d, dn])] += 0.8 * np.array([[1.0, -1.0], [-1.0, 1.0]])
    ph = 2.0 * np.pi * eo * np.arange(ns) / ns
    F_c, F_s = np.zeros(n), np.zeros(n)
    F_c[1::2], F_s[1::2] = np.cos(ph), np.sin(ph)
    contacts = [Contact(between=(2 * s + 1, 2 * s), N=N, mu_s=0.5, mu_k=0.5, k_t=k_t) for s in range(ns)]
    return System(M=M, K=K, C=0.01 * M + 0.01 * K, contacts=contacts, F_c=F_c, F_s=F_s, omega=omega,
                  h=2.0 * np.pi / omega / steps)


def sectors(ns: int = 5) -> tuple[list[list[int]], list[list[int]]]:
    return [[2 * s, 2 * s + 1] for s in range(ns)], [[s] for s in range(ns)]


def test_the_sector_map_finds_the_full_maps_travelling_wave() -> None:
    """On 5 sectors (h a 50th of a sector's share of the period): the orbit by the sector map is the
    full period's orbit (their sections differ, so their grids: within the scheme's O(h^2)), the
    sector runs composed without the relabelling return to it and the product of their Jacobians has
    the orbit's multipliers (the sector map's to the 5th power) to rounding, the full period's
    one-run Jacobian at the same state within O(h^2) (it carries Bossak's acceleration across the
    sectors' ends where the composed runs restart)."""
    s = ring()
    sym = CyclicSymmetry.of_sectors(s, *sectors())
    assert list(sym.dofs[:4]) == [2, 3, 4, 5] and list(sym.contacts) == [1, 2, 3, 4, 0]
    (full,) = find_system_orbits(s, estimate_error=False, transients=100)
    (part,) = find_system_orbits(s, estimate_error=False, transients=100, symmetry=sym)
    assert full.converged and part.converged and part.sectors == 5 and full.sectors == 1
    assert 0.0 < part.stick_fraction[0] < 1.0      # stick-slip: every contact sticks and slides in the cycle
    scale = float(np.max(full.amplitude))
    diff = float(np.max(np.abs(part.amplitude - full.amplitude)))
    assert diff <= 1e-4 * scale and np.max(np.abs(part.x0 - full.x0)) <= 1e-4 * scale
    assert np.max(np.abs(part.stick_fraction - full.stick_fraction)) <= 1e-4
    fine = ring(steps=500)  # (the two grids' difference is the scheme's error: at least O(h^2))
    (full2,) = find_system_orbits(fine, estimate_error=False, guesses=[np.concatenate([full.x0, full.v0, full.s0])],
                                  transients=0)
    (part2,) = find_system_orbits(fine, estimate_error=False, transients=0, symmetry=sym,
                                  guesses=[np.concatenate([part.x0, part.v0, part.s0])])
    assert float(np.max(np.abs(part2.amplitude - full2.amplitude))) <= diff / 3.0
    with SystemFMU3(s) as fmu:
        fmu.system = s
        M = _Map(fmu, s, 1)
        span = M.KT / 5
        z, prod = part.section_state, np.eye(part.section_state.size)
        M.slide[:] = part.section_slide
        for k in range(5):   # (raw runs, each started in the modes the last ended in)
            z, J, _ = M(z, part.section + k * span, span=span)
            prod = J @ prod
            M.slide[:] = M.last_mode
        assert np.max(np.abs(z - part.section_state)) <= 1e-9 * scale
        mu = np.linalg.eigvals(prod)
        mu = mu[np.argsort(-np.abs(mu), kind="stable")]
        assert np.max(np.abs(np.abs(mu[:6]) - np.abs(part.multipliers[:6]))) <= 1e-9
        M.slide[:] = part.section_slide
        Pz, J1, _ = M(part.section_state, part.section)
        assert np.max(np.abs(Pz - part.section_state)) <= 1e-4 * scale
        mu1 = np.sort(np.abs(np.linalg.eigvals(J1)))[::-1]
        assert np.max(np.abs(mu1[:6] - np.abs(part.multipliers[:6]))) <= 1e-4
    assert part.stable == full.stable


def test_the_response_by_the_sector_map_follows_the_full_one() -> None:
    """A three-point response with the symmetry gives the full map's amplitudes within O(h^2) and
    the error estimate of the same size."""
    s = ring()
    sym = CyclicSymmetry.of_sectors(s, *sectors())
    f = np.array([1.25, 1.3, 1.35]) / (2.0 * np.pi)
    a = system_frequency_response(s, f, transients=100, symmetry=sym)
    b = system_frequency_response(s, f, transients=100)
    assert bool(a.converged.all()) and bool(b.converged.all())
    A, B = a.amplitude_m.values, b.amplitude_m.values
    assert np.max(np.abs(A - B)) <= 1e-5 * float(np.max(B))
    assert np.all(a.error_m.values <= 10.0 * b.error_m.values + 1e-12)


def test_the_package_entry_points_take_the_symmetry() -> None:
    """dryfriction.find_orbits and frequency_response of a structure pass its CyclicSymmetry on (the
    oscillator's find_orbits has a symmetry switch of its own, its mirror orbits: a CyclicSymmetry
    there is refused, not taken for True)."""
    from dryfriction import Oscillator, find_orbits, frequency_response

    s = ring()
    sym = CyclicSymmetry.of_sectors(s, *sectors())
    (o,) = find_orbits(s, symmetry=sym, transients=100, estimate_error=False)
    assert o.sectors == 5 and o.converged
    ds = frequency_response(s, [1.3 / (2.0 * np.pi)], symmetry=sym, transients=100)
    assert bool(ds.converged[0]) and ds.amplitude_m.values[0, 1] == pytest.approx(o.amplitude[1], rel=1e-3)
    with pytest.raises(TypeError, match="mirror orbits"):
        find_orbits(Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.6, chi=0.4), symmetry=sym)
    with pytest.raises(ValueError, match="structure"):
        frequency_response(Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.6, chi=0.4), [0.1], symmetry=sym)


def test_a_symmetry_the_structure_does_not_have_is_refused() -> None:
    """check names what breaks the symmetry; of_sectors finds the engine order's sector shift (3 on
    five sectors at engine order 2: 2 x 3 = 1 mod 5) and refuses a standing wave; period 2 and a
    relabelling that is not a permutation are refused."""
    s = ring()
    sym = CyclicSymmetry.of_sectors(s, *sectors())
    M = np.array(s.M)
    M[3, 3] *= 1.01
    with pytest.raises(UsageError, match="M is not invariant"):
        sym.check(s.replace(M=M))
    with pytest.raises(UsageError, match="excitation is not a travelling wave"):
        sym.check(ring(eo=2))
    assert list(CyclicSymmetry.of_sectors(ring(eo=2), *sectors()).contacts) == [3, 4, 0, 1, 2]
    with pytest.raises(UsageError, match="no sector shift"):
        CyclicSymmetry.of_sectors(ring(eo=0), *sectors())
    with pytest.raises(ValueError, match="one period"):
        find_system_orbits(s, period=2, symmetry=sym)
    with pytest.raises(UsageError, match="not a permutation"):
        CyclicSymmetry(5, np.zeros(10, dtype=int), np.arange(5))
    with pytest.raises(UsageError, match="not the identity"):
        CyclicSymmetry(4, sym.dofs, sym.contacts)


def test_the_bladed_disks_symmetry_is_its_engine_orders_shift() -> None:
    """bladed_disk_symmetry: sector s to s + 1 at engine order 1, s + 5 at engine order 5 (5 x 5 = 1
    mod 24); engine order 0 refused."""
    for eo, shift in ((1, 1), (5, 5)):
        d = cases.bladed_disk(omega=1080.0, engine_order=eo)
        sym = cases.bladed_disk_symmetry(d)
        assert sym.sectors == 24 and list(sym.contacts[:3]) == [shift, shift + 1, shift + 2]
        assert list(sym.dofs[:3]) == [3 * shift, 3 * shift + 1, 3 * shift + 2] and sym.dofs[72] == 72 + shift
    with pytest.raises(UsageError):
        cases.bladed_disk_symmetry(cases.bladed_disk(omega=1080.0, engine_order=0))


def test_contacts_in_antiphase_put_a_kink_on_the_orbit() -> None:
    """On 4 sectors at engine order 1 the sectors 2 apart move in antiphase and their contacts switch
    at the same instants: the sector map's Jacobian (one order of each pair of switches) equals its
    central differences (to their error) along states that keep the antiphase, and is off them in a
    direction that breaks it (the differences there average the two orders' derivatives: a kink on
    the orbit). The orbit itself is the full map's within the scheme's error."""
    s = ring(ns=4, steps=200)
    sym = CyclicSymmetry.of_sectors(s, *sectors(4))
    (part,) = find_system_orbits(s, estimate_error=False, transients=100, symmetry=sym)
    (full,) = find_system_orbits(s, estimate_error=False, transients=100)
    assert part.converged and full.converged
    scale = float(np.max(full.amplitude))
    assert np.max(np.abs(part.amplitude - full.amplitude)) <= 1e-4 * scale
    z = part.section_state
    with SystemFMU3(s) as fmu:
        fmu.system = s
        M = _Map(fmu, s, 1, sym)
        anti = sym.power(M.perm, 2)               # (the unknowns' pairing half the disk apart)
        assert np.max(np.abs(z + z[anti])) <= 1e-6 * scale

        def G(x: np.ndarray) -> np.ndarray:
            M.slide[:] = part.section_slide
            return M(x, part.section, jacobian=False)[0]

        M.slide[:] = part.section_slide
        _, J, _ = M(z, part.section)
        rng = np.random.default_rng(3)
        eps = 1e-6 * scale
        for keep in (True, True, False):
            d = rng.standard_normal(z.size)
            d[2 * s.n:] = 0.0                     # (x and v only: the sliders follow from the modes)
            d = 0.5 * (d - d[anti]) if keep else 0.5 * (d + d[anti])
            fd = (G(z + eps * d) - G(z - eps * d)) / (2.0 * eps)
            off = float(np.max(np.abs(fd - J @ d)) / np.max(np.abs(J @ d)))
            assert (off <= 1e-7) if keep else (off >= 1e-2), off   # (measured 6e-10, 2e-9; 4e-2)
