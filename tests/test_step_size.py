"""The internal step h: the default (h = 0, derived from the dynamics) is as accurate as T/1000, the
rule that derives it, the range a given h must be in, and the warning (with the step to choose)
for an h that does not resolve the dynamics; the exact scheme never steps by h."""

from __future__ import annotations

import math

import pytest

from dryfriction import DryFrictionWarning
from dryfriction.drivers.oscillator import OscillatorFMU2, Settings
from dryfriction.params import Oscillator


def _amplitude(fmu: OscillatorFMU2, p: Oscillator, h: float, scheme: str, periods: int = 100) -> float:
    o = fmu.observables(p, periods * p.period, (periods - 1) * p.period, settings=Settings(h=h, scheme=scheme))
    return 0.5 * (o["x_max"] - o["x_min"])


@pytest.mark.parametrize("f_n", [0.1, 10.0, 1591.5494309189535, 1e4])
@pytest.mark.parametrize("lam, mu_s_sigma, zeta", [(0.9, 0.0, 0.0), (0.9, 0.2, 0.0), (2.0, 0.3, 0.01), (0.3, 0.5, 0.05)])
def test_default_step_is_as_accurate_as_T_over_1000(fmu: OscillatorFMU2, f_n: float, lam: float, mu_s_sigma: float,
                                                     zeta: float) -> None:
    """h = 0 (the default): one doStep over 100 periods with the in-FMU observables is at least as
    accurate as a run at h = T/1000 (T the excitation period), on natural frequencies from 0.1 Hz
    to 10 kHz (1.6 kHz: the stiff example m = 0.01 kg, k = 1e6 N/m), against the exact scheme."""
    m = 0.01
    k = m * (2 * math.pi * f_n) ** 2
    nd = Oscillator.from_nondimensional(lam=lam, mu_s_sigma=mu_s_sigma, chi=0.7, zeta=zeta, m=m, k=k, P0=1.0,
                                        mu_s=0.4)
    exact = _amplitude(fmu, nd, 0.0, "exact")
    default = _amplitude(fmu, nd, 0.0, "located")
    h_used = fmu.get(["h_used"])["h_used"]
    t1000 = _amplitude(fmu, nd, nd.period / 1000, "located")
    err_default, err_t1000 = abs(default - exact) / exact, abs(t1000 - exact) / exact
    assert h_used == pytest.approx(2 * math.pi / max(nd.w0, nd.omega, nd.c / nd.m) / 1000, rel=1e-14)
    assert err_default <= 1.02 * err_t1000 + 1e-9, (err_default, err_t1000)
    assert err_default < 0.01


def test_the_old_fixed_step_on_a_stiff_oscillator_warns_and_says_what_to_choose(fmu: OscillatorFMU2) -> None:
    """m = 0.01 kg, k = 1e6 N/m (1.6 kHz) at 0.9 of its natural frequency: h = 1 ms (the former
    default) is refused by nothing but logs a warning naming the step to choose; h = 0 is within
    1 % of the exact amplitude after 100 periods in one doStep."""
    w0 = math.sqrt(1e6 / 0.01)
    p = Oscillator(m=0.01, k=1e6, c=0.0, P0=1.0, omega=0.9 * w0, N=0.0, mu_s=0.0, chi=1.0)
    mark = len(fmu.messages)
    with pytest.warns(DryFrictionWarning, match=r"Choose h <= 6\.28319e-07 s"):  # it reaches the user
        bad = _amplitude(fmu, p, 1e-3, "located")
    warnings = [m for s, c, m in fmu.messages[mark:] if c == "logStatusWarning"]
    assert len(warnings) == 1 and "Choose h <= 6.28319e-07 s" in warnings[0], warnings
    exact = _amplitude(fmu, p, 0.0, "exact")
    assert abs(bad - exact) / exact > 0.5           # the silent failure of the issue, now with a warning
    mark = len(fmu.messages)
    good = _amplitude(fmu, p, 0.0, "located")
    assert abs(good - exact) / exact < 0.01
    assert not [m for s, c, m in fmu.messages[mark:] if c == "logStatusWarning"]


@pytest.mark.parametrize("params, expected", [
    (dict(m=2.0, k=0.0, c=0.0, omega=3.0), 2 * math.pi / 3.0 / 1000),             # no spring: excitation
    (dict(m=2.0, k=50.0, c=0.0, omega=0.0), 2 * math.pi * math.sqrt(2 / 50) / 1000),  # no excitation: natural
    (dict(m=2.0, k=0.0, c=4.0, omega=0.0), 2 * math.pi * 2.0 / 4.0 / 1000),         # damping only: 2 pi m / c
    (dict(m=1.0, k=1.0, c=6.0, omega=0.5), 2 * math.pi / 6.0 / 1000),              # over-damped: c/m fastest
    (dict(m=2.0, k=0.0, c=0.0, omega=0.0), 1e-3),                                  # nothing: 1 ms
])
def test_derived_step_rule(fmu: OscillatorFMU2, params: dict[str, float], expected: float) -> None:
    fmu.start(Oscillator(**params), Settings(h=0.0))
    assert fmu.get(["h_used"])["h_used"] == pytest.approx(expected, rel=1e-14)
    fmu.step_to(0.05)                                # and it runs
    fmu.start(Oscillator(**params), Settings(h=1e-4))
    assert fmu.get(["h_used"])["h_used"] == 1e-4     # a user-set h is used as it is


@pytest.mark.parametrize("h, words", [(-1e-3, "valid range: 0 (derived from the dynamics) or > 0"),
                                      (1e-310, "a normal number"), (math.inf, "finite")])
def test_bad_h_is_refused_with_its_range(fmu: OscillatorFMU2, h: float, words: str) -> None:
    from dryfriction.fmi.fmi2 import FMUError

    with pytest.raises(FMUError, match="variable h") as e:
        fmu.start(Oscillator(), Settings(h=h))
    assert words in str(e.value)


def test_exact_scheme_with_a_coarse_h_does_not_warn(fmu: OscillatorFMU2) -> None:
    mark = len(fmu.messages)
    fmu.start(Oscillator(), Settings(h=10.0, scheme="exact"))
    assert not [m for s, c, m in fmu.messages[mark:] if c == "logStatusWarning"]
