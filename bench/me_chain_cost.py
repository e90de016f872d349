"""Model Exchange of the chain: the cost of a host's calls per block.

The FMI 3.0 chain with n blocks (n set in Configuration Mode; every block with friction, an
excitation on every block) in continuous-time mode; through ctypes, the best of 3 loops of: setTime
and setContinuousStates (the state moved: nothing is evaluated), then either
getContinuousStateDerivatives (the friction forces and the engine's held solve, once per state)
or getEventIndicators. The table gives each loop's time per call and per block; the calls' own
overhead (ctypes, the glue's checks) is the first row's (n = 10).

Usage: python bench/me_chain_cost.py [--fmu PATH] [--sizes 10,100,1000,4000]
"""

from __future__ import annotations

import argparse
import shutil
import sys
import time
from ctypes import c_double, c_int, c_size_t, c_void_p
from pathlib import Path
from typing import Any, Callable

import numpy as np
from fmpy import extract
from fmpy.fmi3 import FMU3Model

from dryfriction.drivers.chain import default_chain_fmu3
from dryfriction.drivers.chain_me import chain_me_description


def best_of(call: Callable[[], Any], reps: int) -> float:
    """The fastest of 3 loops of reps calls, per call (s)."""
    best = float("inf")
    for _ in range(3):
        t0 = time.perf_counter()
        for _ in range(reps):
            call()
        best = min(best, (time.perf_counter() - t0) / reps)
    return best


def measure(fmu: Path, unzipped: str, n: int) -> dict[str, float]:
    """The time per call (s) of the three loops on a chain of n blocks."""
    md = chain_me_description(fmu, n)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    f = FMU3Model(guid=md.guid, unzipDirectory=unzipped, modelIdentifier="DryFrictionChain", instanceName="cost")
    f.instantiate()
    try:
        f.enterConfigurationMode()
        f.setUInt64([vr["n"]], [n])
        f.exitConfigurationMode()
        f.setFloat64([vr["N"]], [0.5] * n)
        f.setFloat64([vr["P0"]], [1.0] * n)
        f.enterInitializationMode()
        f.exitInitializationMode()
        f.updateDiscreteStates()
        f.enterContinuousTimeMode()
        x, dx, z = np.zeros(2 * n), np.zeros(2 * n), np.zeros(2 * n)
        dll, comp = f.dll, f.component
        get_x, get_dx, get_z, set_x = (dll.fmi3GetContinuousStates, dll.fmi3GetContinuousStateDerivatives,
                                       dll.fmi3GetEventIndicators, dll.fmi3SetContinuousStates)
        for fn in (get_x, get_dx, get_z, set_x):
            fn.argtypes, fn.restype = [c_void_p, c_void_p, c_size_t], c_int
        set_t = dll.fmi3SetTime
        set_t.argtypes, set_t.restype = [c_void_p, c_double], c_int
        get_x(comp, x.ctypes.data, 2 * n)
        px, pdx, pz, nx = x.ctypes.data, dx.ctypes.data, z.ctypes.data, 2 * n
        reps = max(200, 200000 // n)
        return {"set": best_of(lambda: (set_t(comp, 0.1), set_x(comp, px, nx)), reps),
                "derivatives": best_of(lambda: (set_t(comp, 0.1), set_x(comp, px, nx), get_dx(comp, pdx, nx)), reps),
                "indicators": best_of(lambda: (set_t(comp, 0.1), set_x(comp, px, nx), get_z(comp, pz, nx)), reps)}
    finally:
        f.terminate()
        f.freeInstance()


def main(argv: list[str] | None = None) -> int:
    """Print the table (markdown)."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--fmu", type=Path, default=None, help="the FMI 3.0 chain FMU (default: the build's)")
    ap.add_argument("--sizes", default="10,100,1000,4000", help="the numbers of blocks, comma-separated")
    a = ap.parse_args(argv)
    fmu = a.fmu or default_chain_fmu3()
    unzipped = extract(str(fmu))
    try:
        print("| n | set time and states (us) | + getDerivatives (us) | + getEventIndicators (us) "
              "| derivatives per block (ns) | indicators per block (ns) |")
        print("|---|---|---|---|---|---|")
        for n in (int(s) for s in a.sizes.split(",")):
            t = measure(fmu, unzipped, n)
            print(f"| {n} | {1e6 * t['set']:.2f} | {1e6 * t['derivatives']:.2f} | {1e6 * t['indicators']:.2f} "
                  f"| {1e9 * (t['derivatives'] - t['set']) / n:.1f} | {1e9 * (t['indicators'] - t['set']) / n:.1f} |")
    finally:
        shutil.rmtree(unzipped, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
