"""The orbit studies on quick sizes (fig8_9_orbits, fig10_11_orbits): what they write, against
independent references.

- fig8_9_orbits: the located symmetry breaking and period doublings lie in the brackets of the
  study's own brute-force runs at the sweep's chi (recomputed here from long_runs.nc and
  doubling_runs.nc: one grid step wide, the sweep's resolution), the period doublings also in the
  finer bracket [0.236, 0.237] of docs/chaos.md; the csv, json and summary say the same; the stable
  branches meet the scatter's attractors (scheme located, 30 periods) where the scatter is periodic.
- fig10_11_orbits: where the orbit never sticks (chi = 1, above the last grazing) the branches are
  Den Hartog's exact non-stop amplitude; at the seeds (the ends of each lambda range) every
  attractor of the scatter is one of the stable orbits the continuation started from.

The tests that run the studies (about 4 s and 8 s, once per module) are marked slow; the checks of
the configuration are not. The location of the bifurcations themselves (reproducibility,
find_orbits either side, separate runs of the located orbits) is asserted in test_continuation.py;
here the study's output is.
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from dryfriction.params import Oscillator
from dryfriction.references.steady import den_hartog_amplitude
from dryfriction.studies import run_study
from dryfriction.studies.common import K_REF, M_REF, MU_S_REF, P0_REF
from dryfriction.sweep import read_netcdf


def _run(name: str, out: Path, fmu_path: Path) -> Path:
    res = run_study(name, quick=True, out=out, fmu=fmu_path, progress=False, workers=0)
    return res.out_dir


@pytest.fixture(scope="module")
def band(tmp_path_factory: pytest.TempPathFactory, fmu_path: Path) -> Path:
    return _run("fig8_9_orbits", tmp_path_factory.mktemp("fig8_9_orbits"), fmu_path)


@pytest.fixture(scope="module")
def freq(tmp_path_factory: pytest.TempPathFactory, fmu_path: Path) -> Path:
    return _run("fig10_11_orbits", tmp_path_factory.mktemp("fig10_11_orbits"), fmu_path)


def _rows(d: Path) -> tuple[list[dict], dict]:
    doc = json.loads((d / "bifurcations.json").read_text())
    with open(d / "bifurcations.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [r["type"] for r in rows] == [b["type"] for b in doc["bifurcations"]]
    assert [float(r["param_value"]) for r in rows] == [b["param_value"] for b in doc["bifurcations"]]
    return doc["bifurcations"], doc


# ---- Fig. 8/9 ------------------------------------------------------------------------------------

def _symmetric(a: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Per row (one chi): one amplitude and zero asymmetry over the runs, 1e-3 of the median amplitude."""
    med = np.median(a, axis=1)
    return ((a.max(1) - a.min(1)) / med < 1e-3) & (np.abs(s).max(1) / med < 1e-3)


@pytest.mark.slow
def test_fig8_9_bifurcations_within_the_brute_force_resolution(band: Path) -> None:
    bifs, doc = _rows(band)
    # the long runs' bracket, recomputed here: the lowest chi of the symmetric range and the value
    # below it, one step of the scatter's grid apart
    lr = read_netcdf(band / "long_runs.nc")
    chi = lr.chi.values
    sym = _symmetric(lr.amplitude.values, lr.asymmetry.values)
    assert lr.symmetric_periodic.dtype == bool and np.array_equal(lr.symmetric_periodic.values, sym)
    i = int(np.argmax(sym))                              # quick: 0.6
    assert i > 0 and sym[i:].all() and not sym[i - 1]
    lo, hi = chi[i - 1], chi[i]
    assert doc["brute_force"]["symmetry_breaking"] == [pytest.approx(lo, abs=1e-15), pytest.approx(hi, abs=1e-15)]
    sc = read_netcdf(band / "fig8_9.nc")
    assert hi - lo == pytest.approx(float(np.diff(sc.chi.values).max()), rel=1e-12)
    # below the bracket the long runs end on the mirror pair (asymmetry of both signs)
    s_lo = lr.asymmetry.values[i - 1]
    assert s_lo.max() > 0.1 and s_lo.min() < -0.1
    # the 30-period snapshot's bracket is written beside it (no lower than the long runs')
    snap = doc["snapshot_symmetry_breaking"]
    assert snap[1] >= hi

    (sb,) = [b for b in bifs if b["type"] == "symmetry_breaking"]
    assert lo < sb["param_value"] < hi and sb["within_brute_force"] is True
    assert abs(sb["param_value"] - 0.55395) <= 1e-4      # between the full sweep's 0.54 and 0.56 too
    assert abs(sb["mu1_re"] - 1.0) <= 1e-6 and abs(sb["offset_z"]) <= 1e-9

    # the period doubling's bracket, recomputed from the 2000-period runs: below it the extremes
    # of the last two periods differ (period 2, or longer), above it they agree
    dr = read_netcdf(band / "doubling_runs.nc")
    split = dr.split.values.max(axis=1)
    k = int(np.where(split > 1e-2)[0][-1])
    assert np.all(split[k + 1:] < 1e-6) and k + 1 < split.size
    pd_lo, pd_hi = dr.chi.values[k], dr.chi.values[k + 1]
    assert dr.period_1.dtype == bool and np.array_equal(dr.period_1.values, split <= 1e-6)
    assert doc["brute_force"]["period_doubling"] == [pytest.approx(pd_lo, abs=1e-15), pytest.approx(pd_hi, abs=1e-15)]
    assert pd_hi - pd_lo == pytest.approx(float(np.diff(sc.chi.values).max()), rel=1e-12)
    assert doc["reference_period_doubling"] == [0.236, 0.237]

    pd = [b for b in bifs if b["type"] == "period_doubling"]
    assert len(pd) == 2                                  # one on each mirror branch
    for b in pd:
        assert pd_lo < b["param_value"] < pd_hi and b["within_brute_force"] is True
        assert 0.236 <= b["param_value"] <= 0.237 and b["within_reference"] is True   # docs/chaos.md
        assert abs(b["mu1_re"] + 1.0) <= 1e-6 and b["period"] == 1
    assert pd[0]["offset_z"] == pytest.approx(-pd[1]["offset_z"], rel=1e-8)
    assert abs(pd[0]["param_value"] - pd[1]["param_value"]) <= 1e-8

    g = [b for b in bifs if b["type"] == "grazing"]
    assert len(g) == 2 and all(b["within_brute_force"] == "" for b in g)
    assert all(sb["param_value"] > b["param_value"] > pd[0]["param_value"] for b in g)

    summary = json.loads((band / "summary.json").read_text())["summary"]
    assert summary["symmetry_breaking_within_brute_force"] is True
    assert summary["period_doubling_within_brute_force"] is True
    assert summary["period_doubling_within_reference"] is True
    assert summary["chi_period_doubling"] == [b["param_value"] for b in pd]
    assert (band / "fig8_9_orbits.png").stat().st_size > 10_000


