"""Exact piecewise ("stitching") solution of the dry-friction oscillator (method.md sections 1, 5).

The model, in SI units:

    m x'' + c x' + k x = P0 cos(omega t + phi) + F

    sliding in direction s = sign(x') (mode s = +1 / -1):  F = -s mu_k N,  mu_k = chi mu_s
    stuck (mode 0, x' = 0):  F = -(P(t) - k x),  |F| <= F_b = max(mu_s, mu_k) N

A slip in direction s lasts while s x' > 0.  At a stop (x' = 0) the block sticks if
|P(t) - k x| <= F_b, else it slides on in the direction sign(P - k x).  A stick ends at the first
later time where |P(t) - k x| crosses F_b (closed form via arccos; a tangential touch keeps it
stuck).

Internally every phase is solved in the non-dimensional form of method.md (2), with
tau = w0 t, u = w0 (t - t0) the local time of a phase, and z = x / L where L = F_s / k for a force
scale F_s (|P0| if non-zero):

    z'' + 2 zeta z' + z = a cos(theta0 + lambda u) - s b          (slip,  a = |P0| / F_s,
                                                                   b = mu_k N / F_s)

With w = z + s b the slip phase is linear with homogeneous data w(0), w'(0):

    w(u)  = w0 E(u) + (v0 + zeta w0) F(u) + a x_f(u)
    w'(u) = v0 E(u) - (w0 + zeta v0) F(u) + a v_f(u)

where E = e^{-zeta u} cos(wd u), F = e^{-zeta u} sin(wd u) / wd (wd = sqrt(1 - zeta^2); the
critically and over-damped forms are their analytic continuations) and x_f, v_f the response from
rest to cos(theta0 + lambda u).  For zeta < 1/2 the forced response is written without the
1 / (1 - lambda^2 + 2 i zeta lambda) cancellation,

    x_f = Re[e^{i theta0} e^{i lambda u} u (phi1(z1) - phi1(z2)) / (2 i wd)],
    v_f = Re[e^{i theta0} e^{i lambda u} u (p1 phi1(z1) - p2 phi1(z2)) / (2 i wd)],

    p1,2 = -zeta +- i wd,  z_j = (p_j - i lambda) u,  phi1(z) = (e^z - 1) / z,

so that lambda = 1, zeta = 0 (x_f = (u sin(u + theta0) - sin u sin theta0) / 2) is a limit and not
a special case.  For zeta >= 1/2 the steady-state form Re[H e^{i(theta0 + lambda u)}],
H = 1 / (1 - lambda^2 + 2 i zeta lambda), |H| <= 1.16, is used instead.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import Any, Optional

import numpy as np

from ..params import Oscillator
from ..roots import find_root

__all__ = ["Segment", "ExactSolution", "solve_exact", "linear_solution", "validate_oscillator"]

_EPS = float(np.finfo(float).eps)
_TWO_PI = 2.0 * math.pi
_ZETA_STEADY = 0.5          # zeta at and above which the steady-state form of x_f is used
_ROUND = 64.0 * _EPS        # relative rounding level used for the zero tests
_GEOM_LEVELS = 45           # geometric grid u = h 2^-k, k = 1..45, at the start of a slip from rest
_CHUNK0 = 64                # grid points in the first scan chunk of a slip (then doubling)
_CHUNK_MAX = 4096
# |z| below which phi1(z) = 1 + z / 2 to rounding (the next term z^2 / 6 < 2^-53); also where the
# complex quotient (e^z - 1) / z would divide by a subnormal (numpy's overflows: zeta 1e-298)
_PHI1_SERIES = 1e-9


# --------------------------------------------------------------------------- public types


@dataclass(frozen=True)
class Segment:
    """One phase of the motion: [t0, t1] in s, mode -1 backward slip, 0 stuck, +1 forward slip,
    state x0 (m), v0 (m/s) at t0."""

    t0: float
    t1: float
    mode: int
    x0: float
    v0: float


@dataclass(frozen=True)
class ExactSolution:
    """The exact solution on [0, t_end] as a sequence of segments (see the module docstring)."""

    params: Oscillator
    segments: tuple[Segment, ...]

    @cached_property
    def _model(self) -> "_Model":
        return _Model.from_params(self.params)

    @cached_property
    def _starts(self) -> np.ndarray:
        return np.array([s.t0 for s in self.segments], dtype=float)

    @property
    def t_end(self) -> float:
        """The time the solution ends, s."""
        return self.segments[-1].t1

    def switch_times(self) -> np.ndarray:
        """Times where one segment ends and the next begins (stops, sticks, breakaways), s."""
        return self._starts[1:].copy()

    def modes(self) -> np.ndarray:
        """Mode of each segment (-1, 0, +1)."""
        return np.array([s.mode for s in self.segments], dtype=int)

    def segment_index(self, t: np.ndarray) -> np.ndarray:
        """Index of the segment holding each time; at a switch time the later segment."""
        t = np.asarray(t, dtype=float)
        tol = 1e-12 * max(self.t_end, 1.0 / self._model.w0)
        if t.size and (np.any(~np.isfinite(t)) or t.min() < -tol or t.max() > self.t_end + tol):
            raise ValueError(f"times must lie in [0, {self.t_end}] s")
        idx = np.searchsorted(self._starts, t, side="right") - 1
        return np.clip(idx, 0, len(self.segments) - 1)

    def evaluate(self, t: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """x (m), v (m/s), a (m/s^2), mode at the times t (vectorised per segment).

        At a switch time the later segment is used.  While stuck x = x0, v = a = 0.
        """
        t = np.asarray(t, dtype=float)
        idx = self.segment_index(t)
        x = np.empty(t.shape)
        v = np.zeros(t.shape)
        acc = np.zeros(t.shape)
        mode = np.empty(t.shape, dtype=int)
        mdl = self._model
        order = np.argsort(idx, kind="stable")
        uniq, first = np.unique(idx[order], return_index=True)
        bounds = np.append(first, order.size)
        for j, i in enumerate(uniq):
            sel = order[bounds[j]:bounds[j + 1]]
            seg = self.segments[int(i)]
            mode[sel] = seg.mode
            if seg.mode == 0:
                x[sel] = seg.x0
                continue
            kern = _Slip(mdl, seg.t0, seg.x0, seg.v0, seg.mode)
            z, zd, zdd = kern.eval(mdl.w0 * (t[sel] - seg.t0))
            x[sel] = z * mdl.L
            v[sel] = zd * mdl.L * mdl.w0
            acc[sel] = zdd * mdl.L * mdl.w0**2
        return x, v, acc, mode

    def excitation(self, t: Any) -> np.ndarray:
        """P(t) = P0 cos(omega t + phi), N."""
        p = self.params
        return p.P0 * np.cos(p.omega * np.asarray(t, dtype=float) + p.phi)

    def friction(self, t: Any) -> np.ndarray:
        """Friction force F(t), N: -s mu_k N while sliding, -(P(t) - k x) while stuck."""
        x, _, _, mode = self.evaluate(t)
        p = self.params
        stuck = -(self.excitation(t) - p.k * x)
        return np.where(mode == 0, stuck, -mode * p.mu_k * p.N)


def validate_oscillator(p: Oscillator) -> None:
    """Raise ValueError unless the parameters admit the exact solution."""
    for name, value in p.as_dict().items():
        if not math.isfinite(value):
            raise ValueError(f"parameter {name} = {value} is not finite")
    checks = [
        ("m", p.m > 0, "the mass m must be > 0"),
        ("k", p.k > 0, "the spring stiffness k must be > 0 (the exact solver needs k > 0)"),
        ("c", p.c >= 0, "the damping c must be >= 0"),
        ("N", p.N >= 0, "the normal force N must be >= 0"),
        ("mu_s", p.mu_s >= 0, "the static coefficient mu_s must be >= 0"),
        ("chi", p.chi > 0, "the ratio chi = mu_k / mu_s must be > 0"),
    ]
    for name, ok, msg in checks:
        if not ok:
            raise ValueError(f"{msg}, got {name} = {getattr(p, name)}")


def linear_solution(p: Oscillator, t: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Closed-form x, v, a of the frictionless oscillator m x'' + c x' + k x = P0 cos(omega t + phi)
    from x(0) = x0, x'(0) = v0 (N is ignored); any zeta >= 0, lambda = 1 included."""
    validate_oscillator(p)
    mdl = _Model.from_params(p)
    kern = _Slip(mdl, 0.0, p.x0, p.v0, 0)
    z, zd, zdd = kern.eval(mdl.w0 * np.asarray(t, dtype=float))
    return z * mdl.L, zd * mdl.L * mdl.w0, zdd * mdl.L * mdl.w0**2


