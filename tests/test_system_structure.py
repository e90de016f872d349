"""The structure (dryfriction.System, dryfriction.Contact): every check at construction names the
array and the element or the test that failed; the structure file in every format gives the same
System; the oscillator and the chain as systems; Rayleigh and modal damping (the modal damping
ratios asked are the ones Phi' C Phi has); the FMU's start values."""

from __future__ import annotations

import copy
import math
import pickle
from pathlib import Path

import numpy as np
import pytest
import scipy.io
import scipy.sparse

import dryfriction
from dryfriction import Contact, System, UsageError
from dryfriction.params import Oscillator
from dryfriction.references.chain import Chain
from dryfriction.system import spec

M3 = np.array([[2.0, 0.5, 0.0], [0.5, 1.0, 0.2], [0.0, 0.2, 1.5]])
K3 = np.array([[300.0, -100.0, 0.0], [-100.0, 250.0, -150.0], [0.0, -150.0, 150.0]])
C3 = np.array([[0.3, -0.1, 0.0], [-0.1, 0.4, -0.2], [0.0, -0.2, 0.2]])
CONTACTS = (Contact(dof=0, N=2.0, mu_s=0.4, mu_k=0.3),
            Contact(between=(2, 1), N=1.0, mu_s=0.2, mu_k=0.25, k_t=500.0),
            Contact(w=[0.5, 0.0, -0.5], N=0.5, mu_s=0.3))


def _system(**kw: object) -> System:
    args: dict[str, object] = dict(M=M3, K=K3, C=C3, contacts=CONTACTS, F_c=[1.0, 0.0, 0.5], F_s=[0.0, 0.2, 0.0],
                                   omega=7.0, x0=[0.01, 0.0, -0.02], v0=[0.0, 0.1, 0.0], h=1e-3, scheme="consistent")
    args.update(kw)
    return System(**args)  # type: ignore[arg-type]


def test_the_top_level_names_are_the_structure() -> None:
    assert dryfriction.System is System and dryfriction.Contact is Contact
    assert System.__module__ == "dryfriction.system.structure"


def test_the_fields_rows_and_contact_arrays() -> None:
    s = _system()
    assert (s.n, s.nc) == (3, 3)
    np.testing.assert_array_equal(s.W, [[1, 0, 0], [0, -1, 1], [0.5, 0, -0.5]])
    np.testing.assert_array_equal(s.N, [2.0, 1.0, 0.5])
    np.testing.assert_array_equal(s.mu_s, [0.4, 0.2, 0.3])
    np.testing.assert_array_equal(s.mu_k, [0.3, 0.25, 0.3])       # mu_k defaults to mu_s
    np.testing.assert_array_equal(s.k_t, [0.0, 500.0, 0.0])
    np.testing.assert_allclose(s.breakaway, [0.8, 0.25, 0.15], rtol=1e-15)
    for a in (s.M, s.C, s.K, s.W, s.F_c, s.x0):
        assert a.dtype == np.float64 and not a.flags.writeable
    with pytest.raises(ValueError):
        s.M[0, 0] = 3.0
    with pytest.raises(AttributeError, match="frozen"):
        s.omega = 3.0  # type: ignore[misc]
    assert _system() == s and s.replace(omega=6.0) != s
    # a copy with another frequency or step equals the system built with it, and is checked as it is
    for kw in (dict(omega=6.0), dict(h=2e-3), dict(omega=0.5, h=0.0)):
        r = s.replace(**kw)
        assert type(r) is System and r == _system(**kw) and r.omega == kw.get("omega", 7.0)
        assert r.M is s.M and s == _system()   # (the checked arrays shared, the original unchanged)
    for kw, message in ((dict(omega=-1.0), r"omega is -1.0; valid range: >= 0"), (dict(h=math.nan), r"h is nan"),
                        (dict(omega="fast"), r"omega")):
        with pytest.raises(UsageError, match=message):
            s.replace(**kw)
    assert pickle.loads(pickle.dumps(s)) == s and copy.deepcopy(s) == s
    assert np.array_equal(System(M=M3, K=K3, F_c=2.0).F_c, [2.0, 2.0, 2.0])   # a scalar for every DOF
    assert np.array_equal(System(M=M3, K=K3).C, np.zeros((3, 3)))


