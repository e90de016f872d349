"""``dryfriction continuation`` and ``dryfriction bifurcation``: branches of periodic orbits with
their stability and bifurcations (dryfriction.analysis.continuation; docs/orbits.md).

    dryfriction continuation --param NAME --from A --to B [oscillator] [--period K] [--out DIR] [--json]
    dryfriction bifurcation [--param chi] [--from 1.0 --to 0.2] [--lam 0.5 --mu-s-sigma 0.6] [--quick]

The oscillator is given as ``dryfriction run`` takes it: physical units (``--m --k --c|--zeta --P0
--f|--omega --N --mu-s --mu-k``) or the paper's non-dimensional form (``--lam --mu-s-sigma --chi
--zeta``, default lam 0.5, mu_s sigma 0.6, chi 0.7). ``continuation`` writes continuation.nc,
continuation.csv and continuation.png (stable solid, unstable dashed, bifurcations marked and
labelled); ``--json`` prints one object ``{"param": NAME, "branches": [...], "bifurcations": [...]}``
(files too only with ``--out``). ``bifurcation`` draws the branches over the brute-force attractor
scatter of Fig. 8/9 (the study's sampling at a modest resolution) in one PNG. Bad values: one line,
exit status 2.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from .options import (UsageError, count, nondim_given, nondim_options, number, one_form, path_arg, physical,
                      physical_given, physical_options)
from .output import json_safe, print_json

__all__ = ["add_parser", "run", "work", "PARAMETERS"]

#: the parameters a branch is continued in, as :data:`dryfriction.analysis.continuation.PARAMETERS`
#: has them (read here without loading it, for the help)
PARAMETERS = ("m", "k", "c", "P0", "omega", "phi", "N", "mu_s", "chi", "f", "lam", "zeta", "mu_k", "mu_s_sigma",
              "sigma")
#: the non-dimensional parameters of ``bifurcation`` (the scatter's form)
NONDIM = ("lam", "mu_s_sigma", "chi", "zeta")


def _oscillator_options(c: argparse.ArgumentParser) -> None:
    nondim_options(c, "non-dimensional form (the paper's; default lam 0.5, mu_s sigma 0.6, chi 0.7)")
    c.add_argument("--zeta", type=number("--zeta", 0.0), default=None, help="damping ratio (both forms)")
    c.add_argument("--phi", type=number("--phi"), default=0.0, help="excitation phase, rad (default 0)")
    physical_options(c.add_argument_group("physical units (SI; any of these selects them)"), required=False)


def _common(c: argparse.ArgumentParser, default_out: str) -> None:
    c.add_argument("--period", type=count("--period", 1), default=1, help="orbits of K excitation periods (default 1)")
    c.add_argument("--ds", type=number("--ds", 0.0, True), default=0.02, help="first arclength step (default 0.02)")
    c.add_argument("--ds-max", type=number("--ds-max", 0.0, True), default=1.0, help="largest step (default 1)")
    c.add_argument("--max-points", type=count("--max-points", 2), default=400, help="points per branch (default 400)")
    c.add_argument("--max-branches", type=count("--max-branches", 1), default=8,
                   help="branches in all, the switched ones included (default 8)")
    c.add_argument("--no-switch", action="store_true",
                   help="do not continue the doubled and the asymmetric branches")
    c.add_argument("--out", type=path_arg("--out"), default=None, help=f"output folder (default {default_out})")
    c.add_argument("--no-progress", action="store_true", help="no progress bar")


def add_parser(sub: Any, parents: list[argparse.ArgumentParser]) -> None:
    """Add the ``continuation`` and ``bifurcation`` commands to the main parser's subparsers ``sub``."""
    c = sub.add_parser("continuation", parents=parents,
                       help="continue periodic orbits in a parameter: branches, stability, bifurcations",
                       description="Pseudo-arclength continuation of the periodic orbits of the exact stroboscopic "
                                   "map in one parameter, with folds, period doublings (and the doubled branch), "
                                   "symmetry breaking (and the asymmetric branches) and grazing located.")
    c.add_argument("--param", choices=list(PARAMETERS), required=True, help="the parameter to continue in")
    c.add_argument("--from", dest="start", type=number("--from"), required=True, help="first value")
    c.add_argument("--to", dest="stop", type=number("--to"), required=True, help="last value")
    _oscillator_options(c)
    _common(c, "results/continuation")
    c.add_argument("--json", action="store_true", help="print one JSON object (files only with --out)")

    b = sub.add_parser("bifurcation", parents=parents,
                       help="branches of periodic orbits over the brute-force attractor scatter (Fig. 8/9)",
                       description="Continuation branches (stable solid, unstable dashed, bifurcations marked) over "
                                   "the attractors of a grid of initial conditions after a transient, against a "
                                   "non-dimensional parameter: one PNG.")
    b.add_argument("--param", choices=NONDIM, default="chi", help="the parameter (default chi)")
    b.add_argument("--from", dest="start", type=number("--from"), default=None, help="first value (default 1.0)")
    b.add_argument("--to", dest="stop", type=number("--to"), default=None, help="last value (default 0.2)")
    b.add_argument("--lam", type=number("--lam", 0.0, True), default=0.5, help="omega / w0 (default 0.5)")
    b.add_argument("--mu-s-sigma", type=number("--mu-s-sigma", 0.0), default=0.6, help="mu_s N / P0 (default 0.6)")
    b.add_argument("--chi", type=number("--chi", 0.0), default=0.7, help="mu_k / mu_s (default 0.7)")
    b.add_argument("--zeta", type=number("--zeta", 0.0), default=0.0, help="damping ratio (default 0)")
    b.add_argument("--values", type=count("--values", 2), default=None,
                   help="parameter values of the scatter (default 80; --quick 16)")
    b.add_argument("--ics", type=count("--ics", 1), default=None,
                   help="initial conditions per axis over [-2, 2]^2 (default 11; --quick 5)")
    b.add_argument("--periods", type=count("--periods", 2), default=30,
                   help="transient before the observed period (default 30, as Fig. 8/9)")
    b.add_argument("--quick", action="store_true", help="a coarse scatter (16 values x 5 x 5 initial conditions)")
    _common(b, "results/bifurcation")


