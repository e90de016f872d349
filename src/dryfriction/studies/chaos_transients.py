"""Transient or permanent: the spread of Fig. 8/9's amplitudes after 30, 300 and 1000 periods, and
the distribution of transient lengths (see configs/chaos_transients.toml and docs/chaos.md)."""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

from ..analysis.chaos.batch import concat, map_chunks, transient_rows
from ..analysis.chaos.maps import scheme_label
from .common import FIGURE_BYTES, Estimate, StudyContext, check_numerics, check_params, plt, trajectory_estimate
from .config import grid, require
from . import REGISTRY

NAME = "chaos_transients"
TITLE = REGISTRY[NAME].title
FIGURES = REGISTRY[NAME].figures
DATASET = "chaos_transients.nc"


def check(cfg: dict[str, Any]) -> None:
    """Refuse a configuration of the transients study with a value out of range (ConfigError naming the key),
    before any work."""
    check_params(cfg["params"])
    check_numerics(cfg["numerics"])
    s = cfg["scan"]
    for k in ("chi", "z0", "dz0"):
        grid(s[k], f"scan.{k}")
    require(s["chi"]["start"] > 0, "scan.chi must stay > 0")
    cps = s["checkpoints"]
    require(isinstance(cps, list) and len(cps) >= 1 and all(int(c) >= 1 for c in cps)
            and list(cps) == sorted(set(cps)), "scan.checkpoints must be increasing whole numbers >= 1")
    require(8 < s["tail"] <= cps[-1], "scan.tail must be in (8, last checkpoint]")
    require(s["tol"] > 0 and s["samples_per_period"] >= 10, "scan.tol > 0, scan.samples_per_period >= 10")


