"""The event-driven reference of a structure (dryfriction.references.system) against independent
solutions: one DOF with one rigid contact is the oscillator's exact solution (the same switches),
on a belt the belt reference's; the two-mass case is tests/two_mass_reference.py's; a chain of 3 is
the chain reference's, on belts too; without friction (N = 0) the forced linear system's modal
closed form; a Jenkins element with N huge is a linear spring k_t; with k_t rising (mu_s = mu_k) it
tends to the rigid contact; on random structures the energy balances and every contact keeps its
friction law."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dryfriction import Contact, System
from dryfriction.params import Oscillator
from dryfriction.references.belt import Belt
from dryfriction.references.belt import simulate as belt_reference
from dryfriction.references.chain import Chain, solve_chain
from dryfriction.references.exact import solve_exact
from dryfriction.references.system import simulate
from two_mass_reference import TwoMass
from two_mass_reference import simulate as two_mass

# the work-precision study's cases (bench/cases.py), lam, mu_s sigma, chi, zeta
CASES = {"stick_dominated": (0.25, 0.6, 0.6, 0.0), "chi_near_0": (0.5, 0.4, 0.05, 0.0),
         "chi_above_1": (0.5, 0.3, 1.5, 0.0)}


@pytest.mark.parametrize("case", sorted(CASES))
def test_one_dof_with_one_rigid_contact_is_the_exact_oscillator(case: str) -> None:
    osc = Oscillator.from_nondimensional(*CASES[case])
    T = osc.period
    t = np.linspace(0.0, 10 * T, 1501)
    r = simulate(System.from_oscillator(osc), 10 * T, t)
    ex = solve_exact(osc, 10 * T)
    x, v, _, mode = ex.evaluate(t)
    scale = osc.P0 / osc.k
    assert np.max(np.abs(r.x[:, 0] - x)) < 1e-8 * scale
    assert np.max(np.abs(r.v[:, 0] - v)) < 1e-8 * scale * osc.w0
    sw = ex.switch_times()
    assert sw.size >= 19 and r.switch_times.size == sw.size
    np.testing.assert_allclose(r.switch_times, sw, rtol=0, atol=1e-9 * T)
    inside = np.min(np.abs(t[:, None] - sw[None, :]), axis=1) > 1e-6 * T
    np.testing.assert_array_equal(r.mode[inside, 0], mode[inside])
    # the stuck force within its limit, the sliding one kinetic
    stuck = r.mode[:, 0] == 0
    assert np.all(np.abs(r.f[stuck, 0]) <= osc.breakaway * (1 + 1e-12))
    np.testing.assert_allclose(r.f[~stuck, 0], -r.mode[~stuck, 0] * osc.mu_k * osc.N, rtol=1e-15)


TM = TwoMass(m1=1.0, m2=0.5, k1=100.0, k2=20.0, k12=50.0, c1=0.5, c2=0.3, c12=0.0, P1=1.0, P2=0.5,
             omega=6.0, N_g=2.0, mu_s_g=0.4, mu_k_g=0.28, N_c=1.0, mu_s_c=0.3, mu_k_c=0.2)


def _two_mass_system(p: TwoMass) -> System:
    return System(M=p.mass, K=p.stiffness, C=p.damping, F_c=[p.P1, p.P2], omega=p.omega,
                  contacts=[Contact(dof=0, N=p.N_g, mu_s=p.mu_s_g, mu_k=p.mu_k_g),
                            Contact(between=(0, 1), N=p.N_c, mu_s=p.mu_s_c, mu_k=p.mu_k_c)])


@pytest.mark.parametrize("p", [TM, TM.with_(N_g=2.5)], ids=["base", "general"])
def test_two_masses_are_the_two_mass_reference(p: TwoMass) -> None:
    T = 2 * math.pi / p.omega
    t = np.linspace(0.0, 4 * T, 801)
    r = simulate(_two_mass_system(p), 4 * T, t)
    ref = two_mass(p, 4 * T)
    x, v, modes = ref.evaluate(t)
    assert np.max(np.abs(r.x - x)) < 1e-11 and np.max(np.abs(r.v - v)) < 1e-10
    assert len(r.switches) == len(ref.switches) >= 18
    for a, b in zip(r.switches, ref.switches):
        assert (a.contact, a.before, a.after) == (b.contact, b.before, b.after)
        assert abs(a.t - b.t) < 1e-10 * T
    np.testing.assert_array_equal(r.mode, modes)
    assert len({ph.modes for ph in r.solution.phases}) >= 4
    stuck = r.mode == 0
    assert np.all(np.abs(r.f[stuck]) <= (np.array([p.mu_s_g * p.N_g, p.mu_s_c * p.N_c]) * (1 + 1e-12))[
        np.nonzero(stuck)[1]])


def test_a_chain_of_three_is_the_chain_reference() -> None:
    ch = Chain.make(3, omega=0.8, m=[1.0, 0.8, 1.2], k=[1.0, 0.7, 1.3], c=[0.05, 0.0, 0.1], P0=[1.0, 0.0, 0.5],
                    phi=[0.0, 0.0, 0.7], N=[0.8, 0.5, 0.6], mu_s=0.5, chi=[0.7, 0.5, 1.2])
    T = ch.period
    t = np.linspace(0.0, 5 * T, 1001)
    ref = solve_chain(ch, 5 * T)
    out = ref.evaluate(t)
    s = System.from_chain(m=ch.m, k=ch.k, c=ch.c, P0=ch.P0, phi=ch.phi, N=ch.N, mu_s=ch.mu_s, chi=ch.chi,
                          omega=ch.omega)
    r = simulate(s, 5 * T, t)
    assert np.max(np.abs(r.x - out["x"])) < 1e-9 * np.max(np.abs(out["x"]))
    assert len(r.switches) == len(ref.events) >= 30
    for a, (te, i, before, after) in zip(r.switches, ref.events):
        assert (a.contact, a.before, a.after) == (i, before, after) and abs(a.t - te) < 1e-8 * T
    np.testing.assert_array_equal(r.mode, out["mode"])


@pytest.mark.parametrize("v_belt", [0.05, -0.02])
def test_one_dof_on_a_belt_is_the_belt_reference(v_belt: float) -> None:
    b = Belt(m=1.0, k=100.0, c=0.4, N=2.0, mu_s=0.5, mu_k=0.3, P0=1.0, omega=4.0, phi=0.3)
    T = 2 * math.pi / b.omega
    t = np.linspace(0.0, 10 * T, 2001)
    ref = belt_reference(b, t, v_belt=v_belt)
    s = System(M=[[b.m]], K=[[b.k]], C=[[b.c]], F_c=[b.P0 * math.cos(b.phi)], F_s=[-b.P0 * math.sin(b.phi)],
               omega=b.omega, contacts=[Contact(dof=0, N=b.N, mu_s=b.mu_s, mu_k=b.mu_k)])
    r = simulate(s, 10 * T, t, v_belt=[v_belt])
    assert np.max(np.abs(r.x[:, 0] - ref.x)) < 1e-11 * np.max(np.abs(ref.x))
    np.testing.assert_array_equal(r.mode[:, 0], ref.mode)
    assert len(r.switches) == len(ref.events) >= 15
    np.testing.assert_allclose([sw.t for sw in r.switches], [e[0] for e in ref.events], rtol=0, atol=1e-10 * T)
    stuck = r.mode[:, 0] == 0
    np.testing.assert_allclose(r.v[stuck, 0], v_belt, rtol=1e-12)


def test_a_chain_of_three_on_belts_is_the_chain_reference() -> None:
    ch = Chain.make(3, omega=0.8, m=[1.0, 0.8, 1.2], k=[1.0, 0.7, 1.3], c=[0.05, 0.0, 0.1], P0=[1.0, 0.0, 0.5],
                    phi=[0.0, 0.0, 0.7], N=[0.8, 0.5, 0.6], mu_s=0.5, chi=[0.7, 0.5, 1.2], v_belt=[0.1, -0.05, 0.0])
    T = ch.period
    t = np.linspace(0.0, 5 * T, 1001)
    out = solve_chain(ch, 5 * T)
    s = System.from_chain(m=ch.m, k=ch.k, c=ch.c, P0=ch.P0, phi=ch.phi, N=ch.N, mu_s=ch.mu_s, chi=ch.chi,
                          omega=ch.omega)
    r = simulate(s, 5 * T, t, v_belt=ch.v_belt)
    ref = out.evaluate(t)
    assert np.max(np.abs(r.x - ref["x"])) < 1e-9 * np.max(np.abs(ref["x"]))
    np.testing.assert_array_equal(r.mode, ref["mode"])
    assert len(r.switches) == len(out.events) >= 30
    for a, (te, i, before, after) in zip(r.switches, out.events):
        assert (a.contact, a.before, a.after) == (i, before, after) and abs(a.t - te) < 1e-8 * T


# ---- the linear cases: the modal closed form ---------------------------------------------------------

def _modal_closed_form(s: System, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """x(t), v(t) of M x'' + C x' + K x = F_c cos(omega t) + F_s sin(omega t) for a C diagonal in the
    mass-normalised modes (modal damping, zeta < 1, every frequency > 0): per mode the steady state
    Re(Q e^{i omega t}), Q = p / (w^2 - omega^2 + 2 i zeta w omega), p = Phi'(F_c - i F_s), plus the
    damped free motion that meets the initial conditions."""
    lam, phi = np.linalg.eig(np.linalg.solve(s.M, s.K))
    order = np.argsort(lam.real)
    lam, phi = lam.real[order], phi.real[:, order]
    phi = phi / np.sqrt(np.einsum("ir,ij,jr->r", phi, s.M, phi))        # mass-normalised
    w = np.sqrt(lam)
    cmodal = phi.T @ s.C @ phi
    assert np.max(np.abs(cmodal - np.diag(np.diag(cmodal)))) < 1e-12 * np.max(np.abs(cmodal))
    zeta = np.diag(cmodal) / (2 * w)
    om = s.omega
    p = phi.T @ (s.F_c - 1j * s.F_s)
    Q = p / (w ** 2 - om ** 2 + 2j * zeta * w * om)
    q0 = phi.T @ s.M @ s.x0 - Q.real
    dq0 = phi.T @ s.M @ s.v0 - (1j * om * Q).real
    wd = w * np.sqrt(1 - zeta ** 2)
    tt = t[:, None]
    e = np.exp(-zeta * w * tt)
    A, B = q0, (dq0 + zeta * w * q0) / wd
    q = e * (A * np.cos(wd * tt) + B * np.sin(wd * tt)) + (Q * np.exp(1j * om * tt)).real
    dq = (e * ((B * wd - zeta * w * A) * np.cos(wd * tt) - (A * wd + zeta * w * B) * np.sin(wd * tt))
          + (1j * om * Q * np.exp(1j * om * tt)).real)
    return q @ phi.T, dq @ phi.T


M3 = np.array([[2.0, 0.5, 0.0], [0.5, 1.0, 0.2], [0.0, 0.2, 1.5]])
K3 = np.array([[300.0, -100.0, 0.0], [-100.0, 250.0, -150.0], [0.0, -150.0, 150.0]])


def test_without_friction_the_modal_closed_form() -> None:
    """N = 0 on every contact (rigid and Jenkins, ground and between DOFs): the linear system."""
    s = System(M=M3, K=K3, F_c=[1.0, 0.0, 0.5], F_s=[0.0, 0.3, 0.0], omega=9.0, x0=[0.01, 0.0, -0.005],
               v0=[0.0, 0.05, 0.0], contacts=[Contact(dof=0, N=0.0, mu_s=0.3), Contact(between=(1, 2), mu_s=0.5),
                                              Contact(dof=2, N=0.0, mu_s=0.2, k_t=1e3)])
    s = s.with_modal_damping([0.01, 0.03, 0.05])
    T = 2 * math.pi / s.omega
    t = np.linspace(0.0, 20 * T, 2001)
    r = simulate(s, 20 * T, t)
    x, v = _modal_closed_form(s, t)
    assert np.max(np.abs(x)) > 5e-3
    assert np.max(np.abs(r.x - x)) < 1e-9 * np.max(np.abs(x))
    assert np.max(np.abs(r.v - v)) < 1e-9 * np.max(np.abs(v))
    assert r.switches == [] and np.all(r.f == 0.0)


def test_a_jenkins_element_with_a_huge_normal_load_is_a_spring() -> None:
    """Never sliding, the element is a spring k_t on its row: the linear system with K + k_t w w'."""
    kt = 80.0
    w = np.array([0.0, 1.0, -1.0])
    # the slider starts with its spring relaxed (s = g): g = w x0 = 0 for the spring relaxed at x = 0
    lin = System(M=M3, K=K3 + kt * np.outer(w, w), F_c=[1.0, 0.0, 0.5], omega=7.0, x0=[0.01, 0.005, 0.005])
    lin = lin.with_modal_damping(0.02)
    s = lin.replace(K=K3, contacts=[Contact(between=(1, 2), N=1e8, mu_s=0.3, mu_k=0.2, k_t=kt)])
    T = 2 * math.pi / s.omega
    t = np.linspace(0.0, 10 * T, 1001)
    r = simulate(s, 10 * T, t)
    x, v = _modal_closed_form(lin, t)
    assert np.max(np.abs(r.x - x)) < 1e-9 * np.max(np.abs(x))
    assert np.max(np.abs(r.v - v)) < 1e-9 * np.max(np.abs(v))
    np.testing.assert_allclose(r.f[:, 0], -kt * (x @ w), rtol=0, atol=1e-9 * kt * np.max(np.abs(x)))
    np.testing.assert_array_equal(r.s[:, 0], 0.0)                           # the slider never moved
    assert r.switches == [] and np.all(r.mode == 0)


