"""Batches of chaos runs on Dask workers (or in this process): one FMU instance per process.

The tasks take plain arrays and dicts and return arrays, so a chunk is one Dask task, streamed as
the sweep engine streams its chunks (:mod:`dryfriction.cluster`): the workers of a
LocalCluster read the FMU from its path, an external scheduler's tasks carry its bytes.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ...diagnostics import emit_new, recorded
from ...drivers.oscillator import OscillatorFMU2
from ...sweep.runner import PerProcess
from .attractors import period_of
from .lyapunov import benettin
from .maps import FMUMap, NDParams

__all__ = ["fmu_for", "lyapunov_rows", "orbit_tails", "transient_rows", "map_chunks", "concat", "ChunkStats"]

_FMUS: PerProcess[OscillatorFMU2] = PerProcess(OscillatorFMU2)


def fmu_for(fmu: str | bytes) -> OscillatorFMU2:
    """This process's FMU instance for ``fmu`` (a path or the FMU's bytes), loaded on first use."""
    return _FMUS.get(fmu)


def _map(fmu: str | bytes, nd: Mapping[str, float], num: Mapping[str, Any], chi: float) -> FMUMap:
    return FMUMap(fmu_for(fmu), NDParams.from_mapping(nd, chi=chi), int(num["steps_per_period"]),
                  str(num["scheme"]), float(num.get("alpha", -0.1)))


# ---- tasks --------------------------------------------------------------------------------------

def lyapunov_rows(fmu: str | bytes, nd: Mapping[str, float], num: Mapping[str, Any], lyap: Mapping[str, Any],
                  rows: np.ndarray, n_keep: int) -> dict[str, np.ndarray]:
    """Rows (chi, z0, dz0): Benettin's exponent and the last ``n_keep`` stroboscopic points."""
    n = rows.shape[0]
    out = {"lyapunov": np.empty(n), "stderr": np.empty(n), "half_difference": np.empty(n),
           "collapses": np.empty(n), "strobe": np.empty((n, n_keep, 2)), "cpu": np.zeros(1)}
    c0 = time.process_time()
    for i, (chi, z0, dz0) in enumerate(rows):
        r = benettin(_map(fmu, nd, num, float(chi)), float(z0), float(dz0), periods=int(lyap["periods"]),
                     transient=int(lyap["transient"]), d0=float(lyap["d0"]), renorm=int(lyap["renorm"]))
        out["lyapunov"][i], out["stderr"][i] = r.lyapunov_per_period, r.stderr_per_period
        out["half_difference"][i], out["collapses"][i] = r.half_difference, r.collapses
        out["strobe"][i] = r.strobe[-n_keep:]
    out["cpu"][0] = time.process_time() - c0
    return out


def orbit_tails(fmu: str | bytes, nd: Mapping[str, float], num: Mapping[str, Any], chi: float,
                ics: np.ndarray, transient: int, n_tail: int) -> dict[str, np.ndarray]:
    """Initial conditions (z0, dz0): stroboscopic points transient .. transient + n_tail - 1 of a
    continuous run from each (nan if the FMU failed)."""
    m = _map(fmu, nd, num, chi)
    out = np.full((ics.shape[0], n_tail, 2), np.nan)
    c0 = time.process_time()
    for i, (z0, dz0) in enumerate(ics):
        try:
            out[i] = m.orbit(float(z0), float(dz0), transient, n_tail)
        except RuntimeError:
            pass
    return {"tails": out, "cpu": np.array([time.process_time() - c0])}


