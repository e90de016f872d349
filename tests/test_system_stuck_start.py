"""The stuck start of a structure's orbits (dryfriction.analysis.system_orbits.stuck_start): the linear
steady response with every contact held, against closed forms written here (the Jenkins spring in the
stiffness; a rigid contact between two masses ties them into one), refused where a contact's force
would reach its limit, and Newton converging from it in one step; and Newton's line search without
the Jacobian (a large structure's costly tangent) taking the same iterates as with it."""

from __future__ import annotations

import numpy as np
import pytest

from dryfriction import Contact, System
from dryfriction.analysis import system_orbits as so
from dryfriction.analysis.system_orbits import find_system_orbits, stuck_start
from dryfriction.analysis.system_response import system_frequency_response

loops = pytest.mark.no_sanitizer

M2 = np.diag([1.0, 0.5])
K2 = np.array([[3.0, -1.0], [-1.0, 1.0]])
C2 = 0.02 * K2 + 0.02 * M2


def jenkins(N: float, omega: float = 1.4) -> System:
    return System(M=M2, K=K2, C=C2, F_c=[1.0, 0.0], omega=omega,
                  contacts=[Contact(between=(0, 1), N=N, mu_s=0.5, mu_k=0.4, k_t=20.0)])


def tied(N: float, omega: float = 1.1) -> System:
    return System(M=M2, K=K2, C=C2, F_c=[1.0, 0.0], F_s=[0.0, 0.3], omega=omega,
                  contacts=[Contact(between=(0, 1), N=N, mu_s=0.5, mu_k=0.4)])


def test_the_jenkins_stuck_start_is_the_closed_form() -> None:
    """Two masses with a stuck Jenkins element: K + k_t w w' with w = (1, -1); x(0) = Re X, v(0) =
    -omega Im X, the slider at rest (0); its spring force amplitude 20 |X0 - X1| below mu_s N."""
    om = 1.4
    Ks = K2 + 20.0 * np.array([[1.0, -1.0], [-1.0, 1.0]])
    X = np.linalg.solve(Ks - om * om * M2 + 1j * om * C2, np.array([1.0, 0.0]))
    force = 20.0 * abs(X[0] - X[1])
    N = 1.5 * force / 0.5  # (the limit mu_s N 1.5 times the force)
    z = stuck_start(jenkins(N, om))
    assert z is not None
    np.testing.assert_allclose(z[:2], X.real, rtol=0, atol=1e-14)
    np.testing.assert_allclose(z[2:4], -om * X.imag, rtol=0, atol=1e-14)
    assert z[4] == 0.0
    assert stuck_start(jenkins(0.99 * force / 0.5, om)) is None  # (mu_s N below the force: it would slip)
    assert stuck_start(jenkins(1.01 * force / 0.5, om)) is not None


def test_a_rigid_contact_held_ties_its_masses() -> None:
    """A rigid contact between the two masses held: one mass 1.5 on the summed stiffness, damping and
    force (x0 = x1 = Y): (2 - 1.5 w^2 + i w c) Y = 1 - 0.3 i, c = 0.02 * 2 + 0.02 * 1.5; the holding
    force is the second mass's balance, 0.5 (-w^2) Y + (C Y)_1 + (K Y)_1 - F_1 = f."""
    om = 1.1
    c = 0.02 * 2.0 + 0.02 * 1.5
    Y = (1.0 - 0.3j) / (2.0 - 1.5 * om * om + 1j * om * c)
    z = stuck_start(tied(10.0, om))
    assert z is not None
    np.testing.assert_allclose(z[:2], [Y.real, Y.real], rtol=0, atol=1e-14)
    np.testing.assert_allclose(z[2:], [-om * Y.imag, -om * Y.imag], rtol=0, atol=1e-14)
    x = np.array([Y, Y])
    D = K2 - om * om * M2 + 1j * om * C2
    hold = abs((D @ x)[1] - (-0.3j))  # (the force on mass 1 from the contact: f w_1, w_1 = -1)
    assert stuck_start(tied(0.98 * hold / 0.5, om)) is None
    assert stuck_start(tied(1.02 * hold / 0.5, om)) is not None


