"""The frequency response's picture (the package's doc, dryfriction.analysis.response)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np


def plot_response(ds: Any, path: str | os.PathLike[str]) -> Path:
    """PNG: amplitude (m) vs f (Hz) with Den Hartog's and Inman's curves where they apply, and the
    stick share below; the orbit method: every orbit, stable ones filled on solid lines, unstable
    ones hollow on dashed lines; the transient method: unconverged points drawn hollow and labelled."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ...atomic import atomic_path

    f = ds["f_hz"].values
    amp = ds["amplitude_m"].values
    conv = ds["converged"].values.astype(bool)
    orbit = ds.attrs.get("method") == "orbit"
    fig, (ax, bx) = plt.subplots(2, 1, figsize=(7.5, 6.5), sharex=True, gridspec_kw={"height_ratios": [3, 1.3]})
    if orbit:   # every orbit: stable (and neutral: at rest) filled on solid lines, unstable hollow on dashed ones
        has = ds["has_orbit"].values
        st = ds["stable"].values | ds["neutral"].values
        un = has & ~st
        for j in range(amp.shape[1]):
            a = amp[:, j]
            ax.plot(f, np.where(st[:, j], a, np.nan), "-", color="C0", lw=1, zorder=1)
            ax.plot(f, np.where(un[:, j], a, np.nan), "--", color="C3", lw=1, zorder=1)
        ff = np.broadcast_to(f[:, None], amp.shape)
        ax.plot(ff[st], amp[st], "o", ms=4, color="C0", label="stable orbit (or at rest)", zorder=3)
        if un.any():
            ax.plot(ff[un], amp[un], "o", ms=5, mfc="none", mec="C3", mew=1.2,
                    label="unstable orbit", zorder=3)
    else:
        ax.plot(f, amp, "-", color="0.6", lw=1, zorder=1)
        ax.plot(f[conv], amp[conv], "o", ms=5, color="C0", label="FMU steady state (converged)", zorder=3)
        if (~conv).any():
            ax.plot(f[~conv], amp[~conv], "o", ms=6, mfc="none", mec="C3", mew=1.5,
                    label="not converged (last window)", zorder=3)
    if np.isfinite(ds["den_hartog_m"].values).any():
        ax.plot(f, ds["den_hartog_m"].values, "--", color="k", lw=1.3, label="Den Hartog (exact, non-stop, zeta = 0)")
    if np.isfinite(ds["inman_m"].values).any():
        ax.plot(f, ds["inman_m"].values, ":", color="C2", lw=1.6, label="Inman (approximate, stiction neglected)")
    fn = float(ds.attrs.get("natural_frequency_hz", np.nan))
    for a in (ax, bx):
        if f.min() <= fn <= f.max():
            a.axvline(fn, color="0.5", lw=0.8, ls="-.")
    if f.min() <= fn <= f.max():
        ax.text(fn, ax.get_ylim()[1] * 0.97, f" natural frequency {fn:.4g} Hz", va="top", fontsize=8, color="0.3")
    ax.set_ylabel("amplitude X (half peak-to-peak of x), m")
    ax.set_title(f"steady-state frequency response: m = {ds.attrs['param_m']:g} kg, k = {ds.attrs['param_k']:g} N/m, "
                 f"zeta = {ds.attrs['param_zeta']:.3g},\nP0 = {ds.attrs['param_P0']:g} N, N = {ds.attrs['param_N']:g} N, "
                 f"mu_s = {ds.attrs['param_mu_s']:g}, mu_k = {ds.attrs['param_mu_k']:.3g}", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    if orbit:
        sf = np.where(ds["stable"].values | ds["neutral"].values, ds["stick_fraction"].values, np.nan)
        for j in range(sf.shape[1]):
            bx.plot(f, 100 * sf[:, j], "s-", ms=3, color="C1", label="stuck share of the stable orbits" if j == 0 else None)
    else:
        bx.plot(f, 100 * ds["stick_fraction"].values, "s-", ms=4, color="C1", label="stuck share of the window")
    bx.set_ylabel("stuck, % of time")
    bx.set_xlabel("excitation frequency f, Hz")
    bx.set_ylim(-5, 105)
    bx.grid(alpha=0.3)
    bx.legend(fontsize=8, loc="best")
    fig.tight_layout()
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(out) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)
    return out
