"""Jenkins contacts (k_t > 0: a spring k_t in series with a massless slider) in the DryFrictionSystem
FMU (FMI 3.0, through fmpy), against independent references: the event-driven reference
(dryfriction.references.system) on a two-mass system with a Jenkins element between the masses and
on random structures mixing Jenkins and rigid contacts, chi = mu_k / mu_s on both sides of 1 (the
located scheme second order: error ratios 3.6 to 4.4 per halving of h; the consistent scheme about
first order); with N huge the modal closed form of the structure with the springs k_t w w' added;
k_t rising with mu_s = mu_k tends to the rigid contact; the energy balance with the springs' energy
and the energy a slider's breakaway releases; FMU states with sliders restore bit for bit."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from scipy.linalg import expm

from dryfriction.references.system import simulate
from dryfriction.system.structure import Contact, System
from refcache import RefCache
from test_system_fmu import SCHEMES, SYS3, Fmu3, run


def fmu_values(s: System, scheme: str, h: float) -> dict[str, Any]:
    """The system's FMU start values (without the structural n, nc) with the step h and the scheme."""
    v = s.start_values()
    v.pop("n")
    v.pop("nc")
    return {**v, "h": h, "scheme": SCHEMES[scheme]}


def fmu_outputs(s: System, scheme: str, h: float, times: np.ndarray, tmp: Path) -> dict[str, np.ndarray]:
    """x, v (n), s, f (nc), E_friction and mode at the times (times[0] = 0)."""
    f = Fmu3(SYS3, tmp, {"n": s.n, "nc": s.nc})
    try:
        f.start(fmu_values(s, scheme, h))
        out = run(f, times, [("x", s.n), ("v", s.n), ("s", s.nc), ("f", s.nc), ("E_friction", 1)],
                  [("mode", s.nc)])
    finally:
        f.close()
    n, nc = s.n, s.nc
    cols = np.cumsum([0, n, n, nc, nc, 1, nc])
    names = ("x", "v", "s", "f", "E_friction", "mode")
    return {k: out[:, cols[i]:cols[i + 1]] for i, k in enumerate(names)}


def two_mass(chi: float, k_t: float = 200.0, mu_s: float = 0.5, N: float = 2.0) -> System:
    """Two masses on springs to the ground and between them, driven on the first; a Jenkins element
    between the masses."""
    M = np.diag([1.0, 0.5])
    K = np.array([[60.0, -20.0], [-20.0, 20.0]])
    return System(M=M, K=K, C=0.02 * K, contacts=[Contact(between=(0, 1), N=N, mu_s=mu_s, mu_k=chi * mu_s, k_t=k_t)],
                  F_c=[3.0, 0.0], omega=5.0)


