"""The chain coupled at second order (docs/chain.md, "Coupling"): inputs given with their time
derivatives over each communication step against the event-driven reference of the chain with the
same smooth input (dryfriction.chain_reference.solve_chain with F_ext_t).

The runs go through the chain's instance core (the FMU's code below its FMI glue) by the driver
mode of tests/c/test_chain_deriv; the core's own checks (directional derivatives against finite
differences in every mode, output derivatives against the trajectory, input points, the error
sentences) are that program's ctest run."""

from __future__ import annotations

import io
import os
import subprocess
from pathlib import Path
from typing import Callable

import numpy as np
import pytest

from dryfriction.chain_reference import Chain, ChainSolution, solve_chain

ROOT = Path(__file__).resolve().parents[1]
DRIVER = Path(os.environ.get("DFO_CHAIN_DERIV", ROOT / "build" / "tests" / "c" / "test_chain_deriv"))

# two blocks with stick-slip in both (18 switches over two periods with the harmonic input, 7 of
# them stops), the second forced through its input only
CHAIN = Chain.make(2, omega=0.5, m=[1.0, 1.0], k=[1.0, 1.0], P0=[1.0, 0.0], N=[1.2, 1.0], mu_s=0.5, chi=0.7)
T = CHAIN.period
T_END = 2.0 * T


def _fmt(a: np.ndarray) -> str:
    return ",".join(repr(float(x)) for x in a)


def run(H: float, h: float, order: int, scheme: int = 3, F_amp=(0.0, 0.0), F_omega: float = 1.0,
        F_lin=(0.0, 0.0), F_quad=(0.0, 0.0), ch: Chain = CHAIN, t_end: float = T_END) -> np.ndarray:
    """Rows t, x1, x2, v1, v2 at the communication points of a run with
    F_ext_i(t) = F_amp_i sin(F_omega t) + F_lin_i t + F_quad_i t^2 / 2 given at every point with
    its derivatives up to order (0: held)."""
    if not DRIVER.is_file():
        raise FileNotFoundError(f"test_chain_deriv not built: {DRIVER} (cmake --build build)")
    args = [str(DRIVER), "run", f"scheme={scheme}", f"h={h!r}", f"H={H!r}", f"t_end={t_end!r}", f"order={order}",
            f"F_amp={_fmt(np.asarray(F_amp))}", f"F_omega={F_omega!r}", f"F_lin={_fmt(np.asarray(F_lin))}",
            f"F_quad={_fmt(np.asarray(F_quad))}", f"omega={ch.omega!r}", f"k_end={ch.k_end!r}"]
    for name in ("m", "k", "c", "P0", "phi", "N", "mu_s", "chi", "x0", "v0"):
        args.append(f"{name}={_fmt(getattr(ch, name))}")
    out = subprocess.run(args, check=True, capture_output=True, text=True).stdout
    return np.loadtxt(io.StringIO(out), delimiter=",", ndmin=2)


def error(a: np.ndarray, ref: ChainSolution) -> float:
    return float(np.max(np.abs(a[:, 1:3] - ref.evaluate(a[:, 0])["x"])))


def harmonic(A, W: float) -> Callable[[float], np.ndarray]:
    A = np.asarray(A, dtype=float)
    return lambda t: A * np.sin(W * t)


@pytest.fixture(scope="module")
def ref_harmonic() -> ChainSolution:
    return solve_chain(CHAIN, T_END, F_ext_t=harmonic((0.3, 0.5), 1.1))


def test_reference_case_has_stick_slip_in_both_blocks(ref_harmonic: ChainSolution) -> None:
    blocks = [e[1] for e in ref_harmonic.events if e[3] == 0]  # stops
    assert blocks.count(0) >= 3 and blocks.count(1) >= 3
    assert {e[3] for e in ref_harmonic.events} >= {0, 1}  # stops and breakaways


