"""Smoke test of the work-precision study: runs ``bench/work_precision.py --quick`` once
into a temporary folder and checks what it measured against the exact solution. No timing
assertions: times only have to be finite and positive.

Needs the FMU and bench_stepper built (``cmake --build build``; ``DFO_FMU`` / ``DFO_BENCH_STEPPER``
point elsewhere). Takes about a minute on 2 cores.
"""

from __future__ import annotations

import csv
import json
import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

# a benchmark smoke test: run once, against the Release build (not repeated under ASan)
pytestmark = [pytest.mark.no_sanitizer, pytest.mark.slow]  # the --quick study takes about 45 s

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "bench" / "work_precision.py"
CASES = ("stick_dominated", "reversal_resonance", "heavy_damped", "chi_above_1", "chi_near_0")
FMU_METHODS = {"FMU located", "FMU consistent", "FMU paper", "FMU exact"}
PEER_METHODS = {"event RK45", "event DOP853", "event Radau", "tanh Radau", "tanh LSODA"}
PNGS = ("error_vs_cpu.png", "error_vs_h.png", "cost_growth.png")


def _rows(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


@pytest.fixture(scope="module")
def study(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("work_precision")
    res = subprocess.run([sys.executable, str(SCRIPT), "--quick", "--out", str(out)],
                         capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, f"--quick study failed:\n{res.stderr[-3000:]}"
    return out


def test_orders_are_the_slopes_of_the_measured_errors(study: Path) -> None:
    """orders.csv is the least-squares slope of log(error) against log(h) of work_precision.csv's
    FMU rows, for every case, scheme and alpha (the orders themselves, second for located, first
    or a floor for the others, are asserted once, in test_schemes.py)."""
    # the exact scheme has no step, hence no order: it is not fitted
    rows = [r for r in _rows(study / "work_precision.csv") if r["family"] == "fmu" and r["scheme"] != "exact"]
    orders = _rows(study / "orders.csv")
    assert {(o["case"], o["scheme"]) for o in orders} == {(r["case"], r["scheme"]) for r in rows}
    for o in orders:
        pts = sorted((float(r["steps_per_period"]), float(r["error_z"])) for r in rows
                     if (r["case"], r["scheme"], float(r["alpha"])) == (o["case"], o["scheme"], float(o["alpha"])))
        use = [(n, e) for n, e in pts if n >= 100 and e > 1e-12]
        if len(use) >= 3:
            n, e = np.array(use).T
            assert float(o["order"]) == pytest.approx(np.polyfit(np.log(1 / n), np.log(e), 1)[0], rel=1e-9), o
        else:
            assert math.isnan(float(o["order"])), o


def test_csv_has_every_method_and_case(study: Path) -> None:
    rows = _rows(study / "work_precision.csv")
    for case in CASES:
        methods = {r["method"] for r in rows if r["case"] == case}
        assert FMU_METHODS | PEER_METHODS <= methods, (case, methods)
        for r in rows:
            if r["case"] == case:
                assert math.isfinite(float(r["error_z"])), r
                assert float(r["seconds_per_run"]) > 0, r
    # the FMU sweep covers the three schemes and alphas at every h of the quick study
    fmu = [r for r in rows if r["family"] == "fmu"]
    assert {float(r["alpha"]) for r in fmu} == {0.0, -0.1, -1.0 / 3.0}
    assert len({r["steps_per_period"] for r in fmu}) >= 4


def test_exact_scheme_row_is_exact(study: Path) -> None:
    """The FMU's exact scheme: one row per case, within 1e-10 static deflections of the reference."""
    rows = [r for r in _rows(study / "work_precision.csv") if r["method"] == "FMU exact"]
    assert sorted(r["case"] for r in rows) == sorted(CASES)
    for r in rows:
        assert float(r["error_z"]) < 1e-10, r


def test_event_driven_peer_matches_the_exact_solution(study: Path) -> None:
    """The scipy switching model is itself checked against the exact solution: at tight tolerance
    DOP853 must be accurate on every case, else its cost numbers would mean nothing."""
    rows = _rows(study / "work_precision.csv")
    for case in CASES:
        errs = [float(r["error_z"]) for r in rows if r["case"] == case and r["method"] == "event DOP853"]
        assert min(errs) < 1e-6, (case, errs)


def test_c_benchmark_rows(study: Path) -> None:
    rows = _rows(study / "stepper.csv")
    steps = [r for r in rows if r["kind"] == "step"]
    assert {(r["case"], r["scheme"]) for r in steps} == {
        (c, s) for c in CASES for s in ("paper", "consistent", "located")}
    for r in steps:
        assert float(r["bare_ns_per_step"]) > 0 and float(r["fmu_ns_per_step"]) > 0
        on, off = float(r["observe_on_ns_per_step"]), float(r["observe_off_ns_per_step"])
        assert on > 0 and off > 0 and float(r["observe_cost"]) == pytest.approx(on / off, rel=1e-3)
        assert int(r["steps"]) == 10 * int(float(r["steps_per_period"]))
    inst = next(r for r in rows if r["kind"] == "instance_bytes")
    assert 0 < float(inst["value"]) < 1 << 20


def test_pngs_and_report(study: Path) -> None:
    for name in PNGS:
        data = (study / name).read_bytes()
        assert len(data) > 10_000 and data[:8] == b"\x89PNG\r\n\x1a\n", name
    md = (study / "RESULTS.md").read_text()
    assert "## What accuracy costs" in md
    for case in CASES:
        assert f"- **{case}**:" in md
    goals = md.split("## Performance goals")[1].split("\n## ")[0]
    verdict_lines = [ln for ln in goals.splitlines() if ln.startswith("| ") and not ln.startswith("| goal")]
    assert len(verdict_lines) == 4 + len(CASES)
    assert all(("PASS" in ln) or ("MISS" in ln) or ("SHOWN" in ln) for ln in verdict_lines)
    assert not list(study.glob("*.tmp")), "temporary files left behind"


def test_memory_does_not_grow_over_long_runs(study: Path) -> None:
    mem = {r["kind"]: float(r["value"]) for r in _rows(study / "memory.csv")}
    runs = [mem[f"rss_after_long_run_{k}"] for k in (1, 2, 3)]
    assert runs[-1] - runs[0] <= 1 << 20  # 10^6-step runs: no growth beyond page noise


@pytest.mark.parametrize("args", [["--bogus"], ["--quick", "--fmu", "/nonexistent/x.fmu"],
                                  ["--bench-stepper", "/nonexistent/bench_stepper"]])
def test_bad_arguments_fail_fast(tmp_path: Path, args: list[str]) -> None:
    out = tmp_path / "never"
    res = subprocess.run([sys.executable, str(SCRIPT), "--out", str(out), *args],
                         capture_output=True, text=True, timeout=60)
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "error" in lines[0], res.stderr
    assert not out.exists()


def test_report_can_be_rebuilt_from_the_csvs(study: Path, tmp_path: Path) -> None:
    md = tmp_path / "again.md"
    res = subprocess.run([sys.executable, str(SCRIPT), "--report-only", "--out", str(study), "--md", str(md)],
                         capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    text = md.read_text()
    assert "## What accuracy costs" in text
    links = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", text)
    assert len(links) == 3
    for link in links:  # plot paths are relative to the markdown file
        assert (md.parent / link).resolve() == (study / Path(link).name).resolve()


def test_report_only_needs_a_study(tmp_path: Path) -> None:
    res = subprocess.run([sys.executable, str(SCRIPT), "--report-only", "--out", str(tmp_path)],
                         capture_output=True, text=True, timeout=60)
    assert res.returncode == 2 and len(res.stderr.strip().splitlines()) == 1


def test_orbit_response_benchmark_smoke() -> None:
    """bench/orbit_response.py at 5 frequencies, once: every point has its stable orbit (residual at
    most 1e-12; without friction the closed form within 1e-12), and every transient tolerance
    bounds the transient's measured amplitude error. No timing asserted (times only positive)."""
    res = subprocess.run([sys.executable, str(ROOT / "bench" / "orbit_response.py"), "--num", "5", "--repeats", "1",
                          "--json"], capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr[-3000:]
    out = json.loads(res.stdout)
    assert [r["case"] for r in out["responses"]] == ["engineer 5-15 Hz", "zeta 0.01, N 0.1", "zeta 0.01, N 0"]
    for r in out["responses"]:
        assert r["frequencies_with_a_stable_orbit"] == 5 and r["max_residual"] <= 1e-12 and r["seconds"] > 0
    for row in out["transient"]:
        if row["orbit_error"] is not None:
            assert row["orbit_error"] <= 1e-12
        for t in row["tols"]:
            assert t["converged"] == 5 and t["max_error"] <= t["tol"] + 1e-11 and t["seconds"] > 0


def test_bladed_disk_orbits_benchmark_smoke() -> None:
    """bench/bladed_disk_orbits.py at one stuck frequency (1070 rad/s, 768 steps a period): the
    orbit by the cyclic symmetry converged, its amplitude within the scheme's error of the stuck
    closed form and Richardson's 100x closer (measured 8.9e-5 and 5.2e-7). No timing asserted."""
    res = subprocess.run([sys.executable, str(ROOT / "bench" / "bladed_disk_orbits.py"), "--omegas", "1070",
                          "--steps", "768", "--transients", "0", "--json"], capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr[-3000:]
    (row,) = json.loads(res.stdout.splitlines()[-1])["points"]
    assert row["converged"] and row["reference_kind"] == "stuck closed form" and row["cpu_s"] > 0
    assert row["amplitude_error"] <= 2e-4 and row["extrapolated_error"] <= 1e-2 * row["amplitude_error"]


def _bench_system() -> Path:
    sys.path.insert(0, str(ROOT / "bench"))
    from siconos_system import bench_system_path

    return bench_system_path(None)


def test_system_benchmark_smoke(tmp_path: Path) -> None:
    """bench/bench_system on small sizes, once: a row per structure, scheme and (n, nc), every case in
    the stick-slip regime it is meant for (contacts both stuck and sliding, switches every period),
    the friction solve's share a fraction, the growth fitted. No timing asserted (only positive)."""
    out = tmp_path / "system.csv"
    res = subprocess.run([str(_bench_system()), "--reps", "1", "--periods", "1", "--n", "8,32,64", "--nc-at", "32",
                          "--nc", "2,16", "--csv", str(out)], capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr[-3000:]
    lines = out.read_text().splitlines()
    rows = list(csv.DictReader([ln for ln in lines if not ln.startswith("#")]))
    want = {(st, sc, n, nc) for st in ("chain", "banded") for sc in ("located", "consistent", "paper")
            for n, nc in (("8", "2"), ("32", "8"), ("64", "16"), ("32", "2"), ("32", "16"))}
    assert {(r["structure"], r["scheme"], r["n"], r["nc"]) for r in rows} == want
    for r in rows:
        assert float(r["ns_per_step"]) > 0 and 0.0 < float(r["friction_share"]) < 1.0
        assert 0.0 < float(r["stuck_share"]) < 1.0 and float(r["switches_per_contact_period"]) > 0.5
    fits = [ln for ln in lines if ln.startswith("# fit ")]
    assert len(fits) == 6 and all(math.isfinite(float(re.search(r"n\^(\S+)", f).group(1))) for f in fits)


def test_system_benchmark_case_is_the_linear_closed_form() -> None:
    """bench_system --case (the structure file bench/siconos_system.py writes) without friction
    (N = 0) follows the linear closed form (the forced steady state plus the free transient by the
    matrix exponential) to the located scheme's second-order error: within 1e-5 of the largest
    deflection at h = T/2560, and about 4x closer per halving of h."""
    from scipy.linalg import expm

    sys.path.insert(0, str(ROOT / "bench"))
    import siconos_system as ss

    st = ss.structure(8)
    st["N"] = np.zeros(st["nc"])
    n = st["n"]
    M, C, K, w = st["M"], st["C"], st["K"], ss.OMEGA
    X = np.linalg.solve(K - w**2 * M + 1j * w * C, st["F_c"] - 1j * st["F_s"])
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(M, K), -np.linalg.solve(M, C)]])
    z0 = np.concatenate([-X.real, w * X.imag])  # at rest: minus the steady state's x and v at t = 0
    ns = ss.PERIODS * ss.SAMPLES_PER_PERIOD
    t = np.arange(1, ns + 1) * ss.PERIODS * ss.T / ns
    exact = np.array([(X * np.exp(1j * w * tk)).real + (expm(A * tk) @ z0)[:n] for tk in t])
    errs = []
    for m in (1280, 2560):
        x = ss.ours(_bench_system(), st, m, reps=1)["x"]
        errs.append(float(np.max(np.abs(x - exact)) / np.max(np.abs(exact))))
    assert errs[1] < 1e-5 and 3.5 < errs[0] / errs[1] < 4.5, errs


def test_system_against_siconos_smoke(tmp_path: Path) -> None:
    """bench/siconos_system.py --quick (n = 8): Siconos and the model simulate the same structure
    (Siconos's trajectory within 1 % of the model's reference at h = T/80), that reference within
    3e-5 of the event-driven one (dryfriction.references.system), the model's errors fall about 4x
    per halving of h (located, second order), the JSON complete. No timing asserted.
    Skips, saying why, only when Siconos cannot be installed."""
    sys.path.insert(0, str(ROOT / "bench"))
    from siconos_side import SiconosUnavailable, ensure_siconos

    try:
        ensure_siconos()
    except SiconosUnavailable as e:
        pytest.skip(f"Siconos cannot be installed here: {e}")
    out = tmp_path / "sic.json"
    res = subprocess.run([sys.executable, str(ROOT / "bench" / "siconos_system.py"), "--quick", "--json", str(out)],
                         capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr[-3000:]
    (r,) = json.loads(out.read_text())["results"]
    assert (r["n"], r["nc"]) == (8, 2) and r["ref_error"] < 1e-4 and r["ref_vs_event_driven"] < 3e-5
    sic = {row["m"]: row for row in r["siconos"]}
    assert sic[80]["error"] < 1e-2 and all(row["cpu_s"] > 0 for row in r["siconos"] + r["ours"])
    e = [row["error"] for row in r["ours"]]
    assert all(3.0 < a / b < 5.0 for a, b in zip(e, e[1:])), e
    assert set(r["at_error"]) == {"0.1", "0.03", "0.01", "0.003", "0.001", "0.0003", "0.0001"}