def random_structure(seed: int, n_jenkins: int, n_rigid: int, chi: float) -> System:
    """2 to 4 DOFs; n_jenkins Jenkins contacts and n_rigid rigid ones (independent rows) on a DOF,
    between two DOFs or along a general row; mu_k = chi mu_s; Rayleigh damping."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 5))
    A, B = rng.normal(size=(n, n)), rng.normal(size=(n, n))
    M = A @ A.T / n + np.eye(n)
    K = 100.0 * (B @ B.T / n + 0.1 * np.eye(n))
    contacts: list[Contact] = []
    rows: list[np.ndarray] = []
    for k in range(n_jenkins + n_rigid):
        jenkins = k < n_jenkins
        mu_s = float(rng.uniform(0.1, 0.5))
        kw: dict[str, Any] = dict(N=float(rng.uniform(0.5, 3.0)), mu_s=mu_s, mu_k=chi * mu_s,
                                  k_t=float(rng.uniform(200.0, 2000.0)) if jenkins else 0.0)
        while True:
            kind = int(rng.integers(3))
            if kind == 0:
                c = Contact(dof=int(rng.integers(n)), **kw)
            elif kind == 1:
                i, j = rng.choice(n, 2, replace=False)
                c = Contact(between=(int(i), int(j)), **kw)
            else:
                c = Contact(w=rng.normal(size=n), **kw)
            row = c.row(n)
            if jenkins or np.linalg.matrix_rank(np.array(rows + [row])) > len(rows):
                break
        if not jenkins:
            rows.append(row)
        contacts.append(c)
    return System(M=M, K=K, contacts=contacts, F_c=2.0 * rng.normal(size=n), F_s=rng.normal(size=n),
                  omega=float(rng.uniform(2.0, 8.0))).with_rayleigh(0.05, 1e-3)


def errors(s: System, scheme: str, times: np.ndarray, ref: Any, tmp: Path) -> tuple[np.ndarray, ...]:
    """The largest errors in x, s (Jenkins contacts) and E_friction at h = T/200, T/400, T/800."""
    T = 2 * np.pi / s.omega
    ex, es, ee = [], [], []
    jen = s.k_t > 0
    for h in (T / 200, T / 400, T / 800):
        o = fmu_outputs(s, scheme, h, times, tmp)
        ex.append(np.max(np.abs(o["x"] - ref.x)))
        es.append(np.max(np.abs(o["s"][:, jen] - ref.s[:, jen])))
        ee.append(np.max(np.abs(o["E_friction"][:, 0] - ref.E_friction)))
    return np.array(ex), np.array(es), np.array(ee)


# --------------------------------------------------------------------- against the reference

@pytest.mark.parametrize("chi", [0.7, 1.6])
def test_two_mass_jenkins_located_is_second_order(chi: float, tmp_path: Path, refcache: RefCache) -> None:
    """A Jenkins element between two masses over 3 periods, against the event-driven reference:
    located x, s and E_friction errors fall 3.6 to 4.4 times per halving (measured 3.97, 3.99 in x
    at chi = 0.7, 3.99, 4.00 at chi = 1.6); the consistent and paper schemes converge too (at least
    first order: ratios 2.4 to 4.1 measured)."""
    s = two_mass(chi)
    T = 2 * np.pi / s.omega
    times = np.linspace(0.0, 3 * T, 31)
    ref = refcache.call(simulate, s, times[-1], times)
    assert len(ref.switches) >= 10 and {-1, 0, 1} <= set(np.unique(ref.mode))
    ex, es, ee = errors(s, "located", times, ref, tmp_path)
    assert ex[0] < 1e-3 * np.max(np.abs(ref.x))
    for e in (ex, es, ee):
        assert np.all((e[:-1] / e[1:] > 3.6) & (e[:-1] / e[1:] < 4.4)), e
    for scheme in ("consistent", "paper"):
        cx, _, _ = errors(s, scheme, times, ref, tmp_path)
        assert np.all(cx[:-1] / cx[1:] > 1.8), (scheme, cx)
        assert cx[-1] < 1e-3 * np.max(np.abs(ref.x))


RANDOM = [(1, 1, 1, 0.7), (2, 2, 1, 1.3), (3, 3, 0, 0.6)]


@pytest.mark.parametrize("seed,n_jenkins,n_rigid,chi", RANDOM, ids=[f"seed{c[0]}" for c in RANDOM])
def test_random_structures_located_second_order_consistent_first(seed: int, n_jenkins: int, n_rigid: int,
                                                                  chi: float, tmp_path: Path,
                                                                  refcache: RefCache) -> None:
    """Random structures with Jenkins and rigid contacts (chi on both sides of 1), 3 periods
    against the reference: located ratios 3.6 to 4.4 per halving (measured 3.97/3.95, 3.90/3.88,
    3.96/3.98); consistent about first order, irregular per halving (over the two halvings measured
    4.5, 2.6, 5.0: observed order 0.7 to 1.2)."""
    s = random_structure(seed, n_jenkins, n_rigid, chi)
    assert int(np.sum(s.k_t > 0)) == n_jenkins and s.nc == n_jenkins + n_rigid
    T = 2 * np.pi / s.omega
    times = np.linspace(0.0, 3 * T, 31)
    ref = refcache.call(simulate, s, times[-1], times)
    assert len(ref.switches) >= 10
    ex, es, _ = errors(s, "located", times, ref, tmp_path)
    for e in (ex, es):
        assert np.all((e[:-1] / e[1:] > 3.6) & (e[:-1] / e[1:] < 4.4)), e
    cx, _, _ = errors(s, "consistent", times, ref, tmp_path)
    assert 2.2 < cx[0] / cx[2] < 8.0, cx
    assert ex[2] < 0.5 * cx[2]


BELTS = [(-1, 0, 0, 0.7), (3, 3, 0, 0.6)]


@pytest.mark.parametrize("seed,n_jenkins,n_rigid,chi", BELTS, ids=["two_mass", "seed3"])
def test_moving_belts_keep_the_located_order(seed: int, n_jenkins: int, n_rigid: int, chi: float,
                                              tmp_path: Path, refcache: RefCache) -> None:
    """The contacts' surfaces moving (v_belt, an input, set at the start): a stuck slider moves with
    its belt. Located x and s against the reference: ratios 3.6 to 4.4 per halving (measured
    3.97/3.98 and 3.82/3.91 in x)."""
    s = two_mass(chi) if seed < 0 else random_structure(seed, n_jenkins, n_rigid, chi)
    vb = np.random.default_rng(seed + 100).uniform(-0.1, 0.1, s.nc)
    T = 2 * np.pi / s.omega
    times = np.linspace(0.0, 3 * T, 31)
    ref = refcache.call(simulate, s, times[-1], times, v_belt=vb)
    assert len(ref.switches) >= 10
    jen = s.k_t > 0
    ex, es = [], []
    for h in (T / 200, T / 400, T / 800):
        f = Fmu3(SYS3, tmp_path, {"n": s.n, "nc": s.nc})
        try:
            f.s.enterInitializationMode(startTime=0.0)
            f.set({**fmu_values(s, "located", h), "v_belt": vb})
            f.s.exitInitializationMode()
            out = run(f, times, [("x", s.n), ("s", s.nc)], [])
        finally:
            f.close()
        ex.append(np.max(np.abs(out[:, :s.n] - ref.x)))
        es.append(np.max(np.abs(out[:, s.n:][:, jen] - ref.s[:, jen])))
    for e in (np.array(ex), np.array(es)):
        assert np.all((e[:-1] / e[1:] > 3.6) & (e[:-1] / e[1:] < 4.4)), e


@pytest.mark.parametrize("mu_k", [0.55, 0.478], ids=["mu_k_above_mu_s", "mu_k_equal_mu_s"])
def test_slider_stopping_beside_a_stuck_rigid_contact_stays_stuck(mu_k: float, tmp_path: Path,
                                                                   refcache: RefCache) -> None:
    """One DOF with a rigid contact and a Jenkins contact whose mu_k >= mu_s (its breakaway limit is
    its kinetic force): twice a period the rigid contact stops the DOF while the slider slides, so the
    slider stops with its force on its limit (a hair beyond it in rounding) and stays stuck there while
    the rigid contact holds, as in the reference (both stop at one time). The located scheme runs 4
    periods (it used to stop there: too many stick/slip switches), against the reference second order:
    x and E_friction ratios 3.6 to 4.4 per halving (measured 4.01, 4.01 in x and 4.04, 4.02 in
    E_friction at both mu_k), s 3.2 to 4.4 (measured 3.33, 3.70 at mu_k = 0.55, 3.85 at the next
    halving; 4.2, 4.1 at mu_k = mu_s)."""
    s = System(M=[[1.06]], C=[[0.017]], K=[[1.427]], F_c=[-0.788], omega=2.86, x0=[0.0235],
               contacts=[Contact(dof=0, N=1.178, mu_s=0.664, mu_k=0.546),
                         Contact(dof=0, N=0.903, mu_s=0.478, mu_k=mu_k, k_t=110.0)])
    T = 2 * np.pi / s.omega
    times = np.linspace(0.0, 4 * T, 41)
    ref = refcache.call(simulate, s, times[-1], times)
    # (the case: the rigid contact and the slider stopping at one time, the slider's force on its limit)
    stops = [(a.t, b.t) for a, b in zip(ref.switches, ref.switches[1:])
             if (a.contact, a.after, b.contact, b.after) == (0, 0, 1, 0) and b.t - a.t < 1e-9]
    assert len(stops) >= 3, ref.switches
    ex, es, ee = errors(s, "located", times, ref, tmp_path)
    assert ex[0] < 1e-3 * np.max(np.abs(ref.x))
    for e in (ex, ee):
        assert np.all((e[:-1] / e[1:] > 3.6) & (e[:-1] / e[1:] < 4.4)), e
    assert np.all((es[:-1] / es[1:] > 3.2) & (es[:-1] / es[1:] < 4.4)), es


# --------------------------------------------------------------------- limits

def test_huge_normal_force_makes_a_jenkins_contact_a_spring(tmp_path: Path) -> None:
    """With N huge the sliders never slide: the structure is linear with K + sum k_t w w' (the
    springs relaxed at the start: their force -k_t w (w x - w x0)), against expm of the first-order
    system with the excitation's cos, sin and a constant appended; second order (measured 4.0)."""
    M = np.diag([1.0, 0.5])
    K = np.array([[60.0, -20.0], [-20.0, 20.0]])
    C = 0.02 * K
    contacts = [Contact(between=(0, 1), N=1e12, mu_s=0.5, k_t=150.0), Contact(dof=1, N=1e12, mu_s=0.3, k_t=80.0)]
    s = System(M=M, K=K, C=C, contacts=contacts, F_c=[3.0, -1.0], F_s=[0.0, 0.5], omega=5.0,
               x0=[0.02, -0.01], v0=[0.1, 0.0])
    W, kt = s.W, s.k_t
    Ke = K + (W.T * kt) @ W
    n, om = 2, s.omega
    Mi = np.linalg.inv(M)
    A = np.zeros((2 * n + 3, 2 * n + 3))
    A[:n, n:2 * n] = np.eye(n)
    A[n:2 * n, :n] = -Mi @ Ke
    A[n:2 * n, n:2 * n] = -Mi @ C
    A[n:2 * n, 2 * n] = Mi @ s.F_c
    A[n:2 * n, 2 * n + 1] = Mi @ s.F_s
    A[n:2 * n, 2 * n + 2] = Mi @ ((W.T * kt) @ (W @ s.x0))
    A[2 * n, 2 * n + 1] = -om
    A[2 * n + 1, 2 * n] = om
    z0 = np.concatenate([s.x0, s.v0, [1.0, 0.0, 1.0]])
    T = 2 * np.pi / om
    times = np.linspace(0.0, 3 * T, 31)
    exact = np.array([expm(A * t) @ z0 for t in times])[:, :n]
    e = []
    for h in (T / 400, T / 800):
        o = fmu_outputs(s, "located", h, times, tmp_path)
        assert np.all(o["mode"] == 0)
        np.testing.assert_array_equal(o["s"], np.tile(W @ s.x0, (times.size, 1)))  # the sliders never move
        e.append(np.max(np.abs(o["x"] - exact)))
    assert e[0] < 1e-3 * np.max(np.abs(exact))
    assert 3.6 < e[0] / e[1] < 4.4, e


