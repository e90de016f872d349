"""The frequency response of a structure with friction contacts by its periodic orbits
(docs/system_orbits.md).

At each excitation frequency the orbit of ``period`` periods is found by Newton shooting on the
located map with the FMU's Jacobian (:mod:`dryfriction.analysis.system_orbits`): at the first
frequency from a transient, at each next one from the branch's last orbits extrapolated to the
frequency through up to four of them (their states at the section, at the response's step, where the
section stayed; else their states at t = 0, carried to the section by a run; where that does not
converge, the previous orbit's state at t = 0; the map's Jacobian telling Newton the way; two to
four map evaluations), and from a fresh transient again where none converges. Where no contact's force reaches its limit in the
linear response with every contact stuck, that closed form is the start instead (the first
frequency, a fresh start, or a previous orbit stuck throughout): an orbit, one Newton step. Each point carries its stability (the multipliers),
its residual and the amplitude's error estimated against h / 2 (Richardson), so that a point that is
not converged or not accurate says so. A frequency whose orbit is not found has NaN values,
``converged`` False and the reason.
"""

from __future__ import annotations

import contextlib
import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from .shooting import extrapolate, progress_bar, sweep
from .system_orbits import SystemOrbit, _check_symmetry, _Map, _h_of, _solve, stuck_start

if TYPE_CHECKING:
    from ..system.structure import System as Structure  # (the annotations' name: the API reference links it)
    from ..system.symmetry import CyclicSymmetry

__all__ = ["system_frequency_response", "plot_system_response"]

#: a point starts from the Lagrange polynomial through its branch's last PREDICT orbits (cubic, as the
#: oscillator's response)
PREDICT = 4
#: a prediction is trusted where it would have predicted the branch's last orbit from the ones before
#: within this share of that orbit's step from the one before it (else the frequencies are too far
#: apart for the branch's curvature: the previous orbit is the start)
TRUST = 0.25
#: Newton steps at most from a predicted start (it converges in two or three where the prediction
#: holds; then from the previous orbit itself with the response's max_iter)
PREDICTED_ITER = 8


def _all_stuck(system: "Structure", orbit: SystemOrbit) -> bool:
    """Whether every contact with friction stayed stuck over ``orbit``'s whole cycle."""
    live = np.maximum(system.mu_s, system.mu_k) * system.N > 0.0
    share = np.asarray(orbit.stick_fraction)
    return bool(share.size == live.size and np.all(share[live] >= 1.0))


class _Point(NamedTuple):
    """An orbit of the branch as the next points' predictor reads it: its frequency, its state at
    t = 0 (x0, v0, the Jenkins sliders), its section (a share of its period; its sliders' modes
    there), its state there at the response's h0 (None where not known: h halved more than once) and
    its section_shift."""

    f: float
    z0: np.ndarray
    phase: float
    slide: np.ndarray
    coarse: np.ndarray | None
    shift: np.ndarray


def _point(orbit: SystemOrbit, f: float, system: "Structure", K: int, h0: float) -> _Point:
    """The predictor's record of a converged orbit at the frequency f (h0: the response's step there)."""
    jenk = np.flatnonzero(system.k_t > 0.0)
    coarse = None
    if orbit.h == h0:
        coarse = orbit.section_state
    elif orbit.h == 0.5 * h0 and orbit.section_shift.size == orbit.section_state.size:
        coarse = orbit.section_state - orbit.section_shift
    return _Point(f, np.concatenate([orbit.x0, orbit.v0, orbit.s0[jenk]]), orbit.section * f / K,
                  orbit.section_slide, coarse, orbit.section_shift)


def _predict(fs: list[float], zs: list[np.ndarray], f: float) -> np.ndarray | None:
    """The states zs at the frequencies fs extrapolated to f (:func:`extrapolate`), where trusted: the
    same rule through all but the last predicts the last within TRUST of its step from the one
    before (None: not trusted, or fewer than three)."""
    if len(zs) < 3:
        return None
    back = extrapolate(fs[:-1], zs[:-1], fs[-1])
    step = float(np.max(np.abs(zs[-1] - zs[-2])))
    if not float(np.max(np.abs(back - zs[-1]))) <= TRUST * step:
        return None
    return extrapolate(fs, zs, f)


