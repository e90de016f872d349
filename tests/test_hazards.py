"""Numerical hazards (method.md section 8, and more): the FMU must stay finite, keep its invariants
at every step and match the exact stick-slip solution.

Every run here goes through the FMU (fmpy), with the communication step equal to the internal step
h (or a fixed small multiple of it, stated per test) so that the invariants are checked at every
internal step:

- stuck (mode 0): v == 0 exactly, |F| <= max(mu_s, mu_k) N and F = -(P(t) - k x) (static balance);
- sliding (mode s): F == -s mu_k N and s v >= 0;
- complementarity of method.md section 3 (u1 r1 = u2 r2 = 0, r >= 0) to 1e-12 relative;
- energy balance W_excitation = dE + E_friction + D_viscous, with E_friction from the FMU
  (observe = true) and W, D by the trapezoid rule on the outputs: the residual is O(h^2) (checked:
  it falls about 4x per halving of h) and below ENERGY_RTOL of the energy turnover.

Sizes are chosen to prove each point within the CI budget (the whole file runs in well under a
minute in a Release build); the long-run and fine-step cases say which size they use.
"""

from __future__ import annotations

import math
import shutil
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Slave
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from dryfriction import DryFrictionWarning
from dryfriction.drivers.chain import default_chain_fmu, default_chain_fmu3
from dryfriction.references.exact import ExactSolution, linear_solution, solve_exact
from dryfriction.drivers.oscillator3 import default_fmi3_path
from dryfriction.drivers.oscillator import OscillatorFMU2, Settings, default_fmu_path
from dryfriction.params import SCALE_LIMIT, Oscillator

from fmi2_helpers import Counting

ND = Oscillator.from_nondimensional
COMPLEMENTARITY_RTOL = 1e-12
ENERGY_RTOL = 2e-5  # at h = T/2000; the residual is O(h^2), at most 2.3e-6 measured at T/2000


@pytest.fixture(scope="module")
def fmu() -> Iterator[OscillatorFMU2]:
    f = OscillatorFMU2()
    yield f
    f.close()


# --------------------------------------------------------------------------- helpers


@dataclass
class Run:
    p: Oscillator
    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    a: np.ndarray
    F: np.ndarray
    mode: np.ndarray
    E_friction: float


def run(fmu: OscillatorFMU2, p: Oscillator, t_end: float, h: float, comm: float | None = None,
        scheme: str = "located", **extra: object) -> Run:
    """Dense run from 0 to t_end with communication step comm (default h), observe on over the
    whole run (E_friction is the friction dissipation on [0, t_end])."""
    comm = h if comm is None else comm
    n = int(round(t_end / comm))
    t = np.arange(n + 1) * comm
    s = Settings(h=h, scheme=scheme, observe=True, t_obs_start=0.0, t_obs_stop=t[-1],
                 extra=dict(extra))
    out = fmu.trajectory(p, t, s, ("x", "v", "a", "F_friction", "mode", "E_friction"))
    r = Run(p, t, out["x"], out["v"], out["a"], out["F_friction"], out["mode"].astype(int),
            float(out["E_friction"][-1]))
    assert_finite(r)
    return r


def assert_finite(r: Run) -> None:
    for name in ("x", "v", "a", "F"):
        arr = getattr(r, name)
        assert np.all(np.isfinite(arr)), f"{name} is not finite at t = {r.t[~np.isfinite(arr)][:3]}"
    assert math.isfinite(r.E_friction)
    assert set(np.unique(r.mode)) <= {-1, 0, 1}


def excitation(p: Oscillator, t: np.ndarray) -> np.ndarray:
    return p.P0 * np.cos(p.omega * t + p.phi)


def check_invariants(r: Run, scheme: str = "located", one_step_reversal_stick: bool = False) -> None:
    """Friction law and complementarity at every output point (see the module docstring).

    one_step_reversal_stick: the consistent scheme's fallback of method.md section 4 ("if the
    solved velocity comes out with the wrong sign, stick for this step") holds the block for one
    step although the static force exceeds the limit; the friction is then the limit (not the
    static force) and the block slides off at the next step (unless the force is back inside the
    limit by then). Such points are checked by
    check_forced_sticks instead of the static balance."""
    p = r.p
    Fb, Fk = p.breakaway, p.mu_k * p.N
    force_scale = max(abs(p.P0), Fb, p.k * np.abs(r.x).max(), 1e-300)
    if Fb == 0.0:  # no friction: F = 0 and mode is just the sign of v
        assert np.all(r.F == 0.0) and np.all(r.mode == np.sign(r.v))
        return
    stuck = r.mode == 0
    slide = ~stuck
    # stuck: at rest exactly, inside the breakaway limit
    assert np.all(r.v[stuck] == 0.0), f"stuck with v != 0 at t = {r.t[stuck & (r.v != 0)][:3]}"
    over = np.abs(r.F) - Fb
    bad = stuck & (over > COMPLEMENTARITY_RTOL * force_scale)
    assert not bad.any(), f"stuck with |F| above the limit by {over[bad].max():.3e} N at t = {r.t[bad][:3]}"
    if one_step_reversal_stick:
        stuck = stuck & ~check_forced_sticks(r, force_scale)
    if scheme != "paper" and stuck.any():
        # static balance: the friction force is minus the net applied force
        S = excitation(p, r.t[stuck]) - p.k * r.x[stuck]
        err = np.abs(r.F[stuck] + S).max()
        assert err <= COMPLEMENTARITY_RTOL * force_scale, f"static balance off by {err:.3e} N"
    # sliding: kinetic friction against the motion
    if slide.any():
        errF = np.abs(r.F[slide] + r.mode[slide] * Fk).max()
        assert errF <= COMPLEMENTARITY_RTOL * max(Fk, 1e-300) or errF == 0.0, f"F != -s mu_k N by {errF:.3e}"
        assert np.all(r.mode[slide] * r.v[slide] >= 0.0), "velocity against the sliding direction"
    # the LCP of method.md section 3: u1 = max(v,0), u2 = max(-v,0), r1 = muN + F, r2 = muN - F
    muN = np.where(r.mode == 0, Fb, Fk)
    v, F = r.v, r.F
    u1, u2 = np.maximum(v, 0.0), np.maximum(-v, 0.0)
    r1, r2 = muN + F, muN - F
    vscale = max(np.abs(r.v).max(), 1e-300)
    assert r1.min() >= -COMPLEMENTARITY_RTOL * force_scale and r2.min() >= -COMPLEMENTARITY_RTOL * force_scale
    resid = max(np.abs(u1 * r1).max(), np.abs(u2 * r2).max()) / (vscale * force_scale)
    assert resid <= COMPLEMENTARITY_RTOL, f"complementarity residual {resid:.3e}"


