"""Basins of attraction on a grid of initial conditions, coloured by the attractor reached (see
configs/chaos_basins.toml and docs/chaos.md)."""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

from ..analysis.chaos.attractors import Catalogue
from ..analysis.chaos.batch import concat, map_chunks, orbit_tails
from ..analysis.chaos.maps import scheme_label
from .common import FIGURE_BYTES, Estimate, StudyContext, check_numerics, check_params, plt, trajectory_estimate
from .config import grid, require
from . import REGISTRY

NAME = "chaos_basins"
TITLE = REGISTRY[NAME].title
FIGURES = REGISTRY[NAME].figures


def check(cfg: dict[str, Any]) -> None:
    """Refuse a configuration of the basin maps with a value out of range (ConfigError naming the key), before
    any work."""
    check_numerics(cfg["numerics"])
    require(isinstance(cfg["cases"], list) and len(cfg["cases"]) >= 1, "cases must be a non-empty list")
    for c in cfg["cases"]:
        require(c in cfg and isinstance(cfg[c], dict), f"case {c!r} needs a table [{c}]")
        t = cfg[c]
        check_params({k: t[k] for k in ("lam", "mu_s_sigma", "chi", "zeta")}, c)
        require(t["transient"] >= 0 and t["tail"] >= 4, f"{c}.transient must be >= 0 and {c}.tail >= 4")
        require(t.get("grid_num", 2) >= 2 and t.get("steps_per_period", 10) >= 10,
                f"{c}.grid_num must be >= 2 and {c}.steps_per_period >= 10")
    g = cfg["grid"]
    grid(g["z0"], "grid.z0")
    grid(g["dz0"], "grid.dz0")
    require(g["period_tol"] > 0 and g["match_tol"] > 0, "grid.period_tol and grid.match_tol must be > 0")


def case_grid(cfg: dict[str, Any], case: str) -> tuple[np.ndarray, np.ndarray, dict[str, Any]]:
    """The initial conditions' axes and the numerics of a case (its optional ``grid_num`` and
    ``steps_per_period`` override the shared ones)."""
    t, g = cfg[case], cfg["grid"]
    n = t.get("grid_num")
    z0 = grid({**g["z0"], **({"num": n} if n else {})}, "grid.z0")
    dz0 = grid({**g["dz0"], **({"num": n} if n else {})}, "grid.dz0")
    num = {**cfg["numerics"], "steps_per_period": int(t.get("steps_per_period", cfg["numerics"]["steps_per_period"]))}
    return z0, dz0, num


def basin_map(ctx: StudyContext, case: str) -> tuple[xr.Dataset, Catalogue, float]:
    """The basin map of one case: the attractor each initial condition of the grid settles on, the catalogue
    of attractors and the wall time."""
    cfg = ctx.cfg
    t, g = cfg[case], cfg["grid"]
    z0, dz0, num = case_grid(cfg, case)
    Z, D = np.meshgrid(z0, dz0, indexing="ij")
    ics = np.column_stack([Z.ravel(), D.ravel()])
    nd = {k: t[k] for k in ("lam", "mu_s_sigma", "zeta")}
    n = int(num["chunk_runs"])
    chunks = [(nd, num, float(t["chi"]), ics[i:i + n], int(t["transient"]), int(t["tail"]))
              for i in range(0, ics.shape[0], n)]
    o = ctx.engine_options
    res, st = map_chunks(orbit_tails, o.fmu, chunks, o.workers, o.scheduler, o.progress, f"basins {case}")
    tails = concat(res, "tails")
    cat = Catalogue(tol=float(g["match_tol"]))
    labels = np.array([cat.label(x, float(g["period_tol"])) for x in tails])
    labels = cat.canonical()[labels]
    shares = np.array([np.mean(labels == i) for i in range(len(cat.attractors))])
    ctx.log(f"basins {case}: {ics.shape[0]:,} runs of {t['transient']} + {t['tail']} periods in {st.wall:.1f} s "
            f"(cluster start {st.startup:.1f} s, task CPU {st.task_cpu:.1f} s); "
            + "; ".join(f"{a.describe()}: {s:.4f}" for a, s in zip(cat.attractors, shares)))
    pts = np.full((len(cat.attractors), cat.max_period, 2), np.nan)
    for i, a in enumerate(cat.attractors):
        if a.period:
            pts[i, :a.period] = a.points
    ds = xr.Dataset(
        {"attractor_z": (("attractor_index", "point"), pts[..., 0],
                         {"long_name": "stroboscopic z of the periodic attractor's points (nan-padded)"}),
         "attractor_dz": (("attractor_index", "point"), pts[..., 1]),
         "attractor": (("z0", "dz0"), labels.reshape(Z.shape).astype(np.int16),
                       {"long_name": "index of the attractor reached (-1: the run failed)"}),
         "final_z": (("z0", "dz0"), tails[:, -1, 0].reshape(Z.shape), {"long_name": "last stroboscopic z"}),
         "share": (("attractor_index",), shares, {"long_name": "share of the initial conditions"}),
         "attractor_period": (("attractor_index",), np.array([a.period for a in cat.attractors]),
                              {"long_name": "period of the attractor (0: non-periodic)"})},
        coords={"z0": z0, "dz0": dz0, "attractor_index": np.arange(len(cat.attractors))},
    )
    ds.attrs.update({f"param_{k}": v for k, v in t.items()})
    ds.attrs.update(task_cpu_s=st.task_cpu)
    ds.attrs.update(case=case, scheme=num["scheme"], steps_per_period=num["steps_per_period"], alpha=num["alpha"],
                    period_tol=g["period_tol"], match_tol=g["match_tol"], wall_s=st.wall,
                    attractors="; ".join(a.describe() for a in cat.attractors))
    return ds, cat, st.wall


