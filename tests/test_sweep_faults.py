"""Results that can be trusted after any fault (the sweep engine and the studies' outputs):

- a chunk file with a flipped bit, another chunk's file, an empty one, a truncated one, one that is
  not a chunk file: recomputed with a one-line note, and the final numbers equal a clean run's;
- a configuration changed into the same folder: the previous results and their config.toml stay
  until the new ones are complete (an interrupted run leaves them), then are replaced together
  (the previous configuration's chunks removed only then);
- a full disk (a size-limited file system: RLIMIT_FSIZE with SIGXFSZ ignored, so writes fail with
  EFBIG) while the chunks and while the final NetCDF are written: one line naming the file and the
  cause, no segmentation fault, the earlier results intact, a rerun gives the clean numbers;
- every Dask worker killed at once mid-sweep: the tasks resubmitted, no library traceback on
  stderr, the clean numbers.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from dryfriction.studies import run_study
from dryfriction.sweep import SweepInterrupted, read_netcdf
from dryfriction.sweep.engine import CHUNK_MAGIC

VARS = ("z_max", "z_min", "amplitude", "asymmetry", "stick_fraction", "transitions", "status")


def run(out: Path, fmu_path: Path, **kw: object):  # noqa: ANN201
    return run_study("fig8_9", quick=True, out=out, fmu=fmu_path, progress=False, **{"workers": 0, **kw})


def same(a: xr.Dataset, b: xr.Dataset) -> None:
    for n in VARS:
        assert np.array_equal(a[n].values, b[n].values, equal_nan=True), n
    for c in a.coords:
        assert np.array_equal(a[c].values, b[c].values), c


@pytest.fixture(scope="module")
def clean_run(tmp_path_factory: pytest.TempPathFactory, fmu_path: Path) -> Path:
    """The output folder of fig8_9 --quick computed once without a fault (12 chunks of 25 runs),
    not to be changed: a test that starts from a finished run takes a copy (clean_copy)."""
    out = tmp_path_factory.mktemp("clean")
    run(out, fmu_path)
    return out


@pytest.fixture(scope="module")
def clean(clean_run: Path) -> xr.Dataset:
    """The numbers of fig8_9 --quick without a fault."""
    return read_netcdf(clean_run / "fig8_9" / "fig8_9.nc")


def clean_copy(clean_run: Path, out: Path) -> None:
    """``out`` as a finished fig8_9 --quick run leaves it: a copy of the fault-free run's folder
    (the same files a run into ``out`` writes: nothing in them names the folder)."""
    shutil.copytree(clean_run / "fig8_9", out / "fig8_9")


def _chunks(out: Path) -> list[Path]:
    return sorted((out / "fig8_9" / "chunks").glob("fig8_9-*/c*.chunk"))


def _flip(p: Path) -> str:
    raw = bytearray(p.read_bytes())
    raw[-5] ^= 0x40               # one bit of the exponent of the last value
    p.write_bytes(bytes(raw))
    return "checksum does not match"


def _swap(p: Path) -> str:
    p.write_bytes(p.with_name("c00002.chunk").read_bytes())
    return "holds another chunk"


def _empty(p: Path) -> str:
    p.write_bytes(b"")
    return "empty"


def _truncate(p: Path) -> str:
    p.write_bytes(p.read_bytes()[: p.stat().st_size // 2])
    return "checksum does not match"


def _garbage(p: Path) -> str:
    p.write_bytes(b"\x93NUMPY" + bytes(200))
    return "not a chunk file"


@pytest.mark.parametrize("damage", [_flip, _swap, _empty, _truncate, _garbage])
def test_damaged_chunk_is_recomputed_with_a_note(damage, tmp_path: Path, fmu_path: Path, clean_run: Path,
                                                 clean: xr.Dataset, capsys: pytest.CaptureFixture[str]) -> None:
    clean_copy(clean_run, tmp_path)
    chunks = _chunks(tmp_path)
    assert len(chunks) == 12 and all(c.read_bytes().startswith(CHUNK_MAGIC) for c in chunks)
    victim = chunks[5]
    why = damage(victim)
    (tmp_path / "fig8_9" / "fig8_9.nc").unlink()
    capsys.readouterr()
    res = run(tmp_path, fmu_path)
    st = res.stats[0]
    assert (st.loaded, st.computed) == (11, 1)
    notes = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("note:")]
    assert len(notes) == 1 and str(victim) in notes[0] and why in notes[0] and notes[0].endswith("recomputed")
    same(read_netcdf(tmp_path / "fig8_9" / "fig8_9.nc"), clean)
    # the recomputed chunk is whole again: the next run loads all 12
    assert run(tmp_path, fmu_path).stats[0].loaded == 12


def test_configuration_change_replaces_results_together(tmp_path: Path, fmu_path: Path, clean_run: Path,
                                                        clean: xr.Dataset, capsys: pytest.CaptureFixture[str]) -> None:
    folder = tmp_path / "fig8_9"
    clean_copy(clean_run, tmp_path)
    before = {p.name: p.read_bytes() for p in folder.iterdir() if p.is_file()}
    old_chunks = _chunks(tmp_path)
    # another configuration, stopped after one chunk: the folder is exactly as it was
    with pytest.raises(SweepInterrupted):
        run(tmp_path, fmu_path, sets=["sweep.chi.num=4"], max_chunks=1)
    assert {p.name: p.read_bytes() for p in folder.iterdir() if p.is_file()} == before
    assert all(c.exists() for c in old_chunks)                # the previous chunks are kept
    assert not list(tmp_path.glob(".fig8_9.staging-*"))
    capsys.readouterr()
    # completed: config.toml and the results are the new configuration's, together
    run(tmp_path, fmu_path, sets=["sweep.chi.num=4"])
    err = capsys.readouterr().err
    assert f"note: {folder} holds the results of another configuration" in err
    assert "num = 4" in (folder / "config.toml").read_text()
    ds = read_netcdf(folder / "fig8_9.nc")
    assert ds.sizes["chi"] == 4
    assert not any(c.exists() for c in old_chunks)            # removed once the new results are in place
    # and back: the clean numbers again
    run(tmp_path, fmu_path)
    same(read_netcdf(folder / "fig8_9.nc"), clean)


FULL_DISK = """
import resource, signal, sys
from dryfriction.cli.study import main
import dryfriction.studies.fig8_9_bifurcation, dryfriction.sweep.datasets, h5netcdf, matplotlib.pyplot  # noqa
from dryfriction.sweep.runner import runner_for
runner_for(sys.argv[sys.argv.index("--fmu") + 1])  # the FMU unzipped before the disk is full
signal.signal(signal.SIGXFSZ, signal.SIG_IGN)   # a write past the limit fails with EFBIG
limit = int(sys.argv[1])
resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))
sys.exit(main(sys.argv[2:]))
"""


@pytest.mark.slow
@pytest.mark.parametrize("limit, victim", [(600, r"the chunk \S+/c\d{5}\.chunk"), (4000, r"\S+fig8_9\.nc")])
def test_full_disk_ends_with_one_line_and_earlier_results_intact(limit: int, victim: str, tmp_path: Path,
                                                                 fmu_path: Path, clean: xr.Dataset) -> None:
    folder = tmp_path / "fig8_9"
    run(tmp_path, fmu_path, sets=["sweep.chi.num=4"])         # earlier results, another configuration
    before = {p.name: p.read_bytes() for p in folder.iterdir() if p.is_file()}
    argv = [sys.executable, "-c", FULL_DISK, str(limit), "fig8_9", "--quick", "--workers", "0", "--no-progress",
            "--out", str(tmp_path), "--fmu", str(fmu_path)]
    proc = subprocess.run(argv, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 1, proc.stderr                  # not 139 / -11: no segmentation fault
    lines = [ln for ln in proc.stderr.splitlines() if not ln.startswith("note:")]
    assert len(lines) == 1, proc.stderr
    assert re.fullmatch(r"dryfriction: error: cannot write " + victim + ": File too large", lines[0]), lines
    assert {p.name: p.read_bytes() for p in folder.iterdir() if p.is_file()} == before
    assert not list(tmp_path.glob(".fig8_9.staging-*"))
    # room again: the run completes with the clean numbers (the chunks written before are reused)
    run(tmp_path, fmu_path)
    same(read_netcdf(folder / "fig8_9.nc"), clean)


KILL_WORKERS = """
import os, signal, sys, threading, time
from pathlib import Path
import dryfriction.sweep.engine as engine
from dryfriction.cli.study import main

