"""Periodic orbits of structures (dryfriction.analysis.system_orbits) on the located map with the FMU's
Jacobian: the Jacobian against central differences of the same map, an orbit run on for 20 periods by
a separate FMU, the frictionless structure against its harmonic closed form, one DOF against the
oscillator's exact orbit, the amplitude's second order in h, and the refusals."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

import dryfriction as dfo
from dryfriction import Contact, Oscillator, System
from dryfriction.analysis.system_orbits import SystemOrbit, find_system_orbits, system_map
from dryfriction.drivers.system import SystemFMU3

#: the orbit solves run the FMU hundreds of times: outside the ASan/UBSan pass (the map's Jacobian, its
#: C side, runs under the sanitizers in test_the_maps_jacobian_equals_central_differences and ctest)
loops = pytest.mark.no_sanitizer

M2 = np.diag([1.0, 0.5])
K2 = np.array([[3.0, -1.0], [-1.0, 1.0]])
C2 = 0.02 * K2 + 0.02 * M2


def two_mass(omega: float, N: float = 0.6, mu_s: float = 0.5, mu_k: float = 0.5, h: float = 0.0) -> System:
    """The two-mass structure with a Jenkins element between the masses (the harmonic-balance tools' case)."""
    return System(M=M2, K=K2, C=C2, F_c=[1.0, 0.0], omega=omega, h=h,
                  contacts=[Contact(between=(0, 1), N=N, mu_s=mu_s, mu_k=mu_k, k_t=20.0)])


def three_dofs() -> System:
    """Three DOFs: a rigid contact on the ground, a rigid one between DOFs 2 and 3, a Jenkins one on 3."""
    M = np.array([[1.0, 0.1, 0.0], [0.1, 0.8, 0.0], [0.0, 0.0, 1.2]])
    K = np.array([[2.0, -1.0, 0.0], [-1.0, 2.5, -1.0], [0.0, -1.0, 1.5]])
    return System(M=M, K=K, C=0.03 * K, F_c=[0.8, 0.0, -0.5], omega=1.1,
                  contacts=[Contact(dof=0, N=0.4, mu_s=0.5, mu_k=0.4),
                            Contact(between=(1, 2), N=0.3, mu_s=0.4, mu_k=0.4),
                            Contact(dof=2, N=0.5, mu_s=0.3, mu_k=0.2, k_t=15.0)])


def dependent_contacts() -> System:
    """Two DOFs with rigid contacts whose rows are dependent: one to the ground on each DOF and two
    parallel ones between the DOFs (docs/system.md, "Dependent contacts")."""
    return System(M=M2, K=K2, C=C2, F_c=[1.0, 0.0], omega=1.2,
                  contacts=[Contact(dof=0, N=0.5, mu_s=0.3, mu_k=0.2), Contact(dof=1, N=0.3, mu_s=0.3, mu_k=0.25),
                            Contact(between=(0, 1), N=0.2, mu_s=0.3, mu_k=0.2),
                            Contact(between=(0, 1), N=0.4, mu_s=0.5, mu_k=0.2)])


@pytest.mark.parametrize("case", ["two_mass", "three_dofs", "dependent"])
def test_the_maps_jacobian_equals_central_differences(case: str) -> None:
    """The FMU's Jacobian of the located map over a period, through its switches, against central
    differences of the same map (step 1e-6): within 1e-6 of its scale, and so are the multipliers."""
    system = {"two_mass": lambda: two_mass(1.4), "three_dofs": three_dofs, "dependent": dependent_contacts}[case]()
    n = system.n
    jenk = np.flatnonzero(system.k_t > 0)
    z = np.concatenate([[0.8, 0.4, -0.3][:n], [-0.3, 0.6, 0.2][:n], np.zeros(jenk.size)])
    z[2 * n:] = system.W[jenk] @ z[:n] - 0.005  # (each spring loaded within its limit)
    Pz, J = system_map(system, z)
    fd = np.zeros_like(J)
    for k in range(z.size):
        d = 1e-6 * max(1.0, abs(z[k]))
        zp, zm = z.copy(), z.copy()
        zp[k] += d
        zm[k] -= d
        fd[:, k] = (system_map(system, zp)[0] - system_map(system, zm)[0]) / (2 * d)
    scale = max(1.0, float(np.abs(J).max()))
    assert np.abs(J - fd).max() <= 1e-6 * scale, (J, fd)
    mu, mu_fd = np.sort_complex(np.linalg.eigvals(J)), np.sort_complex(np.linalg.eigvals(fd))
    assert np.abs(mu - mu_fd).max() <= 1e-6
    # the map moved the state through stick-slip (not a linear stretch): its Jacobian is not the
    # frictionless one
    free = system_map(system.replace(contacts=[dataclasses.replace(c, N=0.0) for c in system.contacts]), z)[1]
    assert np.abs(J - free).max() > 1e-2


@loops
def test_an_orbit_returns_to_itself_for_20_periods_in_another_fmu() -> None:
    """The orbit shooting finds, run on for 20 periods from its state at t = 0 by a separate FMU, comes
    back to that state at every period within the Newton tolerance (scaled by its amplitude)."""
    system = two_mass(1.8)
    (orbit,) = find_system_orbits(system, estimate_error=False)
    assert orbit.converged and orbit.residual <= 1e-10 and orbit.stable
    T = 2 * np.pi / system.omega
    w = system.W[0]
    f0 = -20.0 * (w @ orbit.x0 - orbit.s0[0])
    with SystemFMU3(system.replace(h=orbit.h)) as fmu:
        fmu.start(0.0, x0=orbit.x0, v0=orbit.v0, f0=[f0])
        run = fmu.record_at(np.arange(21) * T)
    scale = float(orbit.amplitude.max())
    assert np.abs(run.x - orbit.x0).max() <= 1e-8 * scale
    assert np.abs(run.v - orbit.v0).max() <= 1e-8 * scale * system.omega
    assert np.abs(run.s[:, 0] - orbit.s0[0]).max() <= 1e-8 * scale
    # the orbit slides and sticks: a friction orbit, not a linear one
    assert 0.05 < orbit.stick_fraction[0] < 0.95


@loops
def test_frictionless_response_equals_the_harmonic_closed_form() -> None:
    """Without friction the orbit's amplitude is the linear closed form |(K - w^2 M + i w C)^-1 F| within
    the scheme's error: second order (Richardson's estimate within 3x of the true error)."""
    omega = 1.3
    system = System(M=M2, K=K2, C=C2, F_c=[1.0, 0.0], omega=omega)
    X = np.abs(np.linalg.solve(K2 - omega**2 * M2 + 1j * omega * C2, [1.0, 0.0]))
    (orbit,) = find_system_orbits(system)
    err = np.abs(orbit.amplitude - X).max()
    assert err <= 2e-6 * X.max()
    assert 0.3 * orbit.error <= err <= 3.0 * orbit.error
    assert np.abs(orbit.amplitude_extrapolated - X).max() <= 0.2 * err
    # the multipliers: the damped linear map's, exp(eigenvalue T), within the scheme's error
    T = 2 * np.pi / omega
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-np.linalg.solve(M2, K2), -np.linalg.solve(M2, C2)]])
    exact = np.sort(np.abs(np.exp(np.linalg.eigvals(A) * T)))
    assert np.allclose(np.sort(np.abs(orbit.multipliers)), exact, rtol=1e-4, atol=0)


