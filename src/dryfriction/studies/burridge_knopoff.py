"""The Burridge-Knopoff model of an earthquake fault (Carlson and Langer 1989): a chain of n blocks
coupled by springs k_c, each pulled by a leaf spring k_p to a driver plate that moves at v_p, on
velocity-weakening friction. Run in the plate's frame by the FMI 3.0 chain: site springs k_site =
k_p to the frame, every belt at -v_p. A long run (the first loading cycles dropped) sampled at
communication points; slip events found in space and time (:mod:`dryfriction.analysis.slip_events`); their
moments' distribution per unit time, the event rate and the small events' power law. See
docs/burridge_knopoff.md and configs/burridge_knopoff.toml."""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from .. import paths
from ..drivers.chain import ARRAY_PARAMS, SCALAR_PARAMS, ChainFMU3, default_chain_fmu3
from ..analysis.slip_events import EventDetector, SlipEvents
from .common import FIGURE_BYTES, Estimate, StudyContext, plt
from .config import require
from . import REGISTRY

NAME = "burridge_knopoff"
TITLE = REGISTRY[NAME].title
FIGURES = REGISTRY[NAME].figures

#: the FMU this study runs (dryfriction.paths): the FMI 3.0 chain
FMU_KIND = paths.CHAIN3

LAWS = ("coulomb", "stribeck")


def default_fmu() -> Path:
    """The FMU the study runs by default: the FMI 3.0 chain."""
    return default_chain_fmu3()


def check(cfg: dict[str, Any]) -> None:
    """Refuse a configuration of the Burridge-Knopoff study with a value out of range (ConfigError naming the
    key), before any work."""
    m, r, d, f, num, sp = cfg["model"], cfg["run"], cfg["detect"], cfg["fit"], cfg["numerics"], cfg["speed"]
    require(1 <= m["n"] <= 4096, f"model.n must be in [1, 4096], not {m['n']}")
    require(m["l2"] >= 0, f"model.l2 (k_c / k_p) must be >= 0, not {m['l2']}")
    require(m["nu"] > 0, f"model.nu (plate speed v_p / (omega_p D0)) must be > 0, not {m['nu']}")
    require(m["friction_law"] in LAWS, f"model.friction_law must be coulomb or stribeck, not {m['friction_law']!r}")
    require(0 <= m["chi"] < 1, f"model.chi (mu_k / mu_s) must be in [0, 1) (velocity weakening), not {m['chi']}")
    require(m["alpha"] > 0, f"model.alpha (Carlson-Langer's velocity weakening) must be > 0, not {m['alpha']}")
    require(m["delta"] >= 1, f"model.delta (Stribeck exponent) must be >= 1, not {m['delta']}")
    require(m["c_site"] >= 0, f"model.c_site must be >= 0, not {m['c_site']}")
    require(0 <= m["x0_amplitude"] < 1, f"model.x0_amplitude must be in [0, 1), not {m['x0_amplitude']}")
    require(r["dt"] > 0, f"run.dt (sampling step) must be > 0, not {r['dt']}")
    require(r["t_transient"] >= 0, f"run.t_transient must be >= 0, not {r['t_transient']}")
    require(r["t_record"] >= 10 * r["dt"], f"run.t_record must be >= 10 run.dt = {10 * r['dt']}, not {r['t_record']}")
    require(r["segment"] >= r["dt"], f"run.segment must be >= run.dt = {r['dt']}, not {r['segment']}")
    require(d["v_threshold"] > 0, f"detect.v_threshold must be > 0, not {d['v_threshold']}")
    require(d["d_threshold"] > 0, f"detect.d_threshold must be > 0, not {d['d_threshold']}")
    require(f["bins_per_decade"] >= 1, f"fit.bins_per_decade must be >= 1, not {f['bins_per_decade']}")
    require(f["max_blocks"] >= 1, f"fit.max_blocks must be >= 1, not {f['max_blocks']}")
    require(f["min_count"] >= 1, f"fit.min_count must be >= 1, not {f['min_count']}")
    require(num["steps_per_period"] >= 20,
            f"numerics.steps_per_period (of the shortest period) must be >= 20, not {num['steps_per_period']}")
    require(-1 / 3 <= num["alpha"] <= 0, f"numerics.alpha (Bossak) must be in [-1/3, 0], not {num['alpha']}")
    require(num["scheme"] in ("consistent", "located"),
            f"numerics.scheme must be located or consistent (the paper scheme has no belt), not {num['scheme']!r}")
    require(all(1 <= k <= 4096 for k in sp["n"]), f"speed.n must hold chain sizes in [1, 4096], not {sp['n']}")
    require(sp["t"] > 0, f"speed.t must be > 0, not {sp['t']}")
    require(sp["nu"] > 0, f"speed.nu must be > 0, not {sp['nu']}")