def _rising_base() -> System:
    M = np.array([[1.0, 0.1], [0.1, 0.5]])
    K = np.array([[150.0, -50.0], [-50.0, 70.0]])
    return System(M=M, K=K, F_c=[1.0, 0.5], F_s=[0.0, 0.3], omega=6.0, x0=[0.01, 0.0],
                  v0=[0.0, 0.1]).with_modal_damping([0.02, 0.05])


def test_a_jenkins_element_tends_to_the_rigid_contact_as_k_t_rises() -> None:
    """mu_s = mu_k (method.md section 13: with mu_s > mu_k the limit differs by O(1)): the
    difference from the rigid contact falls as k_t rises (about as k_t^-1/2: the slider's spring
    stretch mu_k N / k_t and the ringing it leaves), and the sliders slide and stick."""
    base = _rising_base()
    T = 2 * math.pi / base.omega
    t = np.linspace(0.0, 2 * T, 401)
    rigid = simulate(base.replace(contacts=[Contact(dof=0, N=2.0, mu_s=0.3)]), 2 * T, t)
    assert len(rigid.switches) >= 6
    errors = []
    for kt in (1e3, 1e4, 1e5):
        r = simulate(base.replace(contacts=[Contact(dof=0, N=2.0, mu_s=0.3, k_t=kt)]), 2 * T, t)
        errors.append(np.max(np.abs(r.x - rigid.x)))
        assert len(r.switches) >= 6
        assert np.all(np.abs(r.f[:, 0]) <= 0.6 * (1 + 1e-9))                     # |f| <= mu N
        sliding = r.mode[:, 0] != 0
        np.testing.assert_allclose(r.f[sliding, 0], -0.6 * r.mode[sliding, 0], rtol=1e-12)
        # the slider's spring force is its stretch
        np.testing.assert_allclose(r.f[:, 0], -kt * (r.x[:, 0] - r.s[:, 0]), rtol=0, atol=1e-7 * 0.6)
    scale = np.max(np.abs(rigid.x))
    assert errors[0] < 0.3 * scale
    assert errors[2] < 0.02 * scale
    assert errors[1] < 0.5 * errors[0] and errors[2] < 0.5 * errors[1]


