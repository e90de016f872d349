"""Validation of the DryFrictionSystem FMU (FMI 3.0, through dryfriction.System's driver) against what
does not share its code:

* the event-driven reference (dryfriction.references.system: DOP853 between events, events by root
  finding, the rest rule) on random structures of 2 to 6 DOFs with 1 to 4 rigid contacts, on the
  ground and between DOFs, chi = mu_k / mu_s below 1 and above 1: the located scheme converges at
  order 2 (the error ratio per halving of h in [3.6, 4.4], every structure, every halving), the
  consistent scheme at order 1 (the median over the structures of the fitted slope); these
  structures' damping 0.002 K is diagonal in the modal basis (the model's modal backend), and two of
  them with a dashpot added (the dense backend) converge at order 2 too;
* without friction (N = 0), the modal closed form over 100 periods of the slowest mode;
* bench/bench_system.c's chain of 16 blocks with a contact on every block, every other one also
  between blocks, where several contacts switch at one instant: located runs to the end and
  converges to the reference at order 2.

The scheme's error level (N = 0): Bossak-Newmark's own solution of each decoupled mode, i.e. the
closed form of the scheme (the mode's 3 x 3 amplification matrix of (q, q', Bossak's A) raised to
the step count, the forcing added step by step). It differs from the continuous closed form by the
scheme's truncation error alone (the FMU's distance to the continuous closed form falls 4x per
halving of h); the FMU must equal it within 1e-10 of the amplitude over the 100 periods (measured:
a few 1e-13, rounding).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from dryfriction import Contact, System
from dryfriction.drivers.system import trajectory
from dryfriction.references.system import simulate
from refcache import RefCache


# --------------------------------------------------------------------------- random structures

def random_system(seed: int, chi_above: bool, n: int, nc: int) -> System:
    """A chain-like structure of n DOFs with a coupled (non-diagonal) mass matrix, light
    stiffness-proportional damping and nc rigid contacts with independent rows (each on the ground
    or between two DOFs, at random), mu_k / mu_s in [1.1, 1.4] (chi_above) or [0.6, 0.9], driven
    near its first resonance."""
    rng = np.random.default_rng(seed)
    m = rng.uniform(0.5, 2.0, n)
    c = 0.1 * np.sqrt(m[:-1] * m[1:]) * rng.uniform(-1.0, 1.0, n - 1)
    M = np.diag(m) + np.diag(c, 1) + np.diag(c, -1)
    k = rng.uniform(50.0, 150.0, n)
    K = np.diag(k + np.append(k[1:], 0.0)) - np.diag(k[1:], 1) - np.diag(k[1:], -1)
    while True:
        kws, rows = [], []
        for _ in range(nc):
            if rng.random() < 0.5:
                i = int(rng.integers(n))
                kws.append({"dof": i})
                rows.append(np.eye(n)[i])
            else:
                i, j = (int(v) for v in rng.choice(n, 2, replace=False))
                kws.append({"between": (i, j)})
                rows.append(np.eye(n)[i] - np.eye(n)[j])
        if np.linalg.matrix_rank(np.array(rows)) == nc:
            break
    contacts = []
    for kw in kws:
        mu_s = rng.uniform(0.2, 0.4)
        chi = rng.uniform(1.1, 1.4) if chi_above else rng.uniform(0.6, 0.9)
        contacts.append(Contact(**kw, N=rng.uniform(0.5, 2.0), mu_s=mu_s, mu_k=chi * mu_s))
    w1 = math.sqrt(float(np.min(np.linalg.eigvals(np.linalg.solve(M, K)).real)))
    F_c = 2.0 * rng.uniform(-1.0, 1.0, n)
    F_c[int(rng.integers(n))] = 2.0
    return System(M=M, K=K, C=0.002 * K, contacts=contacts, F_c=F_c, omega=w1 * rng.uniform(0.6, 1.2))


def fastest_period(s: System) -> float:
    return 2.0 * math.pi / math.sqrt(float(np.max(np.linalg.eigvals(np.linalg.solve(s.M, s.K)).real)))


#: (seed, chi above 1, n, nc): twelve structures of 2 to 6 DOFs and 1 to 4 contacts
CASES = [(0, False, 2, 1), (1, True, 2, 2), (12, False, 3, 2), (3, True, 3, 3), (4, False, 4, 4), (5, True, 4, 3),
         (13, False, 5, 4), (7, True, 5, 2), (8, False, 6, 4), (9, True, 6, 1), (10, False, 6, 3), (11, True, 3, 1)]


@pytest.fixture(scope="module")
def convergence(refcache: RefCache) -> list[dict]:
    """Each structure's reference over two excitation periods (41 points; computed once, kept in the
    pytest cache: conftest.refcache) and the FMU's relative max-norm error of x at
    h = T_min/100 / 2^k: located k = 0..3, consistent k = 0..5."""
    out = []
    for case in CASES:
        s = random_system(*case)
        t_end = 2.0 * 2.0 * math.pi / s.omega
        times = np.linspace(0.0, t_end, 41)
        ref = refcache.call(simulate, s, t_end, t_eval=times)
        scale = float(np.max(np.abs(ref.x)))
        h0 = fastest_period(s) / 100.0
        errs = {}
        for scheme, levels in (("located", 4), ("consistent", 6)):
            hs = h0 / 2.0 ** np.arange(levels)
            errs[scheme] = (hs, np.array([np.max(np.abs(trajectory(s.replace(h=h, scheme=scheme), times).x - ref.x))
                                          for h in hs]) / scale)
        kinds = {("stop" if sw.after == 0 else "breakaway" if sw.before == 0 else "reversal") for sw in ref.switches}
        out.append({"case": case, "system": s, "errs": errs, "kinds": kinds})
    return out


def test_the_cases_cover_what_they_should(convergence: list[dict]) -> None:
    sizes = {c["system"].n for c in convergence}
    ncs = {c["system"].nc for c in convergence}
    assert min(sizes) == 2 and max(sizes) == 6 and ncs == {1, 2, 3, 4}
    between = [any(ct.between is not None for ct in c["system"].contacts) for c in convergence]
    ground = [any(ct.dof is not None for ct in c["system"].contacts) for c in convergence]
    assert any(between) and any(ground)
    chis = np.concatenate([c["system"].mu_k / c["system"].mu_s for c in convergence])
    assert chis.min() < 1.0 < chis.max()
    for c in convergence:  # every structure sticks, breaks away and stops
        assert {"stop", "breakaway"} <= c["kinds"], c["case"]


def test_located_is_second_order_against_the_reference(convergence: list[dict]) -> None:
    """Measured: ratios 3.89 to 4.02 per halving from h = T_min/100 (the error there 3e-5 to 6e-4
    of the amplitude)."""
    for c in convergence:
        e = c["errs"]["located"][1]
        ratios = e[:-1] / e[1:]
        assert np.all((ratios >= 3.6) & (ratios <= 4.4)), (c["case"], ratios)
        assert e[0] < 1e-3, (c["case"], e[0])


def test_consistent_is_first_order_against_the_reference(convergence: list[dict]) -> None:
    """The consistent scheme finds a stop at the end of the step it falls in, so its error at a
    switch is O(h) with a constant that depends on where the switch falls in its step: the ratios
    per halving scatter (measured 0.1 to 14). The order: the least-squares slope of log(error)
    against log(h) over six halvings (T_min/100 to T_min/3200), whose median over the twelve
    structures is 1. Measured slopes: 0.05, 0.07, 0.75, 0.86, 0.88, 1.02, 1.10, 1.21, 1.22, 1.38,
    1.90, 2.00 (median 1.06): two structures (seeds 10 and 13) do not converge in that range (the
    scheme takes another mode set at some event for most of these h), two with few stick phases
    show order 2."""
    slopes = []
    for c in convergence:
        hs, e = c["errs"]["consistent"]
        slopes.append(np.polyfit(np.log(hs), np.log(e), 1)[0])
    median = float(np.median(slopes))
    assert 0.8 <= median <= 1.4, slopes
    located_finest = np.array([c["errs"]["located"][1][-1] for c in convergence])
    consistent_same_h = np.array([c["errs"]["consistent"][1][3] for c in convergence])
    assert np.median(consistent_same_h / located_finest) > 10.0  # located is far better at equal h


# --------------------------------------------------------------------------- N = 0: the modal closed form

ALPHA = -0.1


def modal(s: System) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The mass-normalised modes Phi (Phi' M Phi = I), their omega_k^2 and modal damping c_k (C
    Rayleigh: Phi' C Phi diagonal)."""
    L = np.linalg.cholesky(s.M)
    Li = np.linalg.inv(L)
    w2, V = np.linalg.eigh(Li @ s.K @ Li.T)
    Phi = Li.T @ V
    Cm = Phi.T @ s.C @ Phi
    assert np.max(np.abs(Cm - np.diag(np.diag(Cm)))) < 1e-12 * np.max(np.abs(Cm))
    return Phi, w2, np.diag(Cm).copy()