def work(args: argparse.Namespace) -> tuple[float, str]:
    """``continuation``: points x branches (:func:`dryfriction.budget.continuation_work`);
    ``bifurcation``: the scatter's runs too."""
    from ..budget import continuation_work, fmt

    if args.command == "continuation":
        return continuation_work(int(args.max_points), int(args.max_branches), int(args.period))
    values = int(args.values or (16 if args.quick else 80))
    ics = int(args.ics or (5 if args.quick else 11)) ** 2
    runs = values * ics
    periods = int(args.periods) + 1
    return runs * periods * 1000.0, f"{fmt(runs)} runs x {periods} periods x 1,000 steps"


def _oscillator(args: argparse.Namespace) -> Any:
    from ..params import Oscillator

    nondim = nondim_given(args)
    if physical_given(args):
        one_form(nondim)
        if args.param in ("f", "omega", "lam") and args.f is None and args.omega is None:
            args.omega = 1.0              # replaced by --from
        p = physical(args)
        return p.with_(phi=args.phi)
    return Oscillator.from_nondimensional(lam=nondim.get("lam", 0.5), mu_s_sigma=nondim.get("mu_s_sigma", 0.6),
                                          chi=nondim.get("chi", 0.7), zeta=args.zeta or 0.0, phi=args.phi)


class _Progress:
    def __init__(self, on: bool) -> None:
        self.bar = None
        if on:
            from tqdm import tqdm

            self.bar = tqdm(desc="continuation", unit=" points", file=sys.stderr, leave=False)

    def __call__(self, n: int) -> None:
        if self.bar is not None:
            self.bar.n = n
            self.bar.refresh()

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def _continue(args: argparse.Namespace, p: Any) -> Any:
    from ..analysis.continuation import continue_orbits
    from ..drivers.oscillator import OscillatorFMU2

    prog = _Progress(not args.no_progress and sys.stderr.isatty())
    try:
        with OscillatorFMU2(args.fmu) as fmu:
            return continue_orbits(p, args.param, args.start, args.stop, period=args.period, ds=args.ds,
                                   ds_min=min(1e-6, args.ds), ds_max=max(args.ds_max, args.ds),
                                   max_points=args.max_points, max_branches=args.max_branches,
                                   switch=not args.no_switch, fmu=fmu, progress=prog)
    except (ValueError, NotImplementedError) as e:
        raise UsageError(str(e)) from None
    finally:
        prog.close()


def branches_json(c: Any) -> list[dict[str, Any]]:
    """Every branch of a continuation with its points, as the ``--json`` object lists them."""
    ds = c.dataset
    out = []
    for b in c.branches:
        s = ds.where(ds.branch == b.id, drop=True) if ds.point.size else ds
        d = b.as_dict()
        for name in ("param", "x0", "v0", "amplitude_m", "offset_m", "stick_fraction", "mu_max"):
            d[name] = [float(v) for v in s[name].values]
        d["stable"] = [bool(v) for v in s["stable"].values]
        d["converged"] = [bool(v) for v in s["converged"].values]
        d["multipliers"] = [[[float(r), float(i)] for r, i in zip(re, im)]
                            for re, im in zip(s.multiplier_re.values, s.multiplier_im.values)]
        out.append(d)
    return out


