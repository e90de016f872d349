"""``dryfriction response``: the steady-state frequency response of an oscillator in physical units
(m, Hz), by the orbit method (every periodic orbit with its stability, the default with the exact
scheme) or the transient method (:func:`dryfriction.analysis.response.frequency_response`).

    dryfriction response --m M --k K --zeta Z --P0 P --N N --mu-s MS [--mu-k MK] --f-start F1 --f-stop F2
                         [--num 41] [--method orbit|transient] [--json] [--out DIR] [--format csv|netcdf|both]

A table (or ``--json``, one object) on stdout; ``response.csv``, ``response.nc`` and
``response.png`` in ``--out`` (default results/response; with ``--json`` only when ``--out`` is
given), written all or nothing.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from pathlib import Path
from typing import Any

from .options import SCHEMES, UsageError, count, number, path_arg, physical, physical_options
from .output import finite, percent, print_json, rest_line

__all__ = ["add_parser", "run", "work", "TOL", "MIN_PERIODS", "MAX_PERIODS"]

# the transient method's defaults, as :mod:`dryfriction.analysis.response` has them (read here
# without loading it, for the help)
#: the estimated relative error of the amplitude
TOL = 1e-3
#: the first run's length, excitation periods
MIN_PERIODS = 32
#: the period limit
MAX_PERIODS = 8192


def add_parser(sub: Any, parents: list[argparse.ArgumentParser]) -> None:
    """Add the ``response`` command to the main parser's subparsers ``sub``."""
    q = sub.add_parser("response", parents=parents,
                       help="steady-state frequency response of an oscillator in physical units (m, Hz)",
                       description="Steady-state amplitude (half peak-to-peak of x, m), offset, stick share and "
                                   "convergence at each frequency; CSV/NetCDF and a PNG with Den Hartog's and Inman's "
                                   "amplitudes where they apply.")
    physical_options(q, required=True, frequency=False)
    q.add_argument("--f-start", type=number("--f-start", 0.0, True), required=True, help="first frequency, Hz")
    q.add_argument("--f-stop", type=number("--f-stop", 0.0, True), required=True, help="last frequency, Hz")
    q.add_argument("--num", type=count("--num"), default=41, help="number of frequencies (default 41)")
    q.add_argument("--method", choices=("orbit", "transient"), default=None,
                   help="orbit (default with the exact scheme): every periodic orbit with its stability; transient: "
                        "run until the estimated error is within --tol (the default with a Bossak --scheme)")
    q.add_argument("--period", type=count("--period"), default=1,
                   help="orbit method: excitation periods K of the orbits (default 1)")
    q.add_argument("--tol", type=number("--tol", 0.0, True), default=TOL,
                   help=f"transient method: the estimated relative error of the amplitude (default {TOL:g})")
    q.add_argument("--min-periods", type=count("--min-periods", 2), default=MIN_PERIODS,
                   help=f"first run length in excitation periods (default {MIN_PERIODS})")
    q.add_argument("--max-periods", type=count("--max-periods", 2), default=MAX_PERIODS,
                   help=f"period limit; beyond it converged = false (default {MAX_PERIODS})")
    q.add_argument("--scheme", choices=list(SCHEMES), default=None, help="default: exact (closed form, also for k = 0)")
    q.add_argument("--out", type=path_arg("--out"), default=None,
                   help="output folder (default results/response; with --json: no files unless --out is given)")
    q.add_argument("--format", choices=("csv", "netcdf", "both"), default="both", help="table format (default both)")
    q.add_argument("--no-plot", action="store_true", help="no PNG")
    q.add_argument("--json", action="store_true", help="print the table as one JSON object on stdout")
    q.add_argument("--workers", type=count("--workers", 0), default=None,
                   help="Dask worker processes (default: 0, or all cores above 200 frequencies)")
    q.add_argument("--no-progress", action="store_true", help="no progress bar")


def _method(args: argparse.Namespace) -> str:
    return args.method or ("orbit" if args.scheme in (None, "exact") else "transient")