def solve_exact(p: Oscillator, t_end: float, max_segments: int = 10**6) -> ExactSolution:
    """Exact stick-slip solution on [0, t_end] from x(0) = p.x0, x'(0) = p.v0.

    With v0 = 0 the block starts stuck iff |P(0) - k x0| <= F_b, else it slides in the direction
    of the net force; with v0 != 0 it slides in the direction of v0.

    Parameters
    ----------
    p
        The oscillator (SI units; damping below critical).
    t_end
        The end of the solution, s.
    max_segments
        The most stick and slide segments to compute.

    Returns
    -------
    ExactSolution
        The segments between events, evaluated anywhere by :meth:`ExactSolution.evaluate`.

    Raises
    ------
    ValueError
        ``t_end`` not finite or negative.
    RuntimeError
        More than ``max_segments`` segments before ``t_end``.

    Examples
    --------
    >>> import numpy as np
    >>> from dryfriction import Oscillator, solve_exact
    >>> p = Oscillator.from_nondimensional(lam=0.3, mu_s_sigma=0.7, chi=0.5)
    >>> sol = solve_exact(p, 2 * p.period)
    >>> x, v, a, mode = sol.evaluate(np.linspace(0.0, 2 * p.period, 5))
    """
    validate_oscillator(p)
    if not (math.isfinite(t_end) and t_end >= 0):
        raise ValueError(f"t_end must be finite and >= 0, got {t_end}")
    mdl = _Model.from_params(p)
    segs: list[Segment] = []
    t, x, v = 0.0, float(p.x0), float(p.v0)
    s = int(np.sign(v))
    stopped = v == 0.0
    for _ in range(4 * max_segments + 8):
        if len(segs) >= max_segments:
            break
        if stopped:
            dt, s = _stick_exit(mdl, t, x)
            v = 0.0
            if dt > 0.0:
                t1 = t + dt
                if t1 >= t_end:
                    segs.append(Segment(t, float(t_end), 0, x, 0.0))
                    return ExactSolution(p, tuple(segs))
                segs.append(Segment(t, t1, 0, x, 0.0))
                t = t1
        kern = _Slip(mdl, t, x, v, s)
        u_stop = _find_stop(kern, mdl.w0 * (t_end - t))
        t1 = math.inf if u_stop is None else t + u_stop / mdl.w0
        if t1 >= t_end:
            segs.append(Segment(t, float(t_end), s, x, v))
            return ExactSolution(p, tuple(segs))
        if t1 > t:
            segs.append(Segment(t, t1, s, x, v))
        x = float(kern.eval(u_stop)[0]) * mdl.L
        t, v, stopped = t1, 0.0, True
    raise RuntimeError(
        f"exact solver exceeded max_segments = {max_segments} before t = {t_end} s (reached {t} s)"
    )


