"""The cases of bench/siconos_peer.py: what Siconos and the FMU both simulate, and the reference
each is measured against.

1. ``tutorial``: Siconos's own FrictionOscillator example, m = k = 1, Coulomb force 1 (mu_s = mu_k),
   x0 = 12, v0 = 6, no forcing, 30 s, against its closed form (:func:`tutorial_closed_form`).
2. ``wp_<case>_chi1``: the five cases of bench/cases.py with chi = 1 (mu_k = mu_s), 10 excitation
   periods from rest, against ``dryfriction.references.exact.solve_exact``; error in static deflections
   (z = k x / P0) as in bench/work_precision.py. The cases themselves (chi = 0.6, 0.8, 0.9, 1.5,
   0.05) are outside Siconos's relay law, which has one friction coefficient: distinct static and
   kinetic coefficients cannot be written as ``RelayNSL``, so they are compared at chi = 1 only.
3. ``chain_n<n>``: the chain of docs/chain.md, n unit blocks on unit springs (wall at the left,
   free right end), mu_s = mu_k = 0.5, N = 1 on every block, block 1 forced by cos(0.5 t), from
   rest, one forcing period (4 pi s), against ``dryfriction.references.chain.solve_chain``; error
   max over blocks |x - x_ref| in metres (= static deflections of block 1's force on a unit spring).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np


@dataclass
class PeerCase:
    """One case in the chain form both sides take (n = 1: the single oscillator)."""

    name: str
    kind: str                       # "oscillator" or "chain"
    m: np.ndarray
    K: np.ndarray                   # n x n
    C: np.ndarray                   # n x n
    P0: np.ndarray
    phi: np.ndarray
    omega: float
    mu: np.ndarray                  # the one friction coefficient (mu_s = mu_k)
    N: np.ndarray
    x0: np.ndarray
    v0: np.ndarray
    t_end: float
    error_scale: float              # error = error_scale * max |x - x_ref|
    error_unit: str
    sample_dt: float                # error samples about every sample_dt (a multiple of h)
    note: str
    reference: Callable[[np.ndarray], np.ndarray] | None = None  # t -> x [nt, n]
    oscillator: object | None = None  # dryfriction.params.Oscillator (kind oscillator)
    chain_params: dict = field(default_factory=dict)  # ChainFMU3 parameters (kind chain)

    @property
    def n(self) -> int:
        return int(self.m.size)

    def job(self, h: float, theta: float, steps: int, every: int, reps: int) -> dict:
        """The Siconos worker's job for step h over `steps` steps."""
        return {"n": self.n, "m": self.m.tolist(), "K": self.K.ravel().tolist(), "C": self.C.ravel().tolist(),
                "P0": self.P0.tolist(), "phi": self.phi.tolist(), "omega": self.omega,
                "muN": (self.mu * self.N).tolist(), "x0": self.x0.tolist(), "v0": self.v0.tolist(),
                "t_end": steps * h, "h": h, "theta": theta, "sample_every": every, "reps": reps,
                "id": f"{self.name} theta={theta} h={h:g}"}


def tutorial_closed_form(t: np.ndarray) -> np.ndarray:
    """x(t) of x'' + x = -sign(x') (|friction| <= 1 at rest), x(0) = 12, x'(0) = 6: half-oscillations
    about -1 (sliding up) and +1 (sliding down) whose extremes shrink by 2 each; the first maximum
    sqrt(205) - 1 at t0 = atan(6/13); stuck for good from t0 + 7 pi at x = 15 - sqrt(205)."""
    t = np.asarray(t, dtype=float)
    a = math.sqrt(205.0)
    t0 = math.atan2(6.0, 13.0)
    out = np.empty_like(t)
    pre = t <= t0
    out[pre] = -1.0 + a * np.cos(t[pre] - t0)
    tt = t[~pre] - t0
    k = np.floor(tt / math.pi).astype(int)
    sign = np.where(k % 2 == 0, 1.0, -1.0)
    extreme = sign * (a - 1.0 - 2.0 * k)           # the extreme the k-th half-oscillation starts from
    centre = sign * 1.0
    x = centre + (extreme - centre) * np.cos(tt - k * math.pi)
    x[k >= 7] = 15.0 - a
    out[~pre] = x
    return out