@loops
@pytest.mark.parametrize("make", [lambda: jenkins(8.0), lambda: tied(10.0)], ids=["jenkins", "rigid"])
def test_newton_converges_from_the_stuck_start_in_one_step(make) -> None:
    """The stuck orbit found from the closed form in one Newton step (the map is linear there: every
    contact stays stuck), stuck all cycle, neutral (the rest positions' continuum), its amplitude the
    closed form's to the scheme's O(h^2) (the derived h: 1/1000 of the fastest period), and found
    once (the transient's orbit, resting elsewhere in the continuum, is the same orbit)."""
    system = make()
    z = stuck_start(system)
    orbits = find_system_orbits(system, estimate_error=False)
    assert len(orbits) == 1
    o = orbits[0]
    assert o.converged and o.iterations <= 1 and o.neutral
    assert np.all(o.stick_fraction == 1.0)
    X = z[:2] - 1j * z[2:4] / system.omega
    np.testing.assert_allclose(o.amplitude, np.abs(X), rtol=1e-4)


@loops
def test_a_response_on_the_stuck_branch_starts_from_the_closed_form() -> None:
    """Where the contacts stay stuck at every frequency, each point is the closed form's orbit after
    at most one Newton step, its amplitude the closed form's to O(h^2)."""
    base = jenkins(8.0, 1.0)
    f = np.linspace(0.15, 0.3, 4)
    ds = system_frequency_response(base, f, dof=0, estimate_error=False)
    assert bool(ds.converged.all())
    assert int(ds.iterations.max()) <= 1
    for i, fi in enumerate(f):
        z = stuck_start(base.replace(omega=2 * np.pi * fi))
        X0 = abs(z[0] - 1j * z[2] / (2 * np.pi * fi))
        assert abs(float(ds.amplitude_dof_m[i]) - X0) <= 1e-4 * X0


@loops
def test_the_line_search_without_the_jacobian_takes_the_same_iterates(monkeypatch: pytest.MonkeyPatch) -> None:
    """Newton with the Jacobian computed only at accepted states (a costly tangent) ends at the same
    orbit, bit for bit, as with the Jacobian at every trial, with one Jacobian run per Newton step and
    one at the start."""
    system = System(M=M2, K=K2, C=C2, F_c=[1.0, 0.0], omega=1.0,
                    contacts=[Contact(between=(0, 1), N=0.6, mu_s=0.5, mu_k=0.5, k_t=20.0)])
    results, runs = {}, {}
    call = so._Map.__call__
    for lazy in (False, True):
        count = [0]

        def counted(self, z, t_s, jacobian=True, span=None, wrap=None, _count=count):
            _count[0] += bool(jacobian) and span is None
            return call(self, z, t_s, jacobian=jacobian, span=span, wrap=wrap)

        monkeypatch.setattr(so._Map, "__call__", counted)
        monkeypatch.setattr(so._Map, "expensive_jacobian", lambda self, _lazy=lazy: _lazy)
        o = find_system_orbits(system, estimate_error=False)[0]
        results[lazy], runs[lazy] = o, count[0]
    a, b = results[False], results[True]
    assert a.converged and b.converged and a.iterations == b.iterations >= 2
    assert np.array_equal(a.x0, b.x0) and np.array_equal(a.v0, b.v0) and a.residual == b.residual
    assert np.array_equal(a.multipliers, b.multipliers)
    assert runs[True] == b.iterations + 1
    assert runs[False] >= runs[True]


def test_a_start_within_rounding_of_rest_starts_at_rest() -> None:
    """A rigid contact handed a relative velocity of one ulp of its DOFs' (a host's rounding, e.g. a
    Newton step) starts at rest: the map and its Jacobian are those of the exact rest start (the
    sliding start's stop after ~1e-16 s made the tangent's saltation ~1e15)."""
    from dryfriction.analysis.system_orbits import system_map

    s = tied(10.0)
    z = stuck_start(s)
    assert z[2] == z[3]
    z1 = z.copy()
    z1[3] = np.nextafter(z1[3], np.inf)
    P0, J0 = system_map(s, z)
    P1, J1 = system_map(s, z1)
    np.testing.assert_allclose(P1, P0, rtol=0, atol=1e-13)
    np.testing.assert_allclose(J1, J0, rtol=0, atol=1e-9)
