"""One FMU in a co-simulation (:class:`Unit`): a started driver of the package (any of the four,
FMI 2.0 or FMI 3.0, in step mode) seen by the master through the FMI layer: real values in and
out by value reference, one checked step, FMU states, and the coupling capabilities its model
description declares (output and input derivatives, directional derivatives)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..errors import FMUError
from ..fmi import fmi2, fmi3
from ..fmi._base import State

__all__ = ["Unit", "DEFAULT_DERIVATIVES"]

#: outputs whose time derivatives are other outputs of the package's FMUs (x' = v, x'' = a, v' = a;
#: the FMI 2.0 chain's x[i], v[i] alike): what the master extrapolates from when the FMU does not
#: give output derivatives itself
DEFAULT_DERIVATIVES: dict[str, tuple[str, ...]] = {"x": ("v", "a"), "v": ("a",)}


def _alias(name: str, table: Mapping[str, tuple[str, ...]]) -> tuple[str, ...]:
    if name in table:
        return table[name]
    base, sep, rest = name.partition("[")
    if sep and base in table:  # x[2] -> v[2], a[2]
        return tuple(f"{d}[{rest}" for d in table[base])
    return ()


class Unit:
    """An FMU of a :class:`~dryfriction.cosim.system.System` under its instance name."""

    def __init__(self, name: str, driver: Any, derivatives: Mapping[str, tuple[str, ...]] | None = None) -> None:
        inst = getattr(driver, "inst", None)
        if not isinstance(inst, (fmi2.Instance, fmi3.Instance)) or inst.freed:
            raise FMUError(f"{name}: not an open driver of this package (OscillatorFMU2/3, ChainFMU2/3)")
        self.name, self.driver, self.inst = name, driver, inst
        self.fmi3 = isinstance(inst, fmi3.Instance)
        self.kind = "Float64" if self.fmi3 else "Real"
        self.capabilities = inst.capabilities
        self._derivs = dict(DEFAULT_DERIVATIVES if derivatives is None else derivatives)
        self._state: State | None = None

    # ---- names ------------------------------------------------------------------------------------
    def vr(self, var: str) -> int:
        """The value reference of a real scalar variable of this unit (FMUError if it has none or it is not
        one)."""
        md = self.driver.md
        v = md.variables.get(var)
        if v is None:
            raise FMUError(f"{self.name} has no variable {var!r}")
        if v.call_type not in ("Real", "Float64") or v.dimension is not None:
            raise FMUError(f"{self.name}.{var} is not a real scalar: the master couples real scalars")
        return int(v.vr)

    def causality(self, var: str) -> str:
        """The causality of a variable (``input``, ``output``, ``parameter``, ``local``, ...)."""
        return str(self.driver.md.var(var).causality)

    def derivative_outputs(self, var: str) -> tuple[str, ...]:
        """The outputs that are var's first, second, ... time derivatives (empty if none known)."""
        return tuple(d for d in _alias(var, self._derivs) if d in self.driver.md.variables)

    # ---- values -----------------------------------------------------------------------------------
    def get(self, vrs: Sequence[int]) -> np.ndarray:
        """The values of the real variables ``vrs``."""
        return np.array(self.inst.get(self.kind, list(vrs)), dtype=float)

    def set(self, vrs: Sequence[int], values: Sequence[float]) -> None:
        """Set the real variables ``vrs`` to ``values``."""
        if len(vrs):
            self.inst.set(self.kind, list(vrs), [float(v) for v in values])

    def output_derivatives(self, vrs: Sequence[int], order: int) -> np.ndarray:
        """The FMU's own ``order``-th time derivatives of the outputs ``vrs`` (FMI 2.0
        fmi2GetRealOutputDerivatives, FMI 3.0 fmi3GetOutputDerivatives)."""
        if self.fmi3:
            return self.inst.get_output_derivatives(list(vrs), order)
        return self.inst.get_real_output_derivatives(list(vrs), order)

    def set_input_derivatives(self, vrs: Sequence[int], derivs: Sequence[np.ndarray]) -> None:
        """The inputs' 1st, 2nd, ... time derivatives for the next step (FMI 2.0 only)."""
        if self.fmi3:
            raise FMUError(f"{self.name}: FMI 3.0 has no input derivatives; its inputs vary through "
                           "intermediate updates")
        for order, values in enumerate(derivs, start=1):
            self.inst.set_real_input_derivatives(list(vrs), order, list(values))

    def jacobian(self, unknowns: Sequence[int], knowns: Sequence[int]) -> np.ndarray:
        """d unknowns / d knowns at the current point, from the FMU's directional derivatives."""
        if not self.capabilities.directional_derivatives:
            decl = "providesDirectionalDerivatives" if self.fmi3 else "providesDirectionalDerivative"
            raise FMUError(f"{self.name} declares {decl}=\"false\": no directional derivatives "
                           "(use jacobian='steps')")
        return self.inst.jacobian(list(unknowns), list(knowns))

    # ---- steps and states -------------------------------------------------------------------------
    def step(self, t: float, dt: float) -> None:
        """One checked step from t (the driver's time follows)."""
        if self.fmi3:
            res = self.inst.do_step(t, dt)
            if res.early_return or res.event_handling_needed or res.terminate_simulation:
                raise FMUError(f"{self.name}: fmi3DoStep returned early, asked for event handling or to terminate "
                               f"at t = {res.last_successful_time!r}; the master needs an instance made without early "
                               "return and event mode")
        else:
            self.inst.do_step(t, dt)
        self.driver.time = t + dt

    def save(self) -> None:
        """Remember the current state (one state per unit, overwritten by the next save)."""
        self._state = self.inst.get_state(self._state)

    def restore(self, t: float) -> None:
        """Go back to the saved FMU state, at time ``t`` (FMUError when none was saved)."""
        if self._state is None:
            raise FMUError(f"{self.name}: no saved state to go back to")
        self.inst.set_state(self._state)
        self.driver.time = t

    def free_state(self) -> None:
        """Free the saved FMU state, if any."""
        if self._state is not None:
            self._state.free()
            self._state = None
