"""Shared fixtures: one FMU instance per test session, reused (reset) by every test."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

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