def test_a_jenkins_breakaway_drops_the_force_and_jumps_the_slider() -> None:
    """mu_s > mu_k: at a breakaway the force falls from mu_s N to mu_k N, the slider jumps by
    (mu_s - mu_k) N / k_t; while stuck the slider stays put."""
    kt, N, mu_s, mu_k = 2e3, 2.0, 0.4, 0.25
    s = _rising_base().replace(contacts=[Contact(dof=0, N=N, mu_s=mu_s, mu_k=mu_k, k_t=kt)])
    T = 2 * math.pi / s.omega
    r = simulate(s, 3 * T)
    sol = r.solution
    breaks = [sw for sw in r.switches if sw.before == 0]
    sticks = [sw for sw in r.switches if sw.after == 0]
    assert len(breaks) >= 2 and len(sticks) >= 2
    for sw in breaks:
        before = sol.evaluate([sw.t * (1 - 1e-12)])
        after = sol.evaluate([sw.t])
        assert abs(before["f"][0, 0]) == pytest.approx(mu_s * N, rel=1e-6)
        assert after["f"][0, 0] == pytest.approx(-sw.after * mu_k * N, rel=1e-15)
        assert after["s"][0, 0] - before["s"][0, 0] == pytest.approx(sw.after * (mu_s - mu_k) * N / kt, rel=1e-6)
    for ph in sol.phases:
        if ph.modes[0] == 0 and ph.t1 > ph.t0:
            s_ph = sol.evaluate(np.linspace(ph.t0, ph.t1, 6)[:-1])["s"][:, 0]     # t1: the next phase
            assert np.all(s_ph == s_ph[0])


