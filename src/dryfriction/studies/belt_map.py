"""Self-excited stick-slip over belt speed x normal force: at each grid point the periodic orbit of
the autonomous belt oscillator (dryfriction.analysis.self_excited; docs/self_excited.md), its amplitude,
period and stick share, or steady sliding, with the analytic Hopf line v*(N) drawn (Stribeck,
delta = 1: v* = v_s ln(N (mu_s - mu_k) / (c v_s))).

Each normal force is a row walked up in belt speed: a point's orbit is Newton's from the previous
point's stable orbit (warm start); where that fails or is not stable, from a transient that starts
riding on the belt at x_eq (:func:`~dryfriction.analysis.self_excited.motion.self_excited`); where the orbit solve
fails there too, the transient's last quarter gives the numbers, and the data says so (``motion`` 3,
``method`` per point). With ``numerics.grazing`` the end of stick-slip per N is located too, by
continuation in v_belt from the row's slowest stick-slip orbit (``grazing_v_belt``, the red line).
Runs in this process (a point costs a few FMU runs of a period).
"""

from __future__ import annotations

import inspect
import math
from typing import Any

import numpy as np
import xarray as xr
from matplotlib.colors import LogNorm

from ..references.belt import hopf_belt_speed
from ..budget import SAMPLE_STEPS, fmt
from ..params import Oscillator
from ..analysis.self_excited import BeltProblem, LAWS, continue_orbits, find_orbit, self_excited, transient
from .common import FIGURE_BYTES, Estimate, StudyContext, plt
from .config import grid, require
from . import REGISTRY

NAME = "belt_map"
TITLE = REGISTRY[NAME].title
FIGURES = REGISTRY[NAME].figures

#: ``motion`` codes of the dataset
MOTIONS = {0: "steady sliding", 1: "stick-slip orbit", 2: "slip orbit", 3: "transient (the orbit solve failed)"}


def check(cfg: dict[str, Any]) -> None:
    """Refuse a configuration of the belt map with a value out of range (ConfigError naming the key), before
    any work."""
    p, g, n = cfg["params"], cfg["grid"], cfg["numerics"]
    for key in ("m", "k", "mu_s"):
        require(p[key] > 0, f"params.{key} must be > 0, not {p[key]}")
    for key in ("c", "mu_k"):
        require(p[key] >= 0, f"params.{key} must be >= 0, not {p[key]}")
    require(p["law"] in LAWS, f"params.law must be one of {', '.join(LAWS)}, not {p['law']!r}")
    require(p["v_s"] > 0, f"params.v_s must be > 0, not {p['v_s']}")
    require(p["delta"] >= 1, f"params.delta must be >= 1, not {p['delta']}")
    for key in ("v_belt", "N"):
        require(g[key]["num"] >= 1, f"grid.{key}.num must be >= 1, not {g[key]['num']}")
    vb = grid(g["v_belt"], "grid.v_belt")
    require(bool(np.all(vb > 0)), f"grid.v_belt must be > 0 (one direction of the belt), not {g['v_belt']}")
    N = grid(g["N"], "grid.N")
    require(bool(np.all(N > 0)), f"grid.N must be > 0, not {g['N']}")
    require(n["steps_per_period"] >= 20, f"numerics.steps_per_period must be >= 20, not {n['steps_per_period']}")
    require(n["transient_periods"] >= 5, f"numerics.transient_periods must be >= 5, not {n['transient_periods']}")
    require(isinstance(n["grazing"], bool), f"numerics.grazing must be true or false, not {n['grazing']!r}")


def problem(p: dict[str, Any], N: float, vb: float, steps: int) -> BeltProblem:
    """The belt problem of the map's point (normal force ``N``, belt speed ``vb``) with ``steps`` steps per
    natural period."""
    osc = Oscillator(m=p["m"], k=p["k"], c=p["c"], P0=0.0, omega=0.0, phi=0.0, N=N, mu_s=p["mu_s"],
                     chi=p["mu_k"] / p["mu_s"], x0=0.0, v0=0.0)
    return BeltProblem(osc, vb, law=p["law"], v_s=p["v_s"], delta=p["delta"],
                       h=2.0 * math.pi / math.sqrt(p["k"] / p["m"]) / steps)