def _same_section(branch: list[_Point]) -> list[_Point]:
    """The branch's last orbits at the last one's section (the same share of the period, the same
    sliders' modes there) whose states there at h0 are known."""
    if not branch:
        return []
    out: list[_Point] = []
    last = branch[-1]
    for b in reversed(branch):
        if (b.coarse is None or abs(b.phase - last.phase) > 1e-9 * max(1.0, abs(last.phase))
                or not np.array_equal(b.slide, last.slide)):
            break
        out.append(b)
    return out[::-1]


def system_frequency_response(system: "Structure", f_hz: Sequence[float] | np.ndarray, *, dof: int | None = None,
                              period: int = 1, tol: float = 1e-8, max_iter: int = 30, transients: int = 40,
                              accuracy: float | None = None, estimate_error: bool = True, progress: bool = False,
                              fmu_path: str | os.PathLike[str] | None = None, fmu: "SystemFMU3 | None" = None,
                              symmetry: "CyclicSymmetry | None" = None) -> Any:
    """The steady response of ``system`` at the frequencies ``f_hz`` (Hz) as an xarray Dataset
    (dimensions ``f_hz``, ``dof``, ``contact``): per frequency its orbit's ``amplitude_m``,
    ``offset_m``, ``x0_m``, ``v0_m_per_s`` (per DOF), ``stick_fraction`` (per contact), ``stable``, ``neutral`` (a stuck slider's continuum),
    ``mu_max``, ``residual``, ``error_m`` (the amplitude's estimated error), ``h_s``, ``iterations``,
    ``converged`` and ``reason``; ``amplitude_extrapolated_m`` (per DOF) Richardson's value from
    the error estimate's two steps (NaN without it); ``amplitude_dof_m`` the amplitude of ``dof``
    (default: the DOF with the largest amplitude over the sweep). Settings and units in the
    attributes. ``accuracy``: each orbit's h halved until its estimated error is within it (module
    doc of :mod:`~dryfriction.analysis.system_orbits`). ``fmu``: an open
    :class:`~dryfriction.drivers.system.SystemFMU3` of a structure of the same sizes to run on (else
    one is opened, from ``fmu_path`` or the package's, and closed). ``symmetry``: a
    :class:`~dryfriction.system.symmetry.CyclicSymmetry` of the structure and its excitation, the
    orbits that share it (:func:`~dryfriction.analysis.system_orbits.find_system_orbits`' ``symmetry``;
    ``period`` 1)."""
    import xarray as xr

    from ..drivers.system import SystemFMU3
    from ..system.structure import System

    if not isinstance(system, System):
        raise TypeError(f"system_frequency_response needs a dryfriction.System, not {type(system).__name__}")
    f = np.atleast_1d(np.asarray(f_hz, dtype=float))
    if f.ndim != 1 or f.size < 1 or not np.all(np.isfinite(f)) or np.any(f <= 0):
        raise ValueError("f_hz must be a non-empty 1-D sequence of finite frequencies > 0 (Hz)")
    if dof is not None and not (0 <= int(dof) < system.n):
        raise ValueError(f"dof must be a degree of freedom 0 .. {system.n - 1}, not {dof!r}")
    if system.scheme != "located":
        raise ValueError(f"the response by orbits uses the located scheme's map, and the system's scheme is "
                         f"{system.scheme!r}: System.replace(scheme='located')")
    n, nc, K = system.n, system.nc, int(period)
    _check_symmetry(system, symmetry, K)
    out = {name: np.full((f.size, n), np.nan) for name in ("amplitude_m", "amplitude_extrapolated_m", "offset_m",
                                                           "x0_m", "v0_m_per_s")}
    share = np.full((f.size, nc), np.nan)
    scal = {name: np.full(f.size, np.nan) for name in ("mu_max", "residual", "error_m", "h_s")}
    stable = np.zeros(f.size, dtype=bool)
    neutral = np.zeros(f.size, dtype=bool)
    conv = np.zeros(f.size, dtype=bool)
    iters = np.zeros(f.size, dtype=np.int64)
    reasons = [""] * f.size
    bar = progress_bar(f.size, progress)
    if fmu is not None and (not isinstance(fmu, SystemFMU3) or (fmu.n, fmu.nc) != (system.n, system.nc)):
        raise ValueError("fmu must be an open SystemFMU3 of a structure of the system's sizes (n, nc)")
    with (SystemFMU3(system, fmu_path) if fmu is None else contextlib.nullcontext(fmu)) as fmu:
        maps: dict[int, tuple[_Map, float]] = {}
        branch: list[_Point] = []  # the branch's last orbits

        def at(i: int, s_i: "Structure") -> tuple[_Map, float]:
            """The map of the frequency i at its step h0 (made once per frequency)."""
            if i not in maps:
                maps.clear()
                fmu.system = s_i
                h0 = _h_of(fmu, s_i, accuracy)
                s_h = s_i.replace(h=h0)
                maps[i] = (_Map(fmu, s_h, K, symmetry), h0)
            M, h0 = maps[i]
            fmu.system = M.system
            return M, h0

        def warm(i: int, s_i: "Structure", prev: SystemOrbit) -> SystemOrbit | None:
            """From the branch's last orbits, the previous frequency's last (module doc)."""
            if not prev.converged:
                return None
            M, h0 = at(i, s_i)
            stuck = stuck_start(M.system) if _all_stuck(M.system, prev) else None
            if stuck is not None:  # (the stuck branch: its closed form)
                return _solve(M, fmu, stuck, tol, max_iter, h0, estimate_error, accuracy)
            z = np.concatenate([prev.x0, prev.v0, prev.s0[M.jenk]])
            phase = prev.section * f[i - 1] / K if i > 0 else None  # (its section, a share of its period)
            same = _same_section(branch)
            fs = [b.f for b in same]
            zs = _predict(fs, [b.coarse for b in same], f[i]) if phase is not None else None
            if zs is not None:  # (Newton at the section from the states there at h0)
                shift = (extrapolate(fs, [b.shift for b in same], f[i]) if all(b.shift.size for b in same)
                         else prev.section_shift)
                orbit = _solve(M, fmu, zs, tol, min(max_iter, PREDICTED_ITER), h0, estimate_error, accuracy, phase,
                               prev.section_slide, shift, at_section=True)
                if orbit.converged:
                    return orbit
            zp = _predict([b.f for b in branch], [b.z0 for b in branch], f[i])
            if zp is not None:  # (the branch extrapolated; the previous orbit itself where that fails)
                orbit = _solve(M, fmu, zp, tol, min(max_iter, PREDICTED_ITER), h0, estimate_error, accuracy, phase,
                               prev.section_slide, prev.section_shift, prev.slide0)
                if orbit.converged:
                    return orbit
            orbit = _solve(M, fmu, z, tol, max_iter, h0, estimate_error, accuracy, phase, prev.section_slide,
                           prev.section_shift, prev.slide0)
            return orbit if orbit.converged else None

        def cold(i: int, s_i: "Structure", prev: SystemOrbit | None) -> SystemOrbit:
            """From the stuck closed form where no contact slips in it, else from a transient from
            the system's start; where that does not converge, from a transient from the previous
            frequency's orbit (the attractor it settles to is the one the sweep follows)."""
            M, h0 = at(i, s_i)
            branch.clear()  # (a new branch from here)
            s_h = M.system
            stuck = stuck_start(s_h)
            if stuck is not None:
                return _solve(M, fmu, stuck, tol, max_iter, h0, estimate_error, accuracy)
            # (each transient from its state with its sliders' modes: the rest's stuck, the orbit's own)
            starts = [(np.concatenate([s_h.x0, s_h.v0, s_h.W[M.jenk] @ s_h.x0]), np.zeros(s_h.nc, dtype=int))]
            if prev is not None and prev.converged:
                starts.append((np.concatenate([prev.x0, prev.v0, prev.s0[M.jenk]]), prev.slide0))
            first: SystemOrbit | None = None
            for z, slide in starts:
                M.slide[:] = slide
                orbit = _solve(M, fmu, M.transient(z, transients), tol, max_iter, h0, estimate_error, accuracy)
                if orbit.converged:
                    return orbit
                first = orbit if first is None else first
            assert first is not None
            return first

        def record(i: int, s_i: "Structure", orbit: SystemOrbit) -> None:
            if orbit.converged and orbit.x0.size:
                branch[:] = [*branch[-(PREDICT - 1):], _point(orbit, float(f[i]), s_i, K, maps[i][1])]
            else:
                branch.clear()
            conv[i] = orbit.converged
            reasons[i] = orbit.reason
            if orbit.amplitude.size:
                out["amplitude_m"][i] = orbit.amplitude
                if orbit.amplitude_extrapolated.size:
                    out["amplitude_extrapolated_m"][i] = orbit.amplitude_extrapolated
                out["offset_m"][i] = orbit.offset
                out["x0_m"][i] = orbit.x0
                out["v0_m_per_s"][i] = orbit.v0
                share[i] = orbit.stick_fraction
            stable[i] = orbit.stable
            neutral[i] = orbit.neutral
            scal["mu_max"][i] = orbit.mu_max
            scal["residual"][i] = orbit.residual
            scal["error_m"][i] = orbit.error
            scal["h_s"][i] = orbit.h
            iters[i] = orbit.iterations

        def failed(i: int, e: BaseException) -> None:
            branch.clear()
            reasons[i] = f"{type(e).__name__}: {e}"

        # (an FMU's refusal at one frequency: reported, the sweep goes on)
        sweep([system.replace(omega=2.0 * math.pi * float(fi)) for fi in f], warm, cold, record, failed,
              (Exception,), bar)
    bar(-1)
    pick = int(dof) if dof is not None else int(np.nanargmax(np.nanmax(out["amplitude_m"], axis=0))) \
        if np.any(np.isfinite(out["amplitude_m"])) else 0
    units = {"amplitude_m": "m", "amplitude_extrapolated_m": "m", "offset_m": "m", "x0_m": "m", "v0_m_per_s": "m/s",
             "error_m": "m", "h_s": "s",
             "mu_max": "1", "residual": "1", "stick_fraction": "1", "amplitude_dof_m": "m"}
    data: dict[str, Any] = {name: (("f_hz", "dof"), v) for name, v in out.items()}
    data["stick_fraction"] = (("f_hz", "contact"), share)
    data.update({name: (("f_hz",), v) for name, v in scal.items()})
    data["amplitude_dof_m"] = (("f_hz",), out["amplitude_m"][:, pick])
    data["stable"] = (("f_hz",), stable)
    data["neutral"] = (("f_hz",), neutral)
    data["converged"] = (("f_hz",), conv)
    data["iterations"] = (("f_hz",), iters)
    data["reason"] = (("f_hz",), np.array(reasons, dtype=object))
    ds = xr.Dataset(data, coords={"f_hz": f, "dof": np.arange(n), "contact": np.arange(nc)})
    for name, u in units.items():
        ds[name].attrs["units"] = u
    ds["f_hz"].attrs["units"] = "Hz"
    ds.attrs.update({"method": "orbit (located map, the FMU's Jacobian)", "period": K, "tol": tol, "dof": pick,
                     "n": n, "nc": nc, "accuracy": float("nan") if accuracy is None else float(accuracy),
                     "estimate_error": int(bool(estimate_error))})
    return ds