def write_csv(c: Any, path: Path) -> None:
    """The continuation's points as CSV, one row each."""
    ds = c.dataset
    v = {n: ds[n].values for n in ds.data_vars}
    cols = ["branch", "period", "kind", "param", "converged", "stable", "x0", "v0", "amplitude_m", "offset_m",
            "stick_fraction", "transitions", "mu_max", "mu1_re", "mu1_im", "mu2_re", "mu2_im", "residual", "reason"]
    lines = [",".join(cols)]
    for i in range(ds.point.size):
        row = [str(int(v["branch"][i])), str(int(v["period"][i])), str(v["kind"][i]), repr(float(v["param"][i])),
               str(bool(v["converged"][i])).lower(), str(bool(v["stable"][i])).lower()]
        row += [repr(float(v[n][i])) for n in ("x0", "v0", "amplitude_m", "offset_m", "stick_fraction")]
        row += [str(int(v["transitions"][i])), repr(float(v["mu_max"][i]))]
        for j in range(2):
            row += [repr(float(v["multiplier_re"][i, j])), repr(float(v["multiplier_im"][i, j]))]
        row += [repr(float(v["residual"][i])), '"' + str(v["reason"][i]).replace('"', "'") + '"']
        lines.append(",".join(row))
    from ..atomic import atomic_write_text

    atomic_write_text(path, "\n".join(lines) + "\n")