def tutorial_case() -> PeerCase:
    from dryfriction.params import Oscillator

    one = np.ones(1)
    p = Oscillator(m=1.0, k=1.0, c=0.0, P0=0.0, omega=0.0, phi=0.0, N=1.0, mu_s=1.0, chi=1.0, x0=12.0, v0=6.0)
    return PeerCase("tutorial", "oscillator", one, one.reshape(1, 1), np.zeros((1, 1)), np.zeros(1), np.zeros(1),
                    0.0, one, one, 12.0 * one, 6.0 * one, 30.0, 1.0, "m", 1e-3,
                    "Siconos's FrictionOscillator example (m = k = 1, Coulomb force 1, x0 = 12, v0 = 6, 30 s) "
                    "against its closed form",
                    reference=lambda t: tutorial_closed_form(t)[:, None], oscillator=p)


def wp_cases(names: tuple[str, ...] | None = None) -> list[PeerCase]:
    """The work-precision cases at chi = 1 (see the module docstring)."""
    from cases import CASES
    from dryfriction.references.exact import solve_exact
    from dryfriction.params import Oscillator

    out = []
    for c in CASES:
        if names is not None and c.name not in names:
            continue
        p = Oscillator.from_nondimensional(c.lam, c.mu_s_sigma, 1.0, c.zeta)
        t_end = 10 * p.period
        ex = solve_exact(p, t_end + 0.02)
        a = np.ones(1)
        out.append(PeerCase(
            f"wp_{c.name}_chi1", "oscillator", p.m * a, np.array([[p.k]]), np.array([[p.c]]), p.P0 * a, p.phi * a,
            p.omega, p.mu_s * a, p.N * a, p.x0 * a, p.v0 * a, t_end, p.k / abs(p.P0), "static deflections (z)",
            p.period / 400,
            f"bench/cases.py's {c.name} (lambda {c.lam:g}, mu_s sigma {c.mu_s_sigma:g}, zeta {c.zeta:g}) with "
            f"chi = 1 instead of {c.chi:g}: Siconos's relay law has one coefficient, so the case itself "
            f"(mu_k = {c.chi:g} mu_s) cannot be compared",
            reference=(lambda t, ex=ex: ex.evaluate(t)[0][:, None]), oscillator=p))
    return out


CHAIN_OMEGA = 0.5


def chain_case(n: int) -> PeerCase:
    from dryfriction.references.chain import Chain, solve_chain

    P0 = np.zeros(n)
    P0[0] = 1.0
    ch = Chain.make(n, omega=CHAIN_OMEGA, k_end=0.0, c_end=0.0, m=1.0, k=1.0, c=0.0, P0=P0, phi=0.0, N=1.0,
                    mu_s=0.5, chi=1.0, x0=0.0, v0=0.0)
    t_end = 2 * math.pi / CHAIN_OMEGA
    K, C = ch.matrices()
    holder: dict[str, object] = {}

    def ref(t: np.ndarray) -> np.ndarray:
        if "sol" not in holder:  # solved when first needed (n = 64: seconds)
            holder["sol"] = solve_chain(ch, t_end + 0.02)
        return holder["sol"].evaluate(t)["x"]  # type: ignore[union-attr]

    params = {"m": 1.0, "k": 1.0, "c": 0.0, "P0": P0.tolist(), "phi": 0.0, "N": 1.0, "mu_s": 0.5, "chi": 1.0,
              "x0": 0.0, "v0": 0.0, "k_end": 0.0, "c_end": 0.0, "omega": CHAIN_OMEGA}
    return PeerCase(f"chain_n{n}", "chain", ch.m, K, C, ch.P0, ch.phi, CHAIN_OMEGA, ch.mu_s, ch.N, ch.x0, ch.v0,
                    t_end, 1.0, "m", 0.02,
                    f"the chain of docs/chain.md with n = {n} unit blocks and springs (wall at the left, free end), "
                    "mu_s = mu_k = 0.5, N = 1, block 1 forced by cos(0.5 t), one forcing period, against "
                    "dryfriction.references.chain",
                    reference=ref, chain_params=params)