# ---- the model ----------------------------------------------------------------------------------

def shortest_period(l2: float) -> float:
    """The chain's shortest natural period in units of 1 / omega_p: omega^2 <= k_p + 4 k_c."""
    return 2 * math.pi / math.sqrt(1.0 + 4.0 * l2)


def internal_step(l2: float, steps_per_period: float, dt: float) -> float:
    """The internal step: at most the shortest period over ``steps_per_period``, and a whole
    fraction of the sampling step ``dt`` (the communication points are internal grid points, so
    the sampling does not change the run)."""
    return dt / math.ceil(dt * steps_per_period / shortest_period(l2) - 1e-9)


def chain_params(m: Mapping[str, Any], num: Mapping[str, Any], dt: float, seed_offset: int = 0) -> dict[str, Any]:
    """The FMU's parameters of Carlson-Langer's dimensionless model (units: block mass, k_p, the
    static friction F0 = mu_s N; so omega_p = 1, D0 = F0 / k_p = 1, v_p = nu):

    m = 1, k_site = k_p = 1, k[1] = 0 and k_end = 0 (free ends), k[i] = k_c = l2 between
    neighbours, N = 1, mu_s = 1, chi = mu_k / mu_s; with the Stribeck law v_s = 1 / (2 alpha)
    (Carlson-Langer's initial slope of the friction, -2 alpha F0 per unit speed) and delta; the
    internal step from :func:`internal_step` with the sampling step ``dt``; no
    forcing; blocks start riding their belts (v0 = -nu) at small random x0 (uniform in +-
    x0_amplitude, seeded)."""
    n = int(m["n"])
    rng = np.random.default_rng(int(m["seed"]) + seed_offset)
    l2 = float(m["l2"])
    k = np.full(n, l2)
    k[0] = 0.0
    h = internal_step(l2, float(num["steps_per_period"]), dt)
    p: dict[str, Any] = {
        "m": 1.0, "k": k, "c": 0.0, "k_site": 1.0, "c_site": float(m["c_site"]), "N": 1.0, "mu_s": 1.0,
        "chi": float(m["chi"]), "P0": 0.0, "phi": 0.0, "omega": 1.0,
        "x0": rng.uniform(-1.0, 1.0, n) * float(m["x0_amplitude"]), "v0": -float(m["nu"]),
        "k_end": 0.0, "c_end": 0.0, "h": h, "alpha": float(num["alpha"]), "scheme": num["scheme"]}
    if m["friction_law"] == "stribeck":
        if "friction_law" not in ARRAY_PARAMS + SCALAR_PARAMS:
            from .config import ConfigError

            raise ConfigError("model.friction_law = stribeck needs a chain FMU with the Stribeck law "
                              "(friction_law, v_s, delta); this package's chain has coulomb only")
        p.update(friction_law="stribeck", v_s=1.0 / (2.0 * float(m["alpha"])), delta=float(m["delta"]))
    return p


def _bar(total: float, desc: str, enabled: bool) -> Any:
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit="t", file=sys.stderr, dynamic_ncols=True, disable=not enabled,
                bar_format="{l_bar}{bar}| {n:.0f}/{total:.0f} time units [{elapsed}<{remaining}]")


