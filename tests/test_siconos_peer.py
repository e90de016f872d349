"""bench/siconos_peer.py: Siconos side by side with the FMU.

Runs ``bench/siconos_peer.py --quick --json`` once and checks what it measured against the
independent references (the tutorial's closed form, dryfriction.references.exact, dryfriction.references.chain):
the errors of both sides in their expected bands, the orders, the FMU's exact scheme, and the JSON
object's schema and ratios. No timing assertions: times only have to be finite and positive.
Skips, saying why, only when Siconos cannot be installed (python3-siconos for the system Python).
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "bench" / "siconos_peer.py"
sys.path.insert(0, str(ROOT / "bench"))

# a benchmark run in a subprocess under the system Python: not under ASan's LD_PRELOAD
pytestmark = [pytest.mark.no_sanitizer, pytest.mark.slow]

TARGET_KEYS = ["1e-03", "1e-04", "1e-05", "1e-06", "1e-07", "1e-08"]


@pytest.fixture(scope="module")
def peer() -> dict:
    from siconos_side import SiconosUnavailable, ensure_siconos

    try:
        ensure_siconos()
    except SiconosUnavailable as e:
        pytest.skip(f"Siconos cannot be installed here: {e}")
    # --budget 60: the quick sweep's two steps h whatever the load (its default, 3 s of Siconos wall
    # time per case and theta, drops h = 5e-3 on busy cores)
    res = subprocess.run([sys.executable, str(SCRIPT), "--quick", "--json", "--budget", "60"], capture_output=True,
                         text=True, timeout=600)
    assert res.returncode == 0, res.stderr[-3000:]
    return json.loads(res.stdout)  # stdout holds the JSON object and nothing else


def _case(peer: dict, name: str) -> dict:
    return next(c for c in peer["cases"] if c["name"] == name)


def _sic(case: dict, theta: float, h: float) -> float:
    return next(r["error"] for r in case["siconos"] if r["theta"] == theta and r["h"] == h)


def _fmu(case: dict, scheme: str, h: float | None) -> float:
    return next(r["error"] for r in case["fmu"] if r["scheme"] == scheme and r["h"] == h)


def test_json_schema(peer: dict) -> None:
    assert list(peer) == ["cases"]
    names = [c["name"] for c in peer["cases"]]
    assert names == ["tutorial", "wp_stick_dominated_chi1", "wp_reversal_resonance_chi1", "chain_n2", "chain_n8"]
    for c in peer["cases"]:
        assert list(c) == ["name", "siconos", "fmu", "ratio_at"]
        assert list(c["ratio_at"]) == TARGET_KEYS
        assert {r["theta"] for r in c["siconos"]} == {0.5, 1.0}
        for r in c["siconos"]:
            assert list(r) == ["theta", "h", "cpu_s", "error"]
            assert r["h"] > 0 and math.isfinite(r["cpu_s"]) and r["cpu_s"] > 0 and math.isfinite(r["error"])
        for r in c["fmu"]:
            assert list(r) == ["scheme", "h", "cpu_s", "error"]
            assert (r["h"] is None) == (r["scheme"] == "exact")
            assert math.isfinite(r["cpu_s"]) and r["cpu_s"] > 0 and math.isfinite(r["error"])
        schemes = {r["scheme"] for r in c["fmu"]}
        assert schemes == ({"located"} if c["name"].startswith("chain") else {"located", "exact"})


def test_ratios_are_the_rows_own(peer: dict) -> None:
    """ratio_at: Siconos's best time over the FMU's best time to reach each error, from the rows
    themselves (null where one of them does not reach it)."""
    from report import cost_at

    for c in peer["cases"]:
        for key in TARGET_KEYS:
            E = float(key)
            s = [cost_at([(r["error"], r["cpu_s"]) for r in c["siconos"] if r["theta"] == th], E) for th in (0.5, 1.0)]
            f = [cost_at([(r["error"], r["cpu_s"]) for r in c["fmu"] if r["scheme"] == sc], E)
                 for sc in ("located", "exact")]
            s = [v for v in s if v is not None]
            f = [v for v in f if v is not None]
            want = min(s) / min(f) if s and f else None
            got = c["ratio_at"][key]
            assert (got is None) == (want is None), (c["name"], key)
            if want is not None:
                assert got == pytest.approx(want, rel=1e-12)


def test_tutorial_against_its_closed_form(peer: dict) -> None:
    """Siconos's FrictionOscillator example: Moreau-Jean with theta = 0.5 is 2.5e-2 off the closed
    form at h = 1e-2 (2.48e-2 measured), theta = 1 first order (0.68 -> 0.35 per halving); the FMU's
    located scheme 8.0e-4 at h = 1e-2, second order; the exact scheme below 1e-12."""
    c = _case(peer, "tutorial")
    assert 2.2e-2 <= _sic(c, 0.5, 1e-2) <= 2.8e-2
    assert 0.6 <= _sic(c, 1.0, 1e-2) <= 0.75
    assert 1.8 <= _sic(c, 1.0, 1e-2) / _sic(c, 1.0, 5e-3) <= 2.2
    assert 7.5e-4 <= _fmu(c, "located", 1e-2) <= 8.5e-4
    assert 3.6 <= _fmu(c, "located", 1e-2) / _fmu(c, "located", 5e-3) <= 4.4
    assert _fmu(c, "exact", None) < 1e-12


def test_forced_cases_against_the_exact_solution(peer: dict) -> None:
    """The harmonic force through Siconos's b(t) plugin (from rest nothing would move without it):
    stick_dominated at chi = 1, theta = 0.5, h = 1e-2: 9.5e-4 static deflections (measured), second
    order on this case; the FMU's exact scheme below 1e-12 on both forced cases."""
    c = _case(peer, "wp_stick_dominated_chi1")
    assert 7e-4 <= _sic(c, 0.5, 1e-2) <= 1.3e-3
    assert 3.0 <= _sic(c, 0.5, 1e-2) / _sic(c, 0.5, 5e-3) <= 7.0
    assert 1.7 <= _sic(c, 1.0, 1e-2) / _sic(c, 1.0, 5e-3) <= 2.2  # implicit Euler: first order
    for name in ("wp_stick_dominated_chi1", "wp_reversal_resonance_chi1"):
        assert _fmu(_case(peer, name), "exact", None) < 1e-12
        cc = _case(peer, name)
        assert 3.6 <= _fmu(cc, "located", 1e-2) / _fmu(cc, "located", 5e-3) <= 4.4


