"""Two blocks, the first forced: amplitude and stick share of each block against the frequency
ratio, friction on both blocks and on the second only, over a grid of initial conditions (see
configs/chain2.toml). Runs the FMI 3.0 chain (n = 2 set in Configuration Mode), one Dask task per
chunk of runs."""

from __future__ import annotations

import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from .. import paths
from ..drivers.chain import ChainFMU3, default_chain_fmu3
from ..sweep.runner import PerProcess
from .common import FIGURE_BYTES, Estimate, StudyContext, plt, trajectory_estimate
from .config import grid, require
from . import REGISTRY

NAME = "chain2"
TITLE = REGISTRY[NAME].title
FIGURES = REGISTRY[NAME].figures
CONFIGS = {"both": "friction on both blocks", "second": "friction on the second block only"}

_CHAINS: PerProcess[ChainFMU3] = PerProcess(lambda path: ChainFMU3(2, fmu_path=path))


#: the FMU this study runs (dryfriction.paths): the FMI 3.0 chain
FMU_KIND = paths.CHAIN3


def default_fmu() -> Path:
    """The FMU the study runs by default: the FMI 3.0 chain."""
    return default_chain_fmu3()


def check(cfg: dict[str, Any]) -> None:
    """Refuse a configuration of the two-block chain study with a value out of range (ConfigError naming the
    key), before any work."""
    ch, w, num = cfg["chain"], cfg["window"], cfg["numerics"]
    require(ch["m"] > 0, f"chain.m must be > 0, not {ch['m']}")
    for key in ("k", "c", "N", "mu_s", "chi"):
        require(ch[key] >= 0, f"chain.{key} must be >= 0, not {ch[key]}")
    require(len(ch["configs"]) >= 1 and all(c in CONFIGS for c in ch["configs"]),
            f"chain.configs must be a non-empty list of {', '.join(CONFIGS)}, not {ch['configs']}")
    for key in ("lam", "x0_1", "x0_2"):
        grid(cfg["sweep"][key], f"sweep.{key}")
    require(cfg["sweep"]["lam"]["start"] > 0, "sweep.lam.start must be > 0")
    require(0 < w["obs_periods"] <= w["periods"],
            f"window.obs_periods must be in (0, window.periods = {w['periods']}], not {w['obs_periods']}")
    require(w["samples_per_period"] >= 4, f"window.samples_per_period must be >= 4, not {w['samples_per_period']}")
    require(num["steps_per_period"] >= 10, f"numerics.steps_per_period must be >= 10, not {num['steps_per_period']}")
    require(-1 / 3 <= num["alpha"] <= 0, f"numerics.alpha must be in [-1/3, 0], not {num['alpha']}")
    require(num["scheme"] in ("paper", "consistent", "located"),
            f"numerics.scheme must be paper, consistent or located, not {num['scheme']!r}")
    require(num["chunk_runs"] >= 1, f"numerics.chunk_runs must be >= 1, not {num['chunk_runs']}")


def chain_params(ch: Mapping[str, Any], config: str, lam: float, x0: tuple[float, float],
                 num: Mapping[str, Any]) -> dict[str, Any]:
    """The FMU's parameters of one run (omega = lam sqrt(k/m), h = T / steps_per_period)."""
    omega = lam * np.sqrt(ch["k"] / ch["m"])
    T = 2 * np.pi / omega
    N = [ch["N"], ch["N"]] if config == "both" else [0.0, ch["N"]]
    return {"m": ch["m"], "k": ch["k"], "c": ch["c"], "P0": [ch["P0"], 0.0], "phi": 0.0, "N": N,
            "mu_s": ch["mu_s"], "chi": ch["chi"], "x0": list(x0), "v0": 0.0, "k_end": 0.0, "c_end": 0.0,
            "omega": omega, "h": T / num["steps_per_period"], "alpha": num["alpha"], "scheme": num["scheme"]}


def rows_task(fmu: str | bytes, ch: Mapping[str, Any], window: Mapping[str, Any], num: Mapping[str, Any],
              rows: list[tuple[str, float, float, float]]) -> dict[str, np.ndarray]:
    """Task: rows (config, lam, x0_1, x0_2) -> amplitude and stick share of both blocks [rows, 2]
    over the observation window (nan where the FMU failed)."""
    c0 = time.process_time()
    chain = _CHAINS.get(fmu)
    chain.set_n(2)
    amp, stick = np.full((len(rows), 2), np.nan), np.full((len(rows), 2), np.nan)
    for i, (config, lam, a, b) in enumerate(rows):
        p = chain_params(ch, config, lam, (a, b), num)
        T = 2 * np.pi / p["omega"]
        t0 = (window["periods"] - window["obs_periods"]) * T
        try:
            chain.start(p)
            chain.step_to(t0)  # the transient in one step
            run = chain.record(window["periods"] * T, T / window["samples_per_period"])
        except Exception:  # noqa: BLE001 - a failed run is a nan row, not a failed sweep
            continue
        amp[i], stick[i] = run.amplitude(), run.stick_share()
    return {"amplitude": amp, "stick_share": stick, "cpu": np.array([time.process_time() - c0])}


