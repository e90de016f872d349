#!/usr/bin/env python3
"""docs/img/fmi3_events.png: x(t) of the FMI 3.0 FMU with its stick/slip switches, sampled by a
coarse master (communication step 0.2 s) without and with early return.

    python scripts/plot_fmi3_events.py [--out docs/img/fmi3_events.png] [--dt 0.2] [--periods 2]

Needs the FMI 3.0 FMU (build/fmi3/DryFrictionOscillator.fmu, or DFO_FMU3).
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from dryfriction.references.exact import solve_exact  # noqa: E402
from dryfriction.drivers.oscillator3 import OscillatorFMU3  # noqa: E402
from dryfriction.params import Oscillator  # noqa: E402


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="docs/img/fmi3_events.png")
    ap.add_argument("--dt", type=float, default=0.2, help="the master's communication step, s")
    ap.add_argument("--periods", type=float, default=2.0, help="excitation periods shown")
    a = ap.parse_args(argv)
    p = Oscillator()
    T = 2 * math.pi / p.omega
    t_end = a.periods * T
    try:
        with OscillatorFMU3({"h": T / 1000}) as fmu:
            fine = fmu.run(t_end, T / 1000, outputs=("x",))
        with OscillatorFMU3({"h": T / 1000}) as fmu:
            coarse = fmu.run(t_end, a.dt, outputs=("x",))
        with OscillatorFMU3({"h": T / 1000}, early_return=True) as fmu:
            early = fmu.run(t_end, a.dt, outputs=("x", "mode"))
    except (FileNotFoundError, OSError) as e:
        print(f"plot_fmi3_events: {e}", file=sys.stderr)
        return 1
    ex = solve_exact(p, t_end)
    fig, ax = plt.subplots(figsize=(10, 4.2), dpi=120)
    ax.plot(fine.time, 1e3 * fine.values["x"], color="0.75", lw=2.5, label="x(t), fine sampling")
    ax.plot(coarse.time, 1e3 * coarse.values["x"], "o--", color="tab:blue", ms=4, lw=1,
            label=f"coarse master, dt = {a.dt:g} s")
    ax.plot(early.time, 1e3 * early.values["x"], "-", color="tab:red", lw=1, label="coarse master + early return")
    sw = early.switch_times
    xs = [1e3 * early.values["x"][list(early.time).index(t)] for t in sw]
    marker = {"breakaway": "^", "stop": "s", "reversal": "D"}
    for kind in ("breakaway", "stop", "reversal"):
        pts = [(t, x) for t, x, s in zip(sw, xs, early.switches) if s.kind == kind]
        if pts:
            ax.plot(*zip(*pts), marker[kind], color="tab:red", ms=7, mfc="none", mew=1.5, label=f"switch: {kind}")
    for t in ex.switch_times():
        ax.axvline(t, color="0.6", lw=0.6, ls=":")
    ax.set_xlabel("t (s)   (dotted: the exact solution's switch times)")
    ax.set_ylabel("x (mm)")
    ax.set_title("FMI 3.0: early return lands the master on every stick/slip switch")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.tight_layout()
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(a.out)
    print(f"wrote {a.out}: {len(sw)} switches, {len(coarse.time)} coarse samples, {len(early.time)} with early return")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
