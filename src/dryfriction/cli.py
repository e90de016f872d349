"""Command line: ``dryfriction validate | run | scenes | study | lyapunov``.

Invalid arguments end with one readable line on stderr and exit status 2, before any work.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Sequence
from pathlib import Path

from . import model, scenes
from .argparsing import Parser, UsageError, count, make_parser, number
from .fmu import FMUError, Settings
from .params import Oscillator


def _global_options(suppress: bool) -> argparse.ArgumentParser:
    """The options every subcommand accepts, before or after its name. On the subcommands the
    default is SUPPRESS, so that a value given before the subcommand is kept."""
    g = argparse.ArgumentParser(add_help=False)
    default = argparse.SUPPRESS if suppress else None
    g.add_argument("--fmu", type=Path, default=default,
                   help="path of the FMU (default: $DFO_FMU or build/DryFrictionOscillator.fmu)")
    return g


def build_parser() -> Parser:
    p = make_parser("dryfriction", "Dry-friction oscillator FMU: validation, scenes and studies.",
                    parents=[_global_options(False)])
    sub = p.add_subparsers(dest="command", required=True, parser_class=Parser)
    common = [_global_options(True)]

    v = sub.add_parser("validate", parents=common,
                       help="FMU against the exact solution: errors, orders, results/validation.png")
    v.add_argument("--out", type=Path, default=Path("results"), help="output folder (default: results)")
    v.add_argument("--quick", action="store_true", help="two cases, three step sizes")

    schemes = list(model.default().schemes)
    r = sub.add_parser("run", parents=common, help="run one scene and print its result as JSON")
    r.add_argument("--scene", choices=list(scenes.SCENES), default="validation")
    r.add_argument("--lam", type=number("--lam", 0.0, True), default=0.5, help="frequency ratio omega/w0")
    r.add_argument("--mu-s-sigma", type=number("--mu-s-sigma", 0.0), default=0.4, help="mu_s N / P0")
    r.add_argument("--chi", type=number("--chi", 0.0), default=0.7, help="mu_k / mu_s")
    r.add_argument("--zeta", type=number("--zeta", 0.0), default=0.0, help="damping ratio")
    r.add_argument("--z0", type=number("--z0"), default=0.0, help="initial k x / P0")
    r.add_argument("--dz0", type=number("--dz0"), default=0.0, help="initial dz/dtau")
    r.add_argument("--periods", type=number("--periods", 0.0, True), default=30.0, help="excitation periods")
    r.add_argument("--steps-per-period", type=count("--steps-per-period"), default=1000)
    r.add_argument("--scheme", choices=schemes, default=Settings().scheme)
    r.add_argument("--out", type=Path, default=None, help="CSV file for the trajectory scenes")

    sub.add_parser("scenes", parents=common, help="list the scenes")

    from .chaos.cli import add_lyapunov_parser

    add_lyapunov_parser(sub, parents=common)

    s = sub.add_parser("study", parents=common, help="the paper's studies ('dryfriction study list')",
                       description="Reproduce a study of the paper (see 'list').")
    from .studies import add_arguments

    add_arguments(s, fmu=False)
    return p


def cmd_validate(args: argparse.Namespace) -> int:
    from .report import validate

    print(validate(args.out, quick=args.quick, fmu_path=args.fmu, progress=sys.stderr.isatty()))
    return 0


def cmd_run(args: argparse.Namespace) -> int:
    from .fmu import OscillatorFMU

    p = Oscillator.from_nondimensional(lam=args.lam, mu_s_sigma=args.mu_s_sigma, chi=args.chi, zeta=args.zeta,
                                       z0=args.z0, dz0=args.dz0)
    st = Settings(h=p.period / args.steps_per_period, scheme=args.scheme)
    with OscillatorFMU(args.fmu) as fmu:
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
    if "t" not in res:  # observables: a few numbers
        print(json.dumps({"scene": args.scene, "effects": effects, **{k: float(v) for k, v in res.items()}}, indent=2))
        return 0
    if args.out:
        import numpy as np

        from .atomic import atomic_write_bytes

        keys = list(res)
        rows = np.column_stack([res[k] for k in keys])
        header = ",".join(keys)
        lines = [header] + [",".join(f"{x:.17g}" for x in row) for row in rows]
        atomic_write_bytes(args.out, ("\n".join(lines) + "\n").encode())
    print(json.dumps({"scene": args.scene, "effects": effects, "samples": int(len(res["t"])),
                      "x_final": float(res["x"][-1]), "out": str(args.out) if args.out else None}, indent=2))
    return 0


def cmd_scenes(_: argparse.Namespace) -> int:
    for s in scenes.SCENES.values():
        print(f"{s.name:11s} {s.description}")
    return 0


def cmd_study(args: argparse.Namespace) -> int:
    from .studies import run_args

    return int(run_args(args, prog="dryfriction study"))


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        args = build_parser().parse_args(argv)
        args.fmu = getattr(args, "fmu", None)
        if args.fmu is not None and not args.fmu.is_file():
            raise UsageError(f"--fmu: no such file: {args.fmu}")
        from .chaos.cli import lyapunov_main

        handler = {"validate": cmd_validate, "run": cmd_run, "scenes": cmd_scenes, "study": cmd_study,
                   "lyapunov": lyapunov_main}[args.command]
        return handler(args)
    except UsageError as e:
        print(f"dryfriction: error: {e}", file=sys.stderr)
        return 2
    except FileNotFoundError as e:
        print(f"dryfriction: error: {e}", file=sys.stderr)
        return 2
    except FMUError as e:
        print(f"dryfriction: FMU error: {e}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("dryfriction: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    raise SystemExit(main())