def transient_rows(fmu: str | bytes, nd: Mapping[str, float], num: Mapping[str, Any], chi: float,
                   ics: np.ndarray, checkpoints: Sequence[int], tail: int, tol: float,
                   samples_per_period: int = 100) -> dict[str, np.ndarray]:
    """Initial conditions (z0, dz0), one continuous run each to max(checkpoints) periods: the mean
    amplitude and asymmetry over the period ending at every checkpoint (z sampled at T/
    ``samples_per_period``), the stroboscopic point there, and the transient length: the first
    period from which every stroboscopic point lies within ``tol`` of the periodic orbit of the
    last ``tail`` points (-1 if those are not periodic: no periodic attractor reached)."""
    m = _map(fmu, nd, num, chi)
    f, T = m.fmu, m.T
    n_end = int(max(checkpoints))
    cps = sorted(int(c) for c in checkpoints)
    k_amp, k_asym = np.full((ics.shape[0], len(cps)), np.nan), np.full((ics.shape[0], len(cps)), np.nan)
    k_pt = np.full((ics.shape[0], len(cps), 2), np.nan)
    tlen, period = np.full(ics.shape[0], -1.0), np.full(ics.shape[0], -1.0)
    c0 = time.process_time()
    for i, (z0, dz0) in enumerate(ics):
        m.start(float(z0), float(dz0))
        strobe = np.empty((n_end + 1, 2))
        strobe[0] = m.point()
        j = 0
        for k in range(1, n_end + 1):
            if j < len(cps) and k == cps[j]:
                zs = np.empty(samples_per_period)
                for s in range(1, samples_per_period + 1):
                    f.step_to((k - 1 + s / samples_per_period) * T)
                    zs[s - 1] = f.get(("x",))["x"] / m.z_scale
                k_amp[i, j], k_asym[i, j] = 0.5 * (zs.max() - zs.min()), 0.5 * (zs.max() + zs.min())
                strobe[k] = m.point()
                k_pt[i, j] = strobe[k]
                j += 1
            else:
                f.step_to(k * T)
                strobe[k] = m.point()
        p = period_of(strobe[-tail:], tol, min(32, tail // 2))
        period[i] = p
        if p:
            orbit = strobe[-p:]
            d = np.max(np.abs(strobe[:, None, :] - orbit[None, :, :]), axis=2).min(axis=1)
            off = np.nonzero(d > tol)[0]
            tlen[i] = 0 if off.size == 0 else off[-1] + 1
    return {"amplitude": k_amp, "asymmetry": k_asym, "point": k_pt, "transient": tlen, "period": period,
            "cpu": np.array([time.process_time() - c0])}


# ---- running chunks -----------------------------------------------------------------------------

@dataclass
class ChunkStats:
    """What a batch of chunked tasks cost: tasks, wall time, cluster start-up and the tasks' CPU time (s)."""
    tasks: int
    wall: float
    startup: float
    task_cpu: float


def map_chunks(func: Callable[..., dict[str, np.ndarray]], fmu_path: Path, chunks: Iterable[tuple[Any, ...]],
               workers: int = 0, scheduler: str | None = None, progress: bool = False,
               desc: str = "chaos", total: int | None = None) -> tuple[list[dict[str, np.ndarray]], ChunkStats]:
    """``func(fmu, *chunk)`` for every chunk, in order; on a LocalCluster of ``workers`` single-
    threaded processes (or ``scheduler``), or in this process if ``workers == 0`` and no scheduler.
    ``chunks`` may be a generator (``total``: its length, for the progress bar): the tasks are
    streamed, a few in flight at a time (:func:`dryfriction.cluster.stream`: no large graph,
    a task of a lost worker submitted again, Dask's logs and warnings silenced). The FMU warnings
    raised on a worker are recorded there and emitted again here, once each."""
    from ...cluster import Cluster, stream

    t0 = time.perf_counter()
    if total is None and isinstance(chunks, Sequence):
        total = len(chunks)
    results: dict[int, dict[str, np.ndarray]] = {}
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=total, unit="chunk", desc=desc, file=sys.stderr, dynamic_ncols=True)
    startup = 0.0
    try:
        if workers == 0 and not scheduler:
            for i, c in enumerate(chunks):
                results[i] = func(str(fmu_path), *c)
                if bar is not None:
                    bar.update(1)
        else:
            cluster = Cluster(workers, scheduler)
            try:
                startup = cluster.startup
                fmu = cluster.fmu_arg(fmu_path)
                seen: set[str] = set()
                tasks = ((i, (func, fmu, *c)) for i, c in enumerate(chunks))
                for i, (res, msgs) in stream(cluster, recorded, tasks):
                    results[i] = res
                    emit_new(msgs, seen)  # the worker's FMU warnings, once each
                    if bar is not None:
                        bar.update(1)
                global LAST_PEAK_RSS
                LAST_PEAK_RSS = cluster.peak_rss()
            finally:
                cluster.close()
    finally:
        if bar is not None:
            bar.close()
    out = [results[i] for i in sorted(results)]
    cpu = float(sum(float(r["cpu"].sum()) for r in out if "cpu" in r))
    return out, ChunkStats(len(out), time.perf_counter() - t0, startup, cpu)


#: each worker's peak resident memory (bytes, by worker address) of the last :func:`map_chunks` on
#: Dask (measured for docs/performance.md)
LAST_PEAK_RSS: dict[str, float] = {}


def concat(results: Iterable[Mapping[str, np.ndarray]], key: str) -> np.ndarray:
    """The arrays under ``key`` of every chunk's result, concatenated along the first axis in chunk order."""
    return np.concatenate([r[key] for r in results], axis=0)
