"""Model Exchange of the chain: the error against the host's tolerance.

fmpy's CVode integrates the FMI 3.0 chain (n blocks set in Configuration Mode,
dryfriction.drivers.chain_me) as Model Exchange over 10 excitation periods of each stick-slip case
of n = 3 ... 5 blocks (the Model Exchange tests' cases) at relative tolerances 1e-6 ... 1e-12; the
table gives, per case and tolerance, the largest |x - x_ref| over the blocks and the output points
against the event-driven reference (dryfriction.references.chain), the switches (mode changes of
the blocks with friction) against the reference's, the largest error of the switch times (when the
counts agree) and the CPU time of one run (the best of --repeat, fmpy's overhead included).

Usage: python bench/me_chain_tolerance.py [--fmu PATH] [--repeat 3] [--periods 10]
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT / "bench"))
from me_tolerance import arguments  # noqa: E402
from test_model_exchange import CHAIN_ME_CASES, _chain_switches  # noqa: E402

from dryfriction.drivers.chain import default_chain_fmu3  # noqa: E402
from dryfriction.drivers.chain_me import simulate_chain_me  # noqa: E402
from dryfriction.references.chain import solve_chain  # noqa: E402

TOLERANCES = (1e-6, 1e-8, 1e-10, 1e-12)


def main(argv: list[str] | None = None) -> int:
    """Print the table (markdown)."""
    a = arguments(argv, __doc__, "FMI 3.0 chain", 10)
    fmu = a.fmu or default_chain_fmu3()
    print("| case | n | rtol | max abs x error (m) | switches / reference's | max switch time error (s) | CPU per run (ms) |")
    print("|---|---|---|---|---|---|---|")
    for name, ch in CHAIN_ME_CASES.items():
        t_end = a.periods * ch.period
        ref = solve_chain(ch, t_end)
        t_ref = np.sort([e[0] for e in ref.events])
        for rtol in TOLERANCES:
            cpu = []
            for _ in range(max(a.repeat, 1)):
                t0 = time.process_time()
                r = simulate_chain_me(ch, t_end, fmu, relative_tolerance=rtol, output_interval=ch.period / 50,
                                      record_events=True)
                cpu.append(time.process_time() - t0)
            x, modes = np.asarray(r["x"]), np.asarray(r["mode"])
            err = float(np.max(np.abs(x - ref.evaluate(r["time"])["x"])))
            rows, n = _chain_switches(modes, ch)
            dt = "-"
            if n == len(t_ref):
                per_row = (np.diff(modes[:, np.asarray(ch.N) > 0], axis=0)[rows - 1] != 0).sum(axis=1)
                dt = f"{np.max(np.abs(np.sort(np.repeat(r['time'][rows], per_row)) - t_ref)):.1e}"
            print(f"| {name} | {ch.n} | {rtol:.0e} | {err:.1e} | {n} / {len(t_ref)} | {dt} | {1e3 * min(cpu):.1f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
