"""frequency_response: the steady states of one oscillator over a list of frequencies, by either
method, in this process or on Dask workers in chunks, as an xarray Dataset; the work it will take
(the package's doc, dryfriction.analysis.response)."""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from ...budget import check_memory, check_work
from ...params import Oscillator
from .orbit import COLD_EVERY, ORBIT_COLUMNS, ORBIT_FLAGS, _orbit_chunk
from .transient import MAX_PERIODS, MIN_PERIODS, TOL, TOL_STICK, _chunk

METHODS = ("orbit", "transient")


def frequency_response(p: Oscillator, f_hz: Sequence[float] | np.ndarray, *, method: str | None = None,
                       tol: float = TOL, min_periods: int = MIN_PERIODS, max_periods: int = MAX_PERIODS,
                       scheme: str | None = None, h: float = 0.0, period: int = 1, transients: int = 60,
                       cold_every: int = COLD_EVERY, workers: int = 0, progress: bool = False,
                       fmu_path: str | os.PathLike[str] | None = None, max_work: float | None = None,
                       dof: int | None = None, symmetry: Any = None) -> Any:
    """Steady states of ``p`` at the excitation frequencies ``f_hz`` (Hz), as an xarray Dataset
    (dimension ``f_hz``; attributes: the oscillator and the settings, with units).

    ``p`` a structure (:class:`~dryfriction.system.structure.System`): its response by orbits on the located map
    (:func:`dryfriction.analysis.system_response.system_frequency_response`: dimensions ``f_hz``,
    ``dof``, ``contact``; ``dof`` the DOF whose amplitude is ``amplitude_dof_m``; ``symmetry`` a
    :class:`~dryfriction.system.symmetry.CyclicSymmetry` of it; ``period``, ``transients``,
    ``progress`` and ``fmu_path`` apply, the transient method's settings do not).

    ``method`` ``"orbit"`` (the default, unless a Bossak ``scheme`` is asked for: the orbits need the
    exact scheme's Jacobian): every periodic orbit of ``period`` excitation periods found
    (:func:`dryfriction.analysis.orbits.find_orbits`; the previous frequency's orbits are the next one's
    guesses, ``transients`` the length of the cold searches' transients, ``cold_every`` their
    spacing in frequencies besides the first one and where no stable orbit is found), along a second dimension
    ``orbit``: period, stable, neutral, mu_max, amplitude_m, offset_m, stick_fraction, x0_m,
    v0_m_per_s, residual, rest_from_m, rest_to_m (the block at rest: one orbit, amplitude 0, ``neutral``,
    with the interval of its rest positions); ``n_orbits`` and ``converged`` (at least one stable orbit,
    or the block at rest) per frequency. The padding of ``orbit`` (fewer orbits than the widest
    frequency's) is the bool mask ``has_orbit``: the numbers are NaN there and the bool variables
    ``stable``, ``neutral`` False (they stay bool: NaN would make them floats, None objects, which NetCDF
    cannot hold).

    ``method`` ``"transient"``: :func:`steady_state` (variables amplitude_m, offset_m, stick_fraction,
    converged, periods, change, error).

    Both: reason, den_hartog_m, inman_m. A frequency the FMU cannot compute gets NaN values,
    ``converged`` False and the FMU's sentence in ``reason``; the other frequencies go on.

    ``scheme`` None: exact (also at k = 0). ``workers`` > 0 runs
    the frequencies on a Dask LocalCluster of that many processes (for long sweeps), streamed in
    chunks of at most :data:`MAX_CHUNK` frequencies.

    The work is estimated before it starts (:func:`response_work`, in steps,
    :mod:`dryfriction.budget`) and refused (:class:`~dryfriction.budget.WorkBoundError`) above
    ``max_work`` (default :data:`~dryfriction.budget.DEFAULT_MAX_WORK`), as is a table too large for
    half this machine's memory.

    Returns
    -------
    xarray.Dataset
        The steady states by frequency (and by orbit for ``method="orbit"``), SI units, the units and
        the settings in the attributes.

    Raises
    ------
    ValueError
        An unknown ``method``, a Bossak ``scheme`` with ``method="orbit"``, a ``period`` or
        ``cold_every`` that is not an integer >= 1.
    dryfriction.budget.WorkBoundError
        The estimated work is above ``max_work`` (a :class:`~dryfriction.errors.UsageError`).
    dryfriction.FMUFileError
        No usable oscillator FMU at ``fmu_path`` (or found by :mod:`dryfriction.paths`).

    Examples
    --------
    >>> from dryfriction import Oscillator, frequency_response
    >>> block = Oscillator.physical(m=0.5, k=2000, zeta=0.003, P0=10, f=10, N=20, mu_s=0.3, mu_k=0.2)
    >>> ds = frequency_response(block, [5, 10, 15])         # Hz
    >>> round(float(ds.amplitude_m.sel(f_hz=10).max()), 4)   # m, one stable orbit
    0.2356
    """
    from ...system.structure import System

    if isinstance(p, System):
        from ..system_response import system_frequency_response

        if method not in (None, "orbit"):
            raise ValueError(f"a structure's response is by orbits (method 'orbit'), not {method!r}")
        # (the oscillator's default transient, 60 periods, is the structure's 40)
        return system_frequency_response(p, f_hz, dof=dof, period=period,
                                         transients=transients if transients != 60 else 40,
                                         progress=progress, fmu_path=fmu_path, symmetry=symmetry)
    if dof is not None or symmetry is not None:
        raise ValueError("dof and symmetry apply to a structure (dryfriction.System), not to the oscillator")
    import xarray as xr

    from ..chaos.batch import map_chunks
    from ... import paths
    from ...references.steady import den_hartog_amplitude, inman_amplitude

    f = _frequencies(f_hz)
    if method is None:
        method = "orbit" if scheme in (None, "exact") else "transient"
    if method not in METHODS:
        raise ValueError(f"method must be one of {', '.join(METHODS)}, not {method!r}")
    if method == "orbit" and scheme not in (None, "exact"):
        raise ValueError(f"the orbit method needs the exact scheme (its Jacobian), not scheme {scheme!r}: "
                         "use method='transient' for the Bossak schemes")
    if not (isinstance(period, int) and period >= 1):
        raise ValueError(f"period must be an integer >= 1 (excitation periods), not {period!r}")
    if method == "orbit" and not (isinstance(cold_every, int) and cold_every >= 1):
        raise ValueError(f"cold_every must be an integer >= 1 (frequencies), not {cold_every!r}")
    work, what = response_work(p, f.size, method, period=period, transients=transients, cold_every=cold_every,
                               max_periods=max_periods, scheme=scheme, h=h)
    check_work(work, what, max_work, option="max_work")
    check_memory(f.size * RESPONSE_BYTES, f"{f.size:,} frequencies", "fewer frequencies")
    path = paths.fmu_path(paths.OSCILLATOR, fmu_path)
    base = {k: v for k, v in p.as_dict().items() if k != "omega"}
    if method == "orbit":
        opts: dict[str, Any] = {"period": period, "transients": transients, "cold_every": cold_every}
        per_chunk = min(math.ceil(f.size / max(1, 2 * workers)), MAX_CHUNK) if workers else f.size
        task: Any = _orbit_chunk
    else:
        opts = {"tol": tol, "min_periods": min_periods, "max_periods": max_periods, "scheme": scheme, "h": h}
        per_chunk = max(1, min(16, math.ceil(f.size / max(1, 4 * workers)))) if workers else max(1, min(8, f.size))
        task = _chunk
    # streamed: each task built when it is submitted, from a slice of the frequencies
    chunks = ((base, f[i:i + per_chunk], opts) for i in range(0, f.size, per_chunk))
    results, _ = map_chunks(task, path, chunks, workers=workers, progress=progress, desc="response",
                            total=-(-f.size // per_chunk))
    reason = np.concatenate([r["reason"] for r in results]).astype(str)
    lam = 2.0 * math.pi * f / p.w0 if p.k > 0 else np.full(f.shape, np.inf)
    applies = p.k > 0 and p.c == 0 and p.P0 != 0
    dh = np.asarray(den_hartog_amplitude(p, lam), dtype=float) if applies else np.full(f.shape, np.nan)
    inm = np.asarray(inman_amplitude(p, lam), dtype=float) if applies else np.full(f.shape, np.nan)
    common = {
        "reason": ("f_hz", reason, {"long_name": "why the point was not computed (the FMU's sentence; "
                                                 "empty where it was)"}),
        "den_hartog_m": ("f_hz", dh, {"units": "m", "long_name": "Den Hartog (zeta = 0, non-stop), exact"}),
        "inman_m": ("f_hz", inm, {"units": "m", "long_name": "Inman (equivalent viscous damping), approximate"}),
    }
    attrs = {**{f"param_{k}": v for k, v in p.as_dict().items() if k != "omega"},
             "param_mu_k": p.mu_k, "param_zeta": p.zeta, "natural_frequency_hz": p.f_n_hz,
             "units": "SI: m, kg, N, s, Hz", "method": method, "scheme": scheme or "exact",
             "never_converges": never_converges_note(p)}
    coords = {"f_hz": ("f_hz", f, {"units": "Hz", "long_name": "excitation frequency"})}
    if method == "orbit":
        width = max(r["orbits"].shape[1] for r in results)
        tab = np.concatenate([np.pad(r["orbits"], ((0, 0), (0, width - r["orbits"].shape[1]), (0, 0)),
                                     constant_values=np.nan) for r in results], axis=0)
        col = {n: tab[:, :, i] for i, n in enumerate(ORBIT_COLUMNS + ("attracting",))}
        # a bool stays a bool: the padding (no orbit) is the mask has_orbit, the flags False there (NaN
        # would make them floats, None objects, which NetCDF cannot hold)
        has = np.isfinite(col["period"])
        n_orbits = np.sum(has, axis=1)
        flag = {n: has & (col[n] == 1.0) for n in ORBIT_FLAGS + ("attracting",)}
        dims = ("f_hz", "orbit")
        ds = xr.Dataset(
            {
                "has_orbit": (dims, has, {"long_name": "an orbit at this index (False: padding, every variable "
                                                       "NaN or False there)"}),
                "period": (dims, col["period"], {"units": "excitation periods", "long_name": "period K of the orbit"}),
                "stable": (dims, flag["stable"], {
                    "long_name": "stable: every |multiplier| < 1 (False for an unstable or neutral orbit, and where "
                                 "has_orbit is False)"}),
                "neutral": (dims, flag["neutral"], {
                    "long_name": "neutrally stable: a multiplier exactly 1 along a continuum of orbits, the other "
                                 "inside the unit circle (the block at rest; a family shifted in x)"}),
                "mu_max": (dims, col["mu_max"], {"units": "1", "long_name": "largest |Floquet multiplier|"}),
                "amplitude_m": (dims, col["amplitude_m"], {"units": "m",
                                                           "long_name": "amplitude, half peak-to-peak of x over the orbit"}),
                "offset_m": (dims, col["offset_m"], {"units": "m", "long_name": "offset, (x_max + x_min) / 2"}),
                "stick_fraction": (dims, col["stick_fraction"], {"units": "1", "long_name": "share of the orbit stuck"}),
                "x0_m": (dims, col["x0_m"], {"units": "m", "long_name": "x at t = 0 mod K T"}),
                "v0_m_per_s": (dims, col["v0_m_per_s"], {"units": "m/s", "long_name": "v at t = 0 mod K T"}),
                "residual": (dims, col["residual"], {"units": "1", "long_name": "scaled Newton residual"}),
                "rest_from_m": (dims, col["rest_from_m"], {"units": "m", "long_name": "the block at rest: the lowest "
                                                                     "rest position, -(F_b - |P0|) / k (NaN for "
                                                                     "other orbits)"}),
                "rest_to_m": (dims, col["rest_to_m"], {"units": "m", "long_name": "the block at rest: the highest rest "
                                                                 "position, (F_b - |P0|) / k"}),
                "n_orbits": ("f_hz", n_orbits, {"units": "1", "long_name": "orbits found"}),
                "converged": ("f_hz", np.any(flag["attracting"], axis=1),
                              {"long_name": "a stable orbit was found (a steady state; the block at rest "
                                            "counts, neutral; without a spring: one attracting but for its neutral "
                                            "shift in x)"}),
                **common,
            },
            coords={**coords, "orbit": ("orbit", np.arange(width), {"long_name": "orbit index (stable first, "
                                                                                  "then neutral, then by amplitude)"})},
            attrs={**attrs, "period": period, "transients": transients, "cold_every": cold_every},
        )
        return ds
    rows = np.concatenate([r["rows"] for r in results], axis=0)
    ds = xr.Dataset(
        {
            "amplitude_m": ("f_hz", rows[:, 0], {"units": "m", "long_name": "amplitude, half peak-to-peak of x"}),
            "offset_m": ("f_hz", rows[:, 1], {"units": "m", "long_name": "offset, (x_max + x_min) / 2"}),
            "stick_fraction": ("f_hz", rows[:, 2], {"units": "1", "long_name": "share of the window stuck"}),
            "converged": ("f_hz", rows[:, 3].astype(bool),
                          {"long_name": f"estimated error of the last window within {tol:g} (relative)"}),
            "periods": ("f_hz", rows[:, 4], {"units": "1", "long_name": "excitation periods run"}),
            "change": ("f_hz", rows[:, 5], {"units": "1", "long_name": "relative amplitude change, last two windows"}),
            "error": ("f_hz", rows[:, 6], {"units": "1", "long_name": "estimated relative error left in the last "
                                                                      "window"}),
            **common,
        },
        coords=coords,
        attrs={**attrs, "tol": tol, "tol_stick": TOL_STICK, "min_periods": min_periods, "max_periods": max_periods},
    )
    return ds


#: frequencies of one Dask task of the orbit method at most (a worker's memory and a lost
#: worker's redo stay small)
MAX_CHUNK = 2000
#: bytes the response holds per frequency in this process (the results of the tasks and the
#: Dataset; measured: 2.56 GB for 10^6 frequencies of the orbit method)
RESPONSE_BYTES = 3000
#: steps (:mod:`dryfriction.budget`) one frequency of the orbit method counts, besides its cold
#: searches: Newton from the predicted orbits, their multipliers, the cycle run (measured: 183
#: microseconds per frequency over 10^6 frequencies, about 12,000 Bossak steps)
ORBIT_FREQUENCY_STEPS = 12000.0


def response_work(p: Oscillator, n: int, method: str, *, period: int = 1, transients: int = 60,
                  cold_every: int = COLD_EVERY, max_periods: int = MAX_PERIODS, scheme: str | None = None,
                  h: float = 0.0) -> tuple[float, str]:
    """The estimated work of :func:`frequency_response` over ``n`` frequencies, in steps
    (:mod:`dryfriction.budget`), and what it is made of: the orbit method's Newton periods and
    cold searches (transients from each of the spread's initial conditions at the first frequency
    and every ``cold_every``); the transient method's bound, 2 ``max_periods`` periods per
    frequency (32 + 64 + ... up to the limit)."""
    from ...budget import BOSSAK_PERIOD_STEPS, EXACT_PERIOD_STEPS, fmt
    from ..orbits import DEFAULT_SPREAD

    if method == "orbit":
        cold = len(DEFAULT_SPREAD) * (transients + 10) * period * EXACT_PERIOD_STEPS
        per = ORBIT_FREQUENCY_STEPS * period + cold / cold_every
        return n * per + cold, f"{n:,} frequencies x about {fmt(per)} steps"
    if scheme in (None, "exact"):
        steps = EXACT_PERIOD_STEPS
    elif h > 0:
        steps = max(p.period / h, 1.0)
    else:
        steps = BOSSAK_PERIOD_STEPS
    periods = 2.0 * max_periods
    return n * periods * steps, f"{n:,} frequencies x up to {fmt(periods)} periods x {fmt(steps)} steps"


def _frequencies(f_hz: Any) -> np.ndarray:
    """The frequencies as a 1-D float array, checked: numbers (not strings, not booleans), finite,
    > 0, at least one."""
    if isinstance(f_hz, (str, bytes)):
        raise ValueError(f"the frequencies must be numbers in Hz, not the string {f_hz!r}")
    arr = np.asarray(f_hz)
    if arr.dtype.kind not in "iuf" or isinstance(f_hz, (list, tuple)):
        items = (x.item() if isinstance(x, np.generic) else x
                 for x in (f_hz if isinstance(f_hz, (list, tuple)) else np.ravel(arr)))
        ok = object()
        bad = next((x for x in items if isinstance(x, (str, bytes, bool)) or not isinstance(x, (int, float))), ok)
        if bad is not ok or arr.size == 0 and arr.dtype.kind not in "iufO":
            what = f"{type(bad).__name__} {bad!r}" if bad is not ok else f"{arr.dtype} values"
            raise ValueError(f"the frequencies must be numbers in Hz, not {what}")
    f = np.asarray(arr, dtype=float)
    if f.ndim != 1 or f.size == 0 or not np.all(np.isfinite(f)) or np.any(f <= 0):
        raise ValueError("the frequencies must be a non-empty list of finite values > 0 Hz")
    return f


def never_converges_note(p: Oscillator) -> str:
    """A sentence when the oscillator has an unbounded resonance (c = 0, 4 mu_k N < pi P0), else ''."""
    if p.c == 0 and p.k > 0 and 4.0 * p.mu_k * p.N < math.pi * abs(p.P0):
        return (f"undamped with 4 mu_k N = {4 * p.mu_k * p.N:.4g} N < pi P0 = {math.pi * abs(p.P0):.4g} N: "
                f"at the natural frequency {p.f_n_hz:.6g} Hz the amplitude grows without bound "
                "(never converges)")
    return ""


def with_omega(p: Oscillator, f_hz: float) -> Oscillator:
    """The oscillator driven at ``f_hz`` Hz instead (omega = 2 pi f)."""
    return replace(p, omega=2.0 * math.pi * f_hz)
