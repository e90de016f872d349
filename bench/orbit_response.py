#!/usr/bin/env python3
"""The frequency response from orbits against the transient method, measured side by side in one run.

    python bench/orbit_response.py [--num 401] [--repeats 3] [--json] [--fmu PATH]

1. A 401-point frequency response with every orbit's stability (``frequency_response``, method
   orbit, in this process, one FMU instance): the engineer's example of the README (0.5 kg, 2000 N/m,
   zeta 0.003, 10 N, N 20 N, mu_s 0.3, mu_k 0.2, 5 to 15 Hz) and a light-damping case (zeta = 0.01,
   m = k = 1, P0 = 1, lambda 0.5 to 1.5, with friction N = 0.1, mu_s 0.3, mu_k 0.2, and without,
   N = 0). Wall time, min of ``--repeats``; per point; the evaluations of the stroboscopic map per
   point (counted in one more, untimed run).
2. At zeta = 0.01, the transient method (``steady_state``, scheme exact) at tol 1e-3 ... 1e-12:
   its largest amplitude error against the orbit's (without friction: both against the closed
   form), its time, and the time of the cheapest tolerance whose error is within the target
   accuracy (1e-10 and 1e-6 relative); the ratio to the orbit method's time measured beside it
   (each of the ``--repeats`` transient runs is followed by orbit runs for as long; each method's
   time is its minimum over its runs: both sampled over the same stretches of time). Also the transient's
   best case: per point the one run of the fewest periods (a power of two) whose window is within
   the target, known in hindsight (no convergence test could know it).

No timing is asserted anywhere (tests/test_bench_smoke.py runs it at --num 5). Results:
docs/performance.md, bench/RESULTS.md.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

from dryfriction import Oscillator
from dryfriction.cli.options import count, make_parser
from dryfriction.analysis.response import frequency_response

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))
from timing import timed  # noqa: E402  (bench/timing.py)

ENGINEER = dict(m=0.5, k=2000.0, zeta=0.003, P0=10.0, N=20.0, mu_s=0.3, mu_k=0.2)
LIGHT = dict(m=1.0, k=1.0, zeta=0.01, P0=1.0, mu_s=0.3, mu_k=0.2)
TOLS = (1e-3, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12)
TARGETS = (1e-6, 1e-10)


def evaluations(fn: Any) -> tuple[int, Any]:
    """(how many evaluations of the stroboscopic map one call of fn makes, its result): the map's
    evaluation counted in one untimed call."""
    from dryfriction.analysis import orbits

    count = [0]
    original = orbits._Map.eval

    def counting(self: Any, *args: Any, **kwargs: Any) -> Any:
        count[0] += 1
        return original(self, *args, **kwargs)

    orbits._Map.eval = counting  # type: ignore[method-assign]
    try:
        out = fn()
    finally:
        orbits._Map.eval = original  # type: ignore[method-assign]
    return count[0], out


def closed_form(p: Oscillator, f: np.ndarray) -> np.ndarray:
    w = 2 * math.pi * f
    return abs(p.P0) / np.hypot(p.k - p.m * w * w, p.c * w)


def best_case_transient(p: Oscillator, f: np.ndarray, ref: np.ndarray, target: float, fmu_path: Any,
                        repeats: int) -> tuple[float, float]:
    """Per point the fewest periods n = 32, 64, ... whose window [n/2, n] T gives the amplitude within
    target of ref (found in hindsight), then the time of those single runs; (seconds, mean periods)."""
    from dryfriction.drivers.oscillator import OscillatorFMU2
    from dryfriction.analysis.response import default_settings

    ns = []
    with OscillatorFMU2(fmu_path) as fmu:
        for fi, a in zip(f, ref):
            q = p.with_(omega=2 * math.pi * fi)
            n = 32
            while True:
                o = fmu.observables(q, n * q.period, 0.5 * n * q.period, settings=default_settings(q))
                if abs(0.5 * (o["x_max"] - o["x_min"]) - a) <= target * a or n >= 1 << 16:
                    break
                n *= 2
            ns.append(n)

        def run() -> None:
            for fi, n in zip(f, ns):
                q = p.with_(omega=2 * math.pi * fi)
                fmu.observables(q, n * q.period, 0.5 * n * q.period, settings=default_settings(q))

        t, _ = timed(run, repeats)
    return t, float(np.mean(ns))


def main(argv: list[str] | None = None) -> int:
    ap = make_parser("orbit_response.py", __doc__.splitlines()[0], exit=True)
    ap.add_argument("--num", type=count("--num", 2), default=401, help="frequencies per response (default 401)")
    ap.add_argument("--repeats", type=count("--repeats"), default=3, help="timing repeats, min taken (default 3)")
    ap.add_argument("--json", action="store_true", help="print one JSON object instead of the tables")
    ap.add_argument("--fmu", type=Path, default=None, help="the FMI 2.0 oscillator FMU (default: located)")
    args = ap.parse_args(argv)
    n, R, fmu = args.num, args.repeats, args.fmu
    out: dict[str, Any] = {"num": n, "repeats": R, "responses": [], "transient": []}

    # 1. responses with every orbit's stability
    cases = [("engineer 5-15 Hz", Oscillator.physical(**ENGINEER, f=5.0), np.linspace(5.0, 15.0, n)),
             ("zeta 0.01, N 0.1", Oscillator.physical(**LIGHT, N=0.1, omega=1.0),
              np.linspace(0.5, 1.5, n) / (2 * math.pi)),
             ("zeta 0.01, N 0", Oscillator.physical(**LIGHT, N=0.0, omega=1.0),
              np.linspace(0.5, 1.5, n) / (2 * math.pi))]
    frequency_response(cases[0][1], cases[0][2][:2], fmu_path=fmu)        # load once (not timed)
    orbit_ds = {}
    for name, p, f in cases:
        t, ds = timed(lambda: frequency_response(p, f, fmu_path=fmu), R)
        n_eval, _ = evaluations(lambda: frequency_response(p, f, fmu_path=fmu))
        orbit_ds[name] = (t, ds)
        out["responses"].append({"case": name, "seconds": t, "us_per_point": 1e6 * t / n,
                                 "evaluations_per_point": n_eval / n, "orbits": int(ds["n_orbits"].sum()),
                                 "stable": int(ds["stable"].values.sum()),
                                 "frequencies_with_a_stable_orbit": int(ds["converged"].sum()),
                                 "max_residual": float(np.nanmax(ds["residual"].values))})

    # 2. the transient method at zeta = 0.01 for the same accuracy
    for name, p, f in cases[1:]:
        t_orbit, ds = orbit_ds[name]
        amp = ds["amplitude_m"].values[:, 0]
        exact = closed_form(p, f) if p.N == 0 else None
        ref = exact if exact is not None else amp
        row: dict[str, Any] = {"case": name, "orbit_seconds": t_orbit,
                               "orbit_error": float(np.max(np.abs(amp - exact) / exact)) if exact is not None else None,
                               "tols": []}
        for tol in TOLS:
            # side by side: each run of the transient method is followed by runs of the orbit method
            # for as long (at least one), the ratio is of the two minima: both sampled over the same
            # stretches of time, so a shared machine's load bursts hit both alike
            t, t_orb = math.inf, math.inf
            for _ in range(R):
                tt, tr = timed(lambda: frequency_response(p, f, method="transient", tol=tol, fmu_path=fmu), 1)
                spent = 0.0
                while spent < tt:
                    to, _ = timed(lambda: frequency_response(p, f, fmu_path=fmu), 1)
                    spent += to
                    t_orb = min(t_orb, to)
                t = min(t, tt)
            err = float(np.max(np.abs(tr["amplitude_m"].values - ref) / ref))
            row["tols"].append({"tol": tol, "seconds": t, "orbit_seconds": t_orb, "max_error": err,
                                "converged": int(tr["converged"].sum()), "mean_periods": float(tr["periods"].mean()),
                                "ratio": t / t_orb})
        for target in TARGETS:
            ok = [r for r in row["tols"] if r["max_error"] <= target]
            cheapest = min(ok, key=lambda r: r["seconds"]) if ok else None
            bt, bn = best_case_transient(p, f, ref, target, fmu, R)
            row[f"target_{target:g}"] = {"tol": cheapest["tol"] if cheapest else None,
                                         "seconds": cheapest["seconds"] if cheapest else None,
                                         "orbit_seconds": cheapest["orbit_seconds"] if cheapest else None,
                                         "ratio": cheapest["ratio"] if cheapest else None,
                                         "best_case_seconds": bt, "best_case_mean_periods": bn,
                                         "best_case_ratio": bt / min([t_orbit] + [r["orbit_seconds"] for r in row["tols"]])}
        out["transient"].append(row)

    if args.json:
        print(json.dumps(out))
        return 0
    print(f"frequency responses from orbits, {n} points, every orbit's stability (min of {R} runs, wall time)")
    print(f"{'case':<20} {'seconds':>8} {'us/point':>8} {'evals/point':>11} {'orbits':>7} {'stable':>7} "
          f"{'with stable':>11} {'max residual':>12}")
    for r in out["responses"]:
        print(f"{r['case']:<20} {r['seconds']:8.3f} {r['us_per_point']:8.0f} {r['evaluations_per_point']:11.2f} "
              f"{r['orbits']:7d} {r['stable']:7d} {r['frequencies_with_a_stable_orbit']:11d} {r['max_residual']:12.1e}")
    for row in out["transient"]:
        e = row["orbit_error"]
        print(f"\n{row['case']}: orbit method {row['orbit_seconds']:.3f} s"
              + (f", its amplitude error against the closed form {e:.1e}" if e is not None else ""))
        print(f"{'transient tol':>13} {'seconds':>8} {'orbit s':>8} {'x orbit':>8} {'max error':>10} {'converged':>9} "
              f"{'periods':>8}")
        for r in row["tols"]:
            print(f"{r['tol']:13g} {r['seconds']:8.3f} {r['orbit_seconds']:8.3f} {r['ratio']:8.1f} {r['max_error']:10.1e} "
                  f"{r['converged']:9d} {r['mean_periods']:8.0f}")
        for target in TARGETS:
            c = row[f"target_{target:g}"]
            head = f"  accuracy {target:g}: "
            head += (f"transient tol {c['tol']:g}, {c['seconds']:.3f} s = {c['ratio']:.1f} x the orbit method "
                     f"({c['orbit_seconds']:.3f} s beside it)"
                     if c["tol"] is not None else "no transient tolerance reaches it")
            print(head + f"; its best case (hindsight: {c['best_case_mean_periods']:.0f} periods per point) "
                  f"{c['best_case_seconds']:.3f} s = {c['best_case_ratio']:.1f} x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
