"""What the studies share: the run context, checks of the common config tables, non-dimensional
trajectories through the FMU, and atomic output files (NetCDF datasets, PNG figures)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

from .. import model  # noqa: E402
from ..drivers.oscillator import OscillatorFMU2, Settings  # noqa: E402
from ..params import Oscillator  # noqa: E402
from ..atomic import atomic_path  # noqa: E402
from ..budget import SAMPLE_STEPS, Estimate, fmt, period_steps  # noqa: E402
from ..sweep.datasets import write_netcdf  # noqa: E402
from ..sweep.engine import Engine, EngineOptions, SweepSpec  # noqa: E402
from ..sweep.runner import OUTPUT_COLUMNS, PARAM_COLUMNS  # noqa: E402
from ..sweep.table import nondim_table  # noqa: E402
from .config import ConfigError, require  # noqa: E402,F401

__all__ = [
    "ConfigError",
    "Estimate",
    "FIGURE_BYTES",
    "sweep_estimate",
    "trajectory_estimate",
    "StudyContext",
    "check_numerics",
    "check_params",
    "check_window",
    "ensure",
    "nondim_trajectory",
    "oscillator",
    "plt",
    "sweep_settings",
    "table",
]

# reference SI scales of every study (the results are non-dimensional and do not depend on them)
M_REF, K_REF, P0_REF, MU_S_REF = 1.0, 100.0, 1.0, 0.4


@dataclass
class StudyContext:
    """Everything a study needs to run and where to put its results."""

    name: str
    cfg: dict[str, Any]
    quick: bool
    out_dir: Path
    engine_options: EngineOptions
    messages: list[str] = field(default_factory=list)
    #: where the results end up (``out_dir`` is then the staging folder they are written into)
    final_dir: Path | None = None
    _engine: Engine | None = None
    _fmu: OscillatorFMU2 | None = None

    @property
    def chunk_dir(self) -> Path:
        """The sweeps' finished chunks: in the results folder itself (they outlive a failed run)."""
        return (self.final_dir or self.out_dir) / "chunks"

    def shown(self, path: Path) -> Path:
        """Where a file written into ``out_dir`` ends up."""
        return (self.final_dir or self.out_dir) / path.relative_to(self.out_dir)

    @property
    def fmu_path(self) -> Path:
        """The FMU the study runs."""
        return Path(self.engine_options.fmu)

    def engine(self) -> Engine:
        """The study's sweep engine, started on first use."""
        if self._engine is None:
            self._engine = Engine(self.engine_options)
        return self._engine

    def fmu(self) -> OscillatorFMU2:
        """An FMU instance in this process, for the trajectory studies."""
        if self._fmu is None:
            self._fmu = OscillatorFMU2(self.fmu_path)
        return self._fmu

    def run_sweep(self, spec: SweepSpec) -> np.ndarray:
        """Run a sweep through the study's engine (chunks restartable in the study's folder) and log its
        statistics; returns the table of results."""
        out = self.engine().run(spec, self.chunk_dir)
        self.log(self.engine().stats[-1].line())
        return out

    def close(self) -> None:
        """Close the sweep engine (and its Dask cluster) if it was started."""
        if self._engine is not None:
            self._engine.close()
            self._engine = None
        if self._fmu is not None:
            self._fmu.close()
            self._fmu = None

    def log(self, msg: str) -> None:
        """Print a message and keep it for the study's summary."""
        self.messages.append(msg)
        print(msg, flush=True)

    # ---- outputs ----
    def save_dataset(self, ds: xr.Dataset, filename: str) -> Path:
        """Write a dataset as NetCDF into the study's folder, atomically, with the study's name and size in
        its attributes; returns the path."""
        ds.attrs.setdefault("study", self.name)
        ds.attrs.setdefault("quick", int(self.quick))
        path = write_netcdf(ds, self.out_dir / filename)
        self.log(f"wrote {self.shown(path)}")
        return path

    def save_figure(self, fig: Any, filename: str) -> Path:
        """Write a figure as PNG into the study's folder, atomically, and close it; returns the path."""
        path = self.out_dir / filename
        try:
            with atomic_path(path) as tmp:
                fig.savefig(tmp, format="png", dpi=130, bbox_inches="tight")
        except OSError as e:
            raise OSError(f"cannot write {filename}: {e.strerror or e}") from None
        finally:
            plt.close(fig)
        self.log(f"wrote {self.shown(path)}")
        return path


