"""Model Exchange: the error against the host's tolerance.

fmpy's CVode integrates the oscillator's FMI 2.0 FMU as Model Exchange over 20 excitation periods
of each work-precision case (bench/cases.py) at relative tolerances 1e-4 ... 1e-10; the table gives,
per case and tolerance, the largest |x - x_exact| at the output points and at the events (the exact
solution: dryfriction.references.exact), the events (mode changes) against the exact solution's
switches, the largest error of the switch times (when the counts agree) and the CPU time of one
run (the best of --repeat, fmpy's overhead included; the FMU unzipped once).

With --control, instead, the control table: the same host on the same oscillators without friction (N = 0: a
linear oscillator, no event at all), its largest x and v errors against the closed form and the
largest error of its turning points (v = 0, found on CVode's output by cubic Hermite interpolation
of v and a at period / 4000): the error of the smooth motion the host makes by itself, which bounds
how well any switch of the friction oscillator (a stop is a turning point) can be timed.

Usage: python bench/me_tolerance.py [--fmu PATH] [--repeat 3] [--periods 20] [--control]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import dataclasses

import numpy as np
from fmpy import extract, simulate_fmu
from scipy.interpolate import CubicHermiteSpline
from scipy.optimize import brentq

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
    ap.add_argument("--control", action="store_true",
                    help="the frictionless control instead: the host's own error of the smooth motion")
    return ap.parse_args(argv)


def control(unzipped: str, case: object, rtol: float, periods: int) -> tuple[float, float, float]:
    """The frictionless twin of a case (N = 0) under the same host: the largest x and v errors
    against the closed form and the largest turning-point time error."""
    o = dataclasses.replace(case.oscillator, N=0.0)  # type: ignore[attr-defined]
    t_end = periods * o.period
    ex = solve_exact(o, t_end)
    r = simulate_fmu(unzipped, fmi_type="ModelExchange", solver="CVode", relative_tolerance=rtol,
                     stop_time=t_end, output_interval=o.period / 4000, start_values=o.as_dict(),
                     output=["x", "v", "a"])
    t, v = r["time"], r["v"]
    xe, ve = ex.evaluate(np.minimum(t, ex.t_end))[:2]
    hermite = CubicHermiteSpline(t, v, r["a"])
    turn = np.nonzero((v[1:] * v[:-1] < 0.0) & (np.sign(ve[1:]) != np.sign(ve[:-1])))[0]

    def v_exact(tt: float) -> float:
        return float(ex.evaluate(np.array([tt]))[1][0])

    dt = [abs(brentq(hermite, t[k], t[k + 1], xtol=1e-15) - brentq(v_exact, t[k], t[k + 1], xtol=1e-15))
          for k in turn]
    return float(np.max(np.abs(r["x"] - xe))), float(np.max(np.abs(v - ve))), max(dt, default=float("nan"))


def main(argv: list[str] | None = None) -> int:
    """Print the table (markdown)."""
    a = arguments(argv, __doc__, "FMI 2.0 oscillator", 20)
    fmu = a.fmu or default_fmu_path()
    with tempfile.TemporaryDirectory() as tmp:
        unzipped = extract(str(fmu), unzipdir=tmp)
        if a.control:
            print("| case without friction | rtol | max abs x error (m) | max abs v error (m/s) | max turning-point time error (s) |")
            print("|---|---|---|---|---|")
            for case in CASES:
                for rtol in (1e-8, 1e-10, 1e-12):
                    ex_, ev_, et_ = control(unzipped, case, rtol, a.periods)
                    print(f"| {case.name} | {rtol:.0e} | {ex_:.1e} | {ev_:.1e} | {et_:.1e} |")
            return 0
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
