"""`dryfriction chain`: the files it writes hold the driver's numbers, and the FMI 2.0 chain runs its
built n only."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from dryfriction.drivers.chain import ChainFMU3, ChainFMU2


def test_chain_command_writes_the_run(tmp_path: Path, chain_fmu3: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """dryfriction chain: the CSV and the NetCDF hold the driver's numbers for the same values."""
    from dryfriction.cli import main
    from dryfriction.sweep.datasets import read_netcdf

    out = tmp_path / "out"
    argv = ["chain", "--n", "3", "--t-end", "12", "--dt", "0.25", "--set", "mu_s=0.5", "--set", "P0=1,0,0",
            "--set", "k=1", "--set", "omega=0.5", "--set", "h=0.01", "--set", "scheme=located", "--out", str(out),
            "--fmu", str(chain_fmu3)]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "chain of 3 blocks (FMI 3), 49 points" in text and "share of time stuck per block" in text
    with ChainFMU3(3, fmu_path=chain_fmu3) as f:
        ref = f.run(12.0, 0.25, {"mu_s": 0.5, "P0": [1, 0, 0], "k": 1.0, "omega": 0.5, "h": 0.01})
    csv = np.loadtxt(out / "chain.csv", delimiter=",", skiprows=1)
    header = (out / "chain.csv").read_text().splitlines()[0].split(",")
    assert header[:4] == ["t", "x[1]", "x[2]", "x[3]"] and header[-1] == "mode[3]"
    assert np.array_equal(csv[:, 0], ref.t) and np.array_equal(csv[:, 1:4], ref.x)
    assert np.array_equal(csv[:, -3:], ref.mode)
    ds = read_netcdf(out / "chain.nc")
    assert np.array_equal(ds.F_friction.values, ref.F_friction) and ds.attrs["param_omega"] == 0.5
    assert (out / "chain.png").stat().st_size > 10_000


def test_fmi2_command_needs_the_built_n(tmp_path: Path, chain_fmu2: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from dryfriction.cli import main

    with ChainFMU2(fmu_path=chain_fmu2) as f2:
        n = f2.n
    assert main(["chain", "--fmi", "2", "--n", str(n + 1), "--fmu", str(chain_fmu2), "--out", str(tmp_path)]) == 2
    assert f"this FMI 2.0 chain has n = {n} blocks" in capsys.readouterr().err
    assert main(["chain", "--fmi", "2", "--t-end", "1", "--fmu", str(chain_fmu2), "--out", str(tmp_path),
                 "--format", "csv", "--no-plot"]) == 0
    assert (tmp_path / "chain.csv").is_file() and not (tmp_path / "chain.png").exists()
