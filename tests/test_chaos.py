"""Is it chaos? Physics of the chaos tools (docs/chaos.md), on quick sizes.

The FMU's `exact` scheme is the chaos tools' default; `located` (Bossak) stays selectable.

- a periodic motion (lambda 0.5, mu_s sigma 0.6, chi 1, the symmetric motion of Fig. 8/9) has a
  negative exponent and a single stroboscopic point, the exact solution's;
- with `located` the exponent converges under refinement of h; with `exact` h has no effect; the
  exponent does not depend on d0 or on the renormalisation interval;
- the chaotic motion at chi = 0.1 has a positive exponent (~0.21 per period) that the exact
  solution (dryfriction.references.exact), driven as an independent perturbed pair, reproduces, from the FMU's
  exact scheme (pair by pair while the trajectories stay together, then statistically) and from
  `located`; on a periodic motion the exact scheme's exponent is negative and equals the exact
  solution's;
- basins on a quick grid: shares add to 1, and direct runs from sample points reach the attractor
  the map gives them;
- the CLI's JSON and its one-line errors.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from dryfriction.analysis.chaos import Catalogue, ExactMap, FMUMap, NDParams, benettin, period_of
from dryfriction.drivers.oscillator import OscillatorFMU2
from dryfriction.studies import run_study
from dryfriction.sweep import read_netcdf


FIG89 = dict(lam=0.5, mu_s_sigma=0.6)
CHAOTIC = NDParams(0.5, 0.6, 0.1)      # established by the chaos_scan study: exponent ~ +0.21 / period
PERIODIC = NDParams(0.5, 0.6, 1.0)     # symmetric period-1 motion for every initial condition


def test_periodic_motion_negative_exponent_single_point(fmu: OscillatorFMU2) -> None:
    r = benettin(FMUMap(fmu, PERIODIC), 0.7, -0.4, periods=200, transient=50)
    assert r.lyapunov_per_period < -1.0                       # strongly attracting
    assert r.lyapunov_per_period + 5 * r.stderr_per_period < 0
    assert r.lyapunov_per_second == pytest.approx(r.lyapunov_per_period / r.period_s)
    tail = r.strobe[-40:]
    assert period_of(tail, 1e-9) == 1                          # a single stroboscopic point
    # the exact solution shows the same motion periodic, with the same point (the FMU's exact scheme)
    ex = ExactMap(PERIODIC).orbit(0.7, -0.4, 60, 4)
    assert np.max(np.abs(ex - ex[0])) < 1e-9
    assert np.max(np.abs(tail[-1] - ex[-1])) < 1e-9
    # located (Bossak, h = T/1000): the same point to its second-order error
    loc = FMUMap(fmu, PERIODIC, 1000, "located").orbit(0.7, -0.4, 60, 1)
    assert np.max(np.abs(loc[-1] - ex[-1])) < 1e-4


def test_exponent_converges_under_h(fmu: OscillatorFMU2) -> None:
    """The Bossak path (located): the exponent converges as h is refined."""
    # periodic, asymmetric motion (chi 0.4): deterministic exponent, converges as h^2
    lam = {n: benettin(FMUMap(fmu, NDParams(0.5, 0.6, 0.4), n, "located"), 0.0, 0.0, periods=100, transient=100)
           .lyapunov_per_period for n in (1000, 2000, 4000)}
    assert lam[1000] < -0.5
    assert abs(lam[2000] - lam[4000]) < 1e-2 * abs(lam[4000])
    assert abs(lam[2000] - lam[4000]) < 0.6 * abs(lam[1000] - lam[4000]) + 1e-6
    # chaotic motion: trajectories part, but the exponent agrees within 0.02 per period (10 %)
    chaos = [benettin(FMUMap(fmu, CHAOTIC, n, "located"), 0.0, 0.0, periods=1000, transient=100)
             for n in (1000, 2000, 4000)]
    vals = np.array([c.lyapunov_per_period for c in chaos])
    assert np.all(vals > 0.15)
    assert vals.max() - vals.min() < 0.02


def test_exponent_independent_of_d0_and_renormalisation(fmu: OscillatorFMU2) -> None:
    m = FMUMap(fmu, CHAOTIC)
    by_d0 = [benettin(m, 0.0, 0.0, periods=600, transient=100, d0=d0).lyapunov_per_period
             for d0 in (1e-6, 1e-8, 1e-10)]
    assert max(by_d0) - min(by_d0) < 0.005
    by_renorm = [benettin(m, 0.0, 0.0, periods=600, transient=100, renorm=k).lyapunov_per_period for k in (1, 2, 5)]
    assert min(by_renorm) > 0.15
    assert max(by_renorm) - min(by_renorm) < 0.02


def test_exact_scheme_step_free(fmu: OscillatorFMU2) -> None:
    """The exact scheme: h has no effect, to the bit (chaotic and periodic motion)."""
    for nd in (CHAOTIC, NDParams(0.5, 0.6, 0.4)):
        a, b = (benettin(FMUMap(fmu, nd, n), 0.0, 0.0, periods=100, transient=20) for n in (100, 3000))
        assert a.lyapunov_per_period == b.lyapunov_per_period
        np.testing.assert_array_equal(a.strobe, b.strobe)
        assert a.method == "FMU scheme exact"


def test_exact_scheme_exponent_equals_exact_solution(fmu: OscillatorFMU2) -> None:
    """The FMU's exact scheme against the Python exact solution (dryfriction.references.exact), pair by pair."""
    # chaotic motion: while the two reference trajectories stay together (1e-13 grows e-fold in about
    # 5 periods) every renormalisation measures the same stretching
    ex = benettin(ExactMap(CHAOTIC), 0.0, 0.0, periods=250, transient=20)
    fe = benettin(FMUMap(fmu, CHAOTIC), 0.0, 0.0, periods=250, transient=20)
    assert np.max(np.abs(fe.strobe[:30] - ex.strobe[:30])) < 1e-6
    assert abs(fe.running[29] - ex.running[29]) < 1e-5
    assert ex.lyapunov_per_period - 3 * ex.stderr_per_period > 0.1
    # then statistically: a long FMU run against the exact solution's estimate
    long = benettin(FMUMap(fmu, CHAOTIC), 0.0, 0.0, periods=3000, transient=100)
    assert long.lyapunov_per_period - 3 * long.stderr_per_period > 0.15
    assert period_of(long.strobe[-64:], 1e-6) == 0
    assert abs(long.lyapunov_per_period - ex.lyapunov_per_period) < 3 * (ex.stderr_per_period + long.stderr_per_period)
    # periodic motion (chi 0.4, the asymmetric pair): negative, the same number to 1e-5
    nd = NDParams(0.5, 0.6, 0.4)
    ep = benettin(ExactMap(nd), 0.0, 0.0, periods=100, transient=100)
    fp = benettin(FMUMap(fmu, nd), 0.0, 0.0, periods=100, transient=100)
    assert fp.lyapunov_per_period < -1.0
    assert fp.lyapunov_per_period == pytest.approx(ep.lyapunov_per_period, abs=1e-5)
    assert period_of(fp.strobe[-20:], 1e-9) == 1


