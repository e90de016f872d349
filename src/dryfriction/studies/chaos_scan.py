"""Is it chaos? The largest Lyapunov exponent and the bifurcation diagram (stroboscopic z) against
chi over the range of Fig. 8/9, the onset of chaos refined, and a Poincare section of a chaotic
motion. See configs/chaos_scan.toml and docs/chaos.md."""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

from ..analysis.chaos.attractors import Catalogue, period_of
from ..analysis.chaos.batch import concat, lyapunov_rows, map_chunks, orbit_tails
from ..analysis.chaos.lyapunov import benettin
from ..analysis.chaos.maps import ExactMap, FMUMap, NDParams, scheme_label
from ..budget import EXACT_PERIOD_STEPS
from .common import Estimate, FIGURE_BYTES, StudyContext, check_numerics, check_params, plt, trajectory_estimate
from .config import grid, require
from . import REGISTRY

NAME = "chaos_scan"
TITLE = REGISTRY[NAME].title
FIGURES = REGISTRY[NAME].figures
DATASET = "chaos_scan.nc"


def check(cfg: dict[str, Any]) -> None:
    """Refuse a configuration of the chaos scan with a value out of range (ConfigError naming the key), before
    any work."""
    check_params(cfg["params"])
    check_numerics(cfg["numerics"])
    s, ly = cfg["scan"], cfg["lyapunov"]
    grid(s["chi"], "scan.chi")
    require(s["chi"]["start"] > 0 and s["chi"]["stop"] > 0, "scan.chi must stay > 0")
    require(len(s["z0"]) == len(s["dz0"]) >= 1, "scan.z0 and scan.dz0 must be lists of the same length >= 1")
    require(ly["periods"] >= 20 and ly["renorm"] >= 1 and ly["periods"] >= ly["renorm"],
            "lyapunov.periods must be >= 20 and >= lyapunov.renorm >= 1")
    require(ly["transient"] >= 0, "lyapunov.transient must be >= 0")
    require(0 < ly["d0"] < 1e-2, f"lyapunov.d0 must be in (0, 1e-2), not {ly['d0']}")
    require(2 <= ly["keep"] <= ly["periods"] // ly["renorm"], "lyapunov.keep must be in [2, periods / renorm]")
    require(cfg["refine"]["num"] >= 0 and cfg["refine"]["periods"] >= 20, "refine.num >= 0, refine.periods >= 20")
    require(isinstance(cfg["check"]["chi"], list) and all(c > 0 for c in cfg["check"]["chi"])
            and cfg["check"]["periods"] >= 20, "check.chi must be a list of chi > 0, check.periods >= 20")
    require(cfg["section"]["points"] >= 10 and cfg["section"]["chi"] > 0, "section.points >= 10, section.chi > 0")


def _scan(ctx: StudyContext, chis: np.ndarray, ics: np.ndarray, ly: dict[str, Any], desc: str) -> dict[str, np.ndarray]:
    cfg = ctx.cfg
    chunks = []
    for chi in chis:
        rows = np.column_stack([np.full(len(ics), chi), ics])
        chunks.append((cfg["params"], cfg["numerics"], ly, rows, int(ly["keep"])))
    o = ctx.engine_options
    res, st = map_chunks(lyapunov_rows, o.fmu, chunks, o.workers, o.scheduler, o.progress, desc)
    ctx.log(f"{desc}: {len(chis)} chi x {len(ics)} initial conditions x {ly['transient']} + {ly['periods']} periods "
            f"in {st.wall:.1f} s (cluster start {st.startup:.1f} s, task CPU {st.task_cpu:.1f} s)")
    out = {k: concat(res, k).reshape((len(chis), len(ics)) + concat(res, k).shape[1:])
           for k in ("lyapunov", "stderr", "half_difference", "collapses", "strobe")}
    out["wall"] = np.array(st.wall)
    out["cpu"] = np.array(st.task_cpu)
    return out


#: longest period looked for in the stroboscopic points (near the onset of chaos there are
#: periodic windows of period 10 and 16)
MAX_PERIOD = 32


def classify(strobe: np.ndarray, lyap: np.ndarray, stderr: np.ndarray, tol: float) -> dict[str, np.ndarray]:
    """Per chi: the period of each run (0: none up to min(32, kept points / 2)), the number of
    distinct attractors the runs reached, and whether chaos is established for a run (exponent more
    than 3 standard errors above 0 and no period)."""
    n_chi, n_ic = lyap.shape
    period = np.zeros((n_chi, n_ic), dtype=int)
    n_att = np.zeros(n_chi, dtype=int)
    max_p = min(MAX_PERIOD, strobe.shape[2] // 2)
    for i in range(n_chi):
        cat = Catalogue(tol=max(tol, 1e-9) * 100, max_period=max_p)
        for j in range(n_ic):
            period[i, j] = period_of(strobe[i, j], tol, max_p)
            cat.label(strobe[i, j], period_tol=tol)
        n_att[i] = len(cat.attractors)
    chaotic = (lyap - 3 * stderr > 0) & (period == 0)
    return {"period": period, "attractors": n_att, "chaotic": chaotic}


def zero_crossing(chi: np.ndarray, lyap: np.ndarray) -> tuple[float, float]:
    """Where the (mean) exponent crosses 0 as chi grows: a straight line fitted to the points up to
    the first non-positive one and the next (at least 3 points), its root and the root's standard
    error from the fit's residuals; nan if the exponent does not change sign."""
    neg = np.nonzero(lyap <= 0)[0]
    if neg.size == 0 or neg[0] == 0:
        return float("nan"), float("nan")
    n = min(max(neg[0] + 2, 3), chi.size)
    x, y = chi[:n], lyap[:n]
    A = np.column_stack([x, np.ones_like(x)])
    coef, *_ = np.linalg.lstsq(A, y, rcond=None)
    a, b = coef
    if a >= 0:
        return float("nan"), float("nan")
    res = y - A @ coef
    s = float(np.sqrt(np.sum(res**2) / max(n - 2, 1)))
    root = -b / a
    # standard error of the root: the residual scatter over the slope, plus the slope's own error
    xm = x.mean()
    sxx = float(np.sum((x - xm) ** 2))
    se = s / abs(a) * np.sqrt(1.0 / n + (root - xm) ** 2 / sxx) if sxx > 0 else float("nan")
    return float(root), float(se)


def run(ctx: StudyContext) -> dict[str, Any]:
    """Run the chaos scan: its runs, dataset and figures in the study's folder; returns the summary."""
    cfg = ctx.cfg
    nd, s, ly, num = cfg["params"], cfg["scan"], cfg["lyapunov"], cfg["numerics"]
    chis = grid(s["chi"], "scan.chi")
    ics = np.column_stack([s["z0"], s["dz0"]]).astype(float)
    scan = _scan(ctx, chis, ics, ly, "lyapunov scan")
    cls = classify(scan["strobe"], scan["lyapunov"], scan["stderr"], ly["tol"])
    T_s = NDParams.from_mapping(nd, chi=1.0).oscillator().period    # T in s at the reference scales

    # ---- onset of chaos: refine between the largest chaotic chi and the next chi of the scan
    any_chaos = cls["chaotic"].any(axis=1)
    summary: dict[str, Any] = {"scheme": num["scheme"], "steps_per_period": num["steps_per_period"],
                               "scan_wall_s": float(scan["wall"]), "scan_task_cpu_s": float(scan["cpu"]),
                               "runs": int(chis.size * len(ics)),
                               "periods_per_run": int(ly["transient"] + ly["periods"])}
    ref = None
    if any_chaos.any() and not any_chaos.all():
        i_hi = int(np.nonzero(any_chaos)[0].max())
        lo_c = float(chis[i_hi])
        hi_c = float(chis[min(i_hi + 1, chis.size - 1)])
        if cfg["refine"]["num"] >= 2 and hi_c > lo_c:
            rchis = np.linspace(lo_c, hi_c, int(cfg["refine"]["num"]))
            rly = {**ly, "periods": int(cfg["refine"]["periods"])}
            ref = _scan(ctx, rchis, ics, rly, "onset refinement")
            rcls = classify(ref["strobe"], ref["lyapunov"], ref["stderr"], ly["tol"])
            rchaos = rcls["chaotic"].any(axis=1)
            j = int(np.nonzero(rchaos)[0].max()) if rchaos.any() else 0
            lo_c, hi_c = float(rchis[j]), float(rchis[min(j + 1, rchis.size - 1)])
            if j == rchis.size - 1:
                # the longer refinement runs establish chaos up to the bracket's top: the onset lies
                # between it and the next chi of the scan
                hi_c = float(chis[min(i_hi + 2, chis.size - 1)])
            ref.update(rcls)
            ref["chi"] = rchis
            root, sig = zero_crossing(rchis, ref["lyapunov"].mean(axis=1))
            summary.update(chi_lyapunov_zero=root, chi_lyapunov_zero_uncertainty=sig)
        summary.update(chi_chaos_onset=0.5 * (lo_c + hi_c), chi_chaos_onset_uncertainty=0.5 * (hi_c - lo_c),
                       chi_last_chaotic=lo_c, chi_first_regular=hi_c)
    chaotic_chis = chis[any_chaos]
    summary.update(
        chi_chaotic_min=float(chaotic_chis.min()) if chaotic_chis.size else float("nan"),
        chi_chaotic_max=float(chaotic_chis.max()) if chaotic_chis.size else float("nan"),
        chaotic_all_ics=[float(c) for c in chis[cls["chaotic"].all(axis=1)]],
        lyapunov_max_per_period=float(np.nanmax(scan["lyapunov"])),
        chi_at_lyapunov_max=float(chis[int(np.nanargmax(np.nanmax(scan["lyapunov"], axis=1)))]),
        coexisting_chis=[float(c) for c in chis[cls["attractors"] > 1]],
        periods_seen={f"{c:.4g}": sorted({int(p) for p in cls["period"][i]}) for i, c in enumerate(chis)},
    )

    # ---- the exponent from the exact solution, an independent calculation
    ck = cfg["check"]
    exact_rows = []
    f = ctx.fmu()
    for chi in ck["chi"]:
        ndc = NDParams.from_mapping(nd, chi=float(chi))
        ex = benettin(ExactMap(ndc), 0.0, 0.0, periods=int(ck["periods"]), transient=int(ck["transient"]), d0=ly["d0"])
        fm = benettin(FMUMap(f, ndc, int(num["steps_per_period"]), num["scheme"], num["alpha"]), 0.0, 0.0,
                      periods=int(ck["periods"]), transient=int(ck["transient"]), d0=ly["d0"])
        exact_rows.append((float(chi), ex.lyapunov_per_period, ex.stderr_per_period, fm.lyapunov_per_period,
                           fm.stderr_per_period))
        ctx.log(f"exponent at chi = {chi:g} from (0, 0), {ck['periods']} periods: exact {ex.lyapunov_per_period:+.4f} "
                f"+- {ex.stderr_per_period:.4f}, FMU {fm.lyapunov_per_period:+.4f} +- {fm.stderr_per_period:.4f}")
    summary["exact_check"] = [dict(zip(("chi", "exact", "exact_stderr", "fmu", "fmu_stderr"), r)) for r in exact_rows]

    # ---- Poincare section of one chaotic motion
    sc = cfg["section"]
    o = ctx.engine_options
    sec, _ = map_chunks(orbit_tails, o.fmu, [(nd, num, float(sc["chi"]), np.array([[sc["z0"], sc["dz0"]]]),
                                              int(sc["transient"]), int(sc["points"]))], 0, None, False)
    section = sec[0]["tails"][0]

    # ---- dataset
    k = np.arange(ly["keep"])
    ds = xr.Dataset(
        {
            "lyapunov_per_period": (("chi", "ic"), scan["lyapunov"], {"long_name": "largest Lyapunov exponent per excitation period"}),
            "lyapunov_per_second": (("chi", "ic"), scan["lyapunov"] / T_s,
                                    {"long_name": "largest Lyapunov exponent per second (k = 100 N/m, m = 1 kg: T = 2 pi / (10 lambda) s)", "units": "1/s"}),
            "stderr_per_period": (("chi", "ic"), scan["stderr"], {"long_name": "batch-means standard error (10 blocks)"}),
            "half_difference": (("chi", "ic"), scan["half_difference"], {"long_name": "estimate over 2nd half - over 1st half"}),
            "collapses": (("chi", "ic"), scan["collapses"]),
            "strobe_z": (("chi", "ic", "k"), scan["strobe"][..., 0], {"long_name": "stroboscopic z at t = kT, last periods"}),
            "strobe_dz": (("chi", "ic", "k"), scan["strobe"][..., 1], {"long_name": "stroboscopic z' at t = kT"}),
            "period": (("chi", "ic"), cls["period"], {"long_name": "period of the stroboscopic points (0: none up to 32)"}),
            "attractors": (("chi",), cls["attractors"], {"long_name": "distinct attractors reached by the initial conditions"}),
            "chaotic": (("chi", "ic"), cls["chaotic"].astype(bool), {"long_name": "exponent > 3 stderr and non-periodic"}),
            "section_z": (("n",), section[:, 0]),
            "section_dz": (("n",), section[:, 1]),
        },
        coords={"chi": chis, "ic": np.arange(len(ics)), "k": k, "n": np.arange(section.shape[0]),
                "ic_z0": ("ic", ics[:, 0]), "ic_dz0": ("ic", ics[:, 1])},
    )
    if ref is not None:
        ds = ds.assign_coords(chi_refine=ref["chi"])
        ds["refine_lyapunov_per_period"] = (("chi_refine", "ic"), ref["lyapunov"])
        ds["refine_stderr_per_period"] = (("chi_refine", "ic"), ref["stderr"])
        ds["refine_period"] = (("chi_refine", "ic"), ref["period"])
    er = np.array(exact_rows)
    ds = ds.assign_coords(chi_check=er[:, 0])
    ds["check_exact_lyapunov"] = (("chi_check",), er[:, 1], {"long_name": "exponent / period from dryfriction.references.exact, from (0, 0)"})
    ds["check_exact_stderr"] = (("chi_check",), er[:, 2])
    ds["check_fmu_lyapunov"] = (("chi_check",), er[:, 3], {"long_name": "exponent / period from the FMU, same start"})
    ds["check_fmu_stderr"] = (("chi_check",), er[:, 4])
    ds.attrs.update({f"param_{k_}": v for k_, v in nd.items()})
    ds.attrs.update(scheme=num["scheme"], steps_per_period=num["steps_per_period"], alpha=num["alpha"],
                    lyapunov_method="Benettin two-trajectory, renormalised; fresh FMU start per interval",
                    periods=ly["periods"], transient=ly["transient"], d0=ly["d0"], renorm=ly["renorm"],
                    section_chi=sc["chi"])
    ctx.save_dataset(ds, DATASET)

    # ---- figures
    h_lbl = scheme_label(num["scheme"], num["steps_per_period"])
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 7), sharex=True, gridspec_kw={"height_ratios": [3, 2]})
    for j in range(len(ics)):
        xs = np.repeat(chis, ly["keep"])
        a1.scatter(xs, scan["strobe"][:, j, :, 0].reshape(-1), s=0.8, c=f"C{j}", lw=0, alpha=0.6,
                   label=f"z0, z0' = {ics[j, 0]:g}, {ics[j, 1]:g}")
        a2.plot(chis, scan["lyapunov"][:, j], ".-", ms=3, lw=0.6, c=f"C{j}")
    a1.set_ylabel(f"stroboscopic z(kT), last {ly['keep']} of {ly['transient'] + ly['periods']} T")
    a1.legend(loc="upper right", fontsize=7, markerscale=6)
    a1.grid(alpha=0.3)
    a1.set_title(f"lambda = {nd['lam']}, mu_s sigma = {nd['mu_s_sigma']}, zeta = {nd['zeta']}; {h_lbl}", fontsize=9)
    a2.axhline(0, c="k", lw=0.8)
    if "chi_chaos_onset" in summary:
        for a in (a1, a2):
            a.axvline(summary["chi_chaos_onset"], c="C3", lw=0.8, ls="--")
    lo_y = float(np.nanmin(scan["lyapunov"]))
    if lo_y < -1.0:
        a2.set_ylim(-1.0, max(0.35, float(np.nanmax(scan["lyapunov"])) * 1.2))
        a2.text(0.99, 0.03, f"clipped at -1 (min {lo_y:.1f})", transform=a2.transAxes, ha="right", fontsize=7)
    a2.set_ylabel("largest Lyapunov exponent / period")
    a2.set_xlabel("chi = mu_k / mu_s")
    a2.grid(alpha=0.3)
    ctx.save_figure(fig, FIGURES[0])

    fig, ax = plt.subplots(figsize=(6, 5))
    ax.scatter(section[:, 0], section[:, 1], s=0.5, c="k", lw=0, rasterized=True)
    ax.set_xlabel("z(kT)")
    ax.set_ylabel("z'(kT)")
    ax.set_title(f"Stroboscopic section, chi = {sc['chi']}, {section.shape[0]} points after {sc['transient']} T; "
                 f"{h_lbl}", fontsize=8)
    ax.grid(alpha=0.3)
    ctx.save_figure(fig, FIGURES[1])
    ctx.log(f"chaos_scan: chaotic (some IC) for chi in [{summary['chi_chaotic_min']:.4g}, {summary['chi_chaotic_max']:.4g}]"
            + (f"; onset at chi = {summary['chi_chaos_onset']:.4f} +- {summary['chi_chaos_onset_uncertainty']:.4f}"
               if "chi_chaos_onset" in summary else ""))
    return summary