def test_chain_against_the_reference(peer: dict) -> None:
    """The chain (mu_s = mu_k) at n = 2 and 8 against dryfriction.references.chain: the chain FMU's
    located scheme 2.2e-5 m at h = 1e-2, 4x per halving; Siconos theta = 1 first order."""
    for name in ("chain_n2", "chain_n8"):
        c = _case(peer, name)
        assert 1.5e-5 <= _fmu(c, "located", 1e-2) <= 3e-5, name
        assert 3.6 <= _fmu(c, "located", 1e-2) / _fmu(c, "located", 5e-3) <= 4.4, name
        assert 1.7 <= _sic(c, 1.0, 1e-2) / _sic(c, 1.0, 5e-3) <= 2.3, name
        assert _sic(c, 0.5, 1e-2) < _sic(c, 1.0, 1e-2)


def test_closed_form_is_the_exact_solution() -> None:
    """The tutorial's closed form (bench/siconos_cases.py) against dryfriction.references.exact on the same
    parameters: two independent references agree."""
    from dryfriction.references.exact import solve_exact
    from siconos_cases import tutorial_case, tutorial_closed_form

    case = tutorial_case()
    t = np.linspace(0.0, 30.0, 30001)
    x_exact = solve_exact(case.oscillator, 30.0).evaluate(t)[0]
    assert np.max(np.abs(tutorial_closed_form(t) - x_exact)) < 1e-12
    assert tutorial_closed_form(np.array([math.atan2(6, 13)]))[0] == pytest.approx(math.sqrt(205) - 1, abs=1e-14)


def test_bad_budget_fails_fast() -> None:
    res = subprocess.run([sys.executable, str(SCRIPT), "--budget", "-1"], capture_output=True, text=True, timeout=60)
    assert res.returncode == 2
    assert "--budget" in res.stderr
