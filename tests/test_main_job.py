"""The README's main job (`dryfriction validate`, run by scripts/main.sh), end to end on its quick
size: it writes the CSV and the PNG, covers every scheme of the model description, and its numbers
are the ones the validation asserts elsewhere (located second order, exact at rounding)."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

from dryfriction import model
from dryfriction.cli import main


def test_validate_writes_results_for_every_scheme(tmp_path: Path, fmu_path: Path) -> None:
    assert main(["validate", "--quick", "--out", str(tmp_path), "--fmu", str(fmu_path)]) == 0
    png = tmp_path / "validation.png"
    assert png.is_file() and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with open(tmp_path / "validation.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert {r["scheme"] for r in rows} == set(model.default().schemes)
    for case in {r["case"] for r in rows}:
        loc = [float(r["max_error_z"]) for r in rows if r["case"] == case and r["scheme"] == "located"]
        assert np.all(np.log2(np.array(loc[:-1]) / np.array(loc[1:])) > 1.9), (case, loc)
        exact = [float(r["max_error_z"]) for r in rows if r["case"] == case and r["scheme"] == "exact"]
        assert max(exact) < 1e-10, (case, exact)


@pytest.mark.slow
def test_chain_validation_of_the_main_job(tmp_path: Path, chain_fmu3: Path) -> None:
    """scripts/plot_chain_validation.py (the main job's second part): the chain FMU's located scheme
    at second order on the four coupled cases, in the CSV next to the PNG."""
    import subprocess
    import sys

    root = Path(__file__).resolve().parents[1]
    out = tmp_path / "chain_validation.png"
    r = subprocess.run([sys.executable, str(root / "scripts" / "plot_chain_validation.py"), "--out", str(out),
                        "--fmu", str(chain_fmu3)], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with open(out.with_suffix(".csv"), newline="") as f:
        rows = list(csv.DictReader(f))
    cases = {r["case"] for r in rows}
    assert len(cases) == 4 and {r["scheme"] for r in rows} == {"located", "consistent", "paper"}
    for case in cases:
        loc = [float(r["max_abs_error_x"]) for r in rows if r["case"] == case and r["scheme"] == "located"]
        assert len(loc) == 4 and np.all(np.log2(np.array(loc[:-1]) / np.array(loc[1:])) > 1.9), (case, loc)
