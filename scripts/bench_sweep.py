#!/usr/bin/env python3
"""Speed of the full Fig. 8/9 study (h = T/1000) against the stepper's limit.

    python scripts/bench_sweep.py [--quick] [--workers N] [--out DIR] [--fmu PATH] [--build-dir DIR]
                                  [--sample N] [--resume] [--set key=value ...]

The benchmark runs the 268,960 runs of the speed goal: 160 values of chi x 41 x 41 initial
conditions (``sweep.chi.num=160``; the study's config has 80 values of chi, 134,480 runs, which
``--set sweep.chi.num=80`` benchmarks; ``--quick`` the CI-sized config).

Runs ``dryfriction study fig8_9`` (its NetCDF and PNGs land in ``<out>/fig8_9/``) and reports,
measured in the same run:

- wall time (including the LocalCluster start), runs per second;
- the limit: total internal steps x the bare stepper's ns per step / workers. The bare stepper is
  ``dfo_advance`` from the static physics library ``<build>/libdfo_physics.a``, driven by a tiny C
  loop compiled here, on a stratified sample of the sweep's own runs (same parameters, initial
  conditions, window and step), run as one process per worker at once so that it sees the same
  contention for the cores as the sweep; if no C compiler or library is at hand, the same sample
  through the FMU, one ``fmi2DoStep`` per run, in this process (a proxy that includes the per-run
  FMI overhead);
- the ratio wall / limit, and the per-run cost of the lean FMI runner against the bare loop.

The sample is timed before and after the sweep (the machine may be shared); the faster of the two
is the limit. The CPU-time ratio (workers' task CPU seconds over the bare loop's CPU seconds for
the same steps) is the figure that does not depend on other jobs.
The report goes to stdout and ``<out>/bench/bench_sweep.json``. Not a test: nothing is asserted.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from dryfriction import model
from dryfriction.cli.options import make_parser
from dryfriction.atomic import atomic_write_text
from dryfriction.drivers.oscillator import default_fmu_path
from dryfriction.studies import effective_config, run_study
from dryfriction.studies.fig8_9_bifurcation import spec as fig8_9_spec
from dryfriction.sweep import BatchRunner

ROOT = Path(__file__).resolve().parents[1]

C_DRIVER = r"""
#include "newmark.h"
#include "oscillator.h"
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
/* rows of 16 doubles (m k c P0 omega phi N mu_s chi x0 v0 h alpha t_obs_start t_obs_stop t_stop)
 * on stdin; prints: wall seconds, internal steps, checksum, CPU seconds (of dfo_advance only) */
