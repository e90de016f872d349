"""The Burridge-Knopoff study (docs/burridge_knopoff.md): the slip-event detector on synthetic
records with known events, the physics of small chains against independent facts (one block's
closed-form stick-slip cycle, the moment as the sum of the blocks' slips, the mean position bounded
while the plate moves on), the statistics' helpers, and the study's --quick run and its files."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from dryfriction.references.belt import limit_cycle
from dryfriction.analysis.slip_events import EventDetector, detect_events, slip_cells
from dryfriction.studies import effective_config, main, run_study
from dryfriction.studies import burridge_knopoff as bk
from dryfriction.studies.config import ConfigError
from dryfriction.sweep import read_netcdf


# ---- the detector on synthetic records ------------------------------------------------------------

def _record(nt: int, n: int, vb: float, dt: float = 0.5) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    t = np.arange(nt) * dt
    x = np.zeros((nt, n)) + vb * t[:, None] + np.linspace(-0.3, 0.2, n)[None, :]
    v = np.full((nt, n), vb)
    return t, x, v


def _slip(x: np.ndarray, j: int, i: int, s: float) -> None:
    """Block i slips by s over the interval [t_j, t_j+1] (ending at rest on its belt)."""
    x[j + 1:, i] += s


def _synthetic() -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    vb = -0.1
    t, x, v = _record(40, 12, vb)
    for j in range(3, 6):                   # A: blocks 2-4 (from 0), intervals 3-5, 0.1 each cell
        for i in (2, 3, 4):
            _slip(x, j, i, 0.1)
    _slip(x, 10, 6, 0.25)                  # B: block 6 at interval 10, block 7 at 11 (diagonal only)
    _slip(x, 11, 7, 0.05)
    _slip(x, 20, 0, 0.4)                   # C: block 0, intervals 20-21, a backward part in 21
    _slip(x, 21, 0, -0.15)
    v[25, 9] = vb + 0.7                    # F: block 9 sliding at sample 25, no net slip either side
    _slip(x, 30, 10, 0.02)                 # D: blocks 10, 11 together at interval 30
    _slip(x, 30, 11, 0.03)
    _slip(x, 38, 5, 0.5)                   # E: in the last interval: cut by the record's end
    return t, x, v, vb


def test_detector_counts_sizes_moments() -> None:
    t, x, v, vb = _synthetic()
    ev = detect_events(t, x, v, vb, v_threshold=1e-3, d_threshold=1e-9)
    assert ev.count == 6
    np.testing.assert_array_equal(ev.n_blocks, [3, 2, 1, 1, 2, 1])
    np.testing.assert_allclose(ev.moment, [0.9, 0.3, 0.25, 0.0, 0.05, 0.5], rtol=0, atol=1e-12)
    np.testing.assert_allclose(ev.start, [1.5, 5.0, 10.0, 12.0, 15.0, 19.0])
    np.testing.assert_allclose(ev.stop, [3.0, 6.0, 11.0, 13.0, 15.5, 19.5])
    np.testing.assert_allclose(ev.duration, [1.5, 1.0, 1.0, 1.0, 0.5, 0.5])
    np.testing.assert_allclose(ev.position, [3.0, 6.0, 0.0, 9.0, 10.5, 5.0])
    np.testing.assert_array_equal(ev.block_lo, [2, 6, 0, 9, 10, 5])
    np.testing.assert_array_equal(ev.block_hi, [4, 7, 0, 9, 11, 5])
    np.testing.assert_array_equal(ev.complete, [True, True, True, True, True, False])


def test_detector_connectivity_thresholds_and_segments() -> None:
    t, x, v, vb = _synthetic()
    # without diagonal neighbours B splits into its two blocks
    ev = detect_events(t, x, v, vb, 1e-3, 1e-9, diagonal=False)
    assert ev.count == 7
    np.testing.assert_allclose(ev.moment, [0.9, 0.25, 0.05, 0.25, 0.0, 0.05, 0.5], atol=1e-12)
    # a slip below d_threshold and a speed below v_threshold are not slips: F's sliding sample
    # (v_rel 0.7) is seen at v_threshold 0.5, in both intervals next to it, not at 1.0; a
    # d_threshold of 0.025 drops D's 0.02 cell
    mask, d = slip_cells(t, x, v, vb, 0.5, 1e-9)
    assert mask[24, 9] and mask[25, 9] and not mask[23, 9] and not mask[26, 9]
    np.testing.assert_allclose(d[20:22, 0], [0.4, -0.15])
    assert not slip_cells(t, x, v, vb, 1.0, 1e-9)[0][24, 9]
    ev2 = detect_events(t, x, v, vb, 1.0, 0.025)
    assert ev2.count == 5 and ev2.n_blocks[3] == 1 and math.isclose(ev2.moment[3], 0.03)
    # segments fed one after another (sharing their end samples) give the whole record's events
    det = EventDetector(vb, 1e-3, 1e-9)
    for a, b in ((0, 11), (10, 22), (21, 40)):
        det.feed(t[a:b], x[a:b], v[a:b])
    seg = det.events()
    for name in ("start", "stop", "n_blocks", "moment", "position", "complete"):
        np.testing.assert_array_equal(getattr(seg, name), getattr(ev := detect_events(t, x, v, vb, 1e-3, 1e-9), name))
    assert seg.count == ev.count


def test_detector_rejects_bad_records() -> None:
    t, x, v, vb = _synthetic()
    with pytest.raises(ValueError, match="shape"):
        detect_events(t, x[:-1], v, vb, 1e-3, 1e-9)
    with pytest.raises(ValueError, match="increase strictly"):
        detect_events(t[::-1], x, v, vb, 1e-3, 1e-9)
    det = EventDetector(vb, 1e-3, 1e-9)
    det.feed(t[:10], x[:10], v[:10])
    with pytest.raises(ValueError, match="previous segment's last sample"):
        det.feed(t[11:20], x[11:20], v[11:20])
    quiet = detect_events(*_record(10, 4, 0.3)[:3], 0.3, 1e-3, 1e-9)
    assert quiet.count == 0 and quiet.moment.size == 0


# ---- physics of small chains --------------------------------------------------------------------

def _cfg(**model: object) -> dict:
    cfg = effective_config("burridge_knopoff", quick=True)
    cfg["model"].update(model)
    return cfg


def test_one_block_is_the_closed_form_stick_slip_cycle(chain_fmu3: Path) -> None:
    """n = 1 on its leaf spring only: the classic single block on a belt (belt_reference.limit_cycle,
    mirrored: the belt at -nu). Each event is that block's slip, 2 (F_s - F_k) / k + nu t_slip, once
    per period t_stick + t_slip, lasting t_slip (to the sampling step)."""
    nu, chi = 0.1, 0.5
    cfg = _cfg(n=1, nu=nu, chi=chi, x0_amplitude=0.0)
    cfg["run"].update(t_transient=20.0, t_record=200.0, dt=0.05, segment=50.0)
    res = bk.simulate(chain_fmu3, cfg["model"], cfg["run"], cfg["detect"], cfg["numerics"])
    ev = res["events"].select(res["events"].complete)
    lc = limit_cycle(1.0, 1.0, 1.0, 1.0, chi, nu)
    slip = 2 * (1.0 - chi) + nu * lc.t_slip
    assert ev.count >= 13 and np.all(ev.n_blocks == 1)
    np.testing.assert_allclose(ev.moment, slip, rtol=1e-5)
    np.testing.assert_allclose(np.diff(ev.start), lc.period, atol=0.05 + 1e-9)
    np.testing.assert_allclose(ev.duration, lc.t_slip, atol=2 * 0.05 + 1e-9)
    assert abs(np.mean(np.diff(ev.start)) - lc.period) < 0.1 / ev.count


def test_moments_are_slip_sums_and_the_chain_keeps_up_with_the_plate(chain_fmu3: Path) -> None:
    """A chain of 24 blocks: (1) each event isolated in time has the moment the blocks' positions
    give directly, sum over its blocks of x(stop) - x(start) + nu (stop - start); (2) over the
    record the plate moves nu T = 6 D0 while the mean block position (plate frame) stays within
    1 D0 of where it was: the chain moves on at the plate's speed, and the moments of all events
    add up to n (nu T + the mean's change)."""
    nu = 0.03
    cfg = _cfg(n=24, nu=nu, chi=0.5, x0_amplitude=1e-3)
    cfg["run"].update(t_transient=0.0, t_record=200.0, dt=0.1, segment=50.0)
    m, r, d, num = cfg["model"], cfg["run"], cfg["detect"], cfg["numerics"]
    res = bk.simulate(chain_fmu3, m, r, d, num)
    from dryfriction.drivers.chain import ChainFMU3
    with ChainFMU3(n=24, fmu_path=chain_fmu3) as chain:
        run = chain.run(r["t_record"], r["dt"], bk.chain_params(m, num, r["dt"]), inputs={"v_belt": -nu})
    ev = detect_events(run.t, run.x, run.v, -nu, d["v_threshold"], d["d_threshold"])
    assert ev.count >= 5
    # the study's run (recorded in segments) starts with the same events; the chain is chaotic,
    # and the runs part after some events (the segments' communication times differ in the last bit)
    np.testing.assert_allclose(res["events"].moment[:5], ev.moment[:5], rtol=1e-6)
    checked = 0
    for k in range(ev.count):
        others = [q for q in range(ev.count) if q != k and ev.start[q] < ev.stop[k] and ev.stop[q] > ev.start[k]]
        if others or not ev.complete[k]:
            continue
        a, b = np.searchsorted(run.t, [ev.start[k], ev.stop[k]])
        blocks = slice(ev.block_lo[k], ev.block_hi[k] + 1)
        direct = np.sum(run.x[b, blocks] - run.x[a, blocks]) + (ev.block_hi[k] - ev.block_lo[k] + 1) * nu * (run.t[b] - run.t[a])
        assert math.isclose(ev.moment[k], direct, rel_tol=1e-9, abs_tol=1e-9), (k, ev.moment[k], direct)
        checked += 1
    assert checked >= 3
    T = run.t[-1] - run.t[0]
    drift = run.x[-1].mean() - run.x[0].mean()
    assert nu * T > 5.9 and abs(drift) < 1.0 and np.ptp(run.x.mean(axis=1)) < 1.5 and np.ptp(res["x_mean"]) < 1.5
    assert math.isclose(ev.moment.sum() / 24, nu * T + drift, rel_tol=1e-9)


# ---- statistics ---------------------------------------------------------------------------------

def test_moment_histogram_and_power_law_fit() -> None:
    """Moments drawn from D(M) ~ M^-2 on [0.01, 10] (the inverse CDF): the fit over the bins finds
    the slope -2 and b = 1 within its error; the rate density integrates to the event rate."""
    rng = np.random.default_rng(3)
    a, b_, N = 0.01, 10.0, 20000
    u = rng.uniform(size=N)
    M = 1.0 / (1.0 / a - u * (1.0 / a - 1.0 / b_))
    hist = bk.moment_histogram(M, 100.0, 5)
    assert hist["count"].sum() == N
    assert math.isclose(np.sum(hist["rate_density"] * np.diff(hist["edges"])), N / 100.0)
    fit = bk.fit_power_law(hist, 1.0, 5)
    assert abs(fit["slope"] + 2.0) < 0.05 and abs(fit["b"] - 1.0) < 0.05 and fit["M_hi"] <= 1.0 + 1e-9
    assert math.isnan(bk.fit_power_law(hist, 0.02, 5)["slope"])   # too few bins: not a number


# ---- the study ----------------------------------------------------------------------------------

@pytest.mark.slow
def test_study_quick_writes_its_files(tmp_path: Path, chain_fmu3: Path) -> None:
    res = run_study("burridge_knopoff", quick=True, out=tmp_path, fmu=chain_fmu3, progress=False, workers=0)
    out = res.out_dir
    s = json.loads((out / "summary.json").read_text())["summary"]
    ds = read_netcdf(out / "burridge_knopoff.nc")
    assert s["n"] == 256 and s["events"] == ds.event.size > 10
    assert np.all(ds.n_blocks.values >= 1) and np.all(ds.moment.values > 0)
    assert np.all((ds.position.values >= 1) & (ds.position.values <= 256))
    assert math.isclose(float(ds.event_count.sum()), float(np.sum(ds.moment.values > 0)))
    assert math.isclose(s["event_rate"], s["events"] / s["t_record"])
    assert (out / "burridge_knopoff.png").stat().st_size > 10_000 and (out / "config.toml").exists()


def test_bad_values_and_a_missing_friction_law_are_refused(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["burridge_knopoff", "--quick", "--set", "model.chi=1.2"]) == 2
    assert "model.chi (mu_k / mu_s) must be in [0, 1)" in capsys.readouterr().err
    assert main(["burridge_knopoff", "--quick", "--set", "numerics.scheme=paper"]) == 2
    assert "paper scheme has no belt" in capsys.readouterr().err
    from dryfriction.drivers.chain import ARRAY_PARAMS, SCALAR_PARAMS
    if "friction_law" not in ARRAY_PARAMS + SCALAR_PARAMS:
        cfg = _cfg(friction_law="stribeck")
        with pytest.raises(ConfigError, match="friction_law = stribeck needs a chain FMU with the Stribeck law"):
            bk.chain_params(cfg["model"], cfg["numerics"], 0.1)