def point(fmu: Any, prob: BeltProblem, warm: tuple[float, float] | None, periods: float) -> dict[str, Any]:
    """One grid point: the orbit (warm started, else from a transient), or steady sliding, or the
    transient's numbers."""
    res = None
    method = ""
    if warm is not None:
        o = find_orbit(prob, warm[0], warm[1], fmu=fmu)
        if o.converged and o.stable:
            method = "orbit, warm start"
            res = self_excited(prob, fmu=fmu, guess=(o.v0, o.period))
    if res is None:
        res = self_excited(prob, fmu=fmu, periods=periods)
        method = "orbit, from a transient"
    eq = res.equilibrium
    row = {"eq_mu_max": eq.mu_max, "eq_stable": bool(eq.stable), "residual": math.nan, "mu": math.nan,
           "amplitude": 0.0, "offset": eq.x_eq, "period": math.nan, "stick_fraction": 0.0}
    if res.motion in ("stick-slip", "slip orbit"):
        o = res.orbit
        assert o is not None
        row.update(motion=1 if o.sticks else 2, amplitude=o.amplitude, offset=o.offset, period=o.period,
                   stick_fraction=o.stick_fraction, residual=o.residual, mu=abs(o.multipliers[1]))
        return {**row, "method": method, "warm": (o.v0, o.period)}
    if res.motion == "steady sliding":
        return {**row, "motion": 0, "method": "steady sliding: " + res.reason, "warm": None}
    tr = transient(prob, periods=periods, fmu=fmu)
    w = tr.window()
    row.update(motion=3, amplitude=w["amplitude"], offset=w["offset"], period=w["period"],
               stick_fraction=w["stick_fraction"])
    return {**row, "method": f"transient of {periods:g} natural periods, last quarter (the orbit solve: {res.reason})",
            "warm": None}


