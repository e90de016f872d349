"""Scenes: configured uses of the FMU that pay only for the physics and observables they need.

A scene decides how the FMU is driven (one communication step or many, inputs or not) and which
in-FMU observables are switched on. The FMU itself picks its fast paths from the parameters
(no LCP when mu N = 0, no coefficient update when chi = 1, no damping arithmetic when c = 0,
inputs read only once set); its ``effects`` parameter says what a run simulates.

    validation  full trajectories x, v, a, F_friction, mode at every output point
    sweep       mean amplitude and asymmetry after the transient: observables, one doStep
    stiction    share of time stuck and number of switches in one period: observables, one doStep
    coupled     a co-simulation master feeds F_ext and N_ext every communication step
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from .oscillator import OscillatorFMU2, Settings
from ..params import Oscillator

InputFn = Callable[[float, dict[str, float]], dict[str, float]]


@dataclass(frozen=True)
class Scene:
    """A scene: a named way to run the FMU, with whether it computes the in-FMU observables and whether it
    samples a trajectory."""
    name: str
    description: str
    observe: bool            # in-FMU observables on
    trajectory: bool         # outputs sampled at every communication point

    def settings(self, base: Settings | None = None) -> Settings:
        """The settings of a run of this scene: ``base`` (or the defaults) with the scene's ``observe``."""
        return replace(base or Settings(), observe=self.observe)


SCENES: dict[str, Scene] = {
    s.name: s
    for s in (
        Scene("validation", "full trajectories (x, v, a, F_friction, mode) at every output point", False, True),
        Scene("sweep", "mean amplitude and asymmetry over a window after the transient, in-FMU", True, False),
        Scene("stiction", "share of time stuck and switch count over one period, in-FMU", True, False),
        Scene("coupled", "a master feeds F_ext and N_ext at every communication step", False, True),
    )
}


def get_scene(name: str) -> Scene:
    """The scene named ``name`` (ValueError naming the scenes there are)."""
    try:
        return SCENES[name]
    except KeyError:
        raise ValueError(f"unknown scene {name!r}; choose one of: {', '.join(SCENES)}") from None


def run_validation(fmu: OscillatorFMU2, p: Oscillator, periods: float, samples_per_period: int = 100,
                   settings: Settings | None = None) -> dict[str, np.ndarray]:
    """Scene 'validation': the full trajectory."""
    t = np.arange(int(round(periods * samples_per_period)) + 1) * (p.period / samples_per_period)
    return fmu.trajectory(p, t, SCENES["validation"].settings(settings))


def run_sweep_point(fmu: OscillatorFMU2, p: Oscillator, transient_periods: float = 30.0,
                    window_periods: float = 1.0, settings: Settings | None = None) -> dict[str, float]:
    """Scene 'sweep': amplitude (x_max - x_min)/2 and asymmetry (x_max + x_min)/2 after the
    transient, computed inside the FMU over [transient, transient + window] periods of one run
    from the initial state (the paper's Fig. 8/9 measure: the window of a transient, not a steady
    state; :func:`dryfriction.analysis.response.steady_state` finds that). The result says which window
    it measured: ``window_start_period``, ``window_periods``, ``run_periods``."""
    T = p.period
    o = fmu.observables(p, (transient_periods + window_periods) * T, transient_periods * T,
                        settings=SCENES["sweep"].settings(settings))
    return {"amplitude": (o["x_max"] - o["x_min"]) / 2, "asymmetry": (o["x_max"] + o["x_min"]) / 2, **o,
            "window_start_period": float(transient_periods), "window_periods": float(window_periods),
            "run_periods": float(transient_periods + window_periods)}


def sweep_window_text(p: Oscillator, transient_periods: float, window_periods: float = 1.0) -> str:
    """What the sweep scene measured, in one sentence (printed with its numbers)."""
    a, b = transient_periods, transient_periods + window_periods
    return (f"x over excitation periods {a:g} to {b:g} (t = {a * p.period:.6g} ... {b * p.period:.6g} s) of one run "
            f"from x0 = {p.x0:g} m, v0 = {p.v0:g} m/s: a transient's window (the paper's Fig. 8/9 measure), "
            "not a steady state; for the steady amplitude use 'dryfriction response'")


def run_stiction(fmu: OscillatorFMU2, p: Oscillator, period_index: int = 30,
                 settings: Settings | None = None) -> dict[str, float]:
    """Scene 'stiction': share of the period_index-th excitation period spent stuck (1-based)."""
    T = p.period
    o = fmu.observables(p, period_index * T, (period_index - 1) * T, settings=SCENES["stiction"].settings(settings))
    return {"stick_percent": 100.0 * o["stick_fraction"], **o}


def run_coupled(fmu: OscillatorFMU2, p: Oscillator, t_stop: float, dt: float, inputs: InputFn,
                settings: Settings | None = None) -> dict[str, np.ndarray]:
    """Scene 'coupled': at every communication point the master computes F_ext and N_ext from
    the time and the FMU's outputs (x, v), sets them and steps."""
    n = int(round(t_stop / dt))
    st = SCENES["coupled"].settings(settings)
    # the inputs are connected from the start: their first values are set before initialisation
    first = inputs(0.0, {"x": p.x0, "v": p.v0, "F_friction": 0.0, "mode": 0.0})
    fmu.start(p, replace(st, extra={**st.extra, **first}))
    names = ("x", "v", "F_friction", "mode")
    out = {k: np.empty(n + 1) for k in ("t", *names)}
    for j in range(n + 1):
        y = fmu.get(names)
        out["t"][j] = j * dt
        for k in names:
            out[k][j] = y[k]
        if j < n:
            fmu.set(inputs(j * dt, y))
            fmu.step_to((j + 1) * dt)
    return out