def closed_form(s: System, t: np.ndarray) -> np.ndarray:
    """x(t) of the continuous linear structure (no friction): each mode's free and forced parts."""
    Phi, w2, c = modal(s)
    W = s.omega
    q0, v0 = Phi.T @ s.M @ s.x0, Phi.T @ s.M @ s.v0
    fc, fs = Phi.T @ s.F_c, Phi.T @ s.F_s
    Q = (fc - 1j * fs) / (w2 - W ** 2 + 1j * c * W)          # q_p = Re(Q e^{iWt})
    qp0, vp0 = Q.real, (1j * W * Q).real
    wk = np.sqrt(w2)
    zeta = c / (2.0 * wk)
    wd = wk * np.sqrt(1.0 - zeta ** 2)
    A = q0 - qp0
    B = (v0 - vp0 + zeta * wk * A) / wd
    tt = t[:, None]
    q = np.exp(-zeta * wk * tt) * (A * np.cos(wd * tt) + B * np.sin(wd * tt)) + (Q * np.exp(1j * W * tt)).real
    return q @ Phi.T


def scheme_closed_form(s: System, h: float, steps: int, every: int) -> np.ndarray:
    """x at every ``every``-th step of Bossak-Newmark (alpha = ALPHA) applied to each mode: per mode
    (1 - a) A1 + a A0 + c V1 + w2 X1 = f(t1) with Newmark's kinematics; the first step's A0 is the
    physical acceleration re-based on the step, A0 + a h q''' (the engine's rule, method.md 2)."""
    Phi, w2, c = modal(s)
    a, g = ALPHA, 0.5 - ALPHA
    b = 0.25 * (1.0 - a) ** 2
    W = s.omega
    fc, fs = Phi.T @ s.F_c, Phi.T @ s.F_s
    X, V = Phi.T @ s.M @ s.x0, Phi.T @ s.M @ s.v0
    Acc = fc - c * V - w2 * X                                    # f(0) = fc
    jerk = W * fs - c * Acc - w2 * V                             # f'(0) = W fs
    A = Acc + a * h * jerk
    den = (1.0 - a) + c * h * g + w2 * h * h * b
    out = [X @ Phi.T]
    for k in range(1, steps + 1):
        t1 = k * h
        f1 = fc * math.cos(W * t1) + fs * math.sin(W * t1)
        A1 = (f1 - a * A - c * (V + h * (1.0 - g) * A) - w2 * (X + h * V + h * h * (0.5 - b) * A)) / den
        X = X + h * V + h * h * ((0.5 - b) * A + b * A1)
        V = V + h * ((1.0 - g) * A + g * A1)
        A = A1
        if k % every == 0:
            out.append(X @ Phi.T)
    return np.array(out)


