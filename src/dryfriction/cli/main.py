"""Command line: ``dryfriction validate | run | response | scenes | study | lyapunov | chain | orbit | belt``.

Invalid arguments, an unusable FMU and an error the FMU reports end with one readable line on
stderr (``dryfriction: error: ...``) and exit status 2, before any work where they can be found
before it. Every warning an FMU logs is one line on stderr (``dryfriction: warning: ...``);
``--strict`` makes it an error. A command's files are written all or nothing, an unusable ``--out``
is refused before the work, and Ctrl-C prints one line and exits 130 (:mod:`dryfriction.cli.console`).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import warnings
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from .. import __version__, model
from ..drivers import scenes
from .options import PHYSICAL, Parser, _physical, _physical_options, count, make_parser, number, path_arg
from ..errors import UsageError
from ..diagnostics import DryFrictionWarning
from ..drivers.oscillator import Settings
from ..params import Oscillator


def _global_options(suppress: bool) -> argparse.ArgumentParser:
    """The options every subcommand accepts, before or after its name. On the subcommands the
    default is SUPPRESS, so that a value given before the subcommand is kept."""
    g = argparse.ArgumentParser(add_help=False)
    default = argparse.SUPPRESS if suppress else None
    g.add_argument("--fmu", type=Path, default=default,
                   help="path of the FMU (default: $DFO_FMU, else the installed package's, else build/)")
    g.add_argument("--strict", action="store_true", default=default,
                   help="a warning of the FMU (e.g. a step too coarse for the dynamics) is an error: exit 2")
    from .options import add_max_work_argument

    add_max_work_argument(g, default)
    return g


def build_parser() -> Parser:
    """The command line's parser: the global options and every subcommand."""
    p = make_parser("dryfriction", "Dry-friction oscillator FMU: validation, scenes and studies.",
                    parents=[_global_options(False)])
    p.add_argument("--version", action="version", version=f"dryfriction {__version__}")
    sub = p.add_subparsers(dest="command", required=True, parser_class=Parser, metavar="COMMAND",
                           help="the command ('dryfriction COMMAND --help' for its options)")
    common = [_global_options(True)]

    v = sub.add_parser("validate", parents=common,
                       help="FMU against the exact solution: errors, orders, results/validation.png")
    v.add_argument("--out", type=path_arg("--out"), default=Path("results"), help="output folder (default: results)")
    v.add_argument("--quick", action="store_true", help="two cases, three step sizes")

    schemes = list(model.default().schemes)
    r = sub.add_parser("run", parents=common, help="run one scene and print its result as JSON")
    r.add_argument("--scene", choices=list(scenes.SCENES), default="validation",
                   help="what to run and print (default validation; 'dryfriction scenes' describes each)")
    nd = r.add_argument_group("non-dimensional form (the paper's; the default: lam 0.5, mu_s sigma 0.4, chi 0.7)")
    nd.add_argument("--lam", type=number("--lam", 0.0, True), default=None, help="frequency ratio omega/w0")
    nd.add_argument("--mu-s-sigma", type=number("--mu-s-sigma", 0.0), default=None, help="mu_s N / P0")
    nd.add_argument("--chi", type=number("--chi", 0.0), default=None, help="mu_k / mu_s")
    nd.add_argument("--z0", type=number("--z0"), default=None, help="initial k x / P0")
    nd.add_argument("--dz0", type=number("--dz0"), default=None, help="initial dz/dtau")
    r.add_argument("--zeta", type=number("--zeta", 0.0), default=None, help="damping ratio (both forms)")
    _physical_options(r.add_argument_group("physical units (SI; any of these selects them)"), required=False)
    r.add_argument("--periods", type=number("--periods", 0.0, True), default=30.0, help="excitation periods")
    r.add_argument("--steps-per-period", type=count("--steps-per-period"), default=1000,
                   help="internal steps per excitation period (default 1000)")
    r.add_argument("--h", type=number("--h", 0.0), default=None,
                   help="internal step, s (0: derived by the FMU from the dynamics; overrides --steps-per-period)")
    r.add_argument("--scheme", choices=schemes, default=Settings().scheme,
                   help=f"the FMU's integration scheme (default {Settings().scheme})")
    r.add_argument("--out", type=path_arg("--out", "file"), default=None, help="CSV file for the trajectory scenes")

    from ..analysis.response import MAX_PERIODS, MIN_PERIODS, TOL

    q = sub.add_parser("response", parents=common,
                       help="steady-state frequency response of an oscillator in physical units (m, Hz)",
                       description="Steady-state amplitude (half peak-to-peak of x, m), offset, stick share and "
                                   "convergence at each frequency; CSV/NetCDF and a PNG with Den Hartog's and Inman's "
                                   "amplitudes where they apply.")
    _physical_options(q, required=True, frequency=False)
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
    q.add_argument("--scheme", choices=schemes, default=None, help="default: exact (closed form, also for k = 0)")
    q.add_argument("--out", type=path_arg("--out"), default=None,
                   help="output folder (default results/response; with --json: no files unless --out is given)")
    q.add_argument("--format", choices=("csv", "netcdf", "both"), default="both", help="table format (default both)")
    q.add_argument("--no-plot", action="store_true", help="no PNG")
    q.add_argument("--json", action="store_true", help="print the table as one JSON object on stdout")
    q.add_argument("--workers", type=count("--workers", 0), default=None,
                   help="Dask worker processes (default: 0, or all cores above 200 frequencies)")
    q.add_argument("--no-progress", action="store_true", help="no progress bar")

    sub.add_parser("scenes", parents=common, help="list the scenes")

    from .lyapunov import add_lyapunov_parser

    add_lyapunov_parser(sub, parents=common)

    from .chain import add_chain_parser

    add_chain_parser(sub, parents=common)
    from .continuation import add_continuation_parsers

    add_continuation_parsers(sub, parents=common)
    from .orbit import add_orbit_parser

    add_orbit_parser(sub, parents=common)
    from .belt import add_belt_parser

    add_belt_parser(sub, parents=common)

    s = sub.add_parser("study", parents=common, help="the paper's studies ('dryfriction study list')",
                       description="Reproduce a study of the paper (see 'list').")
    from ..studies import add_arguments

    add_arguments(s, fmu=False)
    return p


