"""``dryfriction system``: a structure with friction contacts (docs/system.md).

    dryfriction system fmu SPEC -o NAME.fmu [--fmi 2|3]   # the structure's own FMU, no compiler
    dryfriction system run SPEC --t-end 10 [--dt 0.01] [--json]
    dryfriction system orbits SPEC [--period K] [--accuracy A] [--json]
    dryfriction system response SPEC --f-start F0 --f-stop F1 [--num N] [--dof D] [--out DIR] [--json]
    dryfriction system continuation SPEC --param omega --start A --stop B [--out DIR] [--json]

``SPEC`` is the TOML structure file (:mod:`dryfriction.system.spec`: the matrices inline or in
``.npy``, ``.csv`` or MatrixMarket ``.mtx`` files beside it). ``fmu`` writes the package's prebuilt
``DryFrictionSystem`` FMU with the structure's values as its start values and in
``resources/structure.bin`` (:func:`dryfriction.system.fmu.write_fmu`; ``--fmi 2``: FMI 2.0, only at
the sizes its prebuilt binary was built for); ``--fmu`` names another prebuilt system FMU to start
from. ``run`` runs the structure through the FMI 3.0 FMU and
prints the last output time's values (``--json``: one object with every output time and the
observables over the run, x_max, x_min, stick_fraction and transitions). ``orbits`` prints the structure's periodic
orbits at its omega (Newton shooting on the located map with the FMU's Jacobian:
:func:`dryfriction.analysis.system_orbits.find_system_orbits`), ``response`` its steady response by
orbits over a frequency range (:func:`dryfriction.analysis.system_response.system_frequency_response`)
into ``--out`` (default results/system_response): response.csv, response.nc (NetCDF) and response.png,
all or nothing; ``--json`` prints the table instead (files only with ``--out``). ``continuation``
follows the orbits in a parameter with the continuation engine
(:func:`dryfriction.analysis.system_continuation.continue_system_orbits`) and writes
continuation.nc, continuation.csv and continuation.png (or prints the branches and bifurcations).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from .options import count, number, path_arg
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
                        "stick_fraction, transitions over the run")
    o = ss.add_parser("orbits", help="the structure's periodic orbits at its omega (located map, Newton shooting)",
                      description="Periodic orbits of the structure at its excitation frequency, by Newton "
                                  "shooting on the located scheme's map with the FMU's Jacobian: state at t = 0, "
                                  "amplitude per DOF, stuck share per contact, multipliers, the estimated error.")
    o.add_argument("spec", type=path_arg("SPEC", "file"), metavar="SPEC", help="the TOML structure file")
    o.add_argument("--period", type=count("--period"), default=1, help="excitation periods K of the orbits (default 1)")
    o.add_argument("--accuracy", type=number("--accuracy", 0.0, True), default=None,
                   help="halve h until the amplitude's estimated error is within this, m (default: one halving, "
                        "the error estimated)")
    o.add_argument("--json", action="store_true", help="print the orbits as one JSON object")
    q = ss.add_parser("response", help="the structure's steady response by periodic orbits over a frequency range",
                      description="Steady response of the structure by its periodic orbits (located map, the "
                                  "FMU's Jacobian) at --num frequencies from --f-start to --f-stop: amplitude per "
                                  "DOF, stuck share per contact, stability, the estimated error; CSV, NetCDF, PNG.")
    q.add_argument("spec", type=path_arg("SPEC", "file"), metavar="SPEC", help="the TOML structure file")
    q.add_argument("--f-start", dest="f_start", type=number("--f-start", 0.0, True), required=True,
                   help="first frequency, Hz")
    q.add_argument("--f-stop", dest="f_stop", type=number("--f-stop", 0.0, True), required=True,
                   help="last frequency, Hz")
    q.add_argument("--num", type=count("--num"), default=41, help="number of frequencies (default 41)")
    q.add_argument("--dof", type=count("--dof", 0), default=None,
                   help="the DOF whose amplitude is amplitude_dof_m (0-based; default the largest)")
    q.add_argument("--period", type=count("--period"), default=1, help="excitation periods K of the orbits (default 1)")
    q.add_argument("--accuracy", type=number("--accuracy", 0.0, True), default=None,
                   help="halve h until each amplitude's estimated error is within this, m")
    q.add_argument("--out", type=path_arg("--out"), default=None,
                   help="output folder (default results/system_response; with --json: no files unless --out is given)")
    q.add_argument("--format", choices=("csv", "netcdf", "both"), default="both", help="table format (default both)")
    q.add_argument("--no-plot", action="store_true", help="no PNG")
    q.add_argument("--json", action="store_true", help="print the table as one JSON object on stdout")
    q.add_argument("--no-progress", action="store_true", help="no progress bar")
    c = ss.add_parser("continuation", help="follow the structure's orbits in a parameter, with their bifurcations",
                      description="Continue the structure's periodic orbits in omega, N, mu_s, mu_k or force (the "
                                  "excitation's scale) from --start to --stop: folds, period doublings and grazings "
                                  "located; continuation.nc, .csv and .png.")
    c.add_argument("spec", type=path_arg("SPEC", "file"), metavar="SPEC", help="the TOML structure file")
    c.add_argument("--param", choices=("omega", "N", "mu_s", "mu_k", "force"), required=True,
                   help="the parameter (N, mu_s, mu_k: every contact's; force: F_c and F_s scaled)")
    c.add_argument("--start", type=number("--start"), required=True, help="the parameter's first value")
    c.add_argument("--stop", type=number("--stop"), required=True, help="the parameter's last value")
    c.add_argument("--period", type=count("--period"), default=1, help="excitation periods K of the orbits (default 1)")
    c.add_argument("--max-points", dest="max_points", type=count("--max-points", 2), default=400,
                   help="points per branch at most (default 400)")
    c.add_argument("--out", type=path_arg("--out"), default=None,
                   help="output folder (default results/system_continuation; with --json: no files unless --out)")
    c.add_argument("--json", action="store_true", help="print the branches, bifurcations and points as JSON")


def _steps_per_period(system: Any) -> float:
    """Internal steps per excitation period of the structure: T / h, h the system's or the FMU's derived
    one (1/1000 of 2 pi over sqrt(lambda_max(M^-1 (K + sum k_t w w'))) + lambda_max(M^-1 C) + omega)."""
    import math

    import numpy as np

    if system.h > 0:
        h = float(system.h)
    else:
        Minv = np.linalg.inv(system.M)
        K = system.K + sum(k * np.outer(w, w) for k, w in zip(system.k_t, system.W) if k > 0)
        lam = float(np.max(np.abs(np.linalg.eigvals(Minv @ K)))) if system.n else 0.0
        lc = float(np.max(np.abs(np.linalg.eigvals(Minv @ system.C)))) if system.n else 0.0
        rate = math.sqrt(lam) + lc + float(system.omega)
        h = 2.0 * math.pi / (1000.0 * rate) if rate > 0 else 1e-3
    return (2.0 * math.pi / system.omega) / h if system.omega > 0 else 1.0 / h


def work(args: argparse.Namespace) -> tuple[float, str] | None:
    """The estimated work (internal steps) of ``system run | orbits | response | continuation``, refused
    above ``--max-work`` before it starts (:mod:`dryfriction.budget`); ``system fmu`` does none."""
    from ..budget import fmt
    from ..system.spec import load

    if args.system_command == "fmu":
        return None
    system = load(args.spec)
    steps = _steps_per_period(system)
    if args.system_command == "run":
        n = float(args.t_end) * system.omega / (2.0 * 3.141592653589793) * steps if system.omega > 0 else \
            float(args.t_end) / (1.0 / steps)
        return n, f"{fmt(n)} steps to t = {args.t_end:g}"
    K = int(getattr(args, "period", 1))
    runs = {"orbits": 60, "response": 40 + 12 * int(getattr(args, "num", 1)),
            "continuation": 40 + 30 * int(getattr(args, "max_points", 1))}[args.system_command]
    return runs * K * steps, f"about {fmt(runs)} runs of the map x {K} periods x {fmt(steps)} steps"


def run(args: argparse.Namespace) -> int:
    """Run ``dryfriction system SUBCOMMAND``."""
    from ..system.spec import load

    system = load(args.spec)
    if args.system_command == "fmu":
        from ..system.fmu import write_fmu

        out = write_fmu(system, Path(args.output), fmi=args.fmi, base=args.fmu)
        print(f"wrote {out}: n = {system.n}, nc = {system.nc} (FMI {args.fmi}.0)")
        return 0
    if args.system_command == "orbits":
        return _orbits(system, args)
    if args.system_command == "response":
        return _response(system, args)
    if args.system_command == "continuation":
        return _continuation(system, args)
    from ..drivers.system import run as run_system

    res = run_system(system, args.t_end, args.dt, fmu_path=args.fmu)
    if args.json:
        print_json({"t": res.t.tolist(), "x": res.x.tolist(), "v": res.v.tolist(), "f": res.f.tolist(),
                    "mode": res.mode.tolist(), "E_friction": res.E_friction.tolist(), "x_max": res.x_max.tolist(),
                    "x_min": res.x_min.tolist(), "stick_fraction": res.stick_fraction.tolist(),
                    "transitions": res.transitions.tolist()})
    else:
        print(f"t = {res.t[-1]:.6g}: x = {res.x[-1].tolist()}, mode = {res.mode[-1].tolist()}, "
              f"E_friction = {res.E_friction[-1]:.6g}")
    return 0


def _orbit_dict(o: Any) -> dict[str, Any]:
    """One orbit as JSON-ready values."""
    return {"period": o.period, "converged": o.converged, "reason": o.reason, "stable": o.stable,
            "neutral": o.neutral, "x0": o.x0.tolist(), "v0": o.v0.tolist(), "s0": o.s0.tolist(),
            "amplitude": o.amplitude.tolist(), "offset": o.offset.tolist(),
            "stick_fraction": o.stick_fraction.tolist(), "mu_max": o.mu_max, "residual": o.residual,
            "error": o.error, "h": o.h, "multipliers_abs": [abs(m) for m in o.multipliers]}


def _orbits(system: Any, args: argparse.Namespace) -> int:
    """``dryfriction system orbits``: the orbits printed (or as JSON); exit status 1 when none converged."""
    from ..analysis.system_orbits import find_system_orbits

    orbits = find_system_orbits(system, args.period, accuracy=args.accuracy, keep_failed=True)
    if args.json:
        print_json({"orbits": [_orbit_dict(o) for o in orbits]})
    else:
        for o in orbits:
            state = "stable" if o.stable else "unstable"
            if o.neutral:
                state += ", neutral"
            if not o.converged:
                print(f"not converged: {o.reason}")
                continue
            print(f"period {o.period} ({state}): amplitude {', '.join(f'{a:.6g}' for a in o.amplitude)} m "
                  f"(estimated error {o.error:.2g} m, h = {o.h:.4g} s), stuck share "
                  f"{', '.join(f'{s:.3f}' for s in o.stick_fraction)}, |mu| max {o.mu_max:.4g}")
    return 0 if any(o.converged for o in orbits) else 1


def _response(system: Any, args: argparse.Namespace) -> int:
    """``dryfriction system response``: the table (and its PNG) written all or nothing, or printed as
    JSON; exit status 1 when some frequency did not converge."""
    import sys

    import numpy as np

    from ..analysis.system_response import plot_system_response, system_frequency_response
    from ..errors import UsageError
    from .output import json_safe

    if args.f_stop < args.f_start:
        raise UsageError(f"--f-stop {args.f_stop:g} must be >= --f-start {args.f_start:g}")
    if args.dof is not None and args.dof >= system.n:
        raise UsageError(f"--dof {args.dof} is not a degree of freedom of the structure (0 .. {system.n - 1})")
    f = np.linspace(args.f_start, args.f_stop, args.num) if args.num > 1 else np.array([args.f_start])
    out = None
    if args.out is not None or not args.json:
        from ..budget import check_writable

        out = check_writable(args.out or Path("results/system_response"), 2000.0 * f.size, "the response's files")
    ds = system_frequency_response(system, f, dof=args.dof, period=args.period, accuracy=args.accuracy,
                                   progress=not args.no_progress and sys.stderr.isatty(), fmu_path=args.fmu)
    files: list[Path] = []
    if out is not None:
        from .console import result_set

        with result_set(out) as stage:
            if args.format in ("csv", "both"):
                files.append(_csv(ds, stage / "response.csv"))
            if args.format in ("netcdf", "both"):
                from ..sweep.datasets import write_netcdf

                files.append(write_netcdf(ds, stage / "response.nc"))
            if not args.no_plot:
                files.append(plot_system_response(ds, stage / "response.png", args.dof))
        files = [out / p.relative_to(stage) for p in files]
    conv = ds["converged"].values
    if args.json:
        print_json({name: json_safe(ds[name].values.tolist()) for name in
                    ("f_hz", "amplitude_m", "amplitude_dof_m", "offset_m", "stick_fraction", "stable", "neutral",
                     "mu_max", "residual", "error_m", "h_s", "converged", "reason")})
    else:
        k = int(np.nanargmax(ds["amplitude_dof_m"].values)) if np.any(np.isfinite(ds["amplitude_dof_m"].values)) else 0
        print(f"{int(conv.sum())} of {conv.size} frequencies converged; DOF {ds.attrs['dof']}'s largest amplitude "
              f"{ds['amplitude_dof_m'].values[k]:.6g} m at {f[k]:.6g} Hz; largest estimated error "
              f"{np.nanmax(ds['error_m'].values):.2g} m")
        for p in files:
            print(f"wrote {p}")
    return 0 if bool(conv.all()) else 1


def _csv(ds: Any, path: Path) -> Path:
    """The response as CSV: one row per frequency, one column per DOF and contact."""
    import csv

    n, nc = ds.sizes["dof"], ds.sizes["contact"]
    head = (["f_hz"] + [f"amplitude_m[{i}]" for i in range(n)] + [f"offset_m[{i}]" for i in range(n)]
            + [f"stick_fraction[{j}]" for j in range(nc)]
            + ["stable", "neutral", "mu_max", "residual", "error_m", "h_s", "converged", "reason"])
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(head)
        for i in range(ds.sizes["f_hz"]):
            w.writerow([repr(float(ds["f_hz"].values[i]))] + [repr(float(v)) for v in ds["amplitude_m"].values[i]]
                       + [repr(float(v)) for v in ds["offset_m"].values[i]]
                       + [repr(float(v)) for v in ds["stick_fraction"].values[i]]
                       + [int(ds["stable"].values[i]), int(ds["neutral"].values[i])]
                       + [repr(float(ds[k].values[i])) for k in ("mu_max", "residual", "error_m", "h_s")]
                       + [int(ds["converged"].values[i]), str(ds["reason"].values[i])])
    return path


def _continuation(system: Any, args: argparse.Namespace) -> int:
    """``dryfriction system continuation``: the branches written (NetCDF, CSV, PNG; all or nothing) or
    printed as JSON; exit status 1 when a branch stopped before the end of the range."""
    import numpy as np

    from ..analysis.system_continuation import continue_system_orbits
    from .output import json_safe

    out = None
    if args.out is not None or not args.json:
        from ..budget import check_writable

        out = check_writable(args.out or Path("results/system_continuation"), 1000.0 * args.max_points,
                             "the continuation's files")
    c = continue_system_orbits(system, args.param, args.start, args.stop, period=args.period,
                               max_points=args.max_points)
    ds = c.dataset
    files: list[Path] = []
    if out is not None:
        from .console import result_set

        with result_set(out) as stage:
            from ..sweep.datasets import write_netcdf

            files.append(write_netcdf(ds, stage / "continuation.nc"))
            files.append(_continuation_csv(ds, stage / "continuation.csv"))
            files.append(_continuation_png(ds, c, stage / "continuation.png"))
        files = [out / p.relative_to(stage) for p in files]
    ended = all(b.stopped.startswith("reached the end") for b in c.branches)
    if args.json:
        print_json({**c.as_dict(), "points": {k: json_safe(ds[k].values.tolist()) for k in
                                              ("param", "amplitude_m", "stick_fraction", "mu_max", "stable",
                                               "branch", "bifurcation")}})
    else:
        for b in c.branches:
            print(f"branch {b.id} (period {b.period}): {b.points} points; {b.stopped}")
        for f in c.bifurcations:
            print(f"{f.type} at {args.param} = {f.param:.8g} (branch {f.branch}){': ' + f.note if f.note else ''}")
        k = int(np.nanargmax(ds["amplitude_m"].values.max(axis=1))) if ds.sizes["point"] else 0
        if ds.sizes["point"]:
            print(f"largest amplitude {np.nanmax(ds['amplitude_m'].values[k]):.6g} m at {args.param} = "
                  f"{float(ds['param'].values[k]):.6g}")
        for p in files:
            print(f"wrote {p}")
    return 0 if ended else 1


def _continuation_csv(ds: Any, path: Path) -> Path:
    """The branch points as CSV: parameter, branch, amplitude per DOF, stuck share per contact, stability."""
    import csv

    n, nc = ds.sizes["dof"], ds.sizes["contact"]
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["param", "branch", *[f"amplitude_m[{i}]" for i in range(n)],
                    *[f"stick_fraction[{j}]" for j in range(nc)], "mu_max", "stable", "bifurcation"])
        for i in range(ds.sizes["point"]):
            w.writerow([repr(float(ds["param"].values[i])), int(ds["branch"].values[i]),
                        *[repr(float(v)) for v in ds["amplitude_m"].values[i]],
                        *[repr(float(v)) for v in ds["stick_fraction"].values[i]],
                        repr(float(ds["mu_max"].values[i])), int(ds["stable"].values[i]),
                        str(ds["bifurcation"].values[i])])
    return path


def _continuation_png(ds: Any, c: Any, path: Path) -> Path:
    """Each DOF's amplitude along the branches (stable solid, unstable dashed), the bifurcations marked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    fig, ax = plt.subplots(figsize=(7, 4.5))
    p, A, st, br = ds["param"].values, ds["amplitude_m"].values, ds["stable"].values, ds["branch"].values
    for b in np.unique(br):
        sel = br == b
        for d in range(A.shape[1]):
            line, = ax.plot(p[sel], np.where(st[sel], A[sel, d], np.nan), "-", label=f"DOF {d}" if b == br[0] else None)
            ax.plot(p[sel], np.where(~st[sel], A[sel, d], np.nan), "--", color=line.get_color())
    for f in c.bifurcations:
        ax.plot([f.param] * np.size(f.amplitude_m), np.atleast_1d(f.amplitude_m), "kx")
    ax.set_xlabel(c.param)
    ax.set_ylabel("amplitude, m")
    ax.set_title("orbits of the structure along the parameter (x: bifurcations)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