def check_forced_sticks(r: Run, force_scale: float) -> np.ndarray:
    """Points where the block is held although the static force S exceeds the limit (the
    consistent scheme's one-step fallback): there F must be the limit against S and the next
    point must slide. Returns the mask of such points."""
    p = r.p
    S = excitation(p, r.t) - p.k * r.x
    forced = (r.mode == 0) & (np.abs(S) > p.breakaway + COMPLEMENTARITY_RTOL * force_scale)
    idx = np.where(forced)[0]
    assert np.all(np.abs(r.F[idx] + np.sign(S[idx]) * p.breakaway) <= COMPLEMENTARITY_RTOL * force_scale), \
        "forced stick: friction is not the limit against the static force"
    idx = idx[idx < r.t.size - 1]
    # the next point slides, unless the static force has come back inside the limit by then (a
    # harmonic force that crosses the limit and returns within one step)
    inside = np.abs(S[idx + 1]) <= p.breakaway + COMPLEMENTARITY_RTOL * force_scale
    held = (r.mode[idx + 1] == 0) & ~inside
    assert not held.any(), f"held beyond one step at t = {r.t[idx][held][:3]}"
    return forced


def trapezoid(y: np.ndarray, x: np.ndarray) -> float:
    """The trapezoid rule (np.trapezoid of NumPy 2, np.trapz before; the package supports both)."""
    return float(np.sum((y[1:] + y[:-1]) * np.diff(x)) / 2.0)


def energy_residual(r: Run) -> tuple[float, float]:
    """(residual, turnover) of W_P = dE + E_friction + D_c, W_P and D_c by the trapezoid rule."""
    p = r.p
    P = excitation(p, r.t)
    W = trapezoid(P * r.v, r.t)
    D = trapezoid(p.c * r.v * r.v, r.t)
    dE = 0.5 * p.m * (r.v[-1] ** 2 - r.v[0] ** 2) + 0.5 * p.k * (r.x[-1] ** 2 - r.x[0] ** 2)
    turnover = trapezoid(np.abs(P * r.v), r.t) + abs(r.E_friction) + D + 1e-300
    return W - dE - r.E_friction - D, turnover


def check_energy(r: Run, rtol: float = ENERGY_RTOL) -> float:
    res, turnover = energy_residual(r)
    rel = abs(res) / turnover
    assert rel <= rtol, f"energy balance residual {rel:.3e} of the turnover (> {rtol:.1e})"
    return rel


def exact_error(r: Run, t_end: float | None = None) -> tuple[float, float]:
    """(max |x - x_exact|, max |x_exact|) over the run."""
    ex = solve_exact(r.p, r.t[-1] if t_end is None else t_end)
    xe = ex.evaluate(r.t)[0]
    return float(np.abs(r.x - xe).max()), float(np.abs(xe).max())


# --------------------------------------------------------------------------- friction coefficients


@pytest.mark.parametrize("chi", [0.01, 3.0])
def test_chi_extremes_match_exact(fmu: OscillatorFMU2, chi: float) -> None:
    """chi near 0 (almost no kinetic friction: long slides after breakaway) and chi = 3 (breakaway
    at mu_k N, zero initial acceleration): located scheme within 3e-4 relative (8.9e-5 and 1.2e-5 measured, second order) of the exact
    solution at h = T/2000 over 10 periods, invariants and energy balance at every step."""
    p = ND(0.5, 0.8 if chi < 1 else 0.2, chi)
    T = p.period
    r = run(fmu, p, 10 * T, T / 2000)
    check_invariants(r)
    check_energy(r)
    err, scale = exact_error(r)
    assert err <= 3e-4 * scale, f"max error {err:.3e} (scale {scale:.3e})"
    assert (r.mode == 0).any() and (r.mode != 0).any(), "the case should contain stick and slip"


# --------------------------------------------------------------------------- never moves / threshold


@pytest.mark.parametrize("scheme", ["paper", "consistent", "located"])
def test_static_friction_far_above_excitation_never_moves(fmu: OscillatorFMU2, scheme: str) -> None:
    """mu_s N = 100 P0: the block stays where it is, exactly, for 100 periods (no creep)."""
    p = Oscillator(N=250.0, mu_s=0.4, x0=0.003)
    T = p.period
    r = run(fmu, p, 100 * T, T / 100, scheme=scheme)
    assert np.all(r.x == p.x0) and np.all(r.v == 0.0) and np.all(r.mode == 0)
    assert r.E_friction == 0.0
    check_invariants(r, scheme)


@pytest.mark.parametrize("scheme", ["paper", "consistent", "located"])
@pytest.mark.parametrize("mu_s,chi", [(0.5, 0.7), (0.25, 2.0)])
def test_exactly_at_breakaway_threshold_stays(fmu: OscillatorFMU2, scheme: str, mu_s: float, chi: float) -> None:
    """max |P(t)| = max(mu_s, mu_k) N exactly (P0 = 1, N = 2, limit 1.0 in binary): the force
    touches the limit every half period but never exceeds it, so the block never moves."""
    p = Oscillator(P0=1.0, N=2.0, mu_s=mu_s, chi=chi)
    assert p.breakaway == 1.0
    T = p.period
    r = run(fmu, p, 20 * T, T / 1000, scheme=scheme)
    assert np.all(r.x == 0.0) and np.all(r.mode == 0), f"moved: max |x| = {np.abs(r.x).max():.3e}"
    check_invariants(r, scheme)