def frictionless(seed: int) -> System:
    """A random structure with contacts of N = 0 (on the ground and between DOFs): linear."""
    s = random_system(seed, False, 5, 3)
    contacts = [Contact(dof=ct.dof, between=ct.between, N=0.0, mu_s=ct.mu_s, mu_k=ct.mu_k) for ct in s.contacts]
    x0 = np.random.default_rng(seed + 100).uniform(-0.01, 0.01, s.n)
    return System(M=s.M, K=s.K, C=s.C, contacts=contacts, F_c=s.F_c, F_s=0.3 * s.F_c[::-1], omega=s.omega * 1.37,
                  x0=x0, v0=-x0, alpha=ALPHA)


@pytest.mark.parametrize("seed", [0, 3])
def test_no_friction_is_the_modal_closed_form_over_100_periods(seed: int) -> None:
    s = frictionless(seed)
    Phi, w2, c = modal(s)
    T_slow = 2.0 * math.pi / math.sqrt(float(np.min(w2)))
    T_fast = 2.0 * math.pi / math.sqrt(float(np.max(w2)))
    every = 10
    h = T_fast / 40.0
    steps = every * int(math.ceil(100.0 * T_slow / (every * h)))
    times = np.arange(steps // every + 1) * (every * h)
    got = trajectory(s.replace(h=h), times)
    scheme = scheme_closed_form(s, h, steps, every)
    amplitude = float(np.max(np.abs(scheme)))
    assert times[-1] >= 100.0 * T_slow
    assert np.all(got.f == 0.0) and np.all(got.E_friction == 0.0)
    # the FMU is the scheme's closed form (measured: 3.6e-13 and 5.1e-13 of the amplitude, 38110 and
    # 31320 steps)
    assert np.max(np.abs(got.x - scheme)) <= 1e-10 * amplitude
    # and the scheme's closed form differs from the continuous one by the scheme's truncation error:
    # second order (measured ratios 4.00 and 3.98 per halving), 2.4e-3 and 4.3e-3 of the amplitude
    # over 100 slow periods at h = T_fast/40
    exact = closed_form(s, times)
    e1 = np.max(np.abs(scheme - exact))
    scheme2 = scheme_closed_form(s, h / 2.0, 2 * steps, 2 * every)
    e2 = np.max(np.abs(scheme2 - exact))
    assert 3.6 <= e1 / e2 <= 4.4, e1 / e2


def test_located_against_the_reference_where_a_later_breakaway_takes_a_stopping_contact_s_load() -> None:
    """Contact 0 stops while contact 1 is stuck, both beyond their limits when held (t = 0.828): the
    cascade releases contact 0, then breaks contact 1 away, after which contact 0's slip would
    accelerate against its slide; the consistent set holds it (0.037 within 0.325) as the engine does."""
    s = random_system(2, False, 3, 2)
    t_end = 2.0 * 2.0 * math.pi / s.omega
    times = np.linspace(0.0, t_end, 41)
    ref = simulate(s, t_end, t_eval=times)
    h0 = fastest_period(s) / 100.0
    e = np.array([np.max(np.abs(trajectory(s.replace(h=h0 / 2.0 ** k), times).x - ref.x)) for k in range(3)])
    ratios = e[:-1] / e[1:]
    assert np.all((ratios >= 3.6) & (ratios <= 4.4)), ratios


@pytest.mark.parametrize("case", [(12, False, 3, 2), (5, True, 4, 3)])
def test_located_with_non_proportional_damping_against_the_reference(case: tuple) -> None:
    """C not diagonal in the modal basis (the structures' 0.002 K plus a dashpot 0.5 on DOF 0): the
    model's dense backend (the Rayleigh-damped structures above take the modal one), second order
    against the reference (ratios 3.6 to 4.4 per halving of h)."""
    s0 = random_system(*case)
    C = np.array(s0.C, dtype=float)
    C[0, 0] += 0.5
    s = s0.replace(C=C)
    t_end = 2.0 * 2.0 * math.pi / s.omega
    times = np.linspace(0.0, t_end, 41)
    ref = simulate(s, t_end, t_eval=times)
    h0 = fastest_period(s) / 100.0
    e = np.array([np.max(np.abs(trajectory(s.replace(h=h0 / 2.0 ** k), times).x - ref.x)) for k in range(4)])
    ratios = e[:-1] / e[1:]
    assert np.all((ratios >= 3.6) & (ratios <= 4.4)), ratios



def test_located_runs_through_simultaneous_switches_of_coupled_contacts() -> None:
    """bench/bench_system.c's chain (M = I, K tridiagonal, C = 0.02 M + 0.002 K, F_c,i = cos(0.1 i),
    F_s,i = sin(0.1 i), omega = 0.5) with n = nc = 16: contact j on block j, odd j also against block
    j + 1 (15 against 14), N = 1.6, mu_s = 0.5, mu_k = 0.35, from rest over 576 steps of h = T/200.
    At t = 32.119 held contact 14 breaks away at once (its force beyond its limit in every trial down
    to 2^-60 of the step) while contact 3 (between blocks 3 and 4), a candidate of the same phase,
    slides on at -0.034: the located step used to switch it there too (held, its slip left at -0.034,
    then released against its slip) and then take phases of length 0 until its limit ("too many
    stick/slip switches inside one internal step", at h and h/2). It runs to the end at h, h/2, h/4
    and converges to the event-driven reference at order 2 (measured: relative errors 1.23e-3,
    2.44e-4, 6.28e-5 of the largest deflection at 72 sample times on the grid; ratios 5.0 and 3.9)."""
    n = 16
    K = 2.0 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    contacts = [Contact(between=(j, j + 1 if j + 1 < n else j - 1), N=1.6, mu_s=0.5, mu_k=0.35) if j % 2
                else Contact(dof=j, N=1.6, mu_s=0.5, mu_k=0.35) for j in range(n)]
    s = System(M=np.eye(n), K=K, C=0.02 * np.eye(n) + 0.002 * K, contacts=contacts,
               F_c=np.cos(0.1 * np.arange(n)), F_s=np.sin(0.1 * np.arange(n)), omega=0.5)
    h0 = 2.0 * math.pi / 0.5 / 200.0
    times = h0 * np.arange(0, 577, 8)  # (on the grid: the steps of one run to the end)
    ref = simulate(s, float(times[-1]), t_eval=times)
    scale = float(np.max(np.abs(ref.x)))
    errs = np.array([np.max(np.abs(trajectory(s.replace(h=h0 / 2.0 ** k), times).x - ref.x)) / scale
                     for k in range(3)])
    ratios = errs[:-1] / errs[1:]
    assert errs[0] < 2.5e-3, errs
    assert np.all((ratios >= 3.5) & (ratios <= 5.5)), (errs, ratios)
