#!/usr/bin/env python3
"""pyHarm (harmonic balance with its DLFT or Jenkins friction element) against the exact periodic orbit.

    python bench/pyharm_peer.py [--harmonics 5,10,20] [--nti 256] [--repeats 3] [--json]
    python bench/pyharm_peer.py --case two_mass [--harmonics 5,10,20,40] [--nti 128] [--omegas 1.0,1.4]
    python bench/pyharm_peer.py --case bladed_disk [--harmonics 5,10,20,40] [--omegas 1060,1080]

Installs pyHarm (``pip install pyharm-os``, the package index's name) into this Python environment
when it cannot be imported; if that fails, one line on stderr and exit status 1. pyHarm is not a
dependency of the package and has no CI stage (a peer measured by hand, as the Siconos one). Its
dependencies pin versions the package's environment may not have (pandas 2): a separate virtual
environment is the safe place (bench/pyharm_system_results.md says how the numbers were made).

``--case oscillator`` (the default): one mass m = 1 kg on a spring k = 1 N/m, damping zeta = 0.01,
excitation P0 = 1 N, Coulomb friction with one coefficient (mu_s = mu_k = 1, N = 0.3 N: mu N / P0 =
0.3), at lambda = omega / w0 = 0.5 (stick-slip), 0.8, 1.0 (resonance), 1.2, 1.5. pyHarm: a 1-dof system
(GOElement for the mass, LinearSpring, LinearDamper, CosinusForcing, DLFTFriction with penalty
``--eps``), ``nh`` harmonics and ``--nti`` time samples (at its defaults, eps 1e3 and 256 samples,
the error stays near 1e-2 off resonance whatever nh: the reversals are located to a sample), one solve at the frequency (the analysis' first point,
from its linear guess; no continuation). Its amplitude is half the peak-to-peak of its Fourier
series sampled 8192 times per period. Ours: ``find_orbits`` (the exact stroboscopic map, residual
1e-12). Error: |A_pyHarm - A_orbit| / A_orbit. Times: wall, min of ``--repeats``, per frequency,
after one warm-up (pyHarm's numba kernels compile on first use); pyHarm's includes building its
system (Maestro), ours the FMU's transients and Newton solves of a cold ``find_orbits`` (one FMU
instance loaded once).

``--case two_mass`` and ``--case bladed_disk``: the structures of :mod:`dryfriction.system.cases`
in pyHarm: one substructure with the system's M, C, K (one node per degree of freedom), a GOForcing
per loaded DOF (amplitude hypot(F_c, F_s), phase atan2(F_s, F_c): F_c cos + F_s sin), a Jenkins
connector (pyHarm's AFT Jenkins element: tangential stiffness k, limit mu N0) per contact between
its two DOFs; ``nh`` harmonics, ``--nti`` time samples (default pyHarm's own, 128), one solve at each
frequency from pyHarm's linear guess (the FRF analysis' first point, its default solver). Its
amplitude per DOF is half the peak-to-peak of its Fourier series (8192 samples per period); the
error is |A_pyHarm - A_ref| / A_ref on the case's DOF of interest (the two-mass case's mass 0, the
disk's blade tip of sector 0, DOF 2), with pyHarm's own convergence flag and residual norm. CPU
time per frequency point (process time: all threads), min of ``--repeats``, after one warm-up solve
(numba and jax compile on first use: about 40 s).

The references: two-mass, the event-driven reference run long
(:func:`dryfriction.references.system_steady.steady_state`, tolerance ``--ref-tol``, default
1e-10, relative); bladed disk, the located FMU run long from the linear stuck response until its
stroboscopic change over a period is below 1e-9 relative (at its measured contraction, about
0.993 a period, 1.4e-7 from the orbit), at h = T/m and T/2m (``--steps``, default 400), the
amplitude Richardson-extrapolated from the last period's step values (each extreme refined by the
parabola through its three steps), its estimated error |A_h - A_h/2| / 3; then, as a check, the
event-driven reference run ``--ref-periods`` periods (default 2) from the fine run's state, its
last stroboscopic change reported (the ring's undamped contact mode, 224563 rad/s, makes it cost
about 12 s of CPU a period: that is why the bladed disk's reference is the FMU's).
"""

from __future__ import annotations

