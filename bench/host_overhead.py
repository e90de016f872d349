"""Host time per reused run, from Python: a short run (lambda 0.5, mu_s sigma 0.4, chi 0.7, located,
h = T/50, one period, read x) through the ``OscillatorFMU2`` API (start, step_to, get) and one row of
``BatchRunner.run`` (reset ... doStep, read the observables). Prints the minimum over repetitions in
microseconds; the FMU's own work is the same in both, so differences between versions of the
Python layer are its overhead.

    python bench/host_overhead.py [--reps N] [--fmu PATH]
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable

import numpy as np

from dryfriction.cli.options import make_parser
from dryfriction.drivers.oscillator import OscillatorFMU2, Settings, default_fmu_path
from dryfriction.params import Oscillator
from dryfriction.sweep.runner import PARAM_COLUMNS, BatchRunner


def best_us(fn: Callable[[], object], reps: int) -> float:
    best = float("inf")
    for _ in range(reps):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best * 1e6


def main(argv: list[str] | None = None) -> int:
    ap = make_parser("host_overhead.py", __doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=3000)
    ap.add_argument("--fmu", default=None)
    args = ap.parse_args(argv)
    p = Oscillator.from_nondimensional(lam=0.5, mu_s_sigma=0.4, chi=0.7)
    st = Settings(h=p.period / 50, alpha=-0.1, scheme="located")
    with OscillatorFMU2(args.fmu) as fmu:
        def api() -> float:
            fmu.start(p, st)
            fmu.step_to(p.period)
            return fmu.get(["x"])["x"]

        api_us = best_us(api, args.reps)
    runner = BatchRunner(args.fmu or str(default_fmu_path()))
    row = dict(p.as_dict(), h=st.h, alpha=st.alpha, t_obs_start=0.0, t_obs_stop=p.period, t_stop=p.period,
               v_s=st.v_s, delta=st.delta)
    table = np.array([[row[c] for c in PARAM_COLUMNS]] * 100)
    batch_us = best_us(lambda: runner.run(table), max(args.reps // 100, 5)) / 100
    runner.close()
    print(f"OscillatorFMU2 API run: {api_us:.2f} us")
    print(f"BatchRunner row:       {batch_us:.2f} us")
    return 0


if __name__ == "__main__":
    sys.exit(main())
