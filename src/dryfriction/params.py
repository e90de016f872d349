"""Physical parameters of the dry-friction oscillator and their non-dimensional form.

The names match the FMU's variables (see modelDescription.xml) and method.md section 1:

    m x'' + c x' + k x = P0 cos(omega t + phi) + F,   F the Coulomb friction force,
    mu_k = chi * mu_s, breakaway limit max(mu_s, mu_k) N.

Physical units first: :meth:`Oscillator.physical` takes what an engineer has (m, k, c or zeta, P0,
f in Hz or omega, N, mu_s, mu_k); :meth:`Oscillator.from_nondimensional` and
:meth:`Oscillator.to_nondimensional` are the paper's form (lambda, mu_s sigma, chi, zeta, z0, z0').
Every value is checked when an Oscillator is made: a real number (not a string), finite, inside the
range the model description declares; the error names the field and the valid range.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, fields, replace
from typing import Any

from . import model

__all__ = ["Oscillator", "UNITS", "SCALE_LIMIT"]

#: m and k (k > 0) must lie within [1 / SCALE_LIMIT, SCALE_LIMIT] (kg, N/m): then the natural
#: frequency sqrt(k/m), the time 1/w0 and every product the solution and its Jacobian form stay inside
#: double precision's normal range (checked: the stroboscopic map and its Jacobian scale exactly,
#: within 1e-9 of the unit oscillator's, on a grid of m, k and P0 from 1e-200 to 1e200 wherever m, k and
#: sqrt(k/m) lie within it; beyond it the FMU's Jacobian overflows (k > 1e154 with friction) or its run
#: silently loses the motion (m = k = 1e-300: stuck where it slides)). The FMUs declare the same
#: range for m and the same maximum for every stiffness (tested equal: tests/test_hazards.py), and
#: refuse at the end of initialisation a stiffness 0 < k < 1 / SCALE_LIMIT and a motion whose force
#: scale over m or over k is below 1 / SCALE_LIMIT^2 (tests/HAZARDS.md, Scales)
SCALE_LIMIT = 1e100

#: unit of every field and derived quantity (the model description's, plus the derived ones; read
#: on first use)
UNITS: Mapping[str, str] = model.LazyMapping(lambda: {
    **{n: (v.unit or "") for n, v in model.default().variables.items() if v.unit},
    "mu_k": "1", "zeta": "1", "f_hz": "Hz", "f_n_hz": "Hz", "w0": "rad/s", "lam": "1", "period": "s",
    "breakaway": "N", "sigma": "1",
})


def _real(field: str, value: Any, where: str = "Oscillator") -> float:
    """value as a float, or ValueError naming the field (strings and booleans are not numbers)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ValueError(f"{where}: {field} must be a real number, not {type(value).__name__} {value!r}")
    x = float(value)
    if not math.isfinite(x):
        raise ValueError(f"{where}: invalid value {x!r} for {field}; valid range: finite")
    return x


def _at_least(field: str, value: Any, lo: float, where: str, open_: bool = False) -> float:
    x = _real(field, value, where)
    if x < lo or (open_ and x == lo):
        raise ValueError(f"{where}: invalid value {x!r} for {field}; valid range: {'>' if open_ else '>='} {lo:g}")
    return x

#: the fields whose size SCALE_LIMIT bounds, with their units (k = 0, no spring, is valid too)
SCALED = {"m": "kg", "k": "N/m"}


def _check_scale(name: str, x: float, what: str) -> None:
    """ValueError naming the field and its valid range unless 1 / SCALE_LIMIT <= x <= SCALE_LIMIT (or
    k = 0)."""
    if name == "k" and x == 0.0:
        return
    if not 1.0 / SCALE_LIMIT <= x <= SCALE_LIMIT:
        zero = " (or 0: no spring)" if name == "k" else ""
        raise ValueError(f"Oscillator: invalid value {x!r} for {name} ({what}); valid range: {1.0 / SCALE_LIMIT:g} "
                         f"to {SCALE_LIMIT:g} {SCALED[name]}{zero}: beyond it the oscillator's scales (the natural "
                         "frequency sqrt(k/m) among them) leave double precision")