# --------------------------------------------------------------------------- model constants


@dataclass(frozen=True)
class _Model:
    """Non-dimensional constants of one parameter set (P0 >= 0 and omega >= 0 normalised)."""

    w0: float       # natural angular frequency, rad/s
    L: float        # length scale F_s / k, m
    omega: float    # |omega|, rad/s
    phi: float      # phase with P0 -> |P0| and omega -> |omega| folded in
    lam: float      # omega / w0 >= 0
    zeta: float
    a: float        # |P0| / F_s
    b: float        # mu_k N / F_s
    fb: float       # F_b / F_s
    h: float        # scan step in u

    @staticmethod
    def from_params(p: Oscillator) -> "_Model":
        phi, omega = float(p.phi), float(p.omega)
        if omega < 0:                       # cos(-|w| t + phi) = cos(|w| t - phi)
            omega, phi = -omega, -phi
        if p.P0 < 0:                        # -|P0| cos(.) = |P0| cos(. + pi)
            phi += math.pi
        w0 = p.w0
        fs = max(abs(p.P0), p.breakaway, p.k * abs(p.x0), math.sqrt(p.k * p.m) * abs(p.v0))
        if not fs > 0:
            fs = 1.0
        lam = omega / w0
        zeta = p.zeta
        return _Model(
            w0=w0,
            L=fs / p.k,
            omega=omega,
            phi=phi,
            lam=lam,
            zeta=zeta,
            a=abs(p.P0) / fs,
            b=p.mu_k * p.N / fs,
            fb=p.breakaway / fs,
            h=0.2 / max(1.0, lam, 2.0 * zeta),
        )