@pytest.mark.parametrize("kw, message", [
    (dict(K=np.eye(2)), r"K is 2 x 2 but M is 3 x 3: the sizes disagree"),
    (dict(C=np.ones((3, 2))), r"C has the shape \(3, 2\); it must be a square matrix"),
    (dict(M=np.ones(3)), r"M has the shape \(3,\); it must be a square matrix"),
    (dict(F_c=[1.0, 2.0]), r"F_c has 2 values .* n = 3 degrees of freedom: the sizes disagree"),
    (dict(x0=[0.0] * 4), r"x0 has 4 values"),
    (dict(v0=np.zeros((3, 1))), r"v0 has 3 values in the shape \(3, 1\)"),
    (dict(K=np.where(np.arange(9).reshape(3, 3) == 5, np.nan, K3)), r"K\[1, 2\] is nan; every value must be finite"),
    (dict(M=np.where(np.eye(3) > 0, [[np.inf]], M3)), r"M\[0, 0\] is inf"),
    (dict(F_s=[0.0, -np.inf, 0.0]), r"F_s\[1\] is -inf"),
    (dict(omega=math.nan), r"omega is nan"),
    (dict(M=M3 + np.diag([0.0, 1e-3], 1)),
     r"M is not symmetric: M\[1, 2\] = 0.201 but M\[2, 1\] = 0.2 \(difference 0.001 beyond the tolerance 2e-12"),
    (dict(M=np.diag([1.0, 0.0, 1.0])), r"M is not positive definite: its Cholesky factorisation fails"),
    (dict(M=np.diag([1.0, -1.0, 1.0])), r"M is not positive definite.*smallest eigenvalue -1"),
    (dict(K=K3 + np.diag([1.0, 1.0], -1)), r"K is not symmetric: K\[0, 1\] = -100.0 but K\[1, 0\] = -99.0"),
    (dict(K=np.diag([1.0, -2.0, 3.0])), r"K has the negative eigenvalue -2 \(beyond rounding: below -[0-9.e-]+\)"),
    (dict(C=np.diag([0.1, 0.1, -1e-3])), r"C has the negative eigenvalue -0.001"),
    (dict(contacts=[Contact(dof=3, N=1.0)]), r"contacts\[0\]: dof = 3 is out of range; valid: 0 to 2"),
    (dict(contacts=[CONTACTS[0], Contact(between=(1, 7))]), r"contacts\[1\]: between = \(1, 7\) has the index 7, out"),
    (dict(contacts=[Contact(w=[1.0, 2.0])]), r"contacts\[0\]: w has 2 values but the structure has n = 3"),
    (dict(scheme="exact"), r"scheme = 'exact' is not a scheme; valid: paper, consistent, located"),
    (dict(h=-1e-3), r"h is -0.001; valid range: >= 0"),
    (dict(alpha=-0.5), r"alpha = -0.5 is out of range; valid: -1/3 to 0"),
    (dict(contacts=[1]), r"contacts\[0\] must be a Contact, not int"),
])
def test_a_bad_structure_names_the_array_and_element(kw: dict, message: str) -> None:
    with pytest.raises(UsageError, match=message):
        _system(**kw)


def test_rounding_is_not_an_error() -> None:
    """Asymmetry and negative eigenvalues at rounding level are accepted (a singular K too)."""
    Kr = np.array([[1.0, -1.0], [-1.0, 1.0]]) * 1e4          # a rigid-body mode: eigenvalue 0
    Kr[0, 1] *= 1 + 1e-15
    s = System(M=np.eye(2), K=Kr, contacts=[Contact(dof=0, N=1.0, mu_s=0.3)])
    assert s.n == 2


