"""The oscillator's parameters in Python (dryfriction.params): physical and non-dimensional
constructions give the same FMU parameters, every bad value is named when an Oscillator is made,
the declared ranges of the model description are the ones Python checks, and a zero frequency or
a missing spring are values, not crashes."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dryfriction import model
from dryfriction.drivers.oscillator import OscillatorFMU2, Settings
from dryfriction.params import Oscillator

from helpers import ENGINEER


def test_physical_and_nondimensional_constructions_give_the_same_fmu_parameters(fmu: OscillatorFMU2) -> None:
    phys = Oscillator.physical(**ENGINEER, f=10.0, x0=0.001, v0=-0.02)
    nd = phys.to_nondimensional()
    back = Oscillator.from_nondimensional(**nd, m=phys.m, k=phys.k, P0=phys.P0, mu_s=phys.mu_s)
    names = list(phys.as_dict())
    read = []
    for p in (phys, back):
        fmu.start(p, Settings(h=0.0))
        read.append(fmu.get(names))
    for n in names:
        assert read[0][n] == pytest.approx(read[1][n], rel=1e-14, abs=1e-15), n
    assert read[0]["chi"] == pytest.approx(0.2 / 0.3, rel=1e-15)
    assert read[0]["c"] == pytest.approx(2 * 0.003 * math.sqrt(2000 * 0.5), rel=1e-15)
    assert read[0]["omega"] == pytest.approx(2 * math.pi * 10, rel=1e-15)
    # the other way: the paper's numbers survive a round trip through physical units
    nd2 = Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.6, chi=0.3, zeta=0.05, z0=1.2, dz0=-0.4)
    rt = Oscillator.physical(m=nd2.m, k=nd2.k, c=nd2.c, P0=nd2.P0, omega=nd2.omega, N=nd2.N, mu_s=nd2.mu_s,
                             mu_k=nd2.mu_k, x0=nd2.x0, v0=nd2.v0).to_nondimensional()
    for key, value in dict(lam=0.5, mu_s_sigma=0.6, chi=0.3, zeta=0.05, z0=1.2, dz0=-0.4).items():
        assert rt[key] == pytest.approx(value, rel=1e-14), key
    assert Oscillator.physical(**ENGINEER, omega=2 * math.pi * 10.0) == Oscillator.physical(**ENGINEER, f=10.0)


@pytest.mark.parametrize("kwargs, words", [
    (dict(m=-0.5), "invalid value -0.5 for m (mass); valid range: 1e-100 to 1e+100 kg"),
    (dict(m=0.0), "for m (mass); valid range: 1e-100 to 1e+100 kg"),
    (dict(m=True), "m must be a real number"),
    (dict(chi="0.3"), "chi must be a real number, not str '0.3'"),
    (dict(k=-1.0), "for k (spring stiffness); valid range: 1e-100 to 1e+100 N/m (or 0: no spring)"),
    (dict(c=-0.1), "for c (viscous damping coefficient); valid range: >= 0"),
    (dict(omega=-1.0), "for omega (excitation angular frequency); valid range: >= 0"),
    (dict(N=-2.0), "for N (normal force pressing the block on its support); valid range: >= 0"),
    (dict(mu_s=-0.1), "for mu_s (static friction coefficient); valid range: >= 0"),
    (dict(chi=-0.1), "for chi "),
    (dict(P0=math.inf), "for P0"),
    (dict(x0=math.nan), "for x0"),
    (dict(v0=None), "v0 must be a real number"),
    (dict(phi=[1.0]), "phi must be a real number"),
])
def test_every_bad_value_is_named_at_construction(kwargs: dict[str, object], words: str) -> None:
    with pytest.raises(ValueError) as e:
        Oscillator(**kwargs)  # type: ignore[arg-type]
    assert words in str(e.value), str(e.value)


@pytest.mark.parametrize("change, words", [
    (dict(zeta=-0.1), "zeta (damping ratio); valid range: >= 0"),
    (dict(mu_k=-0.2), "mu_k (kinetic friction coefficient); valid range: >= 0"),
    (dict(f=-5.0), "f (excitation frequency, Hz); valid range: >= 0"),
    (dict(m=0.0), "for m (mass); valid range: 1e-100 to 1e+100 kg"),
    (dict(k="2000"), "k (stiffness, N/m) must be a real number"),
    (dict(c=0.1), "c or as zeta, not both"),
    (dict(omega=3.0), "f (Hz) or omega (rad/s), exactly one"),
    (dict(mu_s=0.0), "mu_k with mu_s = 0"),
])
def test_physical_errors_name_the_field(change: dict[str, object], words: str) -> None:
    kw: dict[str, object] = {**ENGINEER, "f": 10.0, **change}
    with pytest.raises(ValueError) as e:
        Oscillator.physical(**kw)  # type: ignore[arg-type]
    assert words in str(e.value), str(e.value)


def test_zero_frequency_and_no_spring_are_values_not_crashes(fmu: OscillatorFMU2) -> None:
    p = Oscillator(omega=0.0)
    assert p.period == math.inf and p.f_hz == 0.0
    q = Oscillator(k=0.0)
    assert q.lam == math.inf and q.zeta == 0.0
    traj = fmu.trajectory(p.with_(x0=0.05), [0.0, 0.1, 0.2])   # Settings().h with omega = 0: the FMU derives it
    assert np.all(np.isfinite(traj["x"]))


@pytest.mark.parametrize("name,value,valid", [
    ("m", 0.0, "in [1e-100, 1e+100]"), ("k", -1.0, "in [0, 1e+100]"), ("k", 1e101, "in [0, 1e+100]"),
    ("alpha", 0.1, "in [-0.333333, 0]"), ("alpha", -0.34, "in [-0.3"),
    ("h", math.nan, "finite"), ("P0", math.inf, "finite"), ("frictionUpdates", 101, "in [0, 100]"),
    ("scheme", "fast", "one of paper, consistent, located, exact"), ("scheme", 5, "one of paper"),
])
def test_python_values_are_checked_against_the_declared_range(name: str, value: object, valid: str) -> None:
    md = model.default()
    with pytest.raises(ValueError, match=f"invalid value .* for variable {name}; valid range: ") as err:
        md.check(name, value)
    assert valid in str(err.value), str(err.value)


@pytest.mark.parametrize("name,value", [("m", 1e-100), ("m", 1e100), ("k", 1e100), ("alpha", -1 / 3),
                                        ("alpha", 0.0), ("frictionUpdates", 0),
                                        ("scheme", "paper"), ("scheme", 3), ("observe", True), ("x0", -5.0)])
def test_valid_python_values_pass(name: str, value: object) -> None:
    model.default().check(name, value)