def test_chaotic_exponent_reproduced_by_exact_solution(fmu: OscillatorFMU2) -> None:
    """The Bossak path (located, h = T/2000) reproduces the exact solution's exponent."""
    fm = benettin(FMUMap(fmu, CHAOTIC, 2000, "located"), 0.0, 0.0, periods=1000, transient=100)
    ex = benettin(ExactMap(CHAOTIC), 0.0, 0.0, periods=250, transient=50)
    assert fm.lyapunov_per_period - 3 * fm.stderr_per_period > 0.1
    assert ex.lyapunov_per_period - 3 * ex.stderr_per_period > 0.1      # chaos in the exact solution itself
    assert period_of(ex.strobe[-64:], 1e-6) == 0
    assert abs(fm.lyapunov_per_period - ex.lyapunov_per_period) < 0.03 + 2 * ex.stderr_per_period


def test_catalogue_labels_mirror_orbits_and_chaos() -> None:
    cat = Catalogue(tol=1e-4)
    a = np.tile([[0.8, 0.1], [1.1, -0.2]], (8, 1))
    b = np.tile([[1.1, -0.2], [0.8, 0.1]], (8, 1)) + 1e-6      # same orbit, other phase
    c = np.tile([[1.84, 0.3], [1.85, 0.2]], (8, 1))
    rng = np.random.default_rng(0)
    assert [cat.label(x, 1e-5) for x in (a, b, c, rng.normal(size=(16, 2)))] == [0, 0, 1, 2]
    assert [x.period for x in cat.attractors] == [2, 2, 0]


