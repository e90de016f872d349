"""Speed of the exact scheme against `located` at h = T/1000, side by side in one run.

    python scripts/bench_exact.py [--reps 15] [--fig89-sample 200] [--build-dir build] [--csv FILE]

A tiny C loop (compiled here against ``<build>/libdfo_physics.a``) times ``dfo_advance`` for whole
runs: one call per run of 30 excitation periods from the case's initial state with the in-FMU
observables on (extremes over the 30th period, as a sweep run does). Every run is timed for both
schemes alternately, ``--reps`` times, and the minimum is kept (CPU time of the thread,
CLOCK_THREAD_CPUTIME_ID: on a shared machine less sensitive to the load than wall time). Cases: the five work-precision
cases (bench/cases.py) from rest, and the Fig. 8/9 workload (lambda 0.5, mu_s sigma 0.6, zeta 0,
chi in 0.02 ... 1.6, initial conditions in [-2, 2]^2): a stratified sample of its runs. Prints a
markdown table: microseconds per run and per excitation period for each scheme, the ratio, and
the events per period of the exact scheme. No timing is asserted anywhere.
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "bench"))
sys.path.insert(0, str(ROOT / "src"))

from cases import CASES  # noqa: E402

LOOP_C = r"""
#define _POSIX_C_SOURCE 199309L
#include "scheme.h"
#include "oscillator.h"
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

/* CPU time of this thread: what a run costs, less sensitive than wall time to the load of a shared machine */
static double now(void) { struct timespec ts; clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts); return ts.tv_sec + 1e-9 * ts.tv_nsec; }

/* one run: 30 periods in one call, observables over the last period; returns seconds */
static double run(const dfo_params *p, double periods, long long *events, double *xmax)
{
    dfo_model M; dfo_inputs u; dfo_state s;
    memset(&u, 0, sizeof u);
    dfo_model_init(&M, p);
    dfo_start(&M, &u, 0.0, &s);
    const double T = 2.0 * DFO_PI / p->omega;
    const double t0 = now();
    const dfo_status st = dfo_advance(&M, &u, &s, periods * T, NULL, NULL);
    const double t1 = now();
    if (st != DFO_OK) { fprintf(stderr, "run failed: %s\n", dfo_status_text(st)); return -1.0; }
    *events = s.steps;
    *xmax = s.x_max;
    return t1 - t0;
}