# --------------------------------------------------------------------------- slip kernel


class _Lib:
    """The few elementary functions the kernel needs, for scalars (math) or arrays (numpy)."""

    def __init__(self, mod: Any, scalar: bool) -> None:
        self.cos, self.sin, self.exp, self.expm1 = mod.cos, mod.sin, mod.exp, mod.expm1
        self.scalar = scalar

    def phi1(self, x: Any, y: Any) -> Any:
        """phi1(z) = (e^z - 1) / z for z = x + i y, x <= 0, without cancellation:
        e^z - 1 = expm1(x) cos y - 2 sin^2(y / 2) + i e^x sin y."""
        em_re = self.expm1(x) * self.cos(y) - 2.0 * self.sin(0.5 * y) ** 2
        em_im = self.exp(x) * self.sin(y)
        if self.scalar:
            if abs(x) + abs(y) < _PHI1_SERIES:
                return 1.0 + 0.5 * complex(x, y)
            return complex(em_re, em_im) / complex(x, y)
        den = x + 1j * y
        small = np.abs(x) + np.abs(y) < _PHI1_SERIES
        res = (em_re + 1j * em_im) / np.where(small, 1.0, den)
        return np.where(small, 1.0 + 0.5 * den, res)


_MATH = _Lib(math, True)
_NUMPY = _Lib(np, False)


class _Slip:
    """Closed-form slip phase from (t0, x0, v0) in direction s (s = 0: no friction)."""

    __slots__ = ("m", "s", "w0", "v0", "c0", "ac0", "q", "qp1", "qp2", "hw0", "hv0", "Q", "iQ",
                 "wd", "wh", "r1", "r2", "sb")

    def __init__(self, m: _Model, t0: float, x0: float, v0: float, s: int) -> None:
        self.m, self.s = m, s
        theta0 = math.fmod(m.omega * t0 + m.phi, _TWO_PI)
        self.c0 = complex(math.cos(theta0), math.sin(theta0))
        self.ac0 = m.a * self.c0
        self.sb = s * m.b
        self.w0 = x0 / m.L + self.sb                  # w = z + s b
        self.v0 = v0 / (m.L * m.w0)
        z = m.zeta
        self.wd = math.sqrt(max(0.0, (1.0 - z) * (1.0 + z)))
        self.wh = math.sqrt(max(0.0, (z - 1.0) * (z + 1.0)))
        if z > 1.0:
            self.r1 = -1.0 / (z + self.wh)            # slow root, no cancellation
            self.r2 = -(z + self.wh)
        if z < _ZETA_STEADY:
            p1, p2 = complex(-z, self.wd), complex(-z, -self.wd)
            self.q = self.ac0 / complex(0.0, 2.0 * self.wd)
            self.qp1, self.qp2 = self.q * p1, self.q * p2
            self.hw0, self.hv0 = self.w0, self.v0
        else:
            self.Q = self.ac0 / complex(1.0 - m.lam**2, 2.0 * z * m.lam)
            self.iQ = 1j * m.lam * self.Q
            self.hw0 = self.w0 - self.Q.real            # homogeneous data after removing
            self.hv0 = self.v0 - self.iQ.real           # the steady-state part

    def _ef(self, u: Any, lib: _Lib) -> tuple[Any, Any]:
        """E = e^{-zeta u} cos(wd u), F = e^{-zeta u} sin(wd u) / wd and their continuations."""
        z = self.m.zeta
        if z < 1.0:
            e = lib.exp(-z * u)
            return e * lib.cos(self.wd * u), e * lib.sin(self.wd * u) / self.wd
        if z == 1.0:
            e = lib.exp(-u)
            return e, u * e
        e1, e2 = lib.exp(self.r1 * u), lib.exp(self.r2 * u)
        return 0.5 * (e1 + e2), -e1 * lib.expm1(-2.0 * self.wh * u) / (2.0 * self.wh)

    def eval(self, u: Any) -> tuple[Any, Any, Any]:
        """Non-dimensional z, z', z'' at local time u >= 0 (scalar or array)."""
        lib = _MATH if isinstance(u, (float, int)) else _NUMPY
        m = self.m
        zeta, lam = m.zeta, m.lam
        el = lib.cos(lam * u) + 1j * lib.sin(lam * u)
        E, F = self._ef(u, lib)
        w = self.hw0 * E + (self.hv0 + zeta * self.hw0) * F
        wd_ = self.hv0 * E - (self.hw0 + zeta * self.hv0) * F
        if zeta < _ZETA_STEADY:
            x = -zeta * u
            P1 = lib.phi1(x, (self.wd - lam) * u)
            P2 = lib.phi1(x, -(self.wd + lam) * u)
            eu = el * u
            w = w + (self.q * eu * (P1 - P2)).real
            wd_ = wd_ + (eu * (self.qp1 * P1 - self.qp2 * P2)).real
        else:
            w = w + (self.Q * el).real
            wd_ = wd_ + (self.iQ * el).real
        acc = (self.ac0 * el).real - 2.0 * zeta * wd_ - w
        return w - self.sb, wd_, acc