def work(cfg: dict[str, Any]) -> Estimate:
    """The study's work and output size (:mod:`dryfriction.budget`): the scan and the onset's
    refinement (two runs per chi and initial condition, Benettin's pair), the check (an exact and
    an FMU pair per chi) and the section."""
    s, ly, num, r, ck, sc = cfg["scan"], cfg["lyapunov"], cfg["numerics"], cfg["refine"], cfg["check"], cfg["section"]
    n_ic, keep = len(s["z0"]), int(ly["keep"])
    runs = int(s["chi"]["num"]) * n_ic
    est = trajectory_estimate(Estimate(), "lyapunov scan", 2 * runs, ly["transient"] + ly["periods"], num)
    est.out_bytes += runs * (keep * 2 + 8) * 8
    if r["num"] >= 2:
        trajectory_estimate(est, "onset refinement", 2 * int(r["num"]) * n_ic, ly["transient"] + r["periods"], num)
        est.out_bytes += int(r["num"]) * n_ic * (keep * 2 + 8) * 8
    trajectory_estimate(est, "check (FMU)", 2 * len(ck["chi"]), ck["transient"] + ck["periods"], num)
    est.runs("check (exact)", 2 * len(ck["chi"]), ck["transient"] + ck["periods"], EXACT_PERIOD_STEPS)
    trajectory_estimate(est, "section", 1, sc["transient"] + sc["points"], num)
    est.out_bytes += 16.0 * sc["points"]
    return est.add("figures", 0.0, FIGURE_BYTES * len(FIGURES))
