"""What the orbit studies share (fig8_9_orbits, fig10_11_orbits): the ``[continuation]`` table,
continuations collected into one dataset, the bifurcation table (csv, json), and a sweep whose
chunks are shared with the study it draws over.

The branches come from :func:`dryfriction.analysis.continuation.continue_orbits` (docs/orbits.md); lengths
are written in the paper's z = k x / P0 (static deflections) as the scatter is.
"""

from __future__ import annotations

import csv
import io
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from ..atomic import atomic_write_text
from ..analysis.continuation import Continuation, continue_orbits
from ..sweep import SweepSpec
from .common import K_REF, P0_REF, StudyContext, oscillator
from .config import require

__all__ = ["Z_SCALE", "check_continuation", "continue_nd", "collect", "write_bifurcations", "shared_sweep",
           "BIFURCATION_COLUMNS"]

#: metres -> z = k x / P0 at the studies' reference scales
Z_SCALE = K_REF / P0_REF

BIFURCATION_COLUMNS = ("type", "param", "param_value", "period", "branch", "amplitude_z", "offset_z",
                       "mu1_re", "mu1_im", "mu2_re", "mu2_im", "brute_force_lo", "brute_force_hi",
                       "within_brute_force", "note")


def check_continuation(c: dict[str, Any], where: str = "continuation") -> None:
    """Refuse continuation settings out of range (ConfigError naming the key)."""
    require(0 < c["ds"] <= c["ds_max"], f"{where}: need 0 < ds <= ds_max (ds = {c['ds']}, ds_max = {c['ds_max']})")
    require(c["max_points"] >= 2, f"{where}.max_points must be >= 2, not {c['max_points']}")
    require(c["max_branches"] >= 1, f"{where}.max_branches must be >= 1, not {c['max_branches']}")


def continue_nd(ctx: StudyContext, nd: dict[str, float], param: str, start: float, stop: float,
                c: dict[str, Any]) -> Continuation:
    """continue_orbits of the study's oscillator (non-dimensional ``nd`` at ``param = start``) from
    ``start`` to ``stop``, with the ``[continuation]`` settings ``c``, on the context's FMU."""
    p = oscillator({**nd, param: start})
    return continue_orbits(p, param, start, stop, ds=c["ds"], ds_min=min(1e-6, c["ds"]), ds_max=c["ds_max"],
                           max_points=c["max_points"], max_branches=c["max_branches"], fmu=ctx.fmu())


def collect(runs: list[tuple[dict[str, float], Continuation]]) -> xr.Dataset:
    """The points of several continuations in one dataset (dim ``point``), each labelled with the
    values in its dict (e.g. ``segment``, ``chi``), lengths also in z (``amplitude_z``, ``offset_z``)."""
    parts = []
    for labels, c in runs:
        ds = c.dataset
        if ds.point.size == 0:
            continue
        ds = ds.copy()
        for k, v in labels.items():
            ds[k] = ("point", np.full(ds.point.size, v))
        parts.append(ds)
    if not parts:
        return xr.Dataset()
    out = xr.concat(parts, dim="point", data_vars="all", combine_attrs="drop_conflicts")
    out = out.assign_coords(point=np.arange(out.point.size))
    out["amplitude_z"] = out.amplitude_m * Z_SCALE
    out["offset_z"] = out.offset_m * Z_SCALE
    out.amplitude_z.attrs["long_name"] = "(z_max - z_min) / 2 over the orbit, z = k x / P0"
    out.offset_z.attrs["long_name"] = "(z_max + z_min) / 2 over the orbit (asymmetry)"
    return out


def bifurcation_rows(c: Continuation, labels: dict[str, float],
                     brute: dict[str, tuple[float, float]] | None = None) -> list[dict[str, Any]]:
    """One row per located bifurcation of ``c`` (``labels`` first), with the brute-force bracket of
    its type where one is given and whether the located value lies in it."""
    rows = []
    for b in c.bifurcations:
        mu = [complex(m) for m in b.multipliers] + [complex("nan")] * (2 - len(b.multipliers))
        lo, hi = (brute or {}).get(b.type, (math.nan, math.nan))
        within: bool | str = bool(lo <= b.param <= hi) if math.isfinite(lo) else ""
        rows.append({**labels, "type": b.type, "param": c.param, "param_value": float(b.param), "period": int(b.period),
                     "branch": int(b.branch), "amplitude_z": float(b.amplitude_m) * Z_SCALE,
                     "offset_z": float(b.offset_m) * Z_SCALE,
                     "mu1_re": mu[0].real, "mu1_im": mu[0].imag, "mu2_re": mu[1].real, "mu2_im": mu[1].imag,
                     "brute_force_lo": float(lo), "brute_force_hi": float(hi), "within_brute_force": within,
                     "note": b.note})
    return rows


def _json_safe(x: Any) -> Any:
    if isinstance(x, float) and not math.isfinite(x):
        return None
    if isinstance(x, np.generic):
        return _json_safe(x.item())
    return x


def write_bifurcations(ctx: StudyContext, rows: list[dict[str, Any]], stem: str,
                       extra: dict[str, Any] | None = None) -> tuple[Path, Path]:
    """``<stem>.csv`` (one row per bifurcation) and ``<stem>.json`` (``{"bifurcations": [...], **extra}``)."""
    cols = list(rows[0]) if rows else list(BIFURCATION_COLUMNS)
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=cols, lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: (repr(v) if isinstance(v, float) else v) for k, v in r.items()})
    p_csv = atomic_write_text(ctx.out_dir / f"{stem}.csv", buf.getvalue())
    doc = {"bifurcations": [{k: _json_safe(v) for k, v in r.items()} for r in rows], **(extra or {})}
    p_json = atomic_write_text(ctx.out_dir / f"{stem}.json",
                               json.dumps(doc, indent=1, default=_json_safe, allow_nan=False) + "\n")
    ctx.log(f"wrote {p_csv}")
    ctx.log(f"wrote {p_json}")
    return p_csv, p_json


class _SharedChunks:
    """A stand-in for the context that runs sweeps with the chunks of the study ``base`` (keyed by a
    hash of the run table, the settings and the FMU: only identical runs are reused)."""

    def __init__(self, ctx: StudyContext, base: str) -> None:
        self.cfg, self.quick, self._ctx = ctx.cfg, ctx.quick, ctx
        shared = ctx.out_dir.parent / base / "chunks"
        self.chunk_dir = shared if shared.is_dir() else ctx.chunk_dir

    def run_sweep(self, spec: SweepSpec) -> np.ndarray:
        out = self._ctx.engine().run(spec, self.chunk_dir)
        self._ctx.log(self._ctx.engine().stats[-1].line())
        return out

    def log(self, msg: str) -> None:
        self._ctx.log(msg)


def shared_sweep(ctx: StudyContext, base: str) -> Any:
    """A context for the base study's sweep code: its chunks are reused when that study has run
    (``<out>/<base>/chunks``), else they go to this study's own chunk folder."""
    return _SharedChunks(ctx, base)
