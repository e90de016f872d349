"""Fig. 4: four steady-state cycles below and above resonance.

From rest, after ``run.skip_periods`` periods of transient, z, z' and the stuck intervals over
``run.cycles`` cycles at one frequency ratio below resonance (long stick phases) and one above
(hardly any).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

from .common import (Estimate, FIGURE_BYTES, StudyContext, check_numerics, check_params, ensure, nondim_trajectory, plt,
                     trajectory_estimate)
from .config import require
from . import REGISTRY

NAME = "fig4"
TITLE = REGISTRY[NAME].title
FIGURES = REGISTRY[NAME].figures
DATASET = "fig4.nc"


def check(cfg: dict[str, Any]) -> None:
    """Refuse a configuration of the Fig. 4 study with a value out of range (ConfigError naming the key),
    before any work."""
    check_params(cfg["params"])
    check_numerics(cfg["numerics"])
    r = cfg["run"]
    require(r["lam_below"] > 0 and r["lam_above"] > 0, "run.lam_below and run.lam_above must be > 0")
    require(r["skip_periods"] >= 0, f"run.skip_periods must be >= 0, not {r['skip_periods']}")
    require(r["cycles"] > 0, f"run.cycles must be > 0, not {r['cycles']}")
    require(r["samples_per_period"] >= 10, f"run.samples_per_period must be >= 10, not {r['samples_per_period']}")


def run(ctx: StudyContext) -> dict[str, float]:
    """Run the Fig. 4 study: its runs, dataset and figures in the study's folder; returns the summary."""
    cfg = ctx.cfg
    nd, r, num = cfg["params"], cfg["run"], cfg["numerics"]
    cases = {"below": r["lam_below"], "above": r["lam_above"]}
    t0, t1 = r["skip_periods"], r["skip_periods"] + r["cycles"]
    trs = {k: nondim_trajectory(ctx.fmu(), {**nd, "lam": lam}, t0, t1, r["samples_per_period"], num)
           for k, lam in cases.items()}
    cyc = trs["below"]["cycles"]
    ds = xr.Dataset(
        {key: (("case", "cycles"), np.stack([trs[c][key] for c in cases]), {"long_name": ln})
         for key, ln in (("z", "z = k x / P0"), ("dz", "z' = dz/dtau"), ("mode", "-1/0/+1 backward/stuck/forward"),
                         ("excitation", "cos(lam tau + phi)"))},
        coords={"case": list(cases), "lam": ("case", list(cases.values())),
                "cycles": ("cycles", cyc, {"long_name": "t / T"})},
        attrs={**{f"param_{k}": v for k, v in nd.items()}, "steps_per_period": num["steps_per_period"]},
    )
    stuck = {c: float(np.mean(trs[c]["mode"] == 0)) for c in cases}
    ds["stuck_share"] = ("case", [stuck[c] for c in cases], {"long_name": "share of samples stuck"})
    ctx.save_dataset(ds, DATASET)

    fig, axs = plt.subplots(2, 2, figsize=(10, 6), sharex=True)
    for j, c in enumerate(cases):
        tr = trs[c]
        for i, (key, label) in enumerate((("z", "z"), ("dz", "z'"))):
            ax = axs[i, j]
            ax.plot(cyc, tr[key], color="C0", lw=1.1)
            ax.plot(cyc, tr["excitation"], color="0.6", lw=0.8, ls="--", label="cos(lam tau)")
            y = tr[key]
            ax.fill_between(cyc, y.min(), y.max(), where=tr["mode"] == 0, color="C3", alpha=0.15, lw=0,
                            label="stuck")
            ax.set_ylabel(label)
            ax.grid(alpha=0.3)
        axs[0, j].set_title(f"{c} resonance: lambda = {cases[c]} (stuck {100 * stuck[c]:.0f}% of the time)",
                            fontsize=9)
        axs[1, j].set_xlabel("t / T")
    axs[0, 0].legend(loc="upper right", fontsize=8)
    fig.suptitle(f"Fig. 4: steady state from rest, mu_s sigma = {nd['mu_s_sigma']}, chi = {nd['chi']}", fontsize=10)
    ctx.save_figure(fig, FIGURES[0])
    ensure(stuck["below"] > stuck["above"], "stiction is not longer below resonance than above")
    ctx.log(f"fig4: stuck {100 * stuck['below']:.1f}% of the time at lambda = {cases['below']}, "
            f"{100 * stuck['above']:.1f}% at lambda = {cases['above']}")
    return {"stuck_below": stuck["below"], "stuck_above": stuck["above"]}


def work(cfg: dict[str, Any]) -> Estimate:
    """The study's work and output size (:mod:`dryfriction.budget`): two trajectories, sampled
    over their last ``run.cycles`` periods."""
    r = cfg["run"]
    periods = r["skip_periods"] + r["cycles"]
    est = trajectory_estimate(Estimate(), "fig4 trajectories", 2, periods, cfg["numerics"],
                              r["samples_per_period"] * r["cycles"] / periods)
    return est.add("figures", 0.0, FIGURE_BYTES * len(FIGURES))
