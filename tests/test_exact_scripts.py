"""Smoke tests of the exact scheme's scripts: the benchmark against `located` (no timing asserted)
and the comparison of two Fig. 8/9 datasets (counts checked on a constructed pair)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

pytestmark = pytest.mark.no_sanitizer

ROOT = Path(__file__).resolve().parents[1]


def test_bench_exact_runs_and_reports_both_schemes() -> None:
    res = subprocess.run([sys.executable, str(ROOT / "scripts" / "bench_exact.py"), "--reps", "1",
                          "--fig89-sample", "3", "--periods", "3"], capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    rows = [line for line in res.stdout.splitlines() if line.startswith("| ") and "---" not in line][1:]
    assert [r.split("|")[1].strip() for r in rows] == ["stick_dominated", "reversal_resonance", "heavy_damped",
                                                        "chi_above_1", "chi_near_0", "fig8_9"]
    for r in rows:
        cells = [c.strip() for c in r.split("|")[1:-1]]
        assert float(cells[2]) > 0 and float(cells[3]) > 0 and float(cells[7]) > 0, r


def _dataset(path: Path, scheme: str, shift: np.ndarray) -> Path:
    chi, z = np.array([0.1, 0.5]), np.linspace(-1.0, 1.0, 3)
    base = np.zeros((2, 3, 3))
    ds = xr.Dataset({"z_max": (("chi", "z0", "dz0"), 1.0 + base + shift), "z_min": (("chi", "z0", "dz0"), base - 1.0)},
                    coords={"chi": chi, "z0": z, "dz0": z}, attrs={"scheme": scheme})
    ds.to_netcdf(path)
    return path


@pytest.mark.slow
def test_compare_fig8_9_counts_runs_per_chi(tmp_path: Path) -> None:
    shift = np.zeros((2, 3, 3))
    shift[0, 0, :] = 0.05   # 3 runs differ by > 0.01, not by > 0.1
    shift[0, 1, 0] = 0.5    # 1 run differs by > 0.1
    shift[1, 2, 2] = 0.005  # below the threshold
    a = _dataset(tmp_path / "a.nc", "located", np.zeros_like(shift))
    b = _dataset(tmp_path / "b.nc", "exact", shift)
    res = subprocess.run([sys.executable, str(ROOT / "scripts" / "compare_fig8_9.py"), str(a), str(b)],
                         capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    assert "chi  0.10:     4     1" in res.stdout and "chi  0.50:     0     0" in res.stdout
    assert res.stdout.strip().endswith("total: 4 / 1 of 18 runs")
    bad = subprocess.run([sys.executable, str(ROOT / "scripts" / "compare_fig8_9.py"), str(a), str(tmp_path / "no.nc")],
                         capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1