@pytest.mark.parametrize("kw, message", [
    (dict(), r"give exactly one of dof=i, between=\(i, j\) or w=\[...\] for its direction, not none"),
    (dict(dof=1, between=(1, 2)), r"not dof, between"),
    (dict(between=(2, 2)), r"between = \(2, 2\) names one degree of freedom twice"),
    (dict(between=(1, 2, 3)), r"must be two indices"),
    (dict(dof=-1), r"dof = -1 is negative"),
    (dict(dof=1.5), r"dof must be an integer"),
    (dict(w=[0.0, 0.0]), r"w is a zero row: the contact has no direction"),
    (dict(w=[1.0, np.nan]), r"w\[1\] is nan"),
    (dict(dof=0, N=-1.0), r"Contact: N is -1.0; valid range: >= 0"),
    (dict(dof=0, mu_s=-0.1), r"Contact: mu_s is -0.1"),
    (dict(dof=0, mu_s=0.2, mu_k=-0.1), r"Contact: mu_k is -0.1"),
    (dict(dof=0, k_t=-5.0), r"Contact: k_t is -5.0"),
    (dict(dof=0, N="1"), r"Contact: N must be a real number, not str"),
    (dict(dof=0, law="dahl"), r"law = 'dahl' is not offered; valid: coulomb, stribeck"),
    (dict(dof=0, law="stribeck", delta=0.9), r"law = stribeck supports delta >= 1 only, not 0.9"),
])
def test_a_bad_contact_names_the_field(kw: dict, message: str) -> None:
    with pytest.raises(UsageError, match=message):
        Contact(**kw)


# ---- damping ---------------------------------------------------------------------------------------

def test_rayleigh_damping() -> None:
    s = System(M=M3, K=K3).with_rayleigh(0.2, 1e-3)
    np.testing.assert_array_equal(s.C, 0.2 * M3 + 1e-3 * K3)
    with pytest.raises(UsageError, match="beta_K is -1.0"):
        s.with_rayleigh(0.1, -1.0)


@pytest.mark.parametrize("zeta", [0.03, [0.01, 0.05, 0.2]])
def test_modal_damping_gives_the_ratios_asked(zeta: object) -> None:
    s = System(M=M3, K=K3).with_modal_damping(zeta)  # type: ignore[arg-type]
    w, phi = s.modes()
    np.testing.assert_allclose(phi.T @ M3 @ phi, np.eye(3), atol=1e-14)
    np.testing.assert_allclose(phi.T @ K3 @ phi, np.diag(w ** 2), atol=1e-11 * w.max() ** 2)
    # the undamped frequencies independently: the roots of det(K - w^2 M)
    lam = np.sort(np.linalg.eigvals(np.linalg.solve(M3, K3)).real)
    np.testing.assert_allclose(w, np.sqrt(lam), rtol=1e-13)
    modal = phi.T @ s.C @ phi
    z = np.broadcast_to(np.asarray(zeta, dtype=float), (3,))
    np.testing.assert_allclose(np.diag(modal) / (2.0 * w), z, rtol=1e-12)
    np.testing.assert_allclose(modal - np.diag(np.diag(modal)), 0.0, atol=1e-14 * np.abs(modal).max())


def test_modal_damping_leaves_a_rigid_body_mode_undamped() -> None:
    K = np.array([[1.0, -1.0], [-1.0, 1.0]]) * 100.0
    s = System(M=np.diag([1.0, 2.0]), K=K).with_modal_damping(0.1)
    np.testing.assert_allclose(s.C @ np.ones(2), 0.0, atol=1e-13)           # the rigid motion: no force
    w, phi = s.modes()
    assert w[0] == 0.0 or w[0] < 1e-6
    assert (phi[:, 1] @ s.C @ phi[:, 1]) == pytest.approx(2 * 0.1 * math.sqrt(150.0), rel=1e-12)
    with pytest.raises(UsageError, match=r"zeta\[1\] is -0.1"):
        s.with_modal_damping([0.1, -0.1])


# ---- the other models as systems --------------------------------------------------------------------