#: units of the numbers ``dryfriction run`` prints
RUN_UNITS = {"amplitude": "m", "asymmetry": "m", "x_max": "m", "x_min": "m", "stick_fraction": "1",
             "stick_percent": "%", "transitions": "1", "E_friction": "J", "x_final": "m", "samples": "1",
             "window_start_period": "excitation periods", "window_periods": "excitation periods",
             "run_periods": "excitation periods"}


#: the numbers ``dryfriction run`` prints that are counts (whole numbers in its JSON)
RUN_COUNTS = ("transitions", "samples")


def cmd_validate(args: argparse.Namespace) -> int:
    """Run ``dryfriction validate``: the FMUs against their references, the table printed and the files
    written; returns the exit status."""
    from .console import check_output_folder
    from ..analysis.report import validate

    check_output_folder(args.out)
    print(validate(args.out, quick=args.quick, fmu_path=args.fmu, progress=sys.stderr.isatty()))
    return 0


def cmd_run(args: argparse.Namespace) -> int:
    """Run ``dryfriction run``: one run of a scene, its parameters and results printed with their units (or
    ``--json``); returns the exit status."""
    from ..drivers.oscillator import OscillatorFMU2

    physical = any(getattr(args, n) not in (None, 0.0) for n in PHYSICAL if n not in ("x0", "v0")) or \
        args.x0 != 0.0 or args.v0 != 0.0
    nondim = {n: getattr(args, n) for n in ("lam", "mu_s_sigma", "chi", "z0", "dz0") if getattr(args, n) is not None}
    if physical:
        if nondim:
            raise UsageError(f"give physical units or the non-dimensional form, not both (--{next(iter(nondim)).replace('_', '-')})")
        p = _physical(args)
        if not p.omega > 0:
            raise UsageError("dryfriction run needs an excitation frequency > 0 (its length is in excitation periods)")
    else:
        p = Oscillator.from_nondimensional(lam=nondim.get("lam", 0.5), mu_s_sigma=nondim.get("mu_s_sigma", 0.4),
                                           chi=nondim.get("chi", 0.7), zeta=args.zeta or 0.0,
                                           z0=nondim.get("z0", 0.0), dz0=nondim.get("dz0", 0.0))
    if args.out is not None and scenes.SCENES[args.scene].trajectory:
        from .console import check_output_file

        check_output_file(args.out)
    h = args.h if args.h is not None else p.period / args.steps_per_period
    st = Settings(h=h, scheme=args.scheme)
    with OscillatorFMU2(args.fmu) as fmu:
        if args.scene == "validation":
            res = scenes.run_validation(fmu, p, args.periods, settings=st)
        elif args.scene == "sweep":
            res = scenes.run_sweep_point(fmu, p, transient_periods=args.periods, settings=st)
        elif args.scene == "stiction":
            res = scenes.run_stiction(fmu, p, period_index=max(1, int(args.periods)), settings=st)
        else:  # coupled: a demonstration master pressing harder while the block moves forward
            res = scenes.run_coupled(fmu, p, args.periods * p.period, p.period / 100,
                                     lambda t, y: {"N_ext": 0.5 * p.N if y["v"] > 0 else 0.0}, settings=st)
        effects = fmu.effects()
        h_used = float(fmu.get(["h_used"])["h_used"])
    head: dict[str, Any] = {"scene": args.scene, "scheme": args.scheme, "effects": effects,
                            "parameters": p.describe(), "h_used": {"value": h_used, "unit": "s"}}
    if args.scene == "sweep":
        head["measured"] = scenes.sweep_window_text(p, args.periods)
    if "t" not in res:  # observables: a few numbers
        print(json.dumps({**head, **{k: int(v) if k in RUN_COUNTS else float(v) for k, v in res.items()},
                          "units": {k: RUN_UNITS.get(k, "") for k in res}}, indent=2))
        return 0
    if args.out:
        import numpy as np

        from .console import result_file

        keys = list(res)
        rows = np.column_stack([res[k] for k in keys])
        header = ",".join(keys)
        lines = [header] + [",".join(f"{x:.17g}" for x in row) for row in rows]
        with result_file(args.out) as tmp:
            tmp.write_text("\n".join(lines) + "\n")
    print(json.dumps({**head, "samples": int(len(res["t"])), "x_final": float(res["x"][-1]),
                      "out": str(args.out) if args.out else None,
                      "units": {"x_final": "m", "csv columns": "t s, x m, v m/s, a m/s2, F_friction N, mode 1"}},
                     indent=2))
    return 0


