"""Fig. 10 and 11: frequency-response curves for several chi, each point over a grid of initial
conditions.

For every (chi, lambda), every initial condition (z0, z0') of the grid is run for
``ics.periods`` periods and the FMU takes the amplitude over the last ``ics.obs_periods``. Where
the steady state is unique the points of one lambda coincide; in the sub-harmonic resonance zone
(for chi < 1) they split between coexisting motions. Fig. 10 spans the principal resonance,
Fig. 11 zooms on the low-frequency zone.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

from ..sweep import SweepSpec, observables_dataset
from .common import (Estimate, FIGURE_BYTES, StudyContext, check_numerics, check_params, check_window, plt,
                     sweep_estimate, sweep_settings, table)
from .config import grid, require
from . import REGISTRY

NAME = "fig10_11"
TITLE = REGISTRY[NAME].title
FIGURES = REGISTRY[NAME].figures
DATASETS = ("fig10.nc", "fig11.nc")
PARTS = ("fig10", "fig11")


def check(cfg: dict[str, Any]) -> None:
    """Refuse a configuration of the Fig. 10/11 study with a value out of range (ConfigError naming the key),
    before any work."""
    check_params(cfg["params"])
    check_numerics(cfg["numerics"])
    ic = cfg["ics"]
    check_window(ic["periods"], ic["obs_periods"], "ics")
    grid(ic["z0"], "ics.z0")
    grid(ic["dz0"], "ics.dz0")
    for part in PARTS:
        c = cfg[part]
        require(len(c["chi"]) >= 1, f"{part}.chi needs at least one value")
        for i, v in enumerate(c["chi"]):
            require(v >= 0, f"{part}.chi[{i}] must be >= 0, not {v}")
        require(c["lam"]["start"] > 0 and c["lam"]["stop"] > 0, f"{part}.lam must stay > 0")
        grid(c["lam"], f"{part}.lam")


def _part(ctx: StudyContext, part: str) -> xr.Dataset:
    cfg = ctx.cfg
    nd, ic, num, c = cfg["params"], cfg["ics"], cfg["numerics"], cfg[part]
    ax = {"chi": np.asarray(c["chi"], dtype=float), "lam": grid(c["lam"], f"{part}.lam"),
          "z0": grid(ic["z0"], "ics.z0"), "dz0": grid(ic["dz0"], "ics.dz0")}
    C, L, Z, D = np.meshgrid(*ax.values(), indexing="ij")
    P = table({**nd, "chi": C, "lam": L, "z0": Z, "dz0": D}, ic["periods"], ic["periods"] - ic["obs_periods"],
              ic["periods"], num)
    out = ctx.run_sweep(SweepSpec(part, P, sweep_settings(num), num["chunk_runs"]))
    ds = observables_dataset(out, ax)
    ds["lam"].attrs["long_name"] = "frequency ratio omega / w0"
    ds["chi"].attrs["long_name"] = "chi = mu_k / mu_s"
    ds.attrs.update({f"param_{k}": v for k, v in nd.items()})
    ds.attrs.update(periods=ic["periods"], obs_periods=ic["obs_periods"], steps_per_period=num["steps_per_period"],
                    scheme=num["scheme"], runs=P.shape[0])
    a = ds.amplitude.stack(ic=("z0", "dz0"))
    ds["amplitude_spread"] = (a.max("ic") - a.min("ic")) / a.median("ic")
    ds.amplitude_spread.attrs["long_name"] = "(max - min) of the amplitude over the initial conditions / median"
    return ds


def run(ctx: StudyContext) -> dict[str, float]:
    """Run the Fig. 10/11 study: its runs, dataset and figures in the study's folder; returns the summary."""
    cfg = ctx.cfg
    nd = cfg["params"]
    summary: dict[str, float] = {}
    for part, fig_name, ds_name in zip(PARTS, FIGURES, DATASETS):
        ds = _part(ctx, part)
        ctx.save_dataset(ds, ds_name)
        lam = ds.lam.values
        n_ic = ds.z0.size * ds.dz0.size
        fig, ax = plt.subplots(figsize=(8, 5))
        for i, chi in enumerate(ds.chi.values):
            amp = ds.amplitude.isel(chi=i).values.reshape(lam.size, n_ic)
            ax.scatter(np.repeat(lam, n_ic), amp.reshape(-1), s=2.5 if n_ic > 100 else 9.0, color=f"C{i}", alpha=0.25, lw=0,
                       rasterized=True)
            ax.plot(lam, np.median(amp, axis=1), color=f"C{i}", lw=0.9, label=f"chi = {chi:g} (median)")
            spread = ds.amplitude_spread.isel(chi=i).values
            summary[f"{part}_max_spread_chi_{chi:g}"] = float(np.nanmax(spread))
        if lam.min() < 1 < lam.max():
            ax.set_yscale("log")
        ax.set_xlabel("frequency ratio lambda = omega / w0")
        ax.set_ylabel("mean amplitude (z_max - z_min) / 2  (z = k x / P0, static deflections)")
        ax.grid(alpha=0.3, which="both")
        ax.legend(loc="upper left", fontsize=8)  # not "best": it would test each scattered point
        ax.set_title(f"Fig. {fig_name[3:5]}: mu_s sigma = mu_s N/P0 = {nd['mu_s_sigma']}, zeta = {nd['zeta']}; each lambda: "
                     f"{ds.z0.size} x {ds.dz0.size} initial conditions, after {cfg['ics']['periods']:g} T", fontsize=9)
        ctx.save_figure(fig, fig_name)
    ctx.log("fig10_11: largest relative amplitude spread over the initial conditions: "
            + ", ".join(f"{k}: {v:.3f}" for k, v in summary.items()))
    return summary


def part_runs(cfg: dict[str, Any], part: str) -> int:
    """A part's runs: chi x lambda x z0 x dz0, from the sizes alone."""
    ic, c = cfg["ics"], cfg[part]
    return len(c["chi"]) * int(c["lam"]["num"]) * int(ic["z0"]["num"]) * int(ic["dz0"]["num"])


def work(cfg: dict[str, Any]) -> Estimate:
    """The study's work and output size (:mod:`dryfriction.budget`): one sweep per part."""
    est = Estimate()
    for part in PARTS:
        sweep_estimate(est, part, part_runs(cfg, part), cfg["ics"]["periods"], cfg["numerics"])
    return est.add("figures", 0.0, FIGURE_BYTES * len(FIGURES))
