"""A structure with dry-friction contacts (method.md section 13): :class:`~dryfriction.system.structure.Contact` and
:class:`~dryfriction.system.structure.System`.

    M x'' + C x' + K x = F_c cos(omega t) + F_s sin(omega t) + F_ext + W' f,    g = W x

``x`` in R^n; ``M`` symmetric positive definite, ``C`` and ``K`` symmetric positive semi-definite
(a rigid-body mode held only by friction is allowed). Contact ``j`` has the direction row ``w_j``
(row j of ``W``: ``e_i`` for degree of freedom ``i`` against the ground, ``e_i - e_k`` for the slip
between two), the normal load ``N_j``, the coefficients ``mu_s_j`` and ``mu_k_j`` (breakaway limit
``max(mu_s, mu_k) N``, sliding force ``mu_k N``) and the tangential stiffness ``k_t_j``: 0 a rigid
Coulomb contact, > 0 a Jenkins element (a spring ``k_t`` in series with a massless slider).
Degree-of-freedom indices are 0-based, as in numpy. The friction law is per contact: Coulomb's
(constant ``mu_k`` while sliding, the default) or Stribeck's, the oscillator's and the chain's
``mu(u) = mu_k + (mu_s - mu_k) exp(-(u / v_s)^delta)`` at the slip speed ``u`` (a rigid contact
only, scheme located, ``v_s > 0``, ``delta >= 1``; a Jenkins element takes the Coulomb law, and
Stribeck contacts and Jenkins elements may be in the same structure).

Every value is checked when a System is made; an error is a :class:`~dryfriction.errors.UsageError`
(a ValueError) whose one sentence names the array and the element, or the test that failed.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import UsageError

if TYPE_CHECKING:
    from ..params import Oscillator

__all__ = ["Contact", "System", "SCHEMES", "LAWS", "SYMMETRY_RTOL", "EIGEN_RTOL"]

#: the time-stepping schemes and their values in the FMU's ``scheme`` enumeration
SCHEMES: Mapping[str, int] = {"paper": 1, "consistent": 2, "located": 3}
#: the friction laws a contact may have and their values in the FMU's ``friction_law`` enumeration
LAWS: Mapping[str, int] = {"coulomb": 1, "stribeck": 2}
#: M, C and K count as symmetric when max |A - A'| <= SYMMETRY_RTOL * max |A|
SYMMETRY_RTOL = 1e-12
#: an eigenvalue of C or K counts as rounding when it is >= -EIGEN_RTOL * n * max |eigenvalue|
EIGEN_RTOL = 64.0 * float(np.finfo(float).eps)


def _number(where: str, value: Any) -> float:
    """value as a finite float, or UsageError naming ``where`` (strings and booleans are no numbers)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise UsageError(f"{where} must be a real number, not {type(value).__name__} {value!r}")
    x = float(value)
    if not math.isfinite(x):
        raise UsageError(f"{where} is {x!r}; valid range: finite")
    return x


def _nonneg(where: str, value: Any) -> float:
    x = _number(where, value)
    if x < 0.0:
        raise UsageError(f"{where} is {x!r}; valid range: >= 0")
    return x


def _index(where: str, value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise UsageError(f"{where} must be an integer degree-of-freedom index (0-based), not {value!r}")
    return int(value)


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=np.float64, copy=True)
    a.setflags(write=False)
    return a


def _finite(name: str, a: np.ndarray) -> None:
    """UsageError naming the first element of ``a`` that is NaN or infinite."""
    bad = np.argwhere(~np.isfinite(a))
    if bad.size:
        idx = tuple(int(i) for i in bad[0])
        label = f"{name}[{', '.join(str(i) for i in idx)}]" if idx else name
        raise UsageError(f"{label} is {float(a[idx])!r}; every value must be finite")


