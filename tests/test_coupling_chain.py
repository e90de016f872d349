"""The chain coupled at second order (docs/chain.md, "Coupling"): inputs given with their time
derivatives over each communication step against the event-driven reference of the chain with the
same smooth input (dryfriction.references.chain.solve_chain with F_ext_t).

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

from dryfriction.references.chain import Chain, ChainSolution, solve_chain

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
        F_lin=(0.0, 0.0), F_quad=(0.0, 0.0), ch: Chain = CHAIN, t_end: float = T_END,
        N_lin=(0.0, 0.0), N_quad=(0.0, 0.0)) -> np.ndarray:
    """Rows t, x1, x2, v1, v2 at the communication points of a run with
    F_ext_i(t) = F_amp_i sin(F_omega t) + F_lin_i t + F_quad_i t^2 / 2 (and N_ext_i(t) = N_lin_i t +
    N_quad_i t^2 / 2) given at every point with its derivatives up to order (0: held)."""
    if not DRIVER.is_file():
        raise FileNotFoundError(f"test_chain_deriv not built: {DRIVER} (cmake --build build)")
    args = [str(DRIVER), "run", f"scheme={scheme}", f"h={h!r}", f"H={H!r}", f"t_end={t_end!r}", f"order={order}",
            f"F_amp={_fmt(np.asarray(F_amp))}", f"F_omega={F_omega!r}", f"F_lin={_fmt(np.asarray(F_lin))}",
            f"F_quad={_fmt(np.asarray(F_quad))}", f"N_lin={_fmt(np.asarray(N_lin))}",
            f"N_quad={_fmt(np.asarray(N_quad))}", f"omega={ch.omega!r}", f"k_end={ch.k_end!r}"]
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
    held inputs stay at 0.11, the first-order error of the hold; the paper and consistent schemes,
    first order at a switch, 6.0e-4 at T/2000)."""
    lin, quad = np.array([0.05, -0.04]), np.array([-0.01, 0.012])
    ref = solve_chain(CHAIN, T_END, F_ext_t=lambda t: lin * t + 0.5 * quad * t * t)
    assert sum(e[1] == 0 for e in ref.events) >= 3 and sum(e[1] == 1 for e in ref.events) >= 3
    errs = np.array([error(run(T / 20, T / d, 2, F_lin=lin, F_quad=quad), ref) for d in (250, 500, 1000, 2000)])
    ratios = errs[:-1] / errs[1:]
    assert np.all((ratios > 3.6) & (ratios < 4.4)), (errs, ratios)
    assert errs[-1] < 3e-5
    held = error(run(T / 20, T / 2000, 0, F_lin=lin, F_quad=quad), ref)
    assert held > 0.05  # the hold's error, which the derivatives remove


def test_normal_force_derivatives_second_order_in_h() -> None:
    """N_ext(t) quadratic (both blocks, the normal forces 1.2 ... 0.36), exact with its two
    derivatives at every communication point (H = T/20): the located scheme, limits and kinetic
    forces following the normal force, converges at second order in h against the reference with
    the same normal force (measured 6.8e-4, 1.8e-4, 4.5e-5, 1.1e-5 at h = T/250 ... T/2000; held,
    1.3e-2)."""
    nl, nq = np.array([-0.06, 0.05]), np.array([0.004, -0.006])
    ref = solve_chain(CHAIN, T_END, N_ext_t=lambda t: nl * t + 0.5 * nq * t * t)
    assert sum(e[3] == 0 for e in ref.events) >= 4
    errs = np.array([error(run(T / 20, T / d, 2, N_lin=nl, N_quad=nq), ref) for d in (250, 500, 1000, 2000)])
    ratios = errs[:-1] / errs[1:]
    assert np.all((ratios > 3.6) & (ratios < 4.4)), (errs, ratios)
    assert errs[-1] < 2e-5
    assert error(run(T / 20, T / 2000, 0, N_lin=nl, N_quad=nq), ref) > 0.01


@pytest.mark.parametrize("scheme", [1, 2, 3])
def test_zero_derivatives_are_the_held_run_bit_for_bit(scheme: int) -> None:
    """Derivatives given as 0 (a constant input) are the run without them, to the last bit."""
    held = run(T / 50, T / 1000, 0, scheme=scheme, F_lin=(0.0, 0.0))
    zero = run(T / 50, T / 1000, 2, scheme=scheme, F_lin=(0.0, 0.0))
    assert held.tobytes() == zero.tobytes()
    assert np.any(held[:, 3:5] == 0.0)  # the run sticks