ensure = engine.Engine._ensure_client

def ensure_and_arm(self):
    cluster = ensure(self)
    if not getattr(self, "armed", False):
        self.armed = True
        pids = list(cluster.client.run(os.getpid).values())
        root = Path(sys.argv[1])

        def kill():
            while len(list(root.rglob("c*.chunk"))) < 2:
                time.sleep(0.002)
            for pid in pids:         # every worker at once
                os.kill(pid, signal.SIGKILL)
            print("killed", len(pids), "workers", flush=True)

        threading.Thread(target=kill, daemon=True).start()
    return cluster

engine.Engine._ensure_client = ensure_and_arm
sys.exit(main(sys.argv[2:]))
"""


@pytest.mark.slow
@pytest.mark.no_sanitizer
def test_every_worker_killed_at_once(tmp_path: Path, fmu_path: Path, clean: xr.Dataset) -> None:
    argv = [sys.executable, "-c", KILL_WORKERS, str(tmp_path / "fig8_9" / "chunks"), "fig8_9", "--quick",
            "--workers", "2", "--no-progress", "--out", str(tmp_path), "--fmu", str(fmu_path),
            "--set", "numerics.chunk_runs=2"]
    proc = subprocess.run(argv, capture_output=True, text=True, timeout=600, env={**os.environ})
    assert "killed 2 workers" in proc.stdout, proc.stdout + proc.stderr
    for bad in ("Traceback", "CommClosedError", "FutureCancelledError", "leaked semaphore", "distributed."):
        assert bad not in proc.stderr, proc.stderr
    if proc.returncode != 0:                                  # given up: one line, resumable
        lines = proc.stderr.strip().splitlines()
        assert proc.returncode == 1 and len(lines) == 1 and "run again to resume" in lines[0], proc.stderr
    run(tmp_path, fmu_path, sets=["numerics.chunk_runs=2"])
    same(read_netcdf(tmp_path / "fig8_9" / "fig8_9.nc"), clean)


def _square(x: float) -> float:
    return x * x


@pytest.mark.slow
@pytest.mark.no_sanitizer
def test_tasks_are_streamed_a_few_at_a_time() -> None:
    """The tasks are drawn from their generator as earlier ones finish: at most twice the workers
    (2 here) are submitted before the first result comes back, and every result arrives once."""
    from dryfriction.cluster import Cluster, stream

    drawn: list[int] = []

    def tasks():
        for i in range(40):
            drawn.append(i)
            yield i, (float(i),)

    cluster = Cluster(1)
    try:
        got = {}
        for key, value in stream(cluster, _square, tasks()):
            if not got:
                assert len(drawn) == 2
            got[key] = value
            assert len(drawn) <= len(got) + 2
    finally:
        cluster.close()
    assert got == {i: float(i) ** 2 for i in range(40)}


@pytest.mark.slow
@pytest.mark.no_sanitizer
def test_response_on_dask_says_nothing_of_dask(tmp_path: Path, fmu_path: Path) -> None:
    """A response on 2 Dask workers: stdout the table, stderr empty (no Dask log line, no graph
    warning), the numbers those of the same response in this process."""
    block = ["--m", "0.5", "--k", "2000", "--zeta", "0.003", "--P0", "10", "--N", "20", "--mu-s", "0.3",
             "--mu-k", "0.2", "--f-start", "5", "--f-stop", "15", "--num", "24", "--no-progress", "--format", "netcdf",
             "--no-plot", "--fmu", str(fmu_path)]
    outs = {}
    for workers in ("2", "0"):
        out = tmp_path / f"w{workers}"
        proc = subprocess.run([sys.executable, "-m", "dryfriction", "response", *block, "--workers", workers,
                               "--out", str(out)], capture_output=True, text=True, timeout=600)
        assert proc.returncode == 0 and proc.stderr == "", proc.stderr
        outs[workers] = read_netcdf(out / "response.nc")
    a, b = outs["2"], outs["0"]
    for n in ("amplitude_m", "stable", "mu_max"):
        assert np.allclose(a[n].values, b[n].values, rtol=1e-9, atol=0, equal_nan=True), n


def _die(x: float) -> float:
    os._exit(1)


@pytest.mark.slow
@pytest.mark.no_sanitizer
def test_a_task_that_keeps_losing_its_worker_ends_with_one_line() -> None:
    """A task whose worker dies every time it runs: submitted again ``retries`` times, then
    ClusterLost, one sentence (the CLI prints it as one line)."""
    import dask

    from dryfriction.cluster import Cluster, ClusterLost, stream

    with dask.config.set({"distributed.scheduler.allowed-failures": 0}):
        cluster = Cluster(1)
        try:
            with pytest.raises(ClusterLost) as err:
                list(stream(cluster, _die, [(0, (1.0,))], retries=1))
        finally:
            cluster.close()
    assert str(err.value) == ("the Dask workers were lost 2 times while one task ran; finished chunks are kept, "
                              "run again to resume")