def test_just_above_breakaway_threshold_moves_as_exact(fmu: OscillatorFMU2) -> None:
    """P0 = limit (1 + 1e-3): tiny slips near each force peak, matching the exact solution."""
    p = Oscillator(P0=1.0 + 1e-3, N=2.0, mu_s=0.5, chi=0.7)
    T = p.period
    r = run(fmu, p, 3 * T, T / 4000)
    check_invariants(r)
    err, scale = exact_error(r)
    assert scale > 0 and (r.mode != 0).any()
    assert err <= 5e-5 * scale, f"max error {err:.3e} (scale {scale:.3e})"  # 3.8e-6 measured


# --------------------------------------------------------------------------- no friction


def test_zero_normal_force_is_the_linear_oscillator(fmu: OscillatorFMU2) -> None:
    """N = 0: no LCP (effects bit 1 clear), F = 0, matches the closed-form linear solution to
    second order; the general path (fastPaths = false) gives the same numbers."""
    p = Oscillator(N=0.0, c=0.5, x0=0.01, v0=-0.1)
    T = p.period
    errs = []
    for h in (T / 500, T / 1000):
        r = run(fmu, p, 5 * T, h)
        assert np.all(r.F == 0.0) and r.E_friction == 0.0
        check_energy(r, 1e-3)
        xe = linear_solution(p, r.t)[0]
        errs.append(np.abs(r.x - xe).max() / np.abs(xe).max())
    assert errs[1] < 3e-4
    assert 3.0 < errs[0] / errs[1] < 5.0, f"order off: errors {errs}"
    assert not int(fmu.get(["effects"])["effects"]) & 1
    g = run(fmu, p, 5 * T, T / 1000, fastPaths=False)
    np.testing.assert_allclose(g.x, r.x, rtol=0, atol=1e-12 * np.abs(r.x).max())


# --------------------------------------------------------------------------- damping


@pytest.mark.parametrize("zeta", [1.0, 3.0])
def test_heavy_viscous_damping(fmu: OscillatorFMU2, zeta: float) -> None:
    """Critical and over-critical damping from a displaced start: creeps towards the force balance,
    sticks; matches the exact solution, energy balance includes the viscous dissipation."""
    p = ND(0.5, 0.2, 0.7, zeta=zeta, z0=3.0)
    T = p.period
    r = run(fmu, p, 3 * T, T / 2000)
    check_invariants(r)
    check_energy(r)
    err, scale = exact_error(r)
    assert err <= 1e-5 * scale, f"max error {err:.3e} (scale {scale:.3e})"


# --------------------------------------------------------------------------- resonance, frequency


def test_exact_resonance_1000_periods(fmu: OscillatorFMU2) -> None:
    """lambda = 1, c = 0, 4 mu_k N < pi P0: the amplitude grows without bound (about
    (1 - 4 mu_k N / (pi P0)) P0 / (2k) per radian); over 1000 periods the FMU stays finite and on
    the exact solution (h = T/2000, outputs every T/20): the error is the accumulated phase error,
    3.1e-3 of the amplitude after 1000 periods (second order in h)."""
    p = ND(1.0, 0.2, 0.7)
    T = p.period
    r = run(fmu, p, 1000 * T, T / 2000, comm=T / 20)
    err, scale = exact_error(r)
    assert err <= 5e-3 * scale, f"max error {err:.3e} of the amplitude {scale:.3e}"
    growth = (1 - 4 * p.mu_k * p.N / (math.pi * p.P0)) * p.P0 / (2 * p.k) * p.w0 * r.t[-1]
    assert abs(np.abs(r.x[-40:]).max() / growth - 1) < 0.01
    check_invariants(r)


@pytest.mark.parametrize("lam", [0.01, 20.0])
def test_frequency_extremes(fmu: OscillatorFMU2, lam: float) -> None:
    """lambda = 0.01 (quasi-static: long sticks, fast free oscillations inside each forcing
    period) and lambda = 20 (the block barely follows): h = (natural period)/1000 and
    T/1000 resp.; outputs every 10 internal steps for lambda = 0.01 (2 10^5 steps)."""
    p = ND(lam, 0.4, 0.7, z0=0.5)
    T = p.period
    Tn = 2 * math.pi / p.w0
    if lam < 1:
        r = run(fmu, p, 2 * T, Tn / 1000, comm=Tn / 100)
    else:
        r = run(fmu, p, 10 * T, T / 1000)
    check_invariants(r)
    err, scale = exact_error(r)
    assert err <= 1e-4 * scale, f"max error {err:.3e} (scale {scale:.3e})"


# --------------------------------------------------------------------------- step sizes


@pytest.mark.parametrize("scheme", ["paper", "consistent", "located"])
def test_coarse_step_T_over_8(fmu: OscillatorFMU2, scheme: str) -> None:
    """h = T/8 over 200 periods: finite, invariants at every step, amplitude bounded; the located
    scheme still lands within 15 % of the exact steady amplitude (its switches are exact)."""
    p = ND(0.5, 0.4, 0.7, zeta=0.02)
    T = p.period
    with pytest.warns(DryFrictionWarning, match="takes only 4 internal steps per"):  # T/8 of T/2, the natural period
        r = run(fmu, p, 200 * T, T / 8, scheme=scheme)
    check_invariants(r, scheme, one_step_reversal_stick=scheme == "consistent")
    ex = solve_exact(p, 200 * T)
    xe = ex.evaluate(np.linspace(190 * T, 200 * T, 4001))[0]
    amp_e = 0.5 * (xe.max() - xe.min())
    last = r.t >= 190 * T
    amp = 0.5 * (r.x[last].max() - r.x[last].min())
    assert amp < 3 * amp_e
    if scheme == "located":
        assert abs(amp / amp_e - 1) < 0.15, f"amplitude {amp:.4e} vs exact {amp_e:.4e}"


def test_fine_step_T_over_1e6(fmu: OscillatorFMU2) -> None:
    """h = T/10^6 over one period (10^6 internal steps, outputs every 1000): m_hat ~ 1/h is huge,
    sticking is still decided exactly (v == 0, no +-1e-17 velocities) and the error against the
    exact solution is at the rounding level (<= 1e-9 relative)."""
    p = ND(0.5, 0.4, 0.7)
    T = p.period
    r = run(fmu, p, T, T / 1e6, comm=T / 1000)
    check_invariants(r)
    err, scale = exact_error(r)
    assert err <= 1e-9 * scale, f"max error {err:.3e} (scale {scale:.3e})"
    assert (r.mode == 0).sum() > 10


