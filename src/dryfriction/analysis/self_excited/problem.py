"""The autonomous belt problem and its model (dryfriction.analysis.self_excited)."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

from ...drivers.oscillator import Settings
from ...params import Oscillator

LAWS = {"coulomb": 1, "stribeck": 2}
SCHEMES = ("located", "exact")
#: an orbit (and steady sliding) is stable when its nontrivial multipliers have |mu| < 1 - STABILITY_MARGIN
STABILITY_MARGIN = 1e-9
#: steady sliding is neutral (neither stable nor unstable: e.g. undamped Coulomb, a centre) when its
#: largest |mu| is within this of 1 (the located scheme's own damping and the differences' error are
#: far smaller: 5e-8 over a period at 2000 steps)
NEUTRAL = 1e-6
#: a solution with |v0| under TRIVIAL V on the section is steady sliding itself (R vanishes there
#: for every T), not an orbit
TRIVIAL = 1e-6
#: the most samples of a transient (a slow belt's long stick phases)
MAX_SAMPLES = 200_000
#: internal steps per natural period by default (scheme located)
STEPS_PER_PERIOD = 2000
#: relative size of the central differences, of the state's scales X and X w0
FD_STEP = 1e-6
#: the same for the equilibrium's flow (smooth there: larger steps, less of the located scheme's
#: rounding, with Richardson's extrapolation of the steps d and d / 2)
EQ_FD_STEP = 1e-4
JACOBIAN = ("dx_dx0", "dx_dv0", "dv_dx0", "dv_dv0")


@dataclass(frozen=True)
class BeltProblem:
    """The autonomous belt oscillator: ``oscillator`` gives m, k, c, N, mu_s, chi (mu_k = chi mu_s) and
    no excitation (P0 = 0, or omega = 0: then P0 cos(phi) is a constant force); the belt at
    ``v_belt`` (m/s, nonzero); the friction law with v_s (m/s) and delta; ``F_ext`` a constant force
    (N); the FMU's ``scheme`` (located or exact) and internal step ``h`` (s; None: the natural
    period / 2000)."""

    oscillator: Oscillator
    v_belt: float
    law: str = "coulomb"
    v_s: float = 0.01
    delta: float = 1.0
    F_ext: float = 0.0
    scheme: str = "located"
    h: float | None = None

    def __post_init__(self) -> None:
        p = self.oscillator
        if not isinstance(p, Oscillator):
            raise ValueError(f"oscillator must be an Oscillator, not {type(p).__name__}")
        if p.P0 != 0.0 and p.omega > 0.0:
            raise ValueError(f"the self-excited motion needs no excitation: P0 = 0 or omega = 0 (a constant force), "
                             f"not P0 = {p.P0:g} at omega = {p.omega:g}")
        if not p.k > 0:
            raise ValueError(f"k (stiffness) must be > 0 for a self-excited motion (a sliding equilibrium), "
                             f"not {p.k!r}")
        if not p.N > 0:
            raise ValueError(f"N (normal force) must be > 0 for a self-excited motion, not {p.N!r}")
        for name in ("v_belt", "v_s", "delta", "F_ext"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ValueError(f"{name} must be a finite real number, not {v!r}")
            object.__setattr__(self, name, float(v))
        if self.v_belt == 0.0:
            raise ValueError("v_belt (belt speed) must be nonzero: a belt at rest excites nothing")
        if self.law not in LAWS:
            raise ValueError(f"law (friction law) must be one of {', '.join(LAWS)}, not {self.law!r}")
        if not self.v_s > 0:
            raise ValueError(f"v_s (Stribeck velocity) must be > 0, not {self.v_s!r}")
        if self.law == "stribeck" and not self.delta >= 1.0:
            raise ValueError(f"delta (Stribeck exponent) must be >= 1, not {self.delta!r}")
        if self.scheme not in SCHEMES:
            raise ValueError(f"scheme must be one of {', '.join(SCHEMES)}, not {self.scheme!r}")
        if self.scheme == "exact" and self.law != "coulomb":
            raise ValueError("scheme exact supports law coulomb only (its closed form needs a constant kinetic "
                             "friction): use scheme located for stribeck")
        if self.h is not None and not (isinstance(self.h, (int, float)) and math.isfinite(self.h) and self.h > 0):
            raise ValueError(f"h (internal step) must be > 0 s (or None: the natural period / {STEPS_PER_PERIOD}), "
                             f"not {self.h!r}")

    def with_(self, **kw: Any) -> "BeltProblem":
        """A copy with the given fields changed."""
        return replace(self, **kw)

    # ---- the model ----
    @property
    def m(self) -> float:
        """The block's mass, kg."""
        return self.oscillator.m

    @property
    def w0(self) -> float:
        """The natural angular frequency sqrt(k / m), rad/s."""
        return self.oscillator.w0

    @property
    def natural_period(self) -> float:
        """The natural period 2 pi / w0, s."""
        return 2.0 * math.pi / self.w0

    @property
    def step(self) -> float:
        """The FMU's internal step h: the given one, or the natural period over the default number of steps
        per period."""
        return self.natural_period / STEPS_PER_PERIOD if self.h is None else float(self.h)

    @property
    def force(self) -> float:
        """The constant force F_0, N."""
        p = self.oscillator
        return self.F_ext + (p.P0 * math.cos(p.phi) if p.omega == 0.0 else 0.0)

    @property
    def mu_k(self) -> float:
        """The kinetic friction coefficient."""
        return self.oscillator.mu_k

    def mu(self, u: float) -> float:
        """The sliding coefficient at the relative speed u >= 0."""
        p = self.oscillator
        if self.law == "coulomb":
            return p.mu_k
        return p.mu_k + (p.mu_s - p.mu_k) * math.exp(-((u / self.v_s) ** self.delta))

    @property
    def direction(self) -> int:
        """sign(v_belt)."""
        return 1 if self.v_belt > 0 else -1

    @property
    def x_eq(self) -> float:
        """The steady sliding position, m."""
        p = self.oscillator
        return (self.force + self.direction * p.N * self.mu(abs(self.v_belt))) / p.k

    @property
    def scales(self) -> tuple[float, float]:
        """(X, V): X = max(mu_s, mu_k) N / k, V = X w0."""
        p = self.oscillator
        X = max(p.mu_s, p.mu_k) * p.N / p.k
        X = X if X > 0 else abs(self.v_belt) / self.w0
        return X, X * self.w0

    def acceleration(self, x: float, v: float) -> float:
        """The vector field's acceleration of a sliding block (v != v_belt), m/s^2."""
        p = self.oscillator
        vr = v - self.v_belt
        fr = -math.copysign(1.0, vr) * p.N * self.mu(abs(vr)) if vr != 0.0 else 0.0
        return (self.force - p.c * v - p.k * x + fr) / p.m

    def settings(self, sensitivity: bool = False, t_obs: float | None = None) -> Settings:
        """The FMU settings of a run of this problem (belt speed, friction law, step; the state's Jacobian
        when ``sensitivity``; the observables from ``t_obs`` on)."""
        extra: dict[str, Any] = {"v_belt": self.v_belt}
        if self.F_ext != 0.0:
            extra["F_ext"] = self.F_ext
        if sensitivity:
            extra["sensitivity"] = True
        st = Settings(h=self.step, scheme=self.scheme, friction_law=LAWS[self.law], v_s=self.v_s, delta=self.delta,
                      extra=extra)
        if t_obs is not None:
            st.observe, st.t_obs_start, st.t_obs_stop = True, 0.0, t_obs
        return st
