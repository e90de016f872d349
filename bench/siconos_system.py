#!/usr/bin/env python3
"""The DryFrictionSystem model against Siconos on the same structures, at equal error.

    .venv/bin/python bench/siconos_system.py [--quick] [--n 8,32,128] [--md PATH] [--json PATH]
                                             [--budget S] [--bench-system PATH]

The structure (both sides, from :func:`structure`): bench/bench_system.c's chain, n unit masses
(M = I), K tridiagonal (springs 1 between neighbours and to the walls at both ends), C = 0.02 M +
0.002 K, the force F_c,i cos(omega t) + F_s,i sin(omega t) with F_c,i = cos(0.1 i), F_s,i =
sin(0.1 i), omega = 0.5, from rest; nc = n / 4 rigid contacts (contact j at DOF floor((j + 1/2) n /
nc), even j against the ground, odd j between that DOF and the next), N = 1.6, mu_s = mu_k = 0.4
(Siconos's relay has one coefficient); two forcing periods (T = 4 pi s), x sampled 40 times a
period.

- Siconos (Debian's python3-siconos under the system Python, installed with apt-get when missing,
  as bench/siconos_peer.py does: bench/siconos_side.py): ``EulerMoreauOSI(0.5)``, one relay per
  contact (bench/siconos_system_run.py), the one-step relay by Lemke, b(t) a C plugin; h = T / m,
  m = 40, 80, 160, ... while a run keeps within the budget. CPU time: the process CPU time of
  ``TimeStepping.run()``.
- Ours: the model's physics linked statically (``bench_system --case``: the engine the FMU steps
  with, no FMI layer), the located scheme (alpha = -0.1), h = T / m, m = 40, 80, ..., 2560; CPU time:
  the thread's CPU time of the whole run (its 80 sample stops included), minimum of 3.
- The reference: ours, located, at h = T / 20480 (n <= 32) or T / 10240 (n = 128); its own error
  is estimated by comparison with h doubled (a second-order scheme: about a third of that
  difference) and reported, and for n <= 32 checked against dryfriction.references.system (the
  event-driven reference, independent of the engine: DOP853 between events at rtol 1e-12).
- Error: max over the samples and the DOFs of |x - x_ref|, divided by max |x_ref| (relative).
- Per n: both sides' error and CPU time per h, the ns per step, and the CPU time each needs to
  reach the relative errors 1e-1, 3e-2, ..., 1e-4 (report.cost_at: Pareto front, log-log
  interpolation, no extrapolation) with the ratio Siconos / ours.

OPENBLAS_NUM_THREADS=1 is set for both sides (Siconos's dense algebra goes through OpenBLAS; a
second thread on a shared 2-core machine doubles its CPU time without shortening its run).
--quick: n = 8 only, a few h (a smoke run).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ["OPENBLAS_NUM_THREADS"] = "1"  # before numpy, and inherited by the Siconos worker

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))

OMEGA = 0.5
T = 2.0 * math.pi / OMEGA
PERIODS = 2
SAMPLES_PER_PERIOD = 40
TARGETS = (1e-1, 3e-2, 1e-2, 3e-3, 1e-3, 3e-4, 1e-4)
THETA = 0.5
RUNNER = HERE / "siconos_system_run.py"
EVENT_CHECK_MAX_N = 32  # the event-driven reference checks ours up to this n (it takes seconds there)


def structure(n: int, normal: float = 1.6, mu: float = 0.4) -> dict[str, np.ndarray | float | int]:
    """bench_system's chain structure of n DOFs with nc = n / 4 rigid contacts (at least 1),
    mu_s = mu_k = mu: the arrays both sides take."""
    nc = max(1, n // 4)
    M = np.eye(n)
    K = 2.0 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    C = 0.02 * M + 0.002 * K
    i = np.arange(n)
    W = np.zeros((nc, n))
    for j in range(nc):
        d = int((j + 0.5) * n / nc)
        W[j, d] = 1.0
        if j % 2 == 1 and n > 1:
            W[j, d + 1 if d + 1 < n else d - 1] = -1.0
    return {"n": n, "nc": nc, "M": M, "C": C, "K": K, "F_c": np.cos(0.1 * i), "F_s": np.sin(0.1 * i),
            "x0": np.zeros(n), "v0": np.zeros(n), "W": W, "N": np.full(nc, normal), "mu": np.full(nc, mu),
            "omega": OMEGA}


def bench_system_path(given: str | None) -> Path:
    """The bench_system executable: given, $DFO_BENCH_SYSTEM, or build/bench/bench_system."""
    p = Path(given or os.environ.get("DFO_BENCH_SYSTEM") or ROOT / "build" / "bench" / "bench_system")
    if not p.is_file():
        raise SystemExit(f"bench_system not found at {p}: build it (cmake --build build --target bench_system)")
    return p


def ours(exe: Path, st: dict, m: int, reps: int = 3, scheme: int = 3) -> dict:
    """One run of our model at h = T / m: CPU seconds, steps and the samples (rows: times)."""
    n, nc = st["n"], st["nc"]
    t_end = PERIODS * T
    ns = PERIODS * SAMPLES_PER_PERIOD
    with tempfile.NamedTemporaryFile("w", suffix=".txt", delete=False) as f:
        f.write(f"{n} {nc} {scheme} {OMEGA!r} {T / m!r} {t_end!r} {ns} {reps}\n")
        for key in ("M", "C", "K", "F_c", "F_s", "x0", "v0", "W", "N", "mu", "mu"):
            f.write(" ".join(repr(float(v)) for v in np.ravel(st[key])) + "\n")
        path = f.name
    try:
        r = subprocess.run([str(exe), "--case", path], capture_output=True, text=True, timeout=3600)
    finally:
        os.unlink(path)
    if r.returncode != 0:
        raise RuntimeError(f"bench_system --case failed: {r.stderr.strip()}")
    lines = r.stdout.strip().splitlines()
    head = lines[0].split()
    x = np.array([[float(v) for v in ln.split()] for ln in lines[1:]])
    return {"cpu_s": float(head[1]), "steps": int(head[3]), "x": x}


class SystemWorker:
    """bench/siconos_system_run.py under the system Python (bench/siconos_side.py's worker, this
    runner)."""

    def __init__(self) -> None:
        import siconos_side as side

        self._side = side
        self._dir = Path(tempfile.mkdtemp(prefix="dfo_siconos_sys_"))
        plugin = side.compile_plugin(self._dir)
        self._err = open(self._dir / "stderr.txt", "w+")
        self.proc = subprocess.Popen([side.SYSTEM_PYTHON, str(RUNNER), str(plugin)], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, stderr=self._err, text=True, bufsize=1,
                                     cwd=str(HERE), env={**os.environ, "PYTHONPATH": str(HERE)})
        hello = self._read()
        self.module_version = str(hello.get("siconos", "?"))

    def _read(self) -> dict:
        assert self.proc.stdout is not None
        line = self.proc.stdout.readline()
        if not line:
            self._err.seek(0)
            raise RuntimeError("the Siconos worker stopped: " + " | ".join(self._err.read().strip().splitlines()[-5:]))
        return json.loads(line)

    def run(self, job: dict) -> dict:
        """Send one job, wait for its answer."""
        assert self.proc.stdin is not None
        self.proc.stdin.write(json.dumps(job) + "\n")
        self.proc.stdin.flush()
        res = self._read()
        if "error" in res:
            raise RuntimeError(f"Siconos job {job.get('id')} failed: {res['error']}")
        return res

    def close(self) -> None:
        """Stop the worker and remove its folder."""
        import shutil

        if self.proc.poll() is None:
            assert self.proc.stdin is not None
            self.proc.stdin.close()
            self.proc.wait(timeout=60)
        self._err.close()
        shutil.rmtree(self._dir, ignore_errors=True)


def siconos_job(st: dict, m: int, reps: int) -> dict:
    """The worker's job for the structure at h = T / m (sampled as ours)."""
    steps_per_sample = m // SAMPLES_PER_PERIOD
    return {"id": f"n{st['n']}_m{m}", "n": st["n"], "nc": st["nc"],
            **{k: np.ravel(st[k]).tolist() for k in ("M", "C", "K", "F_c", "F_s", "x0", "v0", "W")},
            "muN": (st["mu"] * st["N"]).tolist(), "omega": OMEGA, "t_end": PERIODS * T, "h": T / m,
            "theta": THETA, "sample_every": steps_per_sample, "reps": reps}