def plot_system_response(ds: Any, path: str | os.PathLike[str], dof: int | None = None) -> Path:
    """The response's PNG: the amplitude of each DOF (or of ``dof``) against frequency, stable
    orbits solid, unstable ones dashed, points not converged marked; the stuck share of each
    contact below. Returns the path written."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path = Path(path)
    f = ds["f_hz"].values
    A = ds["amplitude_m"].values
    dofs = [int(dof)] if dof is not None else list(range(A.shape[1]))
    fig, (ax, bx) = plt.subplots(2, 1, figsize=(7, 6), sharex=True, gridspec_kw={"height_ratios": [3, 1]})
    stable = ds["stable"].values
    for d in dofs:
        a_st = np.where(stable, A[:, d], np.nan)
        a_un = np.where(~stable, A[:, d], np.nan)
        line, = ax.plot(f, a_st, "-", label=f"DOF {d}")
        ax.plot(f, a_un, "--", color=line.get_color())
    bad = ~ds["converged"].values
    if np.any(bad):
        ax.plot(f[bad], np.zeros(int(bad.sum())), "rx", label="not converged")
    ax.set_ylabel("amplitude, m")
    ax.set_title("steady response by periodic orbits (located map)")
    ax.legend(loc="best", fontsize="small")
    ax.grid(True, alpha=0.3)
    share = ds["stick_fraction"].values
    for j in range(share.shape[1]):
        bx.plot(f, share[:, j], label=f"contact {j}")
    bx.set_ylabel("stuck share")
    bx.set_xlabel("frequency, Hz")
    bx.set_ylim(-0.05, 1.05)
    bx.grid(True, alpha=0.3)
    if share.shape[1]:
        bx.legend(loc="best", fontsize="small")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
