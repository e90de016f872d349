"""Siconos as a peer of bench/work_precision.py: its five cases at chi = 1.

Siconos's relay law has one friction coefficient, so the study's cases (chi = 0.6, 0.8, 0.9, 1.5,
0.05) cannot be run by it as they are; they are run at chi = 1 (mu_k = mu_s) by Siconos and, for
the comparison, by the FMU (located over h, exact), with the sweep of bench/siconos_peer.py
(process CPU time of the stepping loop on both sides). Rows for the study's siconos.csv; when
Siconos cannot be had, one row per case saying why (no number is made up).
"""

from __future__ import annotations

import math
import time
from typing import TextIO

from report import _machine
from siconos_peer import THETAS, PeerConfig, fmu_sweep, siconos_sweep


def study_config(quick: bool) -> PeerConfig:
    """The study's share of time: 2 s per case and theta with --quick, 20 s in the full study."""
    if quick:
        return PeerConfig(True, 2.0, (1e-2, 5e-3), (1e-2, 5e-3, 2.5e-3), None, (), False, 0.01)
    return PeerConfig(False, 20.0, tuple(1e-2 / 2**k for k in range(14)), tuple(1e-2 / 2**k for k in range(11)),
                      None, (), False, 0.1)


def _row(case_name: str, method: str, chi: float, h: float | None, steps: int, cpu: float, err: float,
         periods: int, note: str = "") -> dict:
    return dict(case=case_name, chi_study=chi, chi_run=1.0, method=method, measured=time.strftime("%Y-%m-%d %H:%M"),
                machine=_machine(),
                h=float("nan") if h is None else h, steps=steps, cpu_s=cpu, error_z=err,
                us_per_period=cpu / periods * 1e6 if math.isfinite(cpu) else float("nan"), note=note)


def study_rows(quick: bool, periods: int, log: TextIO, fmu_path: str | None = None) -> list[dict]:
    from cases import CASES
    from siconos_cases import wp_cases
    from siconos_fmu import FmuSide
    from siconos_side import SiconosUnavailable, SiconosWorker, ensure_siconos

    chi = {c.name: c.chi for c in CASES}
    try:
        ensure_siconos(log)
    except SiconosUnavailable as e:
        return [_row(c.name, "Siconos", c.chi, None, 0, float("nan"), float("nan"), periods,
                     f"Siconos not available: {e}") for c in CASES]
    cfg = study_config(quick)
    rows: list[dict] = []
    fmu = FmuSide(cfg.fmu_budget_s, fmu_path)
    try:
        with SiconosWorker() as worker:
            for case in wp_cases():
                name = case.name[len("wp_"):-len("_chi1")]
                for th in THETAS:
                    sic, why = siconos_sweep(worker, case, th, cfg, log)
                    for r in sic:
                        rows.append(_row(name, f"Siconos theta={th:g}", chi[name], r["h"], r["steps"], r["cpu_s"],
                                         r["error"], periods, f"sweep stopped at {why}"))
                for r in fmu_sweep(fmu, case, cfg, log):
                    rows.append(_row(name, f"FMU {r['scheme']}", chi[name], r["h"], r["steps"], r["cpu_s"],
                                     r["error"], periods))
    finally:
        fmu.close()
    return rows