def event_check(st: dict, x_ref: np.ndarray) -> float:
    """The reference's relative difference from dryfriction.references.system (event-driven,
    DOP853 at rtol 1e-12, independent of the engine) at the same samples."""
    from dryfriction import Contact, System
    from dryfriction.references.system import simulate

    contacts = [Contact(w=tuple(float(v) for v in st["W"][j]), N=float(st["N"][j]), mu_s=float(st["mu"][j]),
                        mu_k=float(st["mu"][j])) for j in range(st["nc"])]
    sy = System(M=st["M"], C=st["C"], K=st["K"], contacts=contacts, F_c=st["F_c"], F_s=st["F_s"], omega=OMEGA)
    ns = PERIODS * SAMPLES_PER_PERIOD
    t = np.arange(1, ns + 1) * PERIODS * T / ns
    return rel_error(x_ref, np.asarray(simulate(sy, PERIODS * T, t_eval=t).x))


def rel_error(x: np.ndarray, ref: np.ndarray) -> float:
    """max |x - ref| over samples and DOFs over max |ref|."""
    return float(np.max(np.abs(x - ref)) / np.max(np.abs(ref)))


def cost_at(points: list[tuple[float, float]], target: float) -> float | None:
    """report.cost_at: seconds to reach error <= target on the Pareto front (no extrapolation)."""
    from report import cost_at as _cost_at

    return _cost_at(points, target)