def test_stiffening_jenkins_contact_tends_to_the_rigid_one(tmp_path: Path, refcache: RefCache) -> None:
    """mu_s = mu_k: the Jenkins contact with k_t = 1e2, 1e3, 1e4 times the structure's stiffness
    scale tends to the rigid contact (the same FMU with k_t = 0): the largest difference in x over 3
    periods falls as about k_t^-1/2 (measured 2.58e-2, 8.28e-3, 2.52e-3 of the motion's scale), as
    the reference's own difference does (2.58e-2, 8.30e-3, 2.56e-3: the FMU's within 3 %)."""
    T = 2 * np.pi / 5.0
    times = np.linspace(0.0, 3 * T, 61)
    h = T / 2000
    rigid = fmu_outputs(two_mass(1.0, k_t=0.0), "located", h, times, tmp_path)
    assert np.all(np.isnan(rigid["s"]))
    ref0 = refcache.call(simulate, two_mass(1.0, k_t=0.0), times[-1], times)
    scale = np.max(np.abs(rigid["x"]))
    d, dr = [], []
    for kt in (20.0 * 1e2, 20.0 * 1e3, 20.0 * 1e4):
        o = fmu_outputs(two_mass(1.0, k_t=kt), "located", h, times, tmp_path)
        d.append(np.max(np.abs(o["x"] - rigid["x"])) / scale)
        ref = refcache.call(simulate, two_mass(1.0, k_t=kt), times[-1], times)
        dr.append(np.max(np.abs(ref.x - ref0.x)) / scale)
    assert d[0] < 0.05 and d[1] < 0.4 * d[0] and d[2] < 0.4 * d[1], d
    np.testing.assert_allclose(d, dr, rtol=0.03)


