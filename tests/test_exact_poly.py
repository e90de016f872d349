"""The exact scheme with inputs that vary as polynomials over each communication step (FMI input
derivatives; fmu_src/models/oscillator/exact.c, dfo_exact_advance_poly), driven by the C harness
tests/c/test_exact_poly (run mode), against the independent 40-digit reference of
tests/poly_reference.py (mpmath closed form with the polynomial particular solution, sampled event
search): ramp and quadratic F_ext and N_ext, stick-slip with several breakaways and stops, chi < 1,
= 1, > 1, a normal force that vanishes (and returns), undamped, critically and over-damped and
near-resonant blocks, k = 0 with c = 0 and c > 0, one polynomial cut into other communication steps.
Asserted: x and v at every communication point, the events (count, kinds, times), and the
observables (extremes, stick time, friction work)."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

from poly_reference import Solved, solve_case
from refcache import RefCache

ROOT = Path(__file__).resolve().parents[1]
DRIVER = Path(os.environ.get("DFO_POLY_DRIVER", ROOT / "build" / "tests" / "c" / "test_exact_poly"))
TOL = 1e-13        # x, v: max error over the motion's size (measured: 1.7e-16 ... 1.1e-14)
T_TOL = 1e-14      # event times, relative to the run's length (measured: below 2e-15)
W_TOL = 1e-13      # friction work, relative (measured: below 1.2e-15)

BASE = dict(m=1.0, k=1.0, c=0.05, P0=1.0, omega=0.5, phi=0.0, N=0.4, mu_s=1.0, chi=0.7, x0=0.3, v0=0.5)

# name: (parameters, F_ext polynomial (F0, F1, F2), N_ext polynomial, t_end, communication steps)
CASES = {
    "ramp F_ext, stick-slip": ({}, (0.02, 0.01, 0.0), (0, 0, 0), 60.0, 20),
    "ramp F_ext, one step": ({}, (0.0, -0.015, 0.0), (0, 0, 0), 50.0, 1),
    "ramp N_ext, stick-slip": ({}, (0, 0, 0), (0.05, 0.004, 0.0), 60.0, 20),
    "quadratic F_ext and N_ext": ({}, (0.02, 0.01, -4e-4), (0.05, 0.004, -2e-4), 60.0, 20),
    "quadratic, chi = 1": (dict(chi=1.0), (0.0, 0.02, -1e-3), (0.0, -0.003, 1e-4), 60.0, 13),
    "quadratic, chi = 0.3, phase, units": (dict(m=2.0, k=3.0, c=0.2, P0=-2.5, omega=0.9, phi=1.1, N=1.5, chi=0.3,
                                                mu_s=0.6), (0.1, -0.05, 0.004), (0.2, 0.02, -0.001), 40.0, 7),
    "F_ext drift through the limit": (dict(N=0.6), (0.0, 0.08, 0.0), (0, 0, 0), 30.0, 10),
    "normal force ramps to 0": (dict(N=0.8), (0, 0, 0), (0.0, -0.04, 0.0), 30.0, 10),
    "over-damped": (dict(c=3.0, P0=2.0), (0.0, 0.05, 0.0), (0.0, 0.01, 0.0), 40.0, 10),
    "near resonance, light damping": (dict(c=0.01, omega=1.005, N=0.2), (0.0, 0.01, 0.0), (0.0, 0.002, 0.0), 60.0, 10),
    "chi = 1.5 (breakaways at zero acceleration)": (dict(chi=1.5, mu_s=0.5), (0.0, 0.01, 0.0), (0.0, 0.004, 0.0),
                                                     60.0, 10),
    "undamped": (dict(c=0.0, omega=0.7), (0.0, 0.01, -2e-4), (0.0, 0.004, 0.0), 60.0, 10),
    "critically damped": (dict(c=2.0, P0=2.0), (0.0, 0.02, 0.0), (0.0, 0.004, 0.0), 40.0, 5),
    "normal force through 0 and back": (dict(N=0.3), (0, 0, 0), (0.0, -0.04, 0.003), 40.0, 4),
    "no spring, c > 0, chi = 1.5": (dict(k=0.0, c=0.2, chi=1.5, mu_s=0.3, v0=0.0), (0.0, 0.01, 0.0),
                                    (0.0, 0.004, 0.0), 40.0, 10),
    "no spring, c > 0, ramp F_ext": (dict(k=0.0, c=0.3, N=0.25), (0.0, 0.01, 0.0), (0, 0, 0), 60.0, 20),
    "no spring, c = 0, quadratic F_ext and N_ext": (dict(k=0.0, c=0.0, N=0.3, v0=0.0), (0.02, 0.005, -3e-4),
                                                    (0.05, 0.004, -2e-4), 60.0, 20),
    "no spring, c > 0, normal force ramps to 0": (dict(k=0.0, c=0.2, N=0.6, v0=0.0), (0.05, 0.0, 0.0),
                                                  (0.0, -0.03, 0.0), 40.0, 8),
}


def run_driver(params: dict, F, Nx, t_end: float, steps: int, window=None) -> dict:
    args = [str(DRIVER), "run", f"t_end={t_end!r}", f"steps={steps}"]
    if window:
        args += [f"obs_start={window[0]!r}", f"obs_stop={window[1]!r}"]
    args += [f"{k}={v!r}" for k, v in params.items()]
    args += [f"F0={F[0]!r}", f"F1={F[1]!r}", f"F2={F[2]!r}", f"Next0={Nx[0]!r}", f"N1={Nx[1]!r}", f"N2={Nx[2]!r}"]
    out = subprocess.run(args, capture_output=True, text=True, check=True).stdout.splitlines()
    pts = np.array([[float(w) for w in line.split()[1:]] for line in out if line.startswith("point")])
    sw = [(float(line.split()[1]), int(line.split()[3]), int(line.split()[4]))
          for line in out if line.startswith("switch")]
    obs = [float(w) for w in next(line for line in out if line.startswith("obs")).split()[1:]]
    return dict(t=pts[:, 0], x=pts[:, 1], v=pts[:, 2], mode=pts[:, 3].astype(int), switches=sw, obs=obs)


#: the observation window of test_friction_work_in_a_window and its cases (their reference's work in
#: it solved with the case)
WINDOW = (10.3, 47.9)
WINDOW_CASES = ["quadratic F_ext and N_ext", "no spring, c = 0, quadratic F_ext and N_ext"]


@pytest.fixture(scope="module")
def solved(refcache: RefCache):
    """The reference of every case, solved once (about 1.5 s each with its friction work: kept in the
    pytest cache, conftest.refcache)."""
    cache: dict[str, Solved] = {}

    def get(name: str) -> Solved:
        if name not in cache:
            kw, F, Nx, t_end, _ = CASES[name]
            cache[name] = refcache.call(solve_case, {**BASE, **kw}, F, Nx, t_end,
                                         windows=(WINDOW,) if name in WINDOW_CASES else ())
        return cache[name]
    return get


@pytest.mark.parametrize("name", list(CASES))
def test_against_reference(name, solved):
    kw, F, Nx, t_end, steps = CASES[name]
    run = run_driver({**BASE, **kw}, F, Nx, t_end, steps)
    sol = solved(name)
    ref = sol.ref
    xr, vr, mr = ref.evaluate(list(run["t"]))
    xr, vr = np.array(xr), np.array(vr)
    ex = np.abs(run["x"] - xr).max() / max(np.abs(xr).max(), 1e-300)
    ev = np.abs(run["v"] - vr).max() / max(np.abs(vr).max(), 1e-300)
    assert ex < TOL and ev < TOL, (name, ex, ev)
    assert list(run["mode"]) == list(mr)
    # the events: the same kinds in the same order, at the same times
    ev_ref = sol.events
    if not any(seg.free for seg in ref.segments):
        assert [(a, b) for _, a, b in run["switches"]] == [(a, b) for _, a, b in ev_ref]
        dt = max(abs(t - tr) for (t, _, _), (tr, _, _) in zip(run["switches"], ev_ref))
        assert dt < T_TOL * t_end, (name, dt)
        assert len(ev_ref) >= 3
    # the observables over the whole run
    x_max, x_min, t_stuck, E, transitions = run["obs"]
    xr_max, xr_min = sol.extremes
    scale = max(abs(float(xr_max)), abs(float(xr_min)))
    assert abs(x_max - float(xr_max)) < TOL * scale and abs(x_min - float(xr_min)) < TOL * scale
    assert abs(t_stuck - float(sol.stuck_time)) < T_TOL * t_end * 10
    W = float(sol.friction_work)
    assert abs(E - W) < W_TOL * W, (name, E, W)


def test_cases_cover_the_features(solved):
    """Several breakaways and stops in the stick-slip cases; a piece without friction; a varying N in
    a slide (the work is then an integral)."""
    refs = {name: solved(name) for name in ("ramp F_ext, stick-slip", "quadratic F_ext and N_ext",
                                            "normal force ramps to 0")}
    for name in ("ramp F_ext, stick-slip", "quadratic F_ext and N_ext"):
        kinds = [(a, b) for _, a, b in refs[name].events]
        assert sum(1 for a, b in kinds if a == 0) >= 4, name   # breakaways
        assert sum(1 for a, b in kinds if b == 0) >= 4, name   # stops into stick
    assert any(seg.free for seg in refs["normal force ramps to 0"].ref.segments)


def test_one_polynomial_any_steps():
    """One polynomial input cut into 1, 3, 40 or 250 communication steps (the host re-expanding it at
    each point): the same motion to rounding, the same events."""
    kw, F, Nx, t_end, _ = CASES["quadratic F_ext and N_ext"]
    runs = [run_driver({**BASE, **kw}, F, Nx, t_end, n) for n in (1, 3, 40, 250)]
    last = [(r["x"][-1], r["v"][-1]) for r in runs]
    for (x, v) in last[1:]:
        assert abs(x - last[0][0]) < 1e-13 and abs(v - last[0][1]) < 1e-13
    kinds = [[(a, b) for _, a, b in r["switches"]] for r in runs]
    assert all(k == kinds[0] for k in kinds)


@pytest.mark.parametrize("name", WINDOW_CASES)
def test_friction_work_in_a_window(name, solved):
    """The observation window's edges cut slides (both edges fall inside one, in both cases): the
    work of the parts inside (exactly by parts at k > 0, by quadrature at k = 0) against the
    reference's integral over the window."""
    kw, F, Nx, t_end, steps = CASES[name]
    run = run_driver({**BASE, **kw}, F, Nx, t_end, steps, WINDOW)
    W = float(solved(name).window_work[WINDOW])
    assert abs(run["obs"][3] - W) < W_TOL * W, (run["obs"][3], W)
