"""The sweep engine: parameter tables cut into chunks, run on Dask workers, with restart.

A :class:`SweepSpec` is a table of runs (rows of :data:`~dryfriction.sweep.runner.PARAM_COLUMNS`)
and the settings shared by all of them. :class:`Engine` runs it:

- the table is cut into chunks of ``chunk_runs`` rows; each chunk is one Dask task, run by a
  worker process on its own FMU instance (loaded once per process, reset per run);
- every finished chunk is written to ``<chunk_dir>/<sweep>-<key>/cNNNNN.chunk`` (temp name, then
  rename), where ``key`` hashes the table, the settings and the FMU binary, so a changed config or
  a rebuilt FMU never reuses stale chunks; the file names what it holds (the key, the chunk's
  index, a digest of its parameter rows) and carries a checksum of its data (:func:`chunk_bytes`);
- on a restart, the chunks on disk are loaded, only the missing ones are computed; a chunk file
  that is empty, unreadable, damaged (its checksum) or another chunk's (its key, index or rows) is
  recomputed with a one-line note;
- the work of the chunks to compute is estimated first (:func:`sweep_work`) and refused above the
  bound (:mod:`dryfriction.budget`);
- the result is the table of outputs in row order, whatever the number of workers: each run is
  independent and deterministic, so 1 or N workers give bit-identical numbers.

Workers: ``workers = 0`` runs in this process (no Dask), ``workers = N`` starts a
``LocalCluster`` of N single-threaded worker processes, ``scheduler = "host:port"`` uses an
existing Dask cluster (each task carries the FMU's bytes; the workers need this package installed).
The chunks are streamed, a few in flight, and a chunk whose worker was lost is submitted again
(:mod:`dryfriction.cluster`).
"""

from __future__ import annotations

import hashlib
import json
import logging
import shutil
import sys
import time
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..atomic import atomic_write_bytes
from ..budget import BOSSAK_PERIOD_STEPS, EXACT_PERIOD_STEPS, check_work
from ..diagnostics import emit_new, recorded
from .runner import OUTPUT_COLUMNS, PARAM_COLUMNS, run_batch_timed

__all__ = ["SweepSpec", "EngineOptions", "SweepStats", "SweepInterrupted", "Engine", "sweep_work", "chunk_bytes",
           "read_chunk", "save_chunk", "prune_stale", "CHUNK_MAGIC"]


class SweepInterrupted(RuntimeError):
    """The sweep stopped before all chunks were computed (``max_chunks`` reached)."""