@loops
def test_one_dof_is_the_oscillators_orbit() -> None:
    """n = 1 with one rigid contact: the located map's orbit is the oscillator's exact one within the
    scheme's error (amplitude 1e-6, multiplier 1e-4 relative), whose estimate is honest."""
    p = Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.6, chi=0.4)
    exact = dfo.find_orbits(p)[0]
    (orbit,) = dfo.find_orbits(System.from_oscillator(p))  # (the package's one entry point)
    assert isinstance(orbit, SystemOrbit)
    assert abs(orbit.amplitude[0] - exact.amplitude) <= 1e-6 * exact.amplitude
    assert abs(orbit.amplitude[0] - exact.amplitude) <= 5.0 * orbit.error
    mu = exact.multipliers[np.argmax(np.abs(exact.multipliers))]
    assert abs(orbit.multipliers[0] - mu) <= 1e-4 * abs(mu)
    assert orbit["x0"] is orbit.x0 and exact["x0"] == exact.x0


@loops
def test_the_amplitude_converges_at_second_order_in_h() -> None:
    """The orbit's amplitude against the oscillator's exact one at h, h/2, h/4: error ratios near 4."""
    p = Oscillator.from_nondimensional(lam=1.2, mu_s_sigma=0.5, chi=0.6)
    exact = max(o.amplitude for o in dfo.find_orbits(p))
    T = 2 * np.pi / p.omega
    errs = []
    for h in (T / 200, T / 400, T / 800):
        (o,) = find_system_orbits(System.from_oscillator(p, h=h), estimate_error=False)
        errs.append(abs(o.amplitude[0] - exact))
    ratios = [errs[0] / errs[1], errs[1] / errs[2]]
    assert all(3.0 < r < 5.5 for r in ratios), (errs, ratios)


