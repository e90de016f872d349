"""The Modelica Standard Library's sliding mass with Stribeck friction on a spring, as the oscillator
FMU's start values.

The FMIZoo's ``SpringFrictionPendulum1D`` (exported by Dymola and SimulationX) is a
``Modelica.Mechanics.Translational.Components.MassWithStopAndFriction`` of mass m tied to a fixed
point by a ``Spring`` of stiffness c_spring and unstretched length s_rel0::

    m s'' = -c_spring (s - s_rel0) - f,
    sliding:  f = F_prop v + sign(v) (F_Coulomb + F_Stribeck exp(-fexp |v|)),
    stuck:    v = 0 while the holding force stays within F_Coulomb + F_Stribeck (plus the element's margin).

Our oscillator (docs/model_exchange.md, "The FMIZoo friction pendulum") reads it with x = s,
k = c_spring, the spring's offset as the constant force F_ext = k s_rel0, the viscous term as the
damper c = F_prop, N = 1 N and the Stribeck law mu(u) = mu_k + (mu_s - mu_k) exp(-(u / v_s)^delta)::

    mu_s N = F_Coulomb + F_Stribeck,   mu_k N = F_Coulomb,   v_s = 1 / fexp,   delta = 1.

    from dryfriction.drivers.modelica import SpringFrictionPendulum
    from fmpy import simulate_fmu
    zoo = SpringFrictionPendulum()                      # the FMIZoo's parameters
    r = simulate_fmu("build/DryFrictionOscillator.fmu", fmi_type="ModelExchange", stop_time=8.0,
                     relative_tolerance=1e-10, start_values=zoo.start_values(), output=["x", "v"])

What the element does that this mapping leaves out: its hard stops smin, smax (this model's motion
never reaches them: ``reaches_stops``), its breakaway margin (``msl_breakaway``: it breaks away
beyond 1.001 (F_Coulomb + F_Stribeck), ours beyond F_Coulomb + F_Stribeck) and its ``v_small`` (a
direct reversal once the speed passes v_small against the sliding direction; every stop here is
located at v = 0, where it plays no part).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["SpringFrictionPendulum", "DYMOLA_S_AT_8"]

#: the FMIZoo's published Dymola result of ``SpringFrictionPendulum1D``: s(8 s) in m, stuck
DYMOLA_S_AT_8 = 1.06736

#: ``MassWithStopAndFriction``'s breakaway margin: it breaks away beyond ``f0_max = 1.001 f0``
MSL_BREAKAWAY_FACTOR = 1.001


@dataclass(frozen=True)
class SpringFrictionPendulum:
    """A ``MassWithStopAndFriction`` on a ``Spring`` to a fixed point, in the Modelica parameters
    (SI units); the defaults are the FMIZoo's ``SpringFrictionPendulum1D`` (fricScale = 20)."""

    m: float = 1.0
    c_spring: float = 10.0
    s_rel0: float = 1.0
    F_prop: float = 0.05
    F_Coulomb: float = 0.25
    F_Stribeck: float = 0.5
    fexp: float = 2.0
    s0: float = 0.5
    v0: float = 0.0
    smin: float = -25.0
    smax: float = 25.0

    def __post_init__(self) -> None:
        for name in ("m", "c_spring"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0, not {getattr(self, name)!r}")
        for name in ("F_prop", "F_Coulomb", "F_Stribeck", "fexp"):
            if not getattr(self, name) >= 0:
                raise ValueError(f"{name} must be >= 0, not {getattr(self, name)!r}")
        if not (math.isfinite(self.s0) and math.isfinite(self.v0) and self.smin < self.s0 < self.smax):
            raise ValueError(f"s0 = {self.s0!r} must lie strictly between smin = {self.smin!r} "
                             f"and smax = {self.smax!r}")

    @property
    def breakaway(self) -> float:
        """Our breakaway limit F_Coulomb + F_Stribeck (the element's f0), N."""
        return self.F_Coulomb + self.F_Stribeck

    @property
    def msl_breakaway(self) -> float:
        """The element's breakaway limit f0_max = 1.001 f0, N."""
        return MSL_BREAKAWAY_FACTOR * self.breakaway

    def friction(self, v: float) -> float:
        """The element's sliding friction force f at the speed v != 0 (viscous term included), N."""
        return self.F_prop * v + math.copysign(self.F_Coulomb + self.F_Stribeck * math.exp(-self.fexp * abs(v)), v)

    @property
    def reaches_stops(self) -> bool:
        """Whether the energy bound allows the hard stops: |s - s_rel0| never exceeds the amplitude
        the initial spring and kinetic energy give without friction."""
        amp = math.hypot(self.s0 - self.s_rel0, self.v0 * math.sqrt(self.m / self.c_spring))
        return self.s_rel0 - amp <= self.smin or self.s_rel0 + amp >= self.smax

    def start_values(self) -> dict[str, float]:
        """The oscillator FMU's start values for this pendulum (x = s; no harmonic excitation)."""
        if self.reaches_stops:
            raise ValueError(f"the motion may reach a hard stop (smin = {self.smin}, smax = {self.smax}), "
                             "which the oscillator does not model")
        start: dict[str, float] = {
            "m": self.m, "k": self.c_spring, "c": self.F_prop, "P0": 0.0, "N": 1.0,
            "x0": self.s0, "v0": self.v0, "F_ext": self.c_spring * self.s_rel0,
        }
        if self.breakaway == 0:
            return {**start, "mu_s": 0.0, "chi": 1.0}
        if self.F_Stribeck > 0 and self.fexp == 0:  # exp(0) = 1: Coulomb friction at F_Coulomb + F_Stribeck
            return {**start, "mu_s": self.breakaway, "chi": 1.0}
        start.update(mu_s=self.breakaway, chi=self.F_Coulomb / self.breakaway)
        if self.F_Stribeck > 0:
            start.update(friction_law=2, v_s=1.0 / self.fexp, delta=1.0)
        return start