def run(ctx: StudyContext) -> dict[str, Any]:
    """Run the belt map: its runs, dataset and figures in the study's folder; returns the summary."""
    from tqdm import tqdm

    cfg = ctx.cfg
    p, g, n = cfg["params"], cfg["grid"], cfg["numerics"]
    vb = grid(g["v_belt"], "grid.v_belt")
    Ns = grid(g["N"], "grid.N")
    shape = (Ns.size, vb.size)
    names = ("amplitude", "offset", "period", "stick_fraction", "motion", "mu", "eq_mu_max", "eq_stable", "residual")
    data = {k: np.full(shape, np.nan) for k in names if k != "eq_stable"}
    data["eq_stable"] = np.zeros(shape, dtype=bool)     # every point's is computed
    methods = np.empty(shape, dtype=object)
    fmu = ctx.fmu()
    bar = tqdm(total=Ns.size * vb.size, desc=NAME, unit=" points", disable=not ctx.engine_options.progress,
               leave=False)
    try:
        for i, N in enumerate(Ns):
            warm = None
            for j, v in enumerate(vb):
                r = point(fmu, problem(p, float(N), float(v), int(n["steps_per_period"])), warm,
                          float(n["transient_periods"]))
                warm = r["warm"]
                for k in names:
                    data[k][i, j] = r[k]
                methods[i, j] = r["method"]
                bar.update()
    finally:
        bar.close()
    hopf = np.array([hopf_belt_speed(p["c"], float(N), p["mu_s"], p["mu_k"], p["v_s"])
                     if p["law"] == "stribeck" and p["delta"] == 1.0 else math.nan for N in Ns])
    grazing = np.full(Ns.size, np.nan)
    if n["grazing"]:
        # where stick-slip ends, by continuation of each row's slowest stick-slip orbit (its leg only)
        for i, N in enumerate(Ns):
            j = next((j for j in range(vb.size) if data["motion"][i, j] == 1), None)
            if j is None:
                continue
            try:
                br = continue_orbits(problem(p, float(N), float(vb[j]), int(n["steps_per_period"])), float(vb[j]),
                                     float(vb[j]), 10.0 * float(vb.max()), fmu=fmu, slip_leg=False)
            except RuntimeError as e:
                ctx.log(f"belt_map: N = {N:g}: no continuation from v_belt {vb[j]:g}: {e}")
                continue
            grazing[i] = br.grazing
    units = {"amplitude": "m", "offset": "m", "period": "s", "stick_fraction": "1", "motion": "1", "mu": "1",
             "eq_mu_max": "1", "residual": "1"}
    desc = {"amplitude": "(x_max - x_min) / 2 of the orbit (0: steady sliding)",
            "period": "period of the orbit (NaN: steady sliding)",
            "motion": "; ".join(f"{k} {v}" for k, v in MOTIONS.items()),
            "mu": "|nontrivial Floquet multiplier| (0 with a stick phase)",
            "eq_mu_max": "largest |multiplier| of steady sliding's flow over a natural period",
            "eq_stable": "steady sliding stable (True) or not", "residual": "scaled Newton residual of the orbit"}
    ds = xr.Dataset({k: (("N", "v_belt"), data[k], {**({"units": units[k]} if k in units else {}),
                                                    "description": desc.get(k, "")})
                     for k in names},
                    coords={"N": ("N", Ns, {"units": "N"}), "v_belt": ("v_belt", vb, {"units": "m/s"})})
    ds["method"] = (("N", "v_belt"), methods.astype(str))
    ds["hopf_v_belt"] = ("N", hopf, {"units": "m/s", "description": "v*(N) = v_s ln(N (mu_s - mu_k) / (c v_s))"})
    ds["grazing_v_belt"] = ("N", grazing, {"units": "m/s", "description": "the end of stick-slip (the catch grazes), "
                                                                         "by continuation in v_belt (NaN: not computed)"})
    ds.attrs.update({f"param_{k}": v for k, v in p.items()})
    ds.attrs["steps_per_period"] = int(n["steps_per_period"])
    ctx.save_dataset(ds, "belt_map.nc")

    fig, axes = plt.subplots(1, 2, figsize=(12, 4.6), sharey=True)
    for ax, key, label in ((axes[0], "amplitude", "amplitude (m)"), (axes[1], "period", "period (s, log scale)")):
        z = np.where(data["motion"] == 0, np.nan, data[key])
        norm = LogNorm() if key == "period" and np.nanmin(z, initial=np.inf) > 0 and np.isfinite(z).any() else None
        if vb.size > 1 and Ns.size > 1:
            mesh = ax.pcolormesh(vb, Ns, z, shading="nearest", cmap="viridis", norm=norm)
            fig.colorbar(mesh, ax=ax, label=label)
        else:
            sc = ax.scatter(np.tile(vb, Ns.size), np.repeat(Ns, vb.size), c=z.ravel(), cmap="viridis", norm=norm)
            fig.colorbar(sc, ax=ax, label=label)
        still = data["motion"] == 0
        ax.plot(np.tile(vb, Ns.size)[still.ravel()], np.repeat(Ns, vb.size)[still.ravel()], ".", color="0.6", ms=3,
                label="steady sliding")
        tr = data["motion"] == 3
        if tr.any():
            ax.plot(np.tile(vb, Ns.size)[tr.ravel()], np.repeat(Ns, vb.size)[tr.ravel()], "rx", ms=5,
                    label="transient (no orbit solve)")
        if np.isfinite(hopf).any():
            ax.plot(hopf, Ns, "w--", lw=1.5, label="Hopf line v*(N)")
            ax.plot(hopf, Ns, "k:", lw=1.0)
        if np.isfinite(grazing).any():
            ax.plot(grazing, Ns, "-", color="C3", lw=1.2, label="end of stick-slip (continuation)")
        ax.set_xlim(vb.min() - 0.02 * np.ptp(vb), vb.max() + 0.02 * np.ptp(vb))
        ax.set_xlabel("belt speed v_belt (m/s)")
        ax.legend(fontsize=7, loc="upper left")
    axes[0].set_ylabel("normal force N (N)")
    fig.suptitle(f"self-excited motion on a belt ({p['law']}, m = {p['m']:g}, k = {p['k']:g}, c = {p['c']:g}, "
                 f"mu_s = {p['mu_s']:g}, mu_k = {p['mu_k']:g}, v_s = {p['v_s']:g}, delta = {p['delta']:g})\n"
                 "coloured: the stable orbit; grey dots: steady sliding only; steady sliding is unstable left of the "
                 "Hopf line, and stick-slip coexists with it right of the line (subcritical Hopf)", fontsize=8)
    ctx.save_figure(fig, "belt_map.png")

    motion = data["motion"]
    edge = []
    for i in range(Ns.size):
        s = np.nonzero(motion[i] == 1)[0]
        edge.append(float(vb[s.max()]) if s.size else math.nan)
    summary = {
        "points": int(motion.size),
        "stick_slip": int(np.sum(motion == 1)), "slip_orbit": int(np.sum(motion == 2)),
        "steady_sliding": int(np.sum(motion == 0)), "transient": int(np.sum(motion == 3)),
        "warm_started": int(sum("warm start" in str(m) for m in methods.ravel())),
        "max_amplitude_m": float(np.nanmax(data["amplitude"])),
        "hopf_v_belt": [float(h) for h in hopf],
        "stick_slip_edge_v_belt": edge,
        "grazing_v_belt": [float(v) for v in grazing],
        "N": [float(v) for v in Ns],
    }
    ctx.log(f"belt_map: {summary['stick_slip']} stick-slip, {summary['slip_orbit']} slip orbits, "
            f"{summary['steady_sliding']} steady sliding, {summary['transient']} transients of {motion.size} points; "
            f"stick-slip up to v_belt {edge} at N {summary['N']} (Hopf line {summary['hopf_v_belt']})")
    return summary


