"""The Fig. 8/9 band solved: branches of periodic orbits in chi (stable solid, unstable dashed) over
the brute-force scatter of fig8_9, with the symmetry breaking, the period doubling, the grazings
and any fold located by the continuation (dryfriction.analysis.continuation) and set against the brute-force
numbers.

The scatter is the fig8_9 study's own sweep (its config, its chunks when it has run). The
brute-force brackets, at the sweep's resolution (one step of its chi grid), come from longer runs at
the scatter's values of chi, since 30-period snapshots resolve neither point:

- symmetry breaking: ``brute_force.long_periods`` periods from five initial conditions of the
  scatter's grid (its corners and centre), at every chi of the continuation's range; the lowest chi
  of their symmetric range and the grid value below it. Next to the pitchfork the asymmetry decays
  slowly (a multiplier near 1): the 30-period snapshot still shows it at chi = 0.56 and 0.58 (its
  own bracket, [0.58, 0.60] at full size, is written beside).
- period doubling: ``brute_force.doubling_periods`` periods from two corners of the grid, at the
  grid values within ``brute_force.doubling_steps`` steps of the located point; period 1 where the
  extremes over the last two periods agree (1e-6 of the amplitude); the bracket is the highest
  value that is not of period 1 and the one above it (next to the doubling the flip multiplier is
  near -1: at chi = 0.24, -0.989, whose wobble decays by 1e-10 in 2000 periods). The finer
  ``brute_force.reference_period_doubling`` (docs/chaos.md: from (0, 0), 20,000 periods, period 2
  at chi = 0.236, period 1 at 0.237) is written and checked beside it.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..budget import continuation_work
from ..analysis.plots import plot_branches
from ..sweep import SweepSpec, observables_dataset
from . import fig8_9_bifurcation as base
from .branches import Z_SCALE, bifurcation_rows, check_continuation, collect, continue_nd, shared_sweep, \
    write_bifurcations
from .common import FIGURE_BYTES, Estimate, StudyContext, plt, sweep_estimate, sweep_settings, table
from .config import require
from . import REGISTRY

NAME = "fig8_9_orbits"
BASE_CONFIG = "fig8_9"
TITLE = REGISTRY[NAME].title
FIGURES = REGISTRY[NAME].figures
DATASETS = ("fig8_9.nc", "branches.nc")


def check(cfg: dict[str, Any]) -> None:
    """Refuse a configuration of the Fig. 8/9 orbits study with a value out of range (ConfigError naming the
    key), before any work."""
    base.check(cfg)
    c = cfg["continuation"]
    check_continuation(c)
    require(c["start"] != c["stop"], "continuation.start and continuation.stop must differ")
    require(c["start"] > 0 and c["stop"] > 0, "continuation.start and continuation.stop (chi) must be > 0")
    bf = cfg["brute_force"]
    pd = bf["reference_period_doubling"]
    require(len(pd) == 2 and pd[0] <= pd[1],
            f"brute_force.reference_period_doubling must be [lo, hi], lo <= hi, not {pd}")
    for key in ("long_periods", "doubling_periods"):
        require(bf[key] >= 2, f"brute_force.{key} must be >= 2, not {bf[key]}")
    require(bf["doubling_steps"] >= 1, f"brute_force.doubling_steps must be >= 1, not {bf['doubling_steps']}")


def sb_bracket(chi: np.ndarray, sym: np.ndarray) -> tuple[float, float]:
    """The symmetry breaking as the scatter brackets it: (the grid value below the symmetric
    periodic range, its lowest value); NaN where the scatter has no such range or nothing below it."""
    lo, _ = base.symmetric_range(chi, sym)
    if not math.isfinite(lo):
        return math.nan, math.nan
    i = int(np.argmin(np.abs(chi - lo)))
    below = chi[chi < lo]
    return (float(below.max()) if below.size else math.nan), float(chi[i])


def long_runs(ctx: StudyContext, chi: np.ndarray, ax: dict[str, np.ndarray]) -> Any:
    """The scatter's attractors after ``brute_force.long_periods`` periods from five initial
    conditions (the corners and the centre of the scatter's grid), at the values ``chi``."""
    cfg = ctx.cfg
    nd, num, n = cfg["params"], cfg["numerics"], float(cfg["brute_force"]["long_periods"])
    z, d = ax["z0"], ax["dz0"]
    ics = [(z[0], d[0]), (z[0], d[-1]), (z[-1], d[0]), (z[-1], d[-1]), (0.5 * (z[0] + z[-1]), 0.5 * (d[0] + d[-1]))]
    C = np.repeat(chi, len(ics))
    Z = np.tile([a for a, _ in ics], chi.size)
    D = np.tile([b for _, b in ics], chi.size)
    P = table({**nd, "chi": C, "z0": Z, "dz0": D}, n, n - 1.0, n, num)
    out = ctx.run_sweep(SweepSpec("fig8_9_long", P, sweep_settings(num), num["chunk_runs"]))
    return observables_dataset(out, {"chi": chi, "ic": np.arange(len(ics))})


def doubling_runs(ctx: StudyContext, chi: np.ndarray, ax: dict[str, np.ndarray]) -> Any:
    """Runs of ``brute_force.doubling_periods`` periods from two corners of the scatter's grid at
    the values ``chi``, observed over each of the last two periods: ``period_1`` per chi where every
    run's extremes agree over the two (1e-6 of its amplitude)."""
    cfg = ctx.cfg
    nd, num, n = cfg["params"], cfg["numerics"], float(cfg["brute_force"]["doubling_periods"])
    z, d = ax["z0"], ax["dz0"]
    C = np.repeat(chi, 2)
    Z = np.tile([z[0], z[-1]], chi.size)
    D = np.tile([d[0], d[-1]], chi.size)
    vals = {**nd, "chi": C, "z0": Z, "dz0": D}
    win = []
    for k in (2.0, 1.0):
        P = table(vals, n, n - k, n - k + 1.0, num)
        out = ctx.run_sweep(SweepSpec(f"fig8_9_doubling_{int(k)}", P, sweep_settings(num), num["chunk_runs"]))
        win.append(observables_dataset(out, {"chi": chi, "ic": np.arange(2)}))
    a, b = win
    gap = np.maximum(abs(a.z_max - b.z_max), abs(a.z_min - b.z_min)) / b.amplitude
    ds = b.copy()
    ds["split"] = gap
    ds.split.attrs["long_name"] = "max |change of z_max, z_min| from the last period but one to the last / amplitude"
    ds["period_1"] = (gap.max("ic") <= 1e-6).astype(bool)
    ds.attrs.update(periods=n)
    return ds


def pd_bracket(chi: np.ndarray, period_1: np.ndarray) -> tuple[float, float]:
    """(the highest chi not of period 1, the grid value above it), all above of period 1; NaN if
    there is no such pair."""
    bad = np.where(~period_1)[0]
    if bad.size == 0 or bad[-1] == chi.size - 1:
        return math.nan, math.nan
    i = int(bad[-1])
    return float(chi[i]), float(chi[i + 1])


def symmetric_after(ds: Any, tol: float = 1e-3) -> np.ndarray:
    """Per chi: every run on one symmetric motion (amplitude spread and |asymmetry| below ``tol`` of
    the median amplitude), as fig8_9's classification."""
    a, s = ds.amplitude.values, ds.asymmetry.values
    med = np.median(a, axis=1)
    return ((a.max(1) - a.min(1)) / med < tol) & (np.abs(s).max(1) / med < tol)


def run(ctx: StudyContext) -> dict[str, Any]:
    """Run the Fig. 8/9 orbits study: its runs, dataset and figures in the study's folder; returns the
    summary."""
    cfg = ctx.cfg
    nd, s, c = cfg["params"], cfg["sweep"], cfg["continuation"]
    sp, ax = base.spec(cfg)
    out = shared_sweep(ctx, BASE_CONFIG).run_sweep(sp)
    sc = observables_dataset(out, ax)
    cls = base.classify(sc)
    for name in cls.data_vars:
        sc[name] = cls[name]
    sc["symmetric_periodic"] = sc.symmetric_periodic.astype(bool)
    sc.attrs.update({f"param_{k}": v for k, v in nd.items()})
    sc.attrs.update(periods=s["periods"], obs_periods=s["obs_periods"], runs=sp.n_runs)
    ctx.save_dataset(sc, DATASETS[0])

    chi = ax["chi"]
    lo_c, hi_c = min(c["start"], c["stop"]), max(c["start"], c["stop"])
    chi_long = chi[(chi >= lo_c) & (chi <= hi_c)]
    snapshot = sb_bracket(chi, cls.symmetric_periodic.values)
    brute: dict[str, tuple[float, float]] = {"symmetry_breaking": (math.nan, math.nan),
                                             "period_doubling": (math.nan, math.nan)}
    ref_lo, ref_hi = (float(v) for v in cfg["brute_force"]["reference_period_doubling"])
    if chi_long.size:
        lr = long_runs(ctx, chi_long, ax)
        lr["symmetric_periodic"] = ("chi", symmetric_after(lr).astype(bool))
        lr.attrs.update(periods=float(cfg["brute_force"]["long_periods"]))
        ctx.save_dataset(lr, "long_runs.nc")
        brute["symmetry_breaking"] = sb_bracket(chi_long, lr.symmetric_periodic.values)
    cont = continue_nd(ctx, {**nd}, "chi", c["start"], c["stop"], c)
    pds = [b.param for b in cont.bifurcations if b.type == "period_doubling"]
    if pds and chi_long.size > 1:
        step = float(np.diff(chi).max())
        reach = (cfg["brute_force"]["doubling_steps"] + 0.5) * step
        near = chi_long[(chi_long >= min(pds) - reach) & (chi_long <= max(pds) + reach)]
        if near.size > 1:
            dr = doubling_runs(ctx, near, ax)
            ctx.save_dataset(dr, "doubling_runs.nc")
            brute["period_doubling"] = pd_bracket(near, dr.period_1.values)
    ds = collect([({}, cont)])
    ds.attrs.update({f"param_{k}": v for k, v in nd.items() if k != "chi"})
    ctx.save_dataset(ds, DATASETS[1])
    rows = bifurcation_rows(cont, {}, brute)
    for r in rows:
        pd_row = r["type"] == "period_doubling"
        r["reference_lo"], r["reference_hi"] = (ref_lo, ref_hi) if pd_row else (math.nan, math.nan)
        r["within_reference"] = bool(ref_lo <= r["param_value"] <= ref_hi) if pd_row else ""
    extra = {"brute_force": {k: list(v) for k, v in brute.items()},
             "snapshot_symmetry_breaking": list(snapshot),
             "brute_force_source": {"symmetry_breaking": f"{cfg['brute_force']['long_periods']:g}-period runs from 5 "
                                                         f"initial conditions at the scatter's {chi_long.size} values "
                                                         f"of chi in [{lo_c:g}, {hi_c:g}]",
                                    "snapshot_symmetry_breaking": f"fig8_9 scatter after {s['periods']:g} periods, "
                                                                  f"{chi.size} values of chi",
                                    "period_doubling": f"{cfg['brute_force']['doubling_periods']:g}-period runs "
                                                       "from 2 initial conditions at the scatter's chi next to the "
                                                       "located point",
                                    "reference_period_doubling": "brute_force.reference_period_doubling "
                                                                 "(docs/chaos.md: 20,000 periods)"},
             "reference_period_doubling": [ref_lo, ref_hi],
             "branches": [b.as_dict() for b in cont.branches], "evaluations": cont.evaluations}
    write_bifurcations(ctx, rows, "bifurcations", extra)

    fig, axes = plt.subplots(2, 1, figsize=(8, 7.5), sharex=True)
    n_ic = ax["z0"].size * ax["dz0"].size
    xs = np.repeat(chi, n_ic)
    big = xs.size > 20000
    for a, var in zip(axes, ("amplitude", "asymmetry")):
        a.scatter(xs, sc[var].values.reshape(-1), s=0.6 if big else 6.0, c="0.55", alpha=0.35 if big else 0.6, lw=0,
                  rasterized=True, label=f"brute force: {ax['z0'].size} x {ax['dz0'].size} initial conditions "
                                         f"after {s['periods']:g} T")
        for kind, color in (("symmetry_breaking", "C3"), ("period_doubling", "C4")):
            lo, hi = brute[kind]
            if math.isfinite(lo):
                a.axvspan(lo, hi, color=color, alpha=0.12, lw=0,
                          label=(f"brute-force bracket, {kind.replace('_', ' ')}: [{lo:.4g}, {hi:.4g}]"
                                 if var == "amplitude" else None))
    plot_branches(axes, cont, Z_SCALE)
    axes[0].set_ylabel("mean amplitude (z_max - z_min) / 2")
    axes[1].set_ylabel("asymmetry (z_max + z_min) / 2")
    axes[1].set_xlabel("chi = mu_k / mu_s")
    # the continuation's range, and the scatter's chaotic band below it
    x0, x1 = max(float(chi.min()), lo_c - 0.2) - 0.01, min(float(chi.max()), hi_c + 0.1) + 0.01
    axes[1].set_xlim(x0, x1)
    seen = sc.amplitude.values[(chi >= x0) & (chi <= x1)]
    if seen.size and np.isfinite(seen).any():
        a0, a1 = float(np.nanmin(seen)), float(np.nanmax(seen))
        axes[0].set_ylim(a0 - 0.05 * (a1 - a0), a1 + 0.05 * (a1 - a0))
    fig.legend(*axes[0].get_legend_handles_labels(), fontsize=6.5, loc="lower center", ncol=3, markerscale=2)
    for a in axes:
        a.grid(alpha=0.3)
    axes[0].set_title(f"Fig. 8/9 band: lambda = {nd['lam']}, mu_s sigma = {nd['mu_s_sigma']}, zeta = {nd['zeta']} "
                      f"(z = k x / P0); branches of periodic orbits, chi {c['start']:g} -> {c['stop']:g}\n"
                      "solid: stable, dashed: unstable; F fold, PD period doubling, SB symmetry breaking, "
                      "G grazing", fontsize=8)
    fig.tight_layout(rect=(0.0, 0.08, 1.0, 1.0))
    ctx.save_figure(fig, FIGURES[0])

    ctx.log(f"fig8_9_orbits: symmetry breaking bracketed by the {s['periods']:g}-period snapshot: "
            f"[{snapshot[0]:.4g}, {snapshot[1]:.4g}]; by the {cfg['brute_force']['long_periods']:g}-period runs: "
            f"[{brute['symmetry_breaking'][0]:.4g}, {brute['symmetry_breaking'][1]:.4g}]")
    summary: dict[str, Any] = {"runs": float(sp.n_runs), "snapshot_symmetry_breaking": list(snapshot),
                               "branch_points": int(ds.point.size) if ds else 0,
                               "evaluations": cont.evaluations}
    for kind in ("symmetry_breaking", "period_doubling"):
        found = [r["param_value"] for r in rows if r["type"] == kind]
        lo, hi = brute[kind]
        summary[f"chi_{kind}"] = found
        summary[f"brute_force_{kind}"] = [lo, hi]
        summary[f"{kind}_within_brute_force"] = bool(found) and all(lo <= v <= hi for v in found)
    summary["reference_period_doubling"] = [ref_lo, ref_hi]
    summary["period_doubling_within_reference"] = bool(summary["chi_period_doubling"]) and all(
        ref_lo <= v <= ref_hi for v in summary["chi_period_doubling"])
    for r in rows:
        bf = (f"; brute force [{r['brute_force_lo']:.4g}, {r['brute_force_hi']:.4g}]: "
              f"{'within' if r['within_brute_force'] else 'OUTSIDE'}") if r["within_brute_force"] != "" else ""
        if r["within_reference"] != "":
            bf += (f"; reference [{r['reference_lo']:.4g}, {r['reference_hi']:.4g}]: "
                   f"{'within' if r['within_reference'] else 'OUTSIDE'}")
        ctx.log(f"fig8_9_orbits: {r['type']} at chi = {r['param_value']:.10f} (branch {r['branch']}, period "
                f"{r['period']}, amplitude z {r['amplitude_z']:.5f}, asymmetry {r['offset_z']:+.5f}){bf}")
    for b in cont.branches:
        ctx.log(f"fig8_9_orbits: branch {b.id} (period {b.period}, {b.kind}, {b.points} points): {b.stopped}")
    return summary


def work(cfg: dict[str, Any]) -> Estimate:
    """The study's work and output size (:mod:`dryfriction.budget`): fig8_9's sweep, the long runs
    (5 per chi of the continuation's range), the doubling runs (at most 2 sweeps of 2 per such chi)
    and the continuation (every point of ``max_branches`` branches)."""
    c, bf, num = cfg["continuation"], cfg["brute_force"], cfg["numerics"]
    est = sweep_estimate(Estimate(), "fig8_9", base.runs(cfg), cfg["sweep"]["periods"], num)
    chi = base.axes(cfg)["chi"]
    n_long = int(np.sum((chi >= min(c["start"], c["stop"])) & (chi <= max(c["start"], c["stop"]))))
    if n_long:
        sweep_estimate(est, "fig8_9_long", 5 * n_long, bf["long_periods"], num)
    if n_long > 1:
        sweep_estimate(est, "fig8_9_doubling (at most)", 2 * 2 * n_long, bf["doubling_periods"], num)
    steps, what = continuation_work(c["max_points"], c["max_branches"])
    est.add(f"continuation: {what}", steps, 400.0 * c["max_points"] * c["max_branches"])
    return est.add("figures", 0.0, FIGURE_BYTES * len(FIGURES))
