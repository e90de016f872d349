"""The structure file: a :class:`~dryfriction.system.structure.System` described in TOML.

Matrices and vectors are given inline (nested lists, or one number for every entry of a vector) or
as the name of a file, relative to the TOML file's folder: ``.npy`` (numpy), ``.csv`` (numbers
separated by commas, read by ``numpy.loadtxt``; ``#`` starts a comment) or MatrixMarket ``.mtx``
(the format finite-element codes export; sparse or dense, symmetric storage expanded). Degree of
freedom indices are 0-based. Every table and key::

    [structure]                 # required
    M = "M.mtx"                 # mass matrix, n x n (required)
    K = "K.mtx"                 # stiffness matrix, n x n (required)
    C = "C.mtx"                 # damping matrix, n x n (optional; or a [damping] table, not both)

    [damping]                   # optional: one of
    rayleigh = [0.1, 1e-4]      #   C = alpha_M M + beta_K K
    modal = 0.01                #   modal damping ratios: one for every mode, or a list of n

    [excitation]                # optional: F_c cos(omega t) + F_s sin(omega t)
    omega = 12.0                # rad/s (default 0)
    F_c = [0.0, 1.0]            # n values, a file, or a number for every DOF (default 0)
    F_s = [0.0, 0.0]
    # or one force P cos(omega t + phase) on one DOF instead of F_c and F_s:
    # dof = 1
    # amplitude = 1.0
    # phase = 0.0               # rad (default 0)

    [[contact]]                 # any number of contacts
    dof = 3                     # exactly one of dof, between = [i, j] (w = e_i - e_j), w = [...]
    N = 10.0                    # normal load (>= 0)
    mu_s = 0.3
    mu_k = 0.2                  # default mu_s
    k_t = 0.0                   # 0 rigid Coulomb contact (default), > 0 a Jenkins element
    law = "coulomb"             # coulomb (default) or stribeck (a rigid contact, scheme located)
    v_s = 0.01                  # Stribeck velocity, m/s (> 0; default 0.01)
    delta = 1.0                 # Stribeck exponent (>= 1 with stribeck; default 1)

    [run]                       # optional
    h = 0.0                     # internal step (0: derived)
    scheme = "located"          # located, consistent or paper
    alpha = -0.1                # Bossak parameter
    x0 = 0.0                    # initial positions (n values, a file or one number)
    v0 = 0.0

An unknown table or key is an error naming it and its table; a missing file names the file; every
value is then checked as :class:`~dryfriction.system.structure.System` checks it. Errors are :class:`~dryfriction.errors.UsageError`.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import UsageError
from .structure import Contact, System

__all__ = ["load", "loads", "read_array", "TABLES"]

#: every table and its keys
TABLES: dict[str, tuple[str, ...]] = {
    "structure": ("M", "K", "C"),
    "damping": ("rayleigh", "modal"),
    "excitation": ("omega", "F_c", "F_s", "dof", "amplitude", "phase"),
    "contact": ("dof", "between", "w", "N", "mu_s", "mu_k", "k_t", "law", "v_s", "delta"),
    "run": ("h", "scheme", "alpha", "x0", "v0"),
}
#: the file formats of a matrix or a vector given by name
FORMATS = (".npy", ".csv", ".mtx")


def read_array(path: Path, where: str) -> np.ndarray:
    """The array in a .npy, .csv or .mtx file (a MatrixMarket file as a dense matrix, its symmetric
    storage expanded); UsageError naming ``where`` and the file when it is missing or unreadable."""
    if not path.is_file():
        raise UsageError(f"{where}: the file {str(path)!r} does not exist")
    suffix = path.suffix.lower()
    try:
        if suffix == ".npy":
            return np.asarray(np.load(path, allow_pickle=False), dtype=np.float64)
        if suffix == ".csv":
            return np.loadtxt(path, delimiter=",", dtype=np.float64, ndmin=1)
        if suffix == ".mtx":
            from scipy.io import mmread

            a = mmread(str(path))
            a = a.toarray() if hasattr(a, "toarray") else np.asarray(a)
            return np.asarray(a, dtype=np.float64)
    except (OSError, ValueError, TypeError) as e:
        raise UsageError(f"{where}: the file {str(path)!r} cannot be read as {suffix}: {e}") from None
    raise UsageError(f"{where}: the file {str(path)!r} has the suffix {suffix or '(none)'!r}; valid: "
                     f"{', '.join(FORMATS)}")


def _array(value: Any, where: str, base: Path, matrix: bool) -> Any:
    """An inline value as it is (the System checks it), a file name as its array."""
    if isinstance(value, str):
        a = read_array(base / value, where)
        if matrix and a.ndim == 1 and a.size == 1:
            a = a.reshape(1, 1)
        if not matrix and a.ndim == 2 and 1 in a.shape:
            a = a.ravel()
        return a
    return value


def _check_keys(table: dict[str, Any], name: str) -> None:
    for key in table:
        if key not in TABLES[name]:
            raise UsageError(f"unknown key {key!r} in the table [{name}]; valid keys: {', '.join(TABLES[name])}")


def loads(text: str, base: Path | str = ".", where: str = "the structure file") -> System:
    """The System a TOML text describes (see the module docstring); file names relative to ``base``."""
    base = Path(base)
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise UsageError(f"{where} is not valid TOML: {e}") from None
    for key, value in doc.items():
        if key not in TABLES:
            raise UsageError(f"unknown table [{key}] in {where}; valid tables: {', '.join(TABLES)}")
        if key == "contact":
            if not isinstance(value, list):
                raise UsageError(f"contact in {where} must be an array of tables, [[contact]]")
        elif not isinstance(value, dict):
            raise UsageError(f"{key} in {where} must be a table, [{key}]")
    structure = doc.get("structure")
    if structure is None:
        raise UsageError(f"{where} has no [structure] table (it needs M and K)")
    _check_keys(structure, "structure")
    for key in ("M", "K"):
        if key not in structure:
            raise UsageError(f"the table [structure] has no {key}: M and K are required")
    mats = {key: _array(structure[key], f"[structure] {key}", base, True) for key in structure}
    damping = doc.get("damping", {})
    _check_keys(damping, "damping")
    if len(damping) > 1:
        raise UsageError("the table [damping] has both rayleigh and modal: give one")
    if damping and "C" in mats:
        raise UsageError("the damping is given twice: C in [structure] and the table [damping]; give one")
    exc = doc.get("excitation", {})
    _check_keys(exc, "excitation")
    run = doc.get("run", {})
    _check_keys(run, "run")
    contacts = []
    for j, table in enumerate(doc.get("contact", [])):
        if not isinstance(table, dict):
            raise UsageError(f"contact {j} in {where} must be a table")
        for key in table:
            if key not in TABLES["contact"]:
                raise UsageError(f"unknown key {key!r} in the table [[contact]] number {j} (0-based); valid keys: "
                                 f"{', '.join(TABLES['contact'])}")
        kw = dict(table)
        if "between" in kw:
            kw["between"] = tuple(kw["between"]) if isinstance(kw["between"], list) else kw["between"]
        try:
            contacts.append(Contact(**kw))
        except UsageError as e:
            raise UsageError(f"[[contact]] number {j} (0-based): {e}") from None
    vectors: dict[str, Any] = {}
    for key in ("F_c", "F_s"):
        if key in exc:
            vectors[key] = _array(exc[key], f"[excitation] {key}", base, False)
    one = [key for key in ("dof", "amplitude", "phase") if key in exc]
    if one:
        if vectors:
            raise UsageError("the table [excitation] has F_c or F_s and a single force (dof, amplitude): give one")
        if "dof" not in exc or "amplitude" not in exc:
            raise UsageError("the table [excitation] gives a single force by dof and amplitude: both are needed")
        n = np.shape(np.atleast_2d(mats["M"]))[0]
        dof, amp, phase = exc["dof"], exc["amplitude"], exc.get("phase", 0.0)
        if isinstance(dof, bool) or not isinstance(dof, int) or not 0 <= dof < n:
            raise UsageError(f"[excitation] dof = {dof!r} is out of range; valid: 0 to {n - 1}")
        for name, v in (("amplitude", amp), ("phase", phase)):
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise UsageError(f"[excitation] {name} = {v!r} must be a finite number")
        F_c, F_s = np.zeros(n), np.zeros(n)
        F_c[dof], F_s[dof] = amp * math.cos(phase), -amp * math.sin(phase)
        vectors.update(F_c=F_c, F_s=F_s)
    for key in ("x0", "v0"):
        if key in run:
            vectors[key] = _array(run[key], f"[run] {key}", base, False)
    settings = {key: run[key] for key in ("h", "scheme", "alpha") if key in run}
    system = System(M=mats["M"], K=mats["K"], C=mats.get("C"), contacts=contacts, omega=exc.get("omega", 0.0),
                    **vectors, **settings)
    if "rayleigh" in damping:
        r = damping["rayleigh"]
        if not isinstance(r, list) or len(r) != 2:
            raise UsageError(f"[damping] rayleigh = {r!r} must be two numbers [alpha_M, beta_K]")
        system = system.with_rayleigh(*r)
    elif "modal" in damping:
        system = system.with_modal_damping(damping["modal"])
    return system


def load(path: Path | str) -> System:
    """The System the TOML structure file ``path`` describes (see the module docstring)."""
    p = Path(path)
    if not p.is_file():
        raise UsageError(f"the structure file {str(p)!r} does not exist")
    return loads(p.read_text(encoding="utf-8"), base=p.parent, where=f"the structure file {str(p)!r}")