@dataclass
class SweepSpec:
    """One sweep: a parameter table and the settings shared by its runs."""

    name: str
    params: np.ndarray
    settings: Mapping[str, Any] = field(default_factory=dict)
    chunk_runs: int = 1000

    def __post_init__(self) -> None:
        self.params = np.ascontiguousarray(self.params, dtype=np.float64)
        if self.params.ndim != 2 or self.params.shape[1] != len(PARAM_COLUMNS):
            raise ValueError(f"sweep {self.name}: params must have shape (n, {len(PARAM_COLUMNS)})")
        if self.chunk_runs < 1:
            raise ValueError(f"sweep {self.name}: chunk_runs must be >= 1")

    @property
    def n_runs(self) -> int:
        """The number of runs."""
        return int(self.params.shape[0])

    @property
    def n_chunks(self) -> int:
        """The number of chunks."""
        return -(-self.n_runs // self.chunk_runs)

    def chunk(self, i: int) -> np.ndarray:
        """The parameter rows of chunk ``i``."""
        return self.params[i * self.chunk_runs:(i + 1) * self.chunk_runs]

    def key(self, fmu_digest: str) -> str:
        """The sweep's key: a hash of its run table, its settings and the FMU binary's digest (chunks of
        another key are never reused)."""
        h = hashlib.sha256()
        h.update(self.params.tobytes())
        h.update(json.dumps(dict(self.settings), sort_keys=True).encode())
        h.update(str(self.chunk_runs).encode())
        h.update(fmu_digest.encode())
        return h.hexdigest()[:16]


@dataclass
class EngineOptions:
    """How a sweep runs: the FMU, the number of Dask workers (0: in this process) or a scheduler's address,
    the chunk size and the progress bar."""
    fmu: Path
    workers: int = 0                 # 0: in this process; N: LocalCluster of N processes
    scheduler: str | None = None     # address of an existing Dask scheduler
    progress: bool = True
    max_chunks: int | None = None    # compute at most this many new chunks (then SweepInterrupted)
    max_work: float | None = None    # bound of a sweep's work, steps (dryfriction.budget; None: the default)


@dataclass
class SweepStats:
    """What a sweep did: runs, chunks loaded from disk and computed, wall time."""
    name: str
    runs: int
    chunks: int
    loaded: int = 0
    computed: int = 0
    wall: float = 0.0
    startup: float = 0.0   # Dask client / LocalCluster start inside this sweep's wall time
    task_cpu: float = 0.0  # CPU seconds of the computed chunks' tasks (summed over workers)
    task_wall: float = 0.0  # wall seconds of the computed chunks' tasks (summed over workers)

    def line(self) -> str:
        """The statistics in one line."""
        rate = f", {self.runs / self.wall:,.0f} runs/s" if self.computed and self.wall > 0 else ""
        return (f"{self.name}: {self.runs:,} runs in {self.chunks} chunks "
                f"({self.loaded} loaded from disk, {self.computed} computed) in {self.wall:.1f} s{rate}")


#: the first bytes of a chunk file
CHUNK_MAGIC = b"DFOCHUNK 1\n"


def _digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def chunk_bytes(key: str, index: int, params: np.ndarray, out: np.ndarray) -> bytes:
    """A chunk file's bytes: :data:`CHUNK_MAGIC`, one JSON line naming what it holds (the sweep's
    key, the chunk's index, the digest of its parameter rows, its shape, the digest of its data),
    then the outputs (float64, little-endian, C order)."""
    data = np.ascontiguousarray(out, dtype="<f8").tobytes()
    head = {"key": key, "index": index, "params": _digest(np.ascontiguousarray(params, dtype="<f8").tobytes()),
            "shape": list(out.shape), "sha256": _digest(data)}
    return CHUNK_MAGIC + json.dumps(head, sort_keys=True).encode() + b"\n" + data


def read_chunk(path: Path, key: str, index: int, params: np.ndarray) -> tuple[np.ndarray | None, str]:
    """The outputs a chunk file holds, checked against what it must hold (the sweep's ``key``, the
    chunk ``index``, the digest of ``params``, the shape, the checksum of the data); else ``None``
    and why (``""`` when there is no file)."""
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        return None, ""
    except OSError as e:
        return None, f"unreadable ({e.strerror})"
    if not raw:
        return None, "empty"
    if not raw.startswith(CHUNK_MAGIC):
        return None, "not a chunk file"
    rest = raw[len(CHUNK_MAGIC):]
    nl = rest.find(b"\n")
    try:
        head = json.loads(rest[:nl]) if nl > 0 else None
    except ValueError:
        head = None
    if not isinstance(head, dict):
        return None, "its header is unreadable"
    data = rest[nl + 1:]
    shape = (params.shape[0], len(OUTPUT_COLUMNS))
    if head.get("sha256") != _digest(data) or head.get("shape") != list(shape) or len(data) != 8 * shape[0] * shape[1]:
        return None, "its checksum does not match (damaged or truncated)"
    if head.get("key") != key or head.get("index") != index or \
            head.get("params") != _digest(np.ascontiguousarray(params, dtype="<f8").tobytes()):
        return None, "it holds another chunk (its sweep, index or parameters differ)"
    return np.frombuffer(data, dtype="<f8").reshape(shape).astype(np.float64), ""


def save_chunk(path: Path, data: bytes) -> None:
    """Write a chunk file (temp name, then rename); a failure is one line naming the file and the
    cause (an :class:`OSError`)."""
    try:
        atomic_write_bytes(path, data)
    except OSError as e:
        raise OSError(f"cannot write the chunk {path}: {e.strerror or e}") from None


def prune_stale(chunk_root: Path, keep: set[Path]) -> None:
    """Remove the chunk folders of older configurations (or FMUs) of the sweeps in ``keep`` (called
    once the results they were superseded by are in place)."""
    names = {k.name[:-17] for k in keep}
    for old in Path(chunk_root).glob("*-*"):
        stem, _, suffix = old.name.rpartition("-")
        if old in keep or stem not in names or not old.is_dir():
            continue
        if len(suffix) == 16 and all(c in "0123456789abcdef" for c in suffix):
            shutil.rmtree(old, ignore_errors=True)


def sweep_work(spec: SweepSpec, chunks: list[int]) -> float:
    """The work of the given chunks of a sweep, steps (:mod:`dryfriction.budget`): each run's stop
    time over its step h (Bossak schemes), or over its excitation period times
    :data:`~dryfriction.budget.EXACT_PERIOD_STEPS` (the exact scheme)."""
    col = {n: j for j, n in enumerate(PARAM_COLUMNS)}
    exact = str(spec.settings.get("scheme", "")).lower() in ("exact", "4")
    total = 0.0
    for i in chunks:
        P = spec.chunk(i)
        periods = P[:, col["t_stop"]] * np.maximum(P[:, col["omega"]], 0.0) / (2.0 * np.pi)
        if exact:
            total += float(np.sum(periods)) * EXACT_PERIOD_STEPS
        else:   # t_stop / h, or the typical steps per period where h is derived (0)
            h = P[:, col["h"]]
            steps = np.where(h > 0, P[:, col["t_stop"]] / np.where(h > 0, h, 1.0), periods * BOSSAK_PERIOD_STEPS)
            total += float(np.sum(steps))
    return total


class Engine:
    """Runs sweeps; starts its Dask client lazily (only if some chunk must be computed)."""

    def __init__(self, options: EngineOptions) -> None:
        self.opt = options
        self.fmu_digest = hashlib.sha256(Path(options.fmu).read_bytes()).hexdigest()
        self._cluster: Any = None
        self.stats: list[SweepStats] = []
        #: the chunk folders of this engine's sweeps (the others of the same sweeps are stale)
        self.folders: set[Path] = set()
        #: one-line notes (a chunk file recomputed, and why)
        self.notes: list[str] = []
        self._new_chunks = 0
        self.startup = 0.0

    # ---- Dask ----
    def _ensure_client(self) -> Any:
        if self._cluster is None:
            from ..cluster import Cluster

            self._cluster = Cluster(self.opt.workers, self.opt.scheduler)
            self.startup = self._cluster.startup
        return self._cluster

    def close(self) -> None:
        """Close the Dask cluster the engine started, if any."""
        if self._cluster is not None:
            self._cluster.close()
            self._cluster = None

    def __enter__(self) -> "Engine":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @property
    def uses_dask(self) -> bool:
        """Whether sweeps run on Dask (workers or a scheduler) rather than in this process."""
        return bool(self.opt.scheduler) or self.opt.workers > 0

    # ---- chunks ----
    def _chunk_path(self, folder: Path, i: int) -> Path:
        return folder / f"c{i:05d}.chunk"

    def _compute_local(self, spec: SweepSpec, todo: list[int]) -> Iterator[tuple[int, Any]]:
        settings = dict(spec.settings)
        fmu = str(self.opt.fmu)
        for i in todo:
            yield i, run_batch_timed(fmu, settings, spec.chunk(i))

    def _compute_dask(self, spec: SweepSpec, todo: list[int]) -> Iterator[tuple[int, Any]]:
        from ..cluster import stream

        cluster = self._ensure_client()
        settings = dict(spec.settings)
        fmu = cluster.fmu_arg(self.opt.fmu)
        seen: set[str] = set()
        # each task is built when it is submitted: its chunk's rows only (a few in flight)
        tasks = ((i, (run_batch_timed, fmu, settings, spec.chunk(i))) for i in todo)
        for i, (result, msgs) in stream(cluster, recorded, tasks):
            emit_new(msgs, seen)  # the worker's FMU warnings, once each
            yield i, result

    def note(self, msg: str) -> None:
        """A one-line note on stderr (kept in :attr:`notes`)."""
        self.notes.append(msg)
        print(f"note: {msg}", file=sys.stderr, flush=True)

    def run(self, spec: SweepSpec, chunk_root: Path) -> np.ndarray:
        """All outputs of the sweep (shape ``(n_runs, len(OUTPUT_COLUMNS))``), loading finished
        chunks from ``chunk_root`` and writing new ones there."""
        t0 = time.perf_counter()
        key = spec.key(self.fmu_digest)
        folder = Path(chunk_root) / f"{spec.name}-{key}"
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise OSError(f"cannot create the chunk folder {folder}: {e.strerror or e}") from None
        self.folders.add(folder)
        for tmp in folder.glob(".c*.tmp"):  # half-written chunks of a killed run
            tmp.unlink(missing_ok=True)
        # the chunks of an older config or FMU of the same sweep stay until the results that
        # replace them are in place (prune_stale, called by the study)

        out = np.empty((spec.n_runs, len(OUTPUT_COLUMNS)))
        stats = SweepStats(spec.name, spec.n_runs, spec.n_chunks)
        todo: list[int] = []
        for i in range(spec.n_chunks):
            params = spec.chunk(i)
            rows = params.shape[0]
            path = self._chunk_path(folder, i)
            arr, why = read_chunk(path, key, i, params)
            if arr is None:
                if why:
                    self.note(f"chunk {path}: {why}; recomputed")
                todo.append(i)
            else:
                out[i * spec.chunk_runs:i * spec.chunk_runs + rows] = arr
                stats.loaded += 1
        if todo:
            runs = sum(spec.chunk(i).shape[0] for i in todo)
            check_work(sweep_work(spec, todo), f"{runs:,} runs of sweep {spec.name}", self.opt.max_work)
            # the chunks and the dataset made of them: found before the work when the disk lacks room
            need = 2.0 * runs * len(OUTPUT_COLUMNS) * 8 + 400.0 * len(todo)
            free = shutil.disk_usage(folder).free
            if free < need:
                raise OSError(f"cannot write the chunks of sweep {spec.name} into {folder}: {free / 1e6:.3g} MB free, "
                              f"about {need / 1e6:.3g} MB needed")

        if todo:
            budget = None if self.opt.max_chunks is None else max(self.opt.max_chunks - self._new_chunks, 0)
            done_runs = spec.n_runs - sum(spec.chunk(i).shape[0] for i in todo)
            bar = None
            if self.opt.progress:
                from tqdm import tqdm

                bar = tqdm(total=spec.n_runs, initial=done_runs, unit="run", desc=spec.name,
                           file=sys.stderr, dynamic_ncols=True, smoothing=0.05)
            compute = self._compute_dask if self.uses_dask else self._compute_local
            if self.uses_dask and self._cluster is None:
                self._ensure_client()
                stats.startup = self.startup
            interrupted = False
            try:
                if budget == 0:
                    interrupted = True
                else:
                    for i, (arr, cpu, wall) in compute(spec, todo):
                        stats.task_cpu += cpu
                        stats.task_wall += wall
                        save_chunk(self._chunk_path(folder, i), chunk_bytes(key, i, spec.chunk(i), arr))
                        rows = arr.shape[0]
                        out[i * spec.chunk_runs:i * spec.chunk_runs + rows] = arr
                        stats.computed += 1
                        self._new_chunks += 1
                        if bar is not None:
                            bar.update(rows)
                        if budget is not None and stats.computed >= budget:
                            interrupted = stats.computed < len(todo)
                            break
            finally:
                if bar is not None:
                    bar.close()
            if interrupted:
                stats.wall = time.perf_counter() - t0
                self.stats.append(stats)
                raise SweepInterrupted(
                    f"{spec.name}: stopped after {stats.computed} new chunk(s) "
                    f"({stats.loaded + stats.computed} of {spec.n_chunks} done); run again to finish")
        stats.wall = time.perf_counter() - t0
        self.stats.append(stats)
        return out