import contextlib
import importlib
import json
import logging
import math
import subprocess
import sys
import tempfile
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from dryfriction.cli.options import count, make_parser, number

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))
from timing import timed  # noqa: E402  (bench/timing.py)

CASE = dict(m=1.0, k=1.0, zeta=0.01, P0=1.0, N=0.3, mu=1.0)
LAMBDAS = (0.5, 0.8, 1.0, 1.2, 1.5)


def ensure_pyharm() -> Any:
    """pyHarm's Maestro, installed with pip first if needed; exit 1 with one line if impossible."""
    try:
        return importlib.import_module("pyHarm.Maestro").Maestro
    except ImportError:
        pass
    r = subprocess.run([sys.executable, "-m", "pip", "install", "-q", "pyharm-os"], capture_output=True, text=True)
    try:
        if r.returncode != 0:
            raise ImportError(r.stderr.strip().splitlines()[-1] if r.stderr.strip() else f"pip exit {r.returncode}")
        importlib.invalidate_caches()
        return importlib.import_module("pyHarm.Maestro").Maestro
    except ImportError as e:
        print(f"pyharm_peer.py: error: pyHarm (pip install pyharm-os) could not be installed or imported: {e}",
              file=sys.stderr)
        raise SystemExit(1) from None


def pyharm_input(w: float, nh: int, nti: int, eps: float = 1e3) -> dict[str, Any]:
    m, k, P0, N, mu = CASE["m"], CASE["k"], CASE["P0"], CASE["N"], CASE["mu"]
    c = 2.0 * CASE["zeta"] * math.sqrt(k * m)
    con = {"connect": {"block": [0]}, "dirs": [0]}
    return {
        "system": {"type": "Base", "nh": nh, "nti": nti},
        "substructures": {"block": {"type": "onlydofs", "ndofs": 1, "nnodes": 1, "matrix": {}}},
        "connectors": {
            "mass": {"type": "GOElement", "dto": 2, "xo": 1, "k": m, **con},
            "spring": {"type": "LinearSpring", "k": k, **con},
            "damper": {"type": "LinearDamper", "k": c, **con},
            "force": {"type": "CosinusForcing", "amp": P0, **con},
            "friction": {"type": "DLFTFriction", "mu": mu, "N0": N, "eps": eps, **con},
        },
        "analysis": {"frf": {"study": "frf", "puls_inf": w, "puls_sup": 2.0 * w, "verbose": False}},
    }


def fourier_amplitude(x: np.ndarray, nh: int, n: int = 8192) -> float:
    """Half the peak-to-peak of x0 + sum_h a_h cos(h t) + b_h sin(h t) over one period."""
    t = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
    y = np.full(n, float(x[0]))
    for h in range(1, nh + 1):
        y += x[2 * h - 1] * np.cos(h * t) + x[2 * h] * np.sin(h * t)
    return 0.5 * float(y.max() - y.min())


def pyharm_amplitude(Maestro: Any, w: float, nh: int, nti: int, eps: float) -> tuple[float, bool]:
    M = Maestro(pyharm_input(w, nh, nti, eps))
    an = M.nls["frf"]
    an.initialise(None)
    sol = an.SolList[0]
    return fourier_amplitude(np.asarray(sol.x, dtype=float), nh), bool(getattr(sol, "flag_R", True))


#: the structures' frequencies (rad/s): the issue's for the two masses; for the bladed disk (engine
#: order 1) points between the free-ring (1064.0) and the stuck-ring (1090.6) first one-nodal-diameter
#: modes, where the contacts go from stuck to slipping
SYSTEM_OMEGAS = {"two_mass": (1.0, 1.4, 1.8, 2.5), "bladed_disk": (1060.0, 1070.0, 1080.0, 1090.0)}
#: the DOF whose amplitude is compared: mass 0; the blade tip of sector 0
SYSTEM_DOF = {"two_mass": 0, "bladed_disk": 2}


def build_system(case: str, w: float) -> Any:
    """The case's System at the angular frequency w."""
    from dryfriction.system import cases

    return cases.two_mass_jenkins(omega=w) if case == "two_mass" else cases.bladed_disk(omega=w)