@pytest.mark.slow
def test_basins_shares_and_direct_runs(tmp_path: Path, fmu_path: Path, fmu: OscillatorFMU2) -> None:
    out = run_study("chaos_basins", quick=True, out=tmp_path, fmu=fmu_path, workers=0, progress=False,
                    sets=['cases=["subharmonic", "end_of_chaos"]', "grid.z0.num=9", "grid.dz0.num=9"])
    for case in ("subharmonic", "end_of_chaos"):
        ds = read_netcdf(out.out_dir / f"chaos_basins_{case}.nc")
        assert ds.attrs["scheme"] == "exact"
        assert float(ds.share.sum()) == pytest.approx(1.0, abs=1e-12)
        assert ds.share.size == 2 and float(ds.share.min()) > 0.1          # two coexisting motions
        lab = ds.attractor.values
        counts = np.bincount(lab.ravel(), minlength=ds.share.size) / lab.size
        np.testing.assert_allclose(counts, ds.share.values)
        t = run_study.__globals__["effective_config"]("chaos_basins", quick=True)[case]
        m = FMUMap(fmu, NDParams(t["lam"], t["mu_s_sigma"], t["chi"], t["zeta"]), int(ds.attrs["steps_per_period"]),
                   str(ds.attrs["scheme"]))
        for i, j in ((0, 0), (2, 7), (4, 4), (6, 1), (8, 8)):
            tail = m.orbit(float(ds.z0[i]), float(ds.dz0[j]), t["transient"], t["tail"])
            k = int(lab[i, j])
            p = int(ds.attractor_period[k])
            assert period_of(tail, 1e-6) == p
            pts = np.column_stack([ds.attractor_z[k, :p], ds.attractor_dz[k, :p]])
            assert np.max(np.abs(tail[-p:, None, :] - pts[None]), axis=2).min(axis=1).max() < 1e-4


@pytest.mark.slow
def test_scan_quick_verdict(tmp_path: Path, fmu_path: Path) -> None:
    out = run_study("chaos_scan", quick=True, out=tmp_path, fmu=fmu_path, workers=0, progress=False)
    s = out.summary
    assert s["scheme"] == "exact"
    assert 0.14 < s["chi_chaos_onset"] < 0.26 and s["chi_chaos_onset_uncertainty"] < 0.02
    ds = read_netcdf(out.out_dir / "chaos_scan.nc")
    chaotic = ((ds.lyapunov_per_period.values > 0) & (ds.period.values == 0)).all(axis=1)
    assert ds.chaotic.dtype == bool and not ds.chaotic.values[ds.chi.values > 0.25].any()
    lyap, period, chi = ds.lyapunov_per_period.values, ds.period.values, ds.chi.values
    assert chaotic[chi < 0.15].all()
    assert (lyap[chi > 0.25] < 0).all()
    # periodic, except close to a bifurcation where the exponent nears 0 and 150 periods do not settle
    assert (period[chi > 0.25][lyap[chi > 0.25] < -0.1] > 0).all()
    assert ds.attrs["scheme"] == "exact"


@pytest.mark.slow
def test_transients_quick(tmp_path: Path, fmu_path: Path) -> None:
    out = run_study("chaos_transients", quick=True, out=tmp_path, fmu=fmu_path, workers=0, progress=False)
    ds = read_netcdf(out.out_dir / "chaos_transients.nc")
    settled = ds.settled_share.sel(checkpoint=300).values
    chi = ds.chi.values
    assert np.all(settled[chi < 0.15] == 0)            # chaotic: no initial condition settles
    assert np.all(settled[chi > 0.25] == 1)            # the asymmetric pair: all settle
    spread = ds.amplitude_spread.values
    # where all settle, the spread over the ICs falls from the 30-period value to the attractors'
    assert np.all(spread[chi > 0.25, -1] <= spread[chi > 0.25, 0] + 1e-9)


@pytest.mark.slow
def test_basins_on_dask_equal_in_process(tmp_path: Path, fmu_path: Path) -> None:
    """The Dask path (2 worker processes, FMU sent as bytes) gives the same labels as this process."""
    sets = ['cases=["subharmonic"]', "subharmonic.grid_num=7", "subharmonic.transient=60", "numerics.chunk_runs=10"]
    a = run_study("chaos_basins", quick=True, out=tmp_path / "a", fmu=fmu_path, workers=0, progress=False, sets=sets)
    b = run_study("chaos_basins", quick=True, out=tmp_path / "b", fmu=fmu_path, workers=2, progress=False, sets=sets)
    da = read_netcdf(a.out_dir / "chaos_basins_subharmonic.nc")
    db = read_netcdf(b.out_dir / "chaos_basins_subharmonic.nc")
    np.testing.assert_array_equal(da.attractor.values, db.attractor.values)
    np.testing.assert_array_equal(da.final_z.values, db.final_z.values)          # bit for bit
