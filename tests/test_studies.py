"""The paper's studies on quick sizes: physics, not pictures.

- fig2: the FMU follows the exact stick-slip solution over the first cycle;
- fig3: the dataset holds the FMU's steady amplitudes and the Den Hartog / Inman formulas (the
  FMU against them: test_schemes.py);
- fig5_6: the resonant growth per period is pi - 4 mu_k N / P0 (averaging);
- fig7: stiction is longer below resonance than above and grows with friction;
- fig8_9: above the bifurcation the motion is symmetric and independent of the initial
  conditions, between it and the chaotic band periodic but asymmetric, below it spread over a band;
- fig12_14: four stick phases per cycle in the sub-harmonic zone, two above; nearby initial
  conditions part;
- chain2: the frictionless first block never sticks, the unforced one sticks more, a row is a
  direct run of the chain FMU; chain_waves: slip fronts travel outward block after block, below
  the chain's sound speed;
- the sweep engine: the same numbers bit for bit with 0 (no Dask), 1 and 2 workers; a killed
  sweep restarts from its chunks without recomputing them; bad input fails before any work.

The physics tests run sweeps in this process (``workers=0``); the Dask tests start a LocalCluster.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from dryfriction.drivers.oscillator import OscillatorFMU2, Settings
from dryfriction.params import Oscillator
from dryfriction.studies import main, run_study
from dryfriction.sweep import BatchRunner, PARAM_COLUMNS, SweepInterrupted, nondim_table, read_netcdf


DATA_VARS_8_9 = ("z_max", "z_min", "amplitude", "asymmetry", "stick_fraction", "transitions", "status")


def run(name: str, out: Path, fmu_path: Path, **kw) -> tuple[Path, dict]:
    res = run_study(name, quick=True, out=out, fmu=fmu_path, progress=False, **{"workers": 0, **kw})
    return res.out_dir, res.__dict__


# ---------------------------------------------------------------------------- building blocks


def test_table_rows_equal_from_nondimensional() -> None:
    nd = dict(lam=0.37, mu_s_sigma=0.55, chi=0.8, zeta=0.02, z0=-0.3, dz0=1.7, phi=0.4)
    row = nondim_table(nd, 30, 29, 30, 1000)[0]
    p = Oscillator.from_nondimensional(**nd)
    for name, value in p.as_dict().items():
        assert row[PARAM_COLUMNS.index(name)] == value, name
    assert row[PARAM_COLUMNS.index("h")] == p.period / 1000
    assert row[PARAM_COLUMNS.index("t_stop")] == 30 * p.period


@pytest.mark.min_versions
def test_batch_runner_equals_fmu_driver(fmu_path: Path, fmu: OscillatorFMU2) -> None:
    """The lean runner gives the observables of OscillatorFMU2.observables bit for bit, and a row
    the FMU rejects gives nan with status 1 without spoiling the next rows."""
    rows = [dict(lam=0.5, mu_s_sigma=0.6, chi=c, z0=z, dz0=0.3) for c, z in ((0.3, 0.5), (0.9, -1.0), (1.2, 0.0))]
    P = np.vstack([nondim_table(r, 12, 10, 12, 800) for r in rows])
    bad = P[1].copy()
    bad[PARAM_COLUMNS.index("m")] = -1.0
    runner = BatchRunner(fmu_path)
    try:
        out = runner.run(np.vstack([P[0], bad, P[1], P[2]]))
    finally:
        runner.close()
    assert out[1, -1] == 1 and np.all(np.isnan(out[1, :4]))
    ok = out[[0, 2, 3]]
    assert np.all(ok[:, -1] == 0)
    for r, res in zip(rows, ok):
        p = Oscillator.from_nondimensional(**r)
        o = fmu.observables(p, 12 * p.period, 10 * p.period, None, Settings(h=p.period / 800))
        assert res[0] == o["x_max"] and res[1] == o["x_min"]
        assert res[2] == o["stick_fraction"] and res[3] == o["E_friction"] and res[4] == o["transitions"]


# ---------------------------------------------------------------------------- physics


def test_fig2_fmu_follows_exact_solution(tmp_path: Path, fmu_path: Path) -> None:
    out, _ = run("fig2", tmp_path, fmu_path)
    ds = read_netcdf(out / "fig2.nc")
    amp = float(np.abs(ds.z_exact).max())
    assert float(np.abs(ds.z - ds.z_exact).max()) < 1e-3 * amp
    assert float(np.abs(ds.dz - ds.dz_exact).max()) < 1e-3 * float(np.abs(ds.dz_exact).max())
    # the cycle holds forward slip, stick and backward slip, and the FMU has the same modes
    assert {-1, 0, 1} <= set(np.unique(ds.mode_exact.values))
    assert np.mean(ds.mode.values != ds.mode_exact.values) < 0.01
    for f in ("fig2.png", "fig2.nc", "config.toml", "summary.json"):
        assert (out / f).is_file()
    assert not list(out.glob(".*tmp"))


def test_fig3_dataset_is_the_fmus_steady_state_and_the_references(tmp_path: Path, fmu_path: Path,
                                                                   fmu: OscillatorFMU2) -> None:
    """The study's plumbing: each amplitude is the one OscillatorFMU2.observables gives for the
    same run, and the reference columns are steady.py's formulas. (The FMU against Den Hartog and
    Inman themselves: test_schemes.py.)"""
    from dryfriction.references.steady import den_hartog_amplitude, inman_amplitude

    out, res = run("fig3", tmp_path, fmu_path)
    ds = read_netcdf(out / "fig3.nc")
    assert ds.lam.size == 10 and int(ds.status.max()) == 0
    periods, obs = ds.attrs["periods"], ds.attrs["obs_periods"]
    for lam in ds.lam.values[[0, 4, -1]]:
        p = Oscillator.from_nondimensional(lam=float(lam), mu_s_sigma=0.3, chi=1.0)
        o = fmu.observables(p, periods * p.period, (periods - obs) * p.period,
                            settings=Settings(h=p.period / ds.attrs["steps_per_period"]))
        amp = (o["x_max"] - o["x_min"]) / 2 * p.k / p.P0
        assert float(ds.amplitude.sel(lam=lam)) == pytest.approx(amp, rel=1e-12)
    p1 = Oscillator.from_nondimensional(lam=1.0, mu_s_sigma=0.3, chi=1.0)
    scale = p1.k / p1.P0
    np.testing.assert_allclose(ds.inman, np.asarray(inman_amplitude(p1, ds.lam.values)) * scale, rtol=1e-14)
    np.testing.assert_allclose(ds.den_hartog, np.asarray(den_hartog_amplitude(p1, ds.lam.values)) * scale,
                               rtol=1e-14)
    above = ds.lam.values >= 1.2
    dev = np.abs(ds.amplitude / ds.den_hartog - 1).values[above]
    assert res["summary"]["max_rel_dev_den_hartog_above"] == pytest.approx(np.nanmax(dev))


@pytest.mark.slow
def test_fig5_resonant_growth_follows_averaging(tmp_path: Path, fmu_path: Path) -> None:
    out, _ = run("fig5_6", tmp_path, fmu_path)
    ds = read_netcdf(out / "fig5_6.nc")
    f = 0.3  # mu_s sigma chi of configs/fig5_6.toml
    assert ds.attrs["growth_per_period_theory"] == pytest.approx(math.pi - 4 * f)
    assert ds.attrs["growth_per_period"] == pytest.approx(math.pi - 4 * f, rel=0.01)
    # near resonance the response stays bounded and beats: the envelope of |z| goes up and down
    z = ds.z_beating.isel(lam_beating=0).values
    c = ds.cycles_beating.values
    env = np.array([np.abs(z[(c >= k) & (c < k + 1)]).max() for k in range(int(c[-1]))])
    assert env.max() < 20
    assert np.any(np.diff(env) < -0.1) and np.any(np.diff(env) > 0.1)


@pytest.mark.slow
def test_fig7_stiction_longer_below_resonance_and_grows_with_friction(tmp_path: Path, fmu_path: Path) -> None:
    out, _ = run("fig7", tmp_path, fmu_path)
    ds = read_netcdf(out / "fig7.nc")
    st = ds.stiction_percent
    below = st.sel(lam=ds.lam[ds.lam < 0.9]).mean("lam")
    above = st.sel(lam=ds.lam[ds.lam > 1.1]).mean("lam")
    low = ds.mu_s_sigma < 0.6
    assert bool(np.all(below[low] > above[low] + 5))
    assert float(above.sel(mu_s_sigma=0.1)) < 0.5            # hardly any stiction at high frequency
    mean = st.mean("lam").values
    assert np.all(np.diff(mean) > 0)                          # grows with friction
    assert float(st.sel(mu_s_sigma=1.0).min()) > 99.9         # static limit = excitation: never moves
    assert np.all((st.values >= 0) & (st.values <= 100 + 1e-9))


@pytest.fixture(scope="module")
def fig8_9_local(tmp_path_factory: pytest.TempPathFactory, fmu_path: Path) -> xr.Dataset:
    out = tmp_path_factory.mktemp("fig8_9_local")
    d, _ = run("fig8_9", out, fmu_path)
    return read_netcdf(d / "fig8_9.nc")


@pytest.mark.slow
def test_fig8_9_bifurcation(fig8_9_local: xr.Dataset) -> None:
    ds = fig8_9_local
    assert int(ds.status.max()) == 0
    a = ds.amplitude.stack(ic=("z0", "dz0"))
    s = ds.asymmetry.stack(ic=("z0", "dz0"))
    ref = a.median("ic")
    spread = (a.max("ic") - a.min("ic")) / ref
    asym = abs(s).max("ic") / ref
    chi = ds.chi.values
    # the classification, a bool per chi
    assert ds.symmetric_periodic.dtype == bool
    assert np.array_equal(ds.symmetric_periodic.values, ((spread < 1e-3) & (asym < 1e-3)).values)
    # above the bifurcation: symmetric, one amplitude for all initial conditions
    hi = chi >= 0.65
    assert hi.sum() >= 4
    assert float(spread[hi].max()) < 1e-3
    assert float(asym[hi].max()) < 1e-3
    # between the bifurcation and the chaotic band: periodic (one amplitude) but asymmetric,
    # a mirror pair of asymmetries
    mid = (chi > 0.28) & (chi < 0.52)
    assert mid.sum() >= 2
    assert float(spread[mid].max()) < 1e-3
    assert float(asym[mid].min()) > 0.1
    for c in chi[mid]:
        sv = s.sel(chi=c).values
        assert sv.max() == pytest.approx(-sv.min(), rel=1e-3)
    # chaotic band: amplitudes spread over the initial conditions, more as chi decreases
    lo = chi < 0.22
    assert lo.sum() >= 2
    assert float(spread[lo].min()) > 0.03
    assert float(spread.sel(chi=chi[lo][0])) > float(spread.sel(chi=chi[lo][-1]))


@pytest.mark.slow
def test_fig12_14_subharmonic_zone(tmp_path: Path, fmu_path: Path) -> None:
    out, _ = run("fig12_14", tmp_path, fmu_path)
    ds = read_netcdf(out / "fig12_14.nc")
    sticks = dict(zip(ds.case.values, ds.stick_phases_per_cycle.values))
    assert sticks["in_zone"] == pytest.approx(4.0) and sticks["above_zone"] == pytest.approx(2.0)
    a, b = ds.amplitude14.values
    assert abs(a - b) > 0.1 * max(a, b)                       # two different motions
    assert ds.attrs["ic_distance"] <= 1e-4                    # ... from initial conditions this close
    assert ds.attrs["t_part_over_T"] > ds.attrs["t_first_stick_over_T"]


# ---------------------------------------------------------------------------- engine (Dask)


def _same(a: xr.Dataset, b: xr.Dataset, names: tuple[str, ...] = DATA_VARS_8_9) -> None:
    for n in names:
        assert np.array_equal(a[n].values, b[n].values, equal_nan=True), n
    for c in a.coords:
        assert np.array_equal(a[c].values, b[c].values), c


@pytest.mark.min_versions
@pytest.mark.slow
@pytest.mark.no_sanitizer
@pytest.mark.parametrize("workers", [1, 2])
def test_fig8_9_same_numbers_with_1_and_2_workers(workers: int, tmp_path: Path, fmu_path: Path,
                                                  fig8_9_local: xr.Dataset) -> None:
    d, res = run("fig8_9", tmp_path, fmu_path, workers=workers)
    _same(read_netcdf(d / "fig8_9.nc"), fig8_9_local)
    assert res["stats"][0].computed == res["stats"][0].chunks == 12


@pytest.mark.slow
@pytest.mark.no_sanitizer
def test_killed_sweep_restarts_from_its_chunks(tmp_path: Path, fmu_path: Path, fig8_9_local: xr.Dataset) -> None:
    final = tmp_path / "fig8_9" / "fig8_9.nc"
    # a sweep stopped after 5 chunks leaves no dataset, 5 chunk files
    with pytest.raises(SweepInterrupted):
        run("fig8_9", tmp_path, fmu_path, workers=2, max_chunks=5)
    assert not final.exists()
    chunks = sorted((tmp_path / "fig8_9" / "chunks").glob("fig8_9-*/c*.chunk"))
    assert len(chunks) == 5
    stamp = {c: c.stat().st_mtime_ns for c in chunks}
    # restarted: the 5 are loaded, not recomputed, the 7 others computed
    _, res = run("fig8_9", tmp_path, fmu_path, workers=2)
    st = res["stats"][0]
    assert (st.loaded, st.computed) == (5, 7)
    assert all(c.stat().st_mtime_ns == t for c, t in stamp.items())
    _same(read_netcdf(final), fig8_9_local)
    # the final file and some chunks deleted (a crash mid-write): only those chunks are recomputed
    final.unlink()
    all_chunks = sorted(chunks[0].parent.glob("c*.chunk"))
    for c in all_chunks[::4]:
        c.unlink()
    _, res = run("fig8_9", tmp_path, fmu_path, workers=0)
    st = res["stats"][0]
    assert (st.loaded, st.computed) == (12 - len(all_chunks[::4]), len(all_chunks[::4]))
    _same(read_netcdf(final), fig8_9_local)
    # a changed config does not reuse the chunks of the old one (and removes them)
    _, res = run("fig8_9", tmp_path, fmu_path, workers=0, sets=["sweep.chi.num=2", "numerics.chunk_runs=50"])
    assert res["stats"][0].loaded == 0
    assert len(list((tmp_path / "fig8_9" / "chunks").iterdir())) == 1


KILLED_AFTER_3_CHUNKS = """
import os, signal, sys
import dryfriction.sweep.engine as engine
from dryfriction.studies import main
save, saved = engine.save_chunk, []
def save_then_die(path, arr):
    save(path, arr)
    saved.append(path)
    if len(saved) == 3:
        os.kill(os.getpid(), signal.SIGKILL)  # killed right after its third chunk is on disk