def simulate(fmu_path: Path, m: Mapping[str, Any], r: Mapping[str, Any], d: Mapping[str, Any],
             num: Mapping[str, Any], progress: bool = False) -> dict[str, Any]:
    """The long run: the transient stepped over, then ``t_record`` sampled every ``dt`` in segments
    fed to the event detector. Returns the events, the sampled mean position and sliding share,
    the wall time and the internal steps taken."""
    n = int(m["n"])
    nu = float(m["nu"])
    p = chain_params(m, num, float(r["dt"]))
    t0, t1, seg, dt = float(r["t_transient"]), float(r["t_transient"] + r["t_record"]), float(r["segment"]), float(r["dt"])
    det = EventDetector(-nu, float(d["v_threshold"]), float(d["d_threshold"]), bool(d["diagonal"]))
    ts, xmean, sliding, xspan = [], [], [], []
    wall0 = time.perf_counter()
    with ChainFMU3(n=n, fmu_path=fmu_path) as chain, _bar(t1, f"burridge_knopoff n={n}", progress) as bar:
        chain.start(p, inputs={"v_belt": -nu})
        t = 0.0
        while t < t0:
            t_next = min(t + seg, t0)
            chain.step_to(t_next)
            bar.update(t_next - t)
            t = t_next
        # the record starts at t0 exactly: segments on the grid t0 + k dt
        k_total = int(round((t1 - t0) / dt))
        k_seg = max(int(round(seg / dt)), 1)
        k = 0
        while k < k_total:
            k_next = min(k + k_seg, k_total)
            run = chain.record(t0 + k_next * dt, dt)
            det.feed(run.t, run.x, run.v)
            sel = slice(None) if k == 0 else slice(1, None)
            ts.append(run.t[sel])
            xmean.append(run.x[sel].mean(axis=1))
            xspan.append(np.ptp(run.x[sel], axis=1))
            sliding.append(np.mean(run.mode[sel] != 0, axis=1))
            bar.update((k_next - k) * dt)
            k = k_next
    wall = time.perf_counter() - wall0
    return {"events": det.events(), "t": np.concatenate(ts), "x_mean": np.concatenate(xmean),
            "x_span": np.concatenate(xspan), "sliding": np.concatenate(sliding), "wall_s": wall,
            "steps": int(round(t1 / p["h"])), "h": p["h"]}


def measure_speed(fmu_path: Path, m: Mapping[str, Any], num: Mapping[str, Any], sizes: list[int], t: float,
                  dt: float, progress: bool = False) -> list[dict[str, float]]:
    """Wall time of a run of ``t`` time units (sampled every ``dt``) per chain size: per simulated
    time unit and per block-step (internal step times blocks), and the share of samples at
    which some block slides (the cost grows with the switches)."""
    rows = []
    for n in sizes:
        mm = {**m, "n": int(n)}
        p = chain_params(mm, num, dt)
        with ChainFMU3(n=int(n), fmu_path=fmu_path) as chain:
            w0 = time.perf_counter()
            run = chain.run(t, dt, p, inputs={"v_belt": -float(m["nu"])})
            wall = time.perf_counter() - w0
        steps = t / p["h"]
        rows.append({"n": int(n), "t": float(t), "h": float(p["h"]), "wall_s": wall, "wall_per_time_unit_s": wall / t,
                     "ns_per_block_step": 1e9 * wall / (steps * n),
                     "share_samples_sliding": float(np.mean(np.any(run.mode != 0, axis=1)))})
        if progress:
            print(f"speed n = {n}: {wall:.2f} s for {t:g} time units, {rows[-1]['ns_per_block_step']:.1f} ns "
                  "per block-step", file=sys.stderr, flush=True)
    return rows


# ---- statistics ---------------------------------------------------------------------------------

