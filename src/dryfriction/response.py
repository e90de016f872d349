"""Steady states that are steady, and the frequency response of an oscillator in physical units.

:func:`steady_state` runs the FMU from the initial conditions for n = ``min_periods``,
2 n, 4 n, ... excitation periods (one ``doStep`` each, the in-FMU observables over the last half of
the run, so that successive runs observe successive, adjacent windows [n/2, n] T and [n, 2n] T).
It stops when two successive windows agree:

    |A_j - A_{j-1}| <= tol A_j,   |o_j - o_{j-1}| <= tol A_j,   |s_j - s_{j-1}| <= tol_stick

(A the amplitude, half the peak-to-peak of x over the window, m; o the offset, the window's
mid-range, m; s the share of the window spent stuck), and reports ``converged = False`` with the
last window's values when ``max_periods`` is reached first. A window covers many periods, so
period-n motions and slow beats are compared as wholes. An undamped oscillator excited at its
resonance with 4 mu_k N < pi P0 never converges (the amplitude grows by (pi P0 - 4 mu_k N) / k
per period): it is reported so, never as a steady amplitude.

:func:`frequency_response` does this for a list of frequencies in Hz (in this process, or on Dask
workers for long sweeps) and returns an xarray Dataset with units; :func:`plot_response` draws it
with Den Hartog's and Inman's amplitudes where they apply and the stick share below.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from .fmu import FMUError, OscillatorFMU, Settings
from .params import Oscillator

__all__ = ["SteadyState", "steady_state", "frequency_response", "plot_response", "TOL", "TOL_STICK",
           "MIN_PERIODS", "MAX_PERIODS", "default_settings"]

#: relative agreement of successive windows (amplitude and offset, relative to the amplitude)
TOL = 1e-3
#: absolute agreement of the stick share of successive windows
TOL_STICK = 0.01
#: first run length and the period limit (excitation periods)
MIN_PERIODS = 32
MAX_PERIODS = 8192


@dataclass(frozen=True)
class SteadyState:
    """The steady state of one oscillator (SI units)."""

    amplitude: float        # half the peak-to-peak of x over the last window, m
    offset: float           # mid-range (x_max + x_min) / 2 over the last window, m
    x_max: float            # m
    x_min: float            # m
    stick_fraction: float   # share of the last window spent stuck
    converged: bool         # the last two windows agree within tol
    periods: float          # excitation periods run (the last run)
    change: float           # relative change of the amplitude between the last two windows

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def default_settings(p: Oscillator) -> Settings:
    """The exact scheme (closed form, h has no effect), with a spring or without (k = 0: a free
    mass on a rough support, exact_free.c)."""
    return Settings(h=0.0, scheme="exact")


def steady_state(fmu: OscillatorFMU, p: Oscillator, *, tol: float = TOL, tol_stick: float = TOL_STICK,
                 min_periods: int = MIN_PERIODS, max_periods: int = MAX_PERIODS,
                 settings: Settings | None = None) -> SteadyState:
    """Run until successive windows agree (see the module docstring); needs omega > 0."""
    if not p.omega > 0:
        raise ValueError(f"a steady state needs an excitation: omega must be > 0, not {p.omega!r}")
    if not (tol > 0 and tol_stick > 0):
        raise ValueError("tol and tol_stick must be > 0")
    if not (2 <= min_periods <= max_periods):
        raise ValueError(f"need 2 <= min_periods <= max_periods, not {min_periods}, {max_periods}")
    st = settings or default_settings(p)
    T = p.period
    prev: tuple[float, float, float] | None = None
    n = float(min_periods)
    while True:
        o = fmu.observables(p, n * T, 0.5 * n * T, settings=st)
        amp, off = 0.5 * (o["x_max"] - o["x_min"]), 0.5 * (o["x_max"] + o["x_min"])
        stick = float(o["stick_fraction"])
        change = math.inf
        converged = False
        if prev is not None:
            scale = max(amp, 1e-300)
            change = abs(amp - prev[0]) / scale
            converged = (change <= tol and abs(off - prev[1]) <= tol * scale and abs(stick - prev[2]) <= tol_stick)
        if amp == 0.0 and prev is not None and prev[0] == 0.0:
            converged, change = True, 0.0      # stuck for good: nothing moves
        if converged or 2 * n > max_periods:
            return SteadyState(amp, off, float(o["x_max"]), float(o["x_min"]), stick, converged, n, change)
        prev = (amp, off, stick)
        n *= 2


# ---- frequency response ---------------------------------------------------------------------------

def _chunk(fmu: str | bytes, base: Mapping[str, float], f_hz: np.ndarray, opts: Mapping[str, Any]) -> dict[str, np.ndarray]:
    """One Dask task (or an in-process chunk): steady states at the frequencies f_hz."""
    import time

    from .chaos.batch import fmu_for

    inst = fmu_for(fmu)
    t0 = time.process_time()
    rows, reasons = [], []
    for f in f_hz:
        p = Oscillator(**{**base, "omega": 2.0 * math.pi * float(f)})
        st = Settings(h=opts["h"], scheme=opts["scheme"]) if opts["scheme"] else default_settings(p)
        try:
            s = steady_state(inst, p, tol=opts["tol"], min_periods=opts["min_periods"],
                             max_periods=opts["max_periods"], settings=st)
        except FMUError as e:  # this frequency is not computed: its row says why, the sweep goes on
            rows.append((math.nan, math.nan, math.nan, 0.0, math.nan, math.nan))
            reasons.append(e.message)
            continue
        rows.append((s.amplitude, s.offset, s.stick_fraction, float(s.converged), s.periods, s.change))
        reasons.append("")
    out = np.array(rows, dtype=float).reshape(len(f_hz), 6)
    return {"rows": out, "reason": np.array(reasons, dtype=object), "cpu": np.array([time.process_time() - t0])}


def frequency_response(p: Oscillator, f_hz: Sequence[float] | np.ndarray, *, tol: float = TOL,
                       min_periods: int = MIN_PERIODS, max_periods: int = MAX_PERIODS, scheme: str | None = None,
                       h: float = 0.0, workers: int = 0, progress: bool = False,
                       fmu_path: str | os.PathLike[str] | None = None) -> Any:
    """Steady states of ``p`` at the excitation frequencies ``f_hz`` (Hz), as an xarray Dataset
    (dimension ``f_hz``; variables amplitude_m, offset_m, stick_fraction, converged, periods,
    change, reason, den_hartog_m, inman_m; attributes: the oscillator and the settings, with units).
    A frequency the FMU cannot compute gets NaN values, ``converged`` False and the FMU's
    sentence in ``reason``; the other frequencies go on.

    ``scheme`` None: exact (also at k = 0). ``workers`` > 0 runs
    the frequencies on a Dask LocalCluster of that many processes (for long sweeps)."""
    import xarray as xr

    from .chaos.batch import map_chunks
    from . import paths
    from .steady import den_hartog_amplitude, inman_amplitude

    f = np.asarray(f_hz, dtype=float)
    if f.ndim != 1 or f.size == 0 or not np.all(np.isfinite(f)) or np.any(f <= 0):
        raise ValueError("the frequencies must be a non-empty list of finite values > 0 Hz")
    path = paths.fmu_path(paths.OSCILLATOR, fmu_path)
    base = {k: v for k, v in p.as_dict().items() if k != "omega"}
    opts = {"tol": tol, "min_periods": min_periods, "max_periods": max_periods, "scheme": scheme, "h": h}
    per_chunk = max(1, min(16, math.ceil(f.size / max(1, 4 * workers)))) if workers else max(1, min(8, f.size))
    chunks = [(base, f[i:i + per_chunk], opts) for i in range(0, f.size, per_chunk)]
    results, _ = map_chunks(_chunk, path, chunks, workers=workers, progress=progress, desc="response")
    rows = np.concatenate([r["rows"] for r in results], axis=0)
    reason = np.concatenate([r["reason"] for r in results]).astype(str)
    lam = 2.0 * math.pi * f / p.w0 if p.k > 0 else np.full(f.shape, np.inf)
    applies = p.k > 0 and p.c == 0 and p.P0 != 0
    dh = np.asarray(den_hartog_amplitude(p, lam), dtype=float) if applies else np.full(f.shape, np.nan)
    inm = np.asarray(inman_amplitude(p, lam), dtype=float) if applies else np.full(f.shape, np.nan)
    ds = xr.Dataset(
        {
            "amplitude_m": ("f_hz", rows[:, 0], {"units": "m", "long_name": "amplitude, half peak-to-peak of x"}),
            "offset_m": ("f_hz", rows[:, 1], {"units": "m", "long_name": "offset, (x_max + x_min) / 2"}),
            "stick_fraction": ("f_hz", rows[:, 2], {"units": "1", "long_name": "share of the window stuck"}),
            "converged": ("f_hz", rows[:, 3].astype(bool),
                          {"long_name": f"successive windows agree within {tol:g} (relative)"}),
            "periods": ("f_hz", rows[:, 4], {"units": "1", "long_name": "excitation periods run"}),
            "change": ("f_hz", rows[:, 5], {"units": "1", "long_name": "relative amplitude change, last two windows"}),
            "reason": ("f_hz", reason, {"long_name": "why the point was not computed (the FMU's sentence; "
                                                     "empty where it was)"}),
            "den_hartog_m": ("f_hz", dh, {"units": "m", "long_name": "Den Hartog (zeta = 0, non-stop), exact"}),
            "inman_m": ("f_hz", inm, {"units": "m", "long_name": "Inman (equivalent viscous damping), approximate"}),
        },
        coords={"f_hz": ("f_hz", f, {"units": "Hz", "long_name": "excitation frequency"})},
        attrs={**{f"param_{k}": v for k, v in p.as_dict().items() if k != "omega"},
               "param_mu_k": p.mu_k, "param_zeta": p.zeta, "natural_frequency_hz": p.f_n_hz,
               "units": "SI: m, kg, N, s, Hz", "tol": tol, "tol_stick": TOL_STICK, "min_periods": min_periods,
               "max_periods": max_periods, "scheme": scheme or "exact",
               "never_converges": never_converges_note(p)},
    )
    return ds


def never_converges_note(p: Oscillator) -> str:
    """A sentence when the oscillator has an unbounded resonance (c = 0, 4 mu_k N < pi P0), else ''."""
    if p.c == 0 and p.k > 0 and 4.0 * p.mu_k * p.N < math.pi * abs(p.P0):
        return (f"undamped with 4 mu_k N = {4 * p.mu_k * p.N:.4g} N < pi P0 = {math.pi * abs(p.P0):.4g} N: "
                f"at the natural frequency {p.f_n_hz:.6g} Hz the amplitude grows without bound "
                "(never converges)")
    return ""


def plot_response(ds: Any, path: str | os.PathLike[str]) -> Path:
    """PNG: amplitude (m) vs f (Hz) with Den Hartog's and Inman's curves where they apply, and the
    stick share below; unconverged points drawn hollow and labelled."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .atomic import atomic_path

    f = ds["f_hz"].values
    amp = ds["amplitude_m"].values
    conv = ds["converged"].values.astype(bool)
    fig, (ax, bx) = plt.subplots(2, 1, figsize=(7.5, 6.5), sharex=True, gridspec_kw={"height_ratios": [3, 1.3]})
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


def with_omega(p: Oscillator, f_hz: float) -> Oscillator:
    return replace(p, omega=2.0 * math.pi * f_hz)