@pytest.mark.parametrize("ratio", [1 / 7, 997.0])
def test_communication_step_off_the_grid(fmu: OscillatorFMU2, ratio: float) -> None:
    """Communication step h/7 (shorter than the internal step) and 997 h (much longer, off the
    grid): the located scheme keeps its accuracy (within 2x of comm = h, h = T/1000)."""
    p = ND(0.5, 0.4, 0.7)
    T = p.period
    h = T / 1000
    t_end = 4 * T if ratio < 1 else 20 * ratio * h
    ref = run(fmu, p, t_end, h)
    err_ref, scale = exact_error(ref)
    r = run(fmu, p, t_end, h, comm=ratio * h)
    check_invariants(r)
    err, _ = exact_error(r)
    assert err <= 2 * err_ref + 1e-12 * scale, f"error {err:.3e} vs {err_ref:.3e} with comm = h"


@pytest.mark.parametrize("scheme", ["paper", "consistent", "located"])
@pytest.mark.parametrize("k", [1e9, 1e12])
def test_stiff_spring_stays_finite(fmu: OscillatorFMU2, scheme: str, k: float) -> None:
    """A stiff spring against the step (k = 1e9 and 1e12 with m = 1, h = 1 ms: w0 h = 32 and
    1000; Bossak is unconditionally stable): the block hardly moves, |x| <= 2 (P0 + limit) / k,
    outputs finite, invariants hold (5 s, one doStep per 10 internal steps)."""
    p = Oscillator(k=k)
    with pytest.warns(DryFrictionWarning, match="internal steps per"):  # h does not resolve the natural period
        r = run(fmu, p, 5.0, 1e-3, comm=1e-2, scheme=scheme)
    assert np.abs(r.x).max() <= 2 * (abs(p.P0) + p.breakaway) / k
    check_invariants(r, scheme, one_step_reversal_stick=scheme == "consistent")


# --------------------------------------------------------------------------- long runs


def test_1e5_periods(fmu: OscillatorFMU2) -> None:
    """10^5 periods: one doStep of 10^5 - 5 periods at h = T/100 (10^7 internal steps), then 5
    periods at every step. Nothing overflows, the periodic stick-slip orbit is the exact one (a
    drift of the time grid would shift its phase) and the energy balance holds over the last 5
    periods. (Bit-exact time: test_time_lands_exactly_on_the_communication_point_in_long_runs.)"""
    p = ND(0.5, 0.4, 0.7, zeta=0.05)
    T = p.period
    h = T / 100
    n = 10**5
    t1 = (n - 5) * T
    st_ = Settings(h=h, observe=True, t_obs_start=t1, t_obs_stop=n * T)
    fmu.start(p, st_)
    fmu.step_to(t1)
    t = t1 + np.arange(501) * h
    xs, vs = [fmu.get(["x"])["x"]], [fmu.get(["v"])["v"]]
    for j in range(1, t.size):
        fmu.do_step(t[j - 1], t[j] - t[j - 1])
        out = fmu.get(["x", "v"])
        xs.append(out["x"])
        vs.append(out["v"])
    x, v = np.array(xs), np.array(vs)
    assert np.all(np.isfinite(x)) and np.all(np.isfinite(v))
    E_f = fmu.get(["E_friction"])["E_friction"]
    r = Run(p, t, x, v, np.zeros_like(x), np.zeros_like(x), np.zeros(x.size, int), E_f)
    res, turnover = energy_residual(r)
    assert abs(res) <= 2e-3 * turnover, f"energy residual {abs(res) / turnover:.3e}"  # 5.7e-4 measured
    # the attracting periodic orbit, from the exact solution after 60 periods
    ex = solve_exact(p, 65 * T)
    xe = ex.evaluate(60 * T + (t - t1))[0]
    amp = np.abs(xe).max()
    assert np.abs(x - xe).max() <= 3e-3 * amp, f"phase/amplitude off by {np.abs(x - xe).max() / amp:.3e}"


@pytest.mark.parametrize("h_div", [100, 64])
def test_time_lands_exactly_on_the_communication_point_in_long_runs(fmu: OscillatorFMU2, h_div: int) -> None:
    """After fmi2DoStep(0, t1) the FMU's time (fmi2LastSuccessfulTime) is t1 bit for bit, also
    when t1 = 99995 T is 10^7 internal steps away (there the grid snap tolerance 1e-9 h is below
    one ulp of t)."""
    p = ND(0.5, 0.4, 0.7, zeta=0.05)
    T = p.period
    for n in (10, 99995):
        t1 = n * T
        fmu.start(p, Settings(h=T / h_div))
        fmu.do_step(0.0, t1)
        got = fmu.last_successful_time()
        assert got == t1, f"FMU time {got!r} != requested {t1!r} ({(got - t1) / np.spacing(t1):+.0f} ulp)"


def test_long_stick_no_creep_and_exact_time(fmu: OscillatorFMU2) -> None:
    """10^5 communication steps of T/3 while stuck: position frozen bit for bit, time equal to
    the host's k T/3 at every step (the FMU accepts currentCommunicationPoint = k dt)."""
    p = Oscillator(N=10.0, x0=-0.002)
    T = p.period
    fmu.start(p, Settings(h=T / 50))
    dt = T / 3
    for k in range(10**5):
        fmu.do_step(k * dt, dt)
    assert fmu.last_successful_time() == (10**5 - 1) * dt + dt
    assert fmu.get(["x"])["x"] == p.x0 and fmu.get(["v"])["v"] == 0.0


# --------------------------------------------------------------------------- chaos


CHAOTIC = ND(0.25, 0.4, 0.05, zeta=0.05)


