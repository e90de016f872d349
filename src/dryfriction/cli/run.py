"""``dryfriction run``: one scene of the oscillator FMU (``dryfriction scenes`` lists them), its
result printed as JSON (a trajectory also written as CSV with ``--out``).

    dryfriction run [--scene validation|sweep|stiction|coupled] [--lam L --mu-s-sigma S --chi C]
                    [--m M --k K --P0 P --f F --N N --mu-s MS ...] [--periods N] [--scheme NAME]
"""

from __future__ import annotations

import argparse
from typing import Any

from .options import (DEFAULT_SCHEME, SCHEMES, UsageError, count, nondim_given, nondim_options, number, one_form,
                      path_arg, physical, physical_given, physical_options)
from .output import print_json

__all__ = ["add_parser", "run", "work", "SCENES", "RUN_UNITS", "RUN_COUNTS"]

#: the scenes' names, as :data:`dryfriction.drivers.scenes.SCENES` has them (read here without
#: loading the drivers, for the help)
SCENES = ("validation", "sweep", "stiction", "coupled")

#: units of the numbers ``dryfriction run`` prints
RUN_UNITS = {"amplitude": "m", "asymmetry": "m", "x_max": "m", "x_min": "m", "stick_fraction": "1",
             "stick_percent": "%", "transitions": "1", "E_friction": "J", "x_final": "m", "samples": "1",
             "window_start_period": "excitation periods", "window_periods": "excitation periods",
             "run_periods": "excitation periods"}

#: the numbers ``dryfriction run`` prints that are counts (whole numbers in its JSON)
RUN_COUNTS = ("transitions", "samples")


def add_parser(sub: Any, parents: list[argparse.ArgumentParser]) -> None:
    """Add the ``run`` command to the main parser's subparsers ``sub``."""
    r = sub.add_parser("run", parents=parents, help="run one scene and print its result as JSON")
    r.add_argument("--scene", choices=list(SCENES), default="validation",
                   help="what to run and print (default validation; 'dryfriction scenes' describes each)")
    nd = nondim_options(r, "non-dimensional form (the paper's; the default: lam 0.5, mu_s sigma 0.4, chi 0.7)")
    nd.add_argument("--z0", type=number("--z0"), default=None, help="initial k x / P0")
    nd.add_argument("--dz0", type=number("--dz0"), default=None, help="initial dz/dtau")
    r.add_argument("--zeta", type=number("--zeta", 0.0), default=None, help="damping ratio (both forms)")
    physical_options(r.add_argument_group("physical units (SI; any of these selects them)"), required=False)
    r.add_argument("--periods", type=number("--periods", 0.0, True), default=30.0, help="excitation periods")
    r.add_argument("--steps-per-period", type=count("--steps-per-period"), default=1000,
                   help="internal steps per excitation period (default 1000)")
    r.add_argument("--h", type=number("--h", 0.0), default=None,
                   help="internal step, s (0: derived by the FMU from the dynamics; overrides --steps-per-period)")
    r.add_argument("--scheme", choices=list(SCHEMES), default=DEFAULT_SCHEME,
                   help=f"the FMU's integration scheme (default {DEFAULT_SCHEME})")
    r.add_argument("--out", type=path_arg("--out", "file"), default=None, help="CSV file for the trajectory scenes")


def work(args: argparse.Namespace) -> tuple[float, str]:
    """The run's steps: its periods (one more for the observed window) times the steps per period."""
    from ..budget import EXACT_PERIOD_STEPS, fmt

    spp = EXACT_PERIOD_STEPS if args.scheme == "exact" else float(args.steps_per_period)
    periods = float(args.periods) + 1.0
    return periods * spp, f"{fmt(periods)} periods x {fmt(spp)} steps"


def _oscillator(args: argparse.Namespace) -> Any:
    from ..params import Oscillator

    nondim = nondim_given(args, ("lam", "mu_s_sigma", "chi", "z0", "dz0"))
    if physical_given(args):
        one_form(nondim)
        p = physical(args)
        if not p.omega > 0:
            raise UsageError("dryfriction run needs an excitation frequency > 0 (its length is in excitation periods)")
        return p
    return Oscillator.from_nondimensional(lam=nondim.get("lam", 0.5), mu_s_sigma=nondim.get("mu_s_sigma", 0.4),
                                          chi=nondim.get("chi", 0.7), zeta=args.zeta or 0.0,
                                          z0=nondim.get("z0", 0.0), dz0=nondim.get("dz0", 0.0))


def run(args: argparse.Namespace) -> int:
    """Run ``dryfriction run``; the exit status."""
    from ..drivers import scenes
    from ..drivers.oscillator import OscillatorFMU2, Settings

    p = _oscillator(args)
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
        print_json({**head, **{k: int(v) if k in RUN_COUNTS else float(v) for k, v in res.items()},
                    "units": {k: RUN_UNITS.get(k, "") for k in res}}, indent=2)
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
    print_json({**head, "samples": int(len(res["t"])), "x_final": float(res["x"][-1]),
                "out": str(args.out) if args.out else None,
                "units": {"x_final": "m", "csv columns": "t s, x m, v m/s, a m/s2, F_friction N, mode 1"}},
               indent=2)
    return 0
