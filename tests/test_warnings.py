"""The FMUs' warnings in Python: an FMU's sentence is a DryFrictionWarning (from the FMI 2.0 and
3.0 oscillators, the chain and Dask workers), a resolved step warns nothing, and the error filter
turns it into an exception. (On the command line: test_cli_errors.py.)"""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np
import pytest

from dryfriction import DryFrictionWarning, Oscillator
from dryfriction.drivers.oscillator import OscillatorFMU2, Settings


# the default oscillator (m = 1 kg, k = 100 N/m, omega = 5 rad/s): its shortest period is the natural one
T_NAT = 2 * math.pi / 10.0
COARSE = Settings(h=T_NAT / 2)  # two internal steps per natural period: far too coarse


def _fmu_messages(caught: list[warnings.WarningMessage]) -> list[str]:
    return [str(w.message) for w in caught if issubclass(w.category, DryFrictionWarning)]


def test_a_coarse_step_is_a_python_warning_with_the_fmus_sentence(fmu: OscillatorFMU2) -> None:
    p = Oscillator()
    with pytest.warns(DryFrictionWarning) as caught:
        fmu.start(p, COARSE)
    said = _fmu_messages(list(caught))
    assert len(said) == 1, said
    # the FMU's own sentence, with the step to choose: 1/1000 of the natural period
    assert "takes only 2 internal steps per 0.628319 s" in said[0]
    assert f"Choose h <= {T_NAT / 1000:.6g} s" in said[0]


def test_a_resolved_step_warns_nothing(fmu: OscillatorFMU2) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error", DryFrictionWarning)
        fmu.start(Oscillator(), Settings(h=T_NAT / 2000))
        fmu.step_to(1.0)


def test_the_error_filter_turns_the_warning_into_an_exception(fmu: OscillatorFMU2) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error", DryFrictionWarning)
        with pytest.raises(DryFrictionWarning, match="internal steps per"):
            fmu.start(Oscillator(), COARSE)


def test_fmi3_and_chain_warnings_are_the_same_category(chain_fmu2: Path, chain_fmu3: Path) -> None:
    from dryfriction.drivers.chain import ChainFMU3, ChainFMU2
    from dryfriction.drivers.oscillator3 import OscillatorFMU3

    with pytest.warns(DryFrictionWarning, match="internal steps per 0.628319 s"):
        OscillatorFMU3({"h": T_NAT / 2}).close()
    for make in (lambda: ChainFMU3(2, fmu_path=chain_fmu3), lambda: ChainFMU2(fmu_path=chain_fmu2)):
        with pytest.warns(DryFrictionWarning, match="internal steps per"):
            with make() as chain:
                r = chain.run(0.05, 0.01, {"k": 1e5, "h": 1e-3})
        assert np.all(np.isfinite(r.x))


@pytest.mark.slow
def test_warnings_on_dask_workers_reach_the_client(fmu_path: Path) -> None:
    from dryfriction.analysis.response import frequency_response

    p = Oscillator.physical(m=1, k=100, P0=1, f=1, N=0.5, mu_s=0.3)
    with pytest.warns(DryFrictionWarning) as caught:
        ds = frequency_response(p, [0.8, 1.2], scheme="located", h=T_NAT / 2, min_periods=4, max_periods=8,
                                workers=1, fmu_path=fmu_path)
    said = _fmu_messages(list(caught))
    assert said and all("internal steps per" in m for m in said)
    assert len(said) == len(set(said))  # each sentence once
    assert np.all(np.isfinite(ds["amplitude_m"].values))