engine.save_chunk = save_then_die
sys.exit(main(sys.argv[1:]))
"""


@pytest.mark.slow
def test_sigkilled_sweep_resumes(tmp_path: Path, fmu_path: Path, fig8_9_local: xr.Dataset) -> None:
    """A sweep process killed with SIGKILL mid-way (after its third chunk, on every machine): the
    chunks it finished are reused as they are, the rest is computed, and the numbers are those of
    an uninterrupted run (with other chunks)."""
    import signal
    import subprocess
    import sys

    argv = [sys.executable, "-c", KILLED_AFTER_3_CHUNKS, "fig8_9", "--quick", "--workers", "0", "--no-progress",
            "--out", str(tmp_path), "--fmu", str(fmu_path), "--set", "numerics.chunk_runs=4"]
    proc = subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, timeout=300)
    assert proc.returncode == -signal.SIGKILL, proc.stderr
    assert not (tmp_path / "fig8_9" / "fig8_9.nc").exists()
    kept = {c: c.stat().st_mtime_ns for c in (tmp_path / "fig8_9" / "chunks").glob("fig8_9-*/c*.chunk")}
    assert len(kept) == 3
    _, res = run("fig8_9", tmp_path, fmu_path, sets=["numerics.chunk_runs=4"])
    st = res["stats"][0]
    assert (st.loaded, st.computed) == (3, 75 - 3)
    assert all(c.stat().st_mtime_ns == t for c, t in kept.items())
    _same(read_netcdf(tmp_path / "fig8_9" / "fig8_9.nc"), fig8_9_local)


# ---------------------------------------------------------------------------- command line


def test_list_show_config_and_config_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["list"]) == 0
    listing = capsys.readouterr().out
    for name in ("fig2", "fig3", "fig4", "fig5_6", "fig7", "fig8_9", "fig10_11", "fig12_14"):
        assert name in listing
    user = tmp_path / "my.toml"
    user.write_text("[sweep]\nperiods = 20.0\nchi = { num = 7 }\n")
    assert main(["fig9", "--quick", "--config", str(user), "--set", "params.lam=0.6", "--show-config"]) == 0
    text = capsys.readouterr().out
    assert "periods = 20.0" in text and "num = 7" in text and "lam = 0.6" in text


@pytest.mark.min_versions
@pytest.mark.slow
def test_studies_run_through_the_module_entry_point(tmp_path: Path, fmu_path: Path) -> None:
    import subprocess
    import sys

    r = subprocess.run([sys.executable, "-m", "dryfriction.studies", "fig4", "--quick", "--out", str(tmp_path),
                        "--fmu", str(fmu_path)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    ds = read_netcdf(tmp_path / "fig4" / "fig4.nc")
    stuck = dict(zip(ds.case.values, ds.stuck_share.values))
    assert stuck["below"] > 0.3 and stuck["above"] == 0.0
    assert (tmp_path / "fig4" / "fig4.png").stat().st_size > 10_000


# ---------------------------------------------------------------------------- the chain's studies


@pytest.fixture(scope="module")
def chain_fmu3() -> Path:
    from dryfriction.drivers.chain import default_chain_fmu3

    path = default_chain_fmu3()
    if not path.is_file():
        pytest.fail(f"FMI 3.0 chain FMU not built: {path} (cmake --build build)")
    return path


def test_chain2_quick(tmp_path: Path, chain_fmu3: Path) -> None:
    """Two blocks, the first forced: the frictionless first block of the 'second' configuration
    never sticks; a row of the dataset is a direct run of the chain; the far block sticks more."""
    from dryfriction.drivers.chain import ChainFMU3
    from dryfriction.studies.chain2 import chain_params

    out, res = run("chain2", tmp_path, chain_fmu3)
    ds = read_netcdf(out / "chain2.nc")
    assert ds.amplitude.dims == ("config", "lam", "x0_1", "x0_2", "block")
    assert ds.amplitude.shape == (2, 12, 2, 2, 2) and ds.stick_share.shape == ds.amplitude.shape
    assert int(ds.attrs["failed_runs"]) == 0 and not bool(np.isnan(ds.amplitude).any())
    s = ds.stick_share
    assert float(s.min()) >= 0.0 and float(s.max()) <= 1.0
    assert float(s.sel(config="second", block=1).max()) == 0.0          # no friction: never stuck
    assert float(s.sel(config="both", block=1).max()) > 0.2             # with friction it sticks
    for c in ("both", "second"):                                        # the unforced block sticks more
        assert float(s.sel(config=c, block=2).mean()) > float(s.sel(config=c, block=1).mean())
    # plumbing: one row again through the driver, the same numbers
    cfg, lam = res["summary"], float(ds.lam.values[4])
    ch = {k[len("chain_"):]: ds.attrs[k] for k in ds.attrs if k.startswith("chain_")}
    num = {"steps_per_period": ds.attrs["steps_per_period"], "alpha": ds.attrs["alpha"], "scheme": ds.attrs["scheme"]}
    p = chain_params(ch, "both", lam, (-2.0, 2.0), num)
    T = 2 * np.pi / p["omega"]
    with ChainFMU3(2, fmu_path=chain_fmu3) as f:
        f.start(p)
        f.step_to((ds.attrs["periods"] - ds.attrs["obs_periods"]) * T)
        r = f.record(ds.attrs["periods"] * T, T / ds.attrs["samples_per_period"])
    sel = dict(config="both", lam=lam, x0_1=-2.0, x0_2=2.0)
    assert np.array_equal(ds.amplitude.sel(**sel).values, r.amplitude())
    assert np.array_equal(ds.stick_share.sel(**sel).values, r.stick_share())
    assert cfg["runs"] == 96 and (out / "chain2.png").stat().st_size > 10_000


def test_chain_waves_quick(tmp_path: Path, chain_fmu3: Path) -> None:
    """Slip fronts leave the forced block and travel along the chain: the first slip times grow
    with the block index, no faster than the chain's sound speed sqrt(k/m) (1 block/s), a larger
    force reaches farther, and the far blocks stick more than the forced one."""
    out, res = run("chain_waves", tmp_path, chain_fmu3)
    ds = read_netcdf(out / "chain_waves.nc")
    n = ds.block.size
    assert n == 64 and ds.mode.dims == ("P0", "time", "block") and ds.P0.size == 2
    assert ds.mode.shape[1] == 2 * 200 + 1
    main_mode = ds.mode.sel(P0=1.0).values
    assert set(np.unique(main_mode)) == {-1, 0, 1}
    for p in ds.P0.values:
        first = ds.first_slip_time.sel(P0=p).values
        reached = first[np.isfinite(first)]
        assert reached.size >= 3 and np.all(np.diff(reached) >= 0)     # the front moves outward
        assert np.all(np.isfinite(first[:reached.size]))               # ... block after block
        assert 0.05 < float(ds.front_speed.sel(P0=p)) <= 1.05
    assert int(ds.blocks_reached.sel(P0=1.0)) >= int(ds.blocks_reached.sel(P0=0.5))
    st = ds.stick_share.sel(P0=1.0).values
    assert st[0] < 0.5 and st[-1] > st[0]
    assert res["summary"]["n"] == 64 and (out / "chain_waves.png").stat().st_size > 10_000


def test_fig3_sweep_without_an_excluded_band() -> None:
    """sweep.exclude = [] is accepted (nothing left out), no more [5, 6] to say "none"."""
    import tomllib

    from dryfriction.model import repository_xml
    from dryfriction.studies import fig3_frequency_response as fig3

    cfg = tomllib.loads((repository_xml().parent / "configs" / "fig3.toml").read_text())
    full = fig3.lambdas({**cfg, "sweep": {**cfg["sweep"], "exclude": [0.0, 0.0]}})
    cfg["sweep"]["exclude"] = []
    fig3.check(cfg)
    assert fig3.lambdas(cfg).size == full.size
    cfg["sweep"]["exclude"] = [1.0]
    with pytest.raises(Exception, match=r"\[low, high\] or \[\]"):
        fig3.check(cfg)
