"""The study's figures (PNG, written atomically): error vs CPU time per case, error vs h with the
fitted order, and how the cost grows."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from dryfriction.atomic import atomic_path  # noqa: E402

SCHEME_COLORS = {"located": "tab:blue", "consistent": "tab:green", "paper": "tab:red", "exact": "black"}
ALPHA_STYLES = {-0.1: "-", 0.0: "--", -1.0 / 3.0: ":"}
PEER_COLORS = {"event RK45": "tab:orange", "event DOP853": "tab:brown", "event Radau": "tab:purple",
               "tanh Radau": "tab:gray", "tanh LSODA": "tab:olive"}
PEER_MARKERS = {"event RK45": "s", "event DOP853": "D", "event Radau": "^", "tanh Radau": "v", "tanh LSODA": "x"}
# Siconos runs the cases at chi = 1 only (its relay law has one coefficient): drawn with the FMU at chi = 1
SICONOS_STYLES = {"Siconos theta=0.5": ("tab:cyan", "o", "-"), "Siconos theta=1": ("tab:pink", "o", "-"),
                  "FMU located": ("tab:blue", "o", "--")}


def alpha_label(a: float) -> str:
    return "-1/3" if abs(a + 1.0 / 3.0) < 1e-12 else f"{a:g}"


def save(fig: plt.Figure, path: Path) -> None:
    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format="png", dpi=100)
    finally:
        plt.close(fig)


def _grid(n: int) -> tuple[plt.Figure, list[plt.Axes]]:
    cols = 3
    rows = (n + 1 + cols - 1) // cols  # one extra panel for the legend
    fig, axes = plt.subplots(rows, cols, figsize=(5.0 * cols, 4.0 * rows))
    return fig, list(np.ravel(axes))


def error_vs_cpu(rows: Sequence[dict], cases: Sequence[str], path: Path,
                 siconos: Sequence[dict] | None = None) -> None:
    """log-log error vs seconds per period, one line per method, one panel per case; Siconos (rows
    of siconos.csv, the same case at chi = 1) with the FMU's located scheme at chi = 1, thin lines."""
    fig, axes = _grid(len(cases))
    handles: dict[str, object] = {}
    for ax, case in zip(axes, cases):
        sel = [r for r in rows if r["case"] == case and np.isfinite(r["error_z"]) and r["error_z"] > 0]
        fmu = [r for r in sel if r["family"] == "fmu"]
        for (scheme, alpha) in sorted({(r["scheme"], r["alpha"]) for r in fmu}):
            if alpha != -0.1 and scheme != "located":
                continue  # keep the panel readable: other alphas of the other schemes are in the CSV
            pts = sorted((r["us_per_period"], r["error_z"]) for r in fmu
                         if r["scheme"] == scheme and r["alpha"] == alpha)
            x, y = zip(*pts)
            lab = "FMU exact" if scheme == "exact" else f"FMU {scheme} (a={alpha_label(alpha)})"
            (h,) = ax.loglog(x, y, ALPHA_STYLES.get(alpha, "-"), color=SCHEME_COLORS[scheme],
                             marker="*" if scheme == "exact" else ".", ms=12 if scheme == "exact" else 6,
                             lw=1.8 if alpha == -0.1 else 1.0, label=lab)
            handles.setdefault(lab, h)
        for m in PEER_COLORS:
            pts = sorted((r["us_per_period"], r["error_z"]) for r in sel if r["method"] == m)
            if not pts:
                continue
            x, y = zip(*pts)
            (h,) = ax.loglog(x, y, "-", color=PEER_COLORS[m], marker=PEER_MARKERS[m], ms=5, lw=1.2, label=m)
            handles.setdefault(m, h)
        for m, (color, marker, ls) in SICONOS_STYLES.items():
            pts = sorted((r["us_per_period"], r["error_z"]) for r in (siconos or []) if r["case"] == case
                         and r["method"] == m and np.isfinite(r["error_z"]) and r["error_z"] > 0)
            if not pts:
                continue
            x, y = zip(*pts)
            lab = f"{m} (case at chi = 1)"
            (h,) = ax.loglog(x, y, ls, color=color, marker=marker, ms=4, mfc="none", lw=0.9, label=lab)
            handles.setdefault(lab, h)
        ax.axhline(1e-6, color="k", lw=0.6, ls=":")
        ax.set_title(case)
        ax.set_xlabel("CPU time per excitation period (us)")
        ax.set_ylabel("max |z - z_exact|  (z = k x / P0)")
        ax.grid(True, which="major", alpha=0.3)
    for ax in axes[len(cases):]:
        ax.axis("off")
    axes[len(cases)].legend(list(handles.values()), list(handles.keys()), loc="center", fontsize=8)
    fig.suptitle("What accuracy costs: error vs CPU time (FMU through fmpy, reused instance; scipy peers; "
                 "Siconos and the FMU at chi = 1, process CPU time)")
    fig.tight_layout()
    save(fig, path)


