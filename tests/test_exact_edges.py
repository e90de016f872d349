"""The exact scheme (scheme 4) at its edges: each property against a 40-digit
reference (mpmath closed forms written here) or against the same run cut differently.

- one doStep over 1e6 periods equals one doStep per period (within 1e-12 of the motion's size),
  and so do event-rich runs over fewer periods and runs cut at random;
- continuity across critical damping (zeta = 1 - 2^-53, 1, 1 + 2^-52 within 1e-13) and the
  near-critical motion against the closed form;
- heavily over-damped creep towards equilibrium (zeta = 1000, constant force) equals the closed
  form within 1e-12 and is never declared stuck before it has reached the equilibrium, whatever
  the host's communication steps;
- scale invariance: x scales with P0 and N together (1e-200 ... 1e300), time with sqrt(m/k);
  values that would overflow are an error naming the cause, never OK with a wrong number;
- a large phi keeps its phase (phi = 1e12 against phi reduced mod 2 pi to 40 digits);
- the chain at n = 1 is the oscillator bit for bit for every phi, in every scheme (the Bossak
  schemes; the chain has no exact scheme).

Non-dimensional setting unless said otherwise: m = k = P0 = 1, so w0 = 1, lambda = omega,
zeta = c / 2, sigma = N, z = x."""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path

import mpmath as mp
import numpy as np
import pytest

from dryfriction.drivers.chain import ChainFMU3
from dryfriction.drivers.oscillator import FMUError, OscillatorFMU2, Settings
from dryfriction.params import Oscillator

from helpers import CHAIN_N1_REL, assert_rounding_apart

mp.mp.dps = 40


def EXACT(h: float) -> Settings:
    """The exact scheme; h only bounds a communication step's length (1e9 h), it has no effect."""
    return Settings(scheme="exact", h=h)


@pytest.fixture(scope="module")
def fmu(fmu_path) -> Iterator[OscillatorFMU2]:
    with OscillatorFMU2(fmu_path, logging=True) as f:
        yield f


def nondim(lam: float, mss: float, chi: float, zeta: float, **kw: float) -> Oscillator:
    return Oscillator(**{"m": 1.0, "k": 1.0, "c": 2.0 * zeta, "P0": 1.0, "omega": lam, "phi": 0.0, "N": mss / 0.5,
                         "mu_s": 0.5, "chi": chi, "x0": 0.0, "v0": 0.0, **kw})


def one_call(f: OscillatorFMU2, p: Oscillator, t_end: float, h: float) -> dict[str, float]:
    f.start(p, EXACT(h))
    f.step_to(t_end)
    return f.get(["x", "v", "a", "mode"])


# ---- one doStep over many periods = one doStep per period --------------------------------------

@pytest.mark.slow
def test_one_dostep_over_1e6_periods_equals_one_per_period(fmu: OscillatorFMU2) -> None:
    """Slip with two reversals a period (lambda 0.8, mu_s sigma 0.1, chi 0.7: 2e6 events): one
    doStep to 1e6 T and 1e6 doSteps of T agree within 1e-12 of the motion's size (before: 2.8e-8
    after 1e5 periods, growing as n^2: the excitation phase carried over the events and the event
    times rounded to doubles)."""
    p = nondim(0.8, 0.1, 0.7, 0.0)
    T, n = p.period, 1_000_000
    a = one_call(fmu, p, n * T, T)
    # one doStep per period through the C function (a Python loop of 1e6 calls: a few seconds)
    fmu.start(p, EXACT(T))
    inst = fmu.fmi
    do_step, comp = inst.f.DoStep, inst.component
    for i in range(n):
        if st := do_step(comp, i * T, (i + 1) * T - i * T, 1):
            inst.check("fmi2DoStep", st)
    fmu.time = n * T
    b = fmu.get(["x", "v", "mode"])
    size = max(abs(b["x"]), p.P0 / p.k)
    assert b["mode"] == a["mode"] != 0
    assert abs(a["x"] - b["x"]) <= 1e-12 * size, (a["x"], b["x"])
    assert abs(a["v"] - b["v"]) <= 1e-12 * size * p.omega