@pytest.mark.slow
def test_fig8_9_stable_branches_are_the_scatters_attractors(band: Path) -> None:
    """At chi = 0.7 (one symmetric orbit) and 0.4 (the mirror pair) of the quick scatter every
    initial condition ends, after 30 periods of scheme located at h = T/1000, on a stable orbit of
    the branches (interpolated between the branch points: quadratic error well below the tolerance)."""
    sc = read_netcdf(band / "fig8_9.nc")
    br = xr.load_dataset(band / "branches.nc")
    for chi in (0.7, 0.4):
        j = int(np.argmin(np.abs(sc.chi.values - chi)))
        assert abs(sc.chi.values[j] - chi) < 1e-12
        a = sc.amplitude.values[j].reshape(-1)
        s = sc.asymmetry.values[j].reshape(-1)
        orbits = []
        for b in np.unique(br.branch.values):
            pts = br.where((br.branch == b) & br.stable & (br.period == 1), drop=True)
            x = pts.param.values
            if pts.point.size < 2 or not (x.min() < chi < x.max()):
                continue
            o = np.argsort(x)
            orbits.append((np.interp(chi, x[o], pts.amplitude_z.values[o]),
                           np.interp(chi, x[o], pts.offset_z.values[o])))
        assert len(orbits) == (1 if chi > 0.6 else 2), orbits
        for ai, si in zip(a, s):
            gap = min(max(abs(ai - oa), abs(si - os_)) for oa, os_ in orbits)
            assert gap <= 5e-3, (chi, ai, si, orbits)


# ---- Fig. 10/11 ----------------------------------------------------------------------------------

@pytest.mark.slow
def test_fig10_non_stop_branches_are_den_hartog(freq: Path) -> None:
    br = xr.load_dataset(freq / "fig10_branches.nc")
    pts = br.where((br.chi == 1.0) & (br.stick_fraction == 0) & br.converged, drop=True)
    assert pts.point.size >= 20 and float(pts.param.min()) < 0.7 and float(pts.param.max()) == pytest.approx(1.6)
    for lam, az in zip(pts.param.values, pts.amplitude_z.values):
        p = Oscillator.from_nondimensional(lam=float(lam), mu_s_sigma=0.6, chi=1.0, m=M_REF, k=K_REF, P0=P0_REF,
                                           mu_s=MU_S_REF)
        ref = float(den_hartog_amplitude(p)) * K_REF / P0_REF
        assert math.isfinite(ref) and abs(az - ref) <= 1e-9 * ref, (lam, az, ref)
    # the unbounded resonance: the branches reach z > 15 next to lambda = 1 from both sides
    near = br.where(br.chi == 1.0, drop=True)
    assert float(near.where(near.param < 1, drop=True).amplitude_z.max()) > 15
    assert float(near.where(near.param > 1, drop=True).amplitude_z.max()) > 15


