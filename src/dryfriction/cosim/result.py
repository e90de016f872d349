"""The result of a co-simulation run (:class:`CosimResult`): numpy arrays by port name, the
counts of the master's work, and an xarray Dataset on request."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["CosimResult"]


@dataclass
class CosimResult:
    """Outputs at every accepted communication point ``t`` [nt] (``outputs["b1.x"]`` [nt]), the
    inputs the master applied over the step that starts at each point (``inputs["b1.F_ext"]``
    [nt], NaN at the last point; the held value, or the polynomial's value at the start of the
    step), and what the master did."""

    t: np.ndarray
    outputs: dict[str, np.ndarray]
    inputs: dict[str, np.ndarray]
    #: accepted macro steps
    steps: int = 0
    #: rejected steps (redone at half the step from the saved FMU states)
    rejected: int = 0
    #: accepted at the smallest step allowed with the error estimate above the tolerance
    unmet: int = 0
    #: the largest error estimate of an accepted step (NaN without a tolerance)
    max_error: float = float("nan")
    #: FMU steps taken in all, by every unit (the first passes, the Jacobian's and the redone ones)
    fmu_steps: int = 0
    settings: dict[str, Any] = field(default_factory=dict)

    def __getitem__(self, port: str) -> np.ndarray:
        if port in ("t", "time"):
            return self.t
        if port in self.outputs:
            return self.outputs[port]
        return self.inputs[port]

    @property
    def H(self) -> np.ndarray:
        """The length of every accepted step."""
        return np.diff(self.t)

    def to_dataset(self) -> Any:
        """An xarray Dataset over ``time``: one variable per port (its name as given, ``b1.x``)."""
        import xarray as xr

        data = {p: ("time", v) for p, v in {**self.outputs, **self.inputs}.items()}
        attrs = {k: (str(v) if not isinstance(v, (int, float, str)) else v) for k, v in self.settings.items()}
        attrs.update(steps=self.steps, rejected=self.rejected, unmet=self.unmet, fmu_steps=self.fmu_steps)
        return xr.Dataset(data, coords={"time": ("time", self.t, {"units": "s"})}, attrs=attrs)
