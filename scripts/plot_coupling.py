#!/usr/bin/env python3
"""results/coupling_order.png: the error of the split two-block chain (two oscillator FMUs coupled by
dryfriction.cosim through the chain's middle spring and damper) against the macro step H, for the
inputs held (zero-order hold), held at the mean of their Taylor polynomial from the outputs'
derivatives, and sent as input derivatives (FMI 2.0) or at the FMI 3.0 FMUs' input points; the
error is max |x - x_ref| over ten periods against the chain's event-driven reference
(dryfriction.references.chain). The case of tests/test_cosim.py; prints the numbers.

    python scripts/plot_coupling.py [--out results/coupling_order.png] [--periods 10]
"""

from __future__ import annotations

import argparse
import dataclasses
import math
from pathlib import Path
from typing import Any

import numpy as np

from dryfriction.references.chain import Chain, solve_chain
from dryfriction.cosim import CosimResult, System
from dryfriction.cosim.split import split_chain2
from dryfriction.drivers.oscillator import OscillatorFMU2, Settings
from dryfriction.drivers.oscillator3 import OscillatorFMU3

CASE: dict[str, Any] = dict(m=1.0, k=1.0, c=[0.05, 0.1], P0=[1.0, 0.0], N=[0.8, 0.5], mu_s=0.5, chi=0.7, omega=0.6)
DIVISIONS = (25, 50, 100, 200, 400, 800)


def split_run(fmi: int, t_stop: float, H: float, **kw: Any) -> CosimResult:
    b1, b2, element = split_chain2(CASE)
    if fmi == 3:
        cb = (lambda t, can: False) if kw.get("inputs") == "derivatives" else None
        f1 = OscillatorFMU3(params=dataclasses.asdict(b1), intermediate=cb)
        f2 = OscillatorFMU3(params=dataclasses.asdict(b2), intermediate=cb)
    else:
        f1, f2 = OscillatorFMU2(), OscillatorFMU2()
        f1.start(b1, Settings(h=0.0))
        f2.start(b2, Settings(h=0.0))
    with f1, f2:
        s = System()
        s.add("b1", f1)
        s.add("b2", f2)
        s.couple(element)
        return s.run(t_stop, H, **kw)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="results/coupling_order.png")
    ap.add_argument("--periods", type=int, default=10)
    args = ap.parse_args()

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.ticker
    import matplotlib.pyplot as plt

    T = 2 * math.pi / CASE["omega"]
    t_stop = args.periods * T
    ref = solve_chain(Chain.make(2, **CASE), t_stop)
    caps = OscillatorFMU2().inst.capabilities
    modes: list[tuple[str, int, dict[str, Any]]] = [
        ("zero-order hold", 2, {}),
        ("held at the extrapolated mean (v, a)", 2, {"inputs": "extrapolate", "source": "outputs"}),
    ]
    if caps.can_interpolate_inputs:
        modes.append(("input derivatives (FMI 2.0)", 2, {"inputs": "derivatives"}))
        modes.append(("inputs at the input points (FMI 3.0)", 3, {"inputs": "derivatives"}))
    H = np.array([T / n for n in DIVISIONS])
    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    for label, fmi, kw in modes:
        err = []
        for h in H:
            res = split_run(fmi, t_stop, float(h), **kw)
            x = np.column_stack([res["b1.x"], res["b2.x"]])
            err.append(float(np.max(np.abs(x - ref.evaluate(res.t)["x"]))))
        e = np.array(err)
        order = np.log2(e[:-1] / e[1:])
        print(f"{label}: " + " ".join(f"T/{n}: {v:.4g}" for n, v in zip(DIVISIONS, e))
              + "; orders " + " ".join(f"{o:.2f}" for o in order))
        ax.loglog(H / T, e, "o-", label=label)
    for p, style in ((1, ":"), (2, "--")):
        ax.loglog(H / T, 0.5 * (H / H[-1]) ** p * (1e-2 if p == 1 else 2e-5) / 0.5, "k" + style, lw=0.8,
                  label=f"order {p}")
    ax.set_xticks(H / T, [f"1/{n}" for n in DIVISIONS])
    ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax.set_xlabel("macro step H / T")
    ax.set_ylabel("max |x - x_chain| over %d periods (m)" % args.periods)
    ax.set_title("two-block chain split in two FMUs, coupled by dryfriction.cosim")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