@loops
def test_orbits_refuse_what_the_map_does_not_cover() -> None:
    """A scheme other than located, a Stribeck contact, period < 1, omega 0: one sentence each."""
    base = two_mass(1.4)
    with pytest.raises(ValueError, match="located"):
        find_system_orbits(base.replace(scheme="consistent"))
    strib = System(M=[[1.0]], K=[[1.0]], F_c=[1.0], omega=0.5,
                   contacts=[Contact(dof=0, N=0.3, mu_s=0.5, mu_k=0.3, law="stribeck", v_s=0.1)])
    with pytest.raises(ValueError, match="Coulomb"):
        find_system_orbits(strib)
    with pytest.raises(ValueError, match="period"):
        find_system_orbits(base, period=0)
    with pytest.raises(ValueError, match="omega"):
        find_system_orbits(base.replace(omega=0.0))


@loops
def test_the_frequency_response_follows_the_orbits() -> None:
    """frequency_response(system, ...) (the package's one entry point): each frequency's orbit, followed
    from the previous one, is the orbit found cold there (amplitudes within 1e-6, both within the Newton tolerance); without friction the
    amplitudes are the harmonic closed form's within the scheme's error."""
    system = two_mass(1.0)
    f = np.array([0.16, 0.2, 0.3])
    ds = dfo.frequency_response(system, f, dof=1)
    assert bool(ds["converged"].all()) and ds.attrs["dof"] == 1
    for i, fi in enumerate(f):
        (cold,) = find_system_orbits(system.replace(omega=2 * np.pi * fi))
        assert np.allclose(ds["amplitude_m"].values[i], cold.amplitude, rtol=1e-6, atol=0)
        assert bool(ds["stable"].values[i]) == cold.stable
    assert np.array_equal(ds["amplitude_dof_m"].values, ds["amplitude_m"].values[:, 1])
    free = System(M=M2, K=K2, C=C2, F_c=[1.0, 0.0], omega=1.0)
    dsf = dfo.frequency_response(free, f)
    for i, fi in enumerate(f):
        w = 2 * np.pi * fi
        X = np.abs(np.linalg.solve(K2 - w**2 * M2 + 1j * w * C2, [1.0, 0.0]))
        assert np.abs(dsf["amplitude_m"].values[i] - X).max() <= 3.0 * dsf["error_m"].values[i] + 1e-12