def _matrix(name: str, value: Any, n: int | None) -> np.ndarray:
    """A square float64 matrix (n x n when n is given), finite, or UsageError naming it."""
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise UsageError(f"{name} must be a matrix of real numbers ({e})") from None
    if a.ndim == 0 and n == 1:
        a = a.reshape(1, 1)
    if a.ndim != 2 or a.shape[0] != a.shape[1] or a.shape[0] == 0:
        raise UsageError(f"{name} has the shape {a.shape}; it must be a square matrix"
                         + (f" ({n} x {n}, as M)" if n is not None else ""))
    if n is not None and a.shape != (n, n):
        raise UsageError(f"{name} is {a.shape[0]} x {a.shape[1]} but M is {n} x {n}: the sizes disagree")
    _finite(name, a)
    return a


def _vector(name: str, value: Any, n: int) -> np.ndarray:
    """n values (a scalar counts for all), finite, or UsageError naming the array."""
    if value is None:
        return np.zeros(n)
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise UsageError(f"{name} must be real numbers ({e})") from None
    if a.ndim == 0:
        a = np.full(n, float(a))
    if a.shape != (n,):
        raise UsageError(f"{name} has {a.size} values in the shape {a.shape} but the structure has n = {n} "
                         "degrees of freedom: the sizes disagree")
    _finite(name, a)
    return a


def _symmetric(name: str, a: np.ndarray) -> None:
    scale = float(np.max(np.abs(a)))
    d = np.abs(a - a.T)
    i, j = np.unravel_index(int(np.argmax(d)), d.shape)
    tol = SYMMETRY_RTOL * scale
    if d[i, j] > tol:
        raise UsageError(f"{name} is not symmetric: {name}[{i}, {j}] = {float(a[i, j])!r} but {name}[{j}, {i}] = "
                         f"{float(a[j, i])!r} (difference {d[i, j]:.3g} beyond the tolerance {tol:.3g} = "
                         f"{SYMMETRY_RTOL:g} max|{name}|)")


def _semidefinite(name: str, a: np.ndarray) -> None:
    ev = np.linalg.eigvalsh(0.5 * (a + a.T))
    tol = EIGEN_RTOL * a.shape[0] * float(np.max(np.abs(ev))) if ev.size else 0.0
    if ev[0] < -tol:
        raise UsageError(f"{name} has the negative eigenvalue {ev[0]:.6g} (beyond rounding: below -{tol:.3g}); "
                         f"{name} must be positive semi-definite")


