"""``dryfriction chain``: run the chain of n blocks once and write its trajectory.

    dryfriction chain --n 8 --t-end 20 --dt 0.05 --set mu_s=0.3 --set P0=1,0,0,0,0,0,0,0 --set h=0.002
    dryfriction chain --fmi 2 ...            # the FMI 2.0 build (its n is fixed when building)

Writes ``<out>/chain.nc`` (xarray: x, v, a, F_friction, mode over time and block), ``chain.csv``
(t, then x[1] ... x[n], v[...], a[...], F_friction[...], mode[...]) and ``chain.png`` (the
space-time image of the modes and the positions); prints each block's share of time stuck.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import UsageError
from .options import count, number, path_arg

__all__ = ["add_chain_parser", "chain_main", "parse_sets", "write_csv", "plot_run"]


def add_chain_parser(sub: Any, parents: list[argparse.ArgumentParser]) -> argparse.ArgumentParser:
    """Add the ``chain`` command and its options to the subcommands ``sub``."""
    c = sub.add_parser("chain", parents=parents, help="run the chain of n blocks (DryFrictionChain.fmu)",
                       description="Run the chain of n blocks with dry friction once (FMI 3.0: n set in "
                                   "Configuration Mode) and write its trajectory as NetCDF/CSV and a PNG. "
                                   "--fmu PATH selects the chain FMU.")
    c.add_argument("--n", type=count("--n"), default=None, help="number of blocks (default 2; FMI 2.0: its built n)")
    c.add_argument("--fmi", type=int, choices=(2, 3), default=3, help="FMI version of the chain FMU (default 3)")
    c.add_argument("--t-end", type=number("--t-end", 0.0, True), default=20.0, help="end time, s (default 20)")
    c.add_argument("--dt", type=number("--dt", 0.0, True), default=0.05, help="communication step, s (default 0.05)")
    c.add_argument("--set", dest="sets", action="append", default=[], metavar="NAME=VALUE",
                   help="a parameter: one value for every block (mu_s=0.3), n values (P0=1,0,0), a scalar "
                        "(omega=0.5, h=0.002, k_end=1) or the scheme (scheme=consistent); repeatable")
    c.add_argument("--out", type=path_arg("--out"), default=Path("results/chain"),
                   help="output folder (default results/chain)")
    c.add_argument("--format", choices=("csv", "netcdf", "both"), default="both", help="table format (default both)")
    c.add_argument("--no-plot", action="store_true", help="no PNG")
    return c


def parse_sets(sets: list[str]) -> dict[str, Any]:
    """``NAME=VALUE`` strings: a number, a comma-separated list of numbers or (scheme) a name."""
    out: dict[str, Any] = {}
    for item in sets:
        name, eq, text = item.partition("=")
        name = name.strip()
        if not eq or not name or not text.strip():
            raise UsageError(f"--set needs NAME=VALUE, not {item!r}")
        if name == "scheme":
            out[name] = int(text) if text.strip().lstrip("-").isdigit() else text.strip()
            continue
        try:
            vals = [float(x) for x in text.split(",")]
        except ValueError:
            raise UsageError(f"--set {name}: {text!r} is not a number or a comma-separated list of numbers") from None
        out[name] = vals[0] if len(vals) == 1 else vals
    return out


def write_csv(run: Any, path: Path) -> Path:
    """Write a chain run's outputs to a CSV file (a column per output and block), atomically."""
    from ..atomic import atomic_write_text
    from ..drivers.chain import OUTPUTS

    n = run.n
    cols = ["t"] + [f"{k}[{i}]" for k in OUTPUTS for i in range(1, n + 1)]
    lines = [",".join(cols)]
    for j in range(run.t.size):
        row = [f"{run.t[j]:.17g}"]
        for k in OUTPUTS:
            vals = getattr(run, k)[j]
            row.extend(str(int(v)) for v in vals) if k == "mode" else row.extend(f"{v:.17g}" for v in vals)
        lines.append(",".join(row))
    return atomic_write_text(path, "\n".join(lines) + "\n")


def plot_run(run: Any, path: Path) -> Path:
    """Draw a chain run (positions and modes of every block over time) into a PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap

    from ..atomic import atomic_path

    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
    cmap = ListedColormap(["#3b6fb6", "#d9d9d9", "#c0392b"])
    im = ax[0].pcolormesh(np.arange(1, run.n + 1), run.t, run.mode, cmap=cmap, vmin=-1.5, vmax=1.5,
                          shading="nearest", rasterized=True)
    cb = fig.colorbar(im, ax=ax[0], ticks=[-1, 0, 1])
    cb.ax.set_yticklabels(["backward", "stuck", "forward"])
    ax[0].set_xlabel("block")
    ax[0].set_ylabel("t (s)")
    ax[0].set_title("mode of each block")
    show = np.unique(np.linspace(0, run.n - 1, min(run.n, 6)).round().astype(int))
    for i in show:
        ax[1].plot(run.t, run.x[:, i], lw=0.9, label=f"x[{i + 1}]")
    ax[1].set_xlabel("t (s)")
    ax[1].set_ylabel("x (m)")
    ax[1].legend(fontsize=7)
    ax[1].set_title(f"chain of {run.n} blocks")
    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format="png", dpi=110, bbox_inches="tight")
    finally:
        plt.close(fig)
    return path


def chain_main(args: argparse.Namespace) -> int:
    """Run ``dryfriction chain``: one run of the chain FMU, written as NetCDF, CSV and PNG; returns the exit
    status."""
    from ..drivers.chain import ChainFMU2, ChainFMU3

    from .console import check_output_folder, result_set

    params = parse_sets(args.sets)
    out: Path = check_output_folder(args.out)
    try:
        if args.fmi == 3:
            fmu: Any = ChainFMU3(2 if args.n is None else args.n, params, fmu_path=args.fmu)
        else:
            fmu = ChainFMU2(params, fmu_path=args.fmu, n=args.n)
        with fmu:
            run = fmu.run(args.t_end, args.dt)
    except ValueError as e:
        raise UsageError(str(e)) from None
    files = []
    with result_set(out) as stage:
        if args.format in ("csv", "both"):
            files.append(write_csv(run, stage / "chain.csv"))
        if args.format in ("netcdf", "both"):
            from ..sweep.datasets import write_netcdf

            files.append(write_netcdf(run.to_dataset(), stage / "chain.nc"))
        if not args.no_plot:
            files.append(plot_run(run, stage / "chain.png"))
    files = [out / f.relative_to(stage) for f in files]
    share = run.stick_share()
    print(f"chain of {run.n} blocks (FMI {args.fmi}), {run.t.size} points to t = {run.t[-1]:g} s")
    shown = ", ".join(f"{s:.3f}" for s in share[:16]) + (" ..." if run.n > 16 else "")
    print(f"share of time stuck per block: {shown}")
    print(f"largest |x| per block (m): " + ", ".join(f"{v:.4g}" for v in np.max(np.abs(run.x), axis=0)[:16])
          + (" ..." if run.n > 16 else ""))
    for f in files:
        print(f"wrote {f}")
    return 0