# --------------------------------------------------------------------------- stop search


def _root(f: Any, a: float, b: float) -> float:
    """Bracketing root of f on [a, b] (f(a) f(b) <= 0) to full double precision
    (:func:`dryfriction.roots.find_root`, f(a) and f(b) not evaluated again).

    The bracket comes from a scan evaluated on a vector; f here is evaluated on scalars, whose last
    bits can differ: an end value within rounding of 0 may come back with the other sign. Then the
    root is at that end (the end with the smaller |f|)."""
    fa, fb = f(a), f(b)
    if fa == 0.0:
        return a
    if fb == 0.0:
        return b
    if (fa > 0.0) == (fb > 0.0):
        return a if abs(fa) <= abs(fb) else b
    return find_root(f, a, b, fa=fa, fb=fb, xtol=1e-300, rtol=4.0 * _EPS, maxiter=200)


def _find_stop(k: _Slip, u_max: float) -> Optional[float]:
    """First local time u in (0, u_max] where the slip stops (s z' reaches 0), or None.

    The velocity is scanned on a grid of step h (plus a geometric grid near u = 0 for a slip
    starting from rest).  Sign changes of s z' are bracketed; local minima of s z' (sign changes
    of s z'') are located and count as a tangential stop when within rounding of 0.  A slip from
    rest counts as started only once s z' exceeds the rounding level (no numerical Zeno loop).
    """
    if not u_max > 0.0:
        return None
    s = k.s if k.s != 0 else 1
    m = k.m

    def sv(u: float) -> float:
        return s * k.eval(u)[1]

    def sa(u: float) -> float:
        return s * k.eval(u)[2]

    scale0 = m.a + m.b + abs(k.w0) + abs(k.v0)
    sv_prev = s * k.v0
    started = sv_prev > _ROUND * scale0
    u_prev = 0.0
    sa_prev = s * k.eval(0.0)[2]
    n = _CHUNK0
    first = True
    while True:
        grid = u_prev + m.h * np.arange(1, n + 1)
        if first and not started:
            grid = np.concatenate([m.h * 2.0 ** -np.arange(_GEOM_LEVELS, 0, -1), grid])
        first = False
        last = grid[-1] >= u_max
        if last:
            grid = np.append(grid[grid < u_max], u_max)
        z, v, acc = k.eval(grid)
        tol = _ROUND * (scale0 + float(np.max(np.abs(z)) + np.max(np.abs(v))))
        us = np.concatenate([[u_prev], grid])
        svs = np.concatenate([[sv_prev], s * v])
        sas = np.concatenate([[sa_prev], s * acc])
        i0 = 1
        if not started:
            res = _scan_start(us, svs, sas, tol, sv, sa)
            if isinstance(res, float):
                return res
            started = res < len(us)
            i0 = res + 1
        if started:
            res_stop = _scan_slip(us, svs, sas, tol, sv, sa, i0)
            if res_stop is not None:
                return res_stop
        if last:
            return None
        u_prev, sv_prev, sa_prev = float(us[-1]), float(svs[-1]), float(sas[-1])
        n = min(2 * n, _CHUNK_MAX)