def test_from_oscillator() -> None:
    osc = Oscillator(m=2.0, k=150.0, c=0.3, P0=1.5, omega=4.0, phi=0.7, N=2.0, mu_s=0.4, chi=0.6, x0=0.01, v0=-0.2)
    s = System.from_oscillator(osc, h=1e-3, scheme="paper")
    assert (s.n, s.nc, s.h, s.scheme, s.omega) == (1, 1, 1e-3, "paper", 4.0)
    assert (s.M[0, 0], s.K[0, 0], s.C[0, 0], s.x0[0], s.v0[0]) == (2.0, 150.0, 0.3, 0.01, -0.2)
    assert (s.W[0, 0], s.N[0], s.mu_s[0], s.k_t[0]) == (1.0, 2.0, 0.4, 0.0)
    assert s.mu_k[0] == pytest.approx(0.24, rel=1e-15)
    # P0 cos(omega t + phi) = F_c cos(omega t) + F_s sin(omega t) at several times
    for t in (0.0, 0.3, 1.7):
        assert s.excitation(t)[0] == pytest.approx(1.5 * math.cos(4.0 * t + 0.7), abs=1e-15)


def test_from_chain_is_the_chain_topology() -> None:
    """Springs and dampers on the left of each block (the first to the left wall), the last block
    to the right wall by k_end, site springs to the ground: written out for 3 blocks, and the chain
    reference's matrices for 5."""
    s = System.from_chain(m=[1.0, 2.0, 3.0], k=[10.0, 20.0, 30.0], c=[0.1, 0.2, 0.3], k_end=5.0, c_end=0.5,
                          k_site=[1.0, 0.0, 2.0], c_site=0.01, P0=[1.0, 0.0, 2.0], phi=[0.0, 0.0, 0.5],
                          N=[1.0, 0.5, 0.2], mu_s=0.4, chi=[0.7, 0.5, 1.5], omega=3.0)
    np.testing.assert_array_equal(s.M, np.diag([1.0, 2.0, 3.0]))
    np.testing.assert_array_equal(s.K, [[10 + 20 + 1, -20, 0], [-20, 20 + 30, -30], [0, -30, 30 + 5 + 2]])
    np.testing.assert_allclose(s.C, [[0.31, -0.2, 0], [-0.2, 0.51, -0.3], [0, -0.3, 0.81]], rtol=1e-15)
    np.testing.assert_array_equal(s.W, np.eye(3))
    np.testing.assert_allclose(s.mu_k, [0.28, 0.2, 0.6], rtol=1e-15)
    np.testing.assert_allclose(s.F_c, [1.0, 0.0, 2.0 * math.cos(0.5)], rtol=1e-15)
    np.testing.assert_allclose(s.F_s, [0.0, 0.0, -2.0 * math.sin(0.5)], rtol=1e-15)
    ch = Chain.make(5, k=[1.0, 2.0, 3.0, 4.0, 5.0], c=[0.1, 0.0, 0.3, 0.0, 0.5], k_end=2.0, c_end=0.1)
    s5 = System.from_chain(k=ch.k, c=ch.c, k_end=2.0, c_end=0.1, m=ch.m)
    K, C = ch.matrices()
    np.testing.assert_array_equal(s5.K, K)
    np.testing.assert_array_equal(s5.C, C)
    assert System.from_chain(4).n == 4
    with pytest.raises(UsageError, match=r"different lengths \[2, 3\]"):
        System.from_chain(m=[1.0, 1.0], k=[1.0, 1.0, 1.0])
    with pytest.raises(UsageError, match=r"m\[1\] is 0.0; valid range: > 0"):
        System.from_chain(m=[1.0, 0.0])


