"""Fig. 12 to 14: time histories, phase portraits and two nearby initial conditions diverging, in
and beside the sub-harmonic resonance zone.

Fig. 12: z' and the excitation cos(lam tau) over two cycles after ``fig12.skip_periods`` periods
from rest, at a frequency ratio inside the zone (four stick phases per cycle: the slides are
interrupted by extra stops) and one above it (period-1 motion with two stick phases per cycle).
Fig. 13: the phase portraits (z, z') of the same steady states; the extra stops are the cusps on
the z axis.
Fig. 14: where two steady motions coexist (chi < 1), two initial conditions a tiny distance apart
(found by bisection between ``fig14.ic_a`` and ``fig14.ic_b``, which must end on different
motions) follow each other until a stick phase and then part.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import xarray as xr

from ..drivers.oscillator import Settings
from .common import (Estimate, FIGURE_BYTES, StudyContext, check_numerics, check_params, ensure, nondim_trajectory,
                     oscillator, plt, trajectory_estimate)
from .config import require
from . import REGISTRY

NAME = "fig12_14"
TITLE = REGISTRY[NAME].title
FIGURES = REGISTRY[NAME].figures
DATASET = "fig12_14.nc"


def check(cfg: dict[str, Any]) -> None:
    """Refuse a configuration of the Fig. 12-14 study with a value out of range (ConfigError naming the key),
    before any work."""
    check_params(cfg["params"])
    check_numerics(cfg["numerics"])
    f12, f14 = cfg["fig12"], cfg["fig14"]
    check_params({"chi": f12["chi"], "lam": f12["lam_in"]}, "fig12")
    check_params({"lam": f12["lam_above"]}, "fig12")
    require(f12["skip_periods"] >= 0 and f12["cycles"] > 0, "fig12.skip_periods must be >= 0 and fig12.cycles > 0")
    check_params({"chi": f14["chi"], "lam": f14["lam"]}, "fig14")
    require(len(f14["ic_a"]) == 2 and len(f14["ic_b"]) == 2, "fig14.ic_a and fig14.ic_b must be [z0, dz0]")
    require(f14["ic_a"] != f14["ic_b"], "fig14.ic_a and fig14.ic_b must differ")
    require(f14["separation"] > 0, f"fig14.separation must be > 0, not {f14['separation']}")
    require(f14["periods"] >= 2 and f14["show_periods"] > 0, "fig14.periods must be >= 2 and fig14.show_periods > 0")
    require(cfg["run"]["samples_per_period"] >= 10, "run.samples_per_period must be >= 10")


def _stick_phases_per_cycle(mode: np.ndarray, cycles: float) -> float:
    m = np.asarray(mode)
    starts = np.sum((m[1:] == 0) & (m[:-1] != 0))
    return float(starts) / cycles


def _amplitude(ctx: StudyContext, nd: dict[str, float], periods: float, numerics: dict[str, Any]) -> float:
    p = oscillator(nd)
    st = Settings(h=p.period / numerics["steps_per_period"], alpha=numerics["alpha"], scheme=numerics["scheme"])
    o = ctx.fmu().observables(p, periods * p.period, (periods - 1) * p.period, None, st)
    return 0.5 * (o["x_max"] - o["x_min"]) * p.k / p.P0


def _bisect(ctx: StudyContext, nd: dict[str, float], a: np.ndarray, b: np.ndarray, periods: float,
            sep: float, numerics: dict[str, Any]) -> tuple[np.ndarray, np.ndarray, float, float]:
    def amp(ic: np.ndarray) -> float:
        return _amplitude(ctx, {**nd, "z0": float(ic[0]), "dz0": float(ic[1])}, periods, numerics)

    A_a, A_b = amp(a), amp(b)
    if abs(A_a - A_b) <= 0.02 * max(abs(A_a), abs(A_b)):
        raise RuntimeError(f"fig14: ic_a {list(a)} and ic_b {list(b)} end on the same motion (amplitude {A_a:.4f} "
                           f"and {A_b:.4f}); choose ends that reach different motions (see fig10_11)")
    for _ in range(200):
        if float(np.hypot(*(b - a))) <= sep:
            break
        mid = 0.5 * (a + b)
        A_m = amp(mid)
        if abs(A_m - A_a) <= abs(A_m - A_b):
            a, A_a = mid, A_m
        else:
            b, A_b = mid, A_m
    return a, b, A_a, A_b


def run(ctx: StudyContext) -> dict[str, float]:
    """Run the Fig. 12-14 study: its runs, dataset and figures in the study's folder; returns the summary."""
    cfg = ctx.cfg
    nd, num, f12, f14 = cfg["params"], cfg["numerics"], cfg["fig12"], cfg["fig14"]
    spp = cfg["run"]["samples_per_period"]
    fmu = ctx.fmu()

    # ---- Fig. 12 and 13: steady states in and above the zone, from rest ----
    t0, t1 = f12["skip_periods"], f12["skip_periods"] + f12["cycles"]
    cases = {"in_zone": f12["lam_in"], "above_zone": f12["lam_above"]}
    trs = {c: nondim_trajectory(fmu, {**nd, "chi": f12["chi"], "lam": lam}, t0, t1, spp, num)
           for c, lam in cases.items()}
    sticks = {c: _stick_phases_per_cycle(trs[c]["mode"], f12["cycles"]) for c in cases}

    # ---- Fig. 14: two nearby initial conditions ----
    nd14 = {**nd, "chi": f14["chi"], "lam": f14["lam"]}
    a, b, A_a, A_b = _bisect(ctx, nd14, np.asarray(f14["ic_a"], float), np.asarray(f14["ic_b"], float),
                             f14["periods"], f14["separation"], num)
    tr14 = [nondim_trajectory(fmu, {**nd14, "z0": float(ic[0]), "dz0": float(ic[1])}, 0.0, f14["periods"], spp, num)
            for ic in (a, b)]
    last_T = tr14[0]["cycles"] >= f14["periods"] - 1
    amp_traj = [0.5 * float(t["z"][last_T].max() - t["z"][last_T].min()) for t in tr14]
    ensure(all(abs(x - y) <= 1e-6 * max(abs(y), 1.0) for x, y in zip(amp_traj, (A_a, A_b))),
           f"the sampled trajectories end at amplitudes {amp_traj}, the bisection's runs at {[A_a, A_b]}")
    diff = np.abs(tr14[0]["dz"] - tr14[1]["dz"])
    scale = max(np.max(np.abs(tr14[0]["dz"])), 1e-300)
    part = np.nonzero(diff > 1e-2 * scale)[0]
    t_part = float(tr14[0]["cycles"][part[0]]) if part.size else float("nan")
    stuck0 = np.nonzero(tr14[0]["mode"] == 0)[0]
    t_first_stick = float(tr14[0]["cycles"][stuck0[0]]) if stuck0.size else float("nan")

    ds = xr.Dataset(
        {
            "z": (("case", "cycles"), np.stack([trs[c]["z"] for c in cases]), {"long_name": "z (Fig. 12, 13)"}),
            "dz": (("case", "cycles"), np.stack([trs[c]["dz"] for c in cases]), {"long_name": "z' (Fig. 12, 13)"}),
            "mode": (("case", "cycles"), np.stack([trs[c]["mode"] for c in cases])),
            "excitation": (("case", "cycles"), np.stack([trs[c]["excitation"] for c in cases])),
            "stick_phases_per_cycle": ("case", [sticks[c] for c in cases]),
            "z14": (("ic", "cycles14"), np.stack([t["z"] for t in tr14]), {"long_name": "z (Fig. 14)"}),
            "dz14": (("ic", "cycles14"), np.stack([t["dz"] for t in tr14]), {"long_name": "z' (Fig. 14)"}),
            "mode14": (("ic", "cycles14"), np.stack([t["mode"] for t in tr14])),
            "z0_14": ("ic", [a[0], b[0]]),
            "dz0_14": ("ic", [a[1], b[1]]),
            "amplitude14": ("ic", [A_a, A_b], {"long_name": "amplitude over the last period"}),
        },
        coords={"case": list(cases), "lam": ("case", list(cases.values())), "cycles": trs["in_zone"]["cycles"],
                "ic": ["a", "b"], "cycles14": tr14[0]["cycles"]},
        attrs={**{f"param_{k}": v for k, v in nd.items()}, "chi12": f12["chi"], "chi14": f14["chi"],
               "lam14": f14["lam"], "steps_per_period": num["steps_per_period"], "t_part_over_T": t_part,
               "t_first_stick_over_T": t_first_stick, "ic_distance": float(np.hypot(*(b - a)))},
    )
    ctx.save_dataset(ds, DATASET)

    labels = {"in_zone": "in the zone", "above_zone": "above the zone"}
    fig, axs = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    for ax, c in zip(axs, ("above_zone", "in_zone")):
        tr = trs[c]
        ax.plot(tr["cycles"], tr["dz"], color="C0", lw=1.1, label="z'")
        ax.plot(tr["cycles"], tr["excitation"], color="0.5", lw=0.8, ls="--", label="cos(lam tau)")
        ax.set_ylabel("z'")
        ax.grid(alpha=0.3)
        ax.set_title(f"({'a' if c == 'above_zone' else 'b'}) lambda = {cases[c]} ({labels[c]}): "
                     f"{sticks[c]:.0f} stick phases per cycle", fontsize=9)
    axs[0].legend(loc="upper right", fontsize=8)
    axs[-1].set_xlabel("t / T")
    fig.suptitle(f"Fig. 12: steady state after {f12['skip_periods']:g} periods from rest, chi = {f12['chi']}, "
                 f"mu_s sigma = {nd['mu_s_sigma']}", fontsize=10)
    ctx.save_figure(fig, FIGURES[0])

    fig, axs = plt.subplots(1, 2, figsize=(10, 4.5))
    for ax, c in zip(axs, ("above_zone", "in_zone")):
        tr = trs[c]
        ax.plot(tr["z"], tr["dz"], color="C0", lw=1.0)
        ax.axhline(0, color="0.7", lw=0.6)
        ax.set_xlabel("z")
        ax.set_ylabel("z'")
        ax.grid(alpha=0.3)
        ax.set_title(f"({'a' if c == 'above_zone' else 'b'}) lambda = {cases[c]} ({labels[c]})", fontsize=9)
    fig.suptitle(f"Fig. 13: phase portraits of the steady states, chi = {f12['chi']}", fontsize=10)
    ctx.save_figure(fig, FIGURES[1])

    fig, axs = plt.subplots(2, 1, figsize=(8, 6))
    c14 = tr14[0]["cycles"]
    show = c14 <= f14["show_periods"]
    last = c14 >= f14["periods"] - 2
    for i, (tr, ic, A) in enumerate(zip(tr14, (a, b), (A_a, A_b))):
        lab = f"z0 = {ic[0]:.7f}, z0' = {ic[1]:.7f} (amplitude {A:.3f})"
        axs[0].plot(c14[show], tr["dz"][show], lw=1.0 if i == 0 else 0.8, ls="-" if i == 0 else "--", label=lab)
        axs[1].plot(c14[last], tr["dz"][last], lw=1.0 if i == 0 else 0.8, ls="-" if i == 0 else "--")
    if np.isfinite(t_part):
        axs[0].axvline(t_part, color="C3", lw=0.7, ls=":", label=f"part at t = {t_part:.2f} T")
    axs[0].legend(fontsize=7, loc="upper right")
    axs[0].set_title(f"first {f14['show_periods']:g} periods", fontsize=9)
    axs[1].set_title(f"last 2 of {f14['periods']:g} periods: two different motions", fontsize=9)
    for ax in axs:
        ax.set_ylabel("z'")
        ax.set_xlabel("t / T")
        ax.grid(alpha=0.3)
    fig.suptitle(f"Fig. 14: two initial conditions {np.hypot(*(b - a)):.1e} apart, lambda = {f14['lam']}, "
                 f"chi = {f14['chi']}", fontsize=10)
    fig.tight_layout()
    ctx.save_figure(fig, FIGURES[2])

    ensure(sticks["in_zone"] > sticks["above_zone"], "the motion in the zone does not have more stick phases")
    ctx.log(f"fig12_14: stick phases per cycle {sticks['in_zone']:.1f} in the zone (lambda = {cases['in_zone']}), "
            f"{sticks['above_zone']:.1f} above it (lambda = {cases['above_zone']}); Fig. 14: initial conditions "
            f"{np.hypot(*(b - a)):.1e} apart end at amplitudes {A_a:.4f} and {A_b:.4f}, part at t = {t_part:.2f} T "
            f"(first stick at {t_first_stick:.2f} T)")
    return {"stick_in_zone": sticks["in_zone"], "stick_above_zone": sticks["above_zone"],
            "amplitude_a": A_a, "amplitude_b": A_b, "t_part": t_part, "t_first_stick": t_first_stick}


