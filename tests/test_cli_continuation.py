"""`dryfriction continuation` and `dryfriction bifurcation`: the files and the JSON hold the library's
numbers (continue_orbits called directly), the oscillator is read in either form, and bad input is
one line with exit status 2."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from dryfriction import Oscillator
from dryfriction.cli import main
from dryfriction.analysis.continuation import continue_orbits
from dryfriction.drivers.oscillator import OscillatorFMU2


def test_json_holds_the_library_numbers(fmu: OscillatorFMU2, fmu_path: Path,
                                        capsys: pytest.CaptureFixture[str]) -> None:
    """Physical units, N = 0, through resonance: the JSON's branch is continue_orbits' own, and its
    amplitudes are the closed form's."""
    argv = ["continuation", "--param", "omega", "--from", "0.5", "--to", "1.6", "--m", "1", "--k", "1", "--c", "0.1",
            "--P0", "1", "--N", "0", "--mu-s", "0.5", "--json", "--fmu", str(fmu_path)]
    assert main(argv) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out) == {"param", "branches", "bifurcations", "files"} and out["files"] == {}
    assert out["param"] == "omega" and out["bifurcations"] == []
    (b,) = out["branches"]
    assert b["period"] == 1 and b["stopped"].startswith("reached the end of the range at omega = 1.6")
    p = Oscillator.physical(m=1, k=1, c=0.1, P0=1, N=0, mu_s=0.5, omega=1.0)
    ref = continue_orbits(p, "omega", 0.5, 1.6, ds=0.02, ds_max=1.0, fmu=fmu).dataset
    assert b["param"] == [float(v) for v in ref.param.values]
    assert b["amplitude_m"] == [float(v) for v in ref.amplitude_m.values]
    w = np.array(b["param"])
    X = 1.0 / np.hypot(1 - w ** 2, 0.1 * w)
    assert np.max(np.abs(np.array(b["amplitude_m"]) - X) / X) <= 1e-10
    assert all(b["stable"]) and all(b["converged"]) and len(b["multipliers"][0]) == 2


def test_files_and_the_band(tmp_path: Path, fmu_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Non-dimensional form, the Fig. 8/9 band from chi 0.6 to 0.5: the symmetry breaking and the two
    asymmetric branches; the CSV, the NetCDF and the printed lines agree."""
    from dryfriction.sweep.datasets import read_netcdf

    argv = ["continuation", "--param", "chi", "--from", "0.6", "--to", "0.5", "--lam", "0.5", "--mu-s-sigma", "0.6",
            "--out", str(tmp_path), "--fmu", str(fmu_path), "--no-progress"]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "symmetry_breaking at chi = 0.55395" in text and "branch 2: period 1, full" in text
    ds = read_netcdf(tmp_path / "continuation.nc")
    csv = (tmp_path / "continuation.csv").read_text().splitlines()
    header = csv[0].split(",")
    assert header[:4] == ["branch", "period", "kind", "param"] and len(csv) == ds.point.size + 1
    col = header.index("amplitude_m")
    assert [float(r.split(",")[col]) for r in csv[1:]] == [float(v) for v in ds.amplitude_m.values]
    st = header.index("stable")  # booleans as in response.csv
    assert [r.split(",")[st] for r in csv[1:]] == [str(bool(v)).lower() for v in ds.stable.values]
    assert set(np.unique(ds.branch.values)) == {0, 1, 2} and ds.attrs["param"] == "chi"
    assert (tmp_path / "continuation.png").stat().st_size > 20_000
    sb = float(text.split("symmetry_breaking at chi = ")[1].split()[0])
    assert 0.54 < sb < 0.56


@pytest.mark.parametrize("argv, message", [
    (["--param", "chi", "--from", "0.5", "--to", "0.5"], "dryfriction: error: --from and --to must differ (both 0.5)"),
    (["--param", "chi", "--from", "0.6", "--to", "0.5", "--lam", "0.5", "--m", "1"],
     "give physical units or the non-dimensional form, not both (--lam)"),
    (["--param", "chi", "--from", "0.6", "--to", "-0.5"], "chi"),
    (["--param", "colour", "--from", "0.6", "--to", "0.5"], "invalid choice: 'colour'"),
    (["--param", "chi", "--from", "0.6", "--to", "0.5", "--period", "0"], "--period"),
])
def test_bad_input_is_one_line(argv: list[str], message: str, fmu_path: Path,
                               capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["continuation", *argv, "--fmu", str(fmu_path), "--json"]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1, err


def test_bifurcation_quick(tmp_path: Path, fmu_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["bifurcation", "--quick", "--from", "0.6", "--to", "0.45", "--values", "4", "--ics", "3",
            "--out", str(tmp_path), "--fmu", str(fmu_path), "--no-progress"]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "symmetry_breaking at chi = 0.55395" in text and "36 runs for the scatter" in text
    assert (tmp_path / "bifurcation.png").stat().st_size > 20_000
    assert not math.isnan(float(text.split("symmetry_breaking at chi = ")[1].split()[0]))
