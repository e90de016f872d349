"""The orbit method at every size of oscillator: m and k from 1e-12 to 1e6 (kg, N/m) with the
non-dimensional parameters held fixed give the same non-dimensional orbit (Den Hartog's exact
amplitude where it holds, the exact piecewise solution of dryfriction.references.exact elsewhere); a MEMS-sized
block (m down to 1e-12 kg, lambda down to 1.4e-6: slides far shorter than the samples of a cycle)
has its orbit wherever the transient method converges, periodic under the exact solution; values no
computation can honour are refused with the parameter and its valid range."""

from __future__ import annotations

import itertools
import math
import re
from pathlib import Path

import numpy as np
import pytest

from dryfriction import Oscillator
from dryfriction.cli import main
from dryfriction.references.exact import solve_exact
from dryfriction.drivers.oscillator import OscillatorFMU2
from dryfriction.analysis.orbits import Orbit, find_orbits
from dryfriction.params import SCALE_LIMIT
from dryfriction.analysis.response import frequency_response, steady_state
from dryfriction.references.steady import den_hartog_amplitude

SIZES = [1e-12, 1e-6, 1.0, 1e6]
ALL_SIZES = [1e-12, 1e-9, 1e-6, 1e-3, 1.0, 1e3, 1e6]


def exact_cycle(p: Oscillator, o: Orbit) -> tuple[float, float, float]:
    """(x, v) after one period of the exact piecewise solution (dryfriction.references.exact, Python, independent
    of the FMU) from the orbit's state at t = 0, and its amplitude: every turning point of x is a stop
    (v = 0 ends a slide), so x's extremes are among the segments' start states and the end state."""
    sol = solve_exact(p.with_(x0=o.x0, v0=o.v0), o.period * p.period)
    x, v, _, _ = sol.evaluate(np.array([o.period * p.period]))
    xs = [s.x0 for s in sol.segments] + [float(x[0])]
    return float(x[0]), float(v[0]), (max(xs) - min(xs)) / 2.0


def nd(m: float, k: float, **kw: float) -> Oscillator:
    return Oscillator.from_nondimensional(m=m, k=k, P0=3.0, mu_s=0.3, **kw)


@pytest.mark.parametrize("m, k", list(itertools.product(SIZES, SIZES)))
def test_den_hartog_at_every_size(fmu: OscillatorFMU2, m: float, k: float) -> None:
    """zeta 0, mu_s = mu_k, lambda 1.7, mu_s sigma 0.2 (no stops): k X / P0 is Den Hartog's exact
    amplitude within 1e-10 at every m and k (seen within 2e-14)."""
    p = nd(m, k, lam=1.7, mu_s_sigma=0.2, chi=1.0)
    (o,) = find_orbits(p, fmu=fmu)
    A = den_hartog_amplitude(p) * p.k / p.P0
    assert o.converged and o.stable and o.events["stops"] == 0
    assert abs(o.amplitude * p.k / p.P0 - A) <= 1e-10 * A, (m, k, o.amplitude * p.k / p.P0, A)


def stick_slip_case(m: float, k: float) -> Oscillator:
    return nd(m, k, lam=0.5, mu_s_sigma=0.6, chi=0.7, zeta=0.02)


def unit_stick_slip(fmu: OscillatorFMU2) -> Orbit:
    (o,) = find_orbits(stick_slip_case(1.0, 1.0), fmu=fmu)
    return o


@pytest.mark.parametrize("m, k", list(itertools.product(SIZES, SIZES)))
def test_stick_slip_at_every_size(fmu: OscillatorFMU2, m: float, k: float) -> None:
    """lambda 0.5, mu_s sigma 0.6, chi 0.7, zeta 0.02 (two stops a cycle): the non-dimensional state
    and amplitude are the unit oscillator's within 1e-10 and the multipliers within 1e-10; the exact
    solution from the orbit's state returns to it within 1e-12 of the amplitude after one period, its
    amplitude the orbit's within 1e-12."""
    ref = unit_stick_slip(fmu)
    p = stick_slip_case(m, k)
    (o,) = find_orbits(p, fmu=fmu)
    assert o.converged and o.stable and o.stick_fraction > 0
    assert abs(o.amplitude * p.k / p.P0 - ref.amplitude * 1.0 / 3.0) <= 1e-10 * ref.amplitude / 3.0
    assert abs(o.z0 - ref.z0) <= 1e-10 and abs(o.zdot0 - ref.zdot0) <= 1e-10, (o.z0, ref.z0, o.zdot0, ref.zdot0)
    assert np.max(np.abs(np.sort_complex(o.multipliers) - np.sort_complex(ref.multipliers))) <= 1e-10
    x, v, amp = exact_cycle(p, o)
    assert abs(x - o.x0) <= 1e-12 * o.amplitude and abs(v - o.v0) <= 1e-12 * o.amplitude * p.omega
    assert abs(amp - o.amplitude) <= 1e-12 * o.amplitude


