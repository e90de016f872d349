"""Fig. 2: the FMU against the exact piecewise solution over the first excitation cycle.

z, z' and z'' of the FMU (Bossak-Newmark + LCP, sampled at the communication points) and of the
exact stitching solution (``dryfriction.references.exact``) at the same times, from rest, over one cycle of
forward slip, stick and backward slip. The dataset keeps both and the errors.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

from ..references.exact import solve_exact
from .common import (Estimate, FIGURE_BYTES, StudyContext, check_numerics, check_params, ensure, nondim_trajectory,
                     oscillator, plt, trajectory_estimate)
from .config import require
from . import REGISTRY

NAME = "fig2"
TITLE = REGISTRY[NAME].title
FIGURES = REGISTRY[NAME].figures
DATASET = "fig2.nc"


def check(cfg: dict[str, Any]) -> None:
    """Refuse a configuration of the Fig. 2 study with a value out of range (ConfigError naming the key),
    before any work."""
    check_params(cfg["params"])
    check_numerics(cfg["numerics"])
    require(cfg["params"]["zeta"] < 1, f"params.zeta must be < 1 for the exact solution, not {cfg['params']['zeta']}")
    r = cfg["run"]
    require(r["periods"] > 0, f"run.periods must be > 0, not {r['periods']}")
    require(r["samples_per_period"] >= 10, f"run.samples_per_period must be >= 10, not {r['samples_per_period']}")


def run(ctx: StudyContext) -> dict[str, float]:
    """Run the Fig. 2 study: its runs, dataset and figures in the study's folder; returns the summary."""
    cfg = ctx.cfg
    nd, num, r = cfg["params"], cfg["numerics"], cfg["run"]
    p = oscillator(nd)
    tr = nondim_trajectory(ctx.fmu(), nd, 0.0, r["periods"], r["samples_per_period"], num)
    t = tr["tau"] / p.w0
    ex = solve_exact(p, float(t[-1]))
    x, v, a, mode = ex.evaluate(t)
    scale = p.k / p.P0
    z_ex, dz_ex, ddz_ex = x * scale, v * scale / p.w0, a * scale / p.w0**2
    amp = float(np.max(np.abs(z_ex)))
    err = {
        "z": float(np.max(np.abs(tr["z"] - z_ex))),
        "dz": float(np.max(np.abs(tr["dz"] - dz_ex))),
        "ddz": float(np.max(np.abs(tr["ddz"] - ddz_ex))),
    }
    summary = {
        "max_abs_z": amp,
        "err_z": err["z"],
        "err_dz": err["dz"],
        "err_ddz": err["ddz"],
        "rel_err_z": err["z"] / amp,
        "rel_err_dz": err["dz"] / float(np.max(np.abs(dz_ex))),
        "mode_mismatches": int(np.sum(tr["mode"] != mode)),
    }
    ds = xr.Dataset(
        {
            "z": ("cycles", tr["z"], {"long_name": "z = k x / P0 (FMU)"}),
            "dz": ("cycles", tr["dz"], {"long_name": "z' = dz/dtau (FMU)"}),
            "ddz": ("cycles", tr["ddz"], {"long_name": "z'' (FMU)"}),
            "mode": ("cycles", tr["mode"], {"long_name": "-1 backward slip, 0 stuck, +1 forward slip (FMU)"}),
            "z_exact": ("cycles", z_ex, {"long_name": "z, exact piecewise solution"}),
            "dz_exact": ("cycles", dz_ex, {"long_name": "z', exact"}),
            "ddz_exact": ("cycles", ddz_ex, {"long_name": "z'', exact"}),
            "mode_exact": ("cycles", mode.astype(np.int8), {"long_name": "mode, exact"}),
        },
        coords={"cycles": ("cycles", tr["cycles"], {"long_name": "t / T"}),
                "tau": ("cycles", tr["tau"], {"long_name": "tau = w0 t"})},
        attrs={**{f"param_{k}": v for k, v in nd.items()}, "steps_per_period": num["steps_per_period"],
               "scheme": num["scheme"], "alpha": num["alpha"], **summary,
               "switch_times_over_T": ex.switch_times() / p.period},
    )
    ctx.save_dataset(ds, DATASET)

    fig, axs = plt.subplots(3, 1, figsize=(7.5, 7.5), sharex=True)
    c = tr["cycles"]
    for ax, key, label in zip(axs, ("z", "dz", "ddz"), ("z", "z'", "z''")):
        ax.plot(c, ds[f"{key}_exact"], color="0.6", lw=3.5, label="exact")
        ax.plot(c, ds[key], color="C0", lw=1.1, label="FMU")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
        for ts in ex.switch_times() / p.period:
            if ts <= c[-1]:
                ax.axvline(ts, color="C3", lw=0.6, ls=":")
    axs[0].legend(loc="best")
    axs[0].set_title(f"Fig. 2: FMU vs exact, lam = {nd['lam']}, mu_s sigma = {nd['mu_s_sigma']}, "
                     f"chi = {nd['chi']}, h = T/{num['steps_per_period']}\n"
                     f"max |z - z_exact| = {err['z']:.1e} ({err['z'] / amp:.1e} of max |z|)", fontsize=9)
    axs[-1].set_xlabel("t / T")
    ctx.save_figure(fig, FIGURES[0])
    ensure(summary["rel_err_z"] < 1e-3, f"the FMU is off the exact solution by {summary['rel_err_z']:.1e} of max |z|")
    ctx.log(f"fig2: max |z - z_exact| = {err['z']:.2e} ({summary['rel_err_z']:.1e} of max |z| = {amp:.3f}), "
            f"max |z' - z'_exact| = {err['dz']:.2e}, modes differ at {summary['mode_mismatches']} of {c.size} points")
    return summary


def work(cfg: dict[str, Any]) -> Estimate:
    """The study's work and output size (:mod:`dryfriction.budget`): one trajectory."""
    r = cfg["run"]
    est = trajectory_estimate(Estimate(), "fig2 trajectory", 1, r["periods"], cfg["numerics"], r["samples_per_period"])
    return est.add("figures", 0.0, FIGURE_BYTES * len(FIGURES))
