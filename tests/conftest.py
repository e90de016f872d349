"""Shared fixtures: one FMU instance per test session, reused (reset) by every test."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from dryfriction.chain import default_chain_fmu, default_chain_fmu3
from dryfriction.fmu import OscillatorFMU, default_fmu_path
from dryfriction.locate import FMUFileError

# Every FMU comes from dryfriction.locate: DFO_FMU, DFO_FMU3, DFO_CHAIN_FMU, DFO_CHAIN_FMU3 select
# other builds (the ASan/UBSan one), else the installed package's, else build/.


def _located(find: Callable[[], Path]) -> Path:
    try:
        return find()
    except FMUFileError as e:
        pytest.fail(str(e))


@pytest.fixture(scope="session")
def fmu_path() -> Path:
    return _located(default_fmu_path)


@pytest.fixture(scope="session")
def fmu(fmu_path: Path) -> Iterator[OscillatorFMU]:
    with OscillatorFMU(fmu_path) as f:
        yield f


@pytest.fixture(scope="session")
def chain_fmu3() -> Path:
    """The FMI 3.0 chain FMU (DFO_CHAIN_FMU3 selects another build)."""
    return _located(default_chain_fmu3)


@pytest.fixture(scope="session")
def chain_fmu2() -> Path:
    """The FMI 2.0 chain FMU (DFO_CHAIN_FMU selects another build)."""
    return _located(default_chain_fmu)
