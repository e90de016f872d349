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
import json
import math
from typing import Any

from ..errors import UsageError
from .options import count, number

__all__ = ["add_orbit_parser", "orbit_main", "orbit_json"]

NONDIM = ("lam", "mu_s_sigma", "chi")


def add_orbit_parser(sub: Any, parents: list[argparse.ArgumentParser]) -> argparse.ArgumentParser:
    """Add the ``orbit`` command and its options to the subcommands ``sub``."""
    from .options import _physical_options

    o = sub.add_parser("orbit", parents=parents, help="periodic orbits of K excitation periods with their stability",
                       description="Every periodic orbit of K excitation periods found by Newton shooting on the "
                                   "exact stroboscopic map, with its Floquet multipliers (docs/orbits.md).")
    nd = o.add_argument_group("non-dimensional form (the paper's, as dryfriction lyapunov)")
    nd.add_argument("--lam", type=number("--lam", 0.0, True), default=None, help="frequency ratio omega / w0")
    nd.add_argument("--mu-s-sigma", type=number("--mu-s-sigma", 0.0), default=None, help="mu_s N / P0")
    nd.add_argument("--chi", type=number("--chi", 0.0, True), default=None, help="mu_k / mu_s")
    o.add_argument("--zeta", type=number("--zeta", 0.0), default=None, help="damping ratio (both forms; default 0)")
    o.add_argument("--phi", type=number("--phi"), default=0.0, help="excitation phase, rad (both forms; default 0)")
    _physical_options(o.add_argument_group("physical units (SI; any of these selects them)"), required=False)
    o.add_argument("--period", type=count("--period"), default=1, help="K: excitation periods of the orbit (default 1)")
    o.add_argument("--transients", type=count("--transients", 0), default=60,
                   help="K-periods of the transients that give the guesses (default 60)")
    o.add_argument("--json", action="store_true", help="print one JSON object")
    return o


def _oscillator(args: argparse.Namespace) -> Any:
    from .options import PHYSICAL, _physical
    from ..params import Oscillator

    physical = [n for n in PHYSICAL if n not in ("x0", "v0") and getattr(args, n) is not None]
    nondim = [n for n in NONDIM if getattr(args, n) is not None]
    if physical and nondim:
        raise UsageError(f"give physical units or the non-dimensional form, not both (--{nondim[0].replace('_', '-')} "
                         f"and --{physical[0].replace('_', '-')})")
    try:
        if physical:
            p = _physical(args)
            if args.phi:
                p = p.with_(phi=args.phi)
        else:
            missing = [f"--{n.replace('_', '-')}" for n in NONDIM if getattr(args, n) is None]
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


def _percent(share: float) -> str:
    """A share in % with one decimal, more where that would read 0 or 100 of a share that is neither
    (a block stuck but for slides of 1e-4 of the cycle is not at rest)."""
    text = f"{100 * share:.1f}"
    digits = 1
    while 0.0 < share < 1.0 and text in ("0.0", "100.0") and digits < 12:
        digits += 1
        text = f"{100 * share:.{digits}f}"
    return text


def _num(v: float) -> float | None:
    return float(v) if math.isfinite(v) else None