def moment_histogram(moment: np.ndarray, duration: float, bins_per_decade: int) -> dict[str, np.ndarray]:
    """Events per unit time and unit moment, D(M) = count / (dM * duration), on log-spaced bins
    (whole decades, ``bins_per_decade`` each) covering the positive moments."""
    M = moment[moment > 0]
    if M.size == 0:
        edges = np.array([1.0, 10.0])
    else:
        lo, hi = math.floor(math.log10(M.min())), math.ceil(math.log10(M.max()) + 1e-12)
        edges = np.logspace(lo, hi, (hi - lo) * bins_per_decade + 1)
    count, _ = np.histogram(M, edges)
    centre = np.sqrt(edges[:-1] * edges[1:])
    return {"edges": edges, "centre": centre, "count": count, "rate_density": count / (np.diff(edges) * duration)}


def fit_power_law(hist: Mapping[str, np.ndarray], m_max: float, min_count: int) -> dict[str, float]:
    """The least-squares slope of log10 D(M) against log10 M over the bins below ``m_max`` holding
    at least ``min_count`` events (weights sqrt(count), Poisson): D ~ M^slope, slope = -(1 + b).
    NaN (with the bins used: 0 or 1) when fewer than 3 bins qualify."""
    c, M, D = hist["count"], hist["centre"], hist["rate_density"]
    use = (c >= min_count) & (hist["edges"][1:] <= m_max * (1 + 1e-12))
    if np.count_nonzero(use) < 3:
        return {"slope": math.nan, "slope_err": math.nan, "b": math.nan, "bins": int(np.count_nonzero(use)),
                "M_lo": math.nan, "M_hi": math.nan}
    X, Y, w = np.log10(M[use]), np.log10(D[use]), np.sqrt(c[use])
    A = np.vstack([X, np.ones_like(X)]).T * w[:, None]
    coef, *_ = np.linalg.lstsq(A, Y * w, rcond=None)
    res = Y - (coef[0] * X + coef[1])
    dof = max(X.size - 2, 1)
    cov = np.linalg.inv(A.T @ A) * (np.sum((res * w) ** 2) / dof)
    edges = hist["edges"]
    idx = np.flatnonzero(use)
    return {"slope": float(coef[0]), "slope_err": float(math.sqrt(cov[0, 0])), "intercept": float(coef[1]),
            "b": float(-coef[0] - 1.0), "bins": int(idx.size), "M_lo": float(edges[idx[0]]),
            "M_hi": float(edges[idx[-1] + 1])}


def slip_image(ev: SlipEvents, t_lo: float, t_hi: float, rows: int) -> tuple[np.ndarray, np.ndarray]:
    """The slip of each block summed over time bins of [t_lo, t_hi] ([rows, n]) and the bin edges."""
    c = ev.cells
    edges = np.linspace(t_lo, t_hi, rows + 1)
    tc = 0.5 * (c["t"][c["j"]] + c["t"][c["j"] + 1])
    inside = (tc >= t_lo) & (tc < t_hi)
    row = np.clip(np.searchsorted(edges, tc[inside], side="right") - 1, 0, rows - 1)
    img = np.zeros((rows, ev.n))
    np.add.at(img, (row, c["i"][inside]), c["d"][inside])
    return img, edges


# ---- the study ----------------------------------------------------------------------------------

