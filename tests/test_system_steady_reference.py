"""The steady state by long runs of the event-driven reference (dryfriction.references.system_steady)
against the located scheme's FMU run long at small h on the two-mass Jenkins case: the FMU's
stroboscopic state and amplitudes converge to the reference's at order 2 in h; an unconverged long
run says so (and raises in strict mode), never a silent answer."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dryfriction.drivers.system import SystemFMU3
from dryfriction.references.system_steady import SteadyStateNotConverged, steady_state
from dryfriction.system import two_mass_jenkins

from refcache import RefCache

OMEGA = 1.8


@pytest.fixture(scope="module")
def reference(refcache: RefCache):
    """The event-driven reference's steady state (kept between runs: refcache.py)."""
    return refcache.call(steady_state, two_mass_jenkins(omega=OMEGA), periods=200, tol=1e-9)


@pytest.mark.slow
def test_reference_converges_and_fmu_agrees_at_second_order(reference) -> None:
    ref = reference
    assert ref.converged and ref.error_estimate < 1e-9 and ref.periods >= 200
    assert 0.8 < ref.rate < 0.95                                # the transient's decay per period
    np.testing.assert_allclose(ref.amplitude, 0.5 * (ref.x_max - ref.x_min), rtol=0, atol=0)
    T = 2 * math.pi / OMEGA
    P = 300
    state_err, amp_err = [], []
    for m in (400, 800, 1600):
        with SystemFMU3(two_mass_jenkins(omega=OMEGA, h=T / m)) as fmu:
            run = fmu.run(P * T, T, t_obs_start=(P - 1) * T)
        state_err.append(max(np.abs(run.x[-1] - ref.x0).max(), np.abs(run.v[-1] - ref.v0).max() / OMEGA))
        amp_err.append(np.max(np.abs(0.5 * (run.x_max - run.x_min) - ref.amplitude) / ref.amplitude))
    # second order in h: halving h divides the error by 4
    for errs in (state_err, amp_err):
        ratios = np.array(errs[:-1]) / np.array(errs[1:])
        assert np.all((3.6 < ratios) & (ratios < 4.4)), (errs, ratios)
    assert state_err[-1] < 2e-5 and amp_err[-1] < 3e-5


def test_unconverged_run_is_reported_not_silent() -> None:
    sys = two_mass_jenkins(omega=OMEGA)
    short = steady_state(sys, periods=6, max_periods=6, tol=1e-9, samples=256)
    assert not short.converged and short.periods == 6
    assert short.error_estimate > 1e-6 and short.change > 1e-6
    assert "NOT converged" in str(short)
    with pytest.raises(SteadyStateNotConverged, match="NOT converged after 6 periods"):
        steady_state(sys, periods=6, max_periods=6, tol=1e-9, samples=256, strict=True)
    with pytest.raises(ValueError, match="omega"):
        steady_state(sys.replace(omega=0.0))
    with pytest.raises(ValueError, match="tol"):
        steady_state(sys, tol=0.0)