def cmd_response(args: argparse.Namespace) -> int:
    """Run ``dryfriction response``: the frequency response, printed (or ``--json``) and written as CSV,
    NetCDF and PNG; returns the exit status."""
    import numpy as np

    from ..analysis.response import frequency_response

    if args.f_stop < args.f_start:
        raise UsageError(f"--f-stop {args.f_stop:g} must be >= --f-start {args.f_start:g}")
    if args.min_periods > args.max_periods:
        raise UsageError(f"--min-periods {args.min_periods} must be <= --max-periods {args.max_periods}")
    p = _physical(args, omega=2.0 * math.pi * args.f_start)
    f = np.linspace(args.f_start, args.f_stop, args.num) if args.num > 1 else np.array([args.f_start])
    workers = args.workers if args.workers is not None else (0 if args.num <= 200 else (os.cpu_count() or 1))
    progress = not args.no_progress and sys.stderr.isatty()
    method = args.method or ("orbit" if args.scheme in (None, "exact") else "transient")
    if method == "orbit" and args.scheme not in (None, "exact"):
        raise UsageError(f"--method orbit needs the exact scheme, not --scheme {args.scheme} (or --method transient)")
    if args.out is not None or not args.json:  # --json alone writes only to stdout; found before the work
        from ..budget import check_writable

        args.out = check_writable(args.out or Path("results/response"), 1000.0 * f.size, "the response's files")
    ds = frequency_response(p, f, method=method, tol=args.tol, min_periods=args.min_periods,
                            max_periods=args.max_periods, scheme=args.scheme, period=args.period, workers=workers,
                            progress=progress, fmu_path=args.fmu, max_work=args.max_work)
    if method == "orbit":
        from .orbit import print_orbit_response

        return print_orbit_response(ds, args, p, f)
    files = []
    if args.out is not None:
        files = _write_response(ds, args.out, args.format, not args.no_plot)
    conv = ds["converged"].values
    note = ds.attrs["never_converges"]
    if args.json:
        def arr(name: str) -> list[Any]:
            return [None if not np.isfinite(v) else float(v) for v in ds[name].values]

        print(json.dumps({"f_hz": arr("f_hz"), "amplitude_m": arr("amplitude_m"), "offset_m": arr("offset_m"),
                          "stick_fraction": arr("stick_fraction"), "converged": [bool(c) for c in conv],
                          "periods": arr("periods"), "den_hartog_m": arr("den_hartog_m"), "inman_m": arr("inman_m"),
                          "reason": [str(r) or None for r in ds["reason"].values], "scheme": ds.attrs["scheme"],
                          "units": {"f_hz": "Hz", "amplitude_m": "m", "offset_m": "m", "stick_fraction": "1",
                                    "den_hartog_m": "m", "inman_m": "m"},
                          "tol": args.tol, "natural_frequency_hz": p.f_n_hz, "note": note,
                          "files": [str(x) for x in files]}))
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