# ---- through the FMI 2.0 FMUs (fmpy) ------------------------------------------------------------

class Slave:
    """An FMI 2.0 FMU through fmpy's FMU2Slave, its variables by name, its error sentences kept."""

    def __init__(self, path: Path, name: str) -> None:
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE
        from fmpy import calloc, free
        from fmpy.fmi2 import fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE
        self.dir = extract(str(path))
        self.md = read_model_description(self.dir)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.messages: list[str] = []
        cb = fmi2CallbackFunctions()
        cb.logger = fmi2CallbackLoggerTYPE(lambda env, n, status, cat, msg: self.messages.append(msg.decode()))
        cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        cb.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        self.cb = cb
        self.s = FMU2Slave(guid=self.md.guid, unzipDirectory=self.dir,
                           modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=name)
        self.s.instantiate(callbacks=cb, loggingOn=False)

    def start(self, reals: dict[str, float], scheme: int = 3) -> None:
        self.s.setupExperiment(startTime=0.0)
        self.s.setReal([self.vr[k] for k in reals], list(reals.values()))
        self.s.setInteger([self.vr["scheme"]], [scheme])
        self.s.enterInitializationMode()
        self.s.exitInitializationMode()

    def get(self, *names: str) -> list[float]:
        return self.s.getReal([self.vr[n] for n in names])

    def close(self) -> None:
        import shutil
        self.s.terminate()
        self.s.freeInstance()
        shutil.rmtree(self.dir, ignore_errors=True)


def chain_reals(ch: Chain, h: float) -> dict[str, float]:
    r = {"omega": ch.omega, "k_end": ch.k_end, "c_end": ch.c_end, "h": h, "alpha": -0.1}
    for name in ("m", "k", "c", "P0", "phi", "N", "mu_s", "chi", "x0", "v0"):
        for i, x in enumerate(getattr(ch, name)):
            r[f"{name}[{i + 1}]"] = float(x)
    return r


@pytest.fixture()
def chain2(chain_fmu2: Path):
    s = Slave(chain_fmu2, "coupling")
    yield s
    s.close()


def test_fmi2_input_derivatives_are_the_cores(chain2: Slave) -> None:
    """fmi2SetRealInputDerivatives of every F_ext[i] (orders 1 and 2) before every doStep: the FMU's
    trajectory is the core's (the driver) bit for bit, and the inputs end on their polynomials."""
    H, h, A, W = T / 50, T / 1000, np.array([0.3, 0.5]), 1.1
    chain2.start(chain_reals(CHAIN, h))
    F = [chain2.vr[f"F_ext[{i}]"] for i in (1, 2)]
    rows = []
    n = 100
    for s in range(n + 1):
        t = s * H
        rows.append([t, *chain2.get("x[1]", "x[2]", "v[1]", "v[2]")])
        if s == n:
            break
        chain2.s.setReal(F, list(A * np.sin(W * t)))
        chain2.s.setRealInputDerivatives(F, [1, 1], list(A * W * np.cos(W * t)))
        chain2.s.setRealInputDerivatives(F, [2, 2], list(-A * W * W * np.sin(W * t)))
        chain2.s.doStep(t, H)
    end = chain2.get("F_ext[1]", "F_ext[2]")
    core = run(H, h, 2, F_amp=A, F_omega=W, t_end=n * H)
    assert np.array_equal(np.array(rows)[:, 1:], core[:, 1:])
    t0 = (n - 1) * H  # the last step's polynomial at its end
    expect = A * np.sin(W * t0) + (A * W * np.cos(W * t0) + 0.5 * (-A * W * W * np.sin(W * t0)) * H) * H
    assert np.max(np.abs(np.array(end) - expect)) < 1e-15


@pytest.mark.parametrize("v0, N, modes", [((0.5, -0.3), (0.5, 0.4), (1, -1)), ((0.5, 0.0), (0.5, 5.0), (1, 0)),
                                           ((0.0, 0.0), (5.0, 5.0), (0, 0))])
