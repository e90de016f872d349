"""Running and timing the FMU from Python for the study: the error of one configuration against the
exact solution, and the time of one run through a reused instance, two ways:

- ``api``: what a user writes, ``OscillatorFMU2.start(p, settings)``, ``step_to(t_end)``, ``get(['x'])``;
- ``lean``: the same fmi2 calls on the same instance with the value-reference and value arrays
  built once (the typed functions of dryfriction.fmi.fmi2), to separate the FMU's cost from the
  Python wrapper's.

A timed run simulates the whole horizon in one ``doStep`` and reads ``x``: what a sweep point costs.
The error is measured on a separate, untimed run that samples ``x`` at communication points on the
internal grid (so sampling does not change the trajectory).
"""

from __future__ import annotations

import ctypes
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from dryfriction.drivers.oscillator import OscillatorFMU2, Settings
from dryfriction.params import Oscillator

PARAM_NAMES = ("m", "k", "c", "P0", "omega", "phi", "N", "mu_s", "chi", "x0", "v0")


def best_time(fn: Callable[[], object], budget_s: float, min_reps: int = 3, max_reps: int = 50,
              long_s: float = 1.0) -> tuple[float, int]:
    """Minimum wall time (time.perf_counter) of fn over repetitions: at least min_reps and until
    the total reaches budget_s (at most max_reps); a run longer than long_s is timed once.
    Returns (seconds, repetitions)."""
    best = float("inf")
    total = 0.0
    reps = 0
    while reps < max_reps:
        t0 = time.perf_counter()
        fn()
        dt = time.perf_counter() - t0
        best = min(best, dt)
        total += dt
        reps += 1
        if best >= long_s or (reps >= min_reps and total >= budget_s):
            break
    return best, reps


@dataclass(frozen=True)
class FmuConfig:
    scheme: str
    alpha: float
    steps_per_period: int

    def settings(self, p: Oscillator) -> Settings:
        return Settings(h=p.period / self.steps_per_period, alpha=self.alpha, scheme=self.scheme)


class LeanRunner:
    """The fmi2 calls of OscillatorFMU2.start/step_to/get on the same instance, without the
    driver's Python around them: the FMI layer's typed functions and value arrays built once,
    filled once per configuration. Raises FMUError (through the layer's check) on a failed call."""

    def __init__(self, fmu: OscillatorFMU2) -> None:
        self.fmu = fmu
        self.inst = fmu.fmi
        md = fmu.md
        self.reals = PARAM_NAMES + ("h", "alpha", "t_obs_start", "t_obs_stop")
        self.rvr = (ctypes.c_uint * len(self.reals))(*[md.vr(n) for n in self.reals])
        self.rval = (ctypes.c_double * len(self.reals))()
        self.ivr = (ctypes.c_uint * 2)(md.vr("scheme"), md.vr("frictionUpdates"))
        self.ival = (ctypes.c_int * 2)()
        self.bvr = (ctypes.c_uint * 2)(md.vr("observe"), md.vr("fastPaths"))
        self.bval = (ctypes.c_int * 2)()
        self.xvr = (ctypes.c_uint * 1)(md.vr("x"))
        self.xval = (ctypes.c_double * 1)()

    def prepare(self, p: Oscillator, st: Settings) -> None:
        """Fill the value arrays (outside any timing)."""
        self.rval[:] = tuple(float(getattr(p, n)) for n in PARAM_NAMES) + (st.h, st.alpha, 0.0, 1e300)
        self.ival[0], self.ival[1] = self.fmu.md.scheme_value(st.scheme), st.frictionUpdates
        self.bval[0], self.bval[1] = 0, 1

    def run(self, t_end: float) -> float:
        """One whole run with the prepared values: reset ... doStep(0, t_end), returns x(t_end)."""
        inst = self.inst
        c, f = inst.component, inst.f
        for name, s in (("fmi2Reset", f.Reset(c)), ("fmi2SetupExperiment", f.SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0)),
                        ("fmi2SetReal", f.SetReal(c, self.rvr, len(self.rval), self.rval)),
                        ("fmi2SetInteger", f.SetInteger(c, self.ivr, 2, self.ival)),
                        ("fmi2SetBoolean", f.SetBoolean(c, self.bvr, 2, self.bval)),
                        ("fmi2EnterInitializationMode", f.EnterInitializationMode(c)),
                        ("fmi2ExitInitializationMode", f.ExitInitializationMode(c)),
                        ("fmi2DoStep", f.DoStep(c, 0.0, t_end, 1)),
                        ("fmi2GetReal", f.GetReal(c, self.xvr, 1, self.xval))):
            if s:
                inst.check(name, s)
        return self.xval[0]


def api_run(fmu: OscillatorFMU2, p: Oscillator, st: Settings, t_end: float) -> float:
    """One whole run the way a user writes it with the reused OscillatorFMU2."""
    fmu.start(p, st)
    fmu.step_to(t_end)
    return fmu.get(["x"])["x"]


def sample_times(p: Oscillator, periods: int, steps_per_period: int, samples_per_period: int) -> np.ndarray:
    """Communication points for an error run: every internal step, or every
    steps_per_period/samples_per_period steps when that is finer than the sampling grid."""
    per = min(steps_per_period, samples_per_period)
    n = periods * per
    return np.arange(n + 1) * (periods * p.period / n)


def fmu_error(fmu: OscillatorFMU2, p: Oscillator, cfg: FmuConfig, periods: int, samples_per_period: int,
              exact_x: Callable[[np.ndarray], np.ndarray]) -> tuple[float, int]:
    """max |z - z_exact| (z = k x / P0) at the sample points, and the number of samples."""
    t = sample_times(p, periods, cfg.steps_per_period, samples_per_period)
    tr = fmu.trajectory(p, t, cfg.settings(p), outputs=("x",))
    err = float(np.max(np.abs(tr["x"] - exact_x(t)))) * p.k / abs(p.P0)
    return err, int(t.size)
