"""Validation of the FMU against the exact piecewise solution (method.md section 5).

Two checks, used by ``dryfriction validate`` and by the tests:

* the paper's first validation: x, v, a over the first full cycle of forward slip, stick and
  backward slip, FMU against the exact solution;
* convergence: max |x - x_exact| over a number of excitation periods as h is halved, per scheme,
  and the observed order log2(e(h) / e(h/2)).
"""

from __future__ import annotations

import functools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..references.exact import solve_exact
from ..drivers.oscillator import OscillatorFMU2, Settings
from ..model import LazyMapping
from ..params import Oscillator

# The validation cases: (name, parameters, why). Non-dimensional values of method.md (2); made on
# first use (an Oscillator needs the model description, never read at import).
CASES: Mapping[str, tuple[Oscillator, str]] = LazyMapping(lambda: {
    "stick-dominated": (
        Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.4, chi=0.7),
        "lambda 0.5, mu_s sigma 0.4, chi 0.7: stick every half cycle (method.md section 4 case)",
    ),
    "reversal-only": (
        Oscillator.from_nondimensional(lam=0.8, mu_s_sigma=0.1, chi=0.7),
        "lambda 0.8, mu_s sigma 0.1: slides through every turning point without sticking",
    ),
    "heavy-friction": (
        Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.8, chi=0.6, zeta=0.1),
        "mu_s sigma 0.8, zeta 0.1: long sticks, short slips, viscous damping",
    ),
    "chi-small": (
        Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.4, chi=0.05),
        "chi 0.05: kinetic friction far below static (the paper scheme's worst case)",
    ),
    "chi-large": (
        Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.2, chi=2.0),
        "chi 2: kinetic above static, breakaway with zero acceleration",
    ),
})


@functools.cache
def first_cycle_oscillator() -> Oscillator:
    """The paper's first validation: from rest, one excitation period holds forward slip, stick,
    backward slip and stick again (lambda 0.3, mu_s sigma 0.7, chi 0.5). Also ``FIRST_CYCLE``."""
    return Oscillator.from_nondimensional(lam=0.3, mu_s_sigma=0.7, chi=0.5)


def __getattr__(name: str) -> Any:
    if name == "FIRST_CYCLE":  # made on first use, as CASES
        return first_cycle_oscillator()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


@dataclass(frozen=True)
class Convergence:
    """The errors of one scheme on one case against the exact solution, at several steps per period, with the
    observed orders."""
    scheme: str
    steps_per_period: tuple[int, ...]
    errors: tuple[float, ...]          # max |x - x_exact| * k / P0 (non-dimensional)

    @property
    def orders(self) -> np.ndarray:
        """The observed orders log2(e_i / e_{i+1}) between successive halvings of the step."""
        e = np.asarray(self.errors)
        return np.log2(e[:-1] / e[1:])

    @property
    def ratios(self) -> np.ndarray:
        """The error ratios e_i / e_{i+1} between successive halvings of the step."""
        e = np.asarray(self.errors)
        return e[:-1] / e[1:]


def sample_times(p: Oscillator, periods: float, per_period: int = 20) -> np.ndarray:
    """Communication points: per_period per excitation period (multiples of T / per_period)."""
    n = int(round(periods * per_period))
    return np.arange(n + 1) * (p.period / per_period)


def convergence(
    fmu: OscillatorFMU2,
    p: Oscillator,
    scheme: str = "located",
    steps_per_period: Sequence[int] = (400, 800, 1600, 3200),
    periods: float = 10.0,
    alpha: float = -0.1,
    times: np.ndarray | None = None,
) -> Convergence:
    """Max position error against the exact solution as h = T / n shrinks."""
    t = sample_times(p, periods) if times is None else np.asarray(times)
    x_ex = solve_exact(p, float(t[-1])).evaluate(t)[0]
    scale = p.k / p.P0
    errors = []
    for n in steps_per_period:
        r = fmu.trajectory(p, t, Settings(h=p.period / n, scheme=scheme, alpha=alpha), outputs=("x",))
        errors.append(float(np.max(np.abs(r["x"] - x_ex)) * scale))
    return Convergence(scheme, tuple(steps_per_period), tuple(errors))


@dataclass(frozen=True)
class FirstCycle:
    """The FMU's first cycle of stick-slip against the exact solution: the sampled x, v, a of both, the modes
    seen and the largest errors relative to their ranges."""
    t: np.ndarray
    fmu: dict[str, np.ndarray]
    exact: dict[str, np.ndarray]
    modes_seen: tuple[int, ...]        # modes of the exact solution in order of appearance
    errors: dict[str, float]           # max error of x, v, a relative to their ranges


def first_cycle(fmu: OscillatorFMU2, p: Oscillator | None = None, steps_per_period: int = 1000,
                samples: int = 1000) -> FirstCycle:
    """The paper's first validation: one excitation period from rest, FMU against the exact solution
    (``p``: :func:`first_cycle_oscillator` unless given)."""
    p = first_cycle_oscillator() if p is None else p
    t = np.linspace(0.0, p.period, samples + 1)
    r = fmu.trajectory(p, t, Settings(h=p.period / steps_per_period))
    x, v, a, mode = solve_exact(p, p.period).evaluate(t)
    ex = {"x": x, "v": v, "a": a, "mode": mode}
    seen: list[int] = []
    for m in mode.astype(int):
        if not seen or seen[-1] != m:
            seen.append(int(m))
    errors = {}
    for k in ("x", "v", "a"):
        span = float(np.ptp(ex[k])) or 1.0
        diff = np.abs(r[k] - ex[k])
        if k == "a":
            # the acceleration jumps at switches; compare away from them (one internal step)
            sw = solve_exact(p, p.period).switch_times()
            near = np.zeros_like(t, dtype=bool)
            for ts in sw:
                near |= np.abs(t - ts) <= 2.0 * p.period / steps_per_period
            diff = diff[~near]
        errors[k] = float(np.max(diff) / span)
    return FirstCycle(t, r, ex, tuple(seen), errors)
