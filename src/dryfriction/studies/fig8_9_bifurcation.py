"""Fig. 8 and 9: mean amplitude and asymmetry after 30 periods against chi = mu_k / mu_s, over a
grid of initial conditions: the bifurcation from symmetric periodic to asymmetric motion, and the
band below chi ~ 0.25 (chaos below chi = 0.194, transient chaos and period-2 motions above; docs/chaos.md).

For every chi, every initial condition (z0, z0') of the grid is run for ``sweep.periods`` periods;
the FMU takes z_max and z_min over the last ``sweep.obs_periods`` period(s). Mean amplitude
(z_max - z_min) / 2 and asymmetry (z_max + z_min) / 2 (method.md section 6). Where the motion is
periodic and symmetric, all initial conditions give one amplitude and zero asymmetry; past the
bifurcation the asymmetry splits into a mirror pair; where the 30-period snapshots differ (chaos,
transient chaos, coexisting higher-period motions) both spread over a band.
"""

from __future__ import annotations

from typing import Any

Z = "z = k x / P0, in static deflections"

import numpy as np
import xarray as xr

from ..sweep import SweepSpec, observables_dataset
from .common import (Estimate, FIGURE_BYTES, StudyContext, check_numerics, check_params, check_window, plt,
                     sweep_estimate, sweep_settings, table)
from .config import grid, require
from . import REGISTRY

NAME = "fig8_9"
TITLE = REGISTRY[NAME].title
FIGURES = REGISTRY[NAME].figures
DATASET = "fig8_9.nc"


def axes(cfg: dict[str, Any]) -> dict[str, np.ndarray]:
    """The sweep's axes: chi and the grid of initial conditions (z0, dz0)."""
    s = cfg["sweep"]
    return {"chi": grid(s["chi"], "sweep.chi"), "z0": grid(s["z0"], "sweep.z0"), "dz0": grid(s["dz0"], "sweep.dz0")}


def check(cfg: dict[str, Any]) -> None:
    """Refuse a configuration of the Fig. 8/9 study with a value out of range (ConfigError naming the key),
    before any work."""
    check_params(cfg["params"])
    check_numerics(cfg["numerics"])
    s = cfg["sweep"]
    check_window(s["periods"], s["obs_periods"], "sweep")
    require(s["chi"]["start"] >= 0 and s["chi"]["stop"] >= 0, "sweep.chi must stay >= 0")
    axes(cfg)


def spec(cfg: dict[str, Any]) -> tuple[SweepSpec, dict[str, np.ndarray]]:
    """The sweep of the study (one run per chi and initial condition) and its axes."""
    nd, s, num = cfg["params"], cfg["sweep"], cfg["numerics"]
    ax = axes(cfg)
    C, Z, D = np.meshgrid(ax["chi"], ax["z0"], ax["dz0"], indexing="ij")
    vals = {**nd, "chi": C, "z0": Z, "dz0": D}
    P = table(vals, s["periods"], s["periods"] - s["obs_periods"], s["periods"], num)
    return SweepSpec("fig8_9", P, sweep_settings(num), num["chunk_runs"]), ax


def classify(ds: xr.Dataset, tol: float = 1e-3) -> xr.Dataset:
    """Per chi: spread of the amplitude and of the asymmetry over the initial conditions, and the
    largest |asymmetry|, all relative to the median amplitude."""
    a = ds.amplitude.stack(ic=("z0", "dz0"))
    s = ds.asymmetry.stack(ic=("z0", "dz0"))
    ref = a.median("ic")
    out = xr.Dataset({
        "amplitude_spread": (a.max("ic") - a.min("ic")) / ref,
        "asymmetry_max": abs(s).max("ic") / ref,
    })
    out["symmetric_periodic"] = (out.amplitude_spread < tol) & (out.asymmetry_max < tol)
    return out


def symmetric_range(chi: np.ndarray, sym: np.ndarray) -> tuple[float, float]:
    """The longest run of consecutive chi with symmetric periodic motion: (first, last) chi, nan
    if none. Its lower end is the bifurcation. (Where the breakaway limit nears the excitation,
    chi mu_s sigma -> 1, the block hardly moves and 30 periods do not end the transient.)"""
    best, start = (0, -1, -1), None
    for i, ok in enumerate(list(sym) + [False]):
        if ok and start is None:
            start = i
        elif not ok and start is not None:
            if i - start > best[0]:
                best = (i - start, start, i - 1)
            start = None
    if best[0] == 0:
        return float("nan"), float("nan")
    return float(chi[best[1]]), float(chi[best[2]])