def bisection_steps(cfg: dict[str, Any]) -> int:
    """Halvings of Fig. 14's bisection: from ``ic_a``-``ic_b``'s distance down to ``separation``
    (at most 200, as :func:`_bisect`)."""
    f14 = cfg["fig14"]
    d = float(np.hypot(*(np.asarray(f14["ic_b"], float) - np.asarray(f14["ic_a"], float))))
    return min(200, max(0, math.ceil(math.log2(d / f14["separation"])))) if d > f14["separation"] else 0


def work(cfg: dict[str, Any]) -> Estimate:
    """The study's work and output size (:mod:`dryfriction.budget`): Fig. 12/13's two trajectories,
    Fig. 14's bisection (a run of ``fig14.periods`` per halving, two for its ends) and its two
    trajectories."""
    num, f12, f14, spp = cfg["numerics"], cfg["fig12"], cfg["fig14"], cfg["run"]["samples_per_period"]
    periods12 = f12["skip_periods"] + f12["cycles"]
    est = trajectory_estimate(Estimate(), "fig12 trajectories", 2, periods12, num, spp * f12["cycles"] / periods12)
    trajectory_estimate(est, "fig14 bisection", 2 + bisection_steps(cfg), f14["periods"], num)
    trajectory_estimate(est, "fig14 trajectories", 2, f14["periods"], num, spp)
    return est.add("figures", 0.0, FIGURE_BYTES * len(FIGURES))
