"""Fig. 10 and 11 solved: the frequency-response curves as branches of periodic orbits in lambda
(stable solid, unstable dashed, folds and grazings marked) for each chi of the figures, with the
fig10_11 study's scatter of 1681 initial conditions per point drawn over them.

The scatter is the fig10_11 study's own sweep (its config, its chunks when it has run). The
branches: for each chi, the lambda range of the figure is cut at ``continuation.seeds`` and, where
the range spans lambda = 1, around ``continuation.resonance_gap`` (undamped, the principal
resonance is unbounded: no periodic orbit at lambda = 1); every orbit find_orbits finds at each end
of a piece is continued across it (so coexisting motions of the sub-harmonic zone are caught from
either side; a piece continued from both ends is drawn twice, on top of itself).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..analysis.continuation import Continuation
from . import fig10_11_frequency_chi as base
from .branches import Z_SCALE, bifurcation_rows, check_continuation, collect, continue_nd, shared_sweep, \
    write_bifurcations
from ..budget import continuation_work
from .common import FIGURE_BYTES, Estimate, StudyContext, plt
from .config import grid, require
from . import REGISTRY

NAME = "fig10_11_orbits"
BASE_CONFIG = "fig10_11"
TITLE = REGISTRY[NAME].title
FIGURES = REGISTRY[NAME].figures
MARK = {"fold": ("s", "F"), "period_doubling": ("D", "PD"), "symmetry_breaking": ("o", "SB"), "grazing": ("^", "")}


def check(cfg: dict[str, Any]) -> None:
    """Refuse a configuration of the Fig. 10/11 orbits study with a value out of range (ConfigError naming the
    key), before any work."""
    base.check(cfg)
    c = cfg["continuation"]
    check_continuation(c)
    for i, v in enumerate(c["seeds"]):
        require(v > 0, f"continuation.seeds[{i}] must be > 0, not {v}")
    gap = c["resonance_gap"]
    require(len(gap) in (0, 2), f"continuation.resonance_gap must be [] or [lo, hi], not {gap}")
    if gap:
        require(0 < gap[0] < 1 < gap[1], f"continuation.resonance_gap must hold lambda = 1: 0 < lo < 1 < hi, not {gap}")


def pieces(lo: float, hi: float, seeds: list[float], gap: list[float]) -> list[tuple[float, float]]:
    """The lambda range [lo, hi] cut at the seeds inside it and around the resonance gap."""
    edges = {lo, hi} | {s for s in seeds if lo < s < hi}
    cut = bool(gap) and lo < gap[0] and gap[1] < hi
    if cut:
        edges |= {gap[0], gap[1]}
    e = sorted(edges)
    return [(a, b) for a, b in zip(e[:-1], e[1:]) if not (cut and a == gap[0] and b == gap[1])]


def _continue_piece(ctx: StudyContext, nd: dict[str, float], chi: float, a: float, b: float,
                    c: dict[str, Any]) -> Continuation | None:
    try:
        return continue_nd(ctx, {**nd, "chi": chi}, "lam", a, b, c)
    except ValueError as e:          # no orbit found at the seed: said, not fatal
        ctx.log(f"note: chi = {chi:g}, lambda {a:g} -> {b:g}: {e}")
        return None


def _draw(ax: Any, runs: list[tuple[dict[str, float], Continuation]], colors: dict[float, str]) -> None:
    for labels, cont in runs:
        color = colors[labels["chi"]]
        ds = cont.dataset
        for b in cont.branches:
            s = ds.where((ds.branch == b.id) & ds.converged, drop=True)
            if s.point.size == 0:
                continue
            x, y, st = s.param.values, s.amplitude_m.values * Z_SCALE, s.stable.values.astype(bool)
            for mask, ls in ((st, "-"), (~st, "--")):
                edge = mask | np.concatenate([mask[1:], [False]]) | np.concatenate([[False], mask[:-1]])
                ax.plot(x, np.where(edge, y, np.nan), ls=ls, color=color, lw=1.3)
        for f in cont.bifurcations:
            m, lab = MARK[f.type]
            y = f.amplitude_m * Z_SCALE
            ax.plot([f.param], [y], m, color="k", ms=5 if lab else 3.5, mfc="none", mew=0.8)
            if lab and not f.note:          # the located smooth ones (a note: non-smooth, or not located)
                ax.annotate(f"{lab} {f.param:.4g}", (f.param, y), textcoords="offset points", xytext=(3, 3),
                            fontsize=6.5)


def run(ctx: StudyContext) -> dict[str, Any]:
    """Run the Fig. 10/11 orbits study: its runs, dataset and figures in the study's folder; returns the
    summary."""
    cfg = ctx.cfg
    nd, c = cfg["params"], cfg["continuation"]
    summary: dict[str, Any] = {}
    all_rows: list[dict[str, Any]] = []
    for part, fig_name in zip(base.PARTS, FIGURES):
        sc = base._part(shared_sweep(ctx, BASE_CONFIG), part)
        ctx.save_dataset(sc, f"{part}.nc")
        lam = sc.lam.values
        lo, hi = float(lam.min()), float(lam.max())
        runs: list[tuple[dict[str, float], Continuation]] = []
        seg = 0
        for chi in (float(v) for v in sc.chi.values):
            for a, b in pieces(lo, hi, list(c["seeds"]), list(c["resonance_gap"])):
                for start, stop in ((a, b), (b, a)):
                    cont = _continue_piece(ctx, nd, chi, start, stop, c)
                    if cont is not None:
                        labels = {"chi": chi, "segment": float(seg)}
                        runs.append((labels, cont))
                        all_rows += [{"figure": part, "chi": chi, "segment": seg, "from": start, "to": stop, **r}
                                     for r in bifurcation_rows(cont, {})]
                    seg += 1
        ds = collect(runs)
        ds.attrs.update({f"param_{k}": v for k, v in nd.items()})
        ctx.save_dataset(ds, f"{part}_branches.nc")

        n_ic = sc.z0.size * sc.dz0.size
        fig, ax = plt.subplots(figsize=(8, 5))
        colors = {float(v): f"C{i}" for i, v in enumerate(sc.chi.values)}
        for i, chi in enumerate(sc.chi.values):
            amp = sc.amplitude.isel(chi=i).values.reshape(lam.size, n_ic)
            ax.scatter(np.repeat(lam, n_ic), amp.reshape(-1), s=2.5 if n_ic > 100 else 9.0, color=colors[float(chi)],
                       alpha=0.2, lw=0, rasterized=True)
            ax.plot([], [], color=colors[float(chi)], lw=1.3, label=f"chi = {chi:g}: orbits (dots: brute force)")
        _draw(ax, runs, colors)
        ax.plot([], [], "k-", lw=1.0, label="stable")
        ax.plot([], [], "k--", lw=1.0, label="unstable")
        if lo < 1 < hi:
            ax.set_yscale("log")
        ax.set_xlim(lo - 0.01 * (hi - lo), hi + 0.01 * (hi - lo))
        ax.set_xlabel("frequency ratio lambda = omega / w0")
        ax.set_ylabel("mean amplitude (z_max - z_min) / 2  (z = k x / P0, static deflections)")
        ax.grid(alpha=0.3, which="both")
        ax.legend(loc="upper left", fontsize=7)
        ax.set_title(f"Fig. {fig_name[3:5]} as branches of periodic orbits: mu_s sigma = {nd['mu_s_sigma']}, "
                     f"zeta = {nd['zeta']}; dots: {sc.z0.size} x {sc.dz0.size} initial conditions after "
                     f"{cfg['ics']['periods']:g} T\nF fold, SB symmetry breaking, PD period doubling (labelled where "
                     "located), ^ grazing", fontsize=8)
        ctx.save_figure(fig, fig_name)

        summary[f"{part}_branch_points"] = int(ds.point.size) if ds else 0
        summary[f"{part}_continuations"] = len(runs)
        for kind in ("fold", "grazing", "period_doubling", "symmetry_breaking"):
            vals = sorted({round(r["param_value"], 10) for r in all_rows if r["figure"] == part and r["type"] == kind})
            summary[f"{part}_{kind}"] = vals
    extra = {"continuation": {k: v for k, v in c.items()}}
    write_bifurcations(ctx, all_rows, "bifurcations", extra)
    for r in all_rows:
        if r["type"] != "grazing":
            ctx.log(f"fig10_11_orbits: {r['figure']}, chi = {r['chi']:g}: {r['type']} at lambda = "
                    f"{r['param_value']:.10f} (amplitude z {r['amplitude_z']:.5f})"
                    + (f"; {r['note']}" if r["note"] else ""))
    n_g = sum(r["type"] == "grazing" for r in all_rows)
    ctx.log(f"fig10_11_orbits: {len(all_rows)} bifurcations located ({n_g} grazings); "
            + ", ".join(f"{k} {v}" for k, v in summary.items() if k.endswith("points")))
    return summary


def work(cfg: dict[str, Any]) -> Estimate:
    """The study's work and output size (:mod:`dryfriction.budget`): fig10_11's sweeps and, per
    part, chi and piece of the lambda range, a continuation each way."""
    c = cfg["continuation"]
    est = base.work(cfg)
    steps, what = continuation_work(c["max_points"], c["max_branches"])
    for part in base.PARTS:
        lam = grid(cfg[part]["lam"], f"{part}.lam")
        n = 2 * len(cfg[part]["chi"]) * len(pieces(float(lam.min()), float(lam.max()), list(c["seeds"]),
                                                     list(c["resonance_gap"])))
        est.add(f"{part}: {n} continuations x {what}", n * steps, n * 400.0 * c["max_points"] * c["max_branches"])
    return est.add("figures", 0.0, FIGURE_BYTES * len(FIGURES))