def run(ctx: StudyContext) -> dict[str, Any]:
    """Run the Burridge-Knopoff study: its runs, dataset and figures in the study's folder; returns the
    summary."""
    cfg = ctx.cfg
    m, r, d, f, num, sp = cfg["model"], cfg["run"], cfg["detect"], cfg["fit"], cfg["numerics"], cfg["speed"]
    chain_params(m, num, float(r["dt"]))  # a friction law the FMU lacks: refused before the run
    progress = ctx.engine_options.progress
    res = simulate(ctx.fmu_path, m, r, d, num, progress)
    n = int(m["n"])
    allev: SlipEvents = res["events"]
    ev = allev.select(allev.complete)
    T = float(r["t_record"])
    hist = moment_histogram(ev.moment, T, int(f["bins_per_decade"]))
    small = ev.n_blocks <= int(f["max_blocks"])
    m_max = float(ev.moment[small].max()) if np.any(small) else 0.0
    fit = fit_power_law(hist, m_max, int(f["min_count"]))
    rate = ev.count / T
    # the loading cycle: the plate moves D0 = 1 in 1 / nu; a block carries its share of the moment
    moment_rate = float(ev.moment.sum()) / T  # per unit time, all blocks
    big = ev.n_blocks > int(f["max_blocks"])
    x_mean = res["x_mean"]
    ctx.log(f"burridge_knopoff: n = {n}, {m['friction_law']} (chi {m['chi']}), l2 = {m['l2']}, nu = {m['nu']}; "
            f"{T:g} time units recorded after {r['t_transient']:g} ({T * m['nu']:.1f} D0 of plate motion), "
            f"{res['wall_s']:.1f} s wall, {1e9 * res['wall_s'] / (res['steps'] * n):.1f} ns per block-step")
    ctx.log(f"  {ev.count} complete slip events ({allev.count - ev.count} cut by the record's ends), "
            f"rate {rate:.4g} per time unit; largest {int(ev.n_blocks.max()) if ev.count else 0} blocks, "
            f"moment {float(ev.moment.max()) if ev.count else 0:.4g}; small events (<= {f['max_blocks']} blocks): "
            + (f"D(M) ~ M^{fit['slope']:.3f} +- {fit['slope_err']:.3f} (b = {fit['b']:.3f}) over {fit['bins']} bins"
               if math.isfinite(fit["slope"]) else
               f"power law not fitted: {fit['bins']} bins with >= {f['min_count']} events (3 needed; a longer run)"))
    ctx.log(f"  moment rate {moment_rate:.4g} against the plate's n nu = {n * m['nu']:.4g}; "
            f"mean position over the record {x_mean.min():.4g} ... {x_mean.max():.4g} (bounded)")
    speed = measure_speed(ctx.fmu_path, {**m, "nu": sp["nu"]}, num, [int(k) for k in sp["n"]], float(sp["t"]),
                          float(r["dt"]), progress)
    for row in speed:
        ctx.log(f"  speed n = {row['n']}: {row['wall_per_time_unit_s'] * 1e3:.2f} ms wall per time unit, "
                f"{row['ns_per_block_step']:.1f} ns per block-step (h = {row['h']:.3g}, "
                f"{100 * row['share_samples_sliding']:.0f} % of samples with a block sliding)")
    ds = dataset(ev, hist, res, cfg)
    ctx.save_dataset(ds, "burridge_knopoff.nc")
    ctx.save_figure(plot(ev, hist, fit, res, cfg), "burridge_knopoff.png")
    return {
        "n": n, "friction_law": m["friction_law"], "l2": m["l2"], "nu": m["nu"], "chi": m["chi"],
        "t_transient": r["t_transient"], "t_record": T, "dt": r["dt"], "h": res["h"],
        "events": ev.count, "events_cut": allev.count - ev.count, "event_rate": rate,
        "large_events": int(np.count_nonzero(big)), "large_event_rate": float(np.count_nonzero(big)) / T,
        "largest_event_blocks": int(ev.n_blocks.max()) if ev.count else 0,
        "largest_event_moment": float(ev.moment.max()) if ev.count else 0.0,
        "moment_rate": moment_rate, "plate_moment_rate": n * float(m["nu"]),
        "share_moment_large": float(ev.moment[big].sum() / ev.moment.sum()) if ev.count and ev.moment.sum() > 0 else 0.0,
        "fit": fit, "fit_max_blocks": int(f["max_blocks"]),
        "x_mean_range": [float(x_mean.min()), float(x_mean.max())],
        "wall_s": res["wall_s"], "ns_per_block_step": 1e9 * res["wall_s"] / (res["steps"] * n),
        "wall_per_time_unit_s": res["wall_s"] / (r["t_transient"] + T), "speed": speed}


