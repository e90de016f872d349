"""The field's benchmark structures with friction contacts, as :class:`~dryfriction.system.structure.System` s.

- :func:`two_mass_jenkins`: two masses with a Jenkins element between them, the project's goal case
  for steady states of structures (pyHarm measured on it against an exact reference);
- :func:`bladed_disk`: the lumped bladed disk with a friction ring damper of Laxalde et al. (2007)
  (its travelling-wave symmetry: :func:`bladed_disk_symmetry`),
  with the parameters of pyHarm's tutorial 006;
- :func:`cantilever`: the mass and stiffness matrices of a clamped Euler-Bernoulli cantilever (the
  finite-element model of examples/beam_friction_damper.py).

Each builder returns a checked System (every value goes through System's own checks); its
parameters are keyword arguments. Degree-of-freedom indices are 0-based::

    from dryfriction.system import cases
    sys = cases.two_mass_jenkins(N=0.6, omega=1.4)
    disk = cases.bladed_disk(omega=1064.0)        # 96 DOFs, 24 Jenkins contacts
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import UsageError
from .structure import Contact, System

if TYPE_CHECKING:
    from .structure import System as Structure  # (the annotations' name: the API reference links it)
    from .symmetry import CyclicSymmetry

__all__ = ["two_mass_jenkins", "bladed_disk", "bladed_disk_sector", "bladed_disk_modes", "bladed_disk_symmetry", "cantilever",
           "TWO_MASS", "BLADED_DISK"]

#: the two-mass case's fixed values: masses, stiffness matrix, Rayleigh factors, force on mass 0
TWO_MASS: dict[str, Any] = {"M": ((1.0, 0.0), (0.0, 0.5)), "K": ((3.0, -1.0), (-1.0, 1.0)),
                            "alpha_M": 0.02, "beta_K": 0.02, "F_c": (1.0, 0.0)}

#: the bladed disk's parameters (pyHarm tutorial 006, the notebook's code cells; SI units): per sector
#: the disk mass m0 tied to the ground by kg and to the next sector's disk by k0, the blade masses
#: mb1 (on the disk by kb1) and mb2 (on mb1 by kb2); the ring sector's mass mr, tied to the next ring
#: sector by kr, to the ground by kr_ground; the Jenkins contact of ring sector s on disk mass s with
#: the tangential stiffness k_t, the friction coefficient mu and the normal load N = mr R Omega^2
#: (the ring's centrifugal load at the radius R and the rotation speed Omega, which the tutorial
#: takes as half the tuned blisk's first one-nodal-diameter frequency); blisk damping ratio zeta;
#: unit forces on the blade tips mb2
BLADED_DISK: dict[str, Any] = {
    "n_sectors": 24, "m0": 1.2, "mb1": 0.35, "mb2": 0.25, "kg": 6e5, "k0": 5e7, "kb1": 1e6, "kb2": 2e6,
    "mr": 20e-4, "kr": 1e7, "kr_ground": 1e4, "k_t": 1e8, "mu": 0.1, "R": 0.1, "zeta": 1e-3, "F0": 1.0,
}


def two_mass_jenkins(N: float = 0.6, *, mu_s: float = 0.5, mu_k: float | None = None, k_t: float = 20.0,
                     omega: float = 1.0, h: float = 0.0, scheme: str = "located", x0: Any = None,
                     v0: Any = None) -> System:
    """The two-mass structure with a Jenkins element between the masses (the goal case of the
    project's steady states of structures, measured there against pyHarm):

        M = diag(1, 0.5),  K = [[3, -1], [-1, 1]],  C = 0.02 K + 0.02 M,  F = [1, 0] cos(omega t),

    and one Jenkins element (a spring ``k_t`` in series with a slider) on the slip ``x0 - x1``
    (``Contact(between=(0, 1))``) with the normal load ``N`` and the coefficients ``mu_s``, ``mu_k``
    (``mu_k`` defaults to ``mu_s``: one coefficient, 0.5). Its linear limits are closed forms:
    sliding freely (N = 0) the undamped frequencies of (K, M) are 1 and 2 rad/s (w^4 - 5 w^2 + 4
    = 0); stuck, those of (K + k_t w'w, M) solve w^4 - (5 + 3 k_t) w^2 + 4 (1 + k_t) = 0, for k_t =
    20 w^2 = (65 -+ sqrt(3889)) / 2 (1.1485 and 7.9800 rad/s).

    ``omega`` the forcing's angular frequency (rad/s; the benchmark's are 1.0, 1.4, 1.8, 2.5),
    ``h``, ``scheme``, ``x0``, ``v0`` as System's (the start at rest by default).

    Raises dryfriction.UsageError for a value System refuses (negative N, mu_s, mu_k or k_t, ...).
    """
    base = System(M=TWO_MASS["M"], K=TWO_MASS["K"], F_c=TWO_MASS["F_c"], omega=omega, h=h, scheme=scheme,
                  x0=x0, v0=v0,
                  contacts=[Contact(between=(0, 1), N=N, mu_s=mu_s, mu_k=mu_s if mu_k is None else mu_k,
                                    k_t=k_t)])
    return base.with_rayleigh(TWO_MASS["alpha_M"], TWO_MASS["beta_K"])


def cantilever(elements: int, length: float = 1.0, EI: float = 1.0, rhoA: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """M and K of a cantilever clamped at its root: ``elements`` Euler-Bernoulli elements of equal
    length (bending stiffness ``EI``, mass per length ``rhoA``), their consistent element matrices
    assembled over the nodes (deflection w, slope theta per node), the root's two DOFs removed: 2
    ``elements`` DOFs, DOF 2 (k - 1) node k's deflection and 2 (k - 1) + 1 its slope (k = 1 ..
    elements; the tip's deflection is DOF 2 elements - 2)."""
    if int(elements) < 1 or not (length > 0 and EI > 0 and rhoA > 0):
        raise UsageError(f"a cantilever needs elements >= 1 and length, EI, rhoA > 0 (got {elements}, {length}, "
                         f"{EI}, {rhoA})")
    le = length / int(elements)
    ke = EI / le**3 * np.array([[12, 6 * le, -12, 6 * le], [6 * le, 4 * le**2, -6 * le, 2 * le**2],
                                [-12, -6 * le, 12, -6 * le], [6 * le, 2 * le**2, -6 * le, 4 * le**2]])
    me = rhoA * le / 420.0 * np.array([[156, 22 * le, 54, -13 * le], [22 * le, 4 * le**2, 13 * le, -3 * le**2],
                                       [54, 13 * le, 156, -22 * le], [-13 * le, -3 * le**2, -22 * le, 4 * le**2]])
    nd = 2 * (int(elements) + 1)
    M, K = np.zeros((nd, nd)), np.zeros((nd, nd))
    for e in range(int(elements)):
        s = slice(2 * e, 2 * e + 4)
        M[s, s] += me
        K[s, s] += ke
    return M[2:, 2:], K[2:, 2:]


def _sector_blisk(p: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """One blisk sector's mass and stiffness (disk, blade 1, blade 2), without the k0 coupling."""
    Ms = np.diag([p["m0"], p["mb1"], p["mb2"]])
    Ks = np.array([[p["kg"] + p["kb1"], -p["kb1"], 0.0],
                   [-p["kb1"], p["kb1"] + p["kb2"], -p["kb2"]],
                   [0.0, -p["kb2"], p["kb2"]]])
    return Ms, Ks


def _params(overrides: dict[str, Any]) -> dict[str, Any]:
    unknown = set(overrides) - set(BLADED_DISK)
    if unknown:
        raise UsageError(f"bladed_disk has no parameter {sorted(unknown)[0]!r}; parameters: {', '.join(BLADED_DISK)}")
    p = {**BLADED_DISK, **overrides}
    n = p["n_sectors"]
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 3:
        raise UsageError(f"bladed_disk: n_sectors = {n!r}; valid range: an integer >= 3")
    for name in ("m0", "mb1", "mb2", "mr"):
        if not (isinstance(p[name], (int, float)) and math.isfinite(p[name]) and p[name] > 0):
            raise UsageError(f"bladed_disk: {name} = {p[name]!r}; valid range: > 0 (a mass)")
    return p


def _blisk_matrices(p: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """The tuned blisk's M and K (3 n_sectors DOFs; sector s: 3s disk, 3s+1 blade 1, 3s+2 blade 2)."""
    n = p["n_sectors"]
    Ms, Ks = _sector_blisk(p)
    M = np.kron(np.eye(n), Ms)
    K = np.kron(np.eye(n), Ks)
    for s in range(n):
        i, j = 3 * s, 3 * ((s + 1) % n)
        K[i, i] += p["k0"]
        K[j, j] += p["k0"]
        K[i, j] -= p["k0"]
        K[j, i] -= p["k0"]
    return M, K


def bladed_disk_modes(**params: Any) -> np.ndarray:
    """The tuned blisk's natural frequencies without the ring (Hz, ascending, 3 n_sectors values):
    the tutorial's linear analysis (88.26, 169.34, 169.34, 189.30, ... Hz for its parameters).
    ``params`` override :data:`BLADED_DISK`'s."""
    from scipy.linalg import eigh

    M, K = _blisk_matrices(_params(params))
    return np.sqrt(np.maximum(eigh(K, M, eigvals_only=True), 0.0)) / (2.0 * math.pi)


def bladed_disk_sector(nodal_diameter: int, stuck: bool, **params: Any) -> tuple[np.ndarray, np.ndarray]:
    """The cyclic-symmetry reduction of the bladed disk with its ring at one nodal diameter k: the
    sector's 4 x 4 mass and (Hermitian) stiffness matrices (disk, blade 1, blade 2, ring) for the
    travelling wave x_{s} = X exp(i 2 pi k s / n_sectors), the disk-to-disk spring k0 and the
    ring-to-ring spring kr becoming k (2 - 2 cos(2 pi k / n_sectors)) on their DOF; ``stuck``: the
    Jenkins contacts held (the spring k_t between disk and ring), else sliding (no tangential
    force). The full structure's natural frequencies at that diameter are this pair's
    (:func:`numpy.linalg.eigvalsh` of M^-1/2 K M^-1/2): a check on the assembly independent of it."""
    p = _params(params)
    n = p["n_sectors"]
    c = 2.0 - 2.0 * math.cos(2.0 * math.pi * nodal_diameter / n)
    Ms, Ks = _sector_blisk(p)
    M = np.zeros((4, 4))
    K = np.zeros((4, 4))
    M[:3, :3] = Ms
    M[3, 3] = p["mr"]
    K[:3, :3] = Ks
    K[0, 0] += p["k0"] * c
    K[3, 3] = p["kr"] * c + p["kr_ground"]
    if stuck:
        K[np.ix_([0, 3], [0, 3])] += p["k_t"] * np.array([[1.0, -1.0], [-1.0, 1.0]])
    return M, K


def bladed_disk(*, omega: float | None = None, engine_order: int = 1, N: float | None = None,
                mu: float | None = None, k_t: float | None = None, ring: bool = True, h: float = 0.0,
                scheme: str = "located", x0: Any = None, v0: Any = None, **params: Any) -> System:
    """The lumped bladed disk with a friction ring damper of Laxalde, Thouverez, Sinou and Lombard,
    *Qualitative analysis of forced response of blisks with friction ring dampers*, European Journal
    of Mechanics A/Solids 26 (2007) 676-687, with the parameters of pyHarm's tutorial 006
    (repository QUICKguils/pyHarm, ``Tutorials/Tuto_006_LumpedBladedDisk.ipynb`` and its
    ``_correctionfunctions.py``), :data:`BLADED_DISK`.

    The structure: ``n_sectors`` = 24 sectors of three DOFs (sector s: ``3s`` the disk mass m0 =
    1.2 kg, ``3s+1`` the blade mass mb1, ``3s+2`` the blade tip mb2; the disk on the ground by kg =
    6e5 N/m and on the next sector's disk by k0 = 5e7 N/m, the blades in series by kb1 = 1e6 and
    kb2 = 2e6 N/m), then (``ring``) the ring's 24 sectors (DOF ``3 n_sectors + s``, mass mr = 2e-3
    kg, on the next ring sector by kr = 1e7 N/m and on the ground by kr / 1000, the tutorial's
    spring against the ring's rigid-body motion) and 24 Jenkins contacts, ring sector s on disk mass
    s (``Contact(between=(3 n_sectors + s, 3 s))``), with the tutorial's tangential stiffness k_t =
    10 kr = 1e8 N/m, mu = 0.1 (mu_s = mu_k) and the normal load N = mr R Omega^2 (R = 0.1 m, Omega
    half the tuned blisk's first one-nodal-diameter frequency, 2 pi 169.344 / 2 rad/s: N = 56.62 N,
    the limit mu N = 5.66 N). n = 96 DOFs, nc = 24 contacts (72 and 0 without the ring).

    **The blade masses**: the tutorial's table gives mb1 = 3.5e-3 and mb2 = 2.5e-3 kg, its code
    350e-3 and 250e-3 kg; the code is followed (its printed frequencies, 88.26 Hz ..., are the
    code's; :func:`bladed_disk_modes`).

    **Damping**: the blisk's modes have the damping ratio zeta = 1e-3 (the tutorial's xi); the
    tutorial writes C = Phi diag(2 xi w) Phi' with the unit-norm eigenvectors of M^-1 K, which is
    not modal damping (the vectors are not mass-normalised) and not unique for the degenerate
    pairs (its printed C differs from sector to sector); here C = M Phi diag(2 zeta w) Phi' M with
    the mass-normalised modes of the blisk without the ring (Phi' C Phi = diag(2 zeta w)). The
    ring has no damping (the tutorial's ring C = 0).

    **Excitation**: one engine order ``engine_order`` (the tutorial's nodal diameter 1): a force
    F0 = 1 N on every blade tip with the phase phi_s = 2 pi EO s / n_sectors,
    ``F0 cos(omega t - phi_s)`` as pyHarm's GOForcing (cosine part cos(phi_s), sine part sin(phi_s)):
    ``F_c[3s+2] = F0 cos(phi_s)``, ``F_s[3s+2] = F0 sin(phi_s)``. ``omega`` (rad/s) defaults to
    the tuned blisk's first family at that nodal diameter (1064.0 rad/s for EO 1; the tutorial sweeps
    0.95 to 1.10 times it).

    ``N``, ``mu``, ``k_t`` override the contacts' defaults; ``params`` any of :data:`BLADED_DISK`'s
    (``zeta``, ``F0``, ``n_sectors``, masses and stiffnesses); ``h``, ``scheme``, ``x0``, ``v0`` as
    System's.

    Raises dryfriction.UsageError for an unknown parameter, an engine order outside 0 to
    n_sectors / 2, or a value System refuses.
    """
    p = _params(params)
    n = int(p["n_sectors"])
    if isinstance(engine_order, bool) or not isinstance(engine_order, (int, np.integer)) or \
            not 0 <= engine_order <= n // 2:
        raise UsageError(f"bladed_disk: engine_order = {engine_order!r}; valid range: an integer 0 to {n // 2}")
    Mb, Kb = _blisk_matrices(p)
    from scipy.linalg import eigh

    lam, phi = eigh(Kb, Mb)
    w = np.sqrt(np.maximum(lam, 0.0))
    MP = Mb @ phi
    Cb = MP @ np.diag(2.0 * float(p["zeta"]) * w) @ MP.T
    Cb = 0.5 * (Cb + Cb.T)
    nb = 3 * n
    # the first family's frequency at the engine order's diameter (the sector reduction without the ring)
    Ms, Ks = _sector_blisk(p)
    Ks = Ks.copy()
    Ks[0, 0] += p["k0"] * (2.0 - 2.0 * math.cos(2.0 * math.pi * engine_order / n))
    w_eo = float(np.sqrt(eigh(Ks, Ms, eigvals_only=True)[0]))
    Ks1 = _sector_blisk(p)[1].copy()
    Ks1[0, 0] += p["k0"] * (2.0 - 2.0 * math.cos(2.0 * math.pi / n))
    w_nd1 = float(np.sqrt(eigh(Ks1, Ms, eigvals_only=True)[0]))      # the rotation speed's reference
    om = w_eo if omega is None else omega
    phase = 2.0 * math.pi * engine_order * np.arange(n) / n
    nn = nb + (n if ring else 0)
    F_c = np.zeros(nn)
    F_s = np.zeros(nn)
    F_c[3 * np.arange(n) + 2] = p["F0"] * np.cos(phase)
    F_s[3 * np.arange(n) + 2] = p["F0"] * np.sin(phase)
    M = np.zeros((nn, nn))
    K = np.zeros((nn, nn))
    C = np.zeros((nn, nn))
    M[:nb, :nb], K[:nb, :nb], C[:nb, :nb] = Mb, Kb, Cb
    contacts: list[Contact] = []
    if ring:
        r = nb + np.arange(n)
        M[r, r] = p["mr"]
        for s in range(n):
            i, j = nb + s, nb + (s + 1) % n
            K[i, i] += p["kr"] + p["kr_ground"]
            K[j, j] += p["kr"]
            K[i, j] -= p["kr"]
            K[j, i] -= p["kr"]
        normal = p["mr"] * p["R"] * (0.5 * w_nd1) ** 2 if N is None else N
        coef = p["mu"] if mu is None else mu
        kt = p["k_t"] if k_t is None else k_t
        contacts = [Contact(between=(nb + s, 3 * s), N=normal, mu_s=coef, mu_k=coef, k_t=kt) for s in range(n)]
    elif N is not None or mu is not None or k_t is not None:
        raise UsageError("bladed_disk: N, mu and k_t are the ring's contacts' values: give them with ring=True")
    return System(M=M, K=K, C=C, contacts=contacts, F_c=F_c, F_s=F_s, omega=om, x0=x0, v0=v0, h=h,
                  scheme=scheme)


def bladed_disk_symmetry(system: "Structure") -> "CyclicSymmetry":
    """The travelling-wave symmetry of a :func:`bladed_disk` (its sector s: DOFs ``3s``, ``3s+1``,
    ``3s+2`` and, with the ring, ``3 n_sectors + s`` and contact s): the sector shift of its
    engine order (:meth:`~dryfriction.system.symmetry.CyclicSymmetry.of_sectors`), for
    ``find_system_orbits(..., symmetry=...)`` and the response's. Raises dryfriction.UsageError
    where the excitation is not a travelling wave (engine order 0, or one that shares a factor
    with the number of sectors)."""
    from .symmetry import CyclicSymmetry

    ring = system.nc > 0
    ns = system.nc if ring else system.n // 3
    if ns < 2 or system.n != (4 if ring else 3) * ns:
        raise UsageError(f"bladed_disk_symmetry: n = {system.n}, nc = {system.nc} is not a bladed disk's layout")
    dofs = [[3 * s, 3 * s + 1, 3 * s + 2] + ([3 * ns + s] if ring else []) for s in range(ns)]
    return CyclicSymmetry.of_sectors(system, dofs, [[s] for s in range(ns)] if ring else ())