@pytest.mark.parametrize("scheme", [1, 2, 3])
def test_fmi2_directional_derivatives_against_differences(chain2: Slave, v0, N, modes, scheme: int) -> None:
    """fmi2GetDirectionalDerivative of a and F_friction (and x, v: 0) with respect to F_ext and
    N_ext against central differences of the outputs (1e-7), with both blocks sliding, one stuck,
    both stuck, in every scheme."""
    ch = Chain.make(2, omega=1.3, m=[1.0, 1.5], k=[4.0, 2.0], c=[0.05, 0.02], P0=[1.0, 0.6], phi=[0.0, 0.7],
                    N=list(N), mu_s=[0.5, 0.4], chi=[0.7, 0.8], v0=list(v0), k_end=0.5)
    chain2.start(chain_reals(ch, 1e-3), scheme)
    chain2.s.doStep(0.0, 0.01)
    assert tuple(chain2.s.getInteger([chain2.vr["mode[1]"], chain2.vr["mode[2]"]])) == modes
    outs = [f"{o}[{i}]" for o in ("x", "v", "a", "F_friction") for i in (1, 2)]
    ins = [f"{u}[{j}]" for u in ("F_ext", "N_ext") for j in (1, 2)]
    U, K = [chain2.vr[o] for o in outs], [chain2.vr[u] for u in ins]
    chain2.s.setReal([chain2.vr["F_ext[1]"]], [0.2])  # an input set since the step (its feed-through)
    worst = 0.0
    for c, name in enumerate(ins):
        seed = [0.0] * 4
        seed[c] = 1.0
        J = np.array(chain2.s.getDirectionalDerivative(U, K, seed))
        u0 = chain2.get(name)[0]
        d = 1e-6
        chain2.s.setReal([chain2.vr[name]], [u0 + d])
        yp = np.array(chain2.get(*outs))
        chain2.s.setReal([chain2.vr[name]], [u0 - d])
        ym = np.array(chain2.get(*outs))
        chain2.s.setReal([chain2.vr[name]], [u0])
        worst = max(worst, float(np.max(np.abs((yp - ym) / (2 * d) - J))))
        assert np.all(J[:4] == 0.0)
    assert worst < 1e-7


def test_fmi2_output_derivatives_and_errors(chain2: Slave) -> None:
    """fmi2GetRealOutputDerivatives: x' = v, x'' = v' = a; an order beyond 2, a derivative of a,
    and v' at a switch are errors whose sentences name the variable."""
    from fmpy.fmi1 import FMICallException
    chain2.start(chain_reals(CHAIN, T / 1000))
    chain2.s.doStep(0.0, 0.5)
    x1, v1, a1 = chain2.vr["x[1]"], chain2.vr["v[1]"], chain2.vr["a[1]"]
    d = chain2.s.getRealOutputDerivatives([x1, x1, v1], [1, 2, 1])
    assert d == [chain2.get("v[1]")[0], chain2.get("a[1]")[0], chain2.get("a[1]")[0]]
    for call, args, words in [(chain2.s.getRealOutputDerivatives, ([v1], [3]), "order 3 of the derivative of v[1]"),
                              (chain2.s.getRealOutputDerivatives, ([a1], [1]), "a[1] (value reference"),
                              (chain2.s.setRealInputDerivatives, ([x1], [1], [1.0]), "x[1] (value reference")]:
        n = len(chain2.messages)
        with pytest.raises(FMICallException):
            call(*args)
        assert any(words in m for m in chain2.messages[n:]), chain2.messages[n:]


def test_fmi2_directional_derivative_seed_and_overflow_errors(chain2: Slave) -> None:
    """A non-finite seed, and a derivative too large for a double (block 2 sliding with mu_k = 1e300
    on N = 1e-300 and m = 1e-10: da[2]/dN_ext[2] = -mu_k / m), are errors naming the element, not
    an OK inf; block 1's derivatives stay exact (da[1]/dF_ext[1] = 1 / m)."""
    from fmpy.fmi1 import FMICallException
    ch = Chain.make(2, omega=1.3, m=[1.0, 1e-10], k=[4.0, 2.0], c=[0.05, 0.02], P0=[1.0, 0.6], phi=[0.0, 0.7],
                    N=[0.5, 1e-300], mu_s=[0.5, 1e300], chi=[0.7, 0.7], v0=[0.5, 1.0], k_end=0.5)
    chain2.start(chain_reals(ch, 1e-3))
    a, F, N = ([chain2.vr[f"{n}[{i}]"] for i in (1, 2)] for n in ("a", "F_ext", "N_ext"))
    assert chain2.s.getDirectionalDerivative([a[0]], [F[0]], [1.0]) == [1.0]
    for args, words in [(([a[1]], [N[1]], [1.0]), "directional derivative of a[2] is not representable"),
                        (([a[0]], [F[0]], [float("inf")]), "invalid seed inf for F_ext[1]")]:
        n = len(chain2.messages)
        with pytest.raises(FMICallException):
            chain2.s.getDirectionalDerivative(*args)
        assert any(words in m for m in chain2.messages[n:]), chain2.messages[n:]