def test_chaotic_set_statistics_converge(fmu: OscillatorFMU2) -> None:
    """A chaotic set (lambda 0.25, mu_s sigma 0.4, chi 0.05, zeta 0.05): a 1e-9 perturbation of
    x0 grows to the size of the motion (trajectories are not comparable past the Lyapunov time),
    but the statistics over periods 50..350 (stick fraction, mean amplitude, asymmetry) agree
    between h = T/1000, T/2000, T/4000."""
    p = CHAOTIC
    T = p.period
    ts = np.arange(0, 351) * T
    a = fmu.trajectory(p, ts, Settings(h=T / 2000), ("x",))["x"]
    b = fmu.trajectory(p.with_(x0=1e-9 * p.P0 / p.k), ts, Settings(h=T / 2000), ("x",))["x"]
    scale = np.abs(a).max()
    d = np.abs(a - b) / scale
    assert d[:5].max() < 1e-6 and d[200:].max() > 1e-2, f"not sensitive: {d[:5].max():.1e} {d[200:].max():.1e}"
    stats = []
    for n in (1000, 2000, 4000):
        o = fmu.observables(p, 350 * T, 50 * T, settings=Settings(h=T / n))
        amp = 0.5 * (o["x_max"] - o["x_min"])
        asym = 0.5 * (o["x_max"] + o["x_min"])
        stats.append((o["stick_fraction"], amp, asym))
        assert all(math.isfinite(s) for s in stats[-1])
    s = np.array(stats)
    assert np.ptp(s[:, 0]) < 0.05, f"stick fractions {s[:, 0]}"
    assert np.ptp(s[:, 1]) < 0.05 * s[:, 1].mean(), f"amplitudes {s[:, 1]}"
    assert np.ptp(s[:, 2]) < 0.05 * s[:, 1].mean(), f"asymmetries {s[:, 2]}"


# --------------------------------------------------------------------------- start on the limit


# At rest at x0 = P0 / k: the static force P0 (cos w t - 1) is 0 at t = 0 and leaves it like t^2; a
# breakaway limit of 5e-24 N is below the rounding of P0 (1.1e-16 N), so the limit over P0 rounds to
# the force's extreme (the closed-form breakaway's acos argument is -1 exactly).
BELOW_ROUNDING = Oscillator(P0=1.0, N=1e-23, mu_s=0.5, chi=1.0, k=64.0, omega=8.0, x0=1.0 / 64.0)


@pytest.mark.parametrize("scheme", ["located", "consistent", "exact"])
def test_breakaway_limit_below_rounding(fmu: OscillatorFMU2, scheme: str) -> None:
    """A breakaway limit below the rounding of the static force: the block breaks away backward at
    once (the exact solution: at 5e-13 T), as with no static friction, and follows the exact motion;
    never held stuck while the static force is far over the limit (it was, for half a period in the
    located scheme and for good in the exact one: 2.5 and 6.5 P0/k off)."""
    p = BELOW_ROUNDING
    assert p.k * p.x0 == p.P0 and 0.0 < p.breakaway < 1e-16 * p.P0
    T = p.period
    r = run(fmu, p, 2 * T, T / 4000, scheme=scheme)
    check_invariants(r, scheme, one_step_reversal_stick=scheme == "consistent")
    assert r.mode[0] == 0 and r.mode[1] == -1 and r.v[1] < 0.0
    err, _ = exact_error(r)
    # measured: 1.07e-5 P0/k (located and consistent, the exact motion's start is z' = -tau^3/6) and 1.8e-13
    assert err <= (1e-12 if scheme == "exact" else 2e-5) * p.P0 / p.k, err


def test_start_at_rest_on_the_limit_force_falling(fmu: OscillatorFMU2) -> None:
    """x0 with P(0) - k x0 = limit exactly (binary-exact values), force falling: stays stuck
    (the limit is inclusive) until it breaks backward at t = T/4 exactly as the exact solution."""
    p = Oscillator(P0=1.0, N=1.0, mu_s=0.5, chi=0.5, k=64.0, omega=4.0, x0=0.5 / 64.0)
    assert p.P0 - p.k * p.x0 == p.breakaway
    T = p.period
    r = run(fmu, p, 2 * T, T / 2000)
    check_invariants(r)
    i = np.argmax(r.mode != 0)
    assert r.mode[i] == -1 and abs(r.t[i] - T / 4) <= T / 2000 + 1e-12
    err, scale = exact_error(r)
    assert err <= 1e-5 * scale


@pytest.mark.parametrize("chi", [0.5, 2.0])
def test_start_at_rest_on_the_limit_force_rising(fmu: OscillatorFMU2, chi: float) -> None:
    """On the limit with the force rising (phi < 0): breaks away forward at once; for chi >= 1
    with zero initial acceleration (v grows like t^2). Matches the exact solution."""
    phi = -0.3
    p0 = Oscillator(P0=1.0, N=1.0, mu_s=0.5, chi=chi, k=64.0, omega=4.0, phi=phi)
    p = p0.with_(x0=(math.cos(phi) - p0.breakaway) / p0.k)
    T = p.period
    r = run(fmu, p, 2 * T, T / 2000)
    check_invariants(r)
    assert r.mode[1] == 1 and r.v[1] > 0
    err, scale = exact_error(r)
    assert err <= 1e-4 * scale  # 7.6e-6 (chi 0.5) and 4.4e-5 (chi 2) measured, second order


def test_consistent_reversal_keeps_friction_within_limit(fmu: OscillatorFMU2) -> None:
    """The consistent scheme, at a stop followed by a reversal whose solved velocity has the wrong
    sign, "sticks for this step" (method.md section 4) although the static force exceeds the
    limit (by 0.93 N at h = T/4000 here; this does not shrink with h). The friction output stays
    at the limit (never above it) and the block slides off at the next step."""
    p = ND(1.0, 0.5, 1.0)
    T = p.period
    r = run(fmu, p, 2 * T, T / 4000, scheme="consistent")
    check_invariants(r, "consistent", one_step_reversal_stick=True)
    S = excitation(p, r.t) - p.k * r.x
    assert np.sum((r.mode == 0) & (np.abs(S) > p.breakaway + 1e-9)) >= 1, "the case should hold a forced stick"


# --------------------------------------------------------------------------- energy