def dataset(ev: SlipEvents, hist: Mapping[str, np.ndarray], res: Mapping[str, Any], cfg: Mapping[str, Any]) -> xr.Dataset:
    """The events (dim event), the moment histogram (dim moment_bin), the sampled mean position and
    sliding share (dim time)."""
    ds = xr.Dataset(
        {"start": (("event",), ev.start, {"units": "1/omega_p", "long_name": "start of the event's first interval"}),
         "stop": (("event",), ev.stop, {"units": "1/omega_p"}),
         "duration": (("event",), ev.duration, {"units": "1/omega_p"}),
         "n_blocks": (("event",), ev.n_blocks.astype(np.int32), {"long_name": "blocks that slipped"}),
         "moment": (("event",), ev.moment, {"units": "D0", "long_name": "sum over the blocks of their slip"}),
         "position": (("event",), ev.position + 1.0, {"long_name": "epicentre: mean block (from 1) sliding first"}),
         "block_lo": (("event",), ev.block_lo.astype(np.int32) + 1, {"long_name": "first block (from 1)"}),
         "block_hi": (("event",), ev.block_hi.astype(np.int32) + 1, {"long_name": "last block (from 1)"}),
         "rate_density": (("moment_bin",), hist["rate_density"],
                          {"long_name": "events per unit time and unit moment, D(M)"}),
         "event_count": (("moment_bin",), hist["count"].astype(np.int64), {"long_name": "events per moment bin"}),
         "moment_edges": (("moment_edge",), hist["edges"]),
         "x_mean": (("time",), res["x_mean"], {"units": "D0", "long_name": "mean block position, plate frame"}),
         "x_span": (("time",), res["x_span"], {"units": "D0", "long_name": "max - min block position"}),
         "sliding_share": (("time",), res["sliding"], {"long_name": "share of blocks sliding"})},
        coords={"event": np.arange(ev.count), "moment_bin": hist["centre"], "time": res["t"]})
    for table in ("model", "run", "detect", "fit", "numerics"):
        for k, v in cfg[table].items():
            ds.attrs[f"{table}_{k}"] = int(v) if isinstance(v, bool) else v
    ds.attrs["h"] = res["h"]
    return ds


