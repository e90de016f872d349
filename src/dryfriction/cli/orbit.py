"""``dryfriction orbit``: the periodic orbits of one oscillator, with their Floquet multipliers
(:func:`dryfriction.analysis.orbits.find_orbits`; docs/orbits.md).

    dryfriction orbit --lam 0.5 --mu-s-sigma 0.6 --chi 0.4 [--zeta Z] [--phi P] --period 1 [--json]
    dryfriction orbit --m 1 --k 100 --zeta 0.01 --P0 1 --f 1.2 --N 0.5 --mu-s 0.3 --period 2 --json

The oscillator is given in the paper's non-dimensional form (as ``dryfriction lyapunov``: --lam,
--mu-s-sigma, --chi, --zeta) or in physical units (as ``dryfriction run``: --m, --k, --c | --zeta,
--P0, --f | --omega, --N, --mu-s, --mu-k). A table by default; ``--json`` prints exactly one object
``{"orbits": [{"period", "stable", "neutral", "multipliers": [[re, im], ...], "x0", "v0", "z0", "zdot0",
"amplitude_m", "offset_m", "stick_fraction", "residual", "rest_interval_m"}, ...]}`` (x0 in m, v0 in
m/s, z0 = k x0 / P0 and zdot0 = dz/dtau, tau = w0 t, at t = 0 mod K T; null for NaN or infinite;
``rest_interval_m`` [from, to] for the block at rest, else null).

The orbits listed are those of period K and those whose minimal period divides K (a period-1 orbit
asked for as K = 2 comes back after one period and is listed once, with its period 1); the last
line counts them by period. The block at rest (P0 within the breakaway force) is one row, neutral,
and one line gives the interval of its rest positions.
"""

from __future__ import annotations

import argparse
import math
from typing import Any

from .options import (NONDIM, PHYSICAL, UsageError, count, nondim_given, nondim_options, number, one_form, physical,
                      physical_options)
from .output import finite, percent, print_json, rest_line

__all__ = ["add_parser", "run", "work", "orbit_json", "orbit_headline"]


def add_parser(sub: Any, parents: list[argparse.ArgumentParser]) -> None:
    """Add the ``orbit`` command to the main parser's subparsers ``sub``."""
    o = sub.add_parser("orbit", parents=parents, help="periodic orbits of K excitation periods with their stability",
                       description="Every periodic orbit of K excitation periods found by Newton shooting on the "
                                   "exact stroboscopic map, with its Floquet multipliers (docs/orbits.md).")
    nondim_options(o, "non-dimensional form (the paper's, as dryfriction lyapunov)", chi_lo_open=True)
    o.add_argument("--zeta", type=number("--zeta", 0.0), default=None, help="damping ratio (both forms; default 0)")
    o.add_argument("--phi", type=number("--phi"), default=0.0, help="excitation phase, rad (both forms; default 0)")
    physical_options(o.add_argument_group("physical units (SI; any of these selects them)"), required=False)
    o.add_argument("--period", type=count("--period"), default=1, help="K: excitation periods of the orbit (default 1)")
    o.add_argument("--transients", type=count("--transients", 0), default=60,
                   help="K-periods of the transients that give the guesses (default 60)")
    o.add_argument("--json", action="store_true", help="print one JSON object")


def work(args: argparse.Namespace) -> tuple[float, str]:
    """The searches' steps: a transient and a few Newton periods from each guess."""
    from ..analysis.orbits import DEFAULT_SPREAD
    from ..budget import EXACT_PERIOD_STEPS, fmt

    n = len(DEFAULT_SPREAD)
    periods = n * (int(args.transients) + 10) * int(args.period)
    return periods * EXACT_PERIOD_STEPS, f"{n} searches x {fmt(periods / n)} periods x {EXACT_PERIOD_STEPS:g} steps"