@pytest.mark.slow
def test_the_whole_grid_agrees_with_the_transient_method(fmu: OscillatorFMU2) -> None:
    """m and k over 1e-12 ... 1e6 in decades of 3 (49 oscillators), the stick-slip case: the same
    non-dimensional amplitude within 1e-10 everywhere, equal to the transient method's (tol 1e-6)
    wherever it converges (all 49: seen within 4.2e-15; the grid within 2.3e-15 of the unit oscillator)."""
    ref = unit_stick_slip(fmu).amplitude / 3.0
    for m, k in itertools.product(ALL_SIZES, ALL_SIZES):
        p = stick_slip_case(m, k)
        (o,) = find_orbits(p, fmu=fmu)
        a = o.amplitude * p.k / p.P0
        assert abs(a - ref) <= 1e-10 * ref, (m, k, a, ref)
        s = steady_state(fmu, p, tol=1e-6)
        assert s.converged, (m, k)
        assert abs(s.amplitude * p.k / p.P0 - a) <= 1e-6 * a, (m, k, s.amplitude * p.k / p.P0, a)


MEMS = dict(k=2000.0, zeta=0.003, P0=10.0, N=20.0, mu_s=0.3, mu_k=0.2)


@pytest.mark.parametrize("m", [1e-12, 1e-9, 1e-6, 1e-3, 1.0, 1e3, 1e6])
def test_a_small_block_has_its_orbit(fmu_path: Path, m: float) -> None:
    """The block of the five lines of Python with m from 1e-12 to 1e6 kg at 5, 10, 15 Hz (lambda 1.4e-6 to 1400): the
    orbit method finds a stable orbit wherever the transient method converges (also from 1e-9 kg
    down, where the slides last a few 1e-7 of a period, between the cycle's samples), one of them at the transient's amplitude within the transient's tolerance 1e-3
    (seen 4e-11 to 2e-6), and every stable orbit returns to itself under the exact solution within
    1e-11 of its amplitude (plus 1e-15 static deflections, the reference's rounding: at 1e6 kg the
    motion is 1.6e-6 of the static deflection), with the exact solution's amplitude."""
    p = Oscillator.physical(m=m, f=10.0, **MEMS)
    f = [5.0, 10.0, 15.0]
    ds = frequency_response(p, f, fmu_path=fmu_path)
    tr = frequency_response(p, f, method="transient", fmu_path=fmu_path)
    for i, fi in enumerate(f):
        st = ds["stable"].values[i]
        amps = ds["amplitude_m"].values[i][st]
        if tr["converged"].values[i]:
            assert ds["converged"].values[i] and amps.size, (m, fi)
            a = float(tr["amplitude_m"].values[i])
            assert np.min(np.abs(amps - a)) <= 1e-3 * a, (m, fi, amps, a)
        q = p.with_(omega=2 * math.pi * fi)
        for j in np.flatnonzero(st):
            o = Orbit(period=int(ds["period"].values[i, j]), x0=float(ds["x0_m"].values[i, j]),
                      v0=float(ds["v0_m_per_s"].values[i, j]), z0=math.nan, zdot0=math.nan,
                      multipliers=np.zeros(2), stable=True, residual=0.0, amplitude=float(ds["amplitude_m"].values[i, j]),
                      offset=0.0, stick_fraction=0.0, events={}, converged=True)
            x, v, amp = exact_cycle(q, o)
            tol = 1e-11 * o.amplitude + 1e-15 * q.P0 / q.k     # the reference rounds in static deflections
            assert abs(x - o.x0) <= tol and abs(v - o.v0) <= tol * max(q.w0, q.omega), (m, fi, j, x - o.x0)
            assert abs(amp - o.amplitude) <= tol, (m, fi, amp, o.amplitude)
    if m <= 1e-9:
        assert bool(ds["converged"].all())    # the transient method does not converge at 1e-12 kg


