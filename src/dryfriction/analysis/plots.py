"""Plot helpers shared by the analyses, the studies and the commands (matplotlib is imported by
the caller, which owns the figure)."""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["plot_branches", "LABELS", "MARKERS"]

#: the short label and the marker of each kind of bifurcation on a branch plot
LABELS = {"fold": "F", "period_doubling": "PD", "symmetry_breaking": "SB", "grazing": "G"}
MARKERS = {"fold": "s", "period_doubling": "D", "symmetry_breaking": "o", "grazing": "^"}


def plot_branches(axes: Any, c: Any, scale: float, label: bool = True) -> None:
    """Amplitude (upper axes) and offset (lower) of every branch, stable solid, unstable dashed,
    bifurcations marked and labelled; lengths times ``scale``."""
    ds = c.dataset
    for b in c.branches:
        s = ds.where((ds.branch == b.id) & ds.converged, drop=True)
        if s.point.size == 0:
            continue
        x = s.param.values
        st = s.stable.values.astype(bool)
        color = f"C{b.id % 10}"
        for ax, var in zip(axes, ("amplitude_m", "offset_m")):
            y = s[var].values * scale
            for mask, ls in ((st, "-"), (~st, "--")):
                # join each run to its neighbours so that a change of stability leaves no gap
                edge = mask | np.concatenate([mask[1:], [False]]) | np.concatenate([[False], mask[:-1]])
                yy = np.where(edge, y, np.nan)
                ax.plot(x, yy, ls=ls, color=color, lw=1.4,
                        label=(f"branch {b.id} (K = {b.period}{', symmetric' if b.kind == 'symmetric' else ''})"
                               if (ls == "-" and var == "amplitude_m" and label) else None))
    for f in c.bifurcations:
        for ax, y in zip(axes, (f.amplitude_m * scale, f.offset_m * scale)):
            ax.plot([f.param], [y], MARKERS[f.type], color="k", ms=6, mfc="none")
            ax.annotate(f"{LABELS[f.type]} {f.param:.5g}", (f.param, y), textcoords="offset points", xytext=(4, 4),
                        fontsize=7)