def orbit_json(orbits: list[Any]) -> dict[str, Any]:
    """The ``--json`` object of a list of :class:`~dryfriction.analysis.orbits.Orbit`."""
    return {"orbits": [{"period": o.period, "stable": bool(o.stable), "neutral": bool(o.neutral),
                        "multipliers": [[float(m.real), float(m.imag)] for m in o.multipliers],
                        "x0": o.x0, "v0": o.v0, "z0": _num(o.z0), "zdot0": _num(o.zdot0),
                        "amplitude_m": o.amplitude, "offset_m": o.offset, "stick_fraction": o.stick_fraction,
                        "residual": _num(o.residual),
                        "rest_interval_m": None if o.rest_interval is None else [_num(v) for v in o.rest_interval]}
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


def orbit_main(args: argparse.Namespace) -> int:
    """Run ``dryfriction orbit``: every periodic orbit of K periods with its multipliers, printed (or
    ``--json``); returns the exit status."""
    from ..drivers.oscillator import OscillatorFMU2
    from ..analysis.orbits import find_orbits

    p = _oscillator(args)
    with OscillatorFMU2(getattr(args, "fmu", None)) as fmu:
        orbits = find_orbits(p, period=args.period, fmu=fmu, transients=args.transients)
    if args.json:
        print(json.dumps(orbit_json(orbits)))
        return 0
    print(f"{'#':>2} {'K':>2} {'stable':>7} {'|mu|max':>9} {'multipliers':>30} {'amplitude (m)':>14} "
          f"{'offset (m)':>11} {'stuck (%)':>9} {'x0 (m)':>12} {'v0 (m/s)':>12} {'residual':>8}")
    for i, o in enumerate(orbits, 1):
        mu = ", ".join(f"{m.real:.4g}" + (f"{m.imag:+.3g}j" if m.imag else "") for m in o.multipliers)
        print(f"{i:2d} {o.period:2d} {_stability(o):>7} {o.mu_max:9.4g} {mu:>30} {o.amplitude:14.6g} "
              f"{o.offset:11.3g} {_percent(o.stick_fraction):>9} {o.x0:12.6g} {o.v0:12.6g} {o.residual:8.1e}")
    print(f"{orbit_headline(orbits, args.period)}; "
          f"T = {p.period:.6g} s, static deflection P0/k = {abs(p.P0) / p.k if p.k > 0 else math.nan:.4g} m")
    for o in orbits:
        if o.rest_interval is not None:
            print(rest_line(o.rest_interval, p))
    return 0


def rest_line(rest: tuple[float, float], p: Any) -> str:
    """The sentence on the block at rest: the interval of its rest positions."""
    lo, hi = rest
    where = ("at any x (no spring)" if not math.isfinite(hi) else
             f"at any x in [{lo:.6g}, {hi:.6g}] m (|k x| <= F_b - |P0| = {p.breakaway - abs(p.P0):.4g} N)")
    return (f"the block at rest: P0 = {abs(p.P0):.4g} N within the breakaway force F_b = {p.breakaway:.4g} N, it "
            f"rests for good {where}; each rest position is a periodic orbit (multipliers 1 and 0: neutral), "
            "listed once, at the position the transient from x0, v0 reaches")


# ---- dryfriction response --method orbit: the table, the JSON object and the files ---------------

def write_orbit_csv(ds: Any, path: Any) -> Any:
    """The orbit response as CSV: one row per (frequency, orbit), a row of NaN for a frequency
    without an orbit (its reason in the last column)."""
    import csv
    import io

    import numpy as np

    from ..atomic import atomic_write_text
    from ..analysis.response import ORBIT_COLUMNS, ORBIT_FLAGS

    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["f_hz", "orbit", *ORBIT_COLUMNS, "den_hartog_m", "inman_m", "reason"])
    f = ds["f_hz"].values
    for i in range(f.size):
        n = int(ds["n_orbits"].values[i])
        for j in range(max(n, 1)):
            vals = [float(ds[c].values[i, j]) if n else math.nan for c in ORBIT_COLUMNS]
            cells = [f"{v:.10g}" for v in vals]
            if n:
                cells[0] = str(int(vals[0]))
                for c in ORBIT_FLAGS:
                    k = ORBIT_COLUMNS.index(c)
                    cells[k] = str(bool(vals[k])).lower()
            w.writerow([f"{float(f[i]):.10g}", str(j) if n else "", *cells,
                        f"{float(ds['den_hartog_m'].values[i]):.10g}", f"{float(ds['inman_m'].values[i]):.10g}",
                        str(ds["reason"].values[i])])
    return atomic_write_text(path, buf.getvalue())


def orbit_response_json(ds: Any) -> dict[str, Any]:
    """The orbits of a response Dataset per frequency (lists of objects; no NaN padding)."""
    from ..analysis.response import ORBIT_COLUMNS, ORBIT_FLAGS

    out = []
    for i in range(ds.sizes["f_hz"]):
        rows = []
        for j in range(int(ds["n_orbits"].values[i])):
            r: dict[str, Any] = {c: (bool(ds[c].values[i, j]) if c in ORBIT_FLAGS else _num(float(ds[c].values[i, j])))
                                 for c in ORBIT_COLUMNS}
            r["period"] = int(r["period"])
            rows.append(r)
        out.append(rows)
    return {"orbits": out}


def print_orbit_response(ds: Any, args: argparse.Namespace, p: Any, f: Any) -> int:
    """``dryfriction response --method orbit``: the files in ``args.out`` (if given; all or nothing,
    :func:`dryfriction.cli.console.result_set`), then the table or the JSON object."""
    import numpy as np

    from .console import result_set
    from ..analysis.response import plot_response

    files = []
    if args.out is not None:
        with result_set(args.out) as stage:
            if args.format in ("csv", "both"):
                files.append(write_orbit_csv(ds, stage / "response.csv"))
            if args.format in ("netcdf", "both"):
                from ..sweep.datasets import write_netcdf

                files.append(write_netcdf(ds, stage / "response.nc"))
            if not args.no_plot:
                files.append(plot_response(ds, stage / "response.png"))
        files = [args.out / f.relative_to(stage) for f in files]
    conv = ds["converged"].values
    reasons = ds["reason"].values
    note = ds.attrs["never_converges"]
    if args.json:
        def arr(name: str) -> list[Any]:
            return [_num(float(v)) for v in ds[name].values]

        print(json.dumps({"method": "orbit", "f_hz": arr("f_hz"), **orbit_response_json(ds),
                          "n_orbits": [int(n) for n in ds["n_orbits"].values],
                          "converged": [bool(c) for c in conv], "den_hartog_m": arr("den_hartog_m"),
                          "inman_m": arr("inman_m"), "reason": [str(r) or None for r in reasons],
                          "scheme": ds.attrs["scheme"], "period": ds.attrs["period"],
                          "units": {"f_hz": "Hz", "amplitude_m": "m", "offset_m": "m", "stick_fraction": "1",
                                    "x0_m": "m", "v0_m_per_s": "m/s", "mu_max": "1", "period": "excitation periods",
                                    "rest_from_m": "m", "rest_to_m": "m",
                                    "den_hartog_m": "m", "inman_m": "m"},
                          "natural_frequency_hz": p.f_n_hz, "note": note, "files": [str(x) for x in files]}))
        return 0
    print(f"{'f (Hz)':>10} {'#':>2} {'K':>2} {'stable':>7} {'|mu|max':>9} {'amplitude (m)':>14} {'offset (m)':>12} "
          f"{'stuck (%)':>9}")
    for i in range(f.size):
        if reasons[i]:
            print(f"{f[i]:10.4g} not computed: {reasons[i]}")
            continue
        n = int(ds["n_orbits"].values[i])
        if n == 0:
            print(f"{f[i]:10.4g} no orbit found")
        for j in range(n):
            v = {c: float(ds[c].values[i, j]) for c in ("period", "mu_max", "amplitude_m", "offset_m",
                                                        "stick_fraction")}
            st = ("True" if ds["stable"].values[i, j] else "neutral" if ds["neutral"].values[i, j] else "False")
            lead = f"{f[i]:10.4g}" if j == 0 else " " * 10
            print(f"{lead} {j:2d} {int(v['period']):2d} {st:>7} {v['mu_max']:9.4g} "
                  f"{v['amplitude_m']:14.6g} {v['offset_m']:12.3g} {_percent(v['stick_fraction']):>9}")
    failed = int(sum(bool(r) for r in reasons))
    total = int(ds["n_orbits"].values.sum())
    stable = int(ds["stable"].values.sum())
    neutral = int(ds["neutral"].values.sum())
    print(f"natural frequency {p.f_n_hz:.6g} Hz; {total} orbits at {f.size} frequencies ({stable} stable"
          + (f", {neutral} neutral" if neutral else "") + f"); {int(conv.sum())} of {conv.size} with a stable orbit"
          + (" or at rest" if neutral else "") + (f"; {failed} not computed" if failed else "")
          + f"; method orbit, scheme {ds.attrs['scheme']}")
    if note:
        print(note)
    rest = np.isfinite(ds["rest_to_m"].values)
    if rest.any():
        i, j = np.argwhere(rest)[0]
        print(rest_line((float(ds["rest_from_m"].values[i, j]), float(ds["rest_to_m"].values[i, j])), p))
    for x in files:
        print(f"wrote {x}")
    return 0
