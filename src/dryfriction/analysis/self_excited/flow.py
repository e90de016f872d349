"""The FMU's flow of a belt problem and its Jacobian (dryfriction.analysis.self_excited)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from ...drivers.oscillator import OscillatorFMU2
from ...params import Oscillator
from .problem import FD_STEP, JACOBIAN, BeltProblem


class _Flow:
    """The FMU's flow of one problem: (x, v) at t = 0 -> the state at t = T (one doStep)."""

    def __init__(self, fmu: OscillatorFMU2, prob: BeltProblem) -> None:
        self.fmu, self.prob = fmu, prob
        self.exact = prob.scheme == "exact"
        self.X, self.V = prob.scales
        self.evaluations = 0

    def _osc(self, x: float, v: float) -> Oscillator:
        p = self.prob.oscillator
        q = object.__new__(Oscillator)          # a checked one with x0, v0 replaced (finite)
        q.__dict__.update(p.__dict__, x0=float(x), v0=float(v))
        return q

    def end(self, x: float, v: float, T: float, observe: bool = False) -> dict[str, float]:
        """x, v, mode at T (with ``observe``: x_max, x_min, stick_fraction, transitions over [0, T];
        with scheme exact: the sensitivities too)."""
        if not (math.isfinite(x) and math.isfinite(v) and math.isfinite(T) and T > 0):
            raise FloatingPointError(f"not a state and a period: x = {x}, v = {v}, T = {T}")
        f = self.fmu
        f.start(self._osc(x, v), self.prob.settings(self.exact, T if observe else None))
        f.step_to(T)
        names = ("x", "v", "mode") + (("x_max", "x_min", "stick_fraction", "transitions") if observe else ()) \
            + (JACOBIAN if self.exact else ())
        self.evaluations += 1
        return {k: float(val) for k, val in f.get(names).items()}

    def jacobian(self, x: float, v: float, T: float, end: dict[str, float] | None = None,
                 columns: Sequence[int] = (0, 1), step: float = FD_STEP, richardson: bool = False) -> np.ndarray:
        """M = d(x, v)(T) / d(x, v)(0): the FMU's sensitivity (exact) or central differences (located);
        only ``columns`` are computed with differences (the others NaN); ``richardson``: the
        differences of steps d and d / 2 combined, (4 M(d / 2) - M(d)) / 3 (error O(d^4))."""
        if self.exact:
            e = end if end is not None and "dx_dx0" in end else self.end(x, v, T)
            J = np.array([[e["dx_dx0"], e["dx_dv0"]], [e["dv_dx0"], e["dv_dv0"]]])
            if not np.all(np.isfinite(J)):
                raise FloatingPointError("the FMU's sensitivity is not available (NaN)")
            return J
        if richardson:
            fine = self.jacobian(x, v, T, None, columns, step / 2.0)
            return (4.0 * fine - self.jacobian(x, v, T, None, columns, step)) / 3.0
        J = np.full((2, 2), np.nan)
        for j in columns:
            d = step * (self.X if j == 0 else self.V)
            dz = (d, 0.0) if j == 0 else (0.0, d)
            a = self.end(x + dz[0], v + dz[1], T)
            b = self.end(x - dz[0], v - dz[1], T)
            J[:, j] = [(a["x"] - b["x"]) / (2 * d), (a["v"] - b["v"]) / (2 * d)]
        return J


class _fmu:
    """The given FMU, or one loaded for the call and closed after it."""

    def __init__(self, fmu: OscillatorFMU2 | None) -> None:
        self.given, self.fmu = fmu, fmu

    def __enter__(self) -> OscillatorFMU2:
        if self.fmu is None:
            self.fmu = OscillatorFMU2()
        return self.fmu

    def __exit__(self, *exc: Any) -> None:
        if self.given is None and self.fmu is not None:
            self.fmu.close()