int main(void)
{
    /* stdin: lam mu_s_sigma chi zeta z0 dz0 periods spp reps; stdout: best_located best_exact events xmax_l xmax_e */
    double lam, mss, chi, zeta, z0, dz0, periods, spp; int reps;
    while (scanf("%lf %lf %lf %lf %lf %lf %lf %lf %d", &lam, &mss, &chi, &zeta, &z0, &dz0, &periods, &spp, &reps) == 9) {
        dfo_params p; memset(&p, 0, sizeof p);
        p.m = 1.0; p.k = 100.0; p.P0 = 1.0; p.mu_s = 0.4;
        const double w0 = 10.0;
        p.c = 2.0 * zeta * sqrt(p.k * p.m); p.omega = lam * w0; p.N = mss * p.P0 / p.mu_s; p.chi = chi;
        p.x0 = z0 * p.P0 / p.k; p.v0 = dz0 * p.P0 / p.k * w0;
        const double T = 2.0 * DFO_PI / p.omega;
        p.h = T / spp; p.alpha = -0.1; p.frictionUpdates = 1; p.fastPaths = 1; p.observe = 1;
        p.t_obs_start = (periods - 1.0) * T; p.t_obs_stop = 1e300;
        double best[2] = {1e30, 1e30}, xm[2] = {0, 0}; long long ev = 0, e2;
        for (int r = 0; r < reps; r++) {
            for (int k = 0; k < 2; k++) {
                p.scheme = k ? DFO_SCHEME_EXACT : DFO_SCHEME_LOCATED;
                const double dt = run(&p, periods, k ? &ev : &e2, &xm[k]);
                if (dt < 0) return 1;
                if (dt < best[k]) best[k] = dt;
            }
        }
        printf("%.9g %.9g %lld %.17g %.17g\n", best[0], best[1], ev, xm[0] * p.k / p.P0, xm[1] * p.k / p.P0);
        fflush(stdout);
    }
    return 0;
}
"""


def build_loop(build_dir: Path, work: Path) -> Path:
    lib = build_dir / "libdfo_physics.a"
    cc = shutil.which("cc") or shutil.which("gcc")
    if not lib.is_file() or cc is None:
        sys.exit(f"bench_exact: needs a C compiler and {lib} (cmake --build {build_dir})")
    src, exe = work / "loop.c", work / "loop"
    src.write_text(LOOP_C)
    r = subprocess.run([cc, "-O2", "-std=c99", *(f"-I{d}" for d in sorted((ROOT / 'fmu_src').glob('*/')) + sorted((ROOT / 'fmu_src' / 'models').glob('*/'))), str(src), str(lib), "-lm", "-o", str(exe)],
                       capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"bench_exact: compiling the loop failed: {r.stderr.strip().splitlines()[-1]}")
    return exe


def fig89_sample(n: int, seed: int = 1) -> list[tuple[float, float, float]]:
    """n runs of the Fig. 8/9 grid (chi, z0, dz0), stratified over chi."""
    rng = np.random.default_rng(seed)
    chis = np.linspace(0.02, 1.6, 80)
    grid = np.linspace(-2.0, 2.0, 41)
    out = []
    for i in range(n):
        chi = float(chis[(i * len(chis)) // n])
        out.append((chi, float(rng.choice(grid)), float(rng.choice(grid))))
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=15)
    ap.add_argument("--periods", type=float, default=30.0)
    ap.add_argument("--fig89-sample", type=int, default=200)
    ap.add_argument("--build-dir", default=str(ROOT / "build"))
    ap.add_argument("--csv", default=None)
    a = ap.parse_args(argv)
    if a.reps < 1 or a.fig89_sample < 1 or not a.periods > 0:
        sys.exit("bench_exact: --reps, --fig89-sample and --periods must be positive")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        exe = build_loop(Path(a.build_dir), Path(tmp))
        jobs: list[tuple[str, tuple[float, ...]]] = []
        for c in CASES:
            jobs.append((c.name, (c.lam, c.mu_s_sigma, c.chi, c.zeta, 0.0, 0.0)))
        for chi, z0, dz0 in fig89_sample(a.fig89_sample):
            jobs.append(("fig8_9", (0.5, 0.6, chi, 0.0, z0, dz0)))
        lines = "".join(" ".join(repr(v) for v in (*args, a.periods, 1000.0, a.reps)) + "\n" for _, args in jobs)
        r = subprocess.run([str(exe)], input=lines, capture_output=True, text=True)
        if r.returncode != 0:
            sys.exit(f"bench_exact: the loop failed: {r.stderr.strip()}")
        for (name, args), line in zip(jobs, r.stdout.splitlines()):
            tl, te, ev, xl, xe = line.split()
            rows.append((name, args, float(tl), float(te), int(ev), float(xl), float(xe)))
    print(f"| case | runs | located T/1000, us/run | exact, us/run | located us/period | exact us/period "
          f"| exact / located | events/period |")
    print("|---|---|---|---|---|---|---|---|")
    names = [c.name for c in CASES] + ["fig8_9"]
    for name in names:
        sel = [r for r in rows if r[0] == name]
        tl = np.mean([r[2] for r in sel]) * 1e6
        te = np.mean([r[3] for r in sel]) * 1e6
        ev = np.mean([r[4] for r in sel]) / a.periods
        print(f"| {name} | {len(sel)} | {tl:.1f} | {te:.2f} | {tl / a.periods:.2f} | {te / a.periods:.3f} "
              f"| 1/{tl / te:.0f} | {ev:.2f} |")
    if a.csv:
        with open(a.csv, "w") as f:
            f.write("case,lam,mu_s_sigma,chi,zeta,z0,dz0,located_s,exact_s,exact_events,zmax_located,zmax_exact\n")
            for name, args, tl, te, ev, xl, xe in rows:
                f.write(",".join([name, *(repr(v) for v in args), repr(tl), repr(te), str(ev), repr(xl), repr(xe)])
                        + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
