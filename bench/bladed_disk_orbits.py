#!/usr/bin/env python3
"""The lumped bladed disk's orbits by its cyclic symmetry, timed, against references.

    OPENBLAS_NUM_THREADS=1 python bench/bladed_disk_orbits.py [--omegas 1070,1080] [--steps 1536]
        [--transients 120] [--reference] [--sweep 1060:1100:2] [--json]

1. Each frequency of ``--omegas`` (rad/s) from cold as a user would solve it:
   ``find_orbits(disk, symmetry=bladed_disk_symmetry(disk), transients=...)`` (no transient where the
   stuck closed form holds: that start is the orbit, one Newton step) at h = T / steps (T
   the period at that frequency), with the error estimate at h / 2: CPU time (the process's, one
   thread), the tip's amplitude (DOF 2) and Richardson's value, the estimate, and the errors against
   the references: where every contact stays stuck, the stuck closed form (a complex 96 x 96 solve,
   exact for the linear response); at 1080 rad/s the full period's orbits (no symmetry) at T/3200 and
   T/6400 extrapolated (``--reference`` computes them again, about 4 minutes; else the values measured
   with this script, REFERENCE below).
2. ``--sweep a:b:step``: the frequency response through them with the symmetry, the same h
   throughout (T / steps at the sweep's middle), its CPU time per point and the points converged.

pyHarm's numbers on the same structure are in bench/pyharm_system_results.md (its own environment:
bench/pyharm_peer.py --case bladed_disk). No timing is asserted anywhere.
"""

from __future__ import annotations

import argparse
import json
import time
from typing import Any

import numpy as np

from dryfriction.analysis.system_orbits import find_system_orbits, stuck_start
from dryfriction.system import cases

DOF = 2
#: the full period's orbits at 1080 rad/s (h = T / m, no symmetry; measured with --reference): the
#: tip's amplitude at m = 800, 1600, 3200, 6400
REFERENCE = {1080.0: {800: 7.790354192707821e-05, 1600: 7.814714156673962e-05, 3200: 7.81806281294121e-05,
                      6400: 7.818804355049527e-05}}


def reference(omega: float, measured: dict[int, float] | None = None) -> float | None:
    """Richardson's value from the two finest full-period orbits (None: none known)."""
    r = measured or REFERENCE.get(omega)
    if not r:
        return None
    a, b = sorted(r)[-2:]
    return r[b] + (r[b] - r[a]) / 3.0


def closed_form(omega: float) -> float | None:
    """The tip's amplitude of the stuck closed form where every contact stays stuck in it (else None)."""
    disk = cases.bladed_disk(omega=omega)
    z = stuck_start(disk)
    if z is None:
        return None
    n = disk.n
    return float(abs(complex(z[DOF], -z[n + DOF] / omega)))


def full_reference(omega: float, steps: tuple[int, ...] = (800, 1600, 3200, 6400)) -> dict[int, float]:
    """The full period's orbits (no symmetry) at T / steps, each from the last one's state."""
    T = 2.0 * np.pi / omega
    out: dict[int, float] = {}
    guess = None
    for m in steps:
        disk = cases.bladed_disk(omega=omega, h=T / m)
        kw: dict[str, Any] = {"transients": 0, "guesses": [guess]} if guess is not None else {"transients": 120}
        (o,) = find_system_orbits(disk, estimate_error=False, **kw)
        jenk = np.flatnonzero(disk.k_t > 0.0)
        guess = np.concatenate([o.x0, o.v0, o.s0[jenk]])
        out[m] = float(o.amplitude[DOF])
        print(f"  reference T/{m}: {out[m]:.12g} (residual {o.residual:.2g})", flush=True)
    return out


def point(omega: float, steps: int, transients: int) -> dict[str, Any]:
    """One frequency from cold with the symmetry (module doc, 1)."""
    T = 2.0 * np.pi / omega
    disk = cases.bladed_disk(omega=omega, h=T / steps)
    sym = cases.bladed_disk_symmetry(disk)
    if stuck_start(disk) is not None:
        transients = 0
    c0 = time.process_time()
    orbits = find_system_orbits(disk, transients=transients, symmetry=sym, keep_failed=True)
    cpu = time.process_time() - c0
    o = orbits[0]
    ex = o.amplitude_extrapolated[DOF] if o.amplitude_extrapolated.size else float("nan")
    return {"omega": omega, "steps": steps, "cpu_s": cpu, "converged": bool(o.converged), "reason": o.reason,
            "amplitude": float(o.amplitude[DOF]), "extrapolated": float(ex), "error_estimate": float(o.error),
            "stick_fraction": float(np.mean(o.stick_fraction)), "mu_max": float(np.max(np.abs(o.multipliers)))}


def sweep(spec: str, steps: int, transients: int) -> dict[str, Any]:
    """The response through a:b:step rad/s with the symmetry (module doc, 2)."""
    a, b, st = (float(x) for x in spec.split(":"))
    om = np.arange(a, b + 0.5 * st, st)
    mid = 0.5 * (a + b)
    disk = cases.bladed_disk(omega=mid, h=2.0 * np.pi / mid / steps)
    from dryfriction.analysis.system_response import system_frequency_response

    c0 = time.process_time()
    ds = system_frequency_response(disk, om / (2.0 * np.pi), dof=DOF, transients=transients,
                                   symmetry=cases.bladed_disk_symmetry(disk))
    cpu = time.process_time() - c0
    return {"omegas": om.tolist(), "cpu_s": cpu, "per_point_s": cpu / om.size,
            "converged": ds.converged.values.tolist(), "amplitude": ds.amplitude_dof_m.values.tolist(),
            "reason": [str(r) for r in ds.reason.values]}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--omegas", default="1070,1080", help="rad/s, comma-separated (default 1070,1080)")
    ap.add_argument("--steps", type=int, default=1536, help="steps per period (default 1536: 64 a sector)")
    ap.add_argument("--transients", type=int, default=120, help="periods of the cold start's transient")
    ap.add_argument("--reference", action="store_true", help="compute the 1080 rad/s full-period reference again")
    ap.add_argument("--sweep", default="", help="a:b:step rad/s: a frequency response (module doc)")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    out: dict[str, Any] = {"points": []}
    measured = full_reference(1080.0) if args.reference else None
    for om in (float(x) for x in args.omegas.split(",") if x):
        row = point(om, args.steps, args.transients)
        cf = closed_form(om)
        ref = cf if cf is not None else reference(om, measured if om == 1080.0 else None)
        row["reference"] = ref
        row["reference_kind"] = "stuck closed form" if cf is not None else ("full-period orbits" if ref else "none")
        for k in ("amplitude", "extrapolated"):
            row[f"{k}_error"] = abs(row[k] - ref) / ref if ref else float("nan")
        out["points"].append(row)
        print(f"omega {om:g}: {row['cpu_s']:.2f} s, converged {row['converged']} {row['reason'][:60]}; A(h/2) "
              f"{row['amplitude']:.10g} ({row['amplitude_error']:.2g} off), Richardson {row['extrapolated']:.10g} "
              f"({row['extrapolated_error']:.2g} off), estimate {row['error_estimate']:.2g} m, against the "
              f"{row['reference_kind']} {ref if ref else float('nan'):.10g}", flush=True)
    if args.sweep:
        out["sweep"] = sweep(args.sweep, args.steps, args.transients)
        sw = out["sweep"]
        print(f"sweep {args.sweep}: {sw['cpu_s']:.1f} s, {sw['per_point_s']:.2f} s a point, "
              f"{sum(sw['converged'])} of {len(sw['converged'])} converged")
    if args.json:
        print(json.dumps(out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