int main(int argc, char **argv)
{
    int scheme = argc > 1 ? atoi(argv[1]) : 3;
    size_t cap = 1024, n = 0;
    double *rows = malloc(cap * 16 * sizeof(double));
    while (fread(rows + n * 16, sizeof(double), 16, stdin) == 16) {
        if (++n == cap) { cap *= 2; rows = realloc(rows, cap * 16 * sizeof(double)); }
    }
    double secs = 0.0, cpu = 0.0, check = 0.0;
    long long steps = 0;
    for (size_t i = 0; i < n; i++) {
        const double *r = rows + i * 16;
        dfo_params p = {0};
        p.m = r[0]; p.k = r[1]; p.c = r[2]; p.P0 = r[3]; p.omega = r[4]; p.phi = r[5]; p.N = r[6];
        p.mu_s = r[7]; p.chi = r[8]; p.x0 = r[9]; p.v0 = r[10]; p.h = r[11]; p.alpha = r[12];
        p.t_obs_start = r[13]; p.t_obs_stop = r[14];
        p.scheme = scheme; p.frictionUpdates = 1; p.observe = 1; p.fastPaths = 1;
        dfo_model M;
        dfo_inputs u = {0};
        dfo_state s;
        dfo_model_init(&M, &p);
        dfo_start(&M, &u, 0.0, &s);
        struct timespec a, b, ca, cb;
        clock_gettime(CLOCK_MONOTONIC, &a);
        clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ca);
        if (dfo_advance(&M, &u, &s, r[15], NULL, NULL) != DFO_OK) { fprintf(stderr, "run %zu failed\n", i); return 1; }
        clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &cb);
        clock_gettime(CLOCK_MONOTONIC, &b);
        secs += (double)(b.tv_sec - a.tv_sec) + 1e-9 * (double)(b.tv_nsec - a.tv_nsec);
        cpu += (double)(cb.tv_sec - ca.tv_sec) + 1e-9 * (double)(cb.tv_nsec - ca.tv_nsec);
        steps += s.n;
        check += s.x_max - s.x_min;
    }
    printf("%.9f %lld %.17g %.9f\n", secs, steps, check, cpu);
    free(rows);
    return 0;
}
"""


def build_driver(build_dir: Path, workdir: Path) -> Path | None:
    lib = build_dir / "libdfo_physics.a"
    cc = shutil.which("cc") or shutil.which("gcc")
    if not lib.is_file() or cc is None:
        return None
    src = workdir / "bare_loop.c"
    exe = workdir / "bare_loop"
    src.write_text(C_DRIVER)
    r = subprocess.run([cc, "-O2", "-std=c99", "-D_POSIX_C_SOURCE=199309L", *(f"-I{d}" for d in sorted((ROOT / 'fmu_src').glob('*/')) + sorted((ROOT / 'fmu_src' / 'models').glob('*/'))), str(src),
                        str(lib), "-lm", "-o", str(exe)], capture_output=True, text=True)
    if r.returncode != 0:
        print(f"note: could not build the bare loop ({r.stderr.strip().splitlines()[-1:]}); using the FMU proxy",
              file=sys.stderr)
        return None
    return exe


def run_bare(exe: Path, rows: np.ndarray, scheme: int, procs: int = 1) -> tuple[float, float, float]:
    """(wall s, internal steps, CPU s) of the bare loop over the rows, run as ``procs`` processes at
    once on interleaved parts of the rows (the contention the sweep's workers see)."""
    parts = [np.ascontiguousarray(rows[i::procs]) for i in range(procs)]
    running = []
    for part in parts:
        p = subprocess.Popen([str(exe), str(scheme)], stdin=subprocess.PIPE, stdout=subprocess.PIPE)
        running.append(p)
    for p, part in zip(running, parts):
        assert p.stdin is not None
        p.stdin.write(part.tobytes())
        p.stdin.close()
    secs = steps = cpu = 0.0
    for p in running:
        assert p.stdout is not None
        out = p.stdout.read().decode().split()
        if p.wait() != 0:
            raise RuntimeError("the bare loop failed")
        secs += float(out[0])
        steps += int(out[1])
        cpu += float(out[3])
    return secs, steps, cpu


def bare_ns_per_step(exe: Path, rows: np.ndarray, scheme: int, procs: int = 1) -> tuple[float, float]:
    """(wall ns per internal step, CPU ns per internal step) of the bare loop over the rows."""
    secs, steps, cpu = run_bare(exe, rows, scheme, procs)
    return secs / steps * 1e9, cpu / steps * 1e9


def fmu_ns_per_step(runner: BatchRunner, rows: np.ndarray, steps: float) -> tuple[float, float]:
    """(ns per nominal internal step, us per run) through the FMU (lean runner, one doStep per run)."""
    t = time.perf_counter()
    runner.run(rows)
    dt = time.perf_counter() - t
    return dt / steps * 1e9, dt / rows.shape[0] * 1e6


def main() -> int:
    ap = make_parser("bench_sweep.py", __doc__.split("\n\n")[0], exit=True)
    ap.add_argument("--quick", action="store_true", help="the quick fig8_9 (CI-sized)")
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--out", default="results")
    ap.add_argument("--fmu", default=None)
    ap.add_argument("--build-dir", default=None, help="CMake build dir with libdfo_physics.a (default: the FMU's)")
    ap.add_argument("--sample", type=int, default=320, help="runs in the limit's sample")
    ap.add_argument("--resume", action="store_true", help="keep finished chunks (default: start afresh)")
    ap.add_argument("--set", dest="sets", action="append", default=[], metavar="KEY=VALUE",
                    help="override a value of configs/fig8_9.toml (as for dryfriction study)")
    a = ap.parse_args()
    if a.workers < 1:
        print("bench_sweep: error: --workers must be >= 1", file=sys.stderr)
        return 2
    fmu = Path(a.fmu) if a.fmu else default_fmu_path()
    if not fmu.is_file():
        print(f"bench_sweep: error: FMU not found: {fmu}", file=sys.stderr)
        return 2
    build_dir = Path(a.build_dir) if a.build_dir else fmu.parent
    # the speed goal's 268,960 runs unless quick; a --set of the user's comes later and wins
    sets = ([] if a.quick else ["sweep.chi.num=160"]) + list(a.sets)

    try:
        cfg = effective_config("fig8_9", quick=a.quick, sets=sets)
    except ValueError as e:
        print(f"bench_sweep: error: {e}", file=sys.stderr)
        return 2
    sp, _ = fig8_9_spec(cfg)
    num = cfg["numerics"]
    steps_per_run = cfg["sweep"]["periods"] * num["steps_per_period"]
    total_steps = sp.n_runs * steps_per_run
    idx = np.unique(np.linspace(0, sp.n_runs - 1, min(a.sample, sp.n_runs)).round().astype(int))
    sample = sp.params[idx]
    scheme = model.default().scheme_value(num["scheme"])

    work = Path(tempfile.mkdtemp(prefix="bench-sweep-"))
    try:
        exe = build_driver(build_dir, work)
        runner = BatchRunner(fmu, sp.settings)
        runner.run(sample[:4])  # warm up

        def measure() -> dict[str, float]:
            m = {}
            if exe is not None:
                m["bare_ns_per_step"], m["bare_cpu_ns_per_step"] = bare_ns_per_step(exe, sample, scheme, a.workers)
            m["fmu_ns_per_step"], m["fmu_us_per_run"] = fmu_ns_per_step(runner, sample, idx.size * steps_per_run)
            return m

        before = measure()
        print(f"limit sample ({idx.size} runs of the sweep) before: {before}", flush=True)

        chunk_dir = Path(a.out) / "fig8_9" / "chunks"
        if not a.resume and chunk_dir.exists():
            shutil.rmtree(chunk_dir)
        t0 = time.perf_counter()
        res = run_study("fig8_9", quick=a.quick, out=a.out, workers=a.workers, fmu=fmu, sets=sets)
        wall = time.perf_counter() - t0
        st = res.stats[0]

        after = measure()
        print(f"limit sample after: {after}", flush=True)
        runner.close()
    finally:
        shutil.rmtree(work, ignore_errors=True)

    key = "bare_ns_per_step" if "bare_ns_per_step" in before else "fmu_ns_per_step"
    cpu_ns = (0.5 * (before["bare_cpu_ns_per_step"] + after["bare_cpu_ns_per_step"])
              if "bare_cpu_ns_per_step" in before else float("nan"))
    computed_steps = steps_per_run * sum(min(sp.chunk_runs, sp.n_runs - i * sp.chunk_runs)
                                         for i in range(sp.n_chunks)) * (st.computed / max(sp.n_chunks, 1))
    ns = min(before[key], after[key])  # the limit: the stepper's speed when the machine lets it run
    limit = total_steps * ns * 1e-9 / a.workers
    fmu_ns = 0.5 * (before["fmu_ns_per_step"] + after["fmu_ns_per_step"])
    report = {
        "study": "fig8_9" + (" --quick" if a.quick else ""),
        "runs": sp.n_runs,
        "internal_steps": total_steps,
        "workers": a.workers,
        "cores": os.cpu_count(),
        "chunks_computed": st.computed,
        "chunks_loaded": st.loaded,
        "wall_s": wall,
        "sweep_wall_s": st.wall,
        "cluster_start_s": st.startup,
        "runs_per_s": sp.n_runs / wall,
        "limit_source": "bare dfo_advance loop (libdfo_physics.a)" if key == "bare_ns_per_step"
                        else "FMU, one fmi2DoStep per run (proxy)",
        "ns_per_step_limit": ns,
        "ns_per_step_fmu_lean_runner": fmu_ns,
        "fmu_overhead_vs_bare": fmu_ns / ns,
        "limit_s": limit,
        "ratio_to_limit": wall / limit,
        "bare_cpu_ns_per_step": cpu_ns,
        "task_cpu_s": st.task_cpu,
        "task_wall_s": st.task_wall,
        "cpu_ratio_tasks_to_bare": st.task_cpu / (computed_steps * cpu_ns * 1e-9) if st.computed else float("nan"),
        "goal": "268,960 runs in < 180 s, within 1.5x of the limit",
        "wall_s_for_268960_runs_at_this_rate": wall * 268960 / sp.n_runs,
        "ns_per_step_needed_for_268960_runs_in_3_min": 180.0 * a.workers / (268960 * steps_per_run) * 1e9,
        "sample_before": before,
        "sample_after": after,
        "load_average": os.getloadavg(),
    }
    out = Path(a.out) / "bench"
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_text(out / "bench_sweep.json", json.dumps(report, indent=2) + "\n")
    print(f"\nFig. 8/9 sweep: {sp.n_runs:,} runs, {total_steps:.3e} internal steps, {a.workers} workers")
    print(f"  wall {wall:.1f} s (sweep {st.wall:.1f} s, of which LocalCluster start {st.startup:.1f} s), "
          f"{sp.n_runs / wall:,.0f} runs/s")
    print(f"  limit {limit:.1f} s = steps x {ns:.1f} ns/step ({report['limit_source']}) / {a.workers}")
    print(f"  ratio to the limit {wall / limit:.2f} (goal <= 1.5); FMU lean runner {fmu_ns:.1f} ns/step "
          f"= {fmu_ns / ns:.2f} x bare")
    print(f"  CPU time: the workers' tasks {st.task_cpu:.1f} s = {report['cpu_ratio_tasks_to_bare']:.3f} x the bare "
          f"loop's CPU time for the same steps ({cpu_ns:.1f} CPU ns/step; independent of machine load)")
    print(f"  268,960 runs at this rate: {report['wall_s_for_268960_runs_at_this_rate']:.0f} s; 3 minutes for them "
          f"would need {180.0 * a.workers / (268960 * steps_per_run) * 1e9:.1f} ns/step")
    print(f"  report: {out / 'bench_sweep.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
