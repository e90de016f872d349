"""``dryfriction system``: a structure with friction contacts (docs/system.md).

    dryfriction system fmu SPEC -o NAME.fmu [--fmi 2|3]   # the structure's own FMU, no compiler
    dryfriction system run SPEC --t-end 10 [--dt 0.01] [--json]

``SPEC`` is the TOML structure file (:mod:`dryfriction.system.spec`: the matrices inline or in
``.npy``, ``.csv`` or MatrixMarket ``.mtx`` files beside it). ``fmu`` writes the package's prebuilt
``DryFrictionSystem`` FMU with the structure's values as its start values and in
``resources/structure.bin`` (:func:`dryfriction.system.fmu.write_fmu`; ``--fmi 2``: FMI 2.0, only at
the sizes its prebuilt binary was built for); ``--fmu`` names another prebuilt system FMU to start
from. ``run`` runs the structure through the FMI 3.0 FMU and
prints the last output time's values (``--json``: one object with every output time and the
observables over the run, x_max, x_min and stick_fraction).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from .options import number, path_arg
from .output import print_json

__all__ = ["add_parser", "run"]


def add_parser(sub: Any, parents: list[argparse.ArgumentParser]) -> None:
    """Add the ``system`` command (``system fmu``, ``system run``) to the main parser's subparsers."""
    s = sub.add_parser("system", parents=parents, help="a structure with friction contacts: its FMU, a run",
                       description="A structure M x'' + C x' + K x = ... + W' f with friction contacts, described "
                                   "by a TOML file (docs/system.md): write its own FMU without a compiler, or run it.")
    ss = s.add_subparsers(dest="system_command", required=True, metavar="SUBCOMMAND",
                          help="fmu (write the structure's FMU) or run")
    f = ss.add_parser("fmu", help="write the structure's own FMU (no compiler needed)",
                      description="Write the structure's FMU: the prebuilt DryFrictionSystem binary with the "
                                  "structure's values as start values and in resources/structure.bin.")
    f.add_argument("spec", type=path_arg("SPEC", "file"), metavar="SPEC", help="the TOML structure file")
    f.add_argument("-o", "--output", type=path_arg("-o", "file"), required=True, metavar="NAME.fmu",
                   help="the FMU to write")
    f.add_argument("--fmi", type=int, choices=(2, 3), default=3,
                   help="the FMI version (default 3; 2: the flattened names M[1,2], x[3]; any sizes either "
                        "way)")
    r = ss.add_parser("run", help="run the structure through the FMI 3.0 FMU",
                      description="Run the structure through the FMI 3.0 DryFrictionSystem FMU from t = 0.")
    r.add_argument("spec", type=path_arg("SPEC", "file"), metavar="SPEC", help="the TOML structure file")
    r.add_argument("--t-end", dest="t_end", type=number("--t-end", 0.0, True), required=True, help="end time, s")
    r.add_argument("--dt", type=number("--dt", 0.0, True), default=None,
                   help="output interval, s (default 1/100 of the excitation period)")
    r.add_argument("--json", action="store_true",
                   help="print one JSON object with every output time and the observables x_max, x_min, "
                        "stick_fraction over the run")


def run(args: argparse.Namespace) -> int:
    """Run ``dryfriction system SUBCOMMAND``."""
    from ..system.spec import load

    system = load(args.spec)
    if args.system_command == "fmu":
        from ..system.fmu import write_fmu

        out = write_fmu(system, Path(args.output), fmi=args.fmi, base=args.fmu)
        print(f"wrote {out}: n = {system.n}, nc = {system.nc} (FMI {args.fmi}.0)")
        return 0
    from ..drivers.system import run as run_system

    res = run_system(system, args.t_end, args.dt, fmu_path=args.fmu)
    if args.json:
        print_json({"t": res.t.tolist(), "x": res.x.tolist(), "v": res.v.tolist(), "f": res.f.tolist(),
                    "mode": res.mode.tolist(), "E_friction": res.E_friction.tolist(), "x_max": res.x_max.tolist(),
                    "x_min": res.x_min.tolist(), "stick_fraction": res.stick_fraction.tolist()})
    else:
        print(f"t = {res.t[-1]:.6g}: x = {res.x[-1].tolist()}, mode = {res.mode[-1].tolist()}, "
              f"E_friction = {res.E_friction[-1]:.6g}")
    return 0