@pytest.mark.min_versions
@pytest.mark.parametrize("alpha", [0.0, -0.1, -1 / 3])
def test_energy_balance_second_order(fmu: OscillatorFMU2, alpha: float) -> None:
    """Energy balance with friction and viscous damping: the residual falls about 4x per halving
    of h (trapezoid quadrature and Bossak both O(h^2)) and is below ENERGY_RTOL at h = T/2000."""
    p = ND(0.8, 0.3, 0.6, zeta=0.05, z0=1.0)
    T = p.period
    rel = []
    for n in (500, 1000, 2000):
        r = run(fmu, p, 5 * T, T / n, alpha=alpha)
        res, turnover = energy_residual(r)
        rel.append(abs(res) / turnover)
    assert rel[-1] <= ENERGY_RTOL, rel
    assert rel[0] / rel[2] > 8.0, f"not second order: {rel}"


# --------------------------------------------------------------------------- properties


def near_tie_time(ex: ExactSolution, delta: float) -> float:
    """The earliest time (s) at which the exact motion takes a branch decision within delta of a
    tie, ex.t_end if none; delta is non-dimensional (forces in P0, velocities in P0 / sqrt(k m)).

    The decisions are those where the motion is not continuous in the data: a stop (stick or
    reverse: the static force there against the breakaway limit), a stick phase (the static force's
    peak, whether inside the phase or just after its breakaway, against the limit: a grazing of the
    limit) and a slide (an interior minimum of s v against zero: a stop that is only touched). A
    scheme whose decision errs by more than the margin takes the other branch; the motion before
    the returned time is continuous in the data."""
    p = ex.params
    Fb = p.breakaway
    if Fb == 0.0:  # no friction: no decision
        return ex.t_end
    vscale = p.P0 / math.sqrt(p.k * p.m)
    cut = ex.t_end

    def near(value: float) -> bool:
        return abs(value) < delta * p.P0

    for i, seg in enumerate(ex.segments):
        if seg.t0 >= cut:
            break
        ends_inside = i < len(ex.segments) - 1
        if seg.mode != 0:
            ts = np.linspace(seg.t0, seg.t1, 401)
            sv = seg.mode * ex.evaluate(ts)[1] / vscale
            inner = np.flatnonzero((sv[1:-1] <= sv[:-2]) & (sv[1:-1] <= sv[2:]) & (sv[1:-1] < delta)) + 1
            if inner.size:
                cut = min(cut, float(ts[inner[0]]))
            if ends_inside:
                x = float(ex.evaluate(np.array([seg.t1]))[0][0])
                if near(abs(p.P0 * math.cos(p.omega * seg.t1 + p.phi) - p.k * x) - Fb):
                    cut = min(cut, seg.t1)
            continue
        # stuck at x0: S(t) = P0 cos(w t + phi) - k x0, its extrema where the cosine is +-1
        th0, th1 = p.omega * seg.t0 + p.phi, p.omega * seg.t1 + p.phi
        for n in range(math.ceil(th0 / math.pi), math.floor(th1 / math.pi) + 1):
            if near(abs(p.P0 * (-1.0) ** n - p.k * seg.x0) - Fb):
                cut = min(cut, (n * math.pi - p.phi) / p.omega)
        if ends_inside:  # breakaway: the peak the static force would reach, over the limit
            s = 1.0 if p.P0 * math.cos(th1) - p.k * seg.x0 > 0.0 else -1.0
            if near(p.P0 - s * p.k * seg.x0 - Fb):
                cut = min(cut, seg.t1)
    return max(cut, 0.0)


# random steps may be coarse for the drawn dynamics: the FMU's warning is expected there (its
# delivery is tested in test_warnings.py), the property is what this test checks
@pytest.mark.filterwarnings("ignore::dryfriction.diagnostics.DryFrictionWarning")
@pytest.mark.min_versions
@pytest.mark.slow
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(lam=st.floats(0.2, 3.0), ms=st.floats(0.0, 1.5), chi=st.floats(0.05, 3.0), zeta=st.floats(0.0, 1.5),
       z0=st.floats(-2.0, 2.0), dz0=st.floats(-2.0, 2.0), phi=st.floats(-math.pi, math.pi))
# A breakaway tie: at rest, the static force's peak 1 + |z0| equals the limit mu_s sigma to rounding;
# whether the block breaks away depends on the last bit (found by Hypothesis with lam 1, mu_s sigma 1,
# z0 2.2e-16, zeta 0: the two schemes 1.34 apart at T/4000, 1.7e-4 at T/16000; its chi and phi were not
# recorded, 0.5 and 0 here). near_tie_time puts the tie at t = 0: nothing is compared past it.
@example(lam=1.0, ms=1.0, chi=0.5, zeta=0.0, z0=2.220446049250313e-16, dz0=0.0, phi=0.0)
# A breakaway limit below the rounding of the static force (test_breakaway_limit_below_rounding):
# the located and exact schemes held the block stuck with the force 2 N over the limit.
@example(lam=1.0, ms=5.231643411550108e-24, chi=1.0, zeta=0.0, z0=1.0, dz0=0.0, phi=0.0)
# No friction, a stop within rounding of t_end: the exact reference's root finder had no bracket there
# (tests/test_references.py::test_stop_within_rounding_at_the_end).
@example(lam=2.0, ms=0.0, chi=1.0, zeta=0.0, z0=2.0, dz0=0.0, phi=2.0)
# Damping below rounding (zeta 1e-298): the exact reference missed its stops
# (tests/test_references.py::test_damping_below_rounding_is_undamped).
@example(lam=1.0, ms=1.0, chi=1.0, zeta=1.0067496880435664e-298, z0=0.0, dz0=1.0, phi=0.0)
# A near tie: the backward slide ending at t = 1.2145 T stops where the static force is 0.500723 P0,
# 7.2e-4 P0 over the limit 0.5 P0: the exact motion reverses. The consistent scheme decides with the
# force at the step's end (first order: the forcing alone falls 1.1e-3 P0 over a step of T/4000), so
# it sticks there at T/250 and T/4000 (1.04 and 0.95 P0/k off the exact motion) and reverses at T/1000,
# T/2000 and from T/8000 on (errors 6.3e-3, 2.3e-3, 5.6e-4, 6.0e-4, 1.7e-4, 6.0e-5 P0/k at T/1000 ...
# T/64000); the located scheme is on the exact branch at every h (3.4e-2 at T/250, 1.3e-4 at T/4000).
# Found twice by Hypothesis. The comparison stops at t = 1.0116 T, at an earlier stop 1.4e-2 P0 from
# the limit (within delta = 3.1e-2 here); the consistent scheme is 4.7e-4 P0/k off before it.
@example(lam=0.20001220703125028, ms=0.5, chi=0.050781250000000076, zeta=0.0, z0=-0.5,
         dz0=-0.21875000000000033, phi=1.0)
