#!/usr/bin/env python3
"""Speed of the chaos studies against the stepper's limit (as scripts/bench_sweep.py measures it).

    python scripts/bench_chaos.py [--quick] [--workers N] [--out DIR] [--only scan|basins] [--scheme S]
                                  [--set key=value ...]

Runs ``dryfriction study chaos_scan`` (80 chi x 4 initial conditions x 100 + 500 periods, two
trajectories per period, plus the onset refinement) and ``dryfriction study chaos_basins``
(401 x 401 initial conditions per case) and reports for each: wall time, excitation periods
integrated, and the limit = periods x seconds per period of the bare stepper (``dfo_advance`` of
libdfo_physics.a in a tiny C loop, with the study's scheme, one process per worker, on a stratified
sample of the study's own runs, timed before and after; the faster is the limit) / workers, and the
ratio wall / limit. Per period, so that the same rule holds for the exact scheme (closed form
between events, no internal steps to count) and the Bossak schemes (for those, periods x seconds
per period = internal steps x seconds per step). ``--scheme`` sets the scheme of both studies
(default: the configs', exact); ``--set`` applies to the basins study (e.g. ``--set
cases=["end_of_chaos"]``). Not a test: nothing is asserted.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import math
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from dryfriction.drivers.oscillator import SCHEMES, default_fmu_path
from dryfriction.studies import effective_config, run_study
from dryfriction.studies.config import grid
from dryfriction.sweep.table import nondim_table

ROOT = Path(__file__).resolve().parent


def _bench_sweep():
    spec = importlib.util.spec_from_file_location("bench_sweep", ROOT / "bench_sweep.py")
    mod = importlib.util.module_from_spec(spec)
    assert spec.loader is not None
    spec.loader.exec_module(mod)
    return mod


def bare_per_period(exe: Path, rows: np.ndarray, scheme: int, procs: int = 1) -> tuple[float, float]:
    """(wall s, CPU s) per excitation period of the bare loop over the rows (each row one run of
    t_stop = its last column), run as ``procs`` processes at once on interleaved parts of the rows
    (the contention the study's workers see)."""
    secs, _, cpu = _bench_sweep().run_bare(exe, rows, scheme, procs)
    periods = float(np.sum(rows[:, 15] * rows[:, 4] / (2.0 * math.pi)))     # t_stop omega / (2 pi)
    return secs / periods, cpu / periods


def scan_rows(cfg: dict, sample: int) -> tuple[np.ndarray, float]:
    """Sample rows (one trajectory of transient + periods) and the scan's total excitation periods."""
    s, ly, num = cfg["scan"], cfg["lyapunov"], cfg["numerics"]
    chis = grid(s["chi"], "scan.chi")
    spp = num["steps_per_period"]
    n_ic = len(s["z0"])
    per_run = ly["transient"] + 2 * ly["periods"]     # transient once, then two trajectories
    total = chis.size * n_ic * per_run      # the scan itself (timed by the study: scan_wall_s)
    idx = np.unique(np.linspace(0, chis.size * n_ic - 1, min(sample, chis.size * n_ic)).round().astype(int))
    C = chis[idx // n_ic]
    Z = np.asarray(s["z0"], float)[idx % n_ic]
    D = np.asarray(s["dz0"], float)[idx % n_ic]
    per = ly["transient"] + ly["periods"]
    rows = nondim_table({**cfg["params"], "chi": C, "z0": Z, "dz0": D}, per, per - 1, per, spp, alpha=num["alpha"])
    return rows, float(total)


def basin_rows(cfg: dict, sample: int) -> tuple[np.ndarray, float]:
    from dryfriction.studies.chaos_basins import case_grid

    rows, total = [], 0.0
    for case in cfg["cases"]:
        t = cfg[case]
        z0, dz0, num = case_grid(cfg, case)
        n = z0.size * dz0.size
        spp = num["steps_per_period"]
        per = t["transient"] + t["tail"]
        total += n * per
        idx = np.unique(np.linspace(0, n - 1, min(sample, n)).round().astype(int))
        vals = {k: t[k] for k in ("lam", "mu_s_sigma", "chi", "zeta")}
        rows.append(nondim_table({**vals, "z0": z0[idx // dz0.size], "dz0": dz0[idx % dz0.size]},
                                 per, per - 1, per, spp, alpha=num["alpha"]))
    return np.vstack(rows), total


def case_steps(cfg: dict, case: str) -> int:
    from dryfriction.studies.chaos_basins import case_grid

    return int(case_grid(cfg, case)[2]["steps_per_period"])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--out", default="results")
    ap.add_argument("--only", choices=["scan", "basins"], default=None)
    ap.add_argument("--sample", type=int, default=64, help="runs in the limit's sample (per study)")
    ap.add_argument("--scheme", choices=list(SCHEMES), default=None, help="scheme of both studies (default: the configs')")
    ap.add_argument("--set", dest="sets", action="append", default=[], metavar="KEY=VALUE")
    a = ap.parse_args()
    if a.workers < 1:
        print("bench_chaos: error: --workers must be >= 1", file=sys.stderr)
        return 2
    fmu = default_fmu_path()
    if not fmu.is_file():
        print(f"bench_chaos: error: FMU not found: {fmu}", file=sys.stderr)
        return 2
    bs = _bench_sweep()
    work = Path(tempfile.mkdtemp(prefix="bench-chaos-"))
    exe = bs.build_driver(fmu.parent, work)
    if exe is None:
        print("bench_chaos: error: cannot build the bare stepper loop (needs cc and build/libdfo_physics.a)",
              file=sys.stderr)
        return 2
    out = Path(a.out) / "bench"
    out.mkdir(parents=True, exist_ok=True)
    path = out / "bench_chaos.json"
    report = json.loads(path.read_text()) if a.only and path.is_file() else {}   # --only keeps the other entry
    scheme_set = [f'numerics.scheme="{a.scheme}"'] if a.scheme else []
    for name, rows_of, sets in (("chaos_scan", scan_rows, scheme_set), ("chaos_basins", basin_rows, scheme_set + a.sets)):
        if a.only and not name.endswith(a.only):
            continue
        cfg = effective_config(name, quick=a.quick, sets=sets)
        rows, periods = rows_of(cfg, a.sample)
        scheme = SCHEMES[cfg["numerics"]["scheme"]]
        before, cpu_before = bare_per_period(exe, rows, scheme, a.workers)
        t0 = time.perf_counter()
        res = run_study(name, quick=a.quick, out=a.out, workers=a.workers, fmu=fmu, sets=sets, progress=False)
        wall = time.perf_counter() - t0
        after, cpu_after = bare_per_period(exe, rows, scheme, a.workers)
        task_cpu = sum(v.get("task_cpu_s", 0.0) for v in res.summary.values() if isinstance(v, dict))
        if name == "chaos_scan":     # the scan's own time (the study also refines, checks, draws)
            study_wall, wall, task_cpu = wall, res.summary["scan_wall_s"], res.summary["scan_task_cpu_s"]
        else:
            study_wall = wall
        limit = periods * min(before, after) / a.workers
        bare_cpu = 0.5 * (cpu_before + cpu_after)
        key = name if name == "chaos_scan" else f"{name}:{','.join(cfg['cases'])}"
        report[key] = {"wall_s": wall, "study_wall_s": study_wall, "periods": periods,
                        "bare_us_per_period_before": before * 1e6, "bare_us_per_period_after": after * 1e6,
                        "limit_s": limit, "ratio_to_limit": wall / limit,
                        "workers": a.workers, "scheme": cfg["numerics"]["scheme"],
                        "steps_per_period": ({c: case_steps(cfg, c) for c in cfg["cases"]} if "cases" in cfg
                                             else cfg["numerics"]["steps_per_period"]), "summary": res.summary,
                        "bare_cpu_us_per_period": bare_cpu * 1e6, "task_cpu_s": task_cpu or None,
                        "cpu_ratio_tasks_to_bare": task_cpu / (periods * bare_cpu) if task_cpu else None,
                        "load_average": os.getloadavg()}
        cr = report[key]["cpu_ratio_tasks_to_bare"]
        print(f"{name} ({cfg['numerics']['scheme']}): wall {wall:.1f} s, {periods:.3e} periods, bare "
              f"{before * 1e6:.2f} / {after * 1e6:.2f} us/period (before / after), limit {limit:.1f} s, "
              f"ratio {wall / limit:.2f}" + (f", CPU ratio {cr:.2f}" if cr else ""), flush=True)
    path.write_text(json.dumps(report, indent=2, default=float) + "\n")
    print(f"report: {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
