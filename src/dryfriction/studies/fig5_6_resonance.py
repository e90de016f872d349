"""Fig. 5 and 6: unbounded growth at resonance when 4 mu_k N < pi P0, and beating close to it.

Fig. 5 runs at lambda = 1 from rest. With zeta = 0, averaging z'' + z = cos(tau) - f sgn(z')
(f = mu_k N / P0 = chi mu_s sigma) gives the amplitude rate a' = 1/2 - 2 f / pi once the phase has
locked: the growth per period is pi - 4 f, positive exactly when 4 mu_k N < pi P0 (Inman's bound).
The figure draws this envelope and the study compares the FMU's peak growth with it.

Fig. 6 runs just below and above resonance: the free and the forced oscillation beat.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import xarray as xr

from .common import (Estimate, FIGURE_BYTES, StudyContext, check_numerics, check_params, ensure, nondim_trajectory, plt,
                     trajectory_estimate)
from .config import require
from . import REGISTRY

NAME = "fig5_6"
TITLE = REGISTRY[NAME].title
FIGURES = REGISTRY[NAME].figures
DATASET = "fig5_6.nc"


def check(cfg: dict[str, Any]) -> None:
    """Refuse a configuration of the Fig. 5/6 study with a value out of range (ConfigError naming the key),
    before any work."""
    check_params(cfg["params"])
    check_numerics(cfg["numerics"])
    res, beat = cfg["resonance"], cfg["beating"]
    check_params({"lam": res["lam"]}, "resonance")
    require(res["periods"] > 0 and beat["periods"] > 0, "resonance.periods and beating.periods must be > 0")
    require(len(beat["lam"]) >= 1, "beating.lam needs at least one frequency ratio")
    for i, lam in enumerate(beat["lam"]):
        require(lam > 0, f"beating.lam[{i}] must be > 0, not {lam}")
    require(cfg["run"]["samples_per_period"] >= 10, "run.samples_per_period must be >= 10")


def _peak_growth(cycles: np.ndarray, z: np.ndarray) -> float:
    """Growth of max |z| per period, fitted over the second half of the run."""
    n = int(math.floor(cycles[-1]))
    peaks, centres = [], []
    for k in range(n // 2, n):
        sel = (cycles >= k) & (cycles < k + 1)
        if sel.any():
            peaks.append(np.max(np.abs(z[sel])))
            centres.append(k + 0.5)
    if len(peaks) < 2:
        return float("nan")
    return float(np.polyfit(centres, peaks, 1)[0])


def run(ctx: StudyContext) -> dict[str, float]:
    """Run the Fig. 5/6 study: its runs, dataset and figures in the study's folder; returns the summary."""
    cfg = ctx.cfg
    nd, res, beat, num = cfg["params"], cfg["resonance"], cfg["beating"], cfg["numerics"]
    spp = cfg["run"]["samples_per_period"]
    f = nd["chi"] * nd["mu_s_sigma"]
    unbounded = 4 * f < math.pi
    theory = math.pi - 4 * f if nd["zeta"] == 0 and res["lam"] == 1.0 else float("nan")

    tr5 = nondim_trajectory(ctx.fmu(), {**nd, "lam": res["lam"]}, 0.0, res["periods"], spp, num)
    growth = _peak_growth(tr5["cycles"], tr5["z"])
    trs6 = [nondim_trajectory(ctx.fmu(), {**nd, "lam": lam}, 0.0, beat["periods"], spp, num) for lam in beat["lam"]]

    attrs = {**{f"param_{k}": v for k, v in nd.items()}, "steps_per_period": num["steps_per_period"],
             "growth_per_period": growth, "growth_per_period_theory": theory,
             "four_mu_k_N_over_pi_P0": 4 * f / math.pi}
    ds = xr.Dataset(
        {
            "z_resonance": ("cycles_resonance", tr5["z"], {"long_name": f"z at lambda = {res['lam']}"}),
            "dz_resonance": ("cycles_resonance", tr5["dz"], {"long_name": "z' at resonance"}),
            "z_beating": (("lam_beating", "cycles_beating"), np.stack([t["z"] for t in trs6]),
                          {"long_name": "z near resonance"}),
            "dz_beating": (("lam_beating", "cycles_beating"), np.stack([t["dz"] for t in trs6]),
                           {"long_name": "z' near resonance"}),
        },
        coords={"cycles_resonance": tr5["cycles"], "cycles_beating": trs6[0]["cycles"],
                "lam_beating": np.asarray(beat["lam"], dtype=float)},
        attrs=attrs,
    )
    ctx.save_dataset(ds, DATASET)

    fig, ax = plt.subplots(figsize=(8, 4.2))
    ax.plot(tr5["cycles"], tr5["z"], color="C0", lw=0.8, label="FMU")
    if np.isfinite(theory):
        c = tr5["cycles"]
        env = theory * c
        ax.plot(c, env, color="C3", lw=1, ls="--", label=f"envelope (pi - 4 f) t/T, f = {f:g}")
        ax.plot(c, -env, color="C3", lw=1, ls="--")
    ax.set_xlabel("t / T")
    ax.set_ylabel("z")
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", fontsize=8)
    ax.set_title(f"Fig. 5: resonance lambda = {res['lam']}, mu_s sigma = {nd['mu_s_sigma']}, chi = {nd['chi']}: "
                 f"4 mu_k N / (pi P0) = {4 * f / math.pi:.2f}; growth {growth:.3f} per period"
                 + (f" (theory {theory:.3f})" if np.isfinite(theory) else ""), fontsize=9)
    ctx.save_figure(fig, FIGURES[0])

    fig, axs = plt.subplots(len(trs6), 1, figsize=(8, 2.6 * len(trs6)), sharex=True, squeeze=False)
    for ax, lam, t in zip(axs[:, 0], beat["lam"], trs6):
        ax.plot(t["cycles"], t["z"], color="C0", lw=0.7)
        ax.set_ylabel("z")
        ax.grid(alpha=0.3)
        beat_T = lam / abs(1 - lam) if lam != 1 else float("inf")
        ax.set_title(f"lambda = {lam}: beat period lambda / |1 - lambda| = {beat_T:.1f} T", fontsize=9)
    axs[-1, 0].set_xlabel("t / T")
    fig.suptitle(f"Fig. 6: beating near resonance, mu_s sigma = {nd['mu_s_sigma']}, chi = {nd['chi']}", fontsize=10)
    ctx.save_figure(fig, FIGURES[1])

    if np.isfinite(theory):
        ensure(abs(growth / theory - 1) < 0.05 if unbounded else growth < 0.05,
               f"resonant growth {growth:.3f} per period, theory {theory:.3f}")
    kind = "unbounded" if unbounded else "bounded"
    ctx.log(f"fig5_6: 4 mu_k N / (pi P0) = {4 * f / math.pi:.3f} ({kind} resonance); "
            f"growth of max |z| {growth:.4f} per period, averaging theory {theory:.4f}")
    return {"growth_per_period": growth, "growth_theory": theory}


def work(cfg: dict[str, Any]) -> Estimate:
    """The study's work and output size (:mod:`dryfriction.budget`): the resonant trajectory and
    one per beating frequency."""
    res, beat, num, spp = cfg["resonance"], cfg["beating"], cfg["numerics"], cfg["run"]["samples_per_period"]
    est = trajectory_estimate(Estimate(), "fig5 trajectory", 1, res["periods"], num, spp)
    trajectory_estimate(est, "fig6 trajectories", len(beat["lam"]), beat["periods"], num, spp)
    return est.add("figures", 0.0, FIGURE_BYTES * len(FIGURES))