def test_start_values_are_the_fmu_contract() -> None:
    s = _system()
    sv = s.start_values()
    assert set(sv) == {"n", "nc", "M", "C", "K", "F_c", "F_s", "x0", "v0", "W", "N", "mu_s", "mu_k", "k_t", "omega",
                       "h", "alpha", "scheme", "friction_law", "v_s", "delta"}
    assert sv["friction_law"] == [1, 1, 1] and sv["v_s"] == [0.01] * 3 and sv["delta"] == [1.0] * 3
    assert (sv["n"], sv["nc"], sv["scheme"], sv["h"], sv["alpha"]) == (3, 3, 2, 1e-3, -0.1)
    assert sv["M"] == M3.ravel().tolist() and sv["K"][1] == -100.0 and len(sv["C"]) == 9
    assert sv["W"] == [1.0, 0.0, 0.0, 0.0, -1.0, 1.0, 0.5, 0.0, -0.5]          # row-major, nc x n
    assert sv["k_t"] == [0.0, 500.0, 0.0] and sv["mu_k"] == [0.3, 0.25, 0.3]
    assert all(type(v) is float for v in sv["M"] + sv["W"] + sv["x0"])
    assert System(M=M3, K=K3).start_values()["W"] == []
    assert {name: System(M=M3, K=K3, scheme=name).start_values()["scheme"] for name in ("paper", "consistent",
            "located")} == {"paper": 1, "consistent": 2, "located": 3}


# ---- the structure file --------------------------------------------------------------------------

TOML_TAIL = """
[excitation]
omega = 7.0
F_c = {F_c}
F_s = [0.0, 0.2, 0.0]

[[contact]]
dof = 0
N = 2.0
mu_s = 0.4
mu_k = 0.3

[[contact]]
between = [2, 1]
N = 1.0
mu_s = 0.2
mu_k = 0.25
k_t = 500.0

[[contact]]
w = [0.5, 0.0, -0.5]
N = 0.5
mu_s = 0.3

[run]
h = 1e-3
scheme = "consistent"
x0 = {x0}
v0 = [0.0, 0.1, 0.0]
"""


def _write_matrices(d: Path, fmt: str) -> dict[str, str]:
    names = {}
    for name, a in (("M", M3), ("K", K3), ("C", C3)):
        f = d / f"{name}.{fmt}"
        if fmt == "npy":
            np.save(f, a)
        elif fmt == "csv":
            np.savetxt(f, a, delimiter=",", fmt="%.17g")
        else:                                                # MatrixMarket: sparse, symmetric storage
            scipy.io.mmwrite(str(f), scipy.sparse.coo_matrix(a), symmetry="symmetric", precision=17)
        names[name] = f'"{f.name}"'
    return names


def _inline(a: np.ndarray) -> str:
    return "[" + ", ".join("[" + ", ".join(repr(float(v)) for v in row) + "]" for row in a) + "]"


@pytest.mark.parametrize("fmt", ["inline", "npy", "csv", "mtx"])
def test_a_structure_file_in_every_format_gives_the_same_system(tmp_path: Path, fmt: str) -> None:
    if fmt == "inline":
        names = {"M": _inline(M3), "K": _inline(K3), "C": _inline(C3)}
        F_c, x0 = "[1.0, 0.0, 0.5]", "[0.01, 0.0, -0.02]"
    else:
        names = _write_matrices(tmp_path, fmt)
        if fmt == "mtx":
            assert "symmetric" in (tmp_path / "M.mtx").read_text().splitlines()[0]
        vec = tmp_path / f"F_c.{'csv' if fmt == 'mtx' else fmt}"
        if vec.suffix == ".npy":
            np.save(vec, np.array([1.0, 0.0, 0.5]))
        else:
            np.savetxt(vec, [1.0, 0.0, 0.5], delimiter=",")
        F_c, x0 = f'"{vec.name}"', "[0.01, 0.0, -0.02]"
    text = "[structure]\n" + "".join(f"{k} = {v}\n" for k, v in names.items()) + TOML_TAIL.format(F_c=F_c, x0=x0)
    path = tmp_path / "beam.toml"
    path.write_text(text)
    assert System.from_file(path) == _system()
    assert spec.load(str(path)) == _system()


