#!/usr/bin/env python3
"""Work-precision study of the DryFrictionOscillator FMU against the methods users would pick
instead.

    python bench/work_precision.py [--quick] [--out results/work_precision] [--md PATH]
                                   [--fmu PATH] [--bench-stepper PATH] [--no-siconos]

Five cases (bench/cases.py), error = max |z - z_exact| over the run (z = k x / P0, the position in
static deflections) against dryfriction.references.exact.solve_exact. The FMU: scheme paper / consistent /
located, h = T/50 ... T/102400, alpha in {0, -0.1, -1/3}, timed through one reused OscillatorFMU2
(min of several runs, time.perf_counter). Peers (bench/peers.py): event-driven solve_ivp (RK45,
DOP853, Radau) and a tanh-smoothed law (Radau, LSODA). Siconos (bench/siconos_study.py:
Moreau-Jean with the relay solved by Lemke, theta 0.5 and 1) on the same cases at chi = 1, the only
friction law it has (mu_s = mu_k), against the FMU at chi = 1 (process CPU time on both sides).
Also: the bare C stepper vs the FMU's library (bench_stepper), cost growth (periods, steps, Dask
workers) and memory.

Outputs in --out: work_precision.csv (one row per method/case/setting), orders.csv, stepper.csv,
scaling.csv, memory.csv, cases.csv, siconos.csv (unless --no-siconos), error_vs_cpu.png,
error_vs_h.png, cost_growth.png and the markdown report (RESULTS.md, or --md). --quick: fewer
steps, tolerances and widths, shorter timing budgets (under ~2 minutes on 2 cores); every code path
still runs.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from dryfriction import model
from dryfriction.cli.options import make_parser
from dryfriction.atomic import atomic_path, atomic_write_text

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))


def bad(message: str) -> None:
    sys.stderr.write(f"work_precision.py: error: {message}\n")
    raise SystemExit(2)


@dataclass(frozen=True)
class StudyConfig:
    quick: bool
    periods: int
    spp: tuple[int, ...]
    alphas: tuple[float, ...]
    samples_per_period: int
    fmu_budget: float
    fmu_min_reps: int
    peer_budget: float
    peer_min_reps: int
    periods_sweep: tuple[int, ...]
    spp_sweep: tuple[int, ...]
    dask_points: int
    dask_batch: int
    dask_periods: int
    dask_spp: int
    dask_reps: int
    mem_instances: int
    long_steps: int
    c_reps: int
    c_spp: tuple[int, ...]
    order_min_spp: int = 100
    order_min_error: float = 1e-12
    targets: tuple[float, ...] = field(default=(1e-3, 1e-4, 1e-6, 1e-8))

    @staticmethod
    def make(quick: bool) -> "StudyConfig":
        if quick:
            return StudyConfig(quick=True, periods=10, spp=(100, 200, 400, 800, 1600, 3200),
                               alphas=(0.0, -0.1, -1.0 / 3.0), samples_per_period=400, fmu_budget=0.005,
                               fmu_min_reps=2, peer_budget=0.0, peer_min_reps=1, periods_sweep=(1, 2, 4, 8, 16),
                               spp_sweep=(50, 1000, 20000), dask_points=64, dask_batch=16, dask_periods=10,
                               dask_spp=1000, dask_reps=2, mem_instances=40, long_steps=10**6, c_reps=15, c_spp=(1000,))
        return StudyConfig(quick=False, periods=10, spp=tuple(50 * 2**k for k in range(12)),
                           alphas=(0.0, -0.1, -1.0 / 3.0), samples_per_period=1600, fmu_budget=0.3,
                           fmu_min_reps=3, peer_budget=0.5, peer_min_reps=2,
                           periods_sweep=(1, 2, 5, 10, 20, 50, 100),
                           spp_sweep=(50, 200, 1000, 5000, 20000, 100000), dask_points=256, dask_batch=16,
                           dask_periods=20, dask_spp=2000, dask_reps=3, mem_instances=100, long_steps=10**6, c_reps=31,
                           c_spp=(100, 1000, 10000))


# ---------------------------------------------------------------------------- arguments, setup

def parse_args(argv: list[str] | None) -> argparse.Namespace:
    ap = make_parser("work_precision.py", __doc__.split("\n\n")[0], exit=True,
                     formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="the short smoke-test study (< ~2 min)")
    ap.add_argument("--out", default="results/work_precision", help="output folder (created)")
    ap.add_argument("--md", default=None, help="markdown report path (default: OUT/RESULTS.md)")
    ap.add_argument("--fmu", default=None, help="the .fmu (default: $DFO_FMU or build/DryFrictionOscillator.fmu)")
    ap.add_argument("--bench-stepper", default=None,
                    help="bench_stepper executable (default: $DFO_BENCH_STEPPER or <fmu folder>/bench/bench_stepper)")
    ap.add_argument("--no-dask", action="store_true", help="skip the Dask throughput measurement")
    ap.add_argument("--no-siconos", action="store_true",
                    help="skip Siconos (the cases at chi = 1; installs python3-siconos when missing)")
    ap.add_argument("--report-only", action="store_true",
                    help="rebuild the plots and the markdown report from the CSVs and meta.json already in --out")
    args = ap.parse_args(argv)
    out = Path(args.out)
    md = Path(args.md) if args.md else out / "RESULTS.md"
    if args.report_only:
        missing = [n for n in RESULT_FILES if not (out / n).is_file()]
        if missing:
            bad(f"--report-only: {out} lacks {', '.join(missing)} (run the study first)")
        args.out, args.md = out, md
        return args
    from dryfriction.drivers.oscillator import default_fmu_path

    fmu = Path(args.fmu) if args.fmu else default_fmu_path()
    if not fmu.is_file():
        bad(f"FMU not found: {fmu} (build it: cmake -S . -B build && cmake --build build, or pass --fmu)")
    exe_env = os.environ.get("DFO_BENCH_STEPPER")
    exe = Path(args.bench_stepper or exe_env or fmu.resolve().parent / "bench" / "bench_stepper")
    if not (exe.is_file() and os.access(exe, os.X_OK)):
        bad(f"bench_stepper not found or not executable: {exe} (cmake --build <build> --target bench_stepper, "
            "or pass --bench-stepper)")
    if out.exists() and not out.is_dir():
        bad(f"--out {out} exists and is not a folder")
    if md.exists() and md.is_dir():
        bad(f"--md {md} is a folder")
    for d in (out, md.parent):
        probe = d
        while not probe.exists():
            probe = probe.parent
        if not os.access(probe, os.W_OK):
            bad(f"cannot write into {d}")
    args.fmu, args.bench_stepper, args.out, args.md = fmu, exe, out, md
    return args


RESULT_FILES = ("cases.csv", "work_precision.csv", "orders.csv", "stepper.csv", "scaling.csv", "memory.csv",
                "meta.json")


def read_csv(path: Path) -> list[dict]:
    """Rows back from write_csv: ints and floats converted, other cells kept as text."""
    def conv(v: str) -> object:
        for t in (int, float):
            try:
                return t(v)
            except ValueError:
                pass
        return v

    with open(path, newline="") as f:
        return [{k: conv(v) for k, v in r.items()} for r in csv.DictReader(f)]


def write_json(path: Path, data: dict) -> None:
    atomic_write_text(path, json.dumps(data, indent=1))


def render(args: argparse.Namespace, cfg: StudyConfig, meta: dict) -> None:
    """Plots and markdown report from the CSVs in args.out."""
    from cases import CASES
    from report import write_report
    import plots

    out = args.out
    t = {n: read_csv(out / n) for n in RESULT_FILES if n.endswith(".csv")}
    rows, scal, c_rows = t["work_precision.csv"], t["scaling.csv"], t["stepper.csv"]
    for r in c_rows:  # empty cells of bench_stepper's CSV are NaN for the report
        for k, v in r.items():
            if v == "" and k not in ("case", "scheme"):
                r[k] = float("nan")
    names = [c.name for c in CASES]
    ref = CASES[0].name
    bare = next((r["bare_ns_per_step"] for r in c_rows if r["kind"] == "step" and r["case"] == ref
                 and r["scheme"] == "located" and r["steps_per_period"] == 1000), None)
    sic_path = out / "siconos.csv"
    sic = read_csv(sic_path) if sic_path.is_file() else None
    plots.error_vs_cpu(rows, names, out / "error_vs_cpu.png", sic)
    plots.error_vs_h([r for r in rows if r["family"] == "fmu"], t["orders.csv"], names, out / "error_vs_h.png")
    plots.cost_growth(scal, out / "cost_growth.png", bare)
    write_report(args.md, out, cfg, CASES, t["cases.csv"], rows, t["orders.csv"], c_rows, scal, t["memory.csv"],
                 meta, sic)


def write_csv(path: Path, rows: list[dict]) -> None:
    """All keys of all rows as columns, written to a temp file and renamed."""
    cols: list[str] = []
    for r in rows:
        for k in r:
            if k not in cols:
                cols.append(k)
    with atomic_path(path) as tmp, open(tmp, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=cols, restval="")
        w.writeheader()
        for r in rows:
            w.writerow({k: (repr(v) if isinstance(v, float) else v) for k, v in r.items()})


# ---------------------------------------------------------------------------- the study

def alpha_name(a: float) -> str:
    return "-1/3" if abs(a + 1.0 / 3.0) < 1e-12 else f"{a:g}"


def fmu_sweep(fmu, cfg: StudyConfig, cases, exacts, progress) -> list[dict]:
    import numpy as np

    from fmu_runs import FmuConfig, LeanRunner, api_run, best_time, fmu_error

    lean = LeanRunner(fmu)
    rows = []
    for case in cases:
        p = case.oscillator
        ex = exacts[case.name]
        t_end = cfg.periods * p.period
        cache: dict[int, np.ndarray] = {}

        def exact_x(t: np.ndarray) -> np.ndarray:
            key = t.size
            if key not in cache:
                cache[key] = ex.evaluate(t)[0]
            return cache[key]

        # the Bossak schemes swept over h and alpha: located, consistent, paper (exact: below)
        for scheme in reversed([name for name in model.default().schemes if name != "exact"]):
            for alpha in cfg.alphas:
                for spp in cfg.spp:
                    c = FmuConfig(scheme, alpha, spp)
                    st = c.settings(p)
                    err, n_samples = fmu_error(fmu, p, c, cfg.periods, cfg.samples_per_period, exact_x)
                    t_api, reps = best_time(lambda: api_run(fmu, p, st, t_end), cfg.fmu_budget, cfg.fmu_min_reps)
                    lean.prepare(p, st)
                    t_lean, _ = best_time(lambda: lean.run(t_end), cfg.fmu_budget, cfg.fmu_min_reps)
                    rows.append(dict(
                        case=case.name, family="fmu", method=f"FMU {scheme}", scheme=scheme, alpha=alpha,
                        steps_per_period=spp, rtol=float("nan"), eps_rel=float("nan"),
                        setting=f"h=T/{spp} alpha={alpha_name(alpha)}", periods=cfg.periods, error_z=err,
                        error_x_m=err * abs(p.P0) / p.k, error_samples=n_samples, seconds_per_run=t_api,
                        us_per_period=t_api / cfg.periods * 1e6, seconds_per_run_lean=t_lean, timing_reps=reps,
                        steps=cfg.periods * spp, nfev=0, events=0))
                    progress.update(1)
        # the exact scheme: one configuration (h has no effect on it; alpha is not used)
        c = FmuConfig("exact", -0.1, 1000)
        st = c.settings(p)
        err, n_samples = fmu_error(fmu, p, c, cfg.periods, cfg.samples_per_period, exact_x)
        t_api, reps = best_time(lambda: api_run(fmu, p, st, t_end), cfg.fmu_budget, cfg.fmu_min_reps)
        lean.prepare(p, st)
        t_lean, _ = best_time(lambda: lean.run(t_end), cfg.fmu_budget, cfg.fmu_min_reps)
        rows.append(dict(
            case=case.name, family="fmu", method="FMU exact", scheme="exact", alpha=-0.1,
            steps_per_period=1000, rtol=float("nan"), eps_rel=float("nan"), setting="closed form (h no effect)",
            periods=cfg.periods, error_z=err, error_x_m=err * abs(p.P0) / p.k, error_samples=n_samples,
            seconds_per_run=t_api, us_per_period=t_api / cfg.periods * 1e6, seconds_per_run_lean=t_lean,
            timing_reps=reps, steps=0, nfev=0, events=0))
        progress.update(1)
    return rows


def peer_sweep(cfg: StudyConfig, cases, exacts, progress) -> list[dict]:
    import numpy as np

    from fmu_runs import best_time
    from peers import PeerError, peer_settings

    rows = []
    for case in cases:
        p = case.oscillator
        t_end = cfg.periods * p.period
        n = cfg.periods * cfg.samples_per_period
        t = np.arange(n + 1) * (t_end / n)
        xe = exacts[case.name].evaluate(t)[0]
        for s in peer_settings(cfg.quick):
            try:
                run = s.run(p, t_end, dense=True)
                err = float(np.max(np.abs(run.x(t) - xe))) * p.k / abs(p.P0)
                secs, reps = best_time(lambda: s.run(p, t_end, dense=False), cfg.peer_budget, cfg.peer_min_reps)
                note = ""
            except PeerError as e:  # reported in the CSV, not hidden
                run, err, secs, reps, note = None, float("nan"), float("nan"), 0, str(e)
            rows.append(dict(
                case=case.name, family=s.family, method=s.label, scheme="", alpha=float("nan"),
                steps_per_period=0, rtol=s.rtol, eps_rel=s.eps_rel, setting=s.setting, periods=cfg.periods,
                error_z=err, error_x_m=err * abs(p.P0) / p.k, error_samples=n + 1, seconds_per_run=secs,
                us_per_period=secs / cfg.periods * 1e6, seconds_per_run_lean=float("nan"), timing_reps=reps,
                steps=run.steps if run else 0, nfev=run.nfev if run else 0, events=run.events if run else 0,
                note=note))
            progress.update(1)
    return rows


def observed_orders(rows: list[dict], cfg: StudyConfig) -> list[dict]:
    """Least-squares slope of log(error) vs log(h) per case/scheme/alpha over h <= T/order_min_spp
    and error above order_min_error; a scheme with slope < 0.5 has an error floor (its level: the
    geometric mean of the three finest errors)."""
    import numpy as np

    out = []
    keys = sorted({(r["case"], r["scheme"], r["alpha"]) for r in rows if r["family"] == "fmu"})
    for case, scheme, alpha in keys:
        if scheme == "exact":
            continue  # no step: no order
        pts = sorted((r["steps_per_period"], r["error_z"]) for r in rows if r["family"] == "fmu"
                     and r["case"] == case and r["scheme"] == scheme and r["alpha"] == alpha)
        use = [(s, e) for s, e in pts if s >= cfg.order_min_spp and e > cfg.order_min_error]
        order = float("nan")
        if len(use) >= 3:
            s, e = np.array(use, float).T
            order = float(-np.polyfit(np.log(s), np.log(e), 1)[0])
        finest = [e for _, e in pts[-3:]]
        floor = float(np.exp(np.mean(np.log(finest)))) if np.isfinite(order) and order < 0.5 else float("nan")
        out.append(dict(case=case, scheme=scheme, alpha=alpha, order=order, n_points=len(use),
                        h_range=f"T/{use[0][0]}..T/{use[-1][0]}" if use else "", error_floor=floor,
                        min_error=min(e for _, e in pts)))
    return out


def run_c_bench(exe: Path, lib: Path, cases, cfg: StudyConfig, out: Path) -> list[dict]:
    path = out / "stepper.csv"
    cmd = [str(exe), "--fmu-lib", str(lib), "--reps", str(cfg.c_reps), "--periods", "10",
           "--steps-per-period", ",".join(str(s) for s in cfg.c_spp), "--csv", str(path)]
    for c in cases:
        cmd += ["--case", c.c_arg()]
    res = subprocess.run(cmd, capture_output=True, text=True)
    if res.returncode != 0:
        raise RuntimeError(f"bench_stepper failed ({res.returncode}): {res.stderr.strip()}")
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        for k in ("alpha", "steps_per_period", "periods", "steps", "bare_ns_per_step", "fmu_ns_per_step",
                  "fmu_over_bare", "value"):
            r[k] = float(r[k]) if r[k] not in ("", None) else float("nan")
    return rows


def host_overhead(fmu, case, c_rows: list[dict], budget: float) -> list[dict]:
    """The short run bench_stepper times through the fmi2 functions (first case, located, h = T/50,
    one period, read x), timed from Python: the difference is the host's overhead per run."""
    from dryfriction.drivers.oscillator import Settings
    from fmu_runs import LeanRunner, api_run, best_time

    p = case.oscillator
    st = Settings(h=p.period / 50, alpha=-0.1, scheme="located")
    lean = LeanRunner(fmu)
    lean.prepare(p, st)
    t_api, r1 = best_time(lambda: api_run(fmu, p, st, p.period), budget, min_reps=200, max_reps=5000)
    t_lean, r2 = best_time(lambda: lean.run(p.period), budget, min_reps=200, max_reps=5000)
    c_run = next(r["value"] for r in c_rows if r["kind"] == "fmi2_run") * 1e-9
    return [dict(kind="host_overhead", x=1, steps=50, seconds_api=t_api, seconds_lean=t_lean, reps=min(r1, r2),
                 c_fmi2_run_seconds=c_run, overhead_api_us=(t_api - c_run) * 1e6,
                 overhead_lean_us=(t_lean - c_run) * 1e6)]


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    if args.report_only:
        meta = json.loads((args.out / "meta.json").read_text())
        cfg = StudyConfig.make(bool(meta["quick"]))
        args.md.parent.mkdir(parents=True, exist_ok=True)
        render(args, cfg, meta)
        sys.stderr.write(f"report rebuilt: {args.md}\n")
        return 0
    cfg = StudyConfig.make(args.quick)

    import numpy as np
    from tqdm import tqdm

    from cases import CASES
    from dryfriction.references.exact import solve_exact
    from dryfriction.drivers.oscillator import OscillatorFMU2
    from peers import peer_settings
    import scaling

    t_start = time.perf_counter()
    load_start = os.getloadavg()
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    args.md.parent.mkdir(parents=True, exist_ok=True)

    fmu = OscillatorFMU2(args.fmu)
    phases: dict[str, float] = {}
    t_phase = time.perf_counter()

    def phase(name: str) -> None:
        nonlocal t_phase
        now = time.perf_counter()
        phases[name] = now - t_phase
        t_phase = now

    try:
        exacts = {}
        case_rows = []
        for c in CASES:
            p = c.oscillator
            ex = solve_exact(p, cfg.periods * p.period)
            modes = ex.modes()
            tt = np.linspace(0.0, cfg.periods * p.period, 20001)
            xs, _, _, ms = ex.evaluate(tt)
            stuck = float(np.mean(ms == 0))
            exacts[c.name] = ex
            case_rows.append(dict(case=c.name, lam=c.lam, mu_s_sigma=c.mu_s_sigma, chi=c.chi, zeta=c.zeta,
                                  m=p.m, k=p.k, c=p.c, P0=p.P0, omega=p.omega, N=p.N, mu_s=p.mu_s,
                                  period_s=p.period, periods=cfg.periods, exact_stick_share=stuck,
                                  exact_stick_phases=int(np.sum(modes == 0)), exact_switches=len(modes) - 1,
                                  exact_zmax=float(np.max(np.abs(xs))) * p.k / abs(p.P0),
                                  why=c.why))
        write_csv(out / "cases.csv", case_rows)
        phase("exact solutions")

        n_fmu = len(CASES) * (3 * len(cfg.alphas) * len(cfg.spp) + 1)
        with tqdm(total=n_fmu, desc="FMU sweep", unit="run", file=sys.stderr) as bar:
            fmu_rows = fmu_sweep(fmu, cfg, CASES, exacts, bar)
        phase("FMU sweep")
        with tqdm(total=len(CASES) * len(peer_settings(cfg.quick)), desc="scipy peers", unit="run",
                  file=sys.stderr) as bar:
            peer_rows = peer_sweep(cfg, CASES, exacts, bar)
        phase("scipy peers")
        if not args.no_siconos:
            import siconos_study

            sys.stderr.write("Siconos on the cases at chi = 1 ...\n")
            write_csv(out / "siconos.csv", siconos_study.study_rows(cfg.quick, cfg.periods, sys.stderr, str(args.fmu)))
            phase("Siconos")
        elif (out / "siconos.csv").exists():
            (out / "siconos.csv").unlink()  # not a stale one from an earlier run
        rows = fmu_rows + peer_rows
        write_csv(out / "work_precision.csv", rows)
        orders = observed_orders(rows, cfg)
        write_csv(out / "orders.csv", orders)

        lib = scaling.fmu_library_path(fmu)
        c_rows = run_c_bench(args.bench_stepper, lib, CASES, cfg, out)
        phase("C benchmark")

        sys.stderr.write("cost growth, host overhead, memory ...\n")
        ref = CASES[0]
        p_ref = ref.oscillator
        budget = 0.1 if cfg.quick else 0.5
        scal = scaling.cost_vs_periods(fmu, p_ref, "located", -0.1, 1000, cfg.periods_sweep, budget)
        scal += scaling.cost_vs_steps(fmu, p_ref, "located", -0.1, 10, cfg.spp_sweep, budget)
        scal += host_overhead(fmu, ref, c_rows, 0.5 if not cfg.quick else 0.1)
        phase("cost growth and host overhead")
        if not args.no_dask:
            sys.stderr.write("Dask throughput ...\n")
            scal += scaling.parallel_baseline()
            scal += scaling.dask_throughput(str(args.fmu), (1, 2), cfg.dask_points, cfg.dask_batch,
                                            cfg.dask_periods, cfg.dask_spp, cfg.dask_reps)
            scal += scaling.parallel_baseline()
            phase("Dask")
        write_csv(out / "scaling.csv", scal)
        mem = scaling.memory_rows(fmu, p_ref, cfg.mem_instances, cfg.long_steps)
        c_bytes = next(r["value"] for r in c_rows if r["kind"] == "instance_bytes")
        mem.insert(0, dict(kind="c_bytes_per_instance", value=c_bytes, unit="bytes",
                           note="allocated by fmi2Instantiate through the host's allocateMemory (bench_stepper)"))
        write_csv(out / "memory.csv", mem)
        phase("memory")

        meta = dict(phases=phases, quick=cfg.quick, periods=cfg.periods, load_start=load_start,
                    load_end=os.getloadavg(), fmu=str(args.fmu),
                    cmd="python bench/work_precision.py" + (" --quick" if cfg.quick else "")
                    + (" --no-siconos" if args.no_siconos else "")
                    + f" --out {args.out}" + (f" --md {args.md}" if args.md != args.out / "RESULTS.md" else ""))
        meta["seconds"] = time.perf_counter() - t_start
        meta["date"] = time.strftime("%Y-%m-%d %H:%M")
        from report import _machine

        meta["machine"] = _machine()
        write_json(out / "meta.json", meta)
        render(args, cfg, meta)
        phase("plots and report")
        sys.stderr.write(f"done in {meta['seconds']:.0f} s: {args.md}\n")
    finally:
        fmu.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