def error_vs_h(rows: Sequence[dict], orders: Sequence[dict], cases: Sequence[str], path: Path) -> None:
    """log-log error vs h/T per scheme and alpha, with the fitted order in the legend."""
    fig, axes = _grid(len(cases))
    for ax, case in zip(axes, cases):
        fmu = [r for r in rows if r["case"] == case and r["family"] == "fmu"]
        for (scheme, alpha) in sorted({(r["scheme"], r["alpha"]) for r in fmu if r["scheme"] != "exact"}):
            pts = sorted((1.0 / r["steps_per_period"], r["error_z"]) for r in fmu
                         if r["scheme"] == scheme and r["alpha"] == alpha and r["error_z"] > 0)
            if not pts:
                continue
            x, y = zip(*pts)
            o = next((q for q in orders if q["case"] == case and q["scheme"] == scheme and q["alpha"] == alpha), None)
            order = f"{o['order']:.2f}" if o and np.isfinite(o["order"]) else "n/a"
            ax.loglog(x, y, ALPHA_STYLES.get(alpha, "-"), color=SCHEME_COLORS[scheme], marker=".",
                      lw=1.6 if alpha == -0.1 else 1.0, label=f"{scheme} a={alpha_label(alpha)}: p={order}")
        xs = np.array(sorted({1.0 / r["steps_per_period"] for r in fmu}))
        if xs.size:
            ref = [r["error_z"] for r in fmu if r["scheme"] == "located" and r["alpha"] == -0.1
                   and 1.0 / r["steps_per_period"] == xs[-1]]
            if ref:
                ax.loglog(xs, 0.3 * ref[0] * (xs / xs[-1]) ** 2, color="k", lw=0.6, ls="-.", label="slope 2")
        ax.set_title(case)
        ax.set_xlabel("h / T")
        ax.set_ylabel("max |z - z_exact|")
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=6.5, ncol=1)
    for ax in axes[len(cases):]:
        ax.axis("off")
    fig.suptitle("Error vs step (p = least-squares order over h <= T/100)")
    fig.tight_layout()
    save(fig, path)


def cost_growth(scaling: Sequence[dict], path: Path, bare_ns: float | None) -> None:
    """Time vs periods, time vs steps per period, Dask throughput vs workers."""
    fig, (a1, a2, a3) = plt.subplots(1, 3, figsize=(15, 4.2))
    per = sorted((r for r in scaling if r["kind"] == "periods"), key=lambda r: r["x"])
    if per:
        x = np.array([r["x"] for r in per], float)
        a1.loglog(x, [r["seconds_api"] * 1e6 for r in per], "o-", label="OscillatorFMU2 API")
        a1.loglog(x, [r["seconds_lean"] * 1e6 for r in per], "s--", label="lean fmi2 calls")
        if bare_ns:
            a1.loglog(x, x * per[0]["steps"] / per[0]["x"] * bare_ns * 1e-3, "k:",
                      label="bare C stepper (ns/step x steps)")
        a1.set_xlabel("periods simulated")
        a1.set_ylabel("time per run (us)")
        a1.set_title("time vs number of periods (h = T/%d)" % round(per[0]["steps"] / per[0]["x"]))
        a1.legend(fontsize=8)
        a1.grid(True, alpha=0.3)
    spp = sorted((r for r in scaling if r["kind"] == "steps_per_period"), key=lambda r: r["x"])
    if spp:
        x = np.array([r["x"] for r in spp], float)
        a2.loglog(x, [r["seconds_api"] * 1e6 for r in spp], "o-", label="OscillatorFMU2 API")
        a2.loglog(x, [r["seconds_lean"] * 1e6 for r in spp], "s--", label="lean fmi2 calls")
        a2.set_xlabel("internal steps per period")
        a2.set_ylabel("time per run (us)")
        a2.set_title("time vs steps per period (%d periods)" % round(spp[0]["steps"] / spp[0]["x"]))
        a2.legend(fontsize=8)
        a2.grid(True, alpha=0.3)
    dk = sorted((r for r in scaling if r["kind"] == "dask"), key=lambda r: r["x"])
    if dk:
        a3.plot([r["x"] for r in dk], [r["runs_per_second"] for r in dk], "o-")
        a3.set_xticks([r["x"] for r in dk])
        a3.set_xlabel("Dask workers (1 thread each, one FMU instance each)")
        a3.set_ylabel("runs per second")
        a3.set_ylim(bottom=0)
        a3.set_title("sweep throughput vs workers")
        a3.grid(True, alpha=0.3)
    fig.tight_layout()
    save(fig, path)
