"""``dryfriction belt``: the JSON object (against the closed-form belt limit cycle and the Hopf
formula), the PNG, the table, physical units, one-line errors with exit status 2 and nothing
written."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from dryfriction.references.belt import limit_cycle
from dryfriction.cli import main

KEYS = {"motion", "reason", "v_belt", "law", "scheme", "h", "x_eq", "equilibrium", "hopf_formula", "orbit", "units",
        "period", "amplitude", "stick_fraction", "stable", "coexists_with_steady_sliding", "files"}
ORBIT_KEYS = {"period", "amplitude", "offset", "x_max", "x_min", "stick_fraction", "stable", "multipliers", "v0",
              "residual", "converged", "reason", "iterations", "transitions", "jacobian"}


def run_json(argv: list[str], capsys: pytest.CaptureFixture[str]) -> dict:
    assert main(["belt", *argv, "--json"]) == 0
    out = capsys.readouterr().out
    assert out.count("\n") == 1
    return json.loads(out)


def test_undamped_coulomb_json_is_the_closed_form_cycle(fmu_path: Path, tmp_path: Path,
                                                         capsys: pytest.CaptureFixture[str]) -> None:
    """The non-dimensional defaults (m = k = N = 1, mu_s 0.5, mu_k 0.3), v_belt 0.2: the closed-form
    limit cycle (period 6.7124, stick 2.0) to the located scheme's error; the PNG written."""
    res = run_json(["--v-belt", "0.2", "--steps-per-period", "4000", "--out", str(tmp_path), "--fmu", str(fmu_path)],
                   capsys)
    lc = limit_cycle(1.0, 1.0, 1.0, 0.5, 0.3, 0.2)
    assert set(res) == KEYS and set(res["orbit"]) == ORBIT_KEYS
    assert res["motion"] == "stick-slip" and res["stable"] is True and res["reason"] is None
    assert abs(res["period"] - lc.period) < 2e-6          # measured 1.33e-6 (h = T0 / 4000)
    assert abs(res["amplitude"] - lc.amplitude) < 1e-6
    assert abs(res["stick_fraction"] - lc.stick_fraction) < 1e-7
    assert res["orbit"]["multipliers"][1] == [0.0, 0.0]
    assert res["orbit"]["jacobian"] == "central differences" and res["orbit"]["residual"] <= 1e-10
    assert res["x_eq"] == pytest.approx(0.3, abs=1e-15) and res["equilibrium"]["neutral"] is True
    assert res["h"] == pytest.approx(2 * math.pi / 4000, rel=1e-15) and res["hopf_formula"] is None
    png = tmp_path / "belt.png"
    assert res["files"] == [str(png)] and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_stribeck_steady_sliding_and_stick_slip(fmu_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Physical units (c given as zeta), Stribeck with delta = 1: the Hopf formula's speed; well above
    it steady sliding, stable, its slowest multiplier exp(-(c + N mu') tau / 2m); below it stick-slip."""
    base = ["--m", "2", "--k", "8", "--zeta", "0.0125", "--N", "4", "--mu-s", "0.5", "--mu-k", "0.3", "--law",
            "stribeck", "--v-s", "0.1", "--fmu", str(fmu_path)]
    c = 2 * 0.0125 * 4.0                                       # 0.1 N s/m
    v_star = 0.1 * math.log(4 * 0.2 / (c * 0.1))
    high = run_json([*base, "--v-belt", f"{6 * v_star}"], capsys)
    assert high["hopf_formula"] == pytest.approx(v_star, rel=1e-12)
    assert high["motion"] == "steady sliding" and high["stable"] is True and high["orbit"] is None
    assert high["period"] is None and high["files"] == []
    eq = high["equilibrium"]
    c_eff = c - 4 * 0.2 / 0.1 * math.exp(-6 * v_star / 0.1)
    assert eq["slowest_multiplier"] == pytest.approx(math.exp(-c_eff * eq["tau"] / (2 * 2.0)), rel=2e-6)
    assert eq["tau"] == pytest.approx(2 * math.pi / 2.0, rel=1e-15)
    low = run_json([*base, "--v-belt", f"{0.5 * v_star}"], capsys)
    assert low["motion"] == "stick-slip" and low["equilibrium"]["stable"] is False
    assert low["coexists_with_steady_sliding"] is False and high["coexists_with_steady_sliding"] is False
    both = run_json([*base, "--v-belt", f"{1.2 * v_star}"], capsys)           # subcritical: bistable
    assert both["motion"] == "stick-slip" and both["coexists_with_steady_sliding"] is True
    assert 0 < low["stick_fraction"] < 1 and low["orbit"]["multipliers"][1] == [0.0, 0.0]


def test_the_table(fmu_path: Path, capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    assert main(["belt", "--v-belt", "-0.2", "--c", "0.05", "--out", str(tmp_path), "--fmu", str(fmu_path)]) == 0
    out = capsys.readouterr().out
    assert "stick-slip: period" in out and "steady sliding at x_eq = -0.3 m: stable" in out
    assert "the two motions coexist" in out
    assert f"wrote {tmp_path / 'belt.png'}" in out and (tmp_path / "belt.png").stat().st_size > 1000


@pytest.mark.parametrize("argv, message", [
    (["--v-belt", "0"], "--v-belt must be nonzero"),
    (["--v-belt", "x"], "--v-belt must be a number, not 'x'"),
    (["--v-belt", "0.2", "--m", "-1"], "--m must be > 0, not -1"),
    (["--v-belt", "0.2", "--delta", "2"], "--v-s and --delta are parameters of --law stribeck"),
    (["--v-belt", "0.2", "--law", "stribeck", "--delta", "0.5"], "--delta must be >= 1, not 0.5"),
    (["--v-belt", "0.2", "--c", "0.1", "--zeta", "0.1"], "give the damping as --c or --zeta, not both"),
    (["--v-belt", "0.2", "--mu-k", "0.1", "--chi", "0.5"], "--mu-k or --chi, not both"),
    (["--v-belt", "0.2", "--scheme", "exact", "--law", "stribeck"], "scheme exact supports law coulomb only"),
    (["--v-belt", "0.2", "--steps-per-period", "5"], "--steps-per-period must be >= 20, not 5"),
    (["--v-belt", "inf"], "--v-belt must be finite"),
])
def test_bad_input_is_one_line_and_exit_2(argv: list[str], message: str, tmp_path: Path,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "o"
    assert main(["belt", *argv, "--out", str(out)]) == 2
    cap = capsys.readouterr()
    assert cap.out == ""
    lines = cap.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("dryfriction: error: ") and message in lines[0], cap.err
    assert not out.exists()