def run(ctx: StudyContext) -> dict[str, Any]:
    """Run the transients study: its runs, dataset and figures in the study's folder; returns the summary."""
    cfg = ctx.cfg
    nd, s, num = cfg["params"], cfg["scan"], cfg["numerics"]
    chis, z0, dz0 = grid(s["chi"], "scan.chi"), grid(s["z0"], "scan.z0"), grid(s["dz0"], "scan.dz0")
    Z, D = np.meshgrid(z0, dz0, indexing="ij")
    ics = np.column_stack([Z.ravel(), D.ravel()])
    cps = [int(c) for c in s["checkpoints"]]
    n = int(num["chunk_runs"])
    chunks = [(nd, num, float(chi), ics[i:i + n], cps, int(s["tail"]), float(s["tol"]), int(s["samples_per_period"]))
              for chi in chis for i in range(0, ics.shape[0], n)]
    o = ctx.engine_options
    res, st = map_chunks(transient_rows, o.fmu, chunks, o.workers, o.scheduler, o.progress, "transients")
    ctx.log(f"transients: {chis.size} chi x {ics.shape[0]} initial conditions x {cps[-1]} periods in {st.wall:.1f} s "
            f"(cluster start {st.startup:.1f} s, task CPU {st.task_cpu:.1f} s)")
    shp = (chis.size, ics.shape[0])
    amp = concat(res, "amplitude").reshape(shp + (len(cps),))
    asym = concat(res, "asymmetry").reshape(shp + (len(cps),))
    tlen = concat(res, "transient").reshape(shp)
    period = concat(res, "period").reshape(shp)
    med = np.nanmedian(amp, axis=1)
    spread = (np.nanmax(amp, axis=1) - np.nanmin(amp, axis=1)) / med
    asym_spread = (np.nanmax(asym, axis=1) - np.nanmin(asym, axis=1)) / med
    settled = np.stack([np.mean((tlen >= 0) & (tlen <= c), axis=1) for c in cps], axis=1)
    ds = xr.Dataset(
        {"amplitude": (("chi", "ic", "checkpoint"), amp, {"long_name": "mean amplitude over the period ending at the checkpoint"}),
         "asymmetry": (("chi", "ic", "checkpoint"), asym),
         "amplitude_spread": (("chi", "checkpoint"), spread, {"long_name": "(max - min) amplitude over the ICs / median"}),
         "asymmetry_spread": (("chi", "checkpoint"), asym_spread, {"long_name": "(max - min) asymmetry over the ICs / median amplitude"}),
         "settled_share": (("chi", "checkpoint"), settled, {"long_name": "share of ICs on their periodic attractor by the checkpoint"}),
         "transient_periods": (("chi", "ic"), tlen, {"long_name": "transient length in periods (-1: no periodic attractor reached)"}),
         "final_period": (("chi", "ic"), period, {"long_name": "period of the last stroboscopic points (0: none up to 32)"})},
        coords={"chi": chis, "ic": np.arange(ics.shape[0]), "checkpoint": cps,
                "ic_z0": ("ic", ics[:, 0]), "ic_dz0": ("ic", ics[:, 1])},
    )
    ds.attrs.update({f"param_{k}": v for k, v in nd.items()})
    ds.attrs.update(scheme=num["scheme"], steps_per_period=num["steps_per_period"], alpha=num["alpha"],
                    tol=s["tol"], tail=s["tail"], wall_s=st.wall)
    ctx.save_dataset(ds, DATASET)

    h_lbl = scheme_label(num["scheme"], num["steps_per_period"])
    fig, (a1, a2, a3) = plt.subplots(1, 3, figsize=(13, 4.2))
    for j, c in enumerate(cps):
        a1.semilogy(chis, np.maximum(spread[:, j], 1e-12), "o-", ms=3, label=f"after {c} T")
        a2.plot(chis, settled[:, j], "o-", ms=3, label=f"by {c} T")
    a1.set_xlabel("chi")
    a1.set_ylabel("amplitude spread over the ICs / median")
    a1.legend(fontsize=8)
    a1.grid(alpha=0.3)
    a2.set_xlabel("chi")
    a2.set_ylabel("share of ICs settled on a periodic motion")
    a2.legend(fontsize=8)
    a2.grid(alpha=0.3)
    bins = np.unique(np.geomspace(1, cps[-1], 30).round())
    shown = 0
    for i, chi in enumerate(chis):
        tl = tlen[i][tlen[i] >= 0]
        if tl.size >= 0.5 * ics.shape[0] and np.median(tl) > 3 and shown < 6:
            a3.hist(np.maximum(tl, 1), bins=bins, histtype="step", lw=1.2, label=f"chi = {chi:.3g} ({tl.size / ics.shape[0]:.0%} settle)")
            shown += 1
    a3.set_xscale("log")
    a3.set_xlabel("transient length (periods)")
    a3.set_ylabel("initial conditions")
    a3.legend(fontsize=7)
    a3.grid(alpha=0.3)
    fig.suptitle(f"Transient or permanent: lambda = {nd['lam']}, mu_s sigma = {nd['mu_s_sigma']}, zeta = {nd['zeta']}; "
                 f"{ics.shape[0]} initial conditions per chi; {h_lbl}", fontsize=9)
    ctx.save_figure(fig, FIGURES[0])
    summary: dict[str, Any] = {"scheme": num["scheme"], "steps_per_period": num["steps_per_period"], "wall_s": st.wall,
                               "checkpoints": cps}
    for i, chi in enumerate(chis):
        tl = tlen[i][tlen[i] >= 0]
        summary[f"chi={chi:.4g}"] = {
            "amplitude_spread": [float(x) for x in spread[i]],
            "settled_share": [float(x) for x in settled[i]],
            "transient_median": float(np.median(tl)) if tl.size else None,
            "transient_p90": float(np.percentile(tl, 90)) if tl.size else None,
            "transient_max": float(tl.max()) if tl.size else None,
            "periods_final": sorted({int(p) for p in period[i]}),
        }
    return summary


def work(cfg: dict[str, Any]) -> Estimate:
    """The study's work and output size (:mod:`dryfriction.budget`): every chi and initial
    condition run to the last checkpoint."""
    s = cfg["scan"]
    runs = int(s["chi"]["num"]) * int(s["z0"]["num"]) * int(s["dz0"]["num"])
    est = trajectory_estimate(Estimate(), "transients", runs, max(s["checkpoints"]), cfg["numerics"])
    est.out_bytes += runs * (len(s["checkpoints"]) + 4) * 8
    return est.add("figures", 0.0, FIGURE_BYTES * len(FIGURES))
