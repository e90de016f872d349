"""Fig. 7: percentage stiction time in the 30th cycle against the frequency ratio, for ten
friction levels.

Every run starts from rest; the FMU measures the time stuck over the window
[(cycle - 1) T, cycle T] (the ``cycle``-th excitation period), with a fine internal step. The
located scheme places every stop and breakaway inside its step, so the stuck time is accurate to
second order in h.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..sweep import SweepSpec, observables_dataset
from .common import (Estimate, FIGURE_BYTES, StudyContext, check_numerics, check_params, ensure, plt, sweep_estimate,
                     sweep_settings, table)
from .config import grid, require
from . import REGISTRY

NAME = "fig7"
TITLE = REGISTRY[NAME].title
FIGURES = REGISTRY[NAME].figures
DATASET = "fig7.nc"


def check(cfg: dict[str, Any]) -> None:
    """Refuse a configuration of the Fig. 7 study with a value out of range (ConfigError naming the key),
    before any work."""
    check_params(cfg["params"])
    check_numerics(cfg["numerics"])
    s = cfg["sweep"]
    require(len(s["mu_s_sigma"]) >= 1, "sweep.mu_s_sigma needs at least one value")
    for i, v in enumerate(s["mu_s_sigma"]):
        require(v >= 0, f"sweep.mu_s_sigma[{i}] must be >= 0, not {v}")
    require(s["lam"]["start"] > 0 and s["lam"]["stop"] > 0, "sweep.lam must stay > 0")
    grid(s["lam"], "sweep.lam")
    require(s["cycle"] >= 1, f"sweep.cycle must be >= 1, not {s['cycle']}")


def run(ctx: StudyContext) -> dict[str, float]:
    """Run the Fig. 7 study: its runs, dataset and figures in the study's folder; returns the summary."""
    cfg = ctx.cfg
    nd, s, num = cfg["params"], cfg["sweep"], cfg["numerics"]
    mus = np.asarray(s["mu_s_sigma"], dtype=float)
    lam = grid(s["lam"], "sweep.lam")
    M, L = np.meshgrid(mus, lam, indexing="ij")
    vals = {**nd, "mu_s_sigma": M, "lam": L}
    cyc = s["cycle"]
    P = table(vals, cyc, cyc - 1, cyc, num)
    out = ctx.run_sweep(SweepSpec("fig7", P, sweep_settings(num), num["chunk_runs"]))
    ds = observables_dataset(out, {"mu_s_sigma": mus, "lam": lam})
    ds["stiction_percent"] = 100.0 * ds.stick_fraction
    ds["stiction_percent"].attrs.update(long_name=f"time stuck in cycle {cyc}, percent of T", units="%")
    ds["lam"].attrs["long_name"] = "frequency ratio omega / w0"
    ds["mu_s_sigma"].attrs["long_name"] = "mu_s N / P0"
    ds.attrs.update({f"param_{k}": v for k, v in nd.items()})
    ds.attrs.update(cycle=cyc, steps_per_period=num["steps_per_period"], scheme=num["scheme"])
    ctx.save_dataset(ds, DATASET)

    fig, ax = plt.subplots(figsize=(8, 5))
    cmap = plt.get_cmap("viridis")
    for i, mu in enumerate(mus):
        ax.plot(lam, ds.stiction_percent[i], lw=1.0, color=cmap(i / max(len(mus) - 1, 1)), label=f"{mu:g}")
    ax.set_xlabel("frequency ratio lambda = omega / w0")
    ax.set_ylabel(f"stiction time in cycle {cyc}, % of T")
    ax.set_ylim(-2, 102)
    ax.grid(alpha=0.3)
    ax.legend(title="mu_s sigma = mu_s N / P0", fontsize=7, ncol=2)
    ax.set_title(f"Fig. 7: chi = {nd['chi']}, zeta = {nd['zeta']}, from rest, h = T/{num['steps_per_period']}",
                 fontsize=9)
    ctx.save_figure(fig, FIGURES[0])

    below = ds.stiction_percent.sel(lam=lam[lam < 1]).mean("lam")
    above = ds.stiction_percent.sel(lam=lam[lam > 1]).mean("lam")
    summary: dict[str, float] = {f"mean_below_{mu:g}": float(b) for mu, b in zip(mus, below.values)}
    summary.update({f"mean_above_{mu:g}": float(a) for mu, a in zip(mus, above.values)})
    mean = ds.stiction_percent.mean("lam").values[np.argsort(mus)]
    ensure(bool(np.all(np.diff(mean) >= 0)), "the mean stiction time does not grow with the friction level")
    if (lam < 1).any() and (lam > 1).any():
        low = mus < 0.6  # the paper: below mu ~ 0.6 hardly any stiction above resonance
        ensure(bool(np.all(below.values[low] > above.values[low])),
               "for mu_s sigma < 0.6 stiction is not larger below resonance than above")
    ctx.log("fig7: mean stiction % below / above resonance per mu_s sigma: " + ", ".join(
        f"{mu:g}: {b:.0f}/{a:.0f}" for mu, b, a in zip(mus, below.values, above.values)))
    return summary


def work(cfg: dict[str, Any]) -> Estimate:
    """The study's work and output size (:mod:`dryfriction.budget`): one sweep."""
    s = cfg["sweep"]
    est = sweep_estimate(Estimate(), "fig7", len(s["mu_s_sigma"]) * int(s["lam"]["num"]), s["cycle"], cfg["numerics"])
    return est.add("figures", 0.0, FIGURE_BYTES * len(FIGURES))
