"""Scenes pay only for what they use.

Fast paths inside the FMU give the same numbers as the general path (fastPaths = false), the
observables computed inside the FMU agree with the exact solution, and the 'effects' parameter
says what a run simulates. (The inputs F_ext, N_ext: test_inputs.py.)"""

from __future__ import annotations

import numpy as np
import pytest

from dryfriction.drivers import scenes
from dryfriction.references.exact import solve_exact
from dryfriction.drivers.oscillator import OscillatorFMU2, Settings
from dryfriction.params import Oscillator

from helpers import OUT


FAST_PATH_CASES = {
    "no friction (mu_s = 0)": Oscillator.from_nondimensional(lam=0.7, mu_s_sigma=0.4, chi=0.7, zeta=0.05).with_(mu_s=0.0),
    "no friction (N = 0)": Oscillator.from_nondimensional(lam=0.7, mu_s_sigma=0.4, chi=0.7).with_(N=0.0, v0=0.1),
    "equal coefficients (chi = 1)": Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.4, chi=1.0),
    "no damping (c = 0)": Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.4, chi=0.7),
    "everything on": Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.4, chi=0.7, zeta=0.1),
}


@pytest.mark.parametrize("scheme", ["located", "consistent", "paper"])
@pytest.mark.parametrize("case", list(FAST_PATH_CASES))
def test_fast_path_is_bit_identical_to_general_path(fmu: OscillatorFMU2, case: str, scheme: str) -> None:
    p = FAST_PATH_CASES[case]
    rng = np.random.default_rng(7)
    t = np.r_[0.0, np.cumsum(rng.uniform(0.2, 2.0, 400) * p.period / 300)]  # off-grid points too
    fast = fmu.trajectory(p, t, Settings(h=p.period / 300, scheme=scheme, fastPaths=True), OUT)
    general = fmu.trajectory(p, t, Settings(h=p.period / 300, scheme=scheme, fastPaths=False), OUT)
    for k in OUT:
        assert np.array_equal(fast[k], general[k]), (case, scheme, k, np.max(np.abs(fast[k] - general[k])))


def effects_of(fmu: OscillatorFMU2, p: Oscillator, **settings) -> set[str]:
    extra = settings.pop("extra", {})
    fmu.start(p, Settings(extra=extra, **settings))
    return set(fmu.effects())


def test_effects_name_what_is_simulated(fmu: OscillatorFMU2) -> None:
    base = Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.4, chi=0.7)
    assert effects_of(fmu, base) == {"friction", "coefficientUpdate"}
    assert effects_of(fmu, base.with_(chi=1.0)) == {"friction"}
    assert effects_of(fmu, base.with_(N=0.0)) == set()
    assert effects_of(fmu, base.with_(mu_s=0.0)) == set()
    assert effects_of(fmu, base.with_(c=0.5)) == {"friction", "coefficientUpdate", "damping"}
    assert effects_of(fmu, base, observe=True) == {"friction", "coefficientUpdate", "observables"}
    assert effects_of(fmu, base.with_(N=0.0), extra={"N_ext": 1.0}) == {"friction", "coefficientUpdate", "normalInput"}
    assert effects_of(fmu, base, extra={"F_ext": 0.0}) == {"friction", "coefficientUpdate", "forceInput"}


def test_observables_do_not_change_the_motion(fmu: OscillatorFMU2) -> None:
    p = Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.4, chi=0.7)
    t = np.linspace(0, 5 * p.period, 101)
    on = fmu.trajectory(p, t, Settings(observe=True, t_obs_start=p.period), OUT)
    off = fmu.trajectory(p, t, Settings(observe=False), OUT)
    for k in OUT:
        assert np.array_equal(on[k], off[k])
    fmu.start(p, Settings(observe=False))
    fmu.step_to(3 * p.period)
    got = fmu.get(["x_max", "x_min", "stick_fraction", "transitions", "E_friction"])
    assert got.pop("transitions") == -1  # not computed: NaN and -1, never a number that looks like a result
    assert all(np.isnan(v) for v in got.values()), got