def energy_balance(s: System, t: np.ndarray, X: np.ndarray, V: np.ndarray, S: np.ndarray,
                   E: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The balance's residual at the times t (a uniform grid) and the excitation's work: the change of
    0.5 v'Mv + 0.5 x'Kx + 0.5 sum_j k_t_j (w_j x - s_j)^2 (the Jenkins springs; S the sliders, nt x nc,
    NaN at rigid contacts) minus the excitation's work, plus the damping's (trapezoidal rule) and
    E_friction."""
    h = t[1] - t[0]
    springs = np.zeros(len(t))
    for j in np.flatnonzero(np.asarray(s.k_t) > 0):
        springs += 0.5 * s.k_t[j] * (X @ s.W[j] - S[:, j]) ** 2
    mech = 0.5 * np.einsum("ti,ij,tj->t", V, s.M, V) + 0.5 * np.einsum("ti,ij,tj->t", X, s.K, X) + springs
    pv = np.sum(np.outer(np.cos(s.omega * t), s.F_c) * V, 1)
    w_in = np.concatenate([[0.0], np.cumsum(0.5 * h * (pv[1:] + pv[:-1]))])
    cv = np.einsum("ti,ij,tj->t", V, s.C, V)
    d = np.concatenate([[0.0], np.cumsum(0.5 * h * (cv[1:] + cv[:-1]))])
    return mech - mech[0] - (w_in - d - E), w_in


def test_energy_balance_counts_the_springs_and_the_released_energy(tmp_path: Path) -> None:
    """Located, chi = 0.7: the change of 0.5 v'Mv + 0.5 x'Kx + 0.5 k_t (w x - s)^2 equals the
    excitation's work minus the damping's (trapezoidal rule at every internal step) minus E_friction,
    to the scheme's error; the energy the breakaways released ((F_b^2 - F_k^2) / 2 k_t each) is
    part of E_friction, and leaving it out breaks the balance by far more than that error."""
    s = two_mass(0.7)
    T = 2 * np.pi / s.omega
    h = T / 1000
    steps = 3000
    t = np.arange(steps + 1) * h
    o = fmu_outputs(s, "located", h, t, tmp_path)
    X, V, S, E, mode = o["x"], o["v"], o["s"], o["E_friction"][:, 0], o["mode"][:, 0]
    kt = s.k_t[0]
    residual, w_in = energy_balance(s, t, X, V, S, E)
    breakaways = int(np.sum((mode[:-1] == 0) & (mode[1:] != 0)))
    Fb, Fk = s.mu_s[0] * s.N[0], s.mu_k[0] * s.N[0]
    released = breakaways * (Fb ** 2 - Fk ** 2) / (2 * kt)
    assert breakaways >= 4 and E[0] == 0.0 and E[-1] > 0.1 * np.max(np.abs(w_in))
    assert np.max(np.abs(residual)) < 0.05 * released, (np.max(np.abs(residual)), released)
    assert np.max(np.abs(residual)) < 1e-4 * np.max(np.abs(w_in))


# --------------------------------------------------------------------- FMU states

def test_fmu_state_with_sliders_restores_and_round_trips_bit_for_bit(tmp_path: Path) -> None:
    """A state taken mid-run of a structure with Jenkins and rigid contacts continues to the bits of
    the run that never left it (x, v, s, f, E_friction, mode), restored in the same instance and,
    serialised, in another."""
    sysm = random_structure(1, 1, 1, 0.7)
    n, nc = sysm.n, sysm.nc
    T = 2 * np.pi / sysm.omega
    values = fmu_values(sysm, "located", T / 300)
    times = np.linspace(0.0, 2 * T, 41)
    outs = [("x", n), ("v", n), ("s", nc), ("f", nc), ("E_friction", 1)]
    f = Fmu3(SYS3, tmp_path, {"n": n, "nc": nc})
    g = Fmu3(SYS3, tmp_path, {"n": n, "nc": nc})
    try:
        f.start(values)
        for k in range(1, 21):
            f.s.doStep(times[k - 1], times[k] - times[k - 1])
        st = f.s.getFMUState()
        a = run(f, times[20:], outs, [("mode", nc)])
        assert len({tuple(r) for r in a[:, -nc:]}) >= 2  # the modes change after the state
        jen = np.flatnonzero(sysm.k_t > 0)
        assert np.unique(a[:, 2 * n + jen[0]]).size > 2  # the slider moves after the state
        f.s.setFMUState(st)
        b = run(f, times[20:], outs, [("mode", nc)])
        assert a.tobytes() == b.tobytes()
        blob = f.s.serializeFMUState(st)
        g.start(values)
        g.s.setFMUState(g.s.deserializeFMUState(blob))
        c = run(g, times[20:], outs, [("mode", nc)])
        assert a.tobytes() == c.tobytes()
        f.s.freeFMUState(st)
    finally:
        f.close()
        g.close()


def test_h_zero_resolves_the_stuck_springs(tmp_path: Path) -> None:
    """h = 0: h_used is 1/1000 of 2 pi over the fastest rate with every slider stuck, the stiffness
    K + sum k_t w w' (eigenvalues by numpy here, by power iteration in the FMU); a rigid contact
    adds nothing."""
    s = two_mass(0.7, k_t=500.0)
    got = []
    for kt in (500.0, 0.0):
        f = Fmu3(SYS3, tmp_path, {"n": 2, "nc": 1})
        try:
            f.start({**fmu_values(s, "located", 0.0), "k_t": [kt]})
            got.append(f.real("h_used")[0])
        finally:
            f.close()
    for kt, h in zip((500.0, 0.0), got):
        Ke = s.K + kt * np.outer(s.W[0], s.W[0])
        rate = (np.sqrt(max(np.linalg.eigvals(np.linalg.solve(s.M, Ke)).real)) +
                max(np.linalg.eigvals(np.linalg.solve(s.M, s.C)).real) + s.omega)
        assert h == pytest.approx(2 * np.pi / rate / 1000, rel=1e-8)
    assert got[0] < 0.5 * got[1]


@pytest.mark.parametrize("scheme", list(SCHEMES))
def test_normal_force_changes_keep_the_energy_balance(scheme: str, tmp_path: Path) -> None:
    """N_ext stepped every 500 steps (down to 0.4 N, up to 1.4 N): a sliding slider whose spring
    force exceeds the new kinetic force has it drop (the slider jumps, the released energy counted),
    one below it sticks, a stuck one beyond the new limit breaks away. The energy balance (springs
    included) holds through the changes to the schemes' error (measured 1.3e-5 located, 1.3e-4
    consistent, 2.6e-5 paper, of the input work)."""
    s = two_mass(0.7)
    T = 2 * np.pi / s.omega
    h, steps = T / 1000, 3000
    t = np.arange(steps + 1) * h
    rows: dict[bool, Any] = {}
    for change in (True, False):
        f = Fmu3(SYS3, tmp_path, {"n": 2, "nc": 1})
        X, V, S, E = [], [], [], []
        try:
            f.start(fmu_values(s, scheme, h))
            for k in range(steps + 1):
                if k:
                    if change and k % 500 == 0:
                        f.set({"N_ext": [-1.2 if (k // 500) % 2 else 0.8]})
                    f.s.doStep(t[k - 1], h)
                X.append(f.real("x", 2))
                V.append(f.real("v", 2))
                S.append(f.real("s", 1)[0])
                E.append(f.real("E_friction")[0])
        finally:
            f.close()
        rows[change] = (np.array(X), np.array(V), np.array(S), np.array(E))
    X, V, S, E = rows[True]
    assert abs(E[-1] - rows[False][3][-1]) > 0.01 * E[-1]  # the changes matter
    res, w_in = energy_balance(s, t, X, V, S[:, None], E)
    residual = np.max(np.abs(res))
    assert residual < (1e-4 if scheme == "located" else 1e-3) * np.max(np.abs(w_in)), residual
    assert np.diff(E).min() >= 0.0


def test_early_return_ends_steps_at_the_sliders_switches(tmp_path: Path, refcache: RefCache) -> None:
    """FMI 3.0 with early return: a long step ends at each slider's stick and breakaway in turn,
    all of the reference's switches, each at its time to the located scheme's accuracy (measured
    1.8e-5 s at most at h = T/800 = 1.6e-3 s)."""
    from fmpy import extract, read_model_description
    from fmpy.fmi3 import FMU3Slave

    sysm = two_mass(0.7)
    T = 2 * np.pi / sysm.omega
    ref = refcache.call(simulate, sysm, 2 * T, [2 * T])
    md = read_model_description(str(SYS3))
    d = extract(str(SYS3), unzipdir=str(tmp_path / "early"))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    s = FMU3Slave(guid=md.guid, unzipDirectory=d, modelIdentifier=md.coSimulation.modelIdentifier)
    s.instantiate(loggingOn=False, earlyReturnAllowed=True)
    try:
        s.enterConfigurationMode()
        s.setUInt64([vr["n"], vr["nc"]], [2, 1])
        s.exitConfigurationMode()
        s.enterInitializationMode(startTime=0.0)
        for name, value in fmu_values(sysm, "located", T / 800).items():
            if name in ("scheme", "friction_law"):
                s.setInt64([vr[name]], [int(x) for x in np.ravel(value)])
            else:
                s.setFloat64([vr[name]], [float(x) for x in np.ravel(value)])
        s.exitInitializationMode()
        t, ends = 0.0, []
        while t < 2 * T:
            _, _, early, t_last = s.doStep(t, 2 * T - t)
            if not early:
                break
            t = t_last
            ends.append(t)
    finally:
        s.terminate()
        s.freeInstance()
    want = ref.switch_times
    assert len(want) >= 6 and len(ends) == len(want)
    assert np.max(np.abs(np.array(ends) - want)) < 5e-5, np.max(np.abs(np.array(ends) - want))


# --------------------------------------------------------------------- beside a Stribeck contact

def stribeck_and_jenkins() -> System:
    """Three DOFs in a chain to the ground, driven on the first and the last; a rigid Stribeck
    contact on DOF 0 and a Jenkins element between DOFs 1 and 2 (both stick and slip)."""
    M = np.diag([1.0, 0.8, 0.5])
    K = np.array([[70.0, -30.0, 0.0], [-30.0, 50.0, -20.0], [0.0, -20.0, 20.0]])
    return System(M=M, K=K, C=0.02 * K,
                  contacts=[Contact(dof=0, N=2.0, mu_s=0.5, mu_k=0.3, law="stribeck", v_s=0.05, delta=1.0),
                            Contact(between=(1, 2), N=1.5, mu_s=0.4, mu_k=0.3, k_t=150.0)],
                  F_c=[4.0, 0.0, 2.0], omega=5.0)


def test_beside_a_stribeck_contact_located_is_second_order(tmp_path: Path) -> None:
    """A rigid Stribeck contact coupled with a Jenkins element (the event-driven reference models no
    Stribeck law): located's differences between h and h/2 (h = T/200 to T/1600 over 4 periods) fall
    3.6 to 4.4 times per halving in x, the slider's s and E_friction (measured 3.98, 4.00, 4.00 in x;
    3.98, 4.00, 4.00 in s; 3.87, 4.00, 3.88 in E_friction), both contacts sticking and slipping."""
    s = stribeck_and_jenkins()
    T = 2 * np.pi / s.omega
    times = np.linspace(0.0, 4 * T, 41)
    outs = [fmu_outputs(s, "located", T / k, times, tmp_path) for k in (200, 400, 800, 1600, 3200)]
    for j in range(2):
        modes = outs[-1]["mode"][:, j]
        assert np.any(modes == 0) and np.any(modes != 0), j
    for key, cols in (("x", slice(None)), ("s", [1]), ("E_friction", slice(None))):
        d = np.array([np.max(np.abs(a[key][:, cols] - b[key][:, cols])) for a, b in zip(outs[:-1], outs[1:])])
        assert d[0] < 1e-2 * np.max(np.abs(outs[-1][key][:, cols])), (key, d)  # measured 4e-4 to 1.5e-3
        r = d[:-1] / d[1:]
        assert np.all((3.6 < r) & (r < 4.4)), (key, r)


def test_beside_a_stribeck_contact_the_energy_balance_holds(tmp_path: Path) -> None:
    """Located, h = T/1000 over 3 periods: the change of 0.5 v'Mv + 0.5 x'Kx + 0.5 k_t (w x - s)^2
    equals the excitation's work minus the damping's (trapezoidal rule at every internal step) minus
    E_friction (the Stribeck contact's and the Jenkins element's) to the scheme's error (measured
    1.3e-5 against an input work of 1.8 and E_friction 0.51)."""
    s = stribeck_and_jenkins()
    T = 2 * np.pi / s.omega
    h = T / 1000
    t = np.arange(3001) * h
    o = fmu_outputs(s, "located", h, t, tmp_path)
    X, V, S, E, mode = o["x"], o["v"], o["s"], o["E_friction"][:, 0], o["mode"]
    residual, w_in = energy_balance(s, t, X, V, S, E)
    assert np.all(np.isnan(S[:, 0]))  # (no slider at the rigid contact)
    assert np.mean(mode[:, 0] == 0) > 0.02 and np.mean(mode[:, 1] == 0) > 0.1
    assert E[-1] > 0.2 * np.max(np.abs(w_in))
    assert np.max(np.abs(residual)) < 1e-4 * np.max(np.abs(w_in)), (np.max(np.abs(residual)), np.max(np.abs(w_in)))
