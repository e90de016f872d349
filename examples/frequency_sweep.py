"""A frequency sweep in physical units: the steady-state amplitude (m) of a 0.5 kg block on a
2000 N/m spring with 0.3 % damping, pushed by 10 N at 5-15 Hz, pressed on its support by 20 N
(mu_s = 0.3, mu_k = 0.2). Every point is the periodic orbits there (solved by Newton shooting on the
exact map, with their stability), not a transient waited for.

    python examples/frequency_sweep.py [--num 21] [--out results/example_sweep]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from dryfriction import Oscillator
from dryfriction.analysis.response import frequency_response, plot_response


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--num", type=int, default=21, help="number of frequencies")
    ap.add_argument("--out", type=Path, default=Path("results/example_sweep"))
    args = ap.parse_args()

    block = Oscillator.physical(m=0.5, k=2000.0, zeta=0.003, P0=10.0, f=10.0, N=20.0, mu_s=0.3, mu_k=0.2)
    print(f"natural frequency {block.f_n_hz:.4f} Hz, breakaway force {block.breakaway:.1f} N")
    ds = frequency_response(block, np.linspace(5.0, 15.0, args.num))
    for i, f in enumerate(ds["f_hz"].values):
        if not ds["converged"].values[i]:
            print(f"{f:6.2f} Hz  no stable orbit (not converged)")
        for j in range(int(ds["n_orbits"].values[i])):
            a, s = ds["amplitude_m"].values[i, j], ds["stick_fraction"].values[i, j]
            kind = "stable (converged)" if ds["stable"].values[i, j] else "unstable"
            print(f"{f:6.2f} Hz  amplitude {1000 * a:8.3f} mm  stuck {100 * s:5.1f} %  {kind}")
    png = plot_response(ds, args.out / "sweep.png")
    print(f"wrote {png}")


if __name__ == "__main__":
    main()