# ---- n = 1 is the oscillator, with input derivatives --------------------------------------------

DRIVER_N1 = Path(os.environ.get("DFO_CHAIN_DERIV_N1", ROOT / "build" / "tests" / "c" / "chain_deriv_n1"))
ONE_BLOCK = [dict(m=1.0, k=1.0, c=0.0, P0=1.0, omega=0.5, N=0.8, mu_s=0.5, chi=0.7, x0=0.0, v0=0.0),
             dict(m=2.0, k=3.0, c=0.2, P0=1.5, omega=1.1, N=0.6, mu_s=0.4, chi=1.4, x0=0.3, v0=-0.2),
             dict(m=1.0, k=1.0, c=0.0, P0=0.3, omega=0.5, N=0.05, mu_s=0.5, chi=0.7, x0=0.0, v0=2.0)]


@pytest.mark.parametrize("case", range(len(ONE_BLOCK)))
@pytest.mark.parametrize("scheme", [1, 2, 3])
def test_n1_with_input_derivatives_is_the_oscillator_fmu_bit_for_bit(case: int, scheme: int, fmu_path: Path) -> None:
    """One block of the chain's core (the FMI 3.0 build's, n = 1) with F_ext(t) = b t + q t^2 / 2
    and its two derivatives given at every communication point gives the oscillator FMU's x and v
    (fmi2SetRealInputDerivatives) bit for bit, in every scheme, through stick-slip."""
    if not DRIVER_N1.is_file():
        raise FileNotFoundError(f"chain_deriv_n1 not built: {DRIVER_N1} (cmake --build build)")
    p = ONE_BLOCK[case]
    T1 = 2.0 * np.pi / p["omega"]
    h, H, steps, b, q = T1 / 500, T1 / 50, 300, 0.05, -0.01
    args = [str(DRIVER_N1), "run", f"scheme={scheme}", f"h={h!r}", f"H={H!r}", f"t_end={steps * H!r}", "order=2",
            f"F_lin={b!r}", f"F_quad={q!r}", f"omega={p['omega']!r}", "k_end=0.0"]
    args += [f"{k}={p[k]!r}" for k in ("m", "k", "c", "P0", "N", "mu_s", "chi", "x0", "v0")] + ["phi=0.0"]
    out = subprocess.run(args, check=True, capture_output=True, text=True).stdout
    chain = np.loadtxt(io.StringIO(out), delimiter=",", ndmin=2)
    osc = Slave(fmu_path, "oscillator")
    try:
        osc.start({**{k: p[k] for k in ("m", "k", "c", "P0", "omega", "N", "mu_s", "chi", "x0", "v0")},
                   "phi": 0.0, "h": h, "alpha": -0.1}, scheme)
        F = [osc.vr["F_ext"]]
        rows, modes = [], set()
        for s in range(steps + 1):
            t = s * H
            rows.append(osc.get("x", "v"))
            modes.add(osc.s.getInteger([osc.vr["mode"]])[0])
            if s == steps:
                break
            osc.s.setReal(F, [b * t + 0.5 * q * t * t])
            osc.s.setRealInputDerivatives(F, [1], [b + q * t])
            osc.s.setRealInputDerivatives(F, [2], [q])
            osc.s.doStep(t, H)
    finally:
        osc.close()
    ref = np.array(rows)
    assert len(modes) >= 2  # a switch in the run
    assert np.array_equal(chain[:, 1:], ref), np.max(np.abs(chain[:, 1:] - ref))