def _write_response(ds: Any, out: Path, fmt: str, plot: bool) -> list[Path]:
    """The response table as CSV and/or NetCDF and its PNG in ``out``, all or nothing
    (:func:`dryfriction.cli.console.result_set`); the paths written."""
    from .console import result_set

    with result_set(out) as stage:
        files = _response_files(ds, stage, fmt, plot)
    return [out / f.relative_to(stage) for f in files]


def _response_files(ds: Any, out: Path, fmt: str, plot: bool) -> list[Path]:
    import csv
    import io

    import numpy as np

    from ..analysis.response import plot_response

    files = []
    if fmt in ("csv", "both"):
        from ..atomic import atomic_write_text

        cols = ["f_hz", "amplitude_m", "offset_m", "stick_fraction", "converged", "periods", "den_hartog_m", "inman_m"]
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(cols + ["reason"])
        for i in range(ds.sizes["f_hz"]):
            row = [float(ds["f_hz"].values[i])] + [ds[c].values[i] for c in cols[1:]]
            w.writerow([str(bool(v)).lower() if isinstance(v, (bool, np.bool_)) else f"{float(v):.10g}" for v in row]
                       + [str(ds["reason"].values[i])])
        files.append(atomic_write_text(out / "response.csv", buf.getvalue()))
    if fmt in ("netcdf", "both"):
        from ..sweep.datasets import write_netcdf

        files.append(write_netcdf(ds, out / "response.nc"))
    if plot:
        files.append(plot_response(ds, out / "response.png"))
    return files


def cmd_scenes(_: argparse.Namespace) -> int:
    """Run ``dryfriction scenes``: list the scenes and what each simulates; returns 0."""
    for s in scenes.SCENES.values():
        print(f"{s.name:11s} {s.description}")
    return 0


def cmd_study(args: argparse.Namespace) -> int:
    """Run ``dryfriction study``: the named study (or ``list``, ``all``); returns the exit status."""
    from ..studies import run_args

    return int(run_args(args))