def _scan_start(us: np.ndarray, svs: np.ndarray, sas: np.ndarray, tol: float,
                sv: Any, sa: Any) -> int | float:
    """Slip from rest: index of the grid point where the slip counts as started (len(us) if not
    yet; stops are searched only after it), or the stop time of a null slip whose velocity
    never leaves the rounding band."""
    for i in range(1, len(us)):
        if svs[i] > tol:
            return i
        if svs[i] < -tol:                          # never started: stop where it leaves the band
            lo, hi = float(us[i - 1]), float(us[i])
            if svs[i - 1] > 0.0:
                return _root(sv, lo, hi)
            return _root(lambda u: sv(u) + tol, lo, hi)
        if sas[i - 1] > 0.0 > sas[i]:              # a maximum inside the interval
            um = _root(sa, float(us[i - 1]), float(us[i]))
            if sv(um) > tol:
                if svs[i] <= 0.0:
                    return _root(sv, um, float(us[i]))
                return i
    return len(us)


def _scan_slip(us: np.ndarray, svs: np.ndarray, sas: np.ndarray, tol: float,
               sv: Any, sa: Any, i0: int) -> Optional[float]:
    """First stop in the intervals (us[i-1], us[i]], i >= i0, of a started slip."""
    neg = np.nonzero(svs[i0:] <= 0.0)[0]
    i_neg = i0 + int(neg[0]) if neg.size else len(us)
    mins = i0 + np.nonzero((sas[i0 - 1:-1] < 0.0) & (sas[i0:] >= 0.0))[0]
    for i in mins[mins <= i_neg]:
        lo, hi = float(us[i - 1]), float(us[i])
        um = _root(sa, lo, hi)
        svm = sv(um)
        if svm < -tol:
            return _root(sv, lo, um)
        if svm <= tol:                             # tangential stop
            return um
    if i_neg < len(us):
        return _root(sv, float(us[i_neg - 1]), float(us[i_neg]))
    return None


# --------------------------------------------------------------------------- stick phase


def _acos(one_minus_c: float, one_plus_c: float) -> float:
    """arccos(c) from 1 - c and 1 + c, accurate near c = +-1."""
    if one_minus_c < one_plus_c:
        return 2.0 * math.asin(math.sqrt(min(1.0, max(0.0, 0.5 * one_minus_c))))
    return math.pi - 2.0 * math.asin(math.sqrt(min(1.0, max(0.0, 0.5 * one_plus_c))))


def _stick_exit(m: _Model, t0: float, x_star: float) -> tuple[float, int]:
    """Block at rest at x_star at time t0: time dt >= 0 (s) until it slides, and the direction.

    g(theta) = a cos(theta) - z is the net applied force; the block slides once |g| > f_b.
    dt = 0 if |g| > f_b now, or if |g| = f_b (to rounding) and |g| is increasing; dt = inf if
    |g| never exceeds f_b (a touch that does not exceed f_b keeps the block stuck).  Otherwise
    the first entry into {cos theta > (z + f_b)/a} is at theta = 2 pi n - arccos((z + f_b)/a), into
    {cos theta < (z - f_b)/a} at theta = 2 pi n + arccos((z - f_b)/a).
    """
    z = x_star / m.L
    theta0 = math.fmod(m.omega * t0 + m.phi, _TWO_PI)
    if theta0 < 0:
        theta0 += _TWO_PI
    a, fb = m.a, m.fb
    g0 = a * math.cos(theta0) - z
    tol_g = _ROUND * (a + abs(z) + fb)
    if abs(g0) > fb + tol_g:
        return 0.0, (1 if g0 > 0 else -1)
    if a == 0.0 or m.lam == 0.0:
        return math.inf, 0
    dg0 = -a * math.sin(theta0)
    tol_d = _ROUND * a
    if abs(g0) >= fb - tol_g:                      # on the boundary of the stick band
        if fb > tol_g:
            sb = 1 if g0 > 0 else -1
            if sb * dg0 > tol_d:
                return 0.0, sb
        elif abs(dg0) > tol_d:
            return 0.0, (1 if dg0 > 0 else -1)
    best, s = math.inf, 0
    up = a - z - fb                                # max g - f_b
    if up > tol_g:
        alpha = _acos(up / a, (a + z + fb) / a)
        best, s = (-alpha - theta0) % _TWO_PI, 1
    lo = a + z - fb                                # -(min g) - f_b
    if lo > tol_g:
        beta = _acos((a - z + fb) / a, lo / a)
        d = (beta - theta0) % _TWO_PI
        if d < best:
            best, s = d, -1
    return best / m.omega, s