def test_fmi3_derivatives_are_the_fmi2_ones(chain_fmu2: Path, chain_fmu3: Path) -> None:
    """FMI 3.0 (arrays, n = 2): fmi3GetDirectionalDerivative, fmi3GetAdjointDerivative (its
    transpose) and fmi3GetOutputDerivatives at a point give the FMI 2.0 FMU's values there, bit for
    bit (one block sliding, one stuck)."""
    import shutil
    from fmpy import extract, read_model_description
    from fmpy.fmi3 import FMU3Slave, fmi3Float64, fmi3Int32, fmi3ValueReference
    ch = Chain.make(2, omega=1.3, m=[1.0, 1.5], k=[4.0, 2.0], c=[0.05, 0.02], P0=[1.0, 0.6], phi=[0.0, 0.7],
                    N=[0.5, 5.0], mu_s=[0.5, 0.4], chi=[0.7, 0.8], v0=[0.5, 0.0], k_end=0.5)
    f2 = Slave(chain_fmu2, "fmi2")
    d = extract(str(chain_fmu3))
    try:
        f2.start(chain_reals(ch, 1e-3), 3)
        f2.s.doStep(0.0, 0.2)
        f2.s.setReal([f2.vr["F_ext[1]"], f2.vr["N_ext[2]"]], [0.1, -0.2])
        md = read_model_description(d)
        vr = {v.name: v.valueReference for v in md.modelVariables}
        s3 = FMU3Slave(guid=md.guid, unzipDirectory=d, modelIdentifier=md.coSimulation.modelIdentifier,
                       instanceName="fmi3")
        s3.instantiate()
        s3.enterInitializationMode()
        for name in ("m", "k", "c", "P0", "phi", "N", "mu_s", "chi", "x0", "v0"):
            s3.setFloat64([vr[name]], [float(x) for x in getattr(ch, name)])
        s3.setFloat64([vr[k] for k in ("omega", "k_end", "c_end", "h", "alpha")],
                      [ch.omega, ch.k_end, ch.c_end, 1e-3, -0.1])
        s3.exitInitializationMode()
        s3.doStep(0.0, 0.2)
        s3.setFloat64([vr["F_ext"], vr["N_ext"]], [0.1, 0.0, 0.0, -0.2])
        U3, K3 = [vr["x"], vr["v"], vr["a"], vr["F_friction"]], [vr["F_ext"], vr["N_ext"]]
        outs = [f"{o}[{i}]" for o in ("x", "v", "a", "F_friction") for i in (1, 2)]
        ins = [f"{u}[{j}]" for u in ("F_ext", "N_ext") for j in (1, 2)]
        J2 = np.array([f2.s.getDirectionalDerivative([f2.vr[o] for o in outs], [f2.vr[u] for u in ins],
                                                     list(np.eye(4)[c])) for c in range(4)]).T
        J3 = np.array([s3.getDirectionalDerivative(U3, K3, list(np.eye(4)[c]), 8) for c in range(4)]).T
        A3 = np.array([s3.getAdjointDerivative(U3, K3, list(np.eye(8)[r]), 4) for r in range(8)])
        assert np.array_equal(J2, J3) and np.array_equal(A3, J3)
        assert J3[4, 0] == 1.0 and J3[5, 1] == 0.0 and J3[7, 1] == -1.0  # a_1 = 1/m_1; stuck a_2 = 0, F_2 = -F_ext_2
        vals = (fmi3Float64 * 8)()
        s3.fmi3GetOutputDerivatives(s3.component, (fmi3ValueReference * 4)(vr["x"], vr["x"], vr["v"], vr["v"]), 4,
                                    (fmi3Int32 * 4)(1, 2, 1, 2), vals, 8)
        o2 = f2.s.getRealOutputDerivatives([f2.vr[n] for n in ("x[1]", "x[2]", "x[1]", "x[2]", "v[1]", "v[2]",
                                                               "v[1]", "v[2]")], [1, 1, 2, 2, 1, 1, 2, 2])
        assert list(vals) == o2
        assert o2[5] == 0.0 and o2[7] == 0.0  # the stuck block
        s3.terminate()
        s3.freeInstance()
    finally:
        f2.close()
        shutil.rmtree(d, ignore_errors=True)