def run(ctx: StudyContext) -> dict[str, float]:
    """Run the Fig. 8/9 study: its runs, dataset and figures in the study's folder; returns the summary."""
    cfg = ctx.cfg
    nd, s, num = cfg["params"], cfg["sweep"], cfg["numerics"]
    sp, ax = spec(cfg)
    out = ctx.run_sweep(sp)
    ds = observables_dataset(out, ax)
    ds["chi"].attrs["long_name"] = "chi = mu_k / mu_s"
    ds["z0"].attrs["long_name"] = "initial z = k x0 / P0"
    ds["dz0"].attrs["long_name"] = "initial z' = dz/dtau"
    ds.attrs.update({f"param_{k}": v for k, v in nd.items()})
    ds.attrs.update(periods=s["periods"], obs_periods=s["obs_periods"], steps_per_period=num["steps_per_period"],
                    scheme=num["scheme"], runs=sp.n_runs)
    cls = classify(ds)
    for name in cls.data_vars:
        ds[name] = cls[name]
    ds["symmetric_periodic"] = ds.symmetric_periodic.astype(bool)
    ds.amplitude_spread.attrs["long_name"] = "(max - min) of the amplitude over the initial conditions / median"
    ds.asymmetry_max.attrs["long_name"] = "max |asymmetry| over the initial conditions / median amplitude"
    ds.symmetric_periodic.attrs["long_name"] = "True: one amplitude and zero asymmetry for all initial conditions (1e-3)"
    ctx.save_dataset(ds, DATASET)

    chi = ax["chi"]
    lo, hi = symmetric_range(chi, cls.symmetric_periodic.values)
    n_ic = ax["z0"].size * ax["dz0"].size
    xs = np.repeat(chi, n_ic)
    for fig_name, var, label in ((FIGURES[0], "amplitude", f"mean amplitude (z_max - z_min) / 2  ({Z})"),
                                 (FIGURES[1], "asymmetry", f"asymmetry (z_max + z_min) / 2  ({Z})")):
        fig, axp = plt.subplots(figsize=(8, 5))
        # markers that stay visible at quick sizes (few points) and do not blot the full study
        size = 0.6 if xs.size > 20000 else 6.0
        axp.scatter(xs, ds[var].values.reshape(-1), s=size, c="k", alpha=0.35 if xs.size > 20000 else 0.6, lw=0,
                    rasterized=True, label="one initial condition (z0, z0') after the run")
        if np.isfinite(lo):
            axp.axvspan(lo, hi, color="C2", alpha=0.08, lw=0,
                        label=f"symmetric periodic (1e-3): {lo:.3g} <= chi <= {hi:.3g}")
            axp.axvline(lo, color="C3", lw=0.8, ls="--")
            # a fixed place: "best" would test every one of the (up to 269k) points, some 6 s per figure
        axp.legend(loc="upper right", fontsize=8, markerscale=3)
        axp.set_xlabel("chi = mu_k / mu_s")
        axp.set_ylabel(label)
        axp.grid(alpha=0.3)
        axp.set_title(f"Fig. {fig_name[3]}: lambda = omega/w0 = {nd['lam']}, mu_s sigma = mu_s N/P0 = {nd['mu_s_sigma']}, "
                      f"zeta = {nd['zeta']}; "
                      f"{ax['z0'].size} x {ax['dz0'].size} initial conditions x {chi.size} chi = {sp.n_runs:,} runs; "
                      f"after {s['periods']:g} T", fontsize=8.5)
        ctx.save_figure(fig, fig_name)
    ctx.log(f"fig8_9: symmetric periodic motion (1e-3) for {lo:.4g} <= chi <= {hi:.4g}; "
            f"largest amplitude spread {float(cls.amplitude_spread.max()):.3f} at chi = "
            f"{float(chi[int(np.argmax(cls.amplitude_spread.values))]):.3g}")
    return {"chi_bifurcation": lo, "chi_symmetric_max": hi, "runs": float(sp.n_runs)}


def runs(cfg: dict[str, Any]) -> int:
    """The sweep's runs: chi x z0 x dz0, from the sizes alone."""
    s = cfg["sweep"]
    return int(s["chi"]["num"]) * int(s["z0"]["num"]) * int(s["dz0"]["num"])


def work(cfg: dict[str, Any]) -> Estimate:
    """The study's work and output size (:mod:`dryfriction.budget`): one sweep."""
    est = sweep_estimate(Estimate(), "fig8_9", runs(cfg), cfg["sweep"]["periods"], cfg["numerics"])
    return est.add("figures", 0.0, FIGURE_BYTES * len(FIGURES))
