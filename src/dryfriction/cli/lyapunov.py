"""``dryfriction lyapunov``: the largest Lyapunov exponent of one motion (see docs/chaos.md).

    dryfriction lyapunov --lam L --mu-s-sigma S --chi C [--zeta Z] [--z0 Z0 --dz0 V0]
                         [--periods N] [--transient N] [--d0 D] [--renorm N]
                         [--steps-per-period N] [--scheme NAME | --exact] [--json]

The FMU's ``exact`` scheme is the default (``--scheme located`` etc. select the Bossak schemes,
``--exact`` the Python exact solution); the output names the scheme.

The main parser only adds the subcommand (:func:`add_lyapunov_parser`) and calls
:func:`lyapunov_main`; bad values end with one readable line and exit status 2 through the main
parser's error handling.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from typing import Any

from ..errors import UsageError
from .options import count, number
from ..drivers.oscillator import SCHEMES
from ..analysis.chaos.attractors import period_of
from ..analysis.chaos.lyapunov import benettin
from ..analysis.chaos.maps import DEFAULT_SCHEME, ExactMap, FMUMap, NDParams, step_free

__all__ = ["add_lyapunov_parser", "lyapunov_main"]


def add_lyapunov_parser(sub: Any, parents: list[argparse.ArgumentParser] | None = None) -> argparse.ArgumentParser:
    """Add the ``lyapunov`` subcommand to the subparsers ``sub`` of the main parser (``parents``: the
    options every subcommand accepts)."""
    p = sub.add_parser("lyapunov", parents=parents or [], help="largest Lyapunov exponent of one motion (Benettin, two trajectories)",
                       description="Largest Lyapunov exponent of the stroboscopic map, per excitation period and "
                                   "per second, with a convergence estimate.")
    p.add_argument("--lam", type=number("--lam", 0.0, True), required=True, help="frequency ratio omega / w0")
    p.add_argument("--mu-s-sigma", type=number("--mu-s-sigma", 0.0), required=True, help="mu_s N / P0")
    p.add_argument("--chi", type=number("--chi", 0.0, True), required=True, help="mu_k / mu_s")
    p.add_argument("--zeta", type=number("--zeta", 0.0), default=0.0, help="damping ratio (default 0)")
    p.add_argument("--z0", type=number("--z0"), default=0.0, help="initial z = k x / P0 (default 0)")
    p.add_argument("--dz0", type=number("--dz0"), default=0.0, help="initial dz/dtau (default 0)")
    p.add_argument("--periods", type=count("--periods", 20), default=500, help="measured periods (default 500)")
    p.add_argument("--transient", type=count("--transient", 0), default=100, help="periods first dropped (100)")
    p.add_argument("--d0", type=number("--d0", 0.0, True, 1e-2), default=1e-8, help="initial separation (1e-8)")
    p.add_argument("--renorm", type=count("--renorm", 1), default=1, help="periods between renormalisations (1)")
    p.add_argument("--steps-per-period", type=count("--steps-per-period", 10), default=1000,
                   help="FMU internal steps per period, h = T / N (default 1000; no effect on the exact scheme)")
    p.add_argument("--scheme", choices=list(SCHEMES), default=DEFAULT_SCHEME,
                   help=f"FMU scheme (default {DEFAULT_SCHEME}: closed form between events)")
    p.add_argument("--exact", action="store_true",
                   help="use the Python exact piecewise solution (dryfriction.references.exact, an independent reference) "
                        "instead of the FMU")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    return p


def lyapunov_main(args: argparse.Namespace) -> int:
    """Run the ``lyapunov`` subcommand; returns the exit status."""
    from ..drivers.oscillator import OscillatorFMU2

    if args.renorm > args.periods:
        raise UsageError(f"--renorm ({args.renorm}) must not exceed --periods ({args.periods})")
    nd = NDParams(args.lam, args.mu_s_sigma, args.chi, args.zeta)
    fmu = None
    try:
        if args.exact:
            m: Any = ExactMap(nd)
        else:
            fmu = OscillatorFMU2(getattr(args, "fmu", None))
            m = FMUMap(fmu, nd, args.steps_per_period, args.scheme)
        r = benettin(m, args.z0, args.dz0, periods=args.periods, transient=args.transient, d0=args.d0,
                     renorm=args.renorm)
    finally:
        if fmu is not None:
            fmu.close()
    tail = r.strobe[-min(64, r.strobe.shape[0]):]
    p_strobe = period_of(tail, 1e-6) if args.renorm == 1 else -1
    out = {
        "lyapunov_per_period": r.lyapunov_per_period,
        "lyapunov_per_second": r.lyapunov_per_second,
        "periods": r.periods,
        "stderr_per_period": r.stderr_per_period,
        "half_difference": r.half_difference,
        "transient": r.transient,
        "renorm": r.renorm,
        "d0": r.d0,
        "collapses": r.collapses,
        "period_s": r.period_s,
        "stroboscopic_period": p_strobe,
        "last_point": [float(x) for x in r.strobe[-1]],
        "params": {"lam": nd.lam, "mu_s_sigma": nd.mu_s_sigma, "chi": nd.chi, "zeta": nd.zeta,
                   "z0": args.z0, "dz0": args.dz0},
        "method": r.method,
        "map": "dryfriction.references.exact" if args.exact else "FMU",
        "scheme": "exact (dryfriction.references.exact)" if args.exact else args.scheme,
        "steps_per_period": None if args.exact or step_free(args.scheme) else args.steps_per_period,
    }
    if args.json:
        print(json.dumps(out))
        return 0
    verdict = ("positive: chaotic" if r.lyapunov_per_period - 3 * r.stderr_per_period > 0
               else "negative: regular" if r.lyapunov_per_period + 3 * r.stderr_per_period < 0 else "not distinguishable from 0")
    ps = {-1: "n/a (renorm > 1)", 0: "none up to 8"}.get(p_strobe, str(p_strobe))
    print(f"largest Lyapunov exponent {r.lyapunov_per_period:+.5f} per period ({r.lyapunov_per_second:+.5f} 1/s), "
          f"standard error {r.stderr_per_period:.1e}, over {r.periods} periods after {r.transient}: {verdict}\n"
          f"stroboscopic period {ps}; {r.method}", file=sys.stdout)
    return 0
