"""How the FMU's cost grows: with the number of periods, with the steps per period, with
the number of Dask workers; and what it costs in memory.

Every function here returns plain rows (dicts) for the study's CSV; nothing is printed.
"""

from __future__ import annotations

import gc
import os
import time
import tracemalloc
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from dryfriction.drivers.oscillator import OscillatorFMU2, Settings
from dryfriction.params import Oscillator

from fmu_runs import LeanRunner, api_run, best_time


# ---------------------------------------------------------------------------- time vs problem size

def cost_vs_periods(fmu: OscillatorFMU2, p: Oscillator, scheme: str, alpha: float, steps_per_period: int,
                    periods: Sequence[int], budget_s: float) -> list[dict]:
    """Run time (api and lean) against the number of periods at a fixed step."""
    lean = LeanRunner(fmu)
    st = Settings(h=p.period / steps_per_period, alpha=alpha, scheme=scheme)
    lean.prepare(p, st)
    rows = []
    for n in periods:
        t_end = n * p.period
        t_api, r_api = best_time(lambda: api_run(fmu, p, st, t_end), budget_s)
        t_lean, r_lean = best_time(lambda: lean.run(t_end), budget_s)
        rows.append(dict(kind="periods", x=n, steps=n * steps_per_period, seconds_api=t_api,
                         seconds_lean=t_lean, reps=min(r_api, r_lean)))
    return rows


def cost_vs_steps(fmu: OscillatorFMU2, p: Oscillator, scheme: str, alpha: float, periods: int,
                  steps_per_period: Sequence[int], budget_s: float) -> list[dict]:
    """Run time (api and lean) against the steps per period over a fixed horizon."""
    lean = LeanRunner(fmu)
    rows = []
    for spp in steps_per_period:
        st = Settings(h=p.period / spp, alpha=alpha, scheme=scheme)
        lean.prepare(p, st)
        t_end = periods * p.period
        t_api, r_api = best_time(lambda: api_run(fmu, p, st, t_end), budget_s)
        t_lean, r_lean = best_time(lambda: lean.run(t_end), budget_s)
        rows.append(dict(kind="steps_per_period", x=spp, steps=periods * spp, seconds_api=t_api,
                         seconds_lean=t_lean, reps=min(r_api, r_lean)))
    return rows


def linear_fit(x: Sequence[float], y: Sequence[float]) -> tuple[float, float, float]:
    """Least-squares y = a + b x with relative weights 1/y: (a, b, worst relative residual)."""
    xa, ya = np.asarray(x, float), np.asarray(y, float)
    b, a = np.polyfit(xa, ya, 1, w=1.0 / ya)
    res = float(np.max(np.abs(a + b * xa - ya) / ya))
    return float(a), float(b), res


# ---------------------------------------------------------------------------- Dask throughput

def _sweep_batch(fmu_path: str, points: list[tuple[float, ...]], periods: int, steps_per_period: int) -> list[float]:
    """Runs on a Dask worker: one OscillatorFMU2 per worker process, reused for every point."""
    from distributed import get_worker

    w = get_worker()
    fmu = getattr(w, "_dfo_bench_fmu", None)
    if fmu is None:
        fmu = OscillatorFMU2(fmu_path)
        w._dfo_bench_fmu = fmu
    out = []
    for lam, mss, chi, zeta in points:
        p = Oscillator.from_nondimensional(lam, mss, chi, zeta)
        st = Settings(h=p.period / steps_per_period)
        obs = fmu.observables(p, periods * p.period, 0.0, settings=st)
        out.append(obs["x_max"])
    return out


def _close_worker_fmu(dask_worker: object) -> None:
    """Runs on every worker at the end: close its FMU (frees the instance, removes its unzipped copy)."""
    fmu = getattr(dask_worker, "_dfo_bench_fmu", None)
    if fmu is not None:
        fmu.close()
        dask_worker._dfo_bench_fmu = None  # type: ignore[attr-defined]


def dask_throughput(fmu_path: str, workers: Sequence[int], n_points: int, batch: int, periods: int,
                    steps_per_period: int, reps: int = 2) -> list[dict]:
    """Sweep throughput (runs per second) with 1, 2, ... local worker processes; each worker reuses
    one FMU instance. The cluster start-up and a warm-up batch per worker are not timed; the sweep
    is timed reps times per cluster and the best time kept."""
    from distributed import Client, LocalCluster

    lams = np.linspace(0.3, 1.5, n_points)
    points = [(float(lam), 0.4, 0.7, 0.0) for lam in lams]
    batches = [points[i:i + batch] for i in range(0, len(points), batch)]
    rows = []
    for nw in workers:
        with LocalCluster(n_workers=nw, threads_per_worker=1, processes=True, dashboard_address=":0",
                          silence_logs=50) as cluster, Client(cluster) as client:
            client.wait_for_workers(nw)
            names = list(client.scheduler_info()["workers"])
            warm = [client.submit(_sweep_batch, fmu_path, points[:1], periods, steps_per_period,
                                  workers=[w], pure=False) for w in names]
            client.gather(warm)
            best = float("inf")
            for _ in range(reps):
                t0 = time.perf_counter()
                futs = [client.submit(_sweep_batch, fmu_path, b, periods, steps_per_period, pure=False)
                        for b in batches]
                res = client.gather(futs)
                best = min(best, time.perf_counter() - t0)
            client.run(_close_worker_fmu)
        n = sum(len(r) for r in res)
        rows.append(dict(kind="dask", x=nw, steps=n * periods * steps_per_period, seconds_api=best,
                         seconds_lean=float("nan"), reps=reps, runs=n, runs_per_second=n / best))
    return rows


