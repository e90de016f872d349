"""Small things shared by several test modules (one copy each): the engineer's example oscillator,
the outputs compared sample by sample, files that are not usable FMUs, and the oscillator run with
inputs held over communication steps with its event-driven scipy reference."""

from __future__ import annotations

import math
import zipfile
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from dryfriction.drivers.oscillator import OscillatorFMU2, Settings
from dryfriction.params import Oscillator


# the README's engineer example (SI units): m = 0.5 kg, k = 2000 N/m, ... (f given per test)
ENGINEER = dict(m=0.5, k=2000.0, zeta=0.003, P0=10.0, N=20.0, mu_s=0.3, mu_k=0.2)

# the outputs two runs of the oscillator are compared on, sample by sample
OUT = ("x", "v", "a", "F_friction", "mode")

# One block of the chain against the oscillator: the oscillator's Bossak schemes step through the
# friction engine, whose arithmetic is ordered otherwise than the chain's own stepper, so the two
# agree to rounding (measured: below 1e-11 relative), not bit for bit, with the same modes.
CHAIN_N1_REL = 1e-10


def assert_rounding_apart(got: np.ndarray, ref: np.ndarray, what: object = "", rel: float = CHAIN_N1_REL) -> None:
    """got equals ref to rel relative to max(|ref|, 1), sample by sample (the same shape)."""
    g, r = np.asarray(got, dtype=float), np.asarray(ref, dtype=float)
    assert g.shape == r.shape, (what, g.shape, r.shape)
    err = float(np.max(np.abs(g - r) / np.maximum(np.abs(r), 1.0))) if r.size else 0.0
    assert err <= rel, (what, err)


# ---- files that are not usable FMUs (each its own FMUFileError sentence) ----

def _not_zip(tmp_path: Path) -> Path:
    p = tmp_path / "README.md"
    p.write_text("# not an FMU\n")
    return p


def _zip_without_md(tmp_path: Path) -> Path:
    p = tmp_path / "empty.fmu"
    with zipfile.ZipFile(p, "w") as z:
        z.writestr("binaries/readme.txt", "no model description")
    return p


def _bad_xml(tmp_path: Path) -> Path:
    p = tmp_path / "badxml.fmu"
    with zipfile.ZipFile(p, "w") as z:
        z.writestr("modelDescription.xml", "<fmiModelDescription fmiVersion='2.0'")
    return p


# ---- inputs held over communication steps (tests/test_inputs.py, tests/test_exact_scheme.py) ----


def event_driven(p: Oscillator, t_grid: np.ndarray, F_ext: np.ndarray, N_ext: np.ndarray) -> np.ndarray:
    """x at t_grid by DOP853 (rtol 1e-12) on each phase, stopped at every stop and breakaway; the
    inputs F_ext[i], N_ext[i] are held over [t_grid[i], t_grid[i+1]]."""
    m, k, c = p.m, p.k, p.c

    def P(t: float) -> float:
        return p.P0 * math.cos(p.omega * t + p.phi)

    x, v = p.x0, p.v0
    out = [x]
    mode = int(np.sign(v))
    for i in range(len(t_grid) - 1):
        t, t1 = float(t_grid[i]), float(t_grid[i + 1])
        u, N = float(F_ext[i]), max(p.N + float(N_ext[i]), 0.0)
        muk, Fb = p.chi * p.mu_s * N, max(p.mu_s, p.chi * p.mu_s) * N
        if mode == 0 and v == 0.0 and abs(P(t) + u - k * x) > Fb:
            mode = int(np.sign(P(t) + u - k * x))
        if mode == 0 and v != 0.0:
            mode = int(np.sign(v))
        for _ in range(1000):
            if t >= t1:
                break
            if mode == 0:
                def g(s: float) -> float:
                    return abs(P(s) + u - k * x) - Fb
                ts = np.linspace(t, t1, 401)
                gs = np.array([g(s) for s in ts])
                idx = np.nonzero(gs[1:] > 0.0)[0]
                if idx.size == 0:
                    t = t1
                    break
                j = int(idx[0]) + 1
                tb = brentq(g, ts[j - 1], ts[j], xtol=1e-15) if gs[j - 1] <= 0.0 else ts[j - 1]
                t, v = tb, 0.0
                mode = int(np.sign(P(t) + u - k * x))
                continue
            s = mode

            def rhs(tt: float, y: np.ndarray, s: int = s) -> list[float]:
                return [y[1], (P(tt) + u - k * y[0] - c * y[1] - s * muk) / m]

            def stop(tt: float, y: np.ndarray, s: int = s) -> float:
                return s * y[1]
            stop.terminal, stop.direction = True, -1
            # a slide from rest counts from a little later (v = 0 at its start)
            sol = solve_ivp(rhs, (t, t1), [x, v], method="DOP853", rtol=1e-12, atol=1e-15,
                            events=stop if s * v > 0.0 else None, dense_output=True)
            if s * v == 0.0:   # started from rest: find the first stop after the velocity has grown
                tt = np.linspace(t, t1, 2001)
                vv = s * sol.sol(tt)[1]
                pos = np.nonzero(vv > 1e-9 * max(1.0, np.abs(vv).max()))[0]
                neg = np.nonzero(vv <= 0.0)[0]
                neg = neg[neg > (pos[0] if pos.size else len(tt))]
                if neg.size:
                    j = int(neg[0])
                    te = brentq(lambda q: s * sol.sol(q)[1], tt[j - 1], tt[j], xtol=1e-15)
                    x, t, v = float(sol.sol(te)[0]), te, 0.0
                else:
                    x, v, t = float(sol.y[0, -1]), float(sol.y[1, -1]), t1
                    break
            elif sol.status == 1:
                x, t, v = float(sol.y_events[0][0][0]), float(sol.t_events[0][0]), 0.0
            else:
                x, v, t = float(sol.y[0, -1]), float(sol.y[1, -1]), t1
                break
            S = P(t) + u - k * x
            mode = 0 if abs(S) <= Fb else int(np.sign(S))
        out.append(x)
        if v == 0.0 and mode != 0 and abs(P(t1) + u - k * x) <= Fb:
            pass
    return np.array(out)


def held_run(f: OscillatorFMU2, p: Oscillator, settings: Settings, t: np.ndarray, F_ext: np.ndarray,
             N_ext: np.ndarray) -> np.ndarray:
    """x at t (t[0] the start) with F_ext[i], N_ext[i] set before the step to t[i + 1]."""
    f.start(p, settings)
    x = [float(f.get(["x"])["x"])]
    for i in range(t.size - 1):
        f.set({"F_ext": float(F_ext[i]), "N_ext": float(N_ext[i])})
        f.step_to(float(t[i + 1]))
        x.append(float(f.get(["x"])["x"]))
    return np.array(x)