# ---- estimates (dryfriction.budget) -----------------------------------------------------------

#: bytes a study's PNG figure takes at most (the free-space estimate; the gallery's largest: 0.24 MB)
FIGURE_BYTES = 1e6


def sweep_estimate(est: Estimate, name: str, runs: int, periods: float, numerics: Mapping[str, Any]) -> Estimate:
    """Count a sweep of ``runs`` runs of ``periods`` excitation periods each (what
    :func:`~dryfriction.sweep.engine.sweep_work` counts of its table, from the sizes alone: no
    table is built), its chunk files and the dataset made of them."""
    chunks = -(-int(runs) // int(numerics["chunk_runs"]))
    nbytes = 2.0 * runs * len(OUTPUT_COLUMNS) * 8 + 400.0 * chunks
    # held at once: the run table, the outputs and the dataset made of them
    memory = runs * (len(PARAM_COLUMNS) + 2 * len(OUTPUT_COLUMNS)) * 8
    return est.runs(f"sweep {name}", runs, periods, period_steps(numerics.get("scheme"), numerics["steps_per_period"]),
                    nbytes, memory)


def trajectory_estimate(est: Estimate, what: str, runs: float, periods: float, numerics: Mapping[str, Any],
                        samples_per_period: float = 0.0, variables: int = 8, blocks: int = 1) -> Estimate:
    """Count ``runs`` runs of ``periods`` excitation periods each (steps per period from
    ``numerics``: the exact scheme's count, else ``steps_per_period``; once per block of a chain),
    sampled ``samples_per_period`` times a period (each sample counts
    :data:`~dryfriction.budget.SAMPLE_STEPS`) into ``variables`` float64 variables."""
    spp = period_steps(numerics.get("scheme"), float(numerics.get("steps_per_period", 1000)))
    if not samples_per_period:
        return est.runs(what, runs, periods, spp * blocks)
    samples = runs * (periods * samples_per_period + 1.0)
    return est.add(f"{what}: {fmt(runs)} runs x {fmt(periods)} periods x {fmt(spp * blocks)} steps, "
                   f"{fmt(samples)} samples", runs * periods * spp * blocks + samples * SAMPLE_STEPS,
                   samples * variables * 8)


# ---- checks -------------------------------------------------------------------------------------

def _finite(v: float) -> bool:
    return isinstance(v, (int, float)) and math.isfinite(v)


def check_params(p: Mapping[str, Any], where: str = "params") -> None:
    """Checks of a table of non-dimensional parameters (only the keys present)."""
    for k, v in p.items():
        if isinstance(v, (int, float)) and not isinstance(v, bool):
            require(_finite(v), f"{where}.{k} must be finite, not {v}")
    if "lam" in p:
        require(p["lam"] > 0, f"{where}.lam (frequency ratio) must be > 0, not {p['lam']}")
    if "mu_s_sigma" in p:
        require(p["mu_s_sigma"] >= 0, f"{where}.mu_s_sigma must be >= 0, not {p['mu_s_sigma']}")
    if "chi" in p:
        require(p["chi"] >= 0, f"{where}.chi must be >= 0, not {p['chi']}")
    if "zeta" in p:
        require(p["zeta"] >= 0, f"{where}.zeta must be >= 0, not {p['zeta']}")


def check_numerics(n: Mapping[str, Any]) -> None:
    """The numerical settings, against the ranges of the model description's variables."""
    md = model.default()
    require(n["steps_per_period"] >= 10,
            f"numerics.steps_per_period must be >= 10, not {n['steps_per_period']}")
    for key in ("scheme", "alpha", "frictionUpdates"):
        if key in n:
            _check_var(md, key, n[key])
    if "chunk_runs" in n:
        require(n["chunk_runs"] >= 1, f"numerics.chunk_runs must be >= 1, not {n['chunk_runs']}")


def _check_var(md: model.ModelDescription, name: str, value: Any) -> None:
    try:
        md.check(name, value, where=f"numerics.{name}")
    except ValueError as e:
        raise ConfigError(str(e)) from None


def check_window(periods: float, obs_periods: float, where: str) -> None:
    """Refuse an observation window that is not inside the run (ConfigError naming ``where``)."""
    require(periods > 0, f"{where}.periods must be > 0, not {periods}")
    require(0 < obs_periods <= periods,
            f"{where}.obs_periods must be in (0, periods = {periods}], not {obs_periods}")


# ---- runs ---------------------------------------------------------------------------------------

def oscillator(nd: Mapping[str, float]) -> Oscillator:
    """The SI oscillator of a table of non-dimensional parameters (reference scales)."""
    return Oscillator.from_nondimensional(
        lam=nd["lam"], mu_s_sigma=nd["mu_s_sigma"], chi=nd["chi"], zeta=nd.get("zeta", 0.0),
        z0=nd.get("z0", 0.0), dz0=nd.get("dz0", 0.0), phi=nd.get("phi", 0.0),
        m=M_REF, k=K_REF, P0=P0_REF, mu_s=MU_S_REF)


def sweep_settings(numerics: Mapping[str, Any]) -> dict[str, Any]:
    """The FMU settings of a sweep from a study's ``numerics`` table."""
    return {"scheme": numerics["scheme"], "frictionUpdates": int(numerics.get("frictionUpdates", 1)),
            "fastPaths": True}


def table(values: Mapping[str, Any], periods: Any, obs_start: Any, obs_stop: Any,
          numerics: Mapping[str, Any]) -> np.ndarray:
    """The sweep's parameter table of non-dimensional runs on the reference scales (one row per run)."""
    return nondim_table(values, periods, obs_start, obs_stop, numerics["steps_per_period"],
                        alpha=numerics["alpha"], m=M_REF, k=K_REF, P0=P0_REF, mu_s=MU_S_REF)


def nondim_trajectory(fmu: OscillatorFMU2, nd: Mapping[str, float], t_start: float, t_stop: float,
                      samples_per_period: int, numerics: Mapping[str, Any]) -> dict[str, np.ndarray]:
    """z, z', z'' (method.md (2)), the mode and the excitation cos(lam tau + phi) at the
    communication points ``t / T`` in [t_start, t_stop] (excitation periods); the FMU runs from
    t = 0 (the points before ``t_start`` are stepped over in one doStep). When
    ``samples_per_period`` divides ``steps_per_period`` the points are internal grid points."""
    p = oscillator(nd)
    T, w0 = p.period, p.w0
    spp = int(numerics["steps_per_period"])
    h = T / spp
    if spp % samples_per_period == 0 and float(t_start * spp).is_integer() and float(t_stop * spp).is_integer():
        # communication points on the FMU's internal grid t = n h (computed as the FMU does): the
        # run takes exactly the internal steps of a single doStep, so a trajectory and a sweep's
        # observables of the same parameters follow the same numbers
        stride = spp // samples_per_period
        idx = np.arange(int(t_start * spp), int(t_stop * spp) + 1, stride)
        times = idx * h
        cyc = idx / spp
    else:
        n = max(int(round((t_stop - t_start) * samples_per_period)), 1)
        cyc = np.linspace(t_start, t_stop, n + 1)
        times = cyc * T
    if t_start > 0:
        times = np.concatenate([[0.0], times])
    st = Settings(h=h, alpha=numerics["alpha"], scheme=numerics["scheme"],
                  frictionUpdates=int(numerics.get("frictionUpdates", 1)))
    tr = fmu.trajectory(p, times, st, outputs=("x", "v", "a", "F_friction", "mode"))
    sl = slice(1, None) if t_start > 0 else slice(None)
    scale = p.k / p.P0
    tau = times[sl] * w0
    return {
        "cycles": cyc,
        "tau": tau,
        "z": tr["x"][sl] * scale,
        "dz": tr["v"][sl] * scale / w0,
        "ddz": tr["a"][sl] * scale / (w0 * w0),
        "f": tr["F_friction"][sl] / p.P0,
        "mode": tr["mode"][sl].astype(np.int8),
        "excitation": np.cos(nd["lam"] * tau + nd.get("phi", 0.0)),
    }


def ensure(cond: bool, message: str) -> None:
    """A physics expectation of a study that its run did not meet: noted, not fatal."""
    if not cond:
        print(f"note: {message}", flush=True)