def test_contacts_coupled_through_the_mass_matrix_hold_within_their_limits() -> None:
    """Three rigid contacts, one between DOFs, and a Jenkins one on a non-diagonal M: the held
    forces within their limits, the held slips 0, the sliding forces kinetic."""
    s = System(M=M3, K=K3, F_c=[2.0, 0.0, 1.0], F_s=[0.0, 1.0, 0.0], omega=8.0,
               contacts=[Contact(dof=0, N=2.0, mu_s=0.4, mu_k=0.3), Contact(between=(2, 1), N=1.0, mu_s=0.3, mu_k=0.35),
                         Contact(w=[0.0, 1.0, 1.0], N=1.5, mu_s=0.2, mu_k=0.15),
                         Contact(dof=1, N=1.0, mu_s=0.3, mu_k=0.2, k_t=400.0)]).with_rayleigh(0.1, 1e-3)
    T = 2 * math.pi / s.omega
    t = np.linspace(0.0, 4 * T, 801)
    r = simulate(s, 4 * T, t)
    assert len(r.switches) >= 8
    slip = r.v @ s.W.T
    Fb = s.breakaway
    for j in range(3):
        held = r.mode[:, j] == 0
        assert held.any() and (~held).any()
        assert np.all(np.abs(r.f[held, j]) <= Fb[j] * (1 + 1e-9))
        assert np.all(np.abs(slip[held, j]) < 1e-9)
        np.testing.assert_allclose(r.f[~held, j], -r.mode[~held, j] * s.mu_k[j] * s.N[j], rtol=1e-15)
        assert np.all(np.sign(slip[~held, j]) * r.mode[~held, j] >= 0)
    assert np.all(np.abs(r.f[:, 3]) <= Fb[3] * (1 + 1e-9))