#: natural periods of Newton's orbit solve at a point, typically (a few iterations, each the orbit
#: and its variations), and per point of the grazing continuation
NEWTON_ORBIT_PERIODS = 10.0
#: points of a row's grazing continuation, at most (continue_orbits' max_points)
GRAZING_POINTS: int = inspect.signature(continue_orbits).parameters["max_points"].default


def work(cfg: dict[str, Any]) -> Estimate:
    """The study's work and output size (:mod:`dryfriction.budget`): per grid point, a transient
    of at least ``transient_periods`` natural periods (longer at low belt speed: five estimated
    stick-slip cycles, as :func:`~dryfriction.analysis.self_excited.motion.self_excited`) and Newton's solve, in
    orbit periods (a natural period and the ride on the belt); per N, the grazing continuation."""
    p, g, n = cfg["params"], cfg["grid"], cfg["numerics"]
    vb, Ns = grid(g["v_belt"], "grid.v_belt"), grid(g["N"], "grid.N")
    spp = float(n["steps_per_period"])
    Tn = 2.0 * math.pi * math.sqrt(p["m"] / p["k"])
    # an orbit's length in natural periods: 1 + the ride from the catch to the breakaway
    cycle = 1.0 + 2.0 * abs(p["mu_s"] - p["mu_k"]) * Ns[:, None] / (p["k"] * vb[None, :]) / Tn
    sampled = np.maximum(float(n["transient_periods"]), 5.0 * cycle)     # the transient, sampled
    periods = sampled + NEWTON_ORBIT_PERIODS * cycle
    samples = float(sampled.sum()) * inspect.signature(transient).parameters["samples"].default
    est = Estimate().add(f"{vb.size * Ns.size} points x about {float(periods.mean()):,.0f} natural periods x "
                         f"{spp:g} steps, {fmt(samples)} samples", float(periods.sum()) * spp + samples * SAMPLE_STEPS,
                         vb.size * Ns.size * 10 * 8 + 200.0 * vb.size * Ns.size)
    if n["grazing"]:
        est.add(f"grazing: {Ns.size} continuations x {GRAZING_POINTS} points x about {NEWTON_ORBIT_PERIODS:g} "
                f"orbit periods x {spp:g} steps",
                Ns.size * GRAZING_POINTS * NEWTON_ORBIT_PERIODS * float(cycle.mean()) * spp)
    return est.add("figures", 0.0, FIGURE_BYTES * len(FIGURES))
