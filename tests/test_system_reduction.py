"""The Craig-Bampton reduction (dryfriction.system.reduction) against the full model it reduces:

* static response to loads on the boundary: exact (the constraint modes), to rounding;
* every interior mode kept: the reduced model is the full one in other coordinates (the same
  frequencies and the same forced response, to rounding);
* fewer modes: the reduced frequencies bound the full ones from above (Rayleigh-Ritz) and converge
  as modes are added;
* contacts on boundary DOFs become contacts on their coordinates; bad input named in one sentence;
* through the FMU: the reduced beam's periodic orbit without friction equals the full beam's modal
  closed form at the tip (the reduction's and the scheme's errors), and with the damper stuck the
  pinned beam's.
"""

from __future__ import annotations

import numpy as np
import pytest

from dryfriction import Contact, System, UsageError, find_orbits
from dryfriction.system import craig_bampton
from dryfriction.system.cases import cantilever


def beam(elements: int = 10) -> tuple[np.ndarray, np.ndarray]:
    """A clamped cantilever of 10 Euler-Bernoulli elements (unit properties, length 1)."""
    return cantilever(elements)


def beam_system(N: float = 0.0, omega: float = 3.0) -> System:
    M, K = beam()
    n = M.shape[0]
    F = np.zeros(n)
    F[n - 2] = 1.0  # the tip's deflection
    return System(M=M, K=K, F_c=F, omega=omega, contacts=[Contact(dof=6, N=N, mu_s=0.3, mu_k=0.25)]).with_rayleigh(
        0.05, 1e-4)


def test_the_static_response_to_boundary_loads_is_exact() -> None:
    s = beam_system()
    r = craig_bampton(s, 3, boundary=[6, s.n - 2])
    for b in r.boundary:
        F = np.zeros(s.n)
        F[b] = 1.0
        full = np.linalg.solve(s.K, F)
        red = r.expand(np.linalg.solve(r.system.K, r.T.T @ F))
        assert np.abs(red - full).max() <= 1e-10 * np.abs(full).max()


def test_every_mode_kept_is_the_full_model() -> None:
    s = beam_system()
    r = craig_bampton(s, s.n - 1)
    assert np.allclose(r.system.modes()[0], s.modes()[0], rtol=1e-9, atol=0.0)
    for w in (1.0, 3.5, 40.0):
        Z = s.K - w * w * s.M + 1j * w * s.C
        Zr = r.system.K - w * w * r.system.M + 1j * w * r.system.C
        full = np.linalg.solve(Z, s.F_c)
        red = r.expand(np.linalg.solve(Zr, r.system.F_c))
        assert np.abs(red - full).max() <= 1e-9 * np.abs(full).max()


def test_fewer_modes_bound_the_frequencies_from_above_and_converge() -> None:
    s = beam_system()
    w_full = s.modes()[0]
    errors = []
    for k in (1, 2, 4, 8):
        w_red = craig_bampton(s, k).system.modes()[0]
        m = min(3, w_red.size)
        assert np.all(w_red[:m] >= w_full[:m] * (1.0 - 1e-12))
        errors.append(w_red[1] / w_full[1] - 1.0)
    assert all(b < a for a, b in zip(errors, errors[1:])), errors
    assert errors[-1] < 1e-4


def test_contacts_and_state_carry_over() -> None:
    s = beam_system(N=2.0).replace(x0=0.0, v0=0.0)
    r = craig_bampton(s, 4)
    assert r.boundary == (6,) and r.system.n == 5
    c = r.system.contacts[0]
    assert c.dof == 0 and (c.N, c.mu_s, c.mu_k) == (2.0, 0.3, 0.25)
    assert r.coordinate(6) == 0
    x0 = np.linalg.solve(s.K, s.F_c)  # (a state in the reduction's span: the static one to a boundary load)
    r2 = craig_bampton(s.replace(F_c=np.eye(s.n)[6], x0=np.linalg.solve(s.K, np.eye(s.n)[6])), 4)
    assert np.abs(r2.expand(r2.system.x0) - r2.T @ r2.system.x0).max() == 0.0
    assert np.abs(r2.expand(r2.system.x0) - np.linalg.solve(s.K, np.eye(s.n)[6])).max() <= 1e-12 * np.abs(x0).max()


@pytest.mark.parametrize("kwargs, match", [
    (dict(modes=99), r"modes = 99 is out of range; valid: 0 to 19"),
    (dict(modes=2, boundary=[30]), r"boundary DOF 30 is out of range; valid: 0 to 19"),
    (dict(modes=2, boundary=[6, 6]), r"repeats a DOF"),
])
def test_bad_input_is_named(kwargs: dict, match: str) -> None:
    with pytest.raises(UsageError, match=match):
        craig_bampton(beam_system(), **kwargs)


def test_a_free_interior_is_refused() -> None:
    s = System(M=np.eye(3), K=np.array([[1.0, -1.0, 0.0], [-1.0, 1.0, 0.0], [0.0, 0.0, 0.0]]),
               contacts=[Contact(dof=0, N=1.0, mu_s=0.3)])
    with pytest.raises(UsageError, match=r"the boundary does not hold the interior"):
        craig_bampton(s, 1)


def test_orbits_of_the_reduced_beam_meet_the_full_beams_closed_forms() -> None:
    """The beam reduced to the damper's DOF, the tip's and 6 modes, h = T/400 (the reduced fastest
    rate h about 3: the located scheme; the full mesh's would be some 1,000 times too fast for it).
    Without friction the orbit's tip amplitude = the full model's closed form within 1e-4; with the
    damper stuck all cycle (N large) = the pinned beam's within 1e-4."""
    for N in (0.0, 100.0):
        s = beam_system(N=N)
        tip = s.n - 2
        r = craig_bampton(s, 6, boundary=[6, tip])
        T = 2 * np.pi / s.omega
        orbit = find_orbits(r.system.replace(h=T / 400))[0]
        amp = orbit.amplitude[r.coordinate(tip)]
        if N == 0.0:
            Z = s.K - s.omega**2 * s.M + 1j * s.omega * s.C
            closed = abs(np.linalg.solve(Z, s.F_c)[tip])
        else:
            keep = [i for i in range(s.n) if i != 6]
            Z = (s.K - s.omega**2 * s.M + 1j * s.omega * s.C)[np.ix_(keep, keep)]
            closed = abs(np.linalg.solve(Z, s.F_c[keep])[keep.index(tip)])
            assert orbit.stick_fraction[0] == 1.0
        assert orbit.converged and orbit.stable
        assert abs(amp / closed - 1.0) < 1e-4, (N, amp, closed)