@pytest.mark.slow
@pytest.mark.parametrize("lam, mss, chi, zeta, periods", [
    (0.5, 0.4, 0.7, 0.0, 20_000),    # stick-dominated: two stops, two breakaways a period
    (0.5, 0.8, 0.6, 0.1, 20_000),    # heavy friction, damped
    (0.5, 0.2, 2.0, 0.0, 20_000),    # chi = 2: breakaways with zero acceleration
    (3.0, 0.2, 0.5, 0.1, 20_000),    # above resonance, reversals (was 2.5e-11 apart after 1e5 periods)
    (0.8, 0.1, 0.7, 0.02, 20_000),   # reversals, light damping
    (1.3, 0.0, 1.0, 0.0, 20_000),    # neither friction nor damping: nothing decays (was 1.8e-10 after 5e4)
])
def test_event_rich_runs_do_not_depend_on_the_communication_steps(fmu: OscillatorFMU2, lam: float, mss: float,
                                                                   chi: float, zeta: float, periods: int) -> None:
    """One doStep, one doStep per period and doSteps of random length end on the same state
    within 1e-12 of the motion's size."""
    p = nondim(lam, mss, chi, zeta, x0=0.3, v0=-0.2)
    T = p.period
    t_end = periods * T
    a = one_call(fmu, p, t_end, T)
    per = fmu.trajectory(p, T * np.arange(periods + 1), EXACT(T), outputs=("x", "v", "mode"))
    rng = np.random.default_rng(7)
    cuts = np.cumsum(rng.uniform(0.05, 2.0, size=int(1.2 * periods / 1.0)) * T)
    cuts = np.concatenate([[0.0], cuts[cuts < t_end - 1e-9 * T], [t_end]])
    rnd = fmu.trajectory(p, cuts, EXACT(T), outputs=("x", "v", "mode"))
    size = float(np.max(np.abs(per["x"])))
    for r in (per, rnd):
        assert r["mode"][-1] == a["mode"]
        assert abs(r["x"][-1] - a["x"]) <= 1e-12 * size, (r["x"][-1], a["x"])
        assert abs(r["v"][-1] - a["v"]) <= 1e-12 * size * max(1.0, lam)


# ---- critical damping -------------------------------------------------------------------------