def pyharm_system_input(system: Any, w: float, nh: int, nti: int | None) -> dict[str, Any]:
    """pyHarm's input for a System: one substructure with M, C, K; GOForcing per loaded DOF; a
    Jenkins connector per contact (between two DOFs, mu_s = mu_k); the FRF's first point at w."""
    n = system.n
    sub = {"matrix": {"M": np.array(system.M), "C": np.array(system.C), "K": np.array(system.K),
                      "G": np.zeros((n, n))}, "ndofs": 1}
    connectors: dict[str, Any] = {}
    for i in range(n):
        fc, fs = float(system.F_c[i]), float(system.F_s[i])
        if fc or fs:
            connectors[f"F{i}"] = {"type": "GOForcing", "connect": {"s": [i]}, "dirs": [0], "amp": math.hypot(fc, fs),
                                   "dto": 0, "ho": 1, "phi": math.atan2(fs, fc)}
    for j, c in enumerate(system.contacts):
        if c.between is None or c.mu_s != c.mu_k or c.k_t <= 0:
            raise ValueError(f"contacts[{j}]: pyHarm's Jenkins element needs between=(i, j), mu_s = mu_k and k_t > 0")
        # (a list of (substructure, nodes) pairs: the dict form {"s": [i, j]} ties node i to the ground)
        connectors[f"J{j}"] = {"type": "Jenkins", "connect": [("s", [int(c.between[0])]), ("s", [int(c.between[1])])],
                               "dirs": [0], "mu": float(c.mu_k), "N0": float(c.N), "k": float(c.k_t)}
    sysopt: dict[str, Any] = {"type": "Base", "nh": nh}
    if nti is not None:
        sysopt["nti"] = nti
    return {"system": sysopt, "substructures": {"s": sub}, "connectors": connectors,
            "analysis": {"frf": {"study": "frf", "puls_inf": w, "puls_sup": 2.0 * w, "verbose": False}}}


def pyharm_system_solve(Maestro: Any, system: Any, w: float, nh: int, nti: int | None) -> dict[str, Any]:
    """One pyHarm solve at w: the amplitude of every DOF, its convergence flag and residual norm."""
    M = Maestro(pyharm_system_input(system, w, nh, nti))
    an = M.nls["frf"]
    an.initialise(None)
    sol = an.SolList[0]
    x = np.asarray(sol.x, dtype=float)
    ed = M.system.expl_dofs
    amps = np.empty(system.n)
    for i in range(system.n):
        idx = ed.index[(ed["sub"] == "s") & (ed["node_num"] == i) & (ed["dof_num"] == 0)]
        coeff = np.zeros(2 * nh + 1)
        for k in idx:
            h, cs = int(ed.loc[k, "harm"]), ed.loc[k, "cs"]
            coeff[0 if h == 0 else (2 * h - 1 if cs == "c" else 2 * h)] = x[k]
        amps[i] = fourier_amplitude(coeff, nh)
    R = np.asarray(getattr(sol, "R", np.zeros(1)), dtype=float)
    # pyHarm's flags (flag_R, flag_accepted) are True even where its solver stopped at a residual of
    # order 1 (two_mass at omega 1.0): converged here means its residual norm below 1e-6
    res = float(np.linalg.norm(R)) if R.size else float("nan")
    return {"amplitude": amps, "converged": bool(res < 1e-6), "residual": res,
            "pyharm_flags": {"flag_R": bool(getattr(sol, "flag_R", False)),
                             "flag_accepted": bool(getattr(sol, "flag_accepted", False)),
                             "flag_solved": bool(getattr(sol, "flag_solved", False)),
                             "status_solver": str(getattr(sol, "status_solver", ""))}}


