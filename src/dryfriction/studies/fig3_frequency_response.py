"""Fig. 3: steady-state frequency response from rest against Inman's and Den Hartog's amplitudes.

One run per frequency ratio, from rest at z = 0, for ``sweep.periods`` excitation periods; the
amplitude (z_max - z_min) / 2 is taken over the last ``sweep.obs_periods`` periods by the FMU.
Den Hartog's non-stop solution is exact where it holds (no stick at the turning points); Inman's
is his equivalent-energy approximation, which ignores stiction and departs below resonance.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..references.steady import den_hartog_amplitude, inman_amplitude
from ..sweep import SweepSpec, observables_dataset
from .common import (Estimate, FIGURE_BYTES, StudyContext, check_numerics, check_params, check_window, ensure,
                     oscillator, plt, sweep_estimate, sweep_settings, table)
from .config import grid, require
from . import REGISTRY

NAME = "fig3"
TITLE = REGISTRY[NAME].title
FIGURES = REGISTRY[NAME].figures
DATASET = "fig3.nc"


def lambdas(cfg: dict[str, Any]) -> np.ndarray:
    """The frequency ratios of the sweep, the excluded ones left out."""
    s = cfg["sweep"]
    lam = grid(s["lam"], "sweep.lam")
    if not s["exclude"]:            # [] : nothing left out
        return lam
    lo, hi = s["exclude"]
    return lam[~((lam > lo) & (lam < hi))]


def check(cfg: dict[str, Any]) -> None:
    """Refuse a configuration of the Fig. 3 study with a value out of range (ConfigError naming the key),
    before any work."""
    check_params(cfg["params"])
    check_numerics(cfg["numerics"])
    s = cfg["sweep"]
    check_window(s["periods"], s["obs_periods"], "sweep")
    require(s["lam"]["start"] > 0 and s["lam"]["stop"] > 0, "sweep.lam must stay > 0")
    require(len(s["exclude"]) in (0, 2), f"sweep.exclude must be [low, high] or [], not {s['exclude']}")
    require(lambdas(cfg).size >= 1, "no frequency ratio left outside sweep.exclude")


def run(ctx: StudyContext) -> dict[str, float]:
    """Run the Fig. 3 study: its runs, dataset and figures in the study's folder; returns the summary."""
    cfg = ctx.cfg
    nd, s, num = cfg["params"], cfg["sweep"], cfg["numerics"]
    lam = lambdas(cfg)
    vals = {k: v for k, v in nd.items()}
    vals["lam"] = lam
    P = table(vals, s["periods"], s["periods"] - s["obs_periods"], s["periods"], num)
    out = ctx.run_sweep(SweepSpec("fig3", P, sweep_settings(num), num["chunk_runs"]))
    ds = observables_dataset(out, {"lam": lam})
    p = oscillator({**nd, "lam": 1.0})
    scale = p.k / p.P0
    ds["inman"] = ("lam", np.asarray(inman_amplitude(p, lam)) * scale,
                   {"long_name": "Inman's approximate amplitude (stiction neglected)"})
    ds["den_hartog"] = ("lam", np.asarray(den_hartog_amplitude(p, lam)) * scale,
                        {"long_name": "Den Hartog's exact non-stop amplitude (nan where it does not hold)"})
    ds["lam"].attrs["long_name"] = "frequency ratio omega / w0"
    ds.attrs.update({f"param_{k}": v for k, v in nd.items()})
    ds.attrs.update(periods=s["periods"], obs_periods=s["obs_periods"], steps_per_period=num["steps_per_period"],
                    scheme=num["scheme"])
    ctx.save_dataset(ds, DATASET)

    above = lam >= s["check_above"]
    rel_inman = np.abs(ds.amplitude / ds.inman - 1).values
    rel_dh = np.abs(ds.amplitude / ds.den_hartog - 1).values
    summary = {
        "max_rel_dev_inman_above": float(np.nanmax(rel_inman[above])) if above.any() else float("nan"),
        "max_rel_dev_den_hartog_above": float(np.nanmax(rel_dh[above])) if above.any() else float("nan"),
        "max_rel_dev_inman_below": float(np.nanmax(rel_inman[lam < 1])) if (lam < 1).any() else float("nan"),
    }

    fig, (ax, axr) = plt.subplots(2, 1, figsize=(7.5, 7), sharex=True, gridspec_kw={"height_ratios": [2.2, 1]})
    lam_f = np.linspace(lam.min(), lam.max(), 2000)
    lam_f = lam_f[np.abs(lam_f - 1) > 0.01]
    ax.plot(lam_f, np.asarray(inman_amplitude(p, lam_f)) * scale, color="C1", lw=1.2, label="Inman (approx.)")
    ax.plot(lam_f, np.asarray(den_hartog_amplitude(p, lam_f)) * scale, color="k", lw=0.8, ls="--",
            label="Den Hartog (exact, non-stop)")
    ax.plot(lam, ds.amplitude, "o", ms=3.5, color="C0", label="FMU, from rest")
    ax.set_yscale("log")
    ax.set_ylabel("steady-state amplitude (z_max - z_min) / 2\n(z = k x / P0, static deflections)")
    ax.set_title(f"Fig. 3: mu_s sigma = {nd['mu_s_sigma']}, chi = {nd['chi']}, zeta = {nd['zeta']}; "
                 f"last {s['obs_periods']:g} of {s['periods']:g} periods", fontsize=9)
    ax.grid(alpha=0.3, which="both")
    ax.legend()
    axr.plot(lam, 100 * (ds.amplitude / ds.inman - 1), "o-", ms=3, lw=0.8, color="C1", label="FMU / Inman - 1")
    axr.plot(lam, 100 * (ds.amplitude / ds.den_hartog - 1), "s", ms=3, color="k", label="FMU / Den Hartog - 1")
    axr.axhline(0, color="0.6", lw=0.6)
    axr.set_ylabel("deviation, %")
    axr.set_xlabel("frequency ratio lambda = omega / w0")
    axr.grid(alpha=0.3)
    axr.legend(fontsize=8)
    ctx.save_figure(fig, FIGURES[0])
    ensure(summary["max_rel_dev_den_hartog_above"] < 0.01 or not np.isfinite(summary["max_rel_dev_den_hartog_above"]),
           f"above lambda = {s['check_above']} the FMU is {summary['max_rel_dev_den_hartog_above']:.1e} off Den Hartog")
    ctx.log("fig3: above lambda = {:g}: max deviation from Den Hartog {:.1e}, from Inman {:.1e}; "
            "below resonance from Inman up to {:.1e}".format(s["check_above"], summary["max_rel_dev_den_hartog_above"],
                                                               summary["max_rel_dev_inman_above"],
                                                               summary["max_rel_dev_inman_below"]))
    return summary


def work(cfg: dict[str, Any]) -> Estimate:
    """The study's work and output size (:mod:`dryfriction.budget`): one sweep."""
    est = sweep_estimate(Estimate(), "fig3", lambdas(cfg).size, cfg["sweep"]["periods"], cfg["numerics"])
    return est.add("figures", 0.0, FIGURE_BYTES * len(FIGURES))