def run(ctx: StudyContext) -> dict[str, Any]:
    """Run the two-block chain study: its runs, dataset and figures in the study's folder; returns the
    summary."""
    from ..analysis.chaos.batch import concat, map_chunks

    cfg = ctx.cfg
    ch, sw, w, num = cfg["chain"], cfg["sweep"], cfg["window"], cfg["numerics"]
    configs = list(ch["configs"])
    lam, x1, x2 = grid(sw["lam"], "sweep.lam"), grid(sw["x0_1"], "sweep.x0_1"), grid(sw["x0_2"], "sweep.x0_2")
    rows = [(c, float(l), float(a), float(b)) for c in configs for l in lam for a in x1 for b in x2]
    n = int(num["chunk_runs"])
    chunks = [(ch, w, num, rows[i:i + n]) for i in range(0, len(rows), n)]
    o = ctx.engine_options
    res, st = map_chunks(rows_task, o.fmu, chunks, o.workers, o.scheduler, o.progress, "chain2")
    shape = (len(configs), lam.size, x1.size, x2.size, 2)
    amp = concat(res, "amplitude").reshape(shape)
    stick = concat(res, "stick_share").reshape(shape)
    failed = int(np.isnan(amp[..., 0]).sum())
    ctx.log(f"chain2: {len(rows):,} runs of {w['periods']} periods in {st.wall:.1f} s (cluster start "
            f"{st.startup:.1f} s, task CPU {st.task_cpu:.1f} s); {failed} failed")
    dims = ("config", "lam", "x0_1", "x0_2", "block")
    ds = xr.Dataset(
        {"amplitude": (dims, amp, {"long_name": "half the peak-to-peak of x over the observation window",
                                   "units": "m"}),
         "stick_share": (dims, stick, {"long_name": "share of the observation window stuck", "units": "1"})},
        coords={"config": configs, "lam": lam, "x0_1": x1, "x0_2": x2, "block": [1, 2]})
    ds.attrs.update({f"chain_{k}": v for k, v in ch.items() if k != "configs"})
    ds.attrs.update(periods=w["periods"], obs_periods=w["obs_periods"], samples_per_period=w["samples_per_period"],
                    steps_per_period=num["steps_per_period"], scheme=num["scheme"], alpha=num["alpha"],
                    wall_s=st.wall, task_cpu_s=st.task_cpu, failed_runs=failed)
    ctx.save_dataset(ds, "chain2.nc")
    ctx.save_figure(plot(ds), "chain2.png")
    summary: dict[str, Any] = {"runs": len(rows), "failed": failed, "wall_s": st.wall, "task_cpu_s": st.task_cpu}
    for c in configs:
        a = ds.amplitude.sel(config=c)
        s = ds.stick_share.sel(config=c)
        spread = (a.max(("x0_1", "x0_2")) - a.min(("x0_1", "x0_2"))).values
        summary[c] = {
            "peak_amplitude": [float(a.sel(block=b).max()) for b in (1, 2)],
            "lam_at_peak": [float(a.sel(block=b).max(("x0_1", "x0_2")).idxmax("lam")) for b in (1, 2)],
            "mean_stick_share": [float(s.sel(block=b).mean()) for b in (1, 2)],
            "lam_with_coexisting_motions": [float(x) for x in lam[np.nanmax(spread, axis=1) > 0.05]],
        }
    return summary


def plot(ds: xr.Dataset) -> Any:
    """Amplitude (top) and stick share (bottom) of each block against lam, one column per friction
    configuration: the median over the initial conditions as a line, their range as a band."""
    configs = [str(c) for c in ds.config.values]
    fig, axes = plt.subplots(2, len(configs), figsize=(5.2 * len(configs), 6.4), sharex=True, squeeze=False)
    lam = ds.lam.values
    colours = {1: "#1f77b4", 2: "#d62728"}
    for j, c in enumerate(configs):
        for r, var in enumerate(("amplitude", "stick_share")):
            ax = axes[r, j]
            for b in (1, 2):
                v = ds[var].sel(config=c, block=b).values.reshape(lam.size, -1)
                ax.fill_between(lam, np.nanmin(v, axis=1), np.nanmax(v, axis=1), color=colours[b], alpha=0.25, lw=0)
                ax.plot(lam, np.nanmedian(v, axis=1), color=colours[b], lw=1.2, label=f"block {b}")
            ax.set_ylabel("amplitude (m)" if var == "amplitude" else "share of time stuck")
            if r == 0:
                ax.set_title(CONFIGS.get(c, c))
                ax.legend(fontsize=8)
            else:
                ax.set_xlabel("frequency ratio omega / sqrt(k/m)")
                ax.set_ylim(-0.03, 1.03)
    a = ds.attrs
    fig.suptitle(f"Two blocks, the first forced (P0 = {a['chain_P0']}, mu_s N = {a['chain_mu_s'] * a['chain_N']:g}, "
                 f"chi = {a['chain_chi']}, c = {a['chain_c']}): median and range over "
                 f"{ds.x0_1.size * ds.x0_2.size} initial conditions", fontsize=9)
    return fig


def work(cfg: dict[str, Any]) -> Estimate:
    """The study's work and output size (:mod:`dryfriction.budget`): every configuration,
    frequency and pair of initial positions, a run of the two blocks."""
    ch, sw, w = cfg["chain"], cfg["sweep"], cfg["window"]
    runs = len(ch["configs"]) * int(sw["lam"]["num"]) * int(sw["x0_1"]["num"]) * int(sw["x0_2"]["num"])
    est = trajectory_estimate(Estimate(), "chain2", runs, w["periods"], cfg["numerics"], blocks=2)
    est.out_bytes += runs * 4 * 8
    return est.add("figures", 0.0, FIGURE_BYTES * len(FIGURES))