def work(args: argparse.Namespace) -> tuple[float, str]:
    """The response's steps (:func:`dryfriction.analysis.response.response_work`)."""
    from ..analysis.response import response_work
    from ..params import Oscillator

    return response_work(Oscillator(m=1.0, k=1.0, omega=1.0), int(args.num), _method(args), period=int(args.period),
                         max_periods=int(args.max_periods), scheme=args.scheme)


def run(args: argparse.Namespace) -> int:
    """Run ``dryfriction response``; the exit status."""
    import numpy as np

    from ..analysis.response import frequency_response

    if args.f_stop < args.f_start:
        raise UsageError(f"--f-stop {args.f_stop:g} must be >= --f-start {args.f_start:g}")
    if args.min_periods > args.max_periods:
        raise UsageError(f"--min-periods {args.min_periods} must be <= --max-periods {args.max_periods}")
    p = physical(args, omega=2.0 * math.pi * args.f_start)
    f = np.linspace(args.f_start, args.f_stop, args.num) if args.num > 1 else np.array([args.f_start])
    workers = args.workers if args.workers is not None else (0 if args.num <= 200 else (os.cpu_count() or 1))
    progress = not args.no_progress and sys.stderr.isatty()
    method = _method(args)
    if method == "orbit" and args.scheme not in (None, "exact"):
        raise UsageError(f"--method orbit needs the exact scheme, not --scheme {args.scheme} (or --method transient)")
    if args.out is not None or not args.json:  # --json alone writes only to stdout; found before the work
        from ..budget import check_writable

        args.out = check_writable(args.out or Path("results/response"), 1000.0 * f.size, "the response's files")
    ds = frequency_response(p, f, method=method, tol=args.tol, min_periods=args.min_periods,
                            max_periods=args.max_periods, scheme=args.scheme, period=args.period, workers=workers,
                            progress=progress, fmu_path=args.fmu, max_work=args.max_work)
    files = _write(ds, args, method)
    if method == "orbit":
        return _print_orbits(ds, args, p, f, files)
    return _print_transient(ds, args, p, f, files)


# ---- the files ---------------------------------------------------------------------------------

def _write(ds: Any, args: argparse.Namespace, method: str) -> list[Path]:
    """The table as CSV and/or NetCDF and its PNG in ``args.out`` (if given), all or nothing
    (:func:`.console.result_set`); the paths written."""
    if args.out is None:
        return []
    from ..analysis.response import plot_response
    from .console import result_set

    files = []
    with result_set(args.out) as stage:
        if args.format in ("csv", "both"):
            files.append((_orbit_csv if method == "orbit" else _transient_csv)(ds, stage / "response.csv"))
        if args.format in ("netcdf", "both"):
            from ..sweep.datasets import write_netcdf

            files.append(write_netcdf(ds, stage / "response.nc"))
        if not args.no_plot:
            files.append(plot_response(ds, stage / "response.png"))
    return [args.out / f.relative_to(stage) for f in files]


def _transient_csv(ds: Any, path: Path) -> Path:
    """The transient method's table as CSV: one row per frequency."""
    import csv
    import io

    import numpy as np

    from ..atomic import atomic_write_text

    cols = ["f_hz", "amplitude_m", "offset_m", "stick_fraction", "converged", "periods", "den_hartog_m", "inman_m"]
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(cols + ["reason"])
    for i in range(ds.sizes["f_hz"]):
        row = [float(ds["f_hz"].values[i])] + [ds[c].values[i] for c in cols[1:]]
        w.writerow([str(bool(v)).lower() if isinstance(v, (bool, np.bool_)) else f"{float(v):.10g}" for v in row]
                   + [str(ds["reason"].values[i])])
    return atomic_write_text(path, buf.getvalue())


def _orbit_csv(ds: Any, path: Path) -> Path:
    """The orbit method's table as CSV: one row per (frequency, orbit), a row of NaN for a
    frequency without an orbit (its reason in the last column)."""
    import csv
    import io

    from ..analysis.response import ORBIT_COLUMNS, ORBIT_FLAGS
    from ..atomic import atomic_write_text

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


# ---- what it prints ----------------------------------------------------------------------------

def _column(ds: Any, name: str) -> list[float | None]:
    """A variable of the Dataset as a JSON list (NaN and infinities as null)."""
    return [finite(float(v)) for v in ds[name].values]