@loops
def test_a_response_through_a_resonance_from_its_branch_is_the_cold_orbits() -> None:
    """Through the resonance at omega = 1 (mass 0 at 5.2, its slider stuck a sixty-fourth of the cycle,
    the stretch moving along the cycle from point to point): each point started from the branch's
    last orbits extrapolated (and its section found near the last one's) is the orbit found cold at
    its frequency: amplitudes within the two error estimates (at 100 steps a period the orbits of two
    sections differ by the scheme's error: their grids differ; measured 5e-5 relative), the same
    stability."""
    system = two_mass(1.0, h=2 * np.pi / 100)
    f = np.linspace(0.98, 1.0, 7) / (2 * np.pi)
    ds = dfo.frequency_response(system, f)
    assert bool(ds["converged"].all())
    for i, fi in enumerate(f):
        (cold,) = find_system_orbits(system.replace(omega=2 * np.pi * fi))
        bound = 2.0 * (float(ds["error_m"].values[i]) + cold.error)
        assert np.abs(ds["amplitude_m"].values[i] - cold.amplitude).max() <= bound, (i, cold.amplitude, bound)
        assert bool(ds["stable"].values[i]) == cold.stable


@loops
def test_the_command_line_writes_the_response_and_prints_orbits(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``dryfriction system response`` writes response.csv, .nc and .png (the CSV's numbers the table's),
    ``system orbits --json`` prints the orbit; a --dof beyond the structure is one readable line."""
    from dryfriction.cli import main

    spec = tmp_path / "s.toml"
    spec.write_text("[structure]\nM = [[1.0, 0.0], [0.0, 0.5]]\nK = [[3.0, -1.0], [-1.0, 1.0]]\n"
                    "[damping]\nrayleigh = [0.02, 0.02]\n[excitation]\nF_c = [1.0, 0.0]\nomega = 1.4\n"
                    "[[contact]]\nbetween = [0, 1]\nN = 0.6\nmu_s = 0.5\nmu_k = 0.5\nk_t = 20.0\n")
    out = tmp_path / "resp"
    assert main(["system", "response", str(spec), "--f-start", "0.2", "--f-stop", "0.3", "--num", "3",
                 "--out", str(out), "--no-progress"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["response.csv", "response.nc", "response.png"]
    rows = (out / "response.csv").read_text().splitlines()
    assert len(rows) == 4 and rows[0].startswith("f_hz,amplitude_m[0],amplitude_m[1]")
    (orbit,) = find_system_orbits(two_mass(2 * np.pi * 0.3))
    assert np.allclose([float(v) for v in rows[3].split(",")[1:3]], orbit.amplitude, rtol=1e-6, atol=0)
    capsys.readouterr()
    assert main(["system", "orbits", str(spec), "--json"]) == 0

    got = json.loads(capsys.readouterr().out)["orbits"]
    assert len(got) == 1 and got[0]["converged"] and got[0]["stable"]
    assert np.allclose(got[0]["amplitude"], find_system_orbits(two_mass(1.4))[0].amplitude, rtol=1e-12)
    assert main(["system", "response", str(spec), "--f-start", "0.2", "--f-stop", "0.3", "--dof", "5",
                 "--json"]) == 2
    assert "--dof 5" in capsys.readouterr().err


@loops
def test_the_continuation_engine_follows_a_structures_orbits() -> None:
    """continue_orbits(system, "omega", ...) (the project's continuation engine on the located map):
    the branch reaches the end of its range through the first resonance, each point converged, its
    amplitudes the cold solve's at that omega (within 1e-5: both within their tolerances), the peak
    within 1e-3 of the orbit at omega = 1; a neutral start (a slider stuck all cycle) is refused."""
    system = two_mass(0.9)
    c = dfo.continue_orbits(system, "omega", 0.9, 1.2)
    ds = c.dataset
    assert len(c.branches) == 1 and c.branches[0].stopped.startswith("reached the end of the range")
    assert bool(ds["converged"].all()) and ds.sizes["dof"] == 2 and ds.sizes["contact"] == 1
    assert ds["param"].values[0] == pytest.approx(0.9) and ds["param"].values[-1] == pytest.approx(1.2)
    for i in (1, ds.sizes["point"] // 2, ds.sizes["point"] - 2):
        (cold,) = find_system_orbits(system.replace(omega=float(ds["param"].values[i])), estimate_error=False)
        assert np.allclose(ds["amplitude_m"].values[i], cold.amplitude, rtol=1e-5, atol=0)
    k = int(np.argmax(ds["amplitude_m"].values[:, 0]))
    at_1 = find_system_orbits(system.replace(omega=1.0), estimate_error=False)[0].amplitude[0]
    assert abs(ds["param"].values[k] - 1.0) < 0.02 and ds["amplitude_m"].values[k, 0] >= at_1 * (1 - 1e-3)
    with pytest.raises(ValueError, match="neutral"):
        dfo.continue_orbits(two_mass(0.6), "omega", 0.6, 0.7)
    with pytest.raises(ValueError, match="valid: omega, N"):
        dfo.continue_orbits(system, "zeta", 0.9, 1.0)


@loops
def test_the_command_line_continues_a_structures_orbits(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``dryfriction system continuation``: continuation.nc, .csv, .png written; --json prints the
    branch that reached the end of its range, its points' parameters from --start to --stop."""
    from dryfriction.cli import main

    spec = tmp_path / "s.toml"
    spec.write_text("[structure]\nM = [[1.0, 0.0], [0.0, 0.5]]\nK = [[3.0, -1.0], [-1.0, 1.0]]\n"
                    "[damping]\nrayleigh = [0.02, 0.02]\n[excitation]\nF_c = [1.0, 0.0]\nomega = 1.8\n"
                    "[[contact]]\nbetween = [0, 1]\nN = 0.6\nmu_s = 0.5\nmu_k = 0.5\nk_t = 20.0\n")
    out = tmp_path / "cont"
    assert main(["system", "continuation", str(spec), "--param", "force", "--start", "1.0", "--stop", "1.5",
                 "--out", str(out), "--json"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["continuation.csv", "continuation.nc", "continuation.png"]
    got = json.loads(capsys.readouterr().out)
    assert got["param"] == "force" and got["branches"][0]["stopped"].startswith("reached the end")
    p = got["points"]["param"]
    assert p[0] == pytest.approx(1.0) and p[-1] == pytest.approx(1.5) and len(p) >= 3
    # the force's scale 1.5: the orbit of the structure with F_c 1.5 times the file's
    (cold,) = find_system_orbits(two_mass(1.8).replace(F_c=[1.5, 0.0]), estimate_error=False)
    assert np.allclose(got["points"]["amplitude_m"][-1], cold.amplitude, rtol=1e-5)


@loops
def test_a_requested_accuracy_chooses_h() -> None:
    """accuracy= (m) starts from a coarse step (1/32 of the period) and halves it until the amplitude's
    estimated error is within it: n = 1 against the oscillator's exact orbit within twice the request,
    at 1e-4 and 1e-7 of the amplitude, the finer request on a finer step."""
    p = Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.6, chi=0.4)
    exact = dfo.find_orbits(p)[0].amplitude
    steps = []
    for rel in (1e-4, 1e-7):
        (o,) = find_system_orbits(System.from_oscillator(p), accuracy=rel * exact)
        assert o.converged and o.error <= rel * exact
        assert abs(o.amplitude[0] - exact) <= 2.0 * rel * exact
        steps.append(2 * np.pi / p.omega / o.h)
    assert 32 <= steps[0] < steps[1]


def test_a_failed_solve_says_where_the_step_leaves_the_stiffest_mode_coarse() -> None:
    """stiffest_rate is the stuck structure's fastest natural rate (the two-mass case's closed form,
    w^4 - (5 + 3 k_t) w^2 + 4 (1 + k_t) = 0); a Newton solve that stops short (max_iter = 0) names
    that mode and the step that would give it 4 steps a period where h gives it fewer, and only there."""
    from dryfriction.analysis.system_orbits import stiffest_rate
    from dryfriction.system import cases

    for k_t in (20.0, 2.0e4):
        b = 5.0 + 3.0 * k_t
        w = np.sqrt(0.5 * (b + np.sqrt(b * b - 16.0 * (1.0 + k_t))))
        assert stiffest_rate(cases.two_mass_jenkins(k_t=k_t)) == pytest.approx(w, rel=1e-12)
    w = stiffest_rate(cases.two_mass_jenkins(k_t=2.0e4))
    T = 2.0 * np.pi
    for steps, coarse in ((100, True), (int(np.ceil(4.0 * w)) + 1, False)):
        s = cases.two_mass_jenkins(k_t=2.0e4, h=T / steps)
        (o,) = find_system_orbits(s, max_iter=0, keep_failed=True, estimate_error=False)
        assert not o.converged and o.reason.startswith("no convergence in 0 Newton steps")
        assert ("the stiffest mode (" + f"{w:.4g} rad/s" in o.reason) == coarse, o.reason
        if coarse:
            assert f"h <= {T / (4.0 * w):.3g}" in o.reason


def test_map_runs_through_one_fmu_are_fresh_runs_bit_for_bit() -> None:
    """One FMU instance restores its kept Initialization Mode states between runs (per system and
    start time; a state kept for another system restored and only the values that differ set):
    runs alternating four systems (another omega and h, normal load, mass matrix), start times,
    options (Jacobian, observables, windows) and states give the bits of the same runs each in a
    fresh FMU."""
    from dryfriction.drivers.system import SystemFMU3

    a, b = two_mass(1.4, h=0.05), two_mass(1.8, N=0.3, h=0.04)
    c = a.replace(omega=1.5)
    d = System(M=1.5 * a.M, K=a.K, C=a.C, contacts=a.contacts, F_c=a.F_c, omega=a.omega, h=a.h)
    rng = np.random.default_rng(7)
    runs = []
    for k in range(16):
        s = (a, b, a, c, d)[k % 5]
        n = s.n
        runs.append((s, dict(start_time=[0.0, 0.7, 1.3][k % 3], sensitivity=bool(k % 2), observe=k != 5,
                             t_obs_stop=[None, 2.5][k % 2], x0=rng.normal(size=n) * 0.2,
                             v0=rng.normal(size=n) * 0.2)))

    def go(fmu: SystemFMU3, s: System, kw: dict) -> list[np.ndarray]:
        fmu.system = s
        fmu.start(**kw)
        fmu.do_step(3.0)
        out = list(fmu.outputs().values()) + list(fmu.observables())
        return out + ([fmu.jacobian()] if kw["sensitivity"] else [])

    shared = {}
    with SystemFMU3(a) as one:
        for k, (s, kw) in enumerate(runs):
            shared[k] = go(one, s, kw)
    for k, (s, kw) in enumerate(runs):
        with SystemFMU3(s) as f:
            fresh = go(f, s, kw)
        assert all(np.array_equal(x, y, equal_nan=True) for x, y in zip(shared[k], fresh)), k


def test_modes_at_reads_the_modes_record_at_reads() -> None:
    """SystemFMU3.modes_at (the section's sampled cycle) steps as record_at does: the same modes at
    every time, the same end state; bad times refused."""
    from dryfriction.drivers.system import SystemFMU3

    s = two_mass(1.4, h=0.05)
    t = np.linspace(0.3, 0.3 + 2 * 2 * np.pi / 1.4, 301)
    with SystemFMU3(s) as fmu:
        fmu.start(0.3, observe=False, x0=[0.4, -0.2], v0=[0.1, 0.0])
        run = fmu.record_at(t)
        end = fmu.outputs()
        fmu.start(0.3, observe=False, x0=[0.4, -0.2], v0=[0.1, 0.0])
        modes = fmu.modes_at(t)
        assert modes.dtype == np.int8 and modes.shape == run.mode.shape
        assert np.array_equal(modes, run.mode) and len({tuple(m) for m in modes}) >= 2  # (it switches)
        assert all(np.array_equal(a, b) for a, b in zip(fmu.outputs().values(), end.values()))
        with pytest.raises(ValueError, match="strictly increasing"):
            fmu.modes_at([fmu.time, fmu.time])
