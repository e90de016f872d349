#!/usr/bin/env python3
"""pyHarm (harmonic balance with its DLFT friction element) against the exact periodic orbit.

    python bench/pyharm_peer.py [--harmonics 5,10,20] [--nti 256] [--repeats 3] [--json]

Installs pyHarm (``pip install pyharm-os``, the package index's name) into this Python environment
when it cannot be imported; if that fails, one line on stderr and exit status 1. pyHarm is not a
dependency of the package and has no CI stage (a peer measured by hand, as the Siconos one).

The case both tools model: one mass m = 1 kg on a spring k = 1 N/m, damping zeta = 0.01, excitation
P0 = 1 N, Coulomb friction with one coefficient (mu_s = mu_k = 1, N = 0.3 N: mu N / P0 = 0.3), at
lambda = omega / w0 = 0.5 (stick-slip), 0.8, 1.0 (resonance), 1.2, 1.5. pyHarm: a 1-dof system
(GOElement for the mass, LinearSpring, LinearDamper, CosinusForcing, DLFTFriction with penalty
``--eps``), ``nh`` harmonics and ``--nti`` time samples (at its defaults, eps 1e3 and 256 samples,
the error stays near 1e-2 off resonance whatever nh: the reversals are located to a sample), one solve at the frequency (the analysis' first point,
from its linear guess; no continuation). Its amplitude is half the peak-to-peak of its Fourier
series sampled 8192 times per period. Ours: ``find_orbits`` (the exact stroboscopic map, residual
1e-12). Error: |A_pyHarm - A_orbit| / A_orbit. Times: wall, min of ``--repeats``, per frequency,
after one warm-up (pyHarm's numba kernels compile on first use); pyHarm's includes building its
system (Maestro), ours the FMU's transients and Newton solves of a cold ``find_orbits`` (one FMU
instance loaded once).
"""

from __future__ import annotations

import contextlib
import importlib
import json
import logging
import math
import subprocess
import sys
import tempfile
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from dryfriction.cli.options import count, make_parser, number

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))
from timing import timed  # noqa: E402  (bench/timing.py)

CASE = dict(m=1.0, k=1.0, zeta=0.01, P0=1.0, N=0.3, mu=1.0)
LAMBDAS = (0.5, 0.8, 1.0, 1.2, 1.5)


def ensure_pyharm() -> Any:
    """pyHarm's Maestro, installed with pip first if needed; exit 1 with one line if impossible."""
    try:
        return importlib.import_module("pyHarm.Maestro").Maestro
    except ImportError:
        pass
    r = subprocess.run([sys.executable, "-m", "pip", "install", "-q", "pyharm-os"], capture_output=True, text=True)
    try:
        if r.returncode != 0:
            raise ImportError(r.stderr.strip().splitlines()[-1] if r.stderr.strip() else f"pip exit {r.returncode}")
        importlib.invalidate_caches()
        return importlib.import_module("pyHarm.Maestro").Maestro
    except ImportError as e:
        print(f"pyharm_peer.py: error: pyHarm (pip install pyharm-os) could not be installed or imported: {e}",
              file=sys.stderr)
        raise SystemExit(1) from None


def pyharm_input(w: float, nh: int, nti: int, eps: float = 1e3) -> dict[str, Any]:
    m, k, P0, N, mu = CASE["m"], CASE["k"], CASE["P0"], CASE["N"], CASE["mu"]
    c = 2.0 * CASE["zeta"] * math.sqrt(k * m)
    con = {"connect": {"block": [0]}, "dirs": [0]}
    return {
        "system": {"type": "Base", "nh": nh, "nti": nti},
        "substructures": {"block": {"type": "onlydofs", "ndofs": 1, "nnodes": 1, "matrix": {}}},
        "connectors": {
            "mass": {"type": "GOElement", "dto": 2, "xo": 1, "k": m, **con},
            "spring": {"type": "LinearSpring", "k": k, **con},
            "damper": {"type": "LinearDamper", "k": c, **con},
            "force": {"type": "CosinusForcing", "amp": P0, **con},
            "friction": {"type": "DLFTFriction", "mu": mu, "N0": N, "eps": eps, **con},
        },
        "analysis": {"frf": {"study": "frf", "puls_inf": w, "puls_sup": 2.0 * w, "verbose": False}},
    }


def fourier_amplitude(x: np.ndarray, nh: int, n: int = 8192) -> float:
    """Half the peak-to-peak of x0 + sum_h a_h cos(h t) + b_h sin(h t) over one period."""
    t = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
    y = np.full(n, float(x[0]))
    for h in range(1, nh + 1):
        y += x[2 * h - 1] * np.cos(h * t) + x[2 * h] * np.sin(h * t)
    return 0.5 * float(y.max() - y.min())


