"""The five cases of the work-precision study, in the non-dimensional form of method.md (2).

Each case is built through ``Oscillator.from_nondimensional`` (m = 1 kg, k = 100 N/m, P0 = 1 N,
mu_s = 0.4, so w0 = 10 rad/s, the static deflection P0/k = 1 cm) and starts from rest. The "why"
says what the case stresses; the study checks it against the exact solution (stick share, number of
stick phases) and writes both into its CSV and markdown. bench_stepper.c holds a copy of this table
as its default; the study passes these values to it explicitly.
"""

from __future__ import annotations

from dataclasses import dataclass

from dryfriction.params import Oscillator


@dataclass(frozen=True)
class Case:
    name: str
    lam: float          # excitation over natural frequency
    mu_s_sigma: float   # static friction force over excitation amplitude, mu_s N / P0
    chi: float          # mu_k / mu_s
    zeta: float         # damping ratio
    why: str

    @property
    def oscillator(self) -> Oscillator:
        return Oscillator.from_nondimensional(self.lam, self.mu_s_sigma, self.chi, self.zeta)

    def c_arg(self) -> str:
        """The --case argument of bench_stepper."""
        return f"{self.name},{self.lam!r},{self.mu_s_sigma!r},{self.chi!r},{self.zeta!r}"


CASES: tuple[Case, ...] = (
    Case("stick_dominated", 0.25, 0.6, 0.6, 0.0,
         "slow forcing against a high static limit: the block is stuck most of the time and breaks away "
         "twice per period, so every period has four stick/slip switches (the stick-slip case of the "
         "order test)"),
    Case("reversal_resonance", 0.9, 0.1, 0.8, 0.0,
         "near resonance with light friction: the velocity reverses without ever sticking, amplitudes "
         "grow to ~9 static deflections; only the friction sign flips"),
    Case("heavy_damped", 1.0, 0.7, 0.9, 0.2,
         "at resonance with friction close to the non-stop limit 4 mu_k N < pi P0 and 20 % viscous "
         "damping: short stick phases at every turning point, the damping path of the stepper"),
    Case("chi_above_1", 0.5, 0.3, 1.5, 0.0,
         "kinetic coefficient above the static one: breakaway needs mu_k N and starts with zero "
         "acceleration (a tangential start that defeats naive event tests)"),
    Case("chi_near_0", 0.5, 0.4, 0.05, 0.0,
         "almost frictionless sliding but a full static limit: every stop must decide stick vs "
         "reversal on the static force; method.md's case where the paper's literal scheme has an "
         "O(1) error floor"),
)

CASE_BY_NAME = {c.name: c for c in CASES}
