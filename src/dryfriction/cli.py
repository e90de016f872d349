"""Command line: ``dryfriction validate | run | scenes | study``.

Invalid arguments end with one readable line on stderr and exit status 2, before any work.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from collections.abc import Sequence
from pathlib import Path

from . import scenes
from .fmu import FMUError
from .params import Oscillator


class UsageError(Exception):
    pass


class Parser(argparse.ArgumentParser):
    """argparse with a one-line error instead of usage + message."""

    def error(self, message: str) -> None:  # type: ignore[override]
        raise UsageError(message)


def finite(name: str, lo: float | None = None, lo_open: bool = False):
    def conv(text: str) -> float:
        try:
            v = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} must be a number, not {text!r}") from None
        if not math.isfinite(v):
            raise argparse.ArgumentTypeError(f"{name} must be finite, not {text}")
        if lo is not None and (v <= lo if lo_open else v < lo):
            raise argparse.ArgumentTypeError(f"{name} must be {'>' if lo_open else '>='} {lo:g}, not {text}")
        return v

    return conv


def positive_int(name: str):
    def conv(text: str) -> int:
        try:
            v = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} must be a whole number, not {text!r}") from None
        if v < 1:
            raise argparse.ArgumentTypeError(f"{name} must be >= 1, not {text}")
        return v

    return conv


def build_parser() -> Parser:
    p = Parser(prog="dryfriction", description="Dry-friction oscillator FMU: validation, scenes and studies.")
    p.add_argument("--fmu", type=Path, default=None, help="path of the FMU (default: build/DryFrictionOscillator.fmu)")
    sub = p.add_subparsers(dest="command", required=True, parser_class=Parser)

    v = sub.add_parser("validate", help="FMU against the exact solution: errors, orders, results/validation.png")
    v.add_argument("--out", type=Path, default=Path("results"), help="output folder (default: results)")
    v.add_argument("--quick", action="store_true", help="two cases, three step sizes")

    r = sub.add_parser("run", help="run one scene and print its result as JSON")
    r.add_argument("--scene", choices=list(scenes.SCENES), default="validation")
    r.add_argument("--lam", type=finite("--lam", 0.0, True), default=0.5, help="frequency ratio omega/w0")
    r.add_argument("--mu-s-sigma", type=finite("--mu-s-sigma", 0.0), default=0.4, help="mu_s N / P0")
    r.add_argument("--chi", type=finite("--chi", 0.0), default=0.7, help="mu_k / mu_s")
    r.add_argument("--zeta", type=finite("--zeta", 0.0), default=0.0, help="damping ratio")
    r.add_argument("--z0", type=finite("--z0"), default=0.0, help="initial k x / P0")
    r.add_argument("--dz0", type=finite("--dz0"), default=0.0, help="initial dz/dtau")
    r.add_argument("--periods", type=finite("--periods", 0.0, True), default=30.0, help="excitation periods")
    r.add_argument("--steps-per-period", type=positive_int("--steps-per-period"), default=1000)
    r.add_argument("--scheme", choices=["paper", "consistent", "located"], default="located")
    r.add_argument("--out", type=Path, default=None, help="CSV file for the trajectory scenes")

    sub.add_parser("scenes", help="list the scenes")

    from .chaos.cli import add_lyapunov_parser
    add_lyapunov_parser(sub)

    s = sub.add_parser("study", help="the paper's studies (see 'dryfriction study --help')", add_help=False)
    s.add_argument("args", nargs=argparse.REMAINDER)
    return p


def cmd_validate(args: argparse.Namespace) -> int:
    from .report import validate

    print(validate(args.out, quick=args.quick, fmu_path=args.fmu, progress=sys.stderr.isatty()))
    return 0


def cmd_run(args: argparse.Namespace) -> int:
    from .fmu import OscillatorFMU, Settings

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

        from .report import atomic_write_bytes

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


def cmd_study(argv: Sequence[str]) -> int:
    try:
        from .studies import main as studies_main
    except ImportError:
        print("dryfriction: error: the studies are not installed in this version", file=sys.stderr)
        return 2
    return int(studies_main(list(argv)))


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser()
    try:
        if argv and argv[0] == "study":
            return cmd_study(argv[1:])
        if argv[:1] == ["--fmu"] and len(argv) > 2 and argv[2] == "study":
            os.environ["DFO_FMU"] = argv[1]  # the studies' workers find the FMU through it
            return cmd_study(argv[3:])
        args = parser.parse_args(argv)
        if args.fmu is not None and not args.fmu.is_file():
            raise UsageError(f"--fmu: no such file: {args.fmu}")
        from .chaos.cli import lyapunov_main
        handler = {"validate": cmd_validate, "run": cmd_run, "scenes": cmd_scenes, "lyapunov": lyapunov_main}[args.command]
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
