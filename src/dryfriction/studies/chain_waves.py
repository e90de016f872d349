"""Stick-slip fronts along a long chain, the first block forced: the space-time image of every
block's mode (stuck, slipping forward, backward) and the share of time stuck per block, for a few
forcing amplitudes (see configs/chain_waves.toml). Runs the FMI 3.0 chain with n set in
Configuration Mode, one Dask task per amplitude."""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from .. import paths
from ..drivers.chain import ChainFMU3, default_chain_fmu3
from ..sweep.runner import PerProcess
from .common import FIGURE_BYTES, Estimate, StudyContext, plt
from .config import require
from . import REGISTRY

NAME = "chain_waves"
TITLE = REGISTRY[NAME].title
FIGURES = REGISTRY[NAME].figures

_CHAINS: PerProcess[ChainFMU3] = PerProcess(lambda path: ChainFMU3(2, fmu_path=path))


#: the FMU this study runs (dryfriction.paths): the FMI 3.0 chain
FMU_KIND = paths.CHAIN3


def default_fmu() -> Path:
    """The FMU the study runs by default: the FMI 3.0 chain."""
    return default_chain_fmu3()


def check(cfg: dict[str, Any]) -> None:
    """Refuse a configuration of the chain-waves study with a value out of range (ConfigError naming the key),
    before any work."""
    ch, w, num = cfg["chain"], cfg["window"], cfg["numerics"]
    require(2 <= ch["n"] <= 4096, f"chain.n must be in [2, 4096], not {ch['n']}")
    require(ch["m"] > 0, f"chain.m must be > 0, not {ch['m']}")
    for key in ("k", "c", "N", "mu_s", "chi"):
        require(ch[key] >= 0, f"chain.{key} must be >= 0, not {ch[key]}")
    require(ch["omega"] > 0, f"chain.omega must be > 0, not {ch['omega']}")
    require(len(ch["P0_levels"]) >= 1, "chain.P0_levels must hold at least one amplitude")
    require(w["periods"] > 0 and w["samples_per_period"] >= 4,
            "window.periods must be > 0 and window.samples_per_period >= 4")
    require(num["h"] > 0, f"numerics.h must be > 0, not {num['h']}")
    require(-1 / 3 <= num["alpha"] <= 0, f"numerics.alpha must be in [-1/3, 0], not {num['alpha']}")
    require(num["scheme"] in ("paper", "consistent", "located"),
            f"numerics.scheme must be paper, consistent or located, not {num['scheme']!r}")


def chain_params(ch: Mapping[str, Any], P0: float, num: Mapping[str, Any]) -> dict[str, Any]:
    """The FMU's parameters: no wall spring at either end (k[1] = 0, k_end = 0), block 1 forced."""
    n = int(ch["n"])
    k = np.full(n, float(ch["k"]))
    k[0] = 0.0
    P = np.zeros(n)
    P[0] = P0
    return {"m": ch["m"], "k": k, "c": ch["c"], "P0": P, "phi": 0.0, "N": ch["N"], "mu_s": ch["mu_s"],
            "chi": ch["chi"], "x0": 0.0, "v0": 0.0, "k_end": 0.0, "c_end": 0.0, "omega": ch["omega"],
            "h": num["h"], "alpha": num["alpha"], "scheme": num["scheme"]}


def wave_task(fmu: str | bytes, ch: Mapping[str, Any], window: Mapping[str, Any], num: Mapping[str, Any],
              P0: float) -> dict[str, np.ndarray]:
    """Task: one run of the chain; the mode at every sample [nt, n], x's range per block."""
    c0 = time.process_time()
    chain = _CHAINS.get(fmu)
    chain.set_n(int(ch["n"]))
    T = 2 * np.pi / ch["omega"]
    run = chain.run(window["periods"] * T, T / window["samples_per_period"], chain_params(ch, P0, num))
    return {"t": run.t[None], "mode": run.mode[None], "x_max": run.x.max(axis=0)[None],
            "x_min": run.x.min(axis=0)[None], "cpu": np.array([time.process_time() - c0])}


def first_slip(t: np.ndarray, mode: np.ndarray) -> np.ndarray:
    """Per block, the first sample time at which it slips (nan if it never does)."""
    moved = mode != 0
    first = np.argmax(moved, axis=0)
    return np.where(moved.any(axis=0), t[first], np.nan)


def front_speed(first: np.ndarray) -> float:
    """Blocks per second of the first slip front: the least-squares slope of block index against
    first slip time over the blocks it reached (nan if fewer than 3)."""
    idx = np.flatnonzero(np.isfinite(first))
    if idx.size < 3:
        return float("nan")
    return float(np.polyfit(first[idx], idx.astype(float), 1)[0])


