"""The two-mass reference (tests/two_mass_reference.py) against independent solutions: with the
pair locked together (a contact between them that never slips) it is the exact oscillator of
mass m1 + m2; with the contact between them frictionless and no coupling, mass 1 is the exact
oscillator and mass 2 a linear one; in a general case that goes through every kind of mode set
(both contacts stuck, one stuck, the pair stuck together and sliding on the ground, both sliding)
its energy balances, its stuck contacts hold within their limits and the constraints hold."""

from __future__ import annotations

import math

import numpy as np

from dryfriction.references.exact import linear_solution, solve_exact
from dryfriction.params import Oscillator
from two_mass_reference import TwoMass, accelerations, simulate

BASE = TwoMass(m1=1.0, m2=0.5, k1=100.0, k2=20.0, k12=50.0, c1=0.5, c2=0.3, c12=0.0, P1=1.0, P2=0.5,
               omega=6.0, N_g=2.0, mu_s_g=0.4, mu_k_g=0.28, N_c=1.0, mu_s_c=0.3, mu_k_c=0.2)
PERIOD = 2 * math.pi / BASE.omega
# every kind of mode set within 4 periods: both stuck, mass 1 held under a sliding mass 2, the pair
# stuck together and sliding on the ground, both sliding
GENERAL = BASE.with_(N_g=2.5)


def _oscillator(m: float, k: float, c: float, P0: float, N: float, mu_s: float, mu_k: float) -> Oscillator:
    return Oscillator(m=m, k=k, c=c, P0=P0, omega=BASE.omega, phi=0.0, N=N, mu_s=mu_s,
                      chi=mu_k / mu_s, x0=0.0, v0=0.0)


def test_locked_pair_is_the_exact_oscillator() -> None:
    p = BASE.with_(N_c=1e6, mu_s_c=1.0, mu_k_c=0.8)  # the pair never slips: one block of m1 + m2
    sol = simulate(p, 5 * PERIOD)
    osc = _oscillator(p.m1 + p.m2, p.k1 + p.k2, p.c1 + p.c2, p.P1 + p.P2, p.N_g, p.mu_s_g, p.mu_k_g)
    ex = solve_exact(osc, 5 * PERIOD)
    t = np.linspace(0.0, 5 * PERIOD, 3001)
    x, v, modes = sol.evaluate(t)
    xe, ve, _, me = ex.evaluate(t)
    amp = np.max(np.abs(xe))
    assert np.max(np.abs(x[:, 0] - xe)) < 1e-9 * amp and np.max(np.abs(x[:, 1] - xe)) < 1e-9 * amp
    assert np.max(np.abs(v[:, 0] - ve)) < 1e-9 * amp * osc.omega
    assert np.all(modes[:, 1] == 0)  # the contact between the masses holds throughout
    ts = np.array([s.t for s in sol.switches])
    assert ts.size == ex.switch_times().size >= 6 and np.max(np.abs(ts - ex.switch_times())) < 1e-9 * PERIOD
    assert {(s.before, s.after) for s in sol.switches} >= {(1, 0), (0, -1), (-1, 1)}  # stick and reversal


def test_decoupled_masses_are_two_exact_oscillators() -> None:
    p = BASE.with_(N_c=0.0, k12=0.0, c12=0.0)  # nothing between them
    sol = simulate(p, 5 * PERIOD)
    t = np.linspace(0.0, 5 * PERIOD, 3001)
    x, v, _ = sol.evaluate(t)
    ex1 = solve_exact(_oscillator(p.m1, p.k1, p.c1, p.P1, p.N_g, p.mu_s_g, p.mu_k_g), 5 * PERIOD)
    x1, v1, _, _ = ex1.evaluate(t)
    x2, v2, _ = linear_solution(_oscillator(p.m2, p.k2, p.c2, p.P2, 0.0, 0.4, 0.2), t)
    assert ex1.switch_times().size >= 6  # mass 1 sticks and slips
    assert np.max(np.abs(x[:, 0] - x1)) < 1e-9 * np.max(np.abs(x1))
    assert np.max(np.abs(v[:, 0] - v1)) < 1e-9 * np.max(np.abs(v1))
    assert np.max(np.abs(x[:, 1] - x2)) < 1e-9 * np.max(np.abs(x2))
    assert np.max(np.abs(v[:, 1] - v2)) < 1e-9 * np.max(np.abs(v2))


def _energy(p: TwoMass, x: np.ndarray, v: np.ndarray) -> float:
    return 0.5 * float(v @ p.mass @ v + x @ p.stiffness @ x)


def test_general_case_every_mode_set_energy_and_limits() -> None:
    p = GENERAL
    t_end = 4 * PERIOD
    sol = simulate(p, t_end)
    sets = sol.mode_sets()
    assert (0, 0) in sets                                   # both stuck
    assert sets & {(0, 1), (0, -1)}                         # mass 1 held, mass 2 sliding on it
    assert sets & {(1, 0), (-1, 0)}                         # the pair stuck together, sliding on the ground
    assert sets & {(1, 1), (1, -1), (-1, 1), (-1, -1)}      # both sliding
    # the energy balance phase by phase (Gauss-Legendre on each phase's dense output): the change
    # of kinetic + potential energy = the excitation's work - friction's and the dampers' dissipation
    nodes, weights = np.polynomial.legendre.leggauss(48)
    work = 0.0
    Fb = p.breakaway
    for ph in sol.phases:
        if ph.t1 <= ph.t0:
            continue
        tq = 0.5 * (ph.t1 - ph.t0) * nodes + 0.5 * (ph.t1 + ph.t0)
        y = ph.sol(tq)
        for i, tt in enumerate(tq):
            xq, vq = y[:2, i], y[2:, i]
            _, f = accelerations(p, ph.modes, tt, xq, vq)
            for j in range(2):
                if ph.modes[j] == 0:
                    assert abs(f[j]) <= Fb[j] * (1 + 1e-9)      # held within its limit
                    assert abs(p.rows[j] @ vq) < 1e-12          # and not slipping
            P = np.array([p.P1, p.P2]) * math.cos(p.omega * tt + p.phi)
            power = P @ vq + f @ (p.rows @ vq) - vq @ p.damping @ vq
            work += 0.5 * (ph.t1 - ph.t0) * weights[i] * power
    x_end, v_end, _ = sol.evaluate(np.array([t_end]))
    e0 = _energy(p, np.array([p.x1_0, p.x2_0]), np.array([p.v1_0, p.v2_0]))
    e1 = _energy(p, x_end[0], v_end[0])
    scale = p.k1 * (p.P1 / p.k1) ** 2
    assert abs((e1 - e0) - work) < 1e-8 * scale
