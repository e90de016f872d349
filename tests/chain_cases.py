"""Chains used by the chain tests (tests/test_chain*.py): the coupled validation cases of
docs/chain.md, the C driver (tests/c/chain_driver) as a function, and the error of a run against
the reference."""

from __future__ import annotations

import io
import os
import subprocess
from pathlib import Path
from typing import Optional

import numpy as np

from dryfriction.references.chain import Chain, ChainSolution, solve_chain


ROOT = Path(__file__).resolve().parents[1]
# the C driver of the chain: DFO_CHAIN_DRIVER, else the one of the default build
DRIVER = Path(os.environ.get("DFO_CHAIN_DRIVER", ROOT / "build" / "tests" / "c" / "chain_driver"))
PERIODS = 10

# the coupled cases: lambda-like omega against unit masses and springs (natural frequencies of a
# 3-block chain 0.45 ... 1.8 rad/s)
CASES: dict[str, Chain] = {
    # heavy friction on every block: long stick phases
    "stick-dominated": Chain.make(3, omega=0.5, N=[1.2, 1.0, 0.8], chi=0.7),
    # friction on the middle block only
    "friction-on-one": Chain.make(3, omega=0.8, N=[0.0, 0.6, 0.0], chi=0.6),
    # chi < 1 and chi > 1 side by side
    "chi-mixed": Chain.make(3, omega=0.6, N=[0.5, 0.4, 0.3], chi=[0.3, 1.5, 0.8],
                            P0=[1.0, 0.0, 0.5], phi=[0.0, 0.0, 1.0]),
    # damping, a wall spring at the right end, non-zero initial velocities
    "damped-walled": Chain.make(3, omega=0.7, k_end=1.5, c_end=0.1, c=[0.05, 0.1, 0.02],
                                N=[0.4, 0.6, 0.5], v0=[0.3, -0.2, 0.1], x0=[0.1, 0.0, -0.1]),
}


def run_driver(ch: Chain, t_end: float, h: float, dt: Optional[float] = None, scheme: int = 3,
               alpha: float = -0.1, random_dt: Optional[int] = None) -> dict[str, np.ndarray]:
    """Run the C chain and return t, x, v, F, mode (rows: communication points) and the accounts."""
    if not DRIVER.is_file():
        raise FileNotFoundError(f"chain driver not built: {DRIVER} (cmake --build build)")
    args = [str(DRIVER), *ch.driver_args(), f"t_end={t_end!r}", f"h={h!r}", f"scheme={scheme}",
            f"alpha={alpha!r}"]
    if random_dt is not None:
        args.append(f"random_dt={random_dt}")
    else:
        args.append(f"dt={(dt if dt is not None else h)!r}")
    out = subprocess.run(args, check=True, capture_output=True, text=True).stdout
    a = np.loadtxt(io.StringIO(out), delimiter=",", ndmin=2)
    n = ch.n
    blk = a[:, 1:1 + 4 * n].reshape(-1, n, 4)
    tail = a[:, 1 + 4 * n:]
    return {"t": a[:, 0], "x": blk[:, :, 0], "v": blk[:, :, 1], "F": blk[:, :, 2],
            "mode": blk[:, :, 3].astype(int), "E": tail[:, 0], "W_applied": tail[:, 1],
            "W_friction": tail[:, 2], "D_damping": tail[:, 3], "steps": tail[:, 4],
            "pivot_steps": tail[:, 5], "switches": tail[:, 6]}


def error(run: dict[str, np.ndarray], ref: ChainSolution) -> float:
    """Largest |x - x_ref| over the run's points and blocks (m)."""
    r = ref.evaluate(run["t"])
    return float(np.max(np.abs(run["x"] - r["x"])))


def convergence(ch: Chain, per_period: tuple[int, ...] = (400, 800, 1600, 3200),
                random_dt: Optional[int] = None,
                ref: Optional[ChainSolution] = None) -> tuple[np.ndarray, np.ndarray]:
    """Errors of the located scheme at h = T / per_period over PERIODS periods, and their ratios."""
    T = ch.period
    ref = ref if ref is not None else solve_chain(ch, PERIODS * T)
    errs = []
    for ppp in per_period:
        run = run_driver(ch, PERIODS * T, T / ppp, dt=T / 100, random_dt=random_dt)
        errs.append(error(run, ref))
    e = np.array(errs)
    return e, e[:-1] / e[1:]


def chain_params(ch: Chain, h: float, scheme: str = "located", alpha: float = -0.1) -> dict:
    """The FMU's parameters of a reference chain."""
    p = {k: getattr(ch, k) for k in ("m", "k", "c", "P0", "phi", "N", "mu_s", "chi", "x0", "v0")}
    return {**p, "omega": ch.omega, "k_end": ch.k_end, "c_end": ch.c_end, "h": h, "alpha": alpha, "scheme": scheme}


def belt_run(fmu, ch: Chain, h: float, t: np.ndarray, vb0, changes: dict[int, list[float]]) -> dict:
    """Step on the grid t, the belts vb0 from the start and changes[k] set at t[k]."""
    fmu.start(params={**ch.fmu_params(), "h": h}, inputs={"v_belt": vb0})
    out = {k: [v] for k, v in fmu.outputs().items()}
    for k in range(1, t.size):
        if k - 1 in changes:
            fmu.set_inputs({"v_belt": changes[k - 1]})
        fmu.step_to(float(t[k]))
        for name, v in fmu.outputs().items():
            out[name].append(v)
    return {k: np.array(v) for k, v in out.items()}
