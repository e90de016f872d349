#!/usr/bin/env python3
"""What a structure's periodic orbit costs per frequency point against its accuracy: the orbit method
(`frequency_response(system)`: Newton shooting on the located map with the FMU's Jacobian, each
point from the last) at several internal steps, with and without its Richardson extrapolation,
against the event-driven reference.

    python bench/system_orbit_cost.py [--omegas 1.0,1.4,1.8,2.5] [--steps 50,100,...] [--repeats 3] [--json]

The case: the two-mass structure with a Jenkins element between the masses that the harmonic-balance
tools take as their benchmark (M = diag(1, 0.5), K = [[3, -1], [-1, 1]], C = 0.02 K + 0.02 M, force
[1, 0] cos(omega t), k_t = 20, N = 0.6, mu = 0.5; :func:`case`). Reference: the amplitude of mass 0 of
the event-driven reference run to its periodic state (`dryfriction.references.system`, DOP853 at rtol
1e-12, every switch located by Brent's method, run long: estimated error below 3e-12; the constants
in :data:`REFERENCE`, measured with `bench/pyharm_peer.py --case two_mass`'s reference). A point's
cost: a sweep of :data:`SWEEP_POINTS` frequencies over the last 2 % up to omega (one FMU instance,
each point from the last point's orbit, as a frequency sweep runs), its CPU time (process time, the
least of ``--repeats``) over the points; the error of the last point's amplitude (omega itself).
Prints per omega and steps per period: the error of the amplitude at h, of Richardson's value from h
and h / 2, and each one's CPU time; ``--json`` the rows. `bench/pyharm_peer.py --case two_mass` runs
it beside pyHarm in one process.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from typing import Any

import numpy as np

from dryfriction import Contact, System
from dryfriction.analysis.system_response import system_frequency_response
from dryfriction.drivers.system import SystemFMU3

#: mass 0's amplitude of the event-driven reference's periodic state at each omega (module doc)
REFERENCE = {1.0: 5.22200001771, 1.4: 0.435961547973, 1.8: 0.446895397793, 2.5: 0.210591930011}
#: a point's cost: a sweep of SWEEP_POINTS frequencies over the last SWEEP_SPAN of omega, up to omega
SWEEP_POINTS, SWEEP_SPAN = 11, 0.02


def case(omega: float, h: float = 0.0) -> System:
    """The two-mass structure with a Jenkins element between the masses (module doc)."""
    M = np.diag([1.0, 0.5])
    K = np.array([[3.0, -1.0], [-1.0, 1.0]])
    return System(M=M, K=K, C=0.02 * K + 0.02 * M, F_c=[1.0, 0.0], omega=omega, h=h,
                  contacts=[Contact(between=(0, 1), N=0.6, mu_s=0.5, mu_k=0.5, k_t=20.0)])


def measure(omegas: list[float], steps: list[int], repeats: int, points: int = SWEEP_POINTS) -> list[dict[str, Any]]:
    """The rows: per omega, steps per period and with / without Richardson, error and CPU time per
    frequency point of a sweep (module doc)."""
    rows = []
    with SystemFMU3(case(omegas[0])) as fmu:
        for w in omegas:
            ref = REFERENCE[w]
            T = 2.0 * math.pi / w
            f_hz = np.linspace(w * (1.0 - SWEEP_SPAN), w, points) / (2.0 * math.pi)
            for n in steps:
                for richardson in (False, True):
                    best, ds = math.inf, None
                    for _ in range(repeats):
                        t0 = time.process_time()
                        ds = system_frequency_response(case(w, T / n), f_hz, dof=0, estimate_error=richardson,
                                                       fmu=fmu)
                        best = min(best, time.process_time() - t0)
                    assert ds is not None
                    last = ds.isel(f_hz=-1)
                    a = float(last["amplitude_extrapolated_m" if richardson else "amplitude_m"][0])
                    rows.append({"omega": w, "steps_per_period": n, "richardson": richardson,
                                 "error": abs(a - ref) / ref, "cpu_s": best / points,
                                 "converged": bool(ds["converged"].all()),
                                 "estimated_error": float(last["error_m"]) / ref if richardson else None})
    return rows


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--omegas", default="1.0,1.4,1.8,2.5", help="the excitation frequencies, rad/s")
    ap.add_argument("--steps", default="25,50,100,200,400,800,1600,3200", help="internal steps per period")
    ap.add_argument("--repeats", type=int, default=3, help="timing repeats (the least)")
    ap.add_argument("--json", action="store_true", help="print the rows as JSON")
    args = ap.parse_args()
    omegas = [float(v) for v in args.omegas.split(",")]
    bad = [w for w in omegas if w not in REFERENCE]
    if bad:
        print(f"system_orbit_cost: no reference at omega {bad[0]} (have {sorted(REFERENCE)})", file=sys.stderr)
        return 2
    rows = measure(omegas, [int(v) for v in args.steps.split(",")], max(1, args.repeats))
    if args.json:
        print(json.dumps(rows, indent=1))
        return 0
    print("omega  steps/T  error(h)   CPU ms   error(Richardson)  CPU ms")
    for w in omegas:
        for n in sorted({r["steps_per_period"] for r in rows}):
            a, b = (next(r for r in rows if r["omega"] == w and r["steps_per_period"] == n and r["richardson"] == x)
                    for x in (False, True))
            print(f"{w:5.2f}  {n:7d}  {a['error']:.2e}  {1e3 * a['cpu_s']:7.1f}   {b['error']:.2e}          "
                  f"{1e3 * b['cpu_s']:7.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