def plot(ev: SlipEvents, hist: Mapping[str, np.ndarray], fit: Mapping[str, float], res: Mapping[str, Any],
         cfg: Mapping[str, Any]) -> Any:
    """The study's figure: the slip events in space and time and their moments' distribution with the fitted
    power law."""
    from matplotlib.colors import LogNorm

    m, r = cfg["model"], cfg["run"]
    t0, t1 = float(r["t_transient"]), float(r["t_transient"] + r["t_record"])
    fig = plt.figure(figsize=(13, 8.5))
    gs = fig.add_gridspec(2, 2, height_ratios=[1.25, 1])
    ax_all, ax_zoom = fig.add_subplot(gs[0, 0]), fig.add_subplot(gs[0, 1])
    ax_h, ax_s = fig.add_subplot(gs[1, 0]), fig.add_subplot(gs[1, 1])
    blocks = np.arange(1, ev.n + 2) - 0.5
    img, edges = slip_image(ev, t0, t1, min(1500, max(int((t1 - t0) / r["dt"]), 1)))
    vmax = max(float(img.max()), 1e-12)
    norm = LogNorm(vmin=max(vmax * 1e-4, 1e-12), vmax=vmax)
    im = ax_all.pcolormesh(blocks, edges, np.where(img > 0, img, np.nan), norm=norm, cmap="inferno_r",
                           shading="flat", rasterized=True)
    fig.colorbar(im, ax=ax_all, label="slip per block and time bin (D0)")
    ax_all.set_xlabel("block")
    ax_all.set_ylabel("t (1/omega_p)")
    ax_all.set_title(f"slip events in space and time, {t1 - t0:g} time units", fontsize=9)
    # zoom: the largest event, from a little before its start to a little after its end
    if ev.count:
        k = int(np.argmax(ev.moment))
        pad = max(0.5 * float(ev.duration[k]), 5.0)
        dt = float(r["dt"])
        # bins on the sample grid: one sample interval per row
        z0 = t0 + dt * math.floor((max(float(ev.start[k]) - pad, t0) - t0) / dt)
        rows = max(int(round((min(float(ev.stop[k]) + pad, t1) - z0) / dt)), 1)
        z1 = z0 + rows * dt
        zimg, zedges = slip_image(ev, z0, z1, rows)
        zmax = max(float(zimg.max()), 1e-12)
        im2 = ax_zoom.pcolormesh(blocks, zedges, np.where(zimg > 0, zimg, np.nan),
                                 norm=LogNorm(vmin=max(zmax * 1e-4, 1e-12), vmax=zmax), cmap="inferno_r",
                                 shading="flat", rasterized=True)
        fig.colorbar(im2, ax=ax_zoom, label="slip per block and sample interval (D0)")
        ax_zoom.set_title(f"zoom: t {z0:.1f} ... {z1:.1f}, the largest event "
                          f"({int(ev.n_blocks[k])} blocks, M = {ev.moment[k]:.3g})", fontsize=9)
    ax_zoom.set_xlabel("block")
    ax_zoom.set_ylabel("t (1/omega_p)")
    c = hist["count"] > 0
    ax_h.loglog(hist["centre"][c], hist["rate_density"][c], "o", ms=4, label="this run")
    if math.isfinite(fit["slope"]):
        Mf = np.logspace(math.log10(fit["M_lo"]), math.log10(fit["M_hi"]), 20)
        ax_h.loglog(Mf, 10 ** fit["intercept"] * Mf ** fit["slope"], "-", lw=1.5,
                    label=f"fit (small events): slope {fit['slope']:.2f} +- {fit['slope_err']:.2f}")
        ref = 10 ** (fit["intercept"] + fit["slope"] * math.log10(fit["M_lo"])) * (Mf / fit["M_lo"]) ** -2.0
        ax_h.loglog(Mf, ref, "--", color="gray", lw=1, label="M^-2 (Carlson-Langer, b = 1)")
    ax_h.set_xlabel("moment M (sum of the blocks' slips, D0)")
    ax_h.set_ylabel("events per unit time and unit moment, D(M)")
    ax_h.legend(fontsize=8)
    ax_h.set_title(f"{ev.count} events, {ev.count / (t1 - t0):.3g} per time unit", fontsize=9)
    ax_s.loglog(ev.n_blocks, np.maximum(ev.moment, 1e-12), ".", ms=3, alpha=0.5)
    ax_s.set_xlabel("blocks that slipped")
    ax_s.set_ylabel("moment M (D0)")
    ax_s.set_title("event size against moment", fontsize=9)
    law = m["friction_law"] + (f" (chi = mu_k / mu_s = {m['chi']})" if m["friction_law"] == "coulomb"
                                else f" (v_s = 1/(2 alpha), alpha = {m['alpha']}, delta = {m['delta']}, chi = {m['chi']})")
    fig.suptitle(f"Burridge-Knopoff chain of {ev.n} blocks: l^2 = k_c / k_p = {m['l2']:g}, nu = v_p = {m['nu']:g}, "
                 f"{law}; h = {res['h']:.3g}, sampled every {r['dt']:g}", fontsize=10)
    fig.tight_layout()
    return fig


def work(cfg: dict[str, Any]) -> Estimate:
    """The study's work and output size (:mod:`dryfriction.budget`): the long run and the speed
    runs, internal steps times blocks (the record: a few numbers per sample, and the events)."""
    m, r, num, sp = cfg["model"], cfg["run"], cfg["numerics"], cfg["speed"]
    dt, n = float(r["dt"]), int(m["n"])
    h = internal_step(float(m["l2"]), float(num["steps_per_period"]), dt)
    t = float(r["t_transient"] + r["t_record"])
    est = Estimate().add(f"run: {n} blocks x {t / h:,.0f} steps", n * t / h, 4 * 8 * r["t_record"] / dt + 64.0 * n * n)
    for k in sp["n"]:
        est.add(f"speed n = {k}: {int(k)} blocks x {float(sp['t']) / h:,.0f} steps", int(k) * float(sp["t"]) / h)
    return est.add("figures", 0.0, FIGURE_BYTES * len(FIGURES))
