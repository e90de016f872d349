"""The belt references (dryfriction.references.belt) checked against each other and against the
project's other independent references: the event-driven solution reproduces the closed-form
stick-slip limit cycle, the exact piecewise solution of the fixed support (dryfriction.references.exact) when
the belt stands still, the linear closed form without friction, and the Stribeck slide's loss of
stability at the analytic belt speed; a belt change while stuck keeps the block's velocity."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dryfriction import Oscillator
from dryfriction.references.belt import Belt, hopf_belt_speed, limit_cycle, simulate
from dryfriction.references.exact import solve_exact


@pytest.mark.parametrize("m,k,N,mu_s,mu_k,vb", [
    (1.0, 1.0, 1.0, 0.5, 0.3, 0.2),
    (2.0, 50.0, 3.0, 0.6, 0.1, 0.05),
    (0.5, 4.0, 2.0, 0.4, 0.35, 1.5),
])
def test_event_driven_reproduces_the_closed_form_limit_cycle(m: float, k: float, N: float, mu_s: float,
                                                             mu_k: float, vb: float) -> None:
    lc = limit_cycle(m, k, N, mu_s, mu_k, vb)
    b = Belt(m=m, k=k, N=N, mu_s=mu_s, mu_k=mu_k, x0=0.0, v0=vb)
    r = simulate(b, np.linspace(0.0, 8.5 * lc.period, 4001), v_belt=vb)
    br, st = r.times("breakaway"), r.times("stop")
    assert br.size >= 7 and st.size >= 7
    assert np.max(np.abs(np.diff(br) - lc.period)) <= 1e-10 * lc.period
    slips = st[st > br[0]][:br.size - 1] - br[:br.size - 1]
    assert np.max(np.abs(slips - lc.t_slip)) <= 1e-10 * lc.period
    # the turning points: y' = 0 after the phase alpha (top) and pi + alpha (bottom) of the slip
    w = math.sqrt(k / m)
    alpha = math.atan2(vb / w, (mu_s - mu_k) * N / k)
    t_top, t_bot = br[2] + alpha / w, br[2] + (math.pi + alpha) / w
    top = simulate(b, [0.0, t_top, t_bot], v_belt=vb)
    scale = lc.x_max - lc.x_min
    assert abs(top.x[1] - lc.x_max) <= 1e-10 * scale and abs(top.x[2] - lc.x_min) <= 1e-10 * scale
    assert abs(top.v[1]) <= 1e-10 * vb and abs(top.v[2]) <= 1e-10 * vb
    # the stick phase: from x_stick_start to x_breakaway at the belt's speed
    stuck = (r.mode == 0) & (r.t > br[0])
    assert np.all(r.x[stuck] >= lc.x_stick_start - 1e-10 * scale)
    assert np.all(r.x[stuck] <= lc.x_breakaway + 1e-10 * scale)
    assert np.all(r.v[stuck] == vb)


@pytest.mark.parametrize("zeta,chi,mss,lam", [(0.05, 0.7, 0.4, 0.5), (0.02, 0.5, 0.8, 1.3), (0.1, 1.0, 0.3, 0.8)])
def test_a_still_belt_is_the_exact_fixed_support_solution(zeta: float, chi: float, mss: float, lam: float) -> None:
    p = Oscillator.from_nondimensional(lam=lam, mu_s_sigma=mss, chi=chi, zeta=zeta, z0=0.3, dz0=-0.2)
    T = p.period
    t = np.linspace(0.0, 6 * T, 1201)
    ref = solve_exact(p, t[-1])
    x_ref, v_ref, _, _ = ref.evaluate(t)
    b = Belt(m=p.m, k=p.k, c=p.c, N=p.N, mu_s=p.mu_s, mu_k=p.mu_k, P0=p.P0, omega=p.omega, phi=p.phi,
             x0=p.x0, v0=p.v0)
    r = simulate(b, t, v_belt=0.0)
    scale = float(np.max(np.abs(x_ref)))
    assert float(np.max(np.abs(r.x - x_ref))) <= 1e-8 * scale
    assert np.array_equal(r.mode == 0, np.abs(v_ref) == 0.0) or \
        float(np.mean((r.mode == 0) != (v_ref == 0.0))) < 0.01  # at most a sample at a switch


def test_without_friction_the_linear_closed_form() -> None:
    b = Belt(m=1.3, k=2.0, c=0.2, N=0.0, P0=1.0, omega=1.1, phi=0.4, x0=0.5, v0=-0.1)
    t = np.linspace(0.0, 40.0, 801)
    r = simulate(b, t, v_belt=0.7)         # no normal force: the belt does nothing
    w = b.omega
    X = b.P0 / complex(b.k - b.m * w * w, b.c * w)
    xp = (X * np.exp(1j * (w * t + b.phi))).real
    vp = (1j * w * X * np.exp(1j * (w * t + b.phi))).real
    # the free part from the initial state
    lam = np.roots([b.m, b.c, b.k])
    A = np.array([[1, 1], lam]), np.array([b.x0 - xp[0], b.v0 - vp[0]])
    a = np.linalg.solve(*A)
    x = xp + (a[0] * np.exp(lam[0] * t) + a[1] * np.exp(lam[1] * t)).real
    assert float(np.max(np.abs(r.x - x))) <= 1e-10


@pytest.mark.slow
def test_stribeck_slide_loses_stability_at_the_analytic_belt_speed() -> None:
    m, k, c, N, mu_s, mu_k, v_s = 1.0, 1.0, 0.05, 1.0, 0.6, 0.3, 0.5
    v_star = hopf_belt_speed(c, N, mu_s, mu_k, v_s)
    assert v_star == pytest.approx(v_s * math.log(N * (mu_s - mu_k) / (c * v_s)), rel=1e-15)
    b = Belt(m=m, k=k, c=c, N=N, mu_s=mu_s, mu_k=mu_k, law="stribeck", v_s=v_s, delta=1.0)
    growth = {}
    for f in (0.5, 1.5):
        vb = f * v_star
        x_eq = N * b.mu(vb) / k            # steady sliding: v = 0, k x = N mu(v_belt)
        bb = b.with_(x0=x_eq + 1e-2, v0=0.0)
        t = np.linspace(0.0, 200.0, 20001)
        r = simulate(bb, t, v_belt=vb)
        early, late = np.abs(r.x[t < 20] - x_eq).max(), np.abs(r.x[t > 180] - x_eq).max()
        growth[f] = late / early
        # the linearised rate: exp(-(c + N mu'(vb)) / (2 m) t)
        sigma = -(c + N * b.dmu(vb)) / (2 * m)
        if f > 1:
            assert sigma < 0 and growth[f] < 0.1 and not r.times("stop").size
        else:
            assert sigma > 0
            assert r.times("stop").size > 0          # it grew into stick-slip
    assert growth[0.5] > 10 * growth[1.5]


def test_a_belt_change_while_stuck_keeps_the_velocity() -> None:
    b = Belt(m=1.0, k=1.0, N=1.0, mu_s=0.5, mu_k=0.3, x0=0.0, v0=0.2)
    t = np.linspace(0.0, 1.0, 101)
    r = simulate(b, t, v_belt=0.2, changes=[(0.5, -0.1)])
    assert np.all(r.mode[t <= 0.5] == 0)
    after = r.t > 0.5
    assert np.all(r.mode[after] == 1)           # v = 0.2 > v_belt = -0.1: it slides forward
    i = int(np.argmax(after))
    # continuous velocity: v(0.5+) = 0.2, then the kinetic friction and the spring slow it
    assert abs(r.v[i] - (0.2 + (-0.3 - r.x[i]) * (r.t[i] - 0.5))) < 1e-3
    assert r.events[0] == (pytest.approx(0.5), "breakaway")
