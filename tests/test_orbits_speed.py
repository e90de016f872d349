"""The fast paths of the orbit method (docs/performance.md, "Steady states from orbits"): the FMU
driver's Restarts (start's calls with the value arrays built once) against the closed-form harmonic
response and exp(A T) without friction and against the driver's own start / step_to / get; its
refusals; the sweep's cubic predictor against a cubic; the follower's path for a guess that is
periodic already; find_orbits' skipped cycle runs of duplicates against the orbits it finds from
transients (each stable one attracts a separate long transient)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.linalg import expm

from dryfriction import Oscillator
from dryfriction.errors import FMUError
from dryfriction.drivers.oscillator import OscillatorFMU2, Settings
from dryfriction.analysis.orbits import OrbitFollower, find_orbits
from dryfriction.analysis.response import _Branch

JAC = ("dx_dx0", "dx_dv0", "dv_dx0", "dv_dv0")
OBS = ("x_max", "x_min", "stick_fraction")
SENS = Settings(scheme="exact", observe=True, extra={"sensitivity": True})


def harmonic_state(p: Oscillator, t: float) -> tuple[float, float, float]:
    """(X, x(t), v(t)) of the closed-form steady response to P0 cos(w t + phi) without friction."""
    w = p.omega
    X = p.P0 / math.hypot(p.k - p.m * w * w, p.c * w)
    th = math.atan2(p.c * w, p.k - p.m * w * w)
    return X, X * math.cos(w * t + p.phi - th), -X * w * math.sin(w * t + p.phi - th)


def test_restarts_follow_the_closed_form_without_friction(fmu: OscillatorFMU2) -> None:
    # from the harmonic steady state at t0, a run of one period comes back to it; its Jacobian is
    # exp(A T); the mid stop reads the steady state there; x_max - x_min is twice the amplitude
    p = Oscillator.physical(m=1.3, k=2.0, zeta=0.05, P0=0.7, N=0.0, mu_s=0.3, mu_k=0.2, omega=1.1)
    T = p.period
    runs = fmu.restarts(p, SENS, ("x", "v") + JAC + OBS, ("mode", "transitions"))
    for t0 in (0.0, 0.37 * T, 0.91 * T):
        X, x0, v0 = harmonic_state(p, t0)
        t_mid = T * math.floor(t0 / T + 1.0)
        runs.run(x0, v0, t0, t0 + T, t_mid if t_mid < t0 + T - 1e-12 else None)
        r = runs.real
        _, xe, ve = harmonic_state(p, t0 + T)
        assert abs(r[0] - xe) <= 1e-12 * X and abs(r[1] - ve) <= 1e-12 * X * p.omega
        A = np.array([[0.0, 1.0], [-p.k / p.m, -p.c / p.m]])
        assert np.allclose(np.array(r[2:6]).reshape(2, 2), expm(A * T), rtol=0, atol=1e-12)
        assert abs((r[6] - r[7]) / 2.0 - X) <= 1e-12 * X and r[8] == 0.0
        assert runs.int[0] != 0                     # sliding at the end (the mode)
        if runs.mid is not None:
            _, xm, vm = harmonic_state(p, t_mid)
            assert abs(runs.mid[0] - xm) <= 1e-12 * X and abs(runs.mid[1] - vm) <= 1e-12 * X * p.omega
        else:
            assert t0 == 0.0


@pytest.mark.parametrize("settings", [SENS, Settings(scheme="exact", extra={"sensitivity": True, "h": 1e-3}),
                                      Settings(scheme="located", h=2e-3, extra={"frictionUpdates": 2})])
def test_restarts_equal_start_step_get_bit_for_bit(fmu: OscillatorFMU2, settings: Settings) -> None:
    # stick-slip: every value read equals the driver's start / step_to / get from the same state,
    # the FMU's clock from 0 and the excitation's phase that of t0 (phi + omega t0); and that run
    # is the motion started at t0 on the absolute clock
    p = Oscillator.physical(m=1.0, k=1.0, zeta=0.02, P0=1.0, N=1.2, mu_s=0.5, mu_k=0.3, omega=0.8)
    T = p.period
    reals = ("x", "v", "a", "F_friction") + (JAC if settings.extra.get("sensitivity") else ()) + \
        (OBS if settings.observe else ())
    runs = fmu.restarts(p, settings, reals, ("mode",))
    for x0, v0, t0 in ((0.3, -0.2, 0.25 * T), (-1.1, 0.0, 0.6 * T), (0.0, 0.9, 0.0)):
        t_mid, t_end = t0 + 0.5 * T, t0 + 2 * T
        runs.run(x0, v0, t0, t_end, t_mid)
        st = Settings(**{**settings.__dict__, "t_obs_start": 0.0, "t_obs_stop": t_end - t0})
        fmu.start(p.with_(x0=x0, v0=v0, phi=p.phi + p.omega * t0), st)
        fmu.step_to(t_mid - t0)
        mid = fmu.get(("x", "v"))
        fmu.step_to(t_end - t0)
        ref = fmu.get(reals + ("mode",))
        assert runs.mid == (mid["x"], mid["v"])
        assert runs.real == [ref[n] for n in reals] and runs.int == [ref["mode"]]
        assert fmu.time == t_end - t0
        fmu.start(p.with_(x0=x0, v0=v0), Settings(**{**settings.__dict__, "t_obs_start": t0, "t_obs_stop": t_end}),
                  t0=t0)
        fmu.step_to(t_end)
        absolute = fmu.get(("x", "v"))
        # exact: to 1e-12; a Bossak scheme's internal grid from t0 differs from it in rounding, far
        # inside its error (h^2)
        tol = 1e-12 if settings.scheme == "exact" else 1e-2 * settings.h ** 2
        assert abs(runs.real[0] - absolute["x"]) <= tol and abs(runs.real[1] - absolute["v"]) <= tol


def test_restarts_keep_one_template_state_per_settings(fmu: OscillatorFMU2) -> None:
    # the initialisation-mode state is made once per set of Integer / Boolean values and instance:
    # another Restarts with the same settings reuses it, other settings make their own, and runs
    # of the two interleaved give each its own results
    p = Oscillator.physical(m=1.0, k=1.0, zeta=0.02, P0=1.0, N=1.2, mu_s=0.5, mu_k=0.3, omega=0.8)
    fmu._restart_templates.clear()
    a, b = fmu.restarts(p, SENS, ("x", "v")), fmu.restarts(p, SENS, ("x",))
    c = fmu.restarts(p, Settings(scheme="located", h=1e-3), ("x", "v"))
    a.run(0.1, 0.2, 0.0, 3.0)
    first = a.real
    b.run(0.1, 0.2, 0.0, 3.0)
    assert b.real == first[:1] and len(fmu._restart_templates) == 1
    c.run(0.1, 0.2, 0.0, 3.0)
    assert len(fmu._restart_templates) == 2 and c.real != first
    a.run(0.1, 0.2, 0.0, 3.0)
    assert a.real == first
    # a Real extra is set by its own runs only: a template made with it is not another's (F_ext
    # 0.5 held in one, the start value 0 in the other, whichever made its template first)
    fmu._restart_templates.clear()
    d = fmu.restarts(p, Settings(scheme="exact", extra={"F_ext": 0.5}), ("x", "v"))
    e = fmu.restarts(p, Settings(scheme="exact"), ("x", "v"))
    d.run(0.1, 0.2, 0.0, 3.0)
    e.run(0.1, 0.2, 0.0, 3.0)
    fmu.start(p.with_(x0=0.1, v0=0.2), Settings(scheme="exact"))
    fmu.step_to(3.0)
    assert e.real == list(fmu.get(("x", "v")).values()) and d.real != e.real


def test_restarts_retarget_is_the_new_oscillator(fmu: OscillatorFMU2) -> None:
    p = Oscillator.physical(m=1.0, k=1.0, zeta=0.01, P0=1.0, N=0.1, mu_s=0.3, mu_k=0.2, omega=0.9)
    q = p.with_(omega=1.2, N=0.2)
    runs = fmu.restarts(p, SENS, ("x", "v") + OBS)
    runs.retarget(q)
    runs.run(0.4, -0.3, 0.1, 0.1 + q.period)
    fmu.start(q.with_(x0=0.4, v0=-0.3, phi=q.phi + q.omega * 0.1),
              Settings(**{**SENS.__dict__, "t_obs_start": 0.0, "t_obs_stop": (0.1 + q.period) - 0.1}))
    fmu.step_to((0.1 + q.period) - 0.1)
    assert runs.real == list(fmu.get(("x", "v") + OBS).values())


def test_restarts_refuse_with_a_sentence(fmu: OscillatorFMU2) -> None:
    p = Oscillator.physical(m=1.0, k=1.0, zeta=0.01, P0=1.0, N=0.1, mu_s=0.3, mu_k=0.2, omega=0.9)
    with pytest.raises(FMUError, match="scheme must be one of .*not 'rk4'"):
        fmu.restarts(p, Settings(scheme="rk4"))
    with pytest.raises(FMUError, match="unknown variable 'nonsense'"):
        fmu.restarts(p, Settings(scheme="exact", extra={"nonsense": 1}))
    with pytest.raises(FMUError, match="'mode' is not a Real variable"):
        fmu.restarts(p, Settings(scheme="exact"), ("mode",))
    with pytest.raises(FMUError, match="'x' is not an Integer variable"):
        fmu.restarts(p, Settings(scheme="exact"), ("v",), ("x",))
    with pytest.raises(ValueError, match="the observables x_max need Settings"):
        fmu.restarts(p, Settings(scheme="exact"), ("x_max",))
    runs = fmu.restarts(p, Settings(scheme="exact"))
    with pytest.raises(FMUError, match="x0"):            # the FMU's own check names the variable
        runs.run(math.inf, 0.0, 0.0, 1.0)


class _Orbit:
    def __init__(self, x: float, v: float, section: float) -> None:
        self.section_state, self.section = np.array([x, v]), section


def test_the_sweep_predictor_is_exact_for_a_cubic() -> None:
    # four points of a cubic branch in f (section state and phase): the prediction at a fifth
    # frequency is the cubic's value there (a quadratic predictor is off by the cubic term)
    def branch(f: float) -> tuple[float, float, float]:
        return 1.0 + 2.0 * f - 3.0 * f ** 2 + 5.0 * f ** 3, -0.5 + f ** 3, 0.2 + 0.01 * f - 0.02 * f ** 3

    b = None
    for f in (0.40, 0.43, 0.47, 0.50):
        x, v, ph = branch(f)
        b = _Branch(_Orbit(x, v, ph * 2.0), f, 2.0, b)
    assert b is not None and len(b.history) == 3
    (x, v), ph = b.guess(0.55)
    xr, vr, phr = branch(0.55)
    assert abs(x - xr) <= 1e-12 and abs(v - vr) <= 1e-12 and abs(ph - phr) <= 1e-12


def test_follower_from_a_periodic_state_reads_its_state_at_the_period_mark(fmu: OscillatorFMU2) -> None:
    # the guess is the converged section state: Newton takes no step; the state at t = T, the
    # amplitude and the multipliers are those of find_orbits' orbit (its sampled cycle)
    p = Oscillator.physical(m=1.0, k=1.0, zeta=0.01, P0=1.0, N=0.1, mu_s=0.3, mu_k=0.2, omega=0.9)
    o = find_orbits(p, fmu=fmu)[0]
    q = OrbitFollower(fmu)(p, o.section_state, o.section)
    assert q is not None and q.iterations == 0 and q.residual <= 1e-12
    assert abs(q.x0 - o.x0) <= 1e-10 * o.amplitude and abs(q.v0 - o.v0) <= 1e-10 * o.amplitude * p.omega
    assert abs(q.amplitude - o.amplitude) <= 1e-12 * o.amplitude
    assert np.allclose(q.multipliers, o.multipliers, rtol=0, atol=1e-9)


def test_find_orbits_keeps_every_orbit_and_each_stable_one_attracts(fmu: OscillatorFMU2) -> None:
    # a mirror pair of stable stick-slip orbits (lambda 0.5, mu_s sigma 0.6, chi 0.4: the transients
    # find one, most of them converge onto it again and are dropped before their cycle runs, the
    # symmetry image gives the other); each attracts a long transient from a state nearby
    p = Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.6, chi=0.4)
    orbits = find_orbits(p, fmu=fmu, samples=64)
    assert len(orbits) == 2 and all(o.converged and o.stable and o.residual <= 1e-12 for o in orbits)
    assert orbits[0].offset == pytest.approx(-orbits[1].offset, rel=1e-9) and abs(orbits[0].offset) > 0.1 * orbits[0].amplitude
    T = p.period
    for o in orbits:
        fmu.start(p.with_(x0=o.x0 + 1e-3 * o.amplitude, v0=o.v0), Settings(scheme="exact"))
        fmu.step_to(2000 * T)
        y = fmu.get(("x", "v"))
        assert abs(y["x"] - o.x0) <= 1e-9 * o.amplitude and abs(y["v"] - o.v0) <= 1e-9 * o.amplitude * p.omega
