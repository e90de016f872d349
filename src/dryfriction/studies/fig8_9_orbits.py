"""The Fig. 8/9 band solved: branches of periodic orbits in chi (stable solid, unstable dashed) over
the brute-force scatter of fig8_9, with the symmetry breaking, the period doubling, the grazings
and any fold located by the continuation (dryfriction.continuation) and set against the brute-force
numbers.

The scatter is the fig8_9 study's own sweep (its config, its chunks when it has run). The
brute-force bracket of the symmetry breaking is read from that scatter: the lowest chi of its
symmetric periodic range and the grid value below it (the sweep's resolution). The period doubling
cannot be seen in 30-period snapshots; its bracket is ``brute_force.period_doubling``, the long
runs of docs/chaos.md (from (0, 0), 20,000 periods: period 2 at chi = 0.236, period 1 at 0.237).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..continuation_cli import plot_branches
from ..sweep import observables_dataset
from . import fig8_9_bifurcation as base
from .branches import Z_SCALE, bifurcation_rows, check_continuation, collect, continue_nd, shared_sweep, \
    write_bifurcations
from .common import StudyContext, plt
from .config import require

NAME = "fig8_9_orbits"
BASE_CONFIG = "fig8_9"
TITLE = "Fig. 8/9 band: branches of periodic orbits in chi over the scatter, bifurcations vs brute force"
FIGURES = ("fig8_9_orbits.png",)
DATASETS = ("fig8_9.nc", "branches.nc")


def check(cfg: dict[str, Any]) -> None:
    base.check(cfg)
    c = cfg["continuation"]
    check_continuation(c)
    require(c["start"] != c["stop"], "continuation.start and continuation.stop must differ")
    require(c["start"] > 0 and c["stop"] > 0, "continuation.start and continuation.stop (chi) must be > 0")
    pd = cfg["brute_force"]["period_doubling"]
    require(len(pd) == 2 and pd[0] <= pd[1], f"brute_force.period_doubling must be [lo, hi], lo <= hi, not {pd}")


def sb_bracket(chi: np.ndarray, sym: np.ndarray) -> tuple[float, float]:
    """The symmetry breaking as the scatter brackets it: (the grid value below the symmetric
    periodic range, its lowest value); NaN where the scatter has no such range or nothing below it."""
    lo, _ = base.symmetric_range(chi, sym)
    if not math.isfinite(lo):
        return math.nan, math.nan
    i = int(np.argmin(np.abs(chi - lo)))
    below = chi[chi < lo]
    return (float(below.max()) if below.size else math.nan), float(chi[i])


def run(ctx: StudyContext) -> dict[str, Any]:
    cfg = ctx.cfg
    nd, s, c = cfg["params"], cfg["sweep"], cfg["continuation"]
    sp, ax = base.spec(cfg)
    out = shared_sweep(ctx, BASE_CONFIG).run_sweep(sp)
    sc = observables_dataset(out, ax)
    cls = base.classify(sc)
    for name in cls.data_vars:
        sc[name] = cls[name]
    sc["symmetric_periodic"] = sc.symmetric_periodic.astype(np.int8)
    sc.attrs.update({f"param_{k}": v for k, v in nd.items()})
    sc.attrs.update(periods=s["periods"], obs_periods=s["obs_periods"], runs=sp.n_runs)
    ctx.save_dataset(sc, DATASETS[0])

    chi = ax["chi"]
    brute = {"symmetry_breaking": sb_bracket(chi, cls.symmetric_periodic.values),
             "period_doubling": tuple(float(v) for v in cfg["brute_force"]["period_doubling"])}
    cont = continue_nd(ctx, {**nd}, "chi", c["start"], c["stop"], c)
    ds = collect([({}, cont)])
    ds.attrs.update({f"param_{k}": v for k, v in nd.items() if k != "chi"})
    ctx.save_dataset(ds, DATASETS[1])
    rows = bifurcation_rows(cont, {}, brute)
    extra = {"brute_force": {k: list(v) for k, v in brute.items()},
             "brute_force_source": {"symmetry_breaking": f"fig8_9 scatter, {chi.size} values of chi "
                                                         f"from {chi[0]:g} to {chi[-1]:g}",
                                    "period_doubling": "brute_force.period_doubling (docs/chaos.md)"},
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
    axes[0].legend(fontsize=6.5, loc="upper right", markerscale=2)
    for a in axes:
        a.grid(alpha=0.3)
    axes[0].set_title(f"Fig. 8/9 band: lambda = {nd['lam']}, mu_s sigma = {nd['mu_s_sigma']}, zeta = {nd['zeta']} "
                      f"(z = k x / P0); branches of periodic orbits, chi {c['start']:g} -> {c['stop']:g}\n"
                      "solid: stable, dashed: unstable; F fold, PD period doubling, SB symmetry breaking, "
                      "G grazing", fontsize=8)
    fig.tight_layout()
    ctx.save_figure(fig, FIGURES[0])

    summary: dict[str, Any] = {"runs": float(sp.n_runs), "branch_points": int(ds.point.size) if ds else 0,
                               "evaluations": cont.evaluations}
    for kind in ("symmetry_breaking", "period_doubling"):
        found = [r["param_value"] for r in rows if r["type"] == kind]
        lo, hi = brute[kind]
        summary[f"chi_{kind}"] = found
        summary[f"brute_force_{kind}"] = [lo, hi]
        summary[f"{kind}_within_brute_force"] = bool(found) and all(lo <= v <= hi for v in found)
    for r in rows:
        bf = (f"; brute force [{r['brute_force_lo']:.4g}, {r['brute_force_hi']:.4g}]: "
              f"{'within' if r['within_brute_force'] else 'OUTSIDE'}") if r["within_brute_force"] != "" else ""
        ctx.log(f"fig8_9_orbits: {r['type']} at chi = {r['param_value']:.10f} (branch {r['branch']}, period "
                f"{r['period']}, amplitude z {r['amplitude_z']:.5f}, asymmetry {r['offset_z']:+.5f}){bf}")
    for b in cont.branches:
        ctx.log(f"fig8_9_orbits: branch {b.id} (period {b.period}, {b.kind}, {b.points} points): {b.stopped}")
    return summary