def _parabola_extremes(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per column, the max and min of samples of one period (periodic), each refined by the
    parabola through the extreme sample and its two neighbours."""
    out = []
    for sign in (1.0, -1.0):
        y = sign * x
        k = np.argmax(y, axis=0)
        m = y.shape[0]
        cols = np.arange(y.shape[1])
        a, b, c = y[(k - 1) % m, cols], y[k, cols], y[(k + 1) % m, cols]
        den = a - 2 * b + c
        with np.errstate(divide="ignore", invalid="ignore"):
            peak = np.where(den < 0, b - 0.125 * (c - a) ** 2 / den, b)
        out.append(sign * peak)
    return out[0], out[1]


def fmu_long_run(system: Any, m: int, max_periods: int = 4000, chunk: int = 100, tol: float = 1e-9,
                 start: tuple[np.ndarray, np.ndarray] | None = None) -> dict[str, Any]:
    """The located FMU at h = T/m from ``start`` (x0, v0; default the linear stuck response, else the
    sliding one, else rest, where the FMU refuses a start) until the
    stroboscopic change over a period is below ``tol`` (relative) or ``max_periods``: the last
    period's extremes per DOF (step values, parabola-refined), the state at its start."""
    from dryfriction.drivers.system import SystemFMU3

    from dryfriction.errors import FMUCallError

    w = system.omega
    if start is not None:
        return _fmu_long_run(system, m, max_periods, chunk, tol, start, "given")
    # the linear stuck response first; where the located scheme meets more stick/slip switches in one
    # step than it takes (the ring's undamped contact mode chattering after a violent start: at 1090
    # rad/s from the stuck response), the sliding limit's response, then rest
    for label, K in (("linear stuck", system.K + (system.W.T * system.k_t) @ system.W), ("linear sliding", system.K),
                     ("rest", None)):
        if K is None:
            x0 = v0 = np.zeros(system.n)
        else:
            X = np.linalg.solve(K - w * w * system.M + 1j * w * system.C, system.F_c - 1j * system.F_s)
            x0, v0 = X.real, -w * X.imag
        try:
            return _fmu_long_run(system, m, max_periods, chunk, tol, (x0, v0), label)
        except FMUCallError as e:
            print(f"fmu_long_run: omega {w:g}, start {label}: {e}", file=sys.stderr)
    raise RuntimeError(f"the located FMU failed from every start at omega {w:g}")


def _fmu_long_run(system: Any, m: int, max_periods: int, chunk: int, tol: float,
                  start: tuple[np.ndarray, np.ndarray], label: str) -> dict[str, Any]:
    from dryfriction.drivers.system import SystemFMU3

    w = system.omega
    T = 2.0 * math.pi / w
    sysh = system.replace(x0=start[0], v0=start[1], h=T / m)
    with SystemFMU3(sysh) as fmu:
        fmu.start(0.0, observe=False)
        P, change = 0, math.inf
        last = None
        while P < max_periods:
            run = fmu.record_at(np.arange(P, P + chunk + 1) * T)
            z = np.concatenate([run.x, run.v / w], axis=1)
            scale = max(float(np.max(np.abs(z))), 1e-300)
            d = np.max(np.abs(np.diff(z, axis=0)), axis=1) / scale
            P += chunk
            change = float(d[-1])
            last = run
            if change < tol:
                break
        x_start, v_start = last.x[-1].copy(), last.v[-1].copy()
        per = fmu.record_at(P * T + np.arange(m + 1) * (T / m))
    hi, lo = _parabola_extremes(per.x[:-1])
    return {"amplitude": 0.5 * (hi - lo), "x0": x_start, "v0": v_start, "periods": P, "change": change, "h": T / m,
            "start": label}


def system_reference(case: str, w: float, args: Any) -> dict[str, Any]:
    """The reference amplitudes (every DOF) at w, with how they were made and their error estimate."""
    import time

    system = build_system(case, w)
    t0 = time.process_time()
    if case == "two_mass":
        from dryfriction.references.system_steady import steady_state

        r = steady_state(system, tol=args.ref_tol, periods=64)
        return {"amplitude": r.amplitude, "method": "event-driven reference run long", "periods": r.periods,
                "change": r.change, "error_estimate": r.error_estimate, "converged": r.converged,
                "cpu_s": time.process_time() - t0}
    coarse = fmu_long_run(system, args.steps)
    fine = fmu_long_run(system, 2 * args.steps, start=(coarse["x0"], coarse["v0"]))
    A = (4.0 * fine["amplitude"] - coarse["amplitude"]) / 3.0
    est = np.abs(fine["amplitude"] - coarse["amplitude"]) / 3.0
    out = {"amplitude": A, "method": f"located FMU run long at h = T/{args.steps} and T/{2 * args.steps}, Richardson",
           "periods": coarse["periods"] + fine["periods"], "change": fine["change"],
           "error_estimate": float(est[SYSTEM_DOF[case]] / A[SYSTEM_DOF[case]]),
           "converged": bool(fine["change"] < 1e-9), "fine_amplitude": fine["amplitude"],
           "coarse_amplitude": coarse["amplitude"], "coarse_periods": coarse["periods"], "start": coarse["start"],
           "fine_periods": fine["periods"]}
    if args.ref_periods > 0:
        from dryfriction.references.system_steady import steady_state

        r = steady_state(system.replace(x0=fine["x0"], v0=fine["v0"]), periods=args.ref_periods,
                         max_periods=args.ref_periods, tol=1e-9, samples=2048)
        k = SYSTEM_DOF[case]
        out["event_driven_check"] = {"periods": r.periods, "change": r.change,
                                     "amplitude_dof": float(r.amplitude[k]),
                                     "vs_richardson": float((r.amplitude[k] - A[k]) / A[k])}
    out["cpu_s"] = time.process_time() - t0
    return out


def cpu_timed(fn: Any, repeats: int) -> tuple[float, Any]:
    """(the least process CPU time of ``repeats`` calls in seconds, the last result)."""
    import time

    best, out = math.inf, None
    for _ in range(repeats):
        t = time.process_time()
        out = fn()
        best = min(best, time.process_time() - t)
    return best, out


def main_system(args: Any, Maestro: Any, harmonics: list[int]) -> int:
    """The --case two_mass / bladed_disk benchmark (see the module docstring)."""
    case = args.case
    omegas = SYSTEM_OMEGAS[case] if args.omegas is None else tuple(args.omegas)
    k = SYSTEM_DOF[case]
    nti = args.nti
    warm = build_system(case, omegas[0])
    pyharm_system_solve(Maestro, warm, omegas[0], harmonics[0], nti)        # numba's and jax's compilation
    rows = []
    for w in omegas:
        ref = system_reference(case, w, args)
        system = build_system(case, w)
        row: dict[str, Any] = {"omega": w, "reference": {key: (val.tolist() if isinstance(val, np.ndarray) else val)
                                                         for key, val in ref.items()}, "pyharm": []}
        print(f"omega {w:g}: reference A[{k}] = {ref['amplitude'][k]:.12g} ({ref['method']}, est. error "
              f"{ref['error_estimate']:.2g})", file=sys.stderr)
        for nh in harmonics:
            t_ph, res = cpu_timed(lambda: pyharm_system_solve(Maestro, system, w, nh, nti), args.repeats)
            a = float(res["amplitude"][k])
            err_all = np.abs(res["amplitude"] - ref["amplitude"]) / np.maximum(np.abs(ref["amplitude"]), 1e-300)
            err = abs(a - ref["amplitude"][k]) / ref["amplitude"][k]
            row["pyharm"].append({"harmonics": nh, "amplitude": a, "error": err,
                                  "max_error_all_dofs": float(np.max(err_all)), "converged": res["converged"],
                                  "residual": res["residual"], "pyharm_flags": res["pyharm_flags"],
                                  "cpu_s": t_ph})
            print(f"  nh {nh}: A = {a:.10g}, err {row['pyharm'][-1]['error']:.2e}, cpu {t_ph:.3f} s, "
                  f"converged {res['converged']}, residual {res['residual']:.2e}, pyHarm's flags {res['pyharm_flags']}",
                  file=sys.stderr)
        rows.append(row)
    orbits = orbit_side(case, omegas, rows, args.repeats)
    version = importlib.import_module("pyHarm").__dict__.get("__version__", "?")
    out = {"case": case, "dof": k, "nti": nti if nti is not None else "pyHarm default (128)",
           "pyharm_version": version, "rows": rows, "orbits": orbits}
    if args.json:
        print(json.dumps(out))
        return 0
    print(f"pyHarm {version} (Jenkins, nti {out['nti']}) against the reference on {case}, DOF {k}")
    print(f"{'omega':>8} {'nh':>3} {'A pyHarm':>14} {'A reference':>14} {'error':>9} {'cpu s':>7} {'conv':>4} "
          f"{'residual':>9}")
    for r in rows:
        for q in r["pyharm"]:
            print(f"{r['omega']:8g} {q['harmonics']:3d} {q['amplitude']:14.8g} {r['reference']['amplitude'][k]:14.10g} "
                  f"{q['error']:9.2e} {q['cpu_s']:7.3f} {'yes' if q['converged'] else 'NO':>4} {q['residual']:9.2e}")
    if orbits:
        print("\nthe orbit method beside it (bench/system_orbit_cost.py: a point of a sweep, FMU reused): for each "
              "pyHarm point that converged, the cheapest orbit setting at least as accurate")
        print(f"{'omega':>8} {'nh':>3} {'pyHarm err':>10} {'pyHarm ms':>9} {'orbit steps/T':>13} {'orbit err':>9} "
              f"{'orbit ms':>8} {'ratio':>7}")
        for c in orbits["comparison"]:
            print(f"{c['omega']:8g} {c['harmonics']:3d} {c['pyharm_error']:10.2e} {1e3 * c['pyharm_cpu_s']:9.1f} "
                  f"{c['orbit_setting']:>13} {c['orbit_error']:9.2e} {1e3 * c['orbit_cpu_s']:8.1f} {c['ratio']:6.1f}x")
        for w, best in orbits["best"].items():
            print(f"omega {w}: the orbit method's best {best['error']:.2e} ({best['setting']}, {1e3 * best['cpu_s']:.1f} ms); "
                  f"pyHarm's best {orbits['pyharm_best'][w]:.2e}")
    return 0


def orbit_side(case: str, omegas: Sequence[float], rows: list[dict[str, Any]], repeats: int) -> dict[str, Any] | None:
    """The two-mass case: the orbit method's cost and error per frequency point at 25 to 3200 steps a
    period, with and without Richardson (bench/system_orbit_cost.py, the same process), and per
    converged pyHarm point the cheapest orbit setting at least as accurate (None for the disk)."""
    if case != "two_mass":
        return None
    from system_orbit_cost import REFERENCE, measure

    ws = [w for w in omegas if w in REFERENCE]
    ours = measure(ws, [25, 50, 100, 200, 400, 800, 1600, 3200], max(1, repeats))

    def setting(o: dict[str, Any]) -> str:
        return f"{o['steps_per_period']}{' +R' if o['richardson'] else ''}"

    comparison, best, ph_best = [], {}, {}
    for r in rows:
        w = r["omega"]
        mine = [o for o in ours if o["omega"] == w and o["converged"]]
        if not mine:
            continue
        b = min(mine, key=lambda o: o["error"])
        best[w] = {"error": b["error"], "setting": setting(b), "cpu_s": b["cpu_s"]}
        ph_best[w] = min((q["error"] for q in r["pyharm"] if q["converged"]), default=math.nan)
        for q in r["pyharm"]:
            if not q["converged"]:
                continue
            ok = [o for o in mine if o["error"] <= q["error"]]
            if not ok:
                continue
            o = min(ok, key=lambda o: o["cpu_s"])
            comparison.append({"omega": w, "harmonics": q["harmonics"], "pyharm_error": q["error"],
                               "pyharm_cpu_s": q["cpu_s"], "orbit_setting": setting(o), "orbit_error": o["error"],
                               "orbit_cpu_s": o["cpu_s"], "ratio": q["cpu_s"] / o["cpu_s"]})
    return {"rows": ours, "comparison": comparison, "best": best, "pyharm_best": ph_best}


def main(argv: list[str] | None = None) -> int:
    # pyHarm writes its kernel state (.pyHarm/context.json) into the working folder: a temporary one
    with tempfile.TemporaryDirectory(prefix="pyharm_peer_") as tmp, contextlib.chdir(tmp):
        return _main(argv)


def _main(argv: list[str] | None) -> int:
    ap = make_parser("pyharm_peer.py", __doc__.splitlines()[0], exit=True)
    ap.add_argument("--case", choices=("oscillator", "two_mass", "bladed_disk"), default="oscillator",
                    help="the structure (default oscillator: the one-DOF case)")
    ap.add_argument("--harmonics", default=None,
                    help="pyHarm's numbers of harmonics (default 5,10,20; 5,10,20,40 for the structures)")
    ap.add_argument("--nti", type=count("--nti", 8), default=None,
                    help="pyHarm's time samples per period (default 1024; pyHarm's own, 128, for the structures)")
    ap.add_argument("--omegas", type=lambda t: [float(v) for v in t.split(",")], default=None,
                    help="the structure's angular frequencies, rad/s (default the case's)")
    ap.add_argument("--ref-tol", type=number("--ref-tol", 0.0, True), default=1e-10,
                    help="the two-mass reference's tolerance (relative; default 1e-10)")
    ap.add_argument("--steps", type=count("--steps", 16), default=400,
                    help="the bladed disk's FMU reference: steps per period of the coarse run (default 400)")
    ap.add_argument("--ref-periods", type=count("--ref-periods", 0), default=2,
                    help="the bladed disk: event-driven reference periods from the FMU's state (default 2; 0: none)")
    ap.add_argument("--eps", type=number("--eps", 0.0, True), default=1e3,
                    help="pyHarm's DLFT penalty (default 1e3, its own; 1e5 sends its solver to wrong solutions)")
    ap.add_argument("--repeats", type=count("--repeats"), default=3, help="timing repeats, min taken (default 3)")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    args = ap.parse_args(argv)
    if args.harmonics is None:
        args.harmonics = "5,10,20" if args.case == "oscillator" else "5,10,20,40"
    try:
        harmonics = [int(h) for h in args.harmonics.split(",")]
        if any(h < 1 for h in harmonics):
            raise ValueError
    except ValueError:
        ap.error(f"--harmonics must be a comma-separated list of whole numbers >= 1, not {args.harmonics!r}")
    Maestro = ensure_pyharm()
    logging.disable(logging.CRITICAL)            # pyHarm's banner and per-step log
    warnings.filterwarnings("ignore", module="numba")
    warnings.filterwarnings("ignore", category=Warning, module="pyHarm")
    if args.case != "oscillator":
        return main_system(args, Maestro, harmonics)
    if args.nti is None:
        args.nti = 1024

    from dryfriction import Oscillator
    from dryfriction.drivers.oscillator import OscillatorFMU2
    from dryfriction.analysis.orbits import find_orbits

    base = Oscillator.physical(m=CASE["m"], k=CASE["k"], zeta=CASE["zeta"], P0=CASE["P0"], omega=1.0, N=CASE["N"],
                               mu_s=CASE["mu"], mu_k=CASE["mu"])
    pyharm_amplitude(Maestro, 1.0, harmonics[0], args.nti, args.eps)     # numba's compilation: not timed
    rows = []
    with OscillatorFMU2() as fmu:
        for lam in LAMBDAS:
            p = base.with_(omega=lam * base.w0)
            t_orbit, orbits = timed(lambda: find_orbits(p, fmu=fmu), args.repeats)
            stable = [o for o in orbits if o.stable]
            if len(stable) != 1:
                print(f"pyharm_peer.py: error: {len(stable)} stable orbits at lambda {lam}, expected one",
                      file=sys.stderr)
                return 1
            o = stable[0]
            row: dict[str, Any] = {"lambda": lam, "orbit_amplitude_m": o.amplitude, "stick_fraction": o.stick_fraction,
                                   "orbit_residual": o.residual, "orbit_seconds": t_orbit, "pyharm": []}
            for nh in harmonics:
                t_ph, (a, ok) = timed(lambda: pyharm_amplitude(Maestro, lam * base.w0, nh, args.nti, args.eps),
                                      args.repeats)
                row["pyharm"].append({"harmonics": nh, "amplitude_m": a, "converged": ok,
                                      "error": abs(a - o.amplitude) / o.amplitude, "seconds": t_ph})
            rows.append(row)
    version = importlib.import_module("pyHarm").__dict__.get("__version__", "?")
    out = {"case": CASE, "nti": args.nti, "eps": args.eps, "pyharm_version": version, "rows": rows}
    if args.json:
        print(json.dumps(out))
        return 0
    print(f"pyHarm {version} (DLFT friction, nti {args.nti}, eps {args.eps:g}) against the exact orbit: m = k = 1, zeta = 0.01, "
          f"P0 = 1, mu N / P0 = 0.3, mu_s = mu_k")
    head = f"{'lambda':>6} {'orbit A (m)':>12} {'stuck %':>7} {'orbit s':>8}"
    for nh in harmonics:
        head += f" {'err ' + str(nh) + ' h':>9} {'s ' + str(nh) + ' h':>7}"
    print(head)
    for r in rows:
        line = f"{r['lambda']:6.2f} {r['orbit_amplitude_m']:12.6g} {100 * r['stick_fraction']:7.1f} {r['orbit_seconds']:8.4f}"
        for q in r["pyharm"]:
            line += f" {q['error']:9.1e} {q['seconds']:7.3f}" + ("" if q["converged"] else "!")
        print(line)
    print("err: |A_pyHarm - A_orbit| / A_orbit; s: wall seconds per frequency (min of "
          f"{args.repeats}); '!': pyHarm's solver did not report convergence")
    return 0


if __name__ == "__main__":
    sys.exit(main())
