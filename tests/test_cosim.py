"""The co-simulation master dryfriction.cosim (docs/coupling.md) on the two-block chain split in two.

Block 1 (its wall spring, the harmonic force) and block 2 (k = 0) are two oscillator FMUs joined by
the chain's middle spring and damper, computed by the master and set as F_ext, opposite on each.
The chain at n = 2 with the same parameters is the monolithic answer: the event-driven reference
(dryfriction.references.chain, scipy at rtol 1e-12) and the chain FMU. Measured here:

- zero-order-hold Jacobi converges at first order (max |x - x_ref| 1.563, 0.7211, 0.3449, 0.1686 at
  H = T/50 ... T/400), held inputs at the mean of the outputs' Taylor polynomial at second order
  (0.0754, 0.0188, 0.00361, 0.00084), in the located and the exact scheme, with both blocks sticking;
- a coupling spring 10^4 times the blocks' own: zero-order-hold Jacobi diverges (the FMU refuses the
  overflowing state) at H = T/200, the interface-Jacobian correction stays within 0.0065 of the chain;
- rollback: a rejected step goes back to the saved FMU states and is redone at half the step, so a run
  whose every step is rejected down to H/4 is the fixed-step run at H/4, bit for bit;
- libcosim (libcosimpy) holding the inputs the master computes reproduces zero-order-hold Jacobi (1e-12);
- what the FMUs do not provide yet (input derivatives, directional derivatives, output derivatives)
  is refused with a sentence naming the capability; the tests of those modes run once the FMUs
  declare them.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from dryfriction.drivers.chain import ChainFMU3
from dryfriction.references.chain import Chain, ChainSolution, solve_chain
from dryfriction.cosim import Connection, CosimResult, SpringDamper, System, coupling_matrix
from dryfriction.cosim.split import split_chain, split_chain2
from dryfriction.diagnostics import DryFrictionWarning
from dryfriction.errors import FMUCallError, FMUError
from dryfriction.fmi._base import read_capabilities
from dryfriction.drivers.oscillator import OscillatorFMU2, Settings
from dryfriction.params import Oscillator
from refcache import RefCache

# both blocks stick (3 % and 1 % of the time), amplitudes 3.8 and 6.1
CASE: dict[str, Any] = dict(m=1.0, k=1.0, c=[0.05, 0.1], P0=[1.0, 0.0], N=[0.8, 0.5], mu_s=0.5, chi=0.7, omega=0.6)
T = 2 * math.pi / CASE["omega"]
PERIODS = 10
DIVISIONS = (50, 100, 200, 400)


@pytest.fixture(scope="module")
def reference(refcache: RefCache) -> ChainSolution:
    return refcache.call(solve_chain, Chain.make(2, **CASE), PERIODS * T)


@pytest.fixture(scope="module")
def fmu3_path() -> Path:
    from dryfriction.drivers.oscillator3 import default_fmi3_path

    return default_fmi3_path()


@pytest.fixture(scope="module")
def blocks(fmu_path: Path) -> Iterator[tuple[OscillatorFMU2, OscillatorFMU2]]:
    with OscillatorFMU2(fmu_path) as f1, OscillatorFMU2(fmu_path) as f2:
        yield f1, f2


def split(blocks: tuple[OscillatorFMU2, OscillatorFMU2], params: dict[str, Any] = CASE, scheme: str = "located"
          ) -> System:
    b1, b2, element = split_chain2(params)
    f1, f2 = blocks
    f1.start(b1, Settings(h=0.0, scheme=scheme))
    f2.start(b2, Settings(h=0.0, scheme=scheme))
    s = System()
    s.add("b1", f1)
    s.add("b2", f2)
    s.couple(element)
    return s


def error(res: CosimResult, ref: ChainSolution) -> float:
    x = np.column_stack([res["b1.x"], res["b2.x"]])
    return float(np.max(np.abs(x - ref.evaluate(res.t)["x"])))


def errors(blocks: Any, ref: ChainSolution, scheme: str = "located", **kw: Any) -> np.ndarray:
    return np.array([error(split(blocks, scheme=scheme).run(PERIODS * T, T / n, **kw), ref) for n in DIVISIONS])


def orders(e: np.ndarray) -> np.ndarray:
    return np.log2(e[:-1] / e[1:])


# ------------------------------------------------------------------------------- the case itself

def test_the_case_sticks_in_both_blocks_and_the_chain_fmu_agrees(reference: ChainSolution,
                                                                 chain_fmu3: Path) -> None:
    t = np.linspace(0.0, PERIODS * T, 2001)
    ev = reference.evaluate(t)
    stuck = np.mean(ev["mode"] == 0, axis=0)
    assert np.all(stuck > 0.005), stuck
    amp = 0.5 * (ev["x"].max(axis=0) - ev["x"].min(axis=0))
    np.testing.assert_allclose(amp, [3.826, 6.087], atol=2e-3)
    with ChainFMU3(n=2, fmu_path=chain_fmu3) as ch:
        run = ch.run(PERIODS * T, T / 40, params={**CASE, "k_end": 0.0})
    assert np.max(np.abs(run.x - reference.evaluate(run.t)["x"])) < 1e-4  # measured 3.2e-5


# ------------------------------------------------------------------------------- orders of convergence

@pytest.mark.parametrize("scheme", ["located", "exact"])
def test_zero_order_hold_jacobi_is_first_order(blocks: Any, reference: ChainSolution, scheme: str) -> None:
    e = errors(blocks, reference, scheme)
    np.testing.assert_allclose(e, [1.563, 0.7211, 0.3449, 0.1686], rtol=2e-3)
    assert np.all((orders(e) > 1.0) & (orders(e) < 1.15)), orders(e)


@pytest.mark.parametrize("scheme, expected", [("located", [0.07543, 0.01879, 0.003606, 0.0008415]),
                                              ("exact", [0.07541, 0.0188, 0.003569, 0.0008058])])
def test_extrapolated_inputs_are_second_order(blocks: Any, reference: ChainSolution, scheme: str,
                                              expected: list[float]) -> None:
    e = errors(blocks, reference, scheme, inputs="extrapolate", source="outputs")  # x' = v, x'' = a, v' = a
    np.testing.assert_allclose(e, expected, rtol=1e-2)
    assert np.all(orders(e) > 1.95), orders(e)
    zoh = errors(blocks, reference, scheme)
    assert np.all(e < zoh / 20)


def test_gauss_seidel(blocks: Any, reference: ChainSolution) -> None:
    """Gauss-Seidel (block 1 first): the forces on the two blocks are no longer opposite, and held
    inputs drift the free block 2 off (164 at T/50, 1.95 at T/400); extrapolated, 3.6e-4 at T/400."""
    hold = errors(blocks, reference, method="gauss-seidel")
    np.testing.assert_allclose(hold, [164.3, 16.78, 4.89, 1.947], rtol=1e-2)
    ext = errors(blocks, reference, method="gauss-seidel", inputs="extrapolate")
    assert ext[-1] < 4e-4 and ext[-1] < ext[1] / 40, ext


def test_gauss_seidel_steps_the_units_in_order(blocks: Any) -> None:
    """The second block's input is computed from the first's outputs at the end of the step."""
    s = split(blocks)
    H = T / 50
    res = s.run(2 * H, H, method="gauss-seidel", record=["b1.a"])
    k, c = 1.0, 0.1
    F1 = k * (res["b2.x"][1] - res["b1.x"][1]) + c * (res["b2.v"][1] - res["b1.v"][1])
    F2_expected = -(k * (res["b2.x"][1] - res["b1.x"][2]) + c * (res["b2.v"][1] - res["b1.v"][2]))
    assert res.inputs["b1.F_ext"][1] == F1
    assert res.inputs["b2.F_ext"][1] == F2_expected
    assert res["b1.a"].shape == (3,)


def test_a_local_variable_is_recorded_when_asked(blocks: Any) -> None:
    """record= takes a local variable (the oscillator's Jacobian, scheme exact with sensitivity on):
    the identity at the start, then at every point what the unit reads by value reference (the last
    one read again from the unit after the run); a local is no port to couple."""
    b1, b2, element = split_chain2(CASE)
    f1, f2 = blocks
    f1.start(b1, Settings(h=0.0, scheme="exact", extra={"sensitivity": True}))
    f2.start(b2, Settings(h=0.0, scheme="exact"))
    s = System()
    s.add("b1", f1)
    s.add("b2", f2)
    s.couple(element)
    jac = ("dx_dx0", "dx_dv0", "dv_dx0", "dv_dv0")
    res = s.run(4 * T / 50, T / 50, record=[f"b1.{n}" for n in jac])
    assert [res[f"b1.{n}"][0] for n in jac] == [1.0, 0.0, 0.0, 1.0]
    end = f1.get(list(jac))
    assert [res[f"b1.{n}"][-1] for n in jac] == [end[n] for n in jac]
    assert res["b1.dx_dx0"].shape == (5,) and np.all(np.isfinite(res["b1.dv_dx0"]))
    assert res["b1.dv_dx0"][-1] != 0.0  # the Jacobian moved
    s.connect("b1.dx_dx0", "b2.N_ext")
    with pytest.raises(ValueError, match="b1.dx_dx0 is not an output \\(its causality is local\\)"):
        s.run(T, T / 50)
    with pytest.raises(ValueError, match="b1.F_ext is not an output or a local variable"):
        split(blocks).run(T, T / 50, record=["b1.F_ext"])


@pytest.mark.slow
@pytest.mark.parametrize("case, expected", [
    ("stick-dominated", [0.01396, 0.004185, 0.000877, 0.0002209]),
    ("friction-on-one", [0.08905, 0.02392, 0.00588, 0.001363]),
    ("chi-mixed", [0.3033, 0.07243, 0.01799, 0.004217]),
    ("damped-walled", [0.004034, 0.001064, 0.0002791, 7.206e-05]),
])
def test_three_oscillators_are_the_three_block_chain_at_second_order(fmu_path: Path, case: str,
                                                                      expected: list[float],
                                                                      refcache: RefCache) -> None:
    """The coupled cases of docs/chain.md split into three oscillators (two spring-dampers through
    the master), against the chain's reference over ten periods: second order with input
    derivatives on every case (held at the extrapolated mean, the stick-dominated case is only
    first order: a breakaway the coupling force causes inside a step cannot be located with the
    force held, 0.0044 and 0.0026 at T/200 and T/400)."""
    from chain_cases import CASES

    ch = CASES[case]
    names = ("m", "k", "c", "P0", "phi", "N", "mu_s", "chi", "x0", "v0", "omega", "k_end", "c_end")
    params = {f: getattr(ch, f) for f in names}
    period = 2 * math.pi / ch.omega
    ref = refcache.call(solve_chain, ch, PERIODS * period)
    blocks, elements = split_chain(params, ch.n)
    drivers = [OscillatorFMU2(fmu_path) for _ in blocks]
    try:
        if not drivers[0].inst.capabilities.can_interpolate_inputs:
            pytest.skip('did not run: the oscillator FMU does not declare canInterpolateInputs="true"')
        e = []
        for div in DIVISIONS:
            s = System()
            for i, (f, b) in enumerate(zip(drivers, blocks)):
                f.start(b, Settings(h=0.0))
                s.add(f"b{i + 1}", f)
            for el in elements:
                s.couple(el)
            res = s.run(PERIODS * period, period / div, inputs="derivatives")
            x = np.column_stack([res[f"b{i + 1}.x"] for i in range(ch.n)])
            e.append(float(np.max(np.abs(x - ref.evaluate(res.t)["x"]))))
    finally:
        for f in drivers:
            f.close()
    np.testing.assert_allclose(e, expected, rtol=1e-2)
    assert np.all(orders(np.array(e)) > 1.7), orders(np.array(e))


@pytest.mark.slow
def test_a_chain_fmu_and_an_oscillator_are_the_three_block_chain(chain_fmu2: Path, fmu_path: Path,
                                                                 refcache: RefCache) -> None:
    """The FMI 2.0 chain (n = 2: blocks 1, 2) and an oscillator (block 3 with the far wall's spring)
    joined at x[2] and x: the damped, walled case of docs/chain.md, first order with held inputs,
    second order with input derivatives (both FMUs take them)."""
    from chain_cases import CASES

    from dryfriction.drivers.chain import ChainFMU2

    ch = CASES["damped-walled"]
    period = 2 * math.pi / ch.omega
    ref = refcache.call(solve_chain, ch, PERIODS * period)
    sub = {f: getattr(ch, f)[:2].tolist() for f in ("m", "k", "c", "P0", "phi", "N", "mu_s", "chi", "x0", "v0")}
    b3 = Oscillator(m=ch.m[2], k=ch.k_end, c=ch.c_end, P0=ch.P0[2], phi=ch.phi[2], omega=ch.omega, N=ch.N[2],
                    mu_s=ch.mu_s[2], chi=ch.chi[2], x0=ch.x0[2], v0=ch.v0[2])
    element = SpringDamper("c", "b3", k=ch.k[2], c=ch.c[2], x=("x[2]", "x"), v=("v[2]", "v"),
                           force=("F_ext[2]", "F_ext"))
    with ChainFMU2(fmu_path=chain_fmu2) as c, OscillatorFMU2(fmu_path) as o:
        assert c.n == 2

        def errs(**kw: Any) -> np.ndarray:
            e = []
            for div in DIVISIONS:
                c.start({**sub, "omega": ch.omega, "k_end": 0.0, "c_end": 0.0})
                o.start(b3, Settings(h=0.0))
                s = System()
                s.add("c", c)
                s.add("b3", o)
                s.couple(element)
                res = s.run(PERIODS * period, period / div, record=["c.x[1]"], **kw)
                x = np.column_stack([res["c.x[1]"], res["c.x[2]"], res["b3.x"]])
                e.append(float(np.max(np.abs(x - ref.evaluate(res.t)["x"]))))
            return np.array(e)

        e = errs()
        np.testing.assert_allclose(e, [0.09704, 0.04705, 0.02306, 0.01147], rtol=1e-2)
        assert np.all((orders(e) > 1.0) & (orders(e) < 1.1))
        _needs(c.inst.capabilities.can_interpolate_inputs, 'canInterpolateInputs="true" (the chain)')
        e = errs(inputs="derivatives")  # the chain's F_ext[2] and the oscillator's F_ext as ramps
        np.testing.assert_allclose(e, [0.002997, 0.0007829, 0.0001963, 4.786e-05], rtol=1e-2)
        assert np.all(orders(e) > 1.9), orders(e)


# ------------------------------------------------------------------------------- stiff coupling

STIFF = {**CASE, "k": [1.0, 1e4], "c": [0.05, 0.0]}


def test_stiff_coupling_zoh_diverges_the_correction_does_not(blocks: Any, chain_fmu3: Path) -> None:
    H = T / 200
    with pytest.raises(FMUCallError, match="non-finite|invalid value"):
        split(blocks, STIFF).run(5 * T, H)
    res = split(blocks, STIFF).run(5 * T, H, correction=True)
    with ChainFMU3(n=2, fmu_path=chain_fmu3) as ch:
        run = ch.run(5 * T, H, params={**STIFF, "k_end": 0.0})
    x = np.column_stack([res["b1.x"], res["b2.x"]])
    err = np.max(np.abs(x - run.x))
    assert err < 0.01 and np.max(np.abs(run.x)) > 2.5, err  # measured 0.0064 on amplitudes 3.0
    assert res.fmu_steps == 6 * res.steps  # per unit: a first pass, one step for its input (S), the corrected one
    assert res.steps == 1000


def test_correction_on_the_mild_case_is_first_order_and_close_to_zoh(blocks: Any, reference: ChainSolution) -> None:
    e = np.array([error(split(blocks).run(PERIODS * T, T / n, correction=True), reference) for n in (100, 200)])
    assert 0.9 < math.log2(e[0] / e[1]) < 1.2, e
    assert e[1] < 0.5


# ------------------------------------------------------------------------------- rollback

def test_every_step_rejected_gives_the_run_at_the_smaller_step(blocks: Any) -> None:
    H = T / 50
    fixed = split(blocks).run(2 * T, H / 4, inputs="extrapolate")
    with pytest.warns(DryFrictionWarning, match=r"above tol = 1e-300 at 400 step\(s\) .* H/2\^2"):
        adaptive = split(blocks).run(2 * T, H, inputs="extrapolate", tol=1e-300, max_halvings=2)
    assert adaptive.rejected == 2  # the first step, at H and at H/2; then it stays at H/4
    np.testing.assert_array_equal(adaptive.t, fixed.t)
    np.testing.assert_array_equal(adaptive["b1.x"], fixed["b1.x"])
    np.testing.assert_array_equal(adaptive["b2.v"], fixed["b2.v"])
    assert adaptive.unmet == 400 and adaptive.steps == 400


def test_rollback_halves_where_needed_and_grows_back(blocks: Any, reference: ChainSolution) -> None:
    """tol = 0.005 N on the interface force: 857 steps (71 rejected) for the error of 1000 fixed
    steps (0.0184 against 0.0188; 0.0754 at the 500 steps of H)."""
    H = T / 50
    coarse = split(blocks).run(PERIODS * T, H, inputs="extrapolate")
    fine = split(blocks).run(PERIODS * T, H / 2, inputs="extrapolate")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = split(blocks).run(PERIODS * T, H, inputs="extrapolate", tol=0.005, max_halvings=4)
    assert res.rejected > 0 and res.unmet == 0 and res.max_error <= 0.005
    steps = np.unique(np.round(res.H / (H / 16)).astype(int))
    assert steps.max() == 16 and steps.min() < 16  # halved where needed, back to H elsewhere
    assert error(res, reference) < error(coarse, reference) / 3
    assert error(res, reference) < 1.05 * error(fine, reference) and res.steps < fine.steps


# ------------------------------------------------------------------------------- what the FMU lacks today

def test_capabilities_are_read_from_the_description(blocks: Any) -> None:
    f1, _ = blocks
    cap = read_capabilities(f1.unzip_dir)
    assert cap == f1.inst.capabilities and cap.fmi_version == 2 and cap.can_get_and_set_state
    text = (Path(f1.unzip_dir) / "modelDescription.xml").read_text()
    assert cap.can_interpolate_inputs == ('canInterpolateInputs="true"' in text)
    assert cap.directional_derivatives == ('providesDirectionalDerivative="true"' in text)


def test_modes_the_fmu_does_not_provide_are_refused_with_the_capability(blocks: Any) -> None:
    cap = blocks[0].inst.capabilities
    s = split(blocks)
    if not cap.can_interpolate_inputs:
        with pytest.raises(FMUError, match='b1 declares canInterpolateInputs="false"'):
            s.run(T, T / 50, inputs="derivatives")
        with pytest.raises(FMUCallError, match="fmi2SetRealInputDerivatives"):
            blocks[0].inst.set_real_input_derivatives([blocks[0].vr("F_ext")], 1, [0.0])
    if not cap.directional_derivatives:
        with pytest.raises(FMUError, match='providesDirectionalDerivative="false"'):
            s.run(T, T / 50, correction=True, jacobian="directional")
    if cap.max_output_derivative_order == 0:
        with pytest.raises(FMUError, match="maxOutputDerivativeOrder=0"):
            s.run(T, T / 50, inputs="extrapolate", source="fmu")
    with pytest.raises(ValueError, match="inputs='hold'"):
        s.run(T, T / 50, correction=True, inputs="extrapolate")


def _needs(cap_ok: bool, what: str) -> None:
    if not cap_ok:
        pytest.skip(f"did not run: the oscillator FMU does not declare {what}")


@pytest.mark.parametrize("input_order, expected", [(1, [0.01927, 0.004909, 0.00112, 0.0002071]),
                                                   (2, [0.006733, 0.001619, 0.0004842, 0.0002359])])
def test_input_derivatives_are_second_order(blocks: Any, reference: ChainSolution, input_order: int,
                                            expected: list[float]) -> None:
    """The force's slope (and curvature, from x'' = a) sent with fmi2SetRealInputDerivatives: four
    (ten) times closer than held inputs at the extrapolated mean; with the curvature the error
    meets a floor near 2e-4 at T/400 (the FMU's internal step is fixed at T/1000)."""
    _needs(blocks[0].inst.capabilities.can_interpolate_inputs, 'canInterpolateInputs="true"')
    e = errors(blocks, reference, inputs="derivatives", input_order=input_order)
    np.testing.assert_allclose(e, expected, rtol=1e-2)
    assert np.all(orders(e)[:2] > 1.7), orders(e)


def test_input_derivatives_in_the_exact_scheme(blocks: Any, reference: ChainSolution, refcache: RefCache) -> None:
    """The exact scheme follows input derivatives in closed form, the free block (k = 0) too: second
    order on the split chain (0.01943, 0.005064, 0.001269, 0.0003223 at H = T/50 ... T/400); with the far wall's k_end = 0.5 on block 2 (0.006327 ... 9.989e-05;
    located: 0.00632 ... 9.252e-05)."""
    _needs(blocks[0].inst.capabilities.can_interpolate_inputs, 'canInterpolateInputs="true"')
    e = np.array([error(split(blocks, scheme="exact").run(PERIODS * T, T / n, inputs="derivatives"), reference)
                  for n in DIVISIONS])
    assert np.all(orders(e) > 1.8), orders(e)
    walled = {**CASE, "k_end": 0.5}
    ref = refcache.call(solve_chain, Chain.make(2, **walled), PERIODS * T)
    e = np.array([error(split(blocks, walled, "exact").run(PERIODS * T, T / n, inputs="derivatives"), ref)
                  for n in DIVISIONS])
    np.testing.assert_allclose(e, [0.006327, 0.001494, 0.0003886, 9.989e-05], rtol=1e-2)
    assert np.all(orders(e) > 1.9), orders(e)


def test_fmi3_units_hold_as_fmi2_and_take_inputs_during_a_step(fmu3_path: Path, reference: ChainSolution) -> None:
    """FMI 3.0 oscillators: held inputs give the FMI 2.0 bits; inputs="derivatives" sets the
    polynomial at every intermediate update (the FMU's internal steps' ends): second order."""
    from dryfriction.drivers.oscillator3 import OscillatorFMU3

    b1, b2, element = split_chain2(CASE)

    def run(H: float, callback: bool, **kw: Any) -> CosimResult:
        cb = (lambda t, can: False) if callback else None
        with OscillatorFMU3(params=dataclasses.asdict(b1), intermediate=cb, fmu_path=fmu3_path) as f1, \
                OscillatorFMU3(params=dataclasses.asdict(b2), intermediate=cb, fmu_path=fmu3_path) as f2:
            s = System()
            s.add("b1", f1)
            s.add("b2", f2)
            s.couple(element)
            return s.run(PERIODS * T, H, **kw)

    hold = run(T / 50, False)
    assert error(hold, reference) == pytest.approx(1.563, rel=2e-3)
    _needs(_fmi3_intermediate(fmu3_path), 'intermediateUpdate="true" inputs')
    with pytest.raises(FMUError, match="intermediate_update callback"):
        run(T / 50, False, inputs="derivatives")
    e = np.array([error(run(T / n, True, inputs="derivatives"), reference) for n in DIVISIONS])
    np.testing.assert_allclose(e, [0.01938, 0.004992, 0.001202, 0.0004163], rtol=1e-2)
    assert np.all(orders(e) > 1.5), orders(e)


def _fmi3_intermediate(path: Path) -> bool:
    import tempfile
    import zipfile

    with tempfile.TemporaryDirectory() as d:
        zipfile.ZipFile(path).extract("modelDescription.xml", d)
        cap = read_capabilities(d)
    return cap.intermediate_update and len(cap.intermediate_vrs) > 0


def test_zero_input_derivatives_give_the_bits_of_held_inputs(blocks: Any) -> None:
    _needs(blocks[0].inst.capabilities.can_interpolate_inputs, 'canInterpolateInputs="true"')
    f1, _ = blocks
    vr = f1.vr("F_ext")
    runs = []
    for send in (False, True):
        f1.start(split_chain2(CASE)[0], Settings(h=0.0))
        xs = []
        for j in range(50):
            f1.set({"F_ext": 0.3 * math.sin(j)})
            if send:
                f1.inst.set_real_input_derivatives([vr], 1, [0.0])
            f1.do_step(T / 50)
            xs.append(f1.get("x"))
        runs.append(xs)
    assert runs[0] == runs[1]


def test_fmu_output_derivatives(blocks: Any, reference: ChainSolution) -> None:
    """The FMU's own output derivatives (x: v, a; v: a, a's derivative): x' is v to the bit, and
    extrapolating from them is second order (with v'' too: 0.0891 ... 0.00106)."""
    _needs(blocks[0].inst.capabilities.max_output_derivative_order >= 2, "maxOutputDerivativeOrder >= 2")
    f1, _ = blocks
    f1.start(split_chain2(CASE)[0], Settings(h=0.0))
    f1.do_step(T / 7)
    d1 = f1.inst.get_real_output_derivatives([f1.vr("x"), f1.vr("v")], 1)
    d2 = f1.inst.get_real_output_derivatives([f1.vr("x")], 2)
    assert d1.tolist() == [f1.get("v"), f1.get("a")] and d2.tolist() == [f1.get("a")]
    e = errors(blocks, reference, inputs="extrapolate", source="fmu")
    np.testing.assert_allclose(e, [0.08915, 0.02059, 0.004491, 0.001063], rtol=1e-2)
    assert np.all(orders(e) > 2.0), orders(e)


def test_directional_derivatives_of_the_layer(blocks: Any) -> None:
    """d a / d F_ext = 1/m while sliding (the FMU's feed-through), through both FMI layers'
    calls; the FMI 3.0 adjoint is its transpose."""
    _needs(blocks[0].inst.capabilities.directional_derivatives, 'providesDirectionalDerivative="true"')
    f1, _ = blocks
    f1.start(Oscillator(m=2.0, k=1.0, P0=3.0, omega=0.6, N=0.1, mu_s=0.5, chi=0.7), Settings(h=0.0))
    f1.do_step(1.0)
    assert f1.get("mode") != 0
    J = f1.inst.jacobian([f1.vr("a"), f1.vr("x")], [f1.vr("F_ext"), f1.vr("N_ext")])
    assert J[0, 0] == 0.5 and J[1].tolist() == [0.0, 0.0]


def test_fmi3_layer_output_directional_and_adjoint_derivatives(fmu3_path: Path) -> None:
    """fmi3GetOutputDerivatives gives v and a for x, fmi3GetDirectionalDerivative d a / d F_ext =
    1/m while sliding, fmi3GetAdjointDerivative its transpose (the seed over the unknowns)."""
    from dryfriction.drivers.oscillator3 import OscillatorFMU3

    p = Oscillator(m=2.0, k=1.0, P0=3.0, omega=0.6, N=0.1, mu_s=0.5, chi=0.7)
    with OscillatorFMU3(params=dataclasses.asdict(p), fmu_path=fmu3_path) as f:
        cap = f.inst.capabilities
        _needs(cap.directional_derivatives and cap.adjoint_derivatives and cap.max_output_derivative_order >= 2,
               "providesDirectionalDerivatives, providesAdjointDerivatives, maxOutputDerivativeOrder 2")
        f.do_step(1.0)
        assert f.get("mode") != 0
        x, v, a, F, N = (f.vr(n) for n in ("x", "v", "a", "F_ext", "N_ext"))
        assert f.inst.get_output_derivatives([x, x], [1, 2]).tolist() == [f.get("v"), f.get("a")]
        J = f.inst.jacobian([a, x, v], [F, N])
        assert J[0, 0] == 0.5 and J[1:].tolist() == [[0.0, 0.0], [0.0, 0.0]]
        seed = np.array([1.0, 2.0, 3.0])
        np.testing.assert_array_equal(f.inst.get_adjoint_derivative([a, x, v], [F, N], seed), J.T @ seed)


def test_directional_jacobian_is_stable_on_the_stiff_coupling(blocks: Any, chain_fmu3: Path) -> None:
    """S from the directional derivatives at the step's start (dt^2/2 d a/dF for x, dt d a/dF for
    v: the free-mass step, blind to a stuck block's breakaway) is cheaper (4 FMU steps per macro
    step against 6) and less close than by steps: 0.064 against 0.0064 at T/200, on amplitudes 3."""
    _needs(blocks[0].inst.capabilities.directional_derivatives, 'providesDirectionalDerivative="true"')
    H = T / 200
    res = split(blocks, STIFF).run(5 * T, H, correction=True, jacobian="directional")
    with ChainFMU3(n=2, fmu_path=chain_fmu3) as ch:
        run = ch.run(5 * T, H, params={**STIFF, "k_end": 0.0})
    x = np.column_stack([res["b1.x"], res["b2.x"]])
    assert np.max(np.abs(x - run.x)) < 0.08
    assert res.fmu_steps == 4 * res.steps


# ------------------------------------------------------------------------------- the master's parts

def test_coupling_matrix_and_port_checks(blocks: Any) -> None:
    inputs, outputs, G = coupling_matrix([SpringDamper("a", "b", k=2.0, c=0.5), Connection("c.y", "a.F_ext", 3.0)])
    assert inputs == ["a.F_ext", "b.F_ext"]
    assert outputs == ["b.x", "a.x", "b.v", "a.v", "c.y"]
    np.testing.assert_array_equal(G, [[2.0, -2.0, 0.5, -0.5, 3.0], [-2.0, 2.0, -0.5, 0.5, 0.0]])
    with pytest.raises(ValueError, match="k must be a finite number >= 0"):
        SpringDamper("a", "b", k=-1.0).terms()
    s = split(blocks)
    s.connect("b1.F_ext", "b2.N_ext")
    with pytest.raises(ValueError, match="b1.F_ext is not an output"):
        s.run(T, T / 50)
    s2 = System()
    with pytest.raises(ValueError, match="there is already an instance named 'b1'"):
        s2.add("b1", blocks[0])
        s2.add("b1", blocks[1])
    with pytest.raises(ValueError, match="H must be a finite number > 0"):
        split(blocks).run(T, 0.0)


def test_result_as_a_dataset(blocks: Any) -> None:
    res = split(blocks).run(T, T / 20)
    with_bar = split(blocks).run(T, T / 20, progress=True)
    assert with_bar["b2.x"].tolist() == res["b2.x"].tolist()
    ds = res.to_dataset()
    assert ds.sizes["time"] == 21 and ds["b1.x"].values.tolist() == res["b1.x"].tolist()
    assert np.isnan(res.inputs["b1.F_ext"][-1]) and ds.attrs["steps"] == 20


# ------------------------------------------------------------------------------- libcosim

@pytest.mark.slow
def test_libcosim_holding_the_inputs_is_zoh_jacobi(fmu_path: Path, blocks: Any) -> None:
    """libcosim steps the two FMUs itself (its own FMI calls); the spring-damper force it holds over
    each step is computed from its observer's outputs and set through its override manipulator."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimManipulator import CosimManipulator
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    log_output_level(CosimLogLevel.ERROR)
    b1, b2, sd = split_chain2(CASE)
    # libcosim's time is an integer of nanoseconds, converted as count / 1e9: with H = 1/8 s its
    # communication points are k/8 exactly, as the master's
    H_ns, H, steps = 125_000_000, 0.125, 320
    ex = CosimExecution.from_step_size(step_size=H_ns)
    md = blocks[0].md
    assert md.var("scheme").start == md.scheme_value("located")  # libcosim leaves it at its start
    idx = []
    for name, p in (("b1", b1), ("b2", b2)):
        i = ex.add_local_slave(local_slave=CosimLocalSlave(fmu_path=str(fmu_path), instance_name=name))
        for f in ("m", "k", "c", "P0", "omega", "phi", "N", "mu_s", "chi", "x0", "v0"):
            assert ex.real_initial_value(slave_index=i, variable_reference=md.vr(f), value=getattr(p, f))
        idx.append(i)
    obs = CosimObserver.create_last_value()
    ex.add_observer(observer=obs)
    man = CosimManipulator.create_override()
    ex.add_manipulator(manipulator=man)
    vrs = [md.vr("x"), md.vr("v")]
    vr_f = md.vr("F_ext")
    xs = []
    y = [[b1.x0, b1.v0], [b2.x0, b2.v0]]
    for _ in range(steps):
        F = sd.k * (y[1][0] - y[0][0]) + sd.c * (y[1][1] - y[0][1])
        assert man.slave_real_values(idx[0], [vr_f], [F]) and man.slave_real_values(idx[1], [vr_f], [-F])
        assert ex.step()
        y = [obs.last_real_values(slave_index=i, variable_references=vrs) for i in idx]
        xs.append([y[0][0], y[1][0]])
    ours = split(blocks).run(steps * H, H)
    x = np.column_stack([ours["b1.x"], ours["b2.x"]])[1:]
    assert np.max(np.abs(x)) > 0.5
    assert np.max(np.abs(np.array(xs) - x)) <= 1e-12 * np.max(np.abs(x))
