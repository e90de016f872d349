"""Shared fixtures: one FMU instance per test session, reused (reset) by every test."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from dryfriction.chain import default_chain_fmu, default_chain_fmu3
from dryfriction.fmu import OscillatorFMU, default_fmu_path


@pytest.fixture(scope="session")
def fmu_path():
    path = default_fmu_path()
    if not path.is_file():
        pytest.fail(f"FMU not built: {path} (cmake -S . -B build && cmake --build build)")
    return path


@pytest.fixture(scope="session")
def fmu(fmu_path) -> Iterator[OscillatorFMU]:
    with OscillatorFMU(fmu_path) as f:
        yield f


@pytest.fixture(scope="session")
def chain_fmu3() -> Path:
    """The FMI 3.0 chain FMU (DFO_CHAIN_FMU3 selects another build)."""
    path = default_chain_fmu3()
    if not path.is_file():
        pytest.fail(f"FMI 3.0 chain FMU not built: {path} (cmake --build build)")
    return path


@pytest.fixture(scope="session")
def chain_fmu2() -> Path:
    """The FMI 2.0 chain FMU (DFO_CHAIN_FMU selects another build)."""
    path = default_chain_fmu()
    if not path.is_file():
        pytest.fail(f"FMI 2.0 chain FMU not built: {path} (cmake --build build)")
    return path