def test_a_structure_file_with_damping_and_a_single_force(tmp_path: Path) -> None:
    (tmp_path / "s.toml").write_text(f"""
[structure]
M = {_inline(M3)}
K = {_inline(K3)}
[damping]
modal = [0.01, 0.02, 0.03]
[excitation]
omega = 2.0
dof = 2
amplitude = 3.0
phase = 0.5
[run]
x0 = 0.001
""")
    s = System.from_file(tmp_path / "s.toml")
    assert s == System(M=M3, K=K3, omega=2.0, F_c=[0, 0, 3 * math.cos(0.5)], F_s=[0, 0, -3 * math.sin(0.5)],
                       x0=0.001).with_modal_damping([0.01, 0.02, 0.03])
    (tmp_path / "r.toml").write_text(f"[structure]\nM = {_inline(M3)}\nK = {_inline(K3)}\n"
                                     "[damping]\nrayleigh = [0.5, 0.002]\n")
    np.testing.assert_array_equal(System.from_file(tmp_path / "r.toml").C, 0.5 * M3 + 0.002 * K3)


@pytest.mark.parametrize("text, message", [
    ("[structure]\nM = [[1.0]]\nK = [[1.0]]\nL = 2\n",
     r"unknown key 'L' in the table \[structure\]; valid keys: M, K, C"),
    ("[structure]\nM = [[1.0]]\nK = [[1.0]]\n[excite]\nomega = 1\n", r"unknown table \[excite\]"),
    ("[structure]\nM = [[1.0]]\nK = [[1.0]]\n[run]\nsteps = 3\n", r"unknown key 'steps' in the table \[run\]"),
    ("[structure]\nM = [[1.0]]\nK = [[1.0]]\n[[contact]]\ndof = 0\nmu = 0.3\n",
     r"unknown key 'mu' in the table \[\[contact\]\] number 0"),
    ("[structure]\nM = [[1.0]]\nK = [[1.0]]\n[[contact]]\ndof = 1\nN = 1.0\n",
     r"contacts\[0\]: dof = 1 is out of range"),
    ("[structure]\nM = [[1.0]]\nK = [[1.0]]\n[[contact]]\nbetween = [0, 0]\n",
     r"\[\[contact\]\] number 0 \(0-based\): Contact: between = \(0, 0\) names one degree of freedom twice"),
    ("[structure]\nM = [[1.0]]\n", r"the table \[structure\] has no K"),
    ("[run]\nh = 1.0\n", r"has no \[structure\] table"),
    ("[structure]\nM = \"missing.npy\"\nK = [[1.0]]\n", r"\[structure\] M: the file '.*missing.npy' does not exist"),
    ("[structure]\nM = \"M.txt\"\nK = [[1.0]]\n", r"the file '.*M.txt' does not exist"),
    ("[structure]\nM = [[1.0]]\nK = [[1.0]]\nC = [[0.1]]\n[damping]\nmodal = 0.1\n", r"the damping is given twice"),
    ("[structure]\nM = [[1.0]]\nK = [[1.0]]\n[excitation]\ndof = 3\namplitude = 1.0\n",
     r"\[excitation\] dof = 3 is out of range; valid: 0 to 0"),
    ("[structure]\nM = [[1.0]]\nK = [[-1.0]]\n", r"K has the negative eigenvalue -1"),
    ("[structure\n", r"is not valid TOML"),
])
def test_a_bad_structure_file_names_the_key_or_file(tmp_path: Path, text: str, message: str) -> None:
    (tmp_path / "s.toml").write_text(text)
    with pytest.raises(UsageError, match=message):
        System.from_file(tmp_path / "s.toml")


def test_a_missing_structure_file_and_an_unknown_format(tmp_path: Path) -> None:
    with pytest.raises(UsageError, match=r"the structure file '.*nope.toml' does not exist"):
        System.from_file(tmp_path / "nope.toml")
    (tmp_path / "M.txt").write_text("1.0\n")
    (tmp_path / "s.toml").write_text("[structure]\nM = \"M.txt\"\nK = [[1.0]]\n")
    with pytest.raises(UsageError, match=r"has the suffix '.txt'; valid: .npy, .csv, .mtx"):
        System.from_file(tmp_path / "s.toml")