@pytest.mark.parametrize("chi", [0.3, 0.7, 2.0])
def test_observables_match_the_exact_solution(fmu: OscillatorFMU2, chi: float) -> None:
    """x_max, x_min, stick share, switch count and friction work over periods 5..8."""
    p = Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.4 if chi < 1 else 0.2, chi=chi)
    T = p.period
    w0, w1 = 5 * T, 8 * T
    o = fmu.observables(p, w1, w0, settings=Settings(h=T / 4000))
    ex = solve_exact(p, w1)
    t = np.linspace(w0, w1, 200001)
    x, v, _, mode = ex.evaluate(t)
    amp = np.ptp(x)
    assert abs(o["x_max"] - x.max()) < 1e-5 * amp
    assert abs(o["x_min"] - x.min()) < 1e-5 * amp
    stuck = sum(max(0.0, min(s.t1, w1) - max(s.t0, w0)) for s in ex.segments if s.mode == 0)
    assert abs(o["stick_fraction"] - stuck / (w1 - w0)) < 1e-4
    sw = [s for s in ex.segments[1:] if w0 < s.t0 <= w1]
    assert o["transitions"] == len(sw)
    slip = np.sum(np.abs(np.diff(x)) * (mode[1:] != 0))
    assert abs(o["E_friction"] - p.mu_k * p.N * slip) < 1e-4 * p.mu_k * p.N * slip


def test_sweep_and_stiction_scenes(fmu: OscillatorFMU2) -> None:
    p = Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.4, chi=0.7)
    sw = scenes.run_sweep_point(fmu, p, transient_periods=10, settings=Settings(h=p.period / 2000))
    traj = scenes.run_validation(fmu, p, 11, samples_per_period=2000, settings=Settings(h=p.period / 2000))
    late = traj["t"] >= 10 * p.period - 1e-12
    assert abs(sw["amplitude"] - np.ptp(traj["x"][late]) / 2) < 1e-6 * sw["amplitude"]
    st = scenes.run_stiction(fmu, p, period_index=10, settings=Settings(h=p.period / 2000))
    ex = solve_exact(p, 10 * p.period)
    w0, w1 = 9 * p.period, 10 * p.period
    stuck = sum(max(0.0, min(s.t1, w1) - max(s.t0, w0)) for s in ex.segments if s.mode == 0)
    assert abs(st["stick_percent"] - 100 * stuck / p.period) < 0.05


def test_coupled_scene_feeds_inputs(fmu: OscillatorFMU2) -> None:
    """A master that adds N_ext = N while the block slides forward: friction doubles then."""
    p = Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.2, chi=0.7)
    res = scenes.run_coupled(fmu, p, 3 * p.period, p.period / 200,
                             lambda t, y: {"N_ext": p.N if y["v"] > 0 else 0.0})
    fwd = res["mode"] == 1
    back = res["mode"] == -1
    assert np.any(fwd) and np.any(back)
    # zero-order hold: the input chosen at a point acts over the next step, so the friction is
    # mu_k N or mu_k (N + N_ext) = 2 mu_k N, opposed to the motion
    unit = p.mu_k * p.N
    assert np.isin(np.round(res["F_friction"][fwd] / unit, 12), [-1.0, -2.0]).all()
    assert np.isin(np.round(res["F_friction"][back] / unit, 12), [1.0, 2.0]).all()
    assert np.mean(np.isclose(res["F_friction"][fwd], -2 * unit)) > 0.9
    assert np.mean(np.isclose(res["F_friction"][back], unit)) > 0.9


def test_unknown_scene_is_a_clear_error() -> None:
    with pytest.raises(ValueError, match="unknown scene 'nope'; choose one of: validation, sweep, stiction, coupled"):
        scenes.get_scene("nope")