def _print_transient(ds: Any, args: argparse.Namespace, p: Any, f: Any, files: list[Path]) -> int:
    conv = ds["converged"].values
    note = ds.attrs["never_converges"]
    if args.json:
        print_json({"f_hz": _column(ds, "f_hz"), "amplitude_m": _column(ds, "amplitude_m"),
                    "offset_m": _column(ds, "offset_m"), "stick_fraction": _column(ds, "stick_fraction"),
                    "converged": [bool(c) for c in conv], "periods": _column(ds, "periods"),
                    "den_hartog_m": _column(ds, "den_hartog_m"), "inman_m": _column(ds, "inman_m"),
                    "reason": [str(r) or None for r in ds["reason"].values], "scheme": ds.attrs["scheme"],
                    "units": {"f_hz": "Hz", "amplitude_m": "m", "offset_m": "m", "stick_fraction": "1",
                              "den_hartog_m": "m", "inman_m": "m"},
                    "tol": args.tol, "natural_frequency_hz": p.f_n_hz, "note": note,
                    "files": [str(x) for x in files]})
        return 0
    print(f"{'f (Hz)':>10} {'amplitude (m)':>14} {'offset (m)':>12} {'stuck (%)':>9} {'converged':>9} {'periods':>7}")
    reasons = ds["reason"].values
    for i in range(f.size):
        if reasons[i]:
            print(f"{f[i]:10.4g} not computed: {reasons[i]}")
            continue
        print(f"{f[i]:10.4g} {ds['amplitude_m'].values[i]:14.6g} {ds['offset_m'].values[i]:12.3g} "
              f"{100 * ds['stick_fraction'].values[i]:9.1f} {str(bool(conv[i])):>9} {int(ds['periods'].values[i]):7d}")
    failed = int(sum(bool(r) for r in reasons))
    print(f"natural frequency {p.f_n_hz:.6g} Hz; {int(conv.sum())} of {conv.size} converged (tol {args.tol:g})"
          + (f"; {failed} not computed" if failed else "") + f"; scheme {ds.attrs['scheme']}")
    if note:
        print(note)
    for x in files:
        print(f"wrote {x}")
    return 0


def _orbits_json(ds: Any) -> list[list[dict[str, Any]]]:
    """The orbits of a response Dataset per frequency (lists of objects; no NaN padding)."""
    from ..analysis.response import ORBIT_COLUMNS, ORBIT_FLAGS

    out = []
    for i in range(ds.sizes["f_hz"]):
        rows = []
        for j in range(int(ds["n_orbits"].values[i])):
            r: dict[str, Any] = {c: (bool(ds[c].values[i, j]) if c in ORBIT_FLAGS
                                     else finite(float(ds[c].values[i, j]))) for c in ORBIT_COLUMNS}
            r["period"] = int(r["period"])
            rows.append(r)
        out.append(rows)
    return out


def _print_orbits(ds: Any, args: argparse.Namespace, p: Any, f: Any, files: list[Path]) -> int:
    import numpy as np

    conv = ds["converged"].values
    reasons = ds["reason"].values
    note = ds.attrs["never_converges"]
    if args.json:
        print_json({"method": "orbit", "f_hz": _column(ds, "f_hz"), "orbits": _orbits_json(ds),
                    "n_orbits": [int(n) for n in ds["n_orbits"].values],
                    "converged": [bool(c) for c in conv], "den_hartog_m": _column(ds, "den_hartog_m"),
                    "inman_m": _column(ds, "inman_m"), "reason": [str(r) or None for r in reasons],
                    "scheme": ds.attrs["scheme"], "period": ds.attrs["period"],
                    "units": {"f_hz": "Hz", "amplitude_m": "m", "offset_m": "m", "stick_fraction": "1",
                              "x0_m": "m", "v0_m_per_s": "m/s", "mu_max": "1", "period": "excitation periods",
                              "rest_from_m": "m", "rest_to_m": "m",
                              "den_hartog_m": "m", "inman_m": "m"},
                    "natural_frequency_hz": p.f_n_hz, "note": note, "files": [str(x) for x in files]})
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
                  f"{v['amplitude_m']:14.6g} {v['offset_m']:12.3g} {percent(v['stick_fraction']):>9}")
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