def _random_system(rng: np.random.Generator) -> System:
    """2 to 6 DOFs, 1 to 4 contacts of both kinds (on a DOF, between two, a general row; rigid
    rows independent), chi = mu_k / mu_s on both sides of 1, Rayleigh damping."""
    n = int(rng.integers(2, 7))
    A, B = rng.normal(size=(n, n)), rng.normal(size=(n, n))
    M = A @ A.T / n + np.eye(n)
    K = 100.0 * (B @ B.T / n + 0.1 * np.eye(n))
    contacts: list[Contact] = []
    rigid_rows: list[np.ndarray] = []
    while len(contacts) < int(rng.integers(1, 5)):
        kind = int(rng.integers(3))
        mu_s = float(rng.uniform(0.1, 0.5))
        kw = dict(N=float(rng.uniform(0.5, 3.0)), mu_s=mu_s, mu_k=float(rng.choice([0.5, 0.8, 1.0, 1.3])) * mu_s,
                  k_t=0.0 if rng.random() < 0.5 else float(rng.uniform(200.0, 2000.0)))
        if kind == 0:
            c = Contact(dof=int(rng.integers(n)), **kw)  # type: ignore[arg-type]
        elif kind == 1:
            i, k = rng.choice(n, 2, replace=False)
            c = Contact(between=(int(i), int(k)), **kw)  # type: ignore[arg-type]
        else:
            c = Contact(w=rng.normal(size=n), **kw)  # type: ignore[arg-type]
        row = c.row(n)
        if c.k_t == 0.0 and np.linalg.matrix_rank(np.array(rigid_rows + [row])) <= len(rigid_rows):
            continue
        if c.k_t == 0.0:
            rigid_rows.append(row)
        contacts.append(c)
    return System(M=M, K=K, contacts=contacts, F_c=rng.normal(size=n), F_s=rng.normal(size=n),
                  omega=float(rng.uniform(2.0, 12.0))).with_rayleigh(0.05, 1e-3)