def test_random_parameters(fmu: OscillatorFMU2, lam: float, ms: float, chi: float, zeta: float, z0: float,
                           dz0: float, phi: float) -> None:
    """Random valid parameters: outputs finite, invariants at every step, and both Bossak schemes
    converge to the exact solution as h shrinks (over two periods), up to the first decision of the
    exact motion within the consistent scheme's decision error of a tie (near_tie_time).

    The consistent scheme decides a stop with the static force at the step's end, off by up to
    P0 w h from the force at the stop, plus k times its first-order position error (at most 2.2 w0 h
    P0/k measured over 1500 random cases at T/4000); delta = 4 max(w, w0) h covers both. Past a tie
    closer than that, a grid scheme's branch is decided by where the stop falls in its step: the
    limit h -> 0 holds there too, but only below a step that the tie's margin sets, not at T/4000."""
    p = ND(lam, ms, chi, zeta=zeta, z0=z0, dz0=dz0, phi=phi)
    T = p.period
    scale = p.P0 / p.k
    ex = solve_exact(p, 2 * T)
    t_cut = near_tie_time(ex, 4.0 * (2.0 * math.pi / 4000) * max(1.0, 1.0 / lam))
    err: dict[str, list[float]] = {"located": [], "consistent": []}
    for n in (250, 4000):
        t = np.arange(2 * n + 1) * (T / n)
        xe = ex.evaluate(t)[0]
        before = t <= t_cut
        loc = run(fmu, p, 2 * T, T / n)
        check_invariants(loc)
        con = run(fmu, p, 2 * T, T / n, scheme="consistent")
        check_invariants(con, "consistent", one_step_reversal_stick=True)
        for name, r in (("located", loc), ("consistent", con)):
            err[name].append(float(np.abs(r.x - xe)[before].max()) / scale)
    # first order (16x smaller h): at least halved, or small; second order: at least 10x smaller,
    # or small (measured over 1500 random cases at T/4000: 1.2e-2 consistent, 3.3e-4 located)
    assert err["consistent"][1] <= 0.05 or err["consistent"][1] <= 0.5 * err["consistent"][0], err
    assert err["located"][1] <= 0.01 or err["located"][1] <= 0.1 * err["located"][0], err


# --------------------------------------------------------------------------- the scales the FMUs honour
# m within [1 / SCALE_LIMIT, SCALE_LIMIT] and k <= SCALE_LIMIT are declared (a host sees them); k > 0
# below 1 / SCALE_LIMIT and a motion whose force scale over m or over k is below 1 / SCALE_LIMIT^2
# are refused at the end of initialisation with a sentence naming the variables and the range. Each
# of the four FMUs through fmpy itself (no driver of the package between), against its unit-scale run.

FOUR = [("oscillator", 2), ("oscillator", 3), ("chain", 2), ("chain", 3)]
_LOCATE = {("oscillator", 2): default_fmu_path, ("oscillator", 3): default_fmi3_path,
           ("chain", 2): default_chain_fmu, ("chain", 3): default_chain_fmu3}
# the unit oscillator (w0 = 1, zeta = 0.05, lambda = 0.8, mu_s sigma = 0.4, chi = 0.7): stick-slip
UNIT = dict(c=0.1, omega=0.8, mu_s=0.4, chi=0.7)


@pytest.fixture(scope="module")
def four() -> Iterator[dict[tuple[str, int], tuple[str, Any]]]:
    """The four FMUs unzipped, with fmpy's model descriptions."""
    out = {}
    for key, locate in _LOCATE.items():
        path = str(locate())
        out[key] = (extract(path, unzipdir=tempfile.mkdtemp(prefix="dfo-scale-")), read_model_description(path))
    yield out
    for d, _ in out.values():
        shutil.rmtree(d, ignore_errors=True)


class Refused(Exception):
    """An FMI call failed; the FMU's logged error sentences."""


def _fmpy_run(fmu: tuple[str, Any], version: int, reals: dict[str, float], ints: dict[str, int], t_stop: float,
              steps: int = 20) -> np.ndarray:
    """x and v of the first block at steps equal communication points through fmpy's FMU2Slave or
    FMU3Slave; a chain's array parameters get the same value in every block. Refused (with the
    logged error sentences) when a call fails."""
    d, md = fmu
    vars_ = {v.name: v for v in md.modelVariables}
    log: list[tuple[int, str]] = []

    def names(name: str) -> list[str]:  # an FMI 2.0 chain's arrays are m[1] ... m[n]
        return [name] if name in vars_ else sorted((n for n in vars_ if n.startswith(name + "[")),
                                                   key=lambda n: int(n[len(name) + 1:-1]))

    def size(name: str) -> int:  # an FMI 3.0 array's length: the start of its structural parameter
        dims = getattr(vars_[name], "dimensions", None) or []
        return int(vars_[dims[0].variable.name].start) if dims else 1

    if version == 2:
        cb = Counting()
        s: Any = FMU2Slave(guid=md.guid, unzipDirectory=d, modelIdentifier=md.coSimulation.modelIdentifier,
                           instanceName="scale")
        s.instantiate(callbacks=cb.struct)
    else:
        s = FMU3Slave(guid=md.guid, unzipDirectory=d, modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName="scale")
        s.instantiate(logMessage=lambda env, status, cat, msg: log.append((status, msg.decode())))
    try:
        if version == 2:
            s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        for name, value in reals.items():
            for n in names(name):
                if version == 2:
                    s.setReal([vars_[n].valueReference], [value])
                else:
                    s.setFloat64([vars_[n].valueReference], [value] * size(n))
        for name, value in ints.items():
            (s.setInteger if version == 2 else s.setInt64)([vars_[name].valueReference], [value])
        s.exitInitializationMode()
        vr = [vars_[names(n)[0]].valueReference for n in ("x", "v")]
        out = []
        for i in range(steps):
            s.doStep(i * t_stop / steps, t_stop / steps)
            got = s.getReal(vr) if version == 2 else s.getFloat64(vr, nValues=2 * size(names("x")[0]))
            out.append([got[0], got[1 if version == 2 else size(names("x")[0])]])
        s.terminate()
        return np.array(out)
    except Exception as e:  # fmpy raises its own exception for a failed call: the FMU's sentences
        msgs = [m for st, _, m in cb.messages if st >= 3] if version == 2 else [m for st, m in log if st >= 3]
        raise Refused(" | ".join(msgs) or str(e)) from None
    finally:
        s.freeInstance()