@pytest.mark.slow
def test_fig10_11_scatter_at_the_seeds_is_on_stable_orbits(freq: Path) -> None:
    for part in ("fig10", "fig11"):
        sc = read_netcdf(freq / f"{part}.nc")
        br = xr.load_dataset(freq / f"{part}_branches.nc")
        for i, chi in enumerate(sc.chi.values):
            for lam in (float(sc.lam.values[0]), float(sc.lam.values[-1])):
                j = int(np.argmin(np.abs(sc.lam.values - lam)))
                at = br.where((br.chi == chi) & (np.abs(br.param - lam) < 1e-12) & br.stable, drop=True)
                amps = np.unique(np.round(at.amplitude_z.values, 9))
                assert amps.size >= 1, (part, chi, lam)
                for a in sc.amplitude.values[i, j].reshape(-1):
                    assert np.min(np.abs(amps - a)) <= 2e-3 * a, (part, chi, lam, a, amps)


@pytest.mark.slow
def test_fig10_11_bifurcations_written(freq: Path) -> None:
    bifs, doc = _rows(freq)
    folds = sorted({round(b["param_value"], 8) for b in bifs if b["type"] == "fold" and b["note"] == ""
                    and b["figure"] == "fig11" and b["chi"] == 0.7})
    # the two folds of the sub-harmonic zone at chi = 0.7 (the upper one: the fold of
    # test_continuation.py, located there with phi = 0.7: a phase shifts the orbit, not the fold)
    assert folds == [pytest.approx(0.0624978555, abs=1e-8), pytest.approx(0.1725095929, abs=1e-8)]
    assert doc["continuation"]["seeds"] == [0.35]
    summary = json.loads((freq / "summary.json").read_text())["summary"]
    assert summary["fig11_fold"] == sorted({round(b["param_value"], 10) for b in bifs
                                            if b["type"] == "fold" and b["figure"] == "fig11"})
    for name in ("fig10_orbits.png", "fig11_orbits.png"):
        assert (freq / name).stat().st_size > 10_000


@pytest.mark.slow
def test_branches_do_not_jump(band: Path, freq: Path) -> None:
    """Consecutive points of a branch are at most a few steps apart (the arclength step is at most
    ds_max = 0.1 or 0.2 in static deflections): a corrector that lands on another orbit (as the
    solve at the end of a range once did, from the two-stop motion at chi = 0.5 onto the four-stop
    one at lambda = 0.05, 0.44 apart) would show here."""
    for path, bound in ((band / "branches.nc", 0.6), (freq / "fig10_branches.nc", 0.3),
                        (freq / "fig11_branches.nc", 0.3)):
        br = xr.load_dataset(path)
        seg = br.segment.values if "segment" in br else np.zeros(br.point.size)
        bid, ok, amp = br.branch.values, br.converged.values.astype(bool), br.amplitude_z.values
        worst = 0.0
        for key in set(zip(seg, bid)):
            idx = np.where((seg == key[0]) & (bid == key[1]) & ok)[0]
            if idx.size > 1:
                worst = max(worst, float(np.abs(np.diff(amp[idx])).max()))
        assert 0 < worst <= bound, (path.name, worst)


@pytest.mark.parametrize("name, sets, message", [
    ("fig8_9_orbits", ["continuation.ds=-1"], "need 0 < ds <= ds_max"),
    ("fig8_9_orbits", ["continuation.stop=0.8"], "must differ"),
    ("fig8_9_orbits", ["brute_force.reference_period_doubling=[0.3,0.2]"], "reference_period_doubling must be"),
    ("fig8_9_orbits", ["brute_force.long_periods=1"], "long_periods must be >= 2"),
    ("fig8_9_orbits", ["brute_force.doubling_periods=0"], "doubling_periods must be >= 2"),
    ("fig8_9_orbits", ["brute_force.doubling_steps=0"], "doubling_steps must be >= 1"),
    ("fig8_9_orbits", ["sweep.chi.num=0"], r"sweep.chi.num must be in \[1, 10,000,000\]"),   # the base study's check
    ("fig10_11_orbits", ["continuation.resonance_gap=[1.1,1.2]"], "must hold lambda = 1"),
    ("fig10_11_orbits", ["continuation.seeds=[-0.1]"], r"continuation.seeds\[0\] must be > 0"),
    ("fig10_11_orbits", ["continuation.colour=1"], "unknown key 'continuation.colour'"),
])
def test_bad_config_is_one_clear_error(name: str, sets: list[str], message: str) -> None:
    from dryfriction.studies import effective_config
    from dryfriction.studies.config import ConfigError

    with pytest.raises(ConfigError, match=message):
        effective_config(name, quick=True, sets=sets)


def test_the_base_config_is_read_once() -> None:
    """The orbit studies' scatter values are their base studies' (one file each), [quick] included."""
    from dryfriction.studies import effective_config

    for name, base in (("fig8_9_orbits", "fig8_9"), ("fig10_11_orbits", "fig10_11")):
        for quick in (False, True):
            cfg, ref = effective_config(name, quick=quick), effective_config(base, quick=quick)
            assert {k: v for k, v in cfg.items() if k in ref} == ref
            assert "continuation" in cfg and "continuation" not in ref