def pyharm_amplitude(Maestro: Any, w: float, nh: int, nti: int, eps: float) -> tuple[float, bool]:
    M = Maestro(pyharm_input(w, nh, nti, eps))
    an = M.nls["frf"]
    an.initialise(None)
    sol = an.SolList[0]
    return fourier_amplitude(np.asarray(sol.x, dtype=float), nh), bool(getattr(sol, "flag_R", True))


def main(argv: list[str] | None = None) -> int:
    # pyHarm writes its kernel state (.pyHarm/context.json) into the working folder: a temporary one
    with tempfile.TemporaryDirectory(prefix="pyharm_peer_") as tmp, contextlib.chdir(tmp):
        return _main(argv)


def _main(argv: list[str] | None) -> int:
    ap = make_parser("pyharm_peer.py", __doc__.splitlines()[0], exit=True)
    ap.add_argument("--harmonics", default="5,10,20", help="pyHarm's numbers of harmonics (default 5,10,20)")
    ap.add_argument("--nti", type=count("--nti", 8), default=1024,
                    help="pyHarm's time samples per period (default 1024)")
    ap.add_argument("--eps", type=number("--eps", 0.0, True), default=1e3,
                    help="pyHarm's DLFT penalty (default 1e3, its own; 1e5 sends its solver to wrong solutions)")
    ap.add_argument("--repeats", type=count("--repeats"), default=3, help="timing repeats, min taken (default 3)")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    args = ap.parse_args(argv)
    try:
        harmonics = [int(h) for h in args.harmonics.split(",")]
        if any(h < 1 for h in harmonics):
            raise ValueError
    except ValueError:
        ap.error(f"--harmonics must be a comma-separated list of whole numbers >= 1, not {args.harmonics!r}")
    Maestro = ensure_pyharm()
    logging.disable(logging.CRITICAL)            # pyHarm's banner and per-step log
    warnings.filterwarnings("ignore", module="numba")
    warnings.filterwarnings("ignore", category=Warning, module="pyHarm")

    from dryfriction import Oscillator
    from dryfriction.drivers.oscillator import OscillatorFMU2
    from dryfriction.analysis.orbits import find_orbits

    base = Oscillator.physical(m=CASE["m"], k=CASE["k"], zeta=CASE["zeta"], P0=CASE["P0"], omega=1.0, N=CASE["N"],
                               mu_s=CASE["mu"], mu_k=CASE["mu"])
    pyharm_amplitude(Maestro, 1.0, harmonics[0], args.nti, args.eps)     # numba's compilation: not timed
    rows = []
    with OscillatorFMU2() as fmu:
        for lam in LAMBDAS:
            p = base.with_(omega=lam * base.w0)
            t_orbit, orbits = timed(lambda: find_orbits(p, fmu=fmu), args.repeats)
            stable = [o for o in orbits if o.stable]
            if len(stable) != 1:
                print(f"pyharm_peer.py: error: {len(stable)} stable orbits at lambda {lam}, expected one",
                      file=sys.stderr)
                return 1
            o = stable[0]
            row: dict[str, Any] = {"lambda": lam, "orbit_amplitude_m": o.amplitude, "stick_fraction": o.stick_fraction,
                                   "orbit_residual": o.residual, "orbit_seconds": t_orbit, "pyharm": []}
            for nh in harmonics:
                t_ph, (a, ok) = timed(lambda: pyharm_amplitude(Maestro, lam * base.w0, nh, args.nti, args.eps),
                                      args.repeats)
                row["pyharm"].append({"harmonics": nh, "amplitude_m": a, "converged": ok,
                                      "error": abs(a - o.amplitude) / o.amplitude, "seconds": t_ph})
            rows.append(row)
    version = importlib.import_module("pyHarm").__dict__.get("__version__", "?")
    out = {"case": CASE, "nti": args.nti, "eps": args.eps, "pyharm_version": version, "rows": rows}
    if args.json:
        print(json.dumps(out))
        return 0
    print(f"pyHarm {version} (DLFT friction, nti {args.nti}, eps {args.eps:g}) against the exact orbit: m = k = 1, zeta = 0.01, "
          f"P0 = 1, mu N / P0 = 0.3, mu_s = mu_k")
    head = f"{'lambda':>6} {'orbit A (m)':>12} {'stuck %':>7} {'orbit s':>8}"
    for nh in harmonics:
        head += f" {'err ' + str(nh) + ' h':>9} {'s ' + str(nh) + ' h':>7}"
    print(head)
    for r in rows:
        line = f"{r['lambda']:6.2f} {r['orbit_amplitude_m']:12.6g} {100 * r['stick_fraction']:7.1f} {r['orbit_seconds']:8.4f}"
        for q in r["pyharm"]:
            line += f" {q['error']:9.1e} {q['seconds']:7.3f}" + ("" if q["converged"] else "!")
        print(line)
    print("err: |A_pyHarm - A_orbit| / A_orbit; s: wall seconds per frequency (min of "
          f"{args.repeats}); '!': pyHarm's solver did not report convergence")
    return 0


if __name__ == "__main__":
    sys.exit(main())
