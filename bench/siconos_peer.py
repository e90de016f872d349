#!/usr/bin/env python3
"""What accuracy costs, against Siconos: INRIA's platform for non-smooth dynamics (Moreau-Jean
time stepping, the relay solved by Lemke), side by side with the FMU in one run.

    .venv/bin/python bench/siconos_peer.py [--quick] [--json] [--md PATH] [--budget S]

Installs Debian's python3-siconos when the system Python cannot import it (apt-get, waiting for
the dpkg lock), runs Siconos under the system Python in a subprocess (bench/siconos_run.py) and
the FMU here, and measures error against CPU time (process CPU time of the stepping loop only,
both sides) on the cases of bench/siconos_cases.py:

1. Siconos's FrictionOscillator tutorial against its closed form;
2. the work-precision cases of bench/work_precision.py at chi = 1 (Siconos's relay law has one
   friction coefficient: the cases' own distinct mu_s and mu_k cannot be modelled), the harmonic
   force as the dynamical system's b(t), against the exact solution;
3. the chain of docs/chain.md (mu_s = mu_k) at n = 2, 8, 64 and larger while a Siconos run keeps
   within the budget, against dryfriction.references.chain, with ns per block-step.

Siconos: EulerMoreauOSI(theta) with theta = 0.5 and 1, h = 1e-2, 5e-3, ... until its error reaches
1e-6 or the next h would pass the budget (60 s per case and theta). The FMU: the located scheme
over h, and the exact scheme (the oscillator cases; the chain has none). Per case the CPU time each
needs to reach the errors 1e-3 ... 1e-8 (read off its Pareto front, interpolated log-log, never
extrapolated) and the ratio Siconos / FMU (best over theta / over schemes; null where one of them
does not reach it). --json prints only the JSON object on stdout; --md writes the tables as
markdown. --quick: a small version for CI (fewer cases, two steps, ~20 s).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from dataclasses import dataclass
from pathlib import Path

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))

TARGETS = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8)
THETAS = (0.5, 1.0)
STOP_ERROR = 1e-6


@dataclass(frozen=True)
class PeerConfig:
    quick: bool
    budget_s: float                 # Siconos wall time per case and theta
    siconos_h: tuple[float, ...]
    fmu_h: tuple[float, ...]
    wp_names: tuple[str, ...] | None
    chain_n: tuple[int, ...]
    chain_grow: bool                # try 2n after the last n while Siconos keeps within the budget
    fmu_budget_s: float

    @staticmethod
    def make(quick: bool, budget: float | None) -> "PeerConfig":
        if quick:
            return PeerConfig(True, budget or 3.0, (1e-2, 5e-3), (1e-2, 5e-3, 2.5e-3),
                              ("stick_dominated", "reversal_resonance"), (2, 8), False, 0.01)
        return PeerConfig(False, budget or 60.0, tuple(1e-2 / 2**k for k in range(14)),
                          tuple(1e-2 / 2**k for k in range(11)), None, (2, 8, 64), True, 0.2)


def cost_at(points: list[tuple[float, float]], target: float) -> float | None:
    """Seconds to reach error <= target from (error, seconds) points (report.cost_at: the Pareto
    front, interpolated log-log, no extrapolation)."""
    from report import cost_at as _cost_at

    return _cost_at(points, target)


def ratio_at(sic: list[dict], fmu: list[dict]) -> dict[str, float | None]:
    out: dict[str, float | None] = {}
    for E in TARGETS:
        s_best = [c for c in (cost_at([(r["error"], r["cpu_s"]) for r in sic if r["theta"] == th], E)
                              for th in THETAS) if c is not None]
        f_best = [c for c in (cost_at([(r["error"], r["cpu_s"]) for r in fmu if r["scheme"] == sc], E)
                              for sc in sorted({r["scheme"] for r in fmu})) if c is not None]
        out[f"{E:.0e}"] = (min(s_best) / min(f_best)) if s_best and f_best else None
    return out


def siconos_sweep(worker, case, theta: float, cfg: PeerConfig, log) -> tuple[list[dict], str]:
    """Siconos rows for one case and theta, and why the sweep stopped."""
    import numpy as np

    rows: list[dict] = []
    spent, last_wall = 0.0, 0.0
    why = f"the finest h of the sweep ({cfg.siconos_h[-1]:g})"
    for i, h in enumerate(cfg.siconos_h):
        steps = math.ceil(case.t_end / h - 1e-9)
        predict = 2.0 * last_wall if i else 0.0
        if i and spent + predict > cfg.budget_s:
            why = (f"the budget: h = {h:g} would take about {predict:.0f} s more (spent {spent:.0f} s of "
                   f"{cfg.budget_s:g} s)")
            break
        every = max(1, round(case.sample_dt / h))
        reps = 3 if last_wall < 1.0 else 1  # timed runs of run(); the first h: 3
        t0 = time.perf_counter()
        res = worker.run(case.job(h, theta, steps, every, reps))
        last_wall = time.perf_counter() - t0
        spent += last_wall
        t = np.asarray(res["t"])
        x = np.asarray(res["x"])
        err = float(np.max(np.abs(x - case.reference(t)))) * case.error_scale
        if res["steps"] != steps:
            raise RuntimeError(f"{case.name}: Siconos took {res['steps']} steps, expected {steps}")
        if res["end_mismatch"] > 1e-9 * (1.0 + float(np.max(np.abs(x)))):
            raise RuntimeError(f"{case.name}: Siconos's run() and stepped loop end {res['end_mismatch']:.3g} apart")
        rows.append({"theta": theta, "h": h, "cpu_s": res["cpu_s"], "error": err, "steps": steps})
        log.write(f"  siconos theta={theta:g} h={h:.3g}: error {err:.3g}, cpu {res['cpu_s']:.3g} s "
                  f"({res['cpu_s'] / steps / case.n * 1e9:.0f} ns per block-step)\n")
        if err <= STOP_ERROR:
            why = f"its error reached {STOP_ERROR:g}"
            break
    return rows, why


def fmu_sweep(fmu, case, cfg: PeerConfig, log) -> list[dict]:
    rows = []
    for h in cfg.fmu_h:
        steps = math.ceil(case.t_end / h - 1e-9)
        every = max(1, round(case.sample_dt / h))
        r = fmu.run(case, "located", h, steps, every)
        rows.append(r)
        log.write(f"  fmu located h={h:.3g}: error {r['error']:.3g}, cpu {r['cpu_s']:.3g} s\n")
        if r["error"] <= 1e-9:
            break
    if case.kind == "oscillator":
        h = cfg.fmu_h[0]
        steps = math.ceil(case.t_end / h - 1e-9)
        r = fmu.run(case, "exact", h, steps, max(1, round(case.sample_dt / h)))
        rows.append(r)
        log.write(f"  fmu exact: error {r['error']:.3g}, cpu {r['cpu_s']:.3g} s\n")
    return rows


def run_case(worker, fmu, case, cfg: PeerConfig, log) -> dict:
    log.write(f"{case.name}: {case.note}\n")
    sic: list[dict] = []
    stops: dict[str, str] = {}
    for th in THETAS:
        rows, why = siconos_sweep(worker, case, th, cfg, log)
        sic += rows
        stops[f"{th:g}"] = why
    fm = fmu_sweep(fmu, case, cfg, log)
    return {"case": case, "siconos": sic, "fmu": fm, "stops": stops, "ratio_at": ratio_at(sic, fm)}


def grow_chain(results: list[dict], cfg: PeerConfig) -> tuple[int | None, str]:
    """The next chain size to try (2n) when Siconos's predicted cost at h = 1e-2 keeps within the
    budget, from the growth of its cost per step between the last two sizes."""
    ch = [r for r in results if r["case"].kind == "chain"]
    if len(ch) < 2:
        return None, ""

    def cost(r: dict) -> float:
        return max(x["cpu_s"] / x["steps"] for x in r["siconos"] if x["h"] == cfg.siconos_h[0])

    a, b = ch[-2], ch[-1]
    na, nb = a["case"].n, b["case"].n
    p = math.log(cost(b) / cost(a)) / math.log(nb / na)
    steps = math.ceil(b["case"].t_end / cfg.siconos_h[0])
    predict = cost(b) * (2.0 ** p) * steps * 2.5  # stepped loop + timed run, per theta
    n = 2 * nb
    if predict > cfg.budget_s:
        return None, (f"n = {n} not run: Siconos's cost per step grows like n^{p:.2f} between n = {na} and {nb}, "
                      f"so one theta at h = {cfg.siconos_h[0]:g} would take about {predict:.0f} s "
                      f"(budget {cfg.budget_s:g} s)")
    return n, ""


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    ap = argparse.ArgumentParser(prog="siconos_peer.py", description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="the small CI version (~20 s)")
    ap.add_argument("--json", action="store_true", help="print only the JSON object on stdout")
    ap.add_argument("--md", default=None, help="write the tables as markdown to this file")
    ap.add_argument("--budget", type=float, default=None,
                    help="Siconos seconds per case and theta (default 60, --quick 3)")
    args = ap.parse_args(argv)
    if args.budget is not None and not (math.isfinite(args.budget) and args.budget > 0):
        ap.error(f"--budget must be a number > 0, not {args.budget}")
    return args


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    cfg = PeerConfig.make(args.quick, args.budget)
    log = sys.stderr
    from dryfriction.drivers.chain import default_chain_fmu3
    from dryfriction.drivers.oscillator import default_fmu_path

    try:  # both FMUs before anything runs
        default_fmu_path()
        default_chain_fmu3()
    except Exception as e:  # noqa: BLE001 - FMUFileError and the like: one line, exit 2
        sys.stderr.write(f"siconos_peer.py: error: {e} (build them: bash scripts/setup.sh)\n")
        return 2
    from siconos_side import SiconosUnavailable, SiconosWorker, ensure_siconos

    try:
        deb = ensure_siconos(log)
    except SiconosUnavailable as e:
        sys.stderr.write(f"siconos_peer.py: Siconos is not available: {e}\n")
        return 3
    import siconos_cases as sc
    import siconos_report
    from siconos_fmu import FmuSide

    t_start = time.perf_counter()
    cases = [sc.tutorial_case()] + sc.wp_cases(cfg.wp_names)
    results: list[dict] = []
    notes: list[str] = []
    fmu = FmuSide(cfg.fmu_budget_s)
    try:
        with SiconosWorker() as worker:
            versions = {"siconos_deb": deb, "siconos_module": worker.module_version, "system_python": worker.python}
            for case in cases:
                results.append(run_case(worker, fmu, case, cfg, log))
            for n in cfg.chain_n:
                results.append(run_case(worker, fmu, sc.chain_case(n), cfg, log))
            while cfg.chain_grow:
                n, why = grow_chain(results, cfg)
                if n is None:
                    if why:
                        notes.append(why)
                        log.write(why + "\n")
                    break
                results.append(run_case(worker, fmu, sc.chain_case(n), cfg, log))
    finally:
        fmu.close()
    seconds = time.perf_counter() - t_start
    obj = {"cases": [{"name": r["case"].name,
                      "siconos": [{k: x[k] for k in ("theta", "h", "cpu_s", "error")} for x in r["siconos"]],
                      "fmu": [{k: x[k] for k in ("scheme", "h", "cpu_s", "error")} for x in r["fmu"]],
                      "ratio_at": r["ratio_at"]} for r in results]}
    meta = siconos_report.meta(versions, cfg, seconds)
    text = siconos_report.markdown(results, notes, meta, TARGETS)
    if args.md:
        from dryfriction.atomic import atomic_write_text

        Path(args.md).parent.mkdir(parents=True, exist_ok=True)
        atomic_write_text(Path(args.md), text)
    if args.json:
        sys.stdout.write(json.dumps(obj, indent=1) + "\n")
    else:
        sys.stdout.write(text)
    log.write(f"done in {seconds:.0f} s\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