def _start(name: str) -> float:
    """The start value of a parameter in the model description (the defaults below, read when
    first needed, never at import)."""
    return float(model.default().var(name).start)  # type: ignore[arg-type]


def _default(name: str) -> Any:
    """A dataclass field whose default is the model description's start value of ``name``."""
    return field(default_factory=lambda: _start(name))


@dataclass(frozen=True)
class Oscillator:
    """One parameter set in SI units; the defaults are the model description's start values
    (lambda = 0.5, mu_s sigma = 0.4, chi = 0.7)."""

    m: float = _default("m")
    k: float = _default("k")
    c: float = _default("c")
    P0: float = _default("P0")
    omega: float = _default("omega")
    phi: float = _default("phi")
    N: float = _default("N")
    mu_s: float = _default("mu_s")
    chi: float = _default("chi")
    x0: float = _default("x0")
    v0: float = _default("v0")

    def __post_init__(self) -> None:
        """Check every field against the model description's range (errors name the field)."""
        md = model.default()
        for f in fields(self):
            value = getattr(self, f.name)
            x = _real(f.name, value)
            if f.name in SCALED:
                _check_scale(f.name, x, md.var(f.name).description.split(" (")[0])
            try:
                md.check(f.name, x, where=f"{f.name} ({md.var(f.name).description.split(' (')[0]})")
            except ValueError as e:
                raise ValueError(f"Oscillator: {e}") from None
            object.__setattr__(self, f.name, x)

    # --- derived quantities (method.md section 1) ---
    @property
    def mu_k(self) -> float:
        """Kinetic friction coefficient chi mu_s."""
        return self.chi * self.mu_s

    @property
    def w0(self) -> float:
        """Natural angular frequency sqrt(k/m), rad/s."""
        return math.sqrt(self.k / self.m)

    @property
    def f_n_hz(self) -> float:
        """Natural frequency sqrt(k/m) / (2 pi), Hz."""
        return self.w0 / (2.0 * math.pi)

    @property
    def f_hz(self) -> float:
        """Excitation frequency omega / (2 pi), Hz."""
        return self.omega / (2.0 * math.pi)

    @property
    def lam(self) -> float:
        """Frequency ratio lambda = omega / w0 (inf without a spring)."""
        return self.omega / self.w0 if self.w0 > 0 else (math.inf if self.omega > 0 else math.nan)

    @property
    def zeta(self) -> float:
        """Damping ratio c / (2 sqrt(k m)) (inf without a spring, unless c = 0)."""
        d = 2.0 * math.sqrt(self.k * self.m)
        return self.c / d if d > 0 else (math.inf if self.c > 0 else 0.0)

    @property
    def sigma(self) -> float:
        """Normal force over excitation amplitude N / P0 (inf when P0 = 0)."""
        return self.N / abs(self.P0) if self.P0 != 0 else (math.inf if self.N > 0 else math.nan)

    @property
    def period(self) -> float:
        """Excitation period T = 2 pi / omega, s (inf when omega = 0)."""
        return 2.0 * math.pi / self.omega if self.omega > 0 else math.inf

    @property
    def breakaway(self) -> float:
        """Breakaway force max(mu_s, mu_k) N, N."""
        return max(self.mu_s, self.mu_k) * self.N

    def with_(self, **changes: float) -> "Oscillator":
        """A copy with the given parameters changed (checked again)."""
        return replace(self, **changes)

    def as_dict(self) -> dict[str, float]:
        """The parameters as a dict, SI units."""
        return asdict(self)

    @classmethod
    def physical(
        cls,
        *,
        m: float,
        k: float,
        P0: float,
        N: float,
        mu_s: float,
        mu_k: float | None = None,
        chi: float | None = None,
        c: float | None = None,
        zeta: float | None = None,
        f: float | None = None,
        omega: float | None = None,
        phi: float = 0.0,
        x0: float = 0.0,
        v0: float = 0.0,
    ) -> "Oscillator":
        """An oscillator from what an engineer has, in SI units: mass m (kg), stiffness k (N/m),
        damping as c (N s/m) or zeta (damping ratio, c = 2 zeta sqrt(k m); default c = 0),
        excitation amplitude P0 (N) and frequency f (Hz) or omega (rad/s), normal force N (N),
        mu_s and mu_k (default mu_k = mu_s), phase phi (rad), x0 (m), v0 (m/s).

        Each value is checked; the error names the field and its valid range."""
        where = "Oscillator.physical"
        if (c is None) == (zeta is None) and c is not None:
            raise ValueError(f"{where}: give the damping as c or as zeta, not both")
        if (f is None) == (omega is None):
            raise ValueError(f"{where}: give the excitation frequency as f (Hz) or omega (rad/s), exactly one")
        if mu_k is not None and chi is not None:
            raise ValueError(f"{where}: give mu_k or chi, not both")
        m = _real("m (mass, kg)", m, where)
        _check_scale("m", m, "mass")
        k = _real("k (stiffness, N/m)", k, where)
        _check_scale("k", k, "spring stiffness")
        mu_s = _at_least("mu_s (static friction coefficient)", mu_s, 0.0, where)
        if zeta is not None:
            c = 2.0 * _at_least("zeta (damping ratio)", zeta, 0.0, where) * math.sqrt(k * m)
        if f is not None:
            omega = 2.0 * math.pi * _at_least("f (excitation frequency, Hz)", f, 0.0, where)
        if chi is None:
            mk = mu_s if mu_k is None else _at_least("mu_k (kinetic friction coefficient)", mu_k, 0.0, where)
            if mu_s == 0.0 and mk > 0.0:
                raise ValueError(f"{where}: invalid value {mk!r} for mu_k with mu_s = 0; valid range: 0 "
                                 "(the model's kinetic coefficient is chi mu_s: give mu_s > 0)")
            chi = mk / mu_s if mu_s > 0 else 1.0
        return cls(m=m, k=k, c=0.0 if c is None else c, P0=P0, omega=omega, phi=phi, N=N, mu_s=mu_s, chi=chi,
                   x0=x0, v0=v0)

    def to_nondimensional(self) -> dict[str, float]:
        """The paper's form (method.md (2)): lam, mu_s_sigma, chi, zeta, z0, dz0, phi, with
        z = k x / P0 and tau = w0 t. :meth:`from_nondimensional` with these and m, k, P0, mu_s
        gives this oscillator back. Needs k > 0 and P0 != 0."""
        if not (self.k > 0 and self.P0 != 0):
            raise ValueError(f"the non-dimensional form needs k > 0 and P0 != 0 (k = {self.k!r}, P0 = {self.P0!r})")
        return {"lam": self.lam, "mu_s_sigma": self.mu_s * self.N / self.P0, "chi": self.chi, "zeta": self.zeta,
                "z0": self.k * self.x0 / self.P0, "dz0": self.k * self.v0 / (self.P0 * self.w0), "phi": self.phi}

    def describe(self) -> dict[str, Any]:
        """Every field and derived quantity with its unit: {name: {"value": v, "unit": u}}."""
        out: dict[str, Any] = {}
        for name in (*self.as_dict(), "mu_k", "zeta", "f_hz", "f_n_hz", "lam", "breakaway"):
            out[name] = {"value": float(getattr(self, name)), "unit": UNITS.get(name, "")}
        return out

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
        m: float | None = None,
        k: float | None = None,
        P0: float | None = None,
        mu_s: float | None = None,
    ) -> "Oscillator":
        """Physical parameters for the non-dimensional set of method.md (2).

        z = k x / P0 and z' = dz/dtau with tau = w0 t, so x0 = z0 P0 / k and
        v0 = dz0 P0 w0 / k.  mu_s_sigma = mu_s N / P0 fixes N. m, k, P0 and mu_s default to the
        model description's start values.
        """
        m = _start("m") if m is None else m
        k = _start("k") if k is None else k
        P0 = _start("P0") if P0 is None else P0
        mu_s = _start("mu_s") if mu_s is None else mu_s
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
