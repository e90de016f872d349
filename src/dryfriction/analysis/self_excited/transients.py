"""Sampled runs of a belt problem and their section crossings (dryfriction.analysis.self_excited)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...drivers.oscillator import OscillatorFMU2
from ...params import Oscillator
from .flow import _fmu
from .problem import MAX_SAMPLES, BeltProblem


@dataclass
class Transient:
    """A sampled run and its crossings of the section (x = x_eq against the belt)."""

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    mode: np.ndarray
    crossings: np.ndarray            # times, s
    crossing_v: np.ndarray           # velocities there, m/s

    def window(self, fraction: float = 0.25) -> dict[str, float]:
        """Amplitude, offset, stick share and the mean period over the last ``fraction`` of the run."""
        i = self.t >= self.t[-1] - fraction * (self.t[-1] - self.t[0])
        x = self.x[i]
        c = self.crossings[self.crossings >= self.t[-1] - fraction * (self.t[-1] - self.t[0])]
        return {"amplitude": float(np.ptp(x) / 2.0), "offset": float((x.max() + x.min()) / 2.0),
                "stick_fraction": float(np.mean(self.mode[i] == 0)),
                "period": float(np.mean(np.diff(c))) if c.size > 1 else math.nan}


def transient(prob: BeltProblem, x0: float | None = None, v0: float | None = None, periods: float = 40.0,
              samples: int = 256, *, fmu: OscillatorFMU2 | None = None) -> Transient:
    """The motion over ``periods`` natural periods from (x0, v0) (default: riding on the belt at x_eq),
    ``samples`` per natural period (fewer, but at least 16, when that would be more than MAX_SAMPLES
    in all), with its section crossings (linear interpolation)."""
    xs = prob.x_eq if x0 is None else float(x0)
    vs = prob.v_belt if v0 is None else float(v0)
    T0 = prob.natural_period
    n = max(int(round(periods * min(samples, max(16, MAX_SAMPLES // max(periods, 1.0))))), 2)
    grid = np.linspace(0.0, periods * T0, n + 1)
    with _fmu(fmu) as f:
        q = object.__new__(Oscillator)
        q.__dict__.update(prob.oscillator.__dict__, x0=xs, v0=vs)
        tr = f.trajectory(q, grid, prob.settings(), ("x", "v", "mode"))
    x, v = tr["x"], tr["v"]
    d = -prob.direction
    g = x - prob.x_eq
    idx = np.nonzero((np.sign(g[:-1]) == -d) & (np.sign(g[1:]) != -d))[0]
    idx = idx[(tr["mode"][idx] != 0) & (tr["mode"][idx + 1] != 0)]
    w = g[idx] / (g[idx] - g[idx + 1])
    tc = grid[idx] + w * (grid[idx + 1] - grid[idx])
    vc = v[idx] + w * (v[idx + 1] - v[idx])
    return Transient(grid, x, v, tr["mode"], tc, vc)