@dataclass(frozen=True)
class Contact:
    """One friction contact: its direction (exactly one of ``dof``, ``between``, ``w``) and its
    friction.

    ``dof=i``: degree of freedom ``i`` against the ground (``w = e_i``); ``between=(i, j)``: the
    slip of ``i`` relative to ``j`` (``w = e_i - e_j``); ``w=[...]``: a full row of n values.
    ``N`` the normal load (N, >= 0), ``mu_s`` and ``mu_k`` the static and kinetic coefficients
    (>= 0; ``mu_k`` defaults to ``mu_s``), ``k_t`` the tangential stiffness (N/m, >= 0: 0 a rigid
    Coulomb contact, > 0 a Jenkins element), ``law`` the sliding friction law: ``"coulomb"``
    (``mu_k`` while sliding, the default) or ``"stribeck"``, ``mu(u) = mu_k + (mu_s - mu_k)
    exp(-(u / v_s)^delta)`` at the slip speed ``u``, with the Stribeck velocity ``v_s`` (m/s, > 0,
    default 0.01) and exponent ``delta`` (>= 1, default 1) as the FMU's; a rigid contact only (a
    Jenkins element takes the Coulomb law), and the system's scheme must be located."""

    dof: int | None = None
    between: tuple[int, int] | None = None
    w: tuple[float, ...] | None = None
    N: float = 0.0
    mu_s: float = 0.0
    mu_k: float | None = None
    k_t: float = 0.0
    law: str = "coulomb"
    v_s: float = 0.01
    delta: float = 1.0

    def __post_init__(self) -> None:
        """Check every field (UsageError naming it)."""
        given = [name for name in ("dof", "between", "w") if getattr(self, name) is not None]
        if len(given) != 1:
            raise UsageError("Contact: give exactly one of dof=i, between=(i, j) or w=[...] for its direction, "
                             f"not {', '.join(given) if given else 'none'}")
        if self.dof is not None:
            i = _index("Contact: dof", self.dof)
            if i < 0:
                raise UsageError(f"Contact: dof = {i} is negative; degree-of-freedom indices start at 0")
            object.__setattr__(self, "dof", i)
        if self.between is not None:
            b = tuple(self.between)
            if len(b) != 2:
                raise UsageError(f"Contact: between = {self.between!r} must be two indices (i, j)")
            i, j = (_index("Contact: between", k) for k in b)
            if i < 0 or j < 0:
                raise UsageError(f"Contact: between = ({i}, {j}) has a negative index; indices start at 0")
            if i == j:
                raise UsageError(f"Contact: between = ({i}, {j}) names one degree of freedom twice: its slip "
                                 "would be 0 (give two different indices)")
            object.__setattr__(self, "between", (i, j))
        if self.w is not None:
            try:
                row = np.asarray(self.w, dtype=np.float64)
            except (TypeError, ValueError) as e:
                raise UsageError(f"Contact: w must be a row of real numbers ({e})") from None
            if row.ndim != 1 or row.size == 0:
                raise UsageError(f"Contact: w has the shape {row.shape}; it must be one row of n values")
            _finite("Contact: w", row)
            if not np.any(row != 0.0):
                raise UsageError("Contact: w is a zero row: the contact has no direction")
            object.__setattr__(self, "w", tuple(float(v) for v in row))
        object.__setattr__(self, "N", _nonneg("Contact: N", self.N))
        object.__setattr__(self, "mu_s", _nonneg("Contact: mu_s", self.mu_s))
        mu_k = self.mu_s if self.mu_k is None else self.mu_k
        object.__setattr__(self, "mu_k", _nonneg("Contact: mu_k", mu_k))
        object.__setattr__(self, "k_t", _nonneg("Contact: k_t", self.k_t))
        if not isinstance(self.law, str) or self.law not in LAWS:
            raise UsageError(f"Contact: law = {self.law!r} is not offered; valid: {', '.join(LAWS)}")
        v_s = _number("Contact: v_s", self.v_s)
        if not v_s > 0.0:
            raise UsageError(f"Contact: v_s = {v_s!r} is not > 0: the contact's Stribeck velocity; valid range: > 0")
        object.__setattr__(self, "v_s", v_s)
        delta = _number("Contact: delta", self.delta)
        if not delta > 0.0:
            raise UsageError(f"Contact: delta = {delta!r} is out of range; valid range: > 0")
        if self.law == "stribeck" and delta < 1.0:
            raise UsageError(f"Contact: law = stribeck supports delta >= 1 only, not {delta!r} for delta (below 1 "
                             "the friction's slope is infinite at zero slip speed)")
        object.__setattr__(self, "delta", delta)
        if self.law == "stribeck" and self.k_t > 0.0:
            raise UsageError(f"Contact: a Jenkins element (k_t = {self.k_t!r} > 0) takes the Coulomb law only: "
                             "set law = 'coulomb' or k_t = 0")

    @property
    def jenkins(self) -> bool:
        """True for a Jenkins element (k_t > 0), False for a rigid contact."""
        return self.k_t > 0.0

    @property
    def breakaway(self) -> float:
        """The breakaway limit max(mu_s, mu_k) N, N."""
        return max(self.mu_s, float(self.mu_k)) * self.N  # type: ignore[arg-type]

    def row(self, n: int, where: str = "Contact") -> np.ndarray:
        """The direction row w (n values) in a structure of n degrees of freedom (UsageError for an
        index out of range or a row of another length)."""
        w = np.zeros(n)
        if self.dof is not None:
            if self.dof >= n:
                raise UsageError(f"{where}: dof = {self.dof} is out of range; valid: 0 to {n - 1}")
            w[self.dof] = 1.0
        elif self.between is not None:
            for k in self.between:
                if k >= n:
                    raise UsageError(f"{where}: between = {self.between} has the index {k}, out of range; "
                                     f"valid: 0 to {n - 1}")
            w[self.between[0]] = 1.0
            w[self.between[1]] = -1.0
        else:
            assert self.w is not None
            if len(self.w) != n:
                raise UsageError(f"{where}: w has {len(self.w)} values but the structure has n = {n} "
                                 "degrees of freedom: the sizes disagree")
            w[:] = self.w
        return w