def _scaled(fmu: tuple[str, Any], model: str, version: int, m: float, k: float, s: float,
            scheme: int | None = None) -> np.ndarray:
    """The unit oscillator scaled: mass m, stiffness k, forces s (P0 and N), so that x scales as s/k
    and time as sqrt(m/k); returned non-dimensional (x k/s and v sqrt(k m)/s over w0 t in [0, 20])."""
    w0 = math.sqrt(k) / math.sqrt(m)
    reals = dict(m=m, k=k, c=UNIT["c"] * math.sqrt(k) * math.sqrt(m), P0=s, omega=UNIT["omega"] * w0, N=s,
                 mu_s=UNIT["mu_s"], chi=UNIT["chi"])
    r = _fmpy_run(fmu, version, reals, {} if scheme is None else {"scheme": scheme}, 20.0 / w0)
    return np.column_stack([r[:, 0] / s * k, r[:, 1] / s * math.sqrt(k) * math.sqrt(m)])


def test_the_scale_limit_is_the_declared_range_of_every_fmu(four: dict) -> None:
    """One source of truth: params.SCALE_LIMIT (the Python side's check) is the range every FMU
    declares for m ([1/limit, limit]) and every stiffness (<= limit), in both FMI versions."""
    for key, (_, md) in four.items():
        by = {v.name: v for v in md.modelVariables}
        ms = [v for n, v in by.items() if n == "m" or n.startswith("m[")]
        ks = [v for n, v in by.items() if n.split("[")[0] in ("k", "k_end", "k_site")]
        assert ms and ks, key
        for v in ms:
            assert (float(v.min), float(v.max)) == (1.0 / SCALE_LIMIT, SCALE_LIMIT), (key, v.name)
        for v in ks:
            assert (float(v.min), float(v.max)) == (0.0, SCALE_LIMIT), (key, v.name)
    assert SCALE_LIMIT == 1e100


@pytest.mark.parametrize("model, version", FOUR)
@pytest.mark.parametrize("m, k, s", [(1e-100, 1e-100, 1.5e-300), (1e100, 1e100, 1.5e-100), (1e-100, 1e100, 1.5e-100),
                                     (1e100, 1e-100, 1.5e-100), (1e100, 1e100, 1e300)])
def test_the_edges_of_the_valid_range_give_the_scaled_result(four: dict, model: str, version: int, m: float,
                                                             k: float, s: float) -> None:
    """m and k at 1e-100 and 1e100 (w0 from 1e-100 to 1e100), the force scale at 1.5 times its
    floor (force / m or force / k = 1.5e-200) or at 1e300: the unit run's motion within 1e-9 (the
    exact scheme and the located one for the oscillator, the chain's default)."""
    schemes = [4, 3] if model == "oscillator" else [None]
    for scheme in schemes:
        ref = _scaled(four[(model, version)], model, version, 1.0, 1.0, 1.0, scheme)
        got = _scaled(four[(model, version)], model, version, m, k, s, scheme)
        assert np.max(np.abs(ref[:, 0])) > 0.5  # it moves
        assert np.max(np.abs(got - ref)) <= 1e-9 * np.max(np.abs(ref)), (scheme, np.max(np.abs(got - ref)))


@pytest.mark.parametrize("model, version", FOUR)
@pytest.mark.parametrize("reals, says", [
    (dict(m=1e-300, k=1e-300), ["invalid value 1e-300 for", "m", "1e-100, 1e+100"]),   # the exact run that said 0
    (dict(m=1.01e100), ["invalid value 1.01e+100 for", "m", "1e-100, 1e+100"]),
    (dict(k=1e155), ["invalid value 1e+155 for", "k", "0, 1e+100"]),                    # its Jacobian turned NaN
    (dict(k=1e-300), ["invalid value 1e-300 for k", "valid range: 0 (no spring) or 1e-100 to 1e+100 N/m"]),
    (dict(P0=1e-250, N=1e-250), ["force scale", "1e-250 N over m", "below 1e-200 m/s2",
                                 "valid range: force scale / m >= 1e-200 m/s2 and force scale / k >= 1e-200 m"]),
    (dict(k=1e100, P0=1e-150, N=1e-150), ["force scale", "1e-150 N over k", "= 1e+100 N/m is below 1e-200 m"]),
])
def test_values_no_computation_honours_are_refused_with_the_reason(four: dict, model: str, version: int,
                                                                   reals: dict[str, float], says: list[str]) -> None:
    """Each refused with an error and a logged sentence naming the variable (the chain: its element)
    and the valid range: m or k beyond their declared ranges when set, k > 0 below 1e-100 and a
    motion below double precision's normal range at the end of initialisation."""
    params = {**dict(m=1.0, k=1.0, c=0.0, P0=1.0, omega=0.8, N=1.0, mu_s=0.4, chi=0.7), **reals}
    with pytest.raises(Refused) as err:
        _fmpy_run(four[(model, version)], version, params, {}, 1.0)
    msg = str(err.value)
    for part in says:
        assert part in msg, (part, msg)
    if model == "chain" and "force scale" not in msg:
        assert "[1]" in msg, msg   # the element named