def plot(c: Any, path: Path, title: str) -> None:
    """Draw the branches (amplitude and ``|mu|max`` against the parameter, unstable ones dashed) with the
    bifurcations into a PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..analysis.plots import plot_branches

    fig, axes = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
    plot_branches(axes, c, 1.0)
    axes[0].set_ylabel("amplitude (x_max - x_min) / 2, m")
    axes[1].set_ylabel("offset (x_max + x_min) / 2, m")
    axes[1].set_xlabel(c.dataset.param.attrs.get("long_name", c.param))
    axes[0].legend(fontsize=7, loc="best")
    for ax in axes:
        ax.grid(alpha=0.3)
    axes[0].set_title(title + "\nsolid: stable, dashed: unstable; F fold, PD period doubling, SB symmetry breaking, "
                              "G grazing", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _describe(p: Any, name: str, start: float) -> str:
    """The fixed parameters of the continuation (the oscillator at its start)."""
    from ..analysis.continuation import set_parameter

    p = set_parameter(p, name, start)
    try:
        vals = {k: v for k, v in p.to_nondimensional().items() if k in NONDIM}
        if name in ("m", "k", "c", "P0", "omega", "f", "N", "mu_s", "mu_k", "sigma"):
            raise ValueError
    except ValueError:
        vals = {"m": p.m, "k": p.k, "c": p.c, "P0": p.P0, "omega": p.omega, "N": p.N, "mu_s": p.mu_s, "chi": p.chi}
    defines = {"f": "omega", "lam": "omega", "zeta": "c", "mu_k": "chi", "mu_s_sigma": "N", "sigma": "N"}
    fixed = ", ".join(f"{k} {v:.4g}" for k, v in vals.items() if k not in (name, defines.get(name)))
    return f"continuation in {name}; {fixed}"


def run(args: argparse.Namespace) -> int:
    """Run ``dryfriction continuation`` or ``dryfriction bifurcation``; the exit status."""
    from .console import check_output_folder, result_set

    if args.command == "bifurcation":
        return _bifurcation(args)
    if args.start == args.stop:
        raise UsageError(f"--from and --to must differ (both {args.start:g})")
    p = _oscillator(args)
    out = None
    if args.out is not None or not args.json:
        out = check_output_folder(args.out or Path("results/continuation"))
    c = _continue(args, p)
    files: dict[str, str] = {}
    if out is not None:
        from ..sweep.datasets import write_netcdf

        with result_set(out) as stage:
            write_netcdf(c.dataset, stage / "continuation.nc")
            write_csv(c, stage / "continuation.csv")
            plot(c, stage / "continuation.png", _describe(p, args.param, args.start))
        files = {kind: str(out / f"continuation.{ext}") for kind, ext in (("netcdf", "nc"), ("csv", "csv"),
                                                                          ("png", "png"))}
    if args.json:
        print_json(json_safe({"param": args.param, "branches": branches_json(c),
                           "bifurcations": [b.as_dict() for b in c.bifurcations], "files": files}))
        return 0
    for b in c.branches:
        print(f"branch {b.id}: period {b.period}, {b.kind}, {b.points} points"
              f"{'' if b.parent is None else f', from branch {b.parent}'}; {b.stopped}")
    for f in c.bifurcations:
        mu = ", ".join(f"{m.real:.6g}{m.imag:+.3g}j" if m.imag else f"{m.real:.6g}" for m in f.multipliers)
        print(f"{f.type} at {args.param} = {f.param:.10g} (branch {f.branch}, period {f.period}; multipliers {mu})"
              f"{'; ' + f.note if f.note else ''}")
    if not c.bifurcations:
        print("no bifurcation found")
    for k, v in files.items():
        print(f"wrote {v}")
    return 0


def _bifurcation(args: argparse.Namespace) -> int:
    import numpy as np

    from .. import paths
    from ..analysis.plots import plot_branches
    from ..params import Oscillator
    from ..studies.common import K_REF, M_REF, MU_S_REF, P0_REF, sweep_settings, table
    from ..sweep.datasets import observables_dataset
    from ..sweep.runner import run_batch
    from .console import check_output_folder, result_set

    start = 1.0 if args.start is None else args.start
    stop = 0.2 if args.stop is None else args.stop
    if start == stop:
        raise UsageError(f"--from and --to must differ (both {start:g})")
    outdir = check_output_folder(args.out or Path("results/bifurcation"))
    nd = {"lam": args.lam, "mu_s_sigma": args.mu_s_sigma, "chi": args.chi, "zeta": args.zeta, "phi": 0.0}
    n_val = args.values or (16 if args.quick else 80)
    n_ic = args.ics or (5 if args.quick else 11)
    grid = np.linspace(min(start, stop), max(start, stop), n_val)
    ics = np.linspace(-2.0, 2.0, n_ic)
    G, Z, D = np.meshgrid(grid, ics, ics, indexing="ij")
    numerics = {"steps_per_period": 1000, "scheme": "exact", "alpha": -0.1, "frictionUpdates": 1}
    vals = {**nd, args.param: G, "z0": Z, "dz0": D}
    P = table(vals, float(args.periods), float(args.periods - 1), float(args.periods), numerics)
    try:
        fmu_path = paths.fmu_path(paths.OSCILLATOR, args.fmu)
        out = run_batch(str(fmu_path), sweep_settings(numerics), P)
    except ValueError as e:
        raise UsageError(str(e)) from None
    sc = observables_dataset(out, {args.param: grid, "z0": ics, "dz0": ics})
    base = {k: v for k, v in nd.items() if k != "phi"}
    base[args.param] = start
    p = Oscillator.from_nondimensional(**base, m=M_REF, k=K_REF, P0=P0_REF, mu_s=MU_S_REF)
    args.period = getattr(args, "period", 1)
    args.start, args.stop = start, stop
    c = _continue(args, p)

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 1, figsize=(8, 7.5), sharex=True)
    xs = np.repeat(grid, n_ic * n_ic)
    for ax, var in zip(axes, ("amplitude", "asymmetry")):
        ax.scatter(xs, sc[var].values.reshape(-1), s=5, c="0.5", alpha=0.5, lw=0, rasterized=True,
                   label=f"attractors: {n_ic} x {n_ic} initial conditions after {args.periods} T")
    plot_branches(axes, c, K_REF / P0_REF)
    axes[0].set_ylabel("amplitude (z_max - z_min) / 2")
    axes[1].set_ylabel("asymmetry (z_max + z_min) / 2")
    axes[1].set_xlabel(args.param)
    axes[0].legend(fontsize=7, loc="upper right")
    for ax in axes:
        ax.grid(alpha=0.3)
    fixed = ", ".join(f"{k} = {v:g}" for k, v in base.items() if k != args.param)
    axes[0].set_title(f"Branches of periodic orbits over the brute-force attractors ({fixed}; z = k x / P0)\n"
                      "solid: stable, dashed: unstable; F fold, PD period doubling, SB symmetry breaking, G grazing",
                      fontsize=8)
    fig.tight_layout()
    png = outdir / "bifurcation.png"
    try:
        with result_set(outdir) as stage:
            fig.savefig(stage / png.name, dpi=120)
    finally:
        plt.close(fig)
    for f in c.bifurcations:
        print(f"{f.type} at {args.param} = {f.param:.10g} (branch {f.branch}, period {f.period})")
    print(f"{P.shape[0]} runs for the scatter, {c.dataset.point.size} branch points; wrote {png}")
    return 0
