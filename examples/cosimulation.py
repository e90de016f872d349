"""A co-simulation loop with feedback through F_ext: a master (here, a velocity feedback
controller F_ext = -g v, an active damper) reads the FMU's outputs at every communication point
and sets its input for the next step. Inputs are held over a communication step and stay set
until changed; they are part of the FMU state.

The loop is checked against the same oscillator with the damper built in (c = g): with the
feedback sampled every T/200 the amplitudes agree to a few parts in a thousand.

    python examples/cosimulation.py [--gain 2.0]
"""

from __future__ import annotations

import argparse

import numpy as np

from dryfriction import Oscillator
from dryfriction.drivers.oscillator import OscillatorFMU2, Settings


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--gain", type=float, default=2.0, help="feedback gain g, N s/m")
    ap.add_argument("--periods", type=int, default=40)
    args = ap.parse_args()

    block = Oscillator.physical(m=0.5, k=2000.0, P0=10.0, f=10.0, N=20.0, mu_s=0.3, mu_k=0.2)
    dt = block.period / 200                       # communication step
    n = args.periods * 200
    with OscillatorFMU2() as fmu:
        fmu.start(block, Settings(h=0.0, extra={"F_ext": 0.0}))   # h = 0: the FMU derives its step
        x = np.empty(n + 1)
        for j in range(n + 1):
            y = fmu.get(("x", "v"))
            x[j] = y["x"]
            if j < n:
                fmu.set({"F_ext": -args.gain * y["v"]})     # held over the next communication step
                fmu.step_to((j + 1) * dt)
        looped = 0.5 * (x[-201:].max() - x[-201:].min())

        ref = fmu.observables(block.with_(c=args.gain), args.periods * block.period,
                              (args.periods - 1) * block.period, settings=Settings(h=0.0))
        built_in = 0.5 * (ref["x_max"] - ref["x_min"])
    print(f"amplitude with the feedback loop (every T/200): {1000 * looped:.4f} mm")
    print(f"amplitude with the damper built in (c = {args.gain} N s/m): {1000 * built_in:.4f} mm")
    rel = abs(looped - built_in) / built_in
    print(f"relative difference {rel:.2e}")
    if rel > 0.02:
        raise SystemExit(f"the co-simulation loop and the built-in damper differ by {rel:.1%}")


if __name__ == "__main__":
    main()