def linear_ref(zeta: float, lam: float, phi: float, x0: float, v0: float, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """x'' + 2 zeta x' + x = cos(lam t + phi) from (x0, v0), to 40 digits (zeta, phi as given: doubles)."""
    z, lm, ph = mp.mpf(zeta), mp.mpf(lam), mp.mpf(phi)
    Q = mp.exp(1j * ph) / (1 - lm ** 2 + 2j * z * lm)
    hy, hv = mp.mpf(x0) - mp.re(Q), mp.mpf(v0) - mp.re(1j * lm * Q)
    xs, vs = [], []
    for tt in t:
        tm = mp.mpf(float(tt))
        f = Q * mp.exp(1j * lm * tm)
        if z == 1:
            e = mp.exp(-tm)
            yh, vh = (hy + (hv + hy) * tm) * e, ((hv + hy) - hy - (hv + hy) * tm) * e
        else:
            s = mp.sqrt(mp.mpc(z * z - 1))
            r1, r2 = -z + s, -z - s
            c2 = (hv - r1 * hy) / (r2 - r1)
            c1 = hy - c2
            yh = mp.re(c1 * mp.exp(r1 * tm) + c2 * mp.exp(r2 * tm))
            vh = mp.re(c1 * r1 * mp.exp(r1 * tm) + c2 * r2 * mp.exp(r2 * tm))
        xs.append(float(mp.re(f) + yh))
        vs.append(float(mp.re(1j * lm * f) + vh))
    return np.array(xs), np.array(vs)


CRITICAL = [1.0 - 2.0 ** -53, 1.0, 1.0 + 2.0 ** -52, 1.0 - 1e-12, 1.0 + 1e-12, 1.0 - 1e-8, 1.0 + 1e-8,
            1.0 - 1e-4, 1.0 + 1e-4, 0.97, 1.03, 0.9, 1.2]


@pytest.mark.parametrize("lam", [0.5, 1.0, 2.0])
@pytest.mark.parametrize("zeta", CRITICAL)
def test_near_critical_damping_equals_the_closed_form(fmu: OscillatorFMU2, zeta: float, lam: float) -> None:
    """Frictionless (N = 0: the motion is linear, the FMU still stops at every v = 0) at and near
    critical damping: within 1e-13 of the 40-digit closed form (before: up to 4e-10, the free
    part's bounds grew like 1 / wd, 1 / wh near zeta = 1 and made the zero tests coarse)."""
    p = nondim(lam, 0.0, 1.0, 0.0, c=2.0 * zeta, x0=0.4, v0=-0.3)
    t = np.linspace(0.0, 20.0 * p.period, 161)
    tr = fmu.trajectory(p, t, EXACT(p.period), outputs=("x", "v"))
    x, v = linear_ref(zeta, lam, 0.0, 0.4, -0.3, t)
    size = max(float(np.max(np.abs(x))), 1.0)
    assert np.max(np.abs(tr["x"] - x)) <= 1e-13 * size
    assert np.max(np.abs(tr["v"] - v)) <= 1e-13 * size * max(1.0, lam)


@pytest.mark.parametrize("lam, mss, chi", [(0.5, 0.4, 0.7), (1.0, 0.2, 0.7), (2.0, 0.4, 0.7), (0.3, 0.1, 1.0),
                                           (1.0, 0.3, 2.0)])
def test_continuous_across_critical_damping(fmu: OscillatorFMU2, lam: float, mss: float, chi: float) -> None:
    """With stick-slip: c = 2 (1 - 2^-53) sqrt(km), 2 sqrt(km) and 2 (1 + 2^-52) sqrt(km) give
    the same motion within 1e-13 (before: 2e-10 apart), with m, k not 1."""
    m, k = 2.5, 0.7
    base = dict(m=m, k=k, P0=1.0, omega=lam * math.sqrt(k / m), N=mss / 0.5, mu_s=0.5, chi=chi, x0=0.3, v0=-0.1)
    c0 = 2.0 * math.sqrt(k * m)
    runs = []
    for c in (c0 * (1.0 - 2.0 ** -53), c0, c0 * (1.0 + 2.0 ** -52)):
        p = Oscillator(c=c, **base)
        t = np.linspace(0.0, 30.0 * p.period, 301)
        runs.append(fmu.trajectory(p, t, EXACT(p.period), outputs=("x", "v", "mode")))
    size = max(float(np.max(np.abs(runs[1]["x"]))), 1.0 / k)
    for r in (runs[0], runs[2]):
        assert np.max(np.abs(r["x"] - runs[1]["x"])) <= 1e-13 * size
        assert (r["mode"] == runs[1]["mode"]).mean() > 0.99


# ---- over-damped creep ------------------------------------------------------------------------

def creep_ref(zeta: float, x_eq: float, x0: float, t: np.ndarray) -> np.ndarray:
    """x'' + 2 zeta x' + x = x_eq from (x0, 0): x_eq + c1 e^{r1 t} + c2 e^{r2 t}, to 40 digits."""
    z = mp.mpf(zeta)
    s = mp.sqrt(z * z - 1)
    r1, r2 = -z + s, -z - s  # r1 = -1 / (z + s): the slow creep
    hy = mp.mpf(x0) - mp.mpf(x_eq)
    c2 = -r1 * hy / (r2 - r1)
    c1 = hy - c2
    return np.array([float(mp.mpf(x_eq) + c1 * mp.exp(r1 * mp.mpf(float(tt))) + c2 * mp.exp(r2 * mp.mpf(float(tt))))
                     for tt in t])


@pytest.mark.parametrize("cuts", ["one", "10", "100", "1000", "random"])
def test_overdamped_creep_is_not_stuck_early(fmu: OscillatorFMU2, cuts: str) -> None:
    """zeta = 1000, constant force (omega = 0): the block creeps towards x_eq = (P0 - mu_k N) / k
    as e^{-t / 2000} and never stops (v = 0 only in the limit). Against the closed form within
    1e-12 at every communication point, and stuck only where the closed form is within 1e-12 of
    x_eq, whatever the communication steps (before: stuck at v = 2e-10, 1e-8 ... 4.4e-7 short of
    x_eq, depending on the steps: the derivatives from the equation of motion lost (2 zeta)^k)."""
    p = Oscillator(m=1.0, k=1.0, c=2000.0, P0=1.0, omega=0.0, N=0.4, mu_s=0.5, chi=0.7, x0=-1.0, v0=0.0)
    x_eq = (p.P0 - p.chi * p.mu_s * p.N) / p.k
    t_end = 1e5
    if cuts == "one":
        t = np.array([0.0, t_end])
    elif cuts == "random":
        t = np.sort(np.concatenate([[0.0, t_end], np.random.default_rng(3).uniform(0.0, t_end, 300)]))
    else:
        t = np.linspace(0.0, t_end, int(cuts) + 1)
    tr = fmu.trajectory(p, t, EXACT(1.0), outputs=("x", "v", "mode"))
    x = creep_ref(1000.0, x_eq, -1.0, t)
    assert np.max(np.abs(tr["x"] - x)) <= 1e-12
    stuck = tr["mode"] == 0
    assert np.all(np.abs(x[stuck] - x_eq) <= 1e-12), x[stuck] - x_eq
    assert np.all(tr["v"][~stuck] >= 0.0)


# ---- scale invariance, overflow -----------------------------------------------------------------

STICK_SLIP = dict(lam=0.5, mss=0.4, chi=0.7, zeta=0.05, x0=0.3, v0=-0.2)


def scaled_run(f: OscillatorFMU2, s: float, sigma: float = 1.0) -> dict[str, np.ndarray]:
    """The stick-slip case with P0, N, x0, v0 times s and the time unit times sigma (m times sigma^2)."""
    c = STICK_SLIP
    p = Oscillator(m=sigma ** 2, k=1.0, c=2.0 * c["zeta"] * sigma, P0=s, omega=c["lam"] / sigma, N=c["mss"] / 0.5 * s,
                   mu_s=0.5, chi=c["chi"], x0=c["x0"] * s, v0=c["v0"] * s / sigma)
    t = np.linspace(0.0, 10.0 * p.period, 201)
    return f.trajectory(p, t, EXACT(p.period), outputs=("x", "v", "mode"))


@pytest.mark.parametrize("s", [1e-200, 1e-170, 1e-150, 1e-100, 1e-30, 3.7, 1e30, 1e100, 1e150, 1e155, 1e200, 1e300])
def test_x_scales_with_P0_and_N(fmu: OscillatorFMU2, s: float) -> None:
    """x / s and v / s equal the unscaled run's within 1e-13 (before: OK with x = v = a = 0 once
    |x| > 1e154, a relative error of 1e-4 below 1e-162: squares over- and underflowed)."""
    ref, r = scaled_run(fmu, 1.0), scaled_run(fmu, s)
    size = float(np.max(np.abs(ref["x"])))
    assert np.array_equal(r["mode"], ref["mode"])
    assert np.max(np.abs(r["x"] / s - ref["x"])) <= 1e-13 * size
    assert np.max(np.abs(r["v"] / s - ref["v"])) <= 1e-13 * size * STICK_SLIP["lam"]


@pytest.mark.parametrize("sigma, s", [(1e-3, 1.0), (1e4, 1.0), (1e-3, 1e-150), (1e5, 1e120)])
def test_time_scales_with_sqrt_m_over_k(fmu: OscillatorFMU2, sigma: float, s: float) -> None:
    ref, r = scaled_run(fmu, 1.0), scaled_run(fmu, s, sigma)
    size = float(np.max(np.abs(ref["x"])))
    assert np.array_equal(r["mode"], ref["mode"])
    assert np.max(np.abs(r["x"] / s - ref["x"])) <= 1e-13 * size
    assert np.max(np.abs(r["v"] * sigma / s - ref["v"])) <= 1e-13 * size * STICK_SLIP["lam"]


def test_overflow_is_an_error_never_a_wrong_number(fmu: OscillatorFMU2) -> None:
    """At resonance without friction or damping x grows as t sin(t) P0 / 2k: with P0 = 1e307 it
    leaves the double range near t = 36. Every step until then is right (against P0 = 1 scaled),
    the step that would overflow is an error whose logged sentence names the overflow."""
    big = Oscillator(m=1.0, k=1.0, c=0.0, P0=1e307, omega=1.0, N=0.0, mu_s=0.5, chi=1.0)
    unit = Oscillator(m=1.0, k=1.0, c=0.0, P0=1.0, omega=1.0, N=0.0, mu_s=0.5, chi=1.0)
    t = np.linspace(0.0, 60.0, 121)
    ref = fmu.trajectory(unit, t, EXACT(0.1), outputs=("x", "v"))
    fmu.start(big, EXACT(0.1))
    ok = 0
    with pytest.raises(FMUError, match="overflow"):
        for i in range(1, t.size):
            fmu.step_to(float(t[i]))
            x = fmu.get(["x"])["x"]
            assert math.isfinite(x) and abs(x - 1e307 * ref["x"][i]) <= 1e-13 * 1e307 * np.max(np.abs(ref["x"][: i + 1]))
            ok = i
    assert 60 <= ok < 90  # t = 30 ... 45
    assert any(cat == "logStatusError" and "overflow" in msg for _, cat, msg in fmu.messages[-3:])


def test_a_huge_static_deflection_with_a_representable_motion(fmu: OscillatorFMU2) -> None:
    """P0 / k = 1e310 (not a double) but lambda = 1e5: the motion (about P0 / (m omega^2) = 1e300)
    is representable and right: against the run with P0 = 1e-10."""
    p = dict(m=1.0, k=1e-10, c=0.0, omega=1.0, N=0.0, mu_s=0.5, chi=1.0)
    t = np.linspace(0.0, 60.0, 121)
    big = fmu.trajectory(Oscillator(P0=1e300, **p), t, EXACT(0.1), outputs=("x",))
    small = fmu.trajectory(Oscillator(P0=1e-10, **p), t, EXACT(0.1), outputs=("x",))
    assert np.max(np.abs(big["x"] / 1e300 / 1e10 - small["x"])) <= 1e-13 * np.max(np.abs(small["x"]))


# ---- a large phi --------------------------------------------------------------------------------

def reduced(phi: float) -> float:
    with mp.workdps(400):
        return float(mp.fmod(mp.mpf(phi), 2 * mp.pi))


@pytest.mark.parametrize("phi, P0, t0", [(1e12, 1.0, 0.0), (1e12, -1.0, 0.0), (-3e15, 1.0, 0.0), (1e300, 1.0, 0.0),
                                         (123.456, -1.0, 0.0), (1e12, 1.0, 12345.678)])
def test_a_large_phi_keeps_its_phase(fmu: OscillatorFMU2, phi: float, P0: float, t0: float) -> None:
    """phi = 1e12 against phi reduced mod 2 pi to 400 digits (then rounded): the same motion within
    1e-13 (before: 6.7e-5 apart, phi + omega t rounded to an ulp of 1e12), also from a start time
    t0 != 0 (the start's stick/slip decision and acceleration)."""
    c = STICK_SLIP
    base = dict(m=1.0, k=1.0, c=2.0 * c["zeta"], P0=P0, omega=c["lam"], N=c["mss"] / 0.5, mu_s=0.5, chi=c["chi"],
                x0=c["x0"], v0=c["v0"])
    t = t0 + np.linspace(0.0, 10.0 * 2.0 * math.pi / c["lam"], 201)
    out = ("x", "a", "F_friction", "mode")
    a = fmu.trajectory(Oscillator(phi=phi, **base), t, EXACT(1.0), outputs=out)
    b = fmu.trajectory(Oscillator(phi=reduced(phi), **base), t, EXACT(1.0), outputs=out)
    assert np.array_equal(a["mode"], b["mode"])
    for k in ("x", "a", "F_friction"):  # (the outputs a and F_friction too: P0 cos(omega t + phi) exact)
        assert np.max(np.abs(a[k] - b[k])) <= 1e-13 * np.max(np.abs(b[k])), k


def test_a_large_phi_against_the_closed_form(fmu: OscillatorFMU2) -> None:
    """Frictionless, zeta = 0.1, phi = 1e12 exactly in the 40-digit closed form."""
    p = nondim(0.7, 0.0, 1.0, 0.1, phi=1e12, x0=0.2)
    t = np.linspace(0.0, 20.0 * p.period, 101)
    tr = fmu.trajectory(p, t, EXACT(1.0), outputs=("x",))
    with mp.workdps(60):
        x, _ = linear_ref(0.1, 0.7, 1e12, 0.2, 0.0, t)
    assert np.max(np.abs(tr["x"] - x)) <= 1e-13 * np.max(np.abs(x))


# ---- the chain at n = 1 with any phi ------------------------------------------------------------

ONE_BLOCK = [dict(m=2.0, k=3.0, c=0.2, P0=1.5, omega=1.1, N=0.6, mu_s=0.4, chi=1.4, x0=0.3, v0=-0.2),
             dict(m=1.0, k=1.0, c=0.1, P0=-1.0, omega=0.5, N=0.8, mu_s=0.5, chi=0.7, x0=0.3, v0=0.0)]


@pytest.mark.parametrize("case", range(len(ONE_BLOCK)))
@pytest.mark.parametrize("phi", [0.3, -1.2, 2.5, math.pi, 1e3, 1e12])
@pytest.mark.parametrize("scheme", ["located", "consistent", "paper"])
def test_chain_n1_is_the_oscillator_for_every_phi(case: int, phi: float, scheme: str, chain_fmu3: Path,
                                                  fmu: OscillatorFMU2) -> None:
    """One block of the FMI 3.0 chain gives the oscillator FMU's mode with phi != 0, and its x, v, a
    and F_friction to rounding (blocks sharing one phase take the oscillator's excitation, and the
    output a its closed form; helpers.CHAIN_N1_REL: the oscillator's Bossak schemes step through the
    friction engine, the chain through its own stepper, their arithmetic ordered otherwise). Where
    omega t + phi itself rounds by more (phi = 1e12: an ulp of 1.2e-4 rad, the excitation a
    staircase), the located breakaways are placed apart by that much (the chain by the closed form,
    the engine by the root of its trial's force where the closed form misses it): to 2 ulp(phi)."""
    b = ONE_BLOCK[case]
    p = Oscillator(phi=phi, **b)
    T = p.period
    h, dt = T / 500, T / 50
    with ChainFMU3(1, fmu_path=chain_fmu3) as f:
        run = f.run(6 * T, dt, {**b, "phi": phi, "h": h, "alpha": -0.1, "scheme": scheme})
    ref = fmu.trajectory(p, run.t, Settings(h=h, alpha=-0.1, scheme=scheme))
    assert (run.mode != 0).any()
    assert np.array_equal(run.mode[:, 0], ref["mode"])
    rel = max(CHAIN_N1_REL, 2.0 * math.ulp(phi))
    for k in ("x", "v", "F_friction", "a"):
        assert_rounding_apart(getattr(run, k)[:, 0], ref[k], k, rel)