class System:
    """A structure with friction contacts (see the module docstring): the matrices, the contacts,
    the excitation, the initial state and the run's settings.

    ``M``, ``K`` (n x n, required), ``C`` (n x n, default 0); ``contacts`` (a sequence of
    :class:`Contact`); ``F_c``, ``F_s`` (n, default 0: the excitation ``F_c cos(omega t) + F_s
    sin(omega t)``), ``omega`` (rad/s, >= 0); ``x0``, ``v0`` (n, default 0); ``h`` the internal
    step (s, 0: derived from the dynamics), ``scheme`` (``"located"``, ``"consistent"`` or
    ``"paper"``), ``alpha`` the Bossak parameter (-1/3 to 0). Vectors may be given as one scalar
    for every degree of freedom.

    Frozen: the arrays are read-only float64 copies; :meth:`replace` makes a changed copy.

    Raises
    ------
    dryfriction.UsageError
        A value that is not valid, in one sentence naming the array and the element or the test
        that failed: sizes that disagree, NaN or inf, M not symmetric or not positive definite, K or C
        not symmetric or with a negative eigenvalue beyond rounding, a zero contact row, an index out
        of range, a negative N, mu_s, mu_k or k_t, a Stribeck contact with a scheme other than located
        or in a structure with a Jenkins element.
    """

    __slots__ = ("_M", "_C", "_K", "_contacts", "_F_c", "_F_s", "_omega", "_x0", "_v0", "_h", "_scheme",
                 "_alpha", "_W")

    def __init__(self, M: Any, K: Any, C: Any = None, contacts: Sequence[Contact] = (), F_c: Any = None,
                 F_s: Any = None, omega: float = 0.0, x0: Any = None, v0: Any = None, h: float = 0.0,
                 scheme: str = "located", alpha: float = -0.1) -> None:
        Mm = _matrix("M", M, None)
        n = Mm.shape[0]
        Km = _matrix("K", K, n)
        Cm = np.zeros((n, n)) if C is None else _matrix("C", C, n)
        _symmetric("M", Mm)
        try:
            np.linalg.cholesky(0.5 * (Mm + Mm.T))
        except np.linalg.LinAlgError:
            ev = float(np.linalg.eigvalsh(0.5 * (Mm + Mm.T))[0])
            raise UsageError(f"M is not positive definite: its Cholesky factorisation fails (smallest "
                             f"eigenvalue {ev:.6g})") from None
        for name, a in (("K", Km), ("C", Cm)):
            _symmetric(name, a)
            _semidefinite(name, a)
        cs = tuple(contacts)
        rows = np.zeros((len(cs), n))
        for j, c in enumerate(cs):
            if not isinstance(c, Contact):
                raise UsageError(f"contacts[{j}] must be a Contact, not {type(c).__name__}")
            rows[j] = c.row(n, where=f"contacts[{j}]")
            if c.law == "stribeck" and scheme in SCHEMES and scheme != "located":
                raise UsageError(f"contacts[{j}]: law = stribeck needs scheme located (the speed-dependent "
                                 f"friction is solved inside its steps), as the oscillator and the chain: choose "
                                 f"scheme located, or law = coulomb, not scheme {scheme}")
        vec = {name: _vector(name, val, n) for name, val in (("F_c", F_c), ("F_s", F_s), ("x0", x0), ("v0", v0))}
        om = _nonneg("omega", omega)
        hh = _nonneg("h", h)
        if scheme not in SCHEMES:
            raise UsageError(f"scheme = {scheme!r} is not a scheme; valid: {', '.join(SCHEMES)}")
        al = _number("alpha", alpha)
        if not -1.0 / 3.0 <= al <= 0.0:
            raise UsageError(f"alpha = {al!r} is out of range; valid: -1/3 to 0")
        set_ = object.__setattr__
        set_(self, "_M", _frozen(Mm))
        set_(self, "_K", _frozen(Km))
        set_(self, "_C", _frozen(Cm))
        set_(self, "_contacts", cs)
        set_(self, "_W", _frozen(rows))
        for name, a in vec.items():
            set_(self, f"_{name}", _frozen(a))
        set_(self, "_omega", om)
        set_(self, "_h", hh)
        set_(self, "_scheme", scheme)
        set_(self, "_alpha", al)

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError(f"System is frozen: {name} cannot be set (use System.replace)")

    def __repr__(self) -> str:
        return (f"System(n={self.n}, nc={self.nc}, omega={self.omega!r}, scheme={self.scheme!r}, "
                f"h={self.h!r})")

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, System):
            return NotImplemented
        arrays = ("M", "C", "K", "F_c", "F_s", "x0", "v0", "W")
        return (self.n == other.n and self.contacts_equal(other)
                and all(np.array_equal(getattr(self, a), getattr(other, a)) for a in arrays)
                and (self.omega, self.h, self.scheme, self.alpha) == (other.omega, other.h, other.scheme, other.alpha))

    __hash__ = None  # type: ignore[assignment]

    def __reduce__(self) -> tuple[Any, ...]:
        """Pickled (and copied) as its fields, checked again when loaded."""
        return (_make_system, (self._fields(),))

    def contacts_equal(self, other: "System") -> bool:
        """True when both have the same contact rows and the same friction per contact (the same
        direction given as dof, between or w counts as equal)."""
        return (self.nc == other.nc and np.array_equal(self.W, other.W)
                and all(np.array_equal(getattr(self, a), getattr(other, a))
                        for a in ("N", "mu_s", "mu_k", "k_t", "friction_law", "v_s", "delta")))

    # --- the fields ---
    @property
    def M(self) -> np.ndarray:
        """The mass matrix (n x n, read-only)."""
        return self._M

    @property
    def C(self) -> np.ndarray:
        """The damping matrix (n x n, read-only)."""
        return self._C

    @property
    def K(self) -> np.ndarray:
        """The stiffness matrix (n x n, read-only)."""
        return self._K

    @property
    def contacts(self) -> tuple[Contact, ...]:
        """The contacts (a tuple of Contact)."""
        return self._contacts

    @property
    def F_c(self) -> np.ndarray:
        """The cosine amplitudes of the excitation (n, N)."""
        return self._F_c

    @property
    def F_s(self) -> np.ndarray:
        """The sine amplitudes of the excitation (n, N)."""
        return self._F_s

    @property
    def omega(self) -> float:
        """The excitation's angular frequency, rad/s."""
        return self._omega

    @property
    def x0(self) -> np.ndarray:
        """The initial positions (n, m)."""
        return self._x0

    @property
    def v0(self) -> np.ndarray:
        """The initial velocities (n, m/s)."""
        return self._v0

    @property
    def h(self) -> float:
        """The internal step, s (0: derived from the dynamics)."""
        return self._h

    @property
    def scheme(self) -> str:
        """The time-stepping scheme: located, consistent or paper."""
        return self._scheme

    @property
    def alpha(self) -> float:
        """The Bossak parameter (-1/3 to 0)."""
        return self._alpha

    @property
    def W(self) -> np.ndarray:
        """The contact rows (nc x n, read-only)."""
        return self._W


    @property
    def n(self) -> int:
        """The number of degrees of freedom."""
        return int(self._M.shape[0])

    @property
    def nc(self) -> int:
        """The number of contacts."""
        return len(self._contacts)

    def _per_contact(self, name: str) -> np.ndarray:
        return _frozen(np.array([float(getattr(c, name)) for c in self._contacts], dtype=np.float64))

    @property
    def N(self) -> np.ndarray:
        """The normal loads (nc, N)."""
        return self._per_contact("N")

    @property
    def mu_s(self) -> np.ndarray:
        """The static coefficients (nc)."""
        return self._per_contact("mu_s")

    @property
    def mu_k(self) -> np.ndarray:
        """The kinetic coefficients (nc)."""
        return self._per_contact("mu_k")

    @property
    def k_t(self) -> np.ndarray:
        """The tangential stiffnesses (nc, N/m; 0 for a rigid contact)."""
        return self._per_contact("k_t")

    @property
    def friction_law(self) -> np.ndarray:
        """The friction laws as the FMU's enumeration values (nc ints: 1 coulomb, 2 stribeck)."""
        a = np.array([LAWS[c.law] for c in self._contacts], dtype=np.int64)
        a.setflags(write=False)
        return a

    @property
    def v_s(self) -> np.ndarray:
        """The Stribeck velocities (nc, m/s; used by the Stribeck contacts)."""
        return self._per_contact("v_s")

    @property
    def delta(self) -> np.ndarray:
        """The Stribeck exponents (nc; used by the Stribeck contacts)."""
        return self._per_contact("delta")

    @property
    def breakaway(self) -> np.ndarray:
        """The breakaway limits max(mu_s, mu_k) N (nc, N)."""
        return _frozen(np.maximum(self.mu_s, self.mu_k) * self.N)

    def excitation(self, t: float) -> np.ndarray:
        """F_c cos(omega t) + F_s sin(omega t) at time t (n, N)."""
        return self._F_c * math.cos(self._omega * t) + self._F_s * math.sin(self._omega * t)

    # --- copies ---
    def _fields(self) -> dict[str, Any]:
        return dict(M=self.M, K=self.K, C=self.C, contacts=self.contacts, F_c=self.F_c, F_s=self.F_s,
                    omega=self.omega, x0=self.x0, v0=self.v0, h=self.h, scheme=self.scheme, alpha=self.alpha)

    def replace(self, **changes: Any) -> "System":
        """A copy with some fields changed (checked again)."""
        unknown = set(changes) - set(self._fields())
        if unknown:
            raise UsageError(f"System has no field {sorted(unknown)[0]!r}; fields: {', '.join(self._fields())}")
        if changes and set(changes) <= {"omega", "h"}:
            # (only the frequency or the step: the arrays, checked already, shared; the numbers
            # checked as __init__ checks them. A sweep makes one copy per point and step.)
            out = object.__new__(type(self))
            for name in self.__slots__:
                object.__setattr__(out, name, getattr(self, name))
            for name, value in changes.items():
                object.__setattr__(out, f"_{name}", _nonneg(name, value))
            return out
        return System(**{**self._fields(), **changes})

    def with_rayleigh(self, alpha_M: float, beta_K: float) -> "System":
        """A copy with Rayleigh damping C = alpha_M M + beta_K K (alpha_M, beta_K >= 0)."""
        a = _nonneg("alpha_M", alpha_M)
        b = _nonneg("beta_K", beta_K)
        return self.replace(C=a * self.M + b * self.K)

    def modes(self) -> tuple[np.ndarray, np.ndarray]:
        """The undamped modes without friction: the angular frequencies w_r (n, ascending, rad/s) and
        the mass-normalised mode shapes Phi (n x n, Phi' M Phi = I). An eigenvalue of K within
        rounding below 0 counts as 0 (a rigid-body mode)."""
        from scipy.linalg import eigh

        lam, phi = eigh(self.K, self.M)
        return np.sqrt(np.maximum(lam, 0.0)), phi

    def with_modal_damping(self, zeta: float | Sequence[float]) -> "System":
        """A copy with modal damping: C = M Phi diag(2 zeta_r w_r) Phi' M with the mass-normalised
        modes Phi and frequencies w_r of :meth:`modes`, so that Phi' C Phi = diag(2 zeta_r w_r).
        ``zeta`` one ratio for every mode or one per mode (n values, ascending frequency, >= 0).
        A zero-frequency (rigid-body) mode gets no damping (2 zeta w = 0), whatever its zeta."""
        z = _vector("zeta", zeta, self.n)
        bad = np.flatnonzero(z < 0)
        if bad.size:
            raise UsageError(f"zeta[{int(bad[0])}] is {float(z[bad[0]])!r}; valid range: >= 0")
        w, phi = self.modes()
        MP = self.M @ phi
        C = MP @ np.diag(2.0 * z * w) @ MP.T
        return self.replace(C=0.5 * (C + C.T))

    # --- the other models as systems ---
    @classmethod
    def from_oscillator(cls, osc: "Oscillator", h: float = 0.0, scheme: str = "located") -> "System":
        """The oscillator (:class:`dryfriction.params.Oscillator`) as a system: n = 1, one rigid
        contact ``dof=0`` with N, mu_s and mu_k = chi mu_s; the excitation P0 cos(omega t + phi) as
        F_c = P0 cos(phi), F_s = -P0 sin(phi)."""
        return cls(M=[[osc.m]], K=[[osc.k]], C=[[osc.c]],
                   contacts=[Contact(dof=0, N=osc.N, mu_s=osc.mu_s, mu_k=osc.mu_k)],
                   F_c=[osc.P0 * math.cos(osc.phi)], F_s=[-osc.P0 * math.sin(osc.phi) + 0.0], omega=osc.omega,
                   x0=[osc.x0], v0=[osc.v0], h=h, scheme=scheme)

    @classmethod
    def from_chain(cls, n: int | None = None, *, m: Any = 1.0, k: Any = 100.0, c: Any = 0.0, P0: Any = 1.0,
                   phi: Any = 0.0, N: Any = 1.0, mu_s: Any = 0.4, chi: Any = 0.7, x0: Any = 0.0, v0: Any = 0.0,
                   omega: float = 5.0, k_end: float = 0.0, c_end: float = 0.0, k_site: Any = 0.0,
                   c_site: Any = 0.0, h: float = 0.0, scheme: str = "located") -> "System":
        """The chain FMU's model (its parameters by the chain FMU's names and defaults) as a system.

        Block i (0-based here; the chain FMU's ``k[i+1]``) is tied to block i - 1 by the spring
        ``k[i]`` and the damper ``c[i]`` on its left, block 0 to the left wall, the last block to
        the right wall by ``k_end``, ``c_end`` (0: a free end), every block to the ground by
        ``k_site[i]``, ``c_site[i]``. Each block has one rigid contact ``dof=i`` with ``N[i]``,
        ``mu_s[i]`` and ``mu_k = chi[i] mu_s[i]``, and the excitation P0[i] cos(omega t + phi[i]):
        F_c = P0 cos(phi), F_s = -P0 sin(phi). ``n`` defaults to the length of the arrays given
        (scalars count for every block)."""
        arrays = dict(m=m, k=k, c=c, P0=P0, phi=phi, N=N, mu_s=mu_s, chi=chi, x0=x0, v0=v0, k_site=k_site,
                      c_site=c_site)
        if n is None:
            sizes = {np.size(v) for v in arrays.values() if np.ndim(v) > 0}
            if len(sizes) > 1:
                raise UsageError(f"from_chain: the arrays have different lengths {sorted(sizes)}: give n or "
                                 "arrays of one length")
            n = sizes.pop() if sizes else 1
        nn = _index("from_chain: n", n)
        if nn < 1:
            raise UsageError(f"from_chain: n = {nn}; valid range: >= 1")
        a = {name: _vector(name, v, nn) for name, v in arrays.items()}
        for name in ("m",):
            bad = np.flatnonzero(a[name] <= 0)
            if bad.size:
                raise UsageError(f"{name}[{int(bad[0])}] is {float(a[name][bad[0]])!r}; valid range: > 0")
        for name in ("k", "c", "N", "mu_s", "chi", "k_site", "c_site"):
            bad = np.flatnonzero(a[name] < 0)
            if bad.size:
                raise UsageError(f"{name}[{int(bad[0])}] is {float(a[name][bad[0]])!r}; valid range: >= 0")

        def tridiag(s: np.ndarray, s_end: float, site: np.ndarray) -> np.ndarray:
            right = np.append(s[1:], s_end)
            A = np.diag(s + right + site)
            if nn > 1:
                A -= np.diag(s[1:], 1) + np.diag(s[1:], -1)
            return A

        contacts = [Contact(dof=i, N=a["N"][i], mu_s=a["mu_s"][i], mu_k=a["chi"][i] * a["mu_s"][i])
                    for i in range(nn)]
        return cls(M=np.diag(a["m"]), K=tridiag(a["k"], _nonneg("k_end", k_end), a["k_site"]),
                   C=tridiag(a["c"], _nonneg("c_end", c_end), a["c_site"]), contacts=contacts,
                   F_c=a["P0"] * np.cos(a["phi"]), F_s=-a["P0"] * np.sin(a["phi"]) + 0.0, omega=omega,
                   x0=a["x0"], v0=a["v0"], h=h, scheme=scheme)

    @classmethod
    def from_file(cls, path: Any) -> "System":
        """The system a TOML structure file describes (:func:`dryfriction.system.spec.load`)."""
        from .spec import load

        return load(path)

    def fmu(self, path: Any, fmi: int = 3, *, base: Any = None) -> Any:
        """Write this structure's own FMU to ``path`` (``NAME.fmu``) without a compiler: the
        package's prebuilt ``DryFrictionSystem`` binary, this system's values as the model
        description's start values and in ``resources/structure.bin``, read by the binary at
        instantiation (:func:`dryfriction.system.fmu.write_fmu`). ``fmi``: 3 (FMI 3.0) or 2 (FMI
        2.0, flattened names ``M[1,2]``, their value references laid out for this structure's sizes
        in the file too); any sizes either way. Returns the path written."""
        from .fmu import write_fmu

        return write_fmu(self, path, fmi=fmi, base=base)

    # --- the FMU ---
    def start_values(self) -> dict[str, Any]:
        """The start values of the FMI 3.0 FMU ``DryFrictionSystem`` for this system: variable name
        -> value (matrices flattened row-major, arrays as Python lists of floats, ``n`` and ``nc`` as
        ints, ``scheme`` as its enumeration value: paper 1, consistent 2, located 3, ``friction_law``
        as a list of the enumeration's values: coulomb 1, stribeck 2). The observation window of the
        observables (``t_obs_start``, ``t_obs_stop``, ``observe``) is a run's option, not the
        system's (:meth:`dryfriction.drivers.system.SystemFMU3.start`)."""
        return {
            "n": self.n, "nc": self.nc,
            "M": self.M.ravel().tolist(), "C": self.C.ravel().tolist(), "K": self.K.ravel().tolist(),
            "F_c": self.F_c.tolist(), "F_s": self.F_s.tolist(), "x0": self.x0.tolist(), "v0": self.v0.tolist(),
            "W": self.W.ravel().tolist(), "N": self.N.tolist(), "mu_s": self.mu_s.tolist(),
            "mu_k": self.mu_k.tolist(), "k_t": self.k_t.tolist(),
            "friction_law": [int(v) for v in self.friction_law], "v_s": self.v_s.tolist(),
            "delta": self.delta.tolist(),
            "omega": self.omega, "h": self.h, "alpha": self.alpha, "scheme": SCHEMES[self.scheme],
        }


def _make_system(fields: dict[str, Any]) -> System:
    """A System from its fields (the unpickler's)."""
    return System(**fields)