def plot_basins(ds: xr.Dataset) -> Any:
    """The basin map of a dataset written by this study (labels, shares and names from it)."""
    a = ds.attrs
    names = str(a["attractors"]).split("; ")
    lab = ds.attractor.values
    k = len(names)
    fig, ax = plt.subplots(figsize=(6.4, 5.4))
    cmap = plt.get_cmap("tab10", max(k, 2))
    im = ax.pcolormesh(ds.z0.values, ds.dz0.values, lab.T, cmap=cmap, vmin=-0.5, vmax=max(k, 2) - 0.5,
                       shading="nearest", rasterized=True)
    cb = fig.colorbar(im, ax=ax, ticks=range(k))
    cb.ax.set_yticklabels([f"{i}: {n[:28]} ({s:.2%})" for i, (n, s) in enumerate(zip(names, ds.share.values))],
                          fontsize=6)
    ax.set_xlabel("z0")
    ax.set_ylabel("z0'")
    ax.set_title(f"Basins, {a['case']}: lambda = {a['param_lam']}, mu_s sigma = {a['param_mu_s_sigma']}, "
                 f"chi = {a['param_chi']}, zeta = {a['param_zeta']}\n{lab.size:,} initial conditions, "
                 f"{a['param_transient']} T transient; {scheme_label(str(a['scheme']), int(a['steps_per_period']))}", fontsize=8)
    return fig


def run(ctx: StudyContext) -> dict[str, Any]:
    """Run the basin maps: its runs, dataset and figures in the study's folder; returns the summary."""
    cfg = ctx.cfg
    num = cfg["numerics"]
    summary: dict[str, Any] = {"scheme": num["scheme"]}
    for case in cfg["cases"]:
        ds, cat, wall = basin_map(ctx, case)
        ctx.save_dataset(ds, f"chaos_basins_{case}.nc")
        t = cfg[case]
        lab = ds.attractor.values
        fig = plot_basins(ds)
        ctx.save_figure(fig, f"chaos_basins_{case}.png")
        summary[case] = {"runs": int(lab.size), "wall_s": wall, "task_cpu_s": float(ds.attrs["task_cpu_s"]),
                         "steps_per_period": int(ds.attrs["steps_per_period"]), "transient": int(t["transient"]),
                         "attractors": [a.describe() for a in cat.attractors],
                         "shares": [float(s) for s in ds.share.values]}
    return summary


def work(cfg: dict[str, Any]) -> Estimate:
    """The study's work and output size (:mod:`dryfriction.budget`): a grid of runs per case."""
    est = Estimate()
    for case in cfg["cases"]:
        t, g = cfg[case], cfg["grid"]
        n = t.get("grid_num")
        runs = int(n or g["z0"]["num"]) * int(n or g["dz0"]["num"])
        num = {**cfg["numerics"], "steps_per_period": t.get("steps_per_period", cfg["numerics"]["steps_per_period"])}
        trajectory_estimate(est, f"basins {case}", runs, t["transient"] + t["tail"], num)
        est.add(f"figure {case}", 0.0, runs * (2 * int(t["tail"]) + 4) * 8 + FIGURE_BYTES)
    return est