#: distinct FMU warnings printed in full by one command; the rest are counted in one line at its end
MAX_WARNING_LINES = 5


@contextmanager
def fmu_warnings_on_stderr(prog: str, strict: bool) -> Iterator[None]:
    """While the block runs, an FMU warning (:class:`DryFrictionWarning`) is one line on stderr,
    ``<prog>: warning: <the FMU's sentence>`` (each sentence once; past :data:`MAX_WARNING_LINES`
    of them, one line at the end counts the others); ``strict``: raised instead."""
    more = 0
    with warnings.catch_warnings():
        shown = warnings.showwarning
        printed = 0

        def show(message: Warning | str, category: type[Warning], filename: str, lineno: int,
                 file: Any = None, line: str | None = None) -> None:
            nonlocal printed, more
            if not issubclass(category, DryFrictionWarning):
                shown(message, category, filename, lineno, file, line)
            elif printed < MAX_WARNING_LINES:
                printed += 1
                print(f"{prog}: warning: {message}", file=sys.stderr, flush=True)
            else:
                more += 1

        warnings.showwarning = show
        warnings.simplefilter("error" if strict else "default", DryFrictionWarning)
        try:
            yield
        finally:
            if more:
                print(f"{prog}: warning: {more} more FMU warning{'s' if more > 1 else ''} like these "
                      "(--strict stops at the first)", file=sys.stderr, flush=True)


def _check_fmu_option(path: Path, command: str) -> None:
    """An unusable ``--fmu`` is refused before any work (paths.FMUFileError, one line): the
    oscillator's FMI 2.0 FMU for its commands, any of the package's FMUs for a study (each study
    checks its own kind), the chain command checks its own."""
    from .. import paths

    if path.is_dir():
        raise UsageError(f"--fmu: {path} is a directory, not an FMU file")
    if not path.is_file():
        raise UsageError(f"--fmu: no such file: {path}")
    if command == "chain":
        return
    if command == "study":
        for kind in paths.KINDS:
            try:
                paths.check_fmu(path, kind)
                return
            except paths.FMUFileError:
                pass
    paths.check_fmu(path, paths.OSCILLATOR)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line ``argv`` and return its exit status: 0, 1 (the system refused, e.g. a
    full disk, or the Dask workers were lost too often), 2 (bad input, an unusable FMU, an error the
    FMU reports, work above --max-work), 130 (interrupted), 141 (output into a closed pipe); every
    error one line ``dryfriction: error: ...`` (:func:`dryfriction.cli.console.guarded`). Without
    ``argv`` this is the program itself (:func:`dryfriction.cli.console.main`, which exits; a console
    script installed before it existed calls this)."""
    from .console import guarded

    if argv is None:
        from .console import main as program

        program()
    args_list = list(argv or [])
    return guarded(lambda: _run(args_list))


def _run(argv: list[str]) -> int:
    args = build_parser().parse_args(argv)
    args.fmu = getattr(args, "fmu", None)
    args.max_work = getattr(args, "max_work", None)
    from .options import check_command

    check_command(args)  # the work estimated from the arguments, refused above --max-work
    if args.fmu is not None:
        _check_fmu_option(args.fmu, args.command)
    from .chain import chain_main
    from .lyapunov import lyapunov_main
    from .continuation import continuation_main
    from .belt import belt_main
    from .orbit import orbit_main

    handler = {"validate": cmd_validate, "run": cmd_run, "response": cmd_response, "scenes": cmd_scenes,
               "study": cmd_study, "lyapunov": lyapunov_main, "chain": chain_main, "orbit": orbit_main,
               "continuation": continuation_main, "bifurcation": continuation_main, "belt": belt_main}[args.command]
    with fmu_warnings_on_stderr("dryfriction", bool(getattr(args, "strict", False))):
        return handler(args)


if __name__ == "__main__":
    raise SystemExit(main())