@pytest.mark.parametrize("m, k", [(1 / SCALE_LIMIT, 1 / SCALE_LIMIT), (SCALE_LIMIT, SCALE_LIMIT),
                                  (1 / SCALE_LIMIT, SCALE_LIMIT), (SCALE_LIMIT, 1 / SCALE_LIMIT)])
def test_the_edges_of_the_valid_range(fmu: OscillatorFMU2, m: float, k: float) -> None:
    """m and k at 1e-100 and 1e100 (w0 from 1e-100 to 1e100): the unit oscillator's orbit within 1e-10."""
    ref = unit_stick_slip(fmu)
    p = stick_slip_case(m, k)
    (o,) = find_orbits(p, fmu=fmu)
    assert abs(o.z0 - ref.z0) <= 1e-10 and abs(o.zdot0 - ref.zdot0) <= 1e-10, (m, k, o.z0, ref.z0)
    assert abs(o.mu_max - ref.mu_max) <= 1e-10


@pytest.mark.parametrize("field, value, unit", [("m", 1e-300, "kg"), ("m", 1e101, "kg"), ("k", 1e300, "N/m"),
                                                ("k", 1e-101, "N/m")])
def test_sizes_no_computation_honours_are_refused(field: str, value: float, unit: str,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    """m = 1e-300 or k = 1e300 (the issue's: the two methods disagreed, the FMU's Jacobian overflows
    or a run silently loses the motion): one sentence naming the field and the valid range, from the
    API and from the command line (exit status 2, one line)."""
    rng = f"valid range: 1e-100 to 1e+100 {unit}"
    with pytest.raises(ValueError, match=rf"invalid value {re.escape(repr(value))} for {field} \(.*\); {re.escape(rng)}"):
        Oscillator(**{field: value})
    with pytest.raises(ValueError, match=re.escape(rng)):
        Oscillator.physical(**{**dict(m=1.0, k=2000.0, P0=10.0, N=20.0, mu_s=0.3, f=10.0), field: value})
    args = {"m": "1", "k": "2000", field: repr(value)}
    for argv in (["orbit", "--m", args["m"], "--k", args["k"], "--P0", "10", "--N", "20", "--mu-s", "0.3", "--f", "10"],
                 ["response", "--m", args["m"], "--k", args["k"], "--P0", "10", "--N", "20", "--mu-s", "0.3",
                  "--f-start", "5", "--f-stop", "15", "--num", "3"]):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("dryfriction: error: ") and rng in err[0], err
        assert f"for {field} (" in err[0]
    assert Oscillator(k=0.0).k == 0.0            # no spring stays valid


@pytest.mark.parametrize("k, tol", [(1e-6, 1e-6), (1e-9, 1e-3)])
def test_a_spring_too_weak_to_resolve_is_the_free_mass(fmu_path: Path, k: float, tol: float) -> None:
    """m 0.5 kg with k 1e-6 or 1e-9 N/m at 5 to 15 Hz (lambda 4e4 to 4e6): the orbits are a family
    shifted in x as without a spring (the spring's pull, 4e-8 of the offset a period, is below the
    FMU's rounding of the motion: it computes positions in static deflections, 1e7 and 1e10 m): one
    orbit per frequency, neutral, converged, the amplitude of the free mass's (k = 0) within 1e-6 at
    1e-6 N/m (seen 1e-9) and 1e-3 at 1e-9 N/m (seen 3e-5; not 1, 3 and 7 'unstable' orbits without a
    steady state at 1e-9 N/m)."""
    f = [5.0, 10.0, 15.0]
    free = frequency_response(Oscillator.physical(m=0.5, k=0.0, c=1e-3, P0=10, f=10, N=20, mu_s=0.3, mu_k=0.2), f,
                              fmu_path=fmu_path)
    ds = frequency_response(Oscillator.physical(m=0.5, k=k, c=1e-3, P0=10, f=10, N=20, mu_s=0.3, mu_k=0.2), f,
                            fmu_path=fmu_path)
    assert list(ds["n_orbits"].values) == [1, 1, 1] and bool(ds["converged"].all())
    assert ds["neutral"].values[:, 0].all() and not ds["stable"].values.any()
    a, a0 = ds["amplitude_m"].values[:, 0], free["amplitude_m"].values[:, 0]
    assert np.all(np.abs(a - a0) <= tol * a0), (a, a0)
