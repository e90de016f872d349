"""Inputs held over communication steps (zero-order hold, as every co-simulation master does): a
change of F_ext or N_ext at a communication point is a jump of the acceleration there. The Bossak
schemes take the jump into their acceleration (dfo_new_inputs, chain_new_inputs); without it every
change costs a first-order error (measured before: 3.1e-3, 1.5e-3, 7.4e-4, 4.3e-4 at T/400 ...
T/3200, ratio 2). Asserted: the located scheme stays second order against the tight-tolerance
event-driven reference with random inputs on random communication points; the chain (n = 1) takes
the jump with the oscillator's bits; a coupled chain with changing inputs converges at second order."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from dryfriction.drivers.chain import ChainFMU3
from dryfriction.references.chain import Chain
from dryfriction.drivers.oscillator import OscillatorFMU2, Settings
from dryfriction.params import Oscillator

from chain_cases import chain_params, run_driver
from helpers import OUT, assert_rounding_apart, event_driven, held_run


ND = Oscillator.from_nondimensional
DIVS = (400, 800, 1600, 3200)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_located_stays_second_order_with_held_inputs(fmu: OscillatorFMU2, seed: int) -> None:
    rng = np.random.default_rng(seed)
    p = ND(lam=0.6, mu_s_sigma=0.4, chi=0.6, zeta=0.05 * seed)
    T = p.period
    t = np.concatenate([[0.0], np.sort(rng.uniform(0.0, 5.0 * T, 30)), [5.0 * T]])
    F_ext = rng.uniform(-0.5, 0.5, t.size) * p.P0
    N_ext = rng.uniform(-0.5, 1.0, t.size) * p.N
    ref = event_driven(p, t, F_ext, N_ext)
    size = float(np.abs(ref).max())
    errs = [float(np.abs(held_run(fmu, p, Settings(scheme="located", h=T / d), t, F_ext, N_ext) - ref).max()) / size
            for d in DIVS]
    assert errs[0] <= 3e-4, errs
    ratios = [a / b for a, b in zip(errs, errs[1:])]
    assert all(3.5 <= r <= 4.6 for r in ratios), (errs, ratios)


@pytest.mark.parametrize("scheme", ["located", "consistent", "paper"])
def test_chain_n1_takes_input_jumps_as_the_oscillator(fmu: OscillatorFMU2, chain_fmu3: Path, scheme: str) -> None:
    """x and v of one block with inputs changed before every step: the oscillator's, to rounding
    (helpers.CHAIN_N1_REL: the oscillator steps through the friction engine, the chain through its
    own stepper)."""
    b = dict(m=1.0, k=1.0, c=0.1, P0=1.0, omega=0.5, N=0.8, mu_s=0.5, chi=0.7, x0=0.0, v0=0.0)
    p = Oscillator(phi=0.0, **b)
    T = p.period
    h, dt, steps = T / 500, T / 40, 240
    rng = np.random.default_rng(7)
    F = rng.uniform(-0.4, 0.4, steps + 1)
    Nx = rng.uniform(-0.3, 0.5, steps + 1)
    t = dt * np.arange(steps + 1)

    def inputs(time: float, _y: dict) -> dict:
        k = int(round(time / dt))
        return {"F_ext": [float(F[k])], "N_ext": [float(Nx[k])]}

    with ChainFMU3(1, fmu_path=chain_fmu3) as f:
        run = f.run(t[-1], dt, {**b, "phi": 0.0, "h": h, "alpha": -0.1, "scheme": scheme}, inputs=inputs)
    fmu.start(p, Settings(h=h, alpha=-0.1, scheme=scheme))
    x, v = [float(fmu.get(["x"])["x"])], [float(fmu.get(["v"])["v"])]
    for k in range(steps):
        fmu.set({"F_ext": float(F[k]), "N_ext": float(Nx[k])})
        fmu.step_to(float(t[k + 1]))
        out = fmu.get(["x", "v"])
        x.append(float(out["x"]))
        v.append(float(out["v"]))
    assert (run.mode == 0).any() and (run.mode != 0).any()
    assert np.array_equal(run.t, t)
    assert_rounding_apart(run.x[:, 0], np.array(x), "x")
    assert_rounding_apart(run.v[:, 0], np.array(v), "v")


def test_chain_with_changing_inputs_converges_at_second_order(chain_fmu3: Path) -> None:
    """Three coupled blocks, every input changed at every communication point: errors against the
    same run at h = T/6400 fall 4x per halving of h."""
    ch = Chain.make(3, omega=0.6, k_end=0.5, c=0.05, N=[0.6, 0.8, 0.7], chi=[0.8, 1.2, 0.6],
                    P0=[1.0, 0.4, 0.7], phi=[0.0, 0.5, 1.0])
    T = ch.period
    dt = T / 37
    steps = 6 * 37

    def inputs(time: float, _y: dict) -> dict:
        k = int(round(time / dt))
        return {"F_ext": [0.3 * np.sin(1.7 * k), -0.2 * np.cos(0.9 * k), 0.25 * np.sin(2.3 * k + 1.0)],
                "N_ext": [0.2 * np.cos(1.1 * k), 0.15 * np.sin(0.7 * k), -0.1 * np.cos(1.9 * k)]}

    def run(div: int) -> np.ndarray:
        with ChainFMU3(3, fmu_path=chain_fmu3) as f:
            r = f.run(steps * dt, dt, chain_params(ch, T / div), inputs=inputs)
        assert (r.mode == 0).any() and (r.mode != 0).any()
        return r.x

    ref = run(6400)
    size = float(np.abs(ref).max())
    errs = [float(np.abs(run(d) - ref).max()) / size for d in (200, 400, 800)]
    ratios = [a / b for a, b in zip(errs, errs[1:])]
    assert all(3.3 <= r <= 5.0 for r in ratios), (errs, ratios)


# ------------------------------------------------ what the inputs are, and the chain's held inputs

def test_inputs_are_the_forces_they_name(fmu: OscillatorFMU2) -> None:
    """F_ext = F0 shifts the equilibrium by F0/k; N_ext adds to N (same numbers as N + N_ext)."""
    p = Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.4, chi=0.7, zeta=0.05)
    t = np.linspace(0, 5 * p.period, 201)
    F0 = 0.3
    shifted = fmu.trajectory(p.with_(x0=F0 / p.k), t, Settings(extra={"F_ext": F0}), ("x",))["x"]
    plain = fmu.trajectory(p, t, Settings(), ("x",))["x"]
    assert np.max(np.abs(shifted - F0 / p.k - plain)) < 1e-12
    more = fmu.trajectory(p, t, Settings(extra={"N_ext": 0.25}), OUT)
    same = fmu.trajectory(p.with_(N=p.N + 0.25), t, Settings(), OUT)
    for k in OUT:
        assert np.array_equal(more[k], same[k]), k
    # a negative total normal force lifts the block: max(N + N_ext, 0) = 0, no friction
    lifted = fmu.trajectory(p, t, Settings(extra={"N_ext": -2.0 * p.N}), OUT)
    free = fmu.trajectory(p.with_(N=0.0), t, Settings(), OUT)
    assert np.array_equal(lifted["x"], free["x"])


def test_held_inputs_equal_the_c_driver(chain_fmu3: Path) -> None:
    """F_ext held from the start (set in Initialization Mode) gives the C chain's numbers with the
    same F_ext, bit for bit; set by a function before every step (the first after initialisation),
    the same bits too (the input's jump enters the state: chain_new_inputs); a feedback input
    changes the motion."""
    F = [0.2, -0.1, 0.3]
    ch = Chain.make(3, omega=0.6, N=[0.6, 0.8, 0.7], chi=0.8, F_ext=F)
    T = ch.period
    dt = T / 50
    drv = run_driver(ch, 200 * dt, T / 400, dt=dt)
    with ChainFMU3(3, fmu_path=chain_fmu3) as f:
        held = f.run(200 * dt, dt, chain_params(ch, T / 400), inputs={"F_ext": F})
        func = f.run(200 * dt, dt, chain_params(ch, T / 400), inputs=lambda t, y: {"F_ext": F})
        fb = f.run(200 * dt, dt, chain_params(ch, T / 400), inputs=lambda t, y: {"F_ext": -0.5 * y["v"]})
    assert (held.mode == 0).any() and (held.mode != 0).any()
    assert np.array_equal(held.x, drv["x"]) and np.array_equal(held.mode, drv["mode"])
    assert np.array_equal(func.x, held.x)
    assert np.max(np.abs(fb.x - held.x)) > 1e-2
