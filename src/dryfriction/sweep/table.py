"""Parameter tables of a sweep, built from the non-dimensional parameters (method.md (2)).

The conversion is :meth:`dryfriction.params.Oscillator.from_nondimensional`, vectorised: every
column is computed with the same floating-point operations, so a row equals the SI parameters of
``Oscillator.from_nondimensional`` bit for bit.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from .. import model
from .runner import PARAM_COLUMNS


def _start(name: str) -> float:
    """The model description's start value of a parameter: the default scales of a table (read on
    first use)."""
    return float(model.default().var(name).start)  # type: ignore[arg-type]


__all__ = ["NONDIM_NAMES", "nondim_table", "to_nondim"]

#: Non-dimensional inputs of a run: frequency ratio, mu_s sigma (static friction force over P0),
#: chi = mu_k / mu_s, damping ratio, initial z and z' (z = k x / P0, ' = d/dtau, tau = w0 t),
#: excitation phase.
NONDIM_NAMES = ("lam", "mu_s_sigma", "chi", "zeta", "z0", "dz0", "phi")


def nondim_table(
    values: Mapping[str, np.ndarray | float],
    periods: float | np.ndarray,
    obs_start: float | np.ndarray,
    obs_stop: float | np.ndarray,
    steps_per_period: float | np.ndarray,
    alpha: float | None = None,
    m: float | None = None,
    k: float | None = None,
    P0: float | None = None,
    mu_s: float | None = None,
) -> np.ndarray:
    """Rows of :data:`PARAM_COLUMNS` for broadcast arrays of the non-dimensional inputs.

    ``periods``, ``obs_start`` and ``obs_stop`` are in excitation periods T = 2 pi / omega (the run
    ends at ``periods`` T, the observables are taken over [obs_start T, obs_stop T]); the internal
    step is h = T / steps_per_period. ``alpha``, ``m``, ``k``, ``P0``, ``mu_s``: the model
    description's start values unless given.
    """
    alpha = _start("alpha") if alpha is None else alpha
    m = _start("m") if m is None else m
    k = _start("k") if k is None else k
    P0 = _start("P0") if P0 is None else P0
    mu_s = _start("mu_s") if mu_s is None else mu_s
    unknown = set(values) - set(NONDIM_NAMES)
    if unknown:
        raise KeyError(f"unknown non-dimensional parameter(s): {', '.join(sorted(unknown))}")
    defaults = {"zeta": 0.0, "z0": 0.0, "dz0": 0.0, "phi": 0.0}
    v = {n: np.asarray(values.get(n, defaults.get(n, np.nan)), dtype=float) for n in NONDIM_NAMES}
    for n in ("lam", "mu_s_sigma", "chi"):
        if n not in values:
            raise KeyError(f"missing non-dimensional parameter {n}")
    arrs = np.broadcast_arrays(*(v[n] for n in NONDIM_NAMES),
                               *(np.asarray(x, dtype=float) for x in (periods, obs_start, obs_stop, steps_per_period)))
    lam, mss, chi, zeta, z0, dz0, phi, per, o0, o1, spp = (a.ravel() for a in arrs)
    w0 = np.sqrt(np.float64(k) / np.float64(m))
    n = lam.size
    out = np.empty((n, len(PARAM_COLUMNS)))
    col = {name: i for i, name in enumerate(PARAM_COLUMNS)}
    md = model.default()
    for name, i in col.items():  # the columns set below are overwritten; the rest (v_s, delta) at their starts
        if name != "t_stop":
            out[:, i] = md.var(name).start
    omega = lam * w0
    T = 2.0 * np.pi / omega
    out[:, col["m"]] = m
    out[:, col["k"]] = k
    out[:, col["c"]] = 2.0 * zeta * np.sqrt(np.float64(k) * np.float64(m))
    out[:, col["P0"]] = P0
    out[:, col["omega"]] = omega
    out[:, col["phi"]] = phi
    out[:, col["N"]] = mss * P0 / mu_s
    out[:, col["mu_s"]] = mu_s
    out[:, col["chi"]] = chi
    out[:, col["x0"]] = z0 * P0 / k
    out[:, col["v0"]] = dz0 * P0 * w0 / k
    out[:, col["h"]] = T / spp
    out[:, col["alpha"]] = alpha
    out[:, col["t_obs_start"]] = o0 * T
    out[:, col["t_obs_stop"]] = o1 * T
    out[:, col["t_stop"]] = per * T
    return out


def to_nondim(x: np.ndarray, k: float = 100.0, P0: float = 1.0) -> np.ndarray:
    """Displacement in metres to z = k x / P0."""
    return np.asarray(x) * (k / P0)
