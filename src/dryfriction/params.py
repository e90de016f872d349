"""Physical parameters of the dry-friction oscillator and their non-dimensional form.

The names match the FMU's variables (see modelDescription.xml) and method.md section 1:

    m x'' + c x' + k x = P0 cos(omega t + phi) + F,   F the Coulomb friction force,
    mu_k = chi * mu_s, breakaway limit max(mu_s, mu_k) N.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace

from . import model

#: start values of the model description's parameters (the defaults below)
_START = model.default().parameter_starts()


@dataclass(frozen=True)
class Oscillator:
    """One parameter set in SI units; the defaults are the model description's start values
    (lambda = 0.5, mu_s sigma = 0.4, chi = 0.7)."""

    m: float = _START["m"]
    k: float = _START["k"]
    c: float = _START["c"]
    P0: float = _START["P0"]
    omega: float = _START["omega"]
    phi: float = _START["phi"]
    N: float = _START["N"]
    mu_s: float = _START["mu_s"]
    chi: float = _START["chi"]
    x0: float = _START["x0"]
    v0: float = _START["v0"]

    # --- derived quantities (method.md section 1) ---
    @property
    def mu_k(self) -> float:
        return self.chi * self.mu_s

    @property
    def w0(self) -> float:
        """Natural angular frequency sqrt(k/m), rad/s."""
        return math.sqrt(self.k / self.m)

    @property
    def lam(self) -> float:
        """Frequency ratio lambda = omega / w0."""
        return self.omega / self.w0

    @property
    def zeta(self) -> float:
        """Damping ratio c / (2 sqrt(k m))."""
        return self.c / (2.0 * math.sqrt(self.k * self.m))

    @property
    def sigma(self) -> float:
        """Normal force over excitation amplitude N / P0."""
        return self.N / self.P0

    @property
    def period(self) -> float:
        """Excitation period T = 2 pi / omega, s."""
        return 2.0 * math.pi / self.omega

    @property
    def breakaway(self) -> float:
        """Breakaway force max(mu_s, mu_k) N, N."""
        return max(self.mu_s, self.mu_k) * self.N

    def with_(self, **changes: float) -> "Oscillator":
        return replace(self, **changes)

    def as_dict(self) -> dict[str, float]:
        return asdict(self)

    @classmethod
    def from_nondimensional(
        cls,
        lam: float,
        mu_s_sigma: float,
        chi: float,
        zeta: float = 0.0,
        z0: float = 0.0,
        dz0: float = 0.0,
        phi: float = 0.0,
        m: float = _START["m"],
        k: float = _START["k"],
        P0: float = _START["P0"],
        mu_s: float = _START["mu_s"],
    ) -> "Oscillator":
        """Physical parameters for the non-dimensional set of method.md (2).

        z = k x / P0 and z' = dz/dtau with tau = w0 t, so x0 = z0 P0 / k and
        v0 = dz0 P0 w0 / k.  mu_s_sigma = mu_s N / P0 fixes N.
        """
        w0 = math.sqrt(k / m)
        return cls(
            m=m,
            k=k,
            c=2.0 * zeta * math.sqrt(k * m),
            P0=P0,
            omega=lam * w0,
            phi=phi,
            N=mu_s_sigma * P0 / mu_s,
            mu_s=mu_s,
            chi=chi,
            x0=z0 * P0 / k,
            v0=dz0 * P0 * w0 / k,
        )