def _oscillator(args: argparse.Namespace) -> Any:
    from ..params import Oscillator

    given = [n for n in PHYSICAL if n not in ("x0", "v0") and getattr(args, n) is not None]
    nondim = nondim_given(args)
    if given:
        one_form(nondim, given[0])
    try:
        if given:
            p = physical(args)
            if args.phi:
                p = p.with_(phi=args.phi)
        else:
            missing = [f"--{n.replace('_', '-')}" for n in NONDIM if n not in nondim]
            if missing:
                raise UsageError(f"the non-dimensional form needs {', '.join(missing)} (or give physical units: "
                                 "--m --k --P0 --f --N --mu-s)")
            p = Oscillator.from_nondimensional(lam=args.lam, mu_s_sigma=args.mu_s_sigma, chi=args.chi,
                                               zeta=args.zeta or 0.0, phi=args.phi)
    except ValueError as e:
        if isinstance(e, UsageError):
            raise
        raise UsageError(str(e)) from None
    if not (p.omega > 0 and p.P0 != 0):
        raise UsageError("an orbit needs an excitation: the frequency must be > 0 and P0 != 0 (the self-excited "
                         "orbits of the autonomous case, on a moving belt: dryfriction belt)")
    return p


def orbit_json(orbits: list[Any]) -> dict[str, Any]:
    """The ``--json`` object of a list of :class:`~dryfriction.analysis.orbits.Orbit`."""
    return {"orbits": [{"period": o.period, "stable": bool(o.stable), "neutral": bool(o.neutral),
                        "multipliers": [[float(m.real), float(m.imag)] for m in o.multipliers],
                        "x0": o.x0, "v0": o.v0, "z0": finite(o.z0), "zdot0": finite(o.zdot0),
                        "amplitude_m": o.amplitude, "offset_m": o.offset, "stick_fraction": o.stick_fraction,
                        "residual": finite(o.residual),
                        "rest_interval_m": None if o.rest_interval is None else [finite(v) for v in o.rest_interval]}
                       for o in orbits]}


def _stability(o: Any) -> str:
    """stable, neutral (the block at rest; a family shifted in x) or unstable, as the tables print it."""
    return "True" if o.stable else ("neutral" if o.neutral else "False")


def orbit_headline(orbits: list[Any], K: int) -> str:
    """The table's count: the orbits of period K, then those whose minimal period is a divisor j < K
    (found as K-orbits, they repeat after j periods), each with its stable (and neutral) ones."""
    def count(group: list[Any]) -> str:
        neutral = sum(bool(o.neutral) for o in group)
        return f"{sum(bool(o.stable) for o in group)} stable" + (f", {neutral} neutral" if neutral else "")

    per = lambda n: "s" if n != 1 else ""     # noqa: E731
    own = [o for o in orbits if o.period == K]
    line = f"{len(own)} orbit{per(len(own))} of {K} excitation period{per(K)} found ({count(own)})"
    for j in sorted({o.period for o in orbits if o.period != K}, reverse=True):
        group = [o for o in orbits if o.period == j]
        line += (f"; {len(group)} of period {j} ({count(group)}), listed with their minimal period: they repeat "
                 f"after {j} period{per(j)}, so after {K} too")
    return line


def run(args: argparse.Namespace) -> int:
    """Run ``dryfriction orbit``; the exit status."""
    from ..analysis.orbits import find_orbits
    from ..drivers.oscillator import OscillatorFMU2

    p = _oscillator(args)
    with OscillatorFMU2(args.fmu) as fmu:
        orbits = find_orbits(p, period=args.period, fmu=fmu, transients=args.transients)
    if args.json:
        print_json(orbit_json(orbits))
        return 0
    print(f"{'#':>2} {'K':>2} {'stable':>7} {'|mu|max':>9} {'multipliers':>30} {'amplitude (m)':>14} "
          f"{'offset (m)':>11} {'stuck (%)':>9} {'x0 (m)':>12} {'v0 (m/s)':>12} {'residual':>8}")
    for i, o in enumerate(orbits, 1):
        mu = ", ".join(f"{m.real:.4g}" + (f"{m.imag:+.3g}j" if m.imag else "") for m in o.multipliers)
        print(f"{i:2d} {o.period:2d} {_stability(o):>7} {o.mu_max:9.4g} {mu:>30} {o.amplitude:14.6g} "
              f"{o.offset:11.3g} {percent(o.stick_fraction):>9} {o.x0:12.6g} {o.v0:12.6g} {o.residual:8.1e}")
    print(f"{orbit_headline(orbits, args.period)}; "
          f"T = {p.period:.6g} s, static deflection P0/k = {abs(p.P0) / p.k if p.k > 0 else math.nan:.4g} m")
    for o in orbits:
        if o.rest_interval is not None:
            print(rest_line(o.rest_interval, p))
    return 0