def _spin(n: int) -> float:
    s = 0
    for i in range(n):
        s += i * i
    return float(s)


def parallel_baseline(n_loop: int = 2_000_000, reps: int = 3) -> list[dict]:
    """What parallelism the machine offers right now: the same CPU-bound pure-Python loop in one
    process, then in two at once (best of reps each). Context for the Dask numbers on a shared host."""
    import multiprocessing as mp

    rows = []
    with mp.get_context("spawn").Pool(2) as pool:
        pool.map(_spin, [1000, 1000])  # start both processes
        for nproc in (1, 2):
            best = float("inf")
            for _ in range(reps):
                t0 = time.perf_counter()
                pool.map(_spin, [n_loop] * nproc, chunksize=1)
                best = min(best, time.perf_counter() - t0)
            rows.append(dict(kind="cpu_baseline", x=nproc, steps=0, seconds_api=best, seconds_lean=float("nan"),
                             reps=reps, runs=nproc, runs_per_second=nproc / best))
    return rows


# ---------------------------------------------------------------------------- memory

def rss_bytes() -> int:
    """Resident set size of this process (Linux /proc)."""
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def memory_rows(fmu: OscillatorFMU2, p: Oscillator, n_instances: int, long_steps: int) -> list[dict]:
    """Bytes per FMU instance and RSS before/after long runs.

    - per fmi2 instance: n_instances more instances (dryfriction.fmi.fmi2.Instance) of the already
      unzipped FMU (the shared library is loaded once): RSS delta and Python-heap (tracemalloc)
      delta, per instance;
    - per OscillatorFMU2 (unzip + load a private copy + instantiate): RSS delta over a few;
    - a run of long_steps internal steps in one doStep, three times: RSS before and after each.
    """
    from dryfriction.fmi.fmi2 import Instance

    rows: list[dict] = []
    gc.collect()
    slaves = []
    tracemalloc.start()
    rss0 = rss_bytes()
    py0 = tracemalloc.get_traced_memory()[0]
    for i in range(n_instances):
        slaves.append(Instance(fmu.unzip_dir, fmu.md.guid, fmu.md.model_identifier, f"mem{i}"))
    rss1 = rss_bytes()
    py1 = tracemalloc.get_traced_memory()[0]
    tracemalloc.stop()
    rows.append(dict(kind="rss_per_fmi2_instance", value=(rss1 - rss0) / n_instances, unit="bytes",
                     note=f"RSS delta over {n_instances} fmi2 instances sharing one loaded library"))
    rows.append(dict(kind="python_heap_per_fmi2_instance", value=(py1 - py0) / n_instances, unit="bytes",
                     note="tracemalloc delta (Python objects of the FMI layer, not the C instance)"))
    for s in slaves:
        s.free()
    del slaves
    gc.collect()

    n_full = max(2, n_instances // 20)
    rss0 = rss_bytes()
    extra = [OscillatorFMU2(fmu.path) for _ in range(n_full)]
    rss1 = rss_bytes()
    rows.append(dict(kind="rss_per_OscillatorFMU", value=(rss1 - rss0) / n_full, unit="bytes",
                     note=f"RSS delta over {n_full} OscillatorFMU2 objects (each unzips and loads its own copy)"))
    for e in extra:
        e.close()
    del extra
    gc.collect()

    periods = 10
    st = Settings(h=periods * p.period / long_steps)
    before = rss_bytes()
    rows.append(dict(kind="rss_before_long_run", value=before, unit="bytes",
                     note=f"before {long_steps} internal steps in one doStep"))
    for k in range(3):
        api_run(fmu, p, st, periods * p.period)
        rows.append(dict(kind=f"rss_after_long_run_{k + 1}", value=rss_bytes(), unit="bytes",
                         note=f"after run {k + 1} of {long_steps} steps"))
    # the same steps as 1000 communication steps (fmpy call per doStep)
    fmu.start(p, st)
    for j in range(1, 1001):
        fmu.step_to(j * periods * p.period / 1000)
    rows.append(dict(kind="rss_after_long_run_1000_doSteps", value=rss_bytes(), unit="bytes",
                     note=f"after {long_steps} steps as 1000 doStep calls"))
    return rows


def fmu_library_path(fmu: OscillatorFMU2) -> Path:
    """The shared library the FMI layer loaded (what bench_stepper should time too)."""
    from dryfriction.fmi.fmi2 import library_path

    return library_path(fmu.unzip_dir, fmu.md.model_identifier)