def test_fmi2_model_structure_declares_the_directional_derivatives(chain_fmu2: Path) -> None:
    """Every nonzero directional derivative, over the three mode sets and the schemes, is of an
    output element on an input element <ModelStructure> declares (a[i], F_friction[i]: F_ext[i] and
    N_ext[i]; x, v: none), and each declared dependency is nonzero in some mode."""
    seen: dict[str, set[str]] = {}
    declared: dict[str, set[str]] = {}
    for v0, N in [((0.5, -0.3), (0.5, 0.4)), ((0.5, 0.0), (0.5, 5.0)), ((0.0, 0.0), (5.0, 5.0))]:
        for scheme in (1, 3):
            f = Slave(chain_fmu2, "structure")
            try:
                declared = {u.variable.name: {d.name for d in (u.dependencies or [])} for u in f.md.outputs}
                ch = Chain.make(2, omega=1.3, m=[1.0, 1.5], k=[4.0, 2.0], P0=[1.0, 0.6], N=list(N), mu_s=[0.5, 0.4],
                                chi=[0.7, 0.8], v0=list(v0))
                f.start(chain_reals(ch, 1e-3), scheme)
                f.s.doStep(0.0, 0.01)
                outs = [v.name for v in f.md.modelVariables if v.causality == "output" and v.type == "Real"]
                ins = [f"{u}[{j}]" for u in ("F_ext", "N_ext") for j in (1, 2)]
                for name in ins:
                    J = f.s.getDirectionalDerivative([f.vr[o] for o in outs], [f.vr[name]], [1.0])
                    for o, dj in zip(outs, J):
                        if dj != 0.0:
                            seen.setdefault(o, set()).add(name)
            finally:
                f.close()
    for o, deps in seen.items():
        assert deps <= declared[o], (o, deps, declared[o])
    for i in (1, 2):
        assert seen[f"a[{i}]"] == declared[f"a[{i}]"] == {f"F_ext[{i}]", f"N_ext[{i}]"}
        assert seen[f"F_friction[{i}]"] == declared[f"F_friction[{i}]"] == {f"F_ext[{i}]", f"N_ext[{i}]"}


def test_fmi3_inputs_at_input_points_are_steps_of_h(chain_fmu2: Path, chain_fmu3: Path) -> None:
    """An FMI 3.0 host that sets F_ext at every input point (each internal step's end,
    intermediateVariableSetRequested) gives the bits of the FMI 2.0 chain stepped by h with the same
    input set before every step; a host that sets nothing there gives a plain step's bits."""
    import shutil
    from fmpy import extract, read_model_description
    from fmpy.fmi3 import FMU3Slave
    h, H, n_macro = T / 1000, T / 50, 40
    A = np.array([0.3, 0.5])

    def force(t: float) -> list[float]:
        return [float(A[0] * np.sin(1.1 * t)), float(A[1] * np.sin(1.1 * t))]

    d = extract(str(chain_fmu3))
    md = read_model_description(d)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    results = {}
    for setting in (True, False):
        box: dict[str, FMU3Slave] = {}
        points = [0]

        def update(env, t, set_requested, get_allowed, finished, can_return, early, early_time):
            if set_requested:
                points[0] += 1
                if setting:
                    box["s"].setFloat64([vr["F_ext"]], force(t))
            early[0] = False
            early_time[0] = t

        s3 = FMU3Slave(guid=md.guid, unzipDirectory=d, modelIdentifier=md.coSimulation.modelIdentifier,
                       instanceName="points")
        s3.instantiate(intermediateUpdate=update)
        box["s"] = s3
        s3.enterInitializationMode(startTime=0.0)
        for name in ("m", "k", "c", "P0", "phi", "N", "mu_s", "chi", "x0", "v0"):
            s3.setFloat64([vr[name]], [float(x) for x in getattr(CHAIN, name)])
        s3.setFloat64([vr["omega"], vr["h"], vr["alpha"]], [CHAIN.omega, h, -0.1])
        s3.exitInitializationMode()
        rows = []
        for j in range(n_macro):
            s3.setFloat64([vr["F_ext"]], force(j * H))
            s3.doStep(j * H, H)
            rows.append(s3.getFloat64([vr["x"], vr["v"]], 4))
        s3.terminate()
        s3.freeInstance()
        assert points[0] == n_macro * 19  # the internal steps' ends before each communication point
        results[setting] = np.array(rows)
    shutil.rmtree(d, ignore_errors=True)
    f2 = Slave(chain_fmu2, "steps")
    try:
        f2.start(chain_reals(CHAIN, h))
        F = [f2.vr["F_ext[1]"], f2.vr["F_ext[2]"]]
        fine, held = [], []
        t = 0.0
        for j in range(n_macro):
            for g in range(20):
                f2.s.setReal(F, force(j * H if g == 0 else float(j * 20 + g) * h))  # (the grid point's time)
                t_next = (j + 1) * H if g == 19 else t + h
                f2.s.doStep(j * H if g == 0 else t, t_next - (j * H if g == 0 else t))
                t = t_next
            fine.append(f2.get("x[1]", "x[2]", "v[1]", "v[2]"))
    finally:
        f2.close()
    assert results[True].tobytes() != results[False].tobytes()
    assert np.array_equal(results[True], np.array(fine)), np.max(np.abs(results[True] - np.array(fine)))