def compare(n: int, exe: Path, worker: SystemWorker | None, quick: bool, budget: float, log) -> dict:
    """Both sides on the structure of n DOFs: rows, the reference's error, the ratios."""
    st = structure(n)
    m_ref = 2560 if quick else (20480 if n <= 32 else 10240)
    ref = ours(exe, st, m_ref, reps=1)
    half = ours(exe, st, m_ref // 2, reps=1)
    ref_err = rel_error(half["x"], ref["x"]) / 3.0
    event_diff = event_check(st, ref["x"]) if n <= EVENT_CHECK_MAX_N else None
    log.write(f"n = {n}, nc = {st['nc']}: reference h = T/{m_ref}, its error about {ref_err:.2g}"
              + ("" if event_diff is None else f"; against the event-driven reference {event_diff:.2g}") + "\n")
    mine = []
    for m in ((40, 80, 160) if quick else (40, 80, 160, 320, 640, 1280, 2560)):
        r = ours(exe, st, m)
        e = rel_error(r["x"], ref["x"])
        mine.append({"m": m, "h": T / m, "cpu_s": r["cpu_s"], "steps": r["steps"], "error": e,
                     "ns_per_step": 1e9 * r["cpu_s"] / r["steps"]})
        log.write(f"  ours     h = T/{m}: error {e:.3g}, cpu {r['cpu_s']:.3g} s, {mine[-1]['ns_per_step']:.0f} ns/step\n")
    sic = []
    if worker is not None:
        spent, last = 0.0, 0.0
        for m in ((40, 80) if quick else (40, 80, 160, 320, 640, 1280, 2560)):
            if sic and spent + 2.5 * last > budget:
                log.write(f"  siconos  h = T/{m}: skipped (would pass the budget of {budget:g} s)\n")
                break
            t0 = time.perf_counter()
            res = worker.run(siconos_job(st, m, reps=1))
            last = time.perf_counter() - t0
            spent += last
            x = np.asarray(res["x"])[1:]  # the first sample is t = 0
            e = rel_error(x, ref["x"])
            sic.append({"m": m, "h": T / m, "cpu_s": res["cpu_s"], "steps": res["steps"], "error": e,
                        "ns_per_step": 1e9 * res["cpu_s"] / res["steps"]})
            log.write(f"  siconos  h = T/{m}: error {e:.3g}, cpu {res['cpu_s']:.3g} s, "
                      f"{sic[-1]['ns_per_step']:.0f} ns/step\n")
    ratios = {}
    for E in TARGETS:
        cs = cost_at([(r["error"], r["cpu_s"]) for r in sic], E)
        co = cost_at([(r["error"], r["cpu_s"]) for r in mine], E)
        ratios[f"{E:g}"] = {"siconos_s": cs, "ours_s": co, "ratio": (cs / co) if cs and co else None}
    return {"n": n, "nc": st["nc"], "m_ref": m_ref, "ref_error": ref_err, "ref_vs_event_driven": event_diff,
            "ours": mine, "siconos": sic,
            "at_error": ratios}


def markdown(results: list[dict], version: str) -> str:
    """The tables of a run."""
    out = [f"Siconos {version}, EulerMoreauOSI(theta = {THETA}), one relay per contact, Lemke; ours: located "
           "(bench_system --case); OPENBLAS_NUM_THREADS=1; relative error max|x - x_ref| / max|x_ref| over "
           f"{PERIODS} periods.", ""]
    for r in results:
        ev = r["ref_vs_event_driven"]
        out += [f"### n = {r['n']}, nc = {r['nc']} (reference h = T/{r['m_ref']}, its error about {r['ref_error']:.1g}"
                + ("" if ev is None else f"; {ev:.1g} from the event-driven reference") + ")",
                "", "| side | h | error | CPU s | ns per step |", "|---|---|---|---|---|"]
        for side in ("ours", "siconos"):
            for row in r[side]:
                out.append(f"| {side} | T/{row['m']} | {row['error']:.3g} | {row['cpu_s']:.3g} | {row['ns_per_step']:.0f} |")
        out += ["", "| error | Siconos s | ours s | ratio |", "|---|---|---|---|"]
        for E, v in r["at_error"].items():
            f = (lambda x: "not reached" if x is None else f"{x:.3g}")
            out.append(f"| {E} | {f(v['siconos_s'])} | {f(v['ours_s'])} | {f(v['ratio'])} |")
        out.append("")
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    """Run the comparison; tables on stdout (and --md, --json)."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--n", default=None, help="sizes, comma-separated (default 8,32,128)")
    ap.add_argument("--budget", type=float, default=120.0, help="Siconos seconds per n (default 120)")
    ap.add_argument("--md", default=None)
    ap.add_argument("--json", default=None)
    ap.add_argument("--bench-system", default=None)
    ap.add_argument("--no-siconos", action="store_true", help="our side only")
    a = ap.parse_args(argv)
    exe = bench_system_path(a.bench_system)
    ns = [int(v) for v in a.n.split(",")] if a.n else ([8] if a.quick else [8, 32, 128])
    worker, version = None, "not run"
    if not a.no_siconos:
        import siconos_side

        version = siconos_side.ensure_siconos(sys.stderr)
        worker = SystemWorker()
    try:
        results = [compare(n, exe, worker, a.quick, a.budget, sys.stderr) for n in ns]
    finally:
        if worker is not None:
            worker.close()
    md = markdown(results, version)
    print(md)
    if a.md:
        Path(a.md).write_text(md + "\n")
    if a.json:
        Path(a.json).write_text(json.dumps({"siconos": version, "results": results}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
