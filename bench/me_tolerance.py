"""Model Exchange: the error against the host's tolerance.

fmpy's CVode integrates the oscillator's FMI 2.0 FMU as Model Exchange over 20 excitation periods
of each work-precision case (bench/cases.py) at relative tolerances 1e-4 ... 1e-10; the table gives,
per case and tolerance, the largest |x - x_exact| at the output points and at the events (the exact
solution: dryfriction.references.exact), the events (mode changes) against the exact solution's
switches, the largest error of the switch times (when the counts agree) and the CPU time of one
run (the best of --repeat, fmpy's overhead included; the FMU unzipped once).

Usage: python bench/me_tolerance.py [--fmu PATH] [--repeat 3] [--periods 20]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from fmpy import extract, simulate_fmu

sys.path.insert(0, str(Path(__file__).resolve().parent))
from cases import CASES  # noqa: E402

from dryfriction.drivers.oscillator import default_fmu_path  # noqa: E402
from dryfriction.references.exact import solve_exact  # noqa: E402

TOLERANCES = (1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)


def run(unzipped: str, case: object, rtol: float, periods: int) -> tuple[np.ndarray, float]:
    """One Model Exchange run; its result and its CPU time (s)."""
    o = case.oscillator  # type: ignore[attr-defined]
    t0 = time.process_time()
    r = simulate_fmu(unzipped, fmi_type="ModelExchange", solver="CVode", relative_tolerance=rtol,
                     stop_time=periods * o.period, output_interval=o.period / 100, start_values=o.as_dict(),
                     output=["x", "mode"])
    return r, time.process_time() - t0


def arguments(argv: list[str] | None, doc: str, fmu: str, periods: int) -> argparse.Namespace:
    """The options of a Model Exchange tolerance table: --fmu (``fmu`` says which), --repeat,
    --periods (default ``periods``); ``doc``'s first paragraph the description."""
    ap = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    ap.add_argument("--fmu", type=Path, default=None, help=f"the {fmu} FMU (default: the build's)")
    ap.add_argument("--repeat", type=int, default=3, help="runs per point, the fastest counted")
    ap.add_argument("--periods", type=int, default=periods, help="excitation periods per run")
    return ap.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    """Print the table (markdown)."""
    a = arguments(argv, __doc__, "FMI 2.0 oscillator", 20)
    fmu = a.fmu or default_fmu_path()
    with tempfile.TemporaryDirectory() as tmp:
        unzipped = extract(str(fmu), unzipdir=tmp)
        print("| case | rtol | max abs x error (m) | events / exact switches | max switch time error (s) | CPU per run (ms) |")
        print("|---|---|---|---|---|---|")
        for case in CASES:
            o = case.oscillator
            ex = solve_exact(o, a.periods * o.period)
            sw = ex.switch_times()
            for rtol in TOLERANCES:
                runs = [run(unzipped, case, rtol, a.periods) for _ in range(max(a.repeat, 1))]
                r, cpu = runs[0][0], min(c for _, c in runs)
                t = r["time"]
                err = float(np.max(np.abs(r["x"] - ex.evaluate(np.minimum(t, ex.t_end))[0])))
                idx = np.nonzero(np.diff(r["mode"]))[0] + 1
                dt = f"{np.max(np.abs(t[idx] - sw)):.1e}" if len(idx) == len(sw) else "-"
                print(f"| {case.name} | {rtol:.0e} | {err:.1e} | {len(idx)} / {len(sw)} | {dt} | {1e3 * cpu:.1f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