@pytest.mark.parametrize("seed", [0, 1, 3, 5])
def test_random_structures_balance_their_energy_and_keep_the_friction_laws(seed: int) -> None:
    """Input work (the excitation's and, seeds 3 and 5, the belts' f v_belt) = kinetic + potential
    energy (the Jenkins springs' too) + viscous + friction dissipation (sliding |f| |slip|, and the
    spring energy a Jenkins breakaway releases, (F_b^2 - F_k^2) / 2 k_t), by quadrature of the
    sampled motion; a held rigid contact does not slip and holds within its limit; a sliding
    contact's force is kinetic and against its slip. Measured: the balance within 1e-11 of the
    input work's scale, the breakaways' spring energy up to 4e-3 of it."""
    rng = np.random.default_rng(seed)
    s = _random_system(rng)
    vb = rng.uniform(-0.05, 0.05, s.nc) if seed >= 3 else np.zeros(s.nc)
    T = 2 * math.pi / s.omega
    r0 = simulate(s, 3 * T, [3 * T], v_belt=vb)
    # the grid holds every switch and a point just before it (a slider's sliding dissipation starts
    # with a jump at its breakaway); its midpoints added, Richardson's extrapolation of the
    # trapezoidal rule on both (the integrands are smooth between the switches): Simpson's rule
    sw = r0.switch_times
    base = np.unique(np.concatenate([np.linspace(0.0, 3 * T, 3001), sw, sw - 1e-12 * T]))
    t = np.empty(2 * base.size - 1)
    t[0::2], t[1::2] = base, 0.5 * (base[1:] + base[:-1])
    r = r0.solution.evaluate(t)

    def integral(y: np.ndarray) -> float:
        return (4.0 * np.trapezoid(y, t) - np.trapezoid(y[0::2], base)) / 3.0

    x, v, f, mode, sl = r["x"], r["v"], r["f"], r["mode"], r["s"]
    W, Fb, Fk, kt = s.W, s.breakaway, s.mu_k * s.N, s.k_t
    slip = v @ W.T - vb
    jen = kt > 0
    for j in range(s.nc):
        held = mode[:, j] == 0
        assert np.all(np.abs(f[:, j]) <= Fb[j] * (1 + 1e-9))
        np.testing.assert_allclose(f[~held, j], -mode[~held, j] * Fk[j], rtol=1e-15)
        assert np.all(slip[~held, j] * mode[~held, j] >= -1e-9 * np.max(np.abs(slip)))
        if not jen[j]:
            assert np.all(np.abs(slip[held, j]) < 1e-9 * np.max(np.abs(v)))
    P = np.outer(np.cos(s.omega * t), s.F_c) + np.outer(np.sin(s.omega * t), s.F_s)
    g = x @ W.T
    stretch = np.where(jen, g - np.nan_to_num(sl), 0.0)
    energy = (0.5 * np.einsum("ti,ij,tj->t", v, s.M, v) + 0.5 * np.einsum("ti,ij,tj->t", x, s.K, x)
              + 0.5 * np.sum(kt * stretch ** 2, axis=1))
    work = integral(np.sum(P * v, axis=1)) + integral(f @ vb)
    viscous = integral(np.einsum("ti,ij,tj->t", v, s.C, v))
    sliding = integral(np.sum(np.where(mode != 0, Fk * np.abs(slip), 0.0), axis=1))
    jumps = sum((Fb[sw.contact] ** 2 - Fk[sw.contact] ** 2) / (2 * kt[sw.contact])
                for sw in r0.switches if jen[sw.contact] and sw.before == 0)
    assert len(r0.switches) >= 4
    scale = integral(np.abs(np.sum(P * v, axis=1))) + integral(np.abs(f @ vb))
    assert abs(work - (energy[-1] - energy[0]) - viscous - sliding - jumps) < 1e-10 * scale
    # the reference's own account of the friction dissipation
    assert r["E_friction"][-1] == pytest.approx(sliding + jumps, rel=1e-9)
    assert np.all(np.diff(r["E_friction"]) >= -1e-10 * r["E_friction"][-1])        # at a switch: rounding


def test_rigid_contacts_with_dependent_rows_that_cannot_settle_are_named() -> None:
    """Contacts to the ground on two DOFs and a weak one between them (its row the difference of the
    others): its share of the holding forces exceeds its limit while the other two hold its row, so
    it cannot slip; the reference stops with an error naming the three (parallel rows settle:
    tests/test_system_dependent.py)."""
    s = System(M=np.eye(2), K=np.diag([1.0, 2.0]), F_c=[1.0, -1.0], omega=1.0,
               contacts=[Contact(dof=0, N=5.0, mu_s=0.2, mu_k=0.2), Contact(dof=1, N=5.0, mu_s=0.2, mu_k=0.2),
                         Contact(between=(0, 1), N=0.001, mu_s=1.0, mu_k=1.0)])
    with pytest.raises(RuntimeError, match=r"the rigid contacts 0, 1, 2 have dependent rows"):
        simulate(s, 20.0)
