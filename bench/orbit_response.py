#!/usr/bin/env python3
"""The frequency response from orbits against the transient method, measured side by side in one run.

    python bench/orbit_response.py [--num 401] [--small 41] [--repeats 3] [--json] [--fmu PATH]

1. A 401-point (``--num``) and a 41-point (``--small``) frequency response with every orbit's
   stability (``frequency_response``, method orbit, in this process, one FMU instance): the
   engineer's example of the README (0.5 kg, 2000 N/m, zeta 0.003, 10 N, N 20 N, mu_s 0.3, mu_k 0.2,
   5 to 15 Hz) and a light-damping case (zeta = 0.01, m = k = 1, P0 = 1, lambda 0.5 to 1.5, with
   friction N = 0.1, mu_s 0.3, mu_k 0.2, and without, N = 0). Wall time, min of ``--repeats``; per
   point; the evaluations of the stroboscopic map per point and the time of one (counted and timed
   in one more run), and the point's cost against them: that run's time per point / (evaluations
   per point x the time of one evaluation).
2. For each case, the transient method (``steady_state``, scheme exact) at tol 1e-3 ... 1e-12:
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
import time
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


def evaluations(fn: Any) -> tuple[int, float, Any]:
    """(how many evaluations of the stroboscopic map one call of fn makes, the seconds spent inside
    them, its result): the map's evaluations counted and timed in one call that is not otherwise timed
    (the clock's reads add about 0.1 us to each)."""
    from dryfriction.analysis import orbits

    count, spent = [0], [0.0]
    original = orbits._Map.eval
    clock = time.perf_counter

    def counting(self: Any, *args: Any, **kwargs: Any) -> Any:
        t = clock()
        out = original(self, *args, **kwargs)
        spent[0] += clock() - t
        count[0] += 1
        return out

    orbits._Map.eval = counting  # type: ignore[method-assign]
    try:
        out = fn()
    finally:
        orbits._Map.eval = original  # type: ignore[method-assign]
    return count[0], spent[0], out


def relative_error(a: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """Per point |a - ref| / ref against the nearest of the references ref[i, :] (NaN: none there)."""
    with np.errstate(invalid="ignore"):
        return np.nanmin(np.abs(a[:, None] - ref) / ref, axis=1)


def stable_amplitudes(p: Oscillator, f: np.ndarray, ds: Any) -> np.ndarray:
    """[frequency, orbit]: the amplitudes of the stable orbits of the response ds and of find_orbits
    (its transients from six initial conditions) at each frequency, NaN-padded."""
    from dryfriction import find_orbits
    from dryfriction.drivers.oscillator import OscillatorFMU2

    rows = []
    with OscillatorFMU2() as fmu:
        for fi, a, s in zip(f, ds["amplitude_m"].values, ds["stable"].values):
            cold = [o.amplitude for o in find_orbits(p.with_(omega=2 * math.pi * fi), fmu=fmu) if o.stable]
            rows.append(list(a[s]) + cold)
    width = max(len(r) for r in rows)
    return np.array([r + [math.nan] * (width - len(r)) for r in rows])


def closed_form(p: Oscillator, f: np.ndarray) -> np.ndarray:
    w = 2 * math.pi * f
    return abs(p.P0) / np.hypot(p.k - p.m * w * w, p.c * w)


def best_case_transient(p: Oscillator, f: np.ndarray, ref: np.ndarray, target: float, fmu_path: Any,
                        repeats: int) -> tuple[float, float]:
    """Per point the fewest periods n = 32, 64, ... whose window [n/2, n] T gives the amplitude within
    target of ref (the nearest of ref[i, :]; found in hindsight), then the time of those single runs;
    (seconds, mean periods)."""
    from dryfriction.drivers.oscillator import OscillatorFMU2
    from dryfriction.analysis.response import default_settings

    ns = []
    with OscillatorFMU2(fmu_path) as fmu:
        for fi, a in zip(f, ref):
            q = p.with_(omega=2 * math.pi * fi)
            n = 32
            while True:
                o = fmu.observables(q, n * q.period, 0.5 * n * q.period, settings=default_settings(q))
                err = relative_error(np.array([0.5 * (o["x_max"] - o["x_min"])]), a[None, :])[0]
                if err <= target or n >= 1 << 16:
                    break
                n *= 2
            ns.append(n)

        def run() -> None:
            for fi, n in zip(f, ns):
                q = p.with_(omega=2 * math.pi * fi)
                fmu.observables(q, n * q.period, 0.5 * n * q.period, settings=default_settings(q))

        t, _ = timed(run, repeats)
    return t, float(np.mean(ns))


def response_row(name: str, p: Oscillator, f: np.ndarray, R: int, fmu: Any) -> tuple[dict[str, Any], float, Any]:
    """The orbit method's response at the frequencies f: its time (min of R), the map's evaluations
    per point and their cost (counted and timed in one more run), and the point's cost against them
    (time per point / (evaluations per point x one evaluation's time): the "within 5x" figure)."""
    n = f.size
    t, ds = timed(lambda: frequency_response(p, f, fmu_path=fmu), R)
    t_run = time.perf_counter()
    n_eval, t_eval, _ = evaluations(lambda: frequency_response(p, f, fmu_path=fmu))
    t_run = time.perf_counter() - t_run
    per_eval = t_eval / max(n_eval, 1)
    # the point's cost against its evaluations' from the one counted run (both under the same load)
    row = {"case": name, "num": n, "seconds": t, "us_per_point": 1e6 * t / n,
           "evaluations_per_point": n_eval / n, "us_per_evaluation": 1e6 * per_eval,
           "point_over_evaluations": t_run / t_eval if n_eval else math.nan,
           "orbits": int(ds["n_orbits"].sum()), "stable": int(ds["stable"].values.sum()),
           "frequencies_with_a_stable_orbit": int(ds["converged"].sum()),
           "max_residual": float(np.nanmax(ds["residual"].values))}
    return row, t, ds


def transient_row(name: str, p: Oscillator, f: np.ndarray, t_orbit: float, ds: Any, R: int,
                  fmu: Any) -> dict[str, Any]:
    """The transient method at the frequencies f at each of TOLS beside the orbit method (section 2 of
    the module doc), and per target accuracy the cheapest tolerance that reaches it."""
    amp = ds["amplitude_m"].values[:, 0]
    exact = closed_form(p, f) if p.N == 0 else None
    # with friction: every stable orbit's amplitude, the response's and those of a cold find_orbits
    # at each frequency (untimed; where stable orbits coexist the response may follow one branch and
    # the transient reach another: its error is against the nearer)
    ref = exact[:, None] if exact is not None else stable_amplitudes(p, f, ds)
    row: dict[str, Any] = {"case": name, "num": f.size, "orbit_seconds": t_orbit,
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
        err = float(np.max(relative_error(tr["amplitude_m"].values, ref)))
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
    return row


def main(argv: list[str] | None = None) -> int:
    ap = make_parser("orbit_response.py", __doc__.splitlines()[0], exit=True)
    ap.add_argument("--num", type=count("--num", 2), default=401, help="frequencies per response (default 401)")
    ap.add_argument("--small", type=count("--small", 2), default=41,
                    help="frequencies of the short responses (default 41; none when not below --num)")
    ap.add_argument("--repeats", type=count("--repeats"), default=3, help="timing repeats, min taken (default 3)")
    ap.add_argument("--json", action="store_true", help="print one JSON object instead of the tables")
    ap.add_argument("--fmu", type=Path, default=None, help="the FMI 2.0 oscillator FMU (default: located)")
    args = ap.parse_args(argv)
    n, R, fmu = args.num, args.repeats, args.fmu
    sizes = [n] + ([args.small] if args.small < n else [])
    out: dict[str, Any] = {"num": n, "small": sizes[1] if len(sizes) > 1 else None, "repeats": R,
                           "responses": [], "transient": [], "responses_small": [], "transient_small": []}

    def cases(num: int) -> list[tuple[str, Oscillator, np.ndarray]]:
        return [("engineer 5-15 Hz", Oscillator.physical(**ENGINEER, f=5.0), np.linspace(5.0, 15.0, num)),
                ("zeta 0.01, N 0.1", Oscillator.physical(**LIGHT, N=0.1, omega=1.0),
                 np.linspace(0.5, 1.5, num) / (2 * math.pi)),
                ("zeta 0.01, N 0", Oscillator.physical(**LIGHT, N=0.0, omega=1.0),
                 np.linspace(0.5, 1.5, num) / (2 * math.pi))]

    first = cases(n)[0]
    frequency_response(first[1], first[2][:2], fmu_path=fmu)        # load once (not timed)
    for num in sizes:
        suffix = "" if num == n else "_small"
        for name, p, f in cases(num):
            # 1. the response with every orbit's stability; 2. the transient method beside it
            row, t_orbit, ds = response_row(name, p, f, R, fmu)
            out["responses" + suffix].append(row)
            out["transient" + suffix].append(transient_row(name, p, f, t_orbit, ds, R, fmu))

    if args.json:
        print(json.dumps(out))
        return 0
    for suffix in ("", "_small"):
        if not out["responses" + suffix]:
            continue
        num = out["responses" + suffix][0]["num"]
        print(f"\nfrequency responses from orbits, {num} points, every orbit's stability (min of {R} runs, wall time)")
        print(f"{'case':<20} {'seconds':>8} {'us/point':>8} {'evals/point':>11} {'us/eval':>7} {'point/evals':>11} "
              f"{'orbits':>7} {'stable':>7} {'with stable':>11} {'max residual':>12}")
        for r in out["responses" + suffix]:
            print(f"{r['case']:<20} {r['seconds']:8.3f} {r['us_per_point']:8.0f} {r['evaluations_per_point']:11.2f} "
                  f"{r['us_per_evaluation']:7.1f} {r['point_over_evaluations']:11.2f} "
                  f"{r['orbits']:7d} {r['stable']:7d} {r['frequencies_with_a_stable_orbit']:11d} "
                  f"{r['max_residual']:12.1e}")
        for row in out["transient" + suffix]:
            e = row["orbit_error"]
            print(f"\n{row['case']}, {num} points: orbit method {row['orbit_seconds']:.3f} s"
                  + (f", its amplitude error against the closed form {e:.1e}" if e is not None else ""))
            print(f"{'transient tol':>13} {'seconds':>8} {'orbit s':>8} {'x orbit':>8} {'max error':>10} "
                  f"{'converged':>9} {'periods':>8}")
            for r in row["tols"]:
                print(f"{r['tol']:13g} {r['seconds']:8.3f} {r['orbit_seconds']:8.3f} {r['ratio']:8.1f} "
                      f"{r['max_error']:10.1e} {r['converged']:9d} {r['mean_periods']:8.0f}")
            for target in TARGETS:
                c = row[f"target_{target:g}"]
                head = f"  accuracy {target:g}: "
                head += (f"transient tol {c['tol']:g}, {c['seconds']:.3f} s = {c['ratio']:.1f} x the orbit method "
                         f"({c['orbit_seconds']:.3f} s beside it)"
                         if c["tol"] is not None else "no transient tolerance reaches it")
                print(head + f"; its best case (hindsight: {c['best_case_mean_periods']:.0f} periods per point) "
                      f"{c['best_case_seconds']:.3f} s = {c['best_case_ratio']:.1f} x")
    print("\nsummary: transient / orbit time at the cheapest tolerance that reaches the accuracy (side by side)")
    print(f"{'case':<20} {'points':>6} {'orbit s':>8} {'1e-6: tol':>9} {'s':>7} {'x':>6} {'1e-10: tol':>10} {'s':>7} "
          f"{'x':>6} {'point/evals':>11}")
    for suffix in ("", "_small"):
        for resp, row in zip(out["responses" + suffix], out["transient" + suffix]):
            cells = []
            for target in TARGETS:
                c = row[f"target_{target:g}"]
                cells.append(f"{c['tol']:9g} {c['seconds']:7.3f} {c['ratio']:6.1f}" if c["tol"] is not None
                             else f"{'-':>9} {'-':>7} {'-':>6}")
            print(f"{resp['case']:<20} {resp['num']:6d} {resp['seconds']:8.3f} {cells[0]} {' ' + cells[1]} "
                  f"{resp['point_over_evaluations']:11.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