def run(ctx: StudyContext) -> dict[str, Any]:
    """Run the chain-waves study: its runs, dataset and figures in the study's folder; returns the summary."""
    from ..analysis.chaos.batch import map_chunks

    cfg = ctx.cfg
    ch, w, num = cfg["chain"], cfg["window"], cfg["numerics"]
    levels = amplitudes(ch)
    o = ctx.engine_options
    chunks = [(ch, w, num, p) for p in levels]
    res, st = map_chunks(wave_task, o.fmu, chunks, o.workers, o.scheduler, o.progress, "chain_waves")
    t = res[0]["t"][0]
    T = 2 * np.pi / ch["omega"]
    n = int(ch["n"])
    mode = np.concatenate([r["mode"] for r in res]).astype(np.int8)
    stick = np.mean(mode == 0, axis=1)
    first = np.array([first_slip(t, m) for m in mode])
    speed = np.array([front_speed(f) for f in first])
    reach = np.array([int(np.isfinite(f).sum()) for f in first])
    ds = xr.Dataset(
        {"mode": (("P0", "time", "block"), mode, {"long_name": "-1 backward slip, 0 stuck, +1 forward slip"}),
         "stick_share": (("P0", "block"), stick, {"long_name": "share of the run stuck", "units": "1"}),
         "first_slip_time": (("P0", "block"), first, {"long_name": "first time the block slips", "units": "s"}),
         "x_max": (("P0", "block"), np.concatenate([r["x_max"] for r in res]), {"units": "m"}),
         "x_min": (("P0", "block"), np.concatenate([r["x_min"] for r in res]), {"units": "m"}),
         "front_speed": (("P0",), speed, {"long_name": "speed of the first slip front", "units": "blocks/s"}),
         "blocks_reached": (("P0",), reach, {"long_name": "blocks that slipped at least once"})},
        coords={"P0": levels, "time": ("time", t, {"units": "s"}), "block": np.arange(1, n + 1)})
    ds.attrs.update({f"chain_{k}": v for k, v in ch.items() if k != "P0_levels"})
    ds.attrs.update(P0_levels=levels, periods=w["periods"], samples_per_period=w["samples_per_period"],
                    h=num["h"], scheme=num["scheme"], alpha=num["alpha"], wall_s=st.wall, task_cpu_s=st.task_cpu)
    ctx.log(f"chain_waves: {len(levels)} runs of {n} blocks over {w['periods']} periods ({t[-1]:.0f} s, "
            f"{int(round(t[-1] / num['h'])):,} steps each) in {st.wall:.1f} s (task CPU {st.task_cpu:.1f} s); "
            + "; ".join(f"P0 {p:g}: front {s:.3g} blocks/s, {r} blocks reached" for p, s, r in zip(levels, speed, reach)))
    ctx.save_dataset(ds, "chain_waves.nc")
    ctx.save_figure(plot(ds), "chain_waves.png")
    main = levels.index(float(ch["P0"]))
    return {"n": n, "period_s": T, "wall_s": st.wall, "task_cpu_s": st.task_cpu, "P0": levels,
            "front_speed_blocks_per_s": [float(s) for s in speed], "blocks_reached": [int(r) for r in reach],
            "stick_share_first_last": [[float(s[0]), float(s[-1])] for s in stick],
            "main_P0": float(ch["P0"]), "main_mode_counts": {str(v): int(np.sum(mode[main] == v)) for v in (-1, 0, 1)}}


def plot(ds: xr.Dataset) -> Any:
    """The study's figure: the blocks' modes over time (the stick-slip fronts) and the stick share along the
    chain."""
    from matplotlib.colors import ListedColormap

    a = ds.attrs
    main = float(a["chain_P0"])
    m = ds.mode.sel(P0=main).values
    T = 2 * np.pi / float(a["chain_omega"])
    fig, ax = plt.subplots(1, 2, figsize=(12, 5.4), gridspec_kw={"width_ratios": [1.5, 1]})
    cmap = ListedColormap(["#3b6fb6", "#e3e3e3", "#c0392b"])
    im = ax[0].pcolormesh(ds.block.values, ds.time.values / T, m, cmap=cmap, vmin=-1.5, vmax=1.5,
                          shading="nearest", rasterized=True)
    cb = fig.colorbar(im, ax=ax[0], ticks=[-1, 0, 1])
    cb.ax.set_yticklabels(["slipping backward", "stuck", "slipping forward"])
    ax[0].set_xlabel("block")
    ax[0].set_ylabel("t / T (excitation periods)")
    sp = float(ds.front_speed.sel(P0=main))
    ax[0].set_title(f"mode of each block, P0 = {main:g}: first front {sp:.3g} blocks/s", fontsize=9)
    for p in ds.P0.values:
        ax[1].plot(ds.block.values, ds.stick_share.sel(P0=p).values, lw=1.2, label=f"P0 = {p:g}")
    ax[1].set_xlabel("block")
    ax[1].set_ylabel("share of time stuck")
    ax[1].set_ylim(-0.02, 1.02)
    ax[1].legend(fontsize=8)
    ax[1].set_title("stick share per block", fontsize=9)
    fig.suptitle(f"Chain of {ds.block.size} blocks, block 1 forced (omega = {a['chain_omega']} rad/s, "
                 f"mu_s N = {a['chain_mu_s'] * a['chain_N']:g}, chi = {a['chain_chi']}, k = {a['chain_k']}, "
                 f"c = {a['chain_c']}, free ends); {a['scheme']}, h = {a['h']} s", fontsize=9)
    return fig


def amplitudes(ch: Mapping[str, Any]) -> list[float]:
    """The forcing amplitudes run: ``P0`` and ``P0_levels``, each once, in order."""
    return sorted({float(ch["P0"]), *(float(p) for p in ch["P0_levels"])})


def work(cfg: dict[str, Any]) -> Estimate:
    """The study's work and output size (:mod:`dryfriction.budget`): one run of the chain per
    amplitude, internal steps times blocks; the modes of every sample and block."""
    ch, w, num = cfg["chain"], cfg["window"], cfg["numerics"]
    n, k = int(ch["n"]), len(amplitudes(ch))
    steps = w["periods"] * 2 * math.pi / ch["omega"] / num["h"]
    samples = w["periods"] * w["samples_per_period"] + 1
    est = Estimate().add(f"{k} runs x {n} blocks x {steps:,.0f} steps", k * n * steps,
                         k * (samples * (n + 8) + 5 * 8 * n))
    return est.add("figures", 0.0, FIGURE_BYTES * len(FIGURES))