def test_reference_with_a_constant_input_is_the_held_one() -> None:
    """The reference's time-varying input (F_ext_t) reduces to its held F_ext."""
    c = np.array([0.2, -0.15])
    held = solve_chain(Chain.make(2, omega=0.5, m=[1.0, 1.0], k=[1.0, 1.0], P0=[1.0, 0.0], N=[1.2, 1.0],
                                  mu_s=0.5, chi=0.7, F_ext=c), T)
    timed = solve_chain(CHAIN, T, F_ext_t=lambda t: c)
    t = np.linspace(0.0, T, 201)
    assert np.max(np.abs(held.evaluate(t)["x"] - timed.evaluate(t)["x"])) < 1e-10
    assert [e[1:] for e in held.events] == [e[1:] for e in timed.events]


@pytest.mark.parametrize("order, divisors, lo, hi, err_max", [(0, (50, 100, 200, 400), 1.8, 2.3, 0.04),
                                                         (1, (50, 100, 200, 400), 3.6, 4.4, 4e-4),
                                                         (2, (25, 50, 100, 200), 7.0, 10.5, 3e-5)])
def test_input_derivatives_converge_in_the_communication_step(ref_harmonic: ChainSolution, order: int,
                                                               divisors: tuple[int, ...], lo: float, hi: float,
                                                               err_max: float) -> None:
    """A harmonic input given at every communication point: held (order 0) the run is first order
    in H; with its first derivative second order, with the second third order (the internal step
    T/8000 so fine that the scheme's own error is below them; it is reached at H = T/400 with the
    second derivative, 3.5e-6). Measured max |x - x_ref|: 0.26, 0.13, 0.064, 0.029 (held, H = T/50
    ... T/400), 0.019, 4.8e-3, 1.2e-3, 2.9e-4 (order 1, the same H), 1.3e-2, 1.7e-3, 1.8e-4, 1.8e-5
    (order 2, H = T/25 ... T/200)."""
    errs = np.array([error(run(T / d, T / 8000, order, F_amp=(0.3, 0.5), F_omega=1.1), ref_harmonic)
                     for d in divisors])
    ratios = errs[:-1] / errs[1:]
    assert np.all((ratios > lo) & (ratios < hi)), (errs, ratios)
    assert errs[-1] < err_max


def test_located_scheme_is_second_order_in_h_with_ramped_inputs() -> None:
    """A quadratic input, exact with its two derivatives at every communication point (H = T/20):
    the located scheme, switches placed with the inputs at each trial's end, converges at second
    order in the internal step h (measured 1.3e-3, 3.5e-4, 8.7e-5, 2.2e-5 at h = T/250 ... T/2000;
    held inputs stay at 0.11, the first-order error of the hold)."""
    lin, quad = np.array([0.05, -0.04]), np.array([-0.01, 0.012])
    ref = solve_chain(CHAIN, T_END, F_ext_t=lambda t: lin * t + 0.5 * quad * t * t)
    assert sum(e[1] == 0 for e in ref.events) >= 3 and sum(e[1] == 1 for e in ref.events) >= 3
    errs = np.array([error(run(T / 20, T / d, 2, F_lin=lin, F_quad=quad), ref) for d in (250, 500, 1000, 2000)])
    ratios = errs[:-1] / errs[1:]
    assert np.all((ratios > 3.6) & (ratios < 4.4)), (errs, ratios)
    assert errs[-1] < 3e-5
    held = error(run(T / 20, T / 2000, 0, F_lin=lin, F_quad=quad), ref)
    assert held > 0.05  # the hold's error, which the derivatives remove


@pytest.mark.parametrize("scheme", [1, 2, 3])
def test_zero_derivatives_are_the_held_run_bit_for_bit(scheme: int) -> None:
    """Derivatives given as 0 (a constant input) are the run without them, to the last bit."""
    held = run(T / 50, T / 1000, 0, scheme=scheme, F_lin=(0.0, 0.0))
    zero = run(T / 50, T / 1000, 2, scheme=scheme, F_lin=(0.0, 0.0))
    assert held.tobytes() == zero.tobytes()
    assert np.any(held[:, 3:5] == 0.0)  # the run sticks
