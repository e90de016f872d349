"""``dryfriction belt``: the self-excited motion of the block on a belt at a constant speed, without
excitation (:func:`dryfriction.analysis.self_excited.motion.self_excited`; docs/self_excited.md).

    dryfriction belt --v-belt 0.2 [--law coulomb|stribeck --v-s 0.1 --delta 1] [--json] [--out DIR]
    dryfriction belt --m 0.5 --k 2000 --zeta 0.01 --N 20 --mu-s 0.3 --mu-k 0.2 --v-belt 0.05 --law stribeck

The oscillator in physical units (--m, --k, --c | --zeta, --N, --mu-s, --mu-k | --chi, --F-ext), or
in the non-dimensional form: every one of --m, --k, --N left out is 1, so that with none of them x
is in units of N / k, t of 1 / w0 and speeds (--v-belt, --v-s) of w0 N / k; --chi = mu_k / mu_s
and --zeta as for ``dryfriction orbit``. The period, amplitude, stick share and stability of the
orbit, or "steady sliding" with the equilibrium's slowest multiplier; ``--json`` prints exactly one
object; a PNG of x(t) and the phase portrait (v against x, the belt's speed line) goes to
``--out`` (default results/belt; with --json only when --out is given).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from .options import UsageError, count, number, path_arg
from .output import finite, print_json

__all__ = ["add_parser", "run", "work", "belt_json"]


def add_parser(sub: Any, parents: list[argparse.ArgumentParser]) -> None:
    """Add the ``belt`` command to the main parser's subparsers ``sub``."""
    b = sub.add_parser("belt", parents=parents, help="self-excited stick-slip on a belt (no excitation)",
                       description="The self-excited motion of the block on a belt at a constant speed: the "
                                   "periodic orbit (period T an unknown, Newton shooting on a section where it "
                                   "slides) or steady sliding, with their multipliers (docs/self_excited.md). "
                                   "Physical units, or the non-dimensional form with m = k = N = 1.")
    g = b.add_argument_group("the oscillator (SI; --m, --k, --N default to 1: the non-dimensional form)")
    g.add_argument("--m", type=number("--m", 0.0, True), default=1.0, help="mass, kg (default 1)")
    g.add_argument("--k", type=number("--k", 0.0, True), default=1.0, help="stiffness, N/m (default 1)")
    g.add_argument("--c", type=number("--c", 0.0), default=None, help="viscous damping, N s/m (or --zeta; default 0)")
    g.add_argument("--zeta", type=number("--zeta", 0.0), default=None, help="damping ratio c / (2 sqrt(k m))")
    g.add_argument("--N", type=number("--N", 0.0, True), default=1.0, help="normal force, N (default 1)")
    g.add_argument("--mu-s", type=number("--mu-s", 0.0, True), default=0.5, help="static coefficient (default 0.5)")
    g.add_argument("--mu-k", type=number("--mu-k", 0.0), default=None,
                   help="kinetic coefficient (or --chi; default 0.3)")
    g.add_argument("--chi", type=number("--chi", 0.0), default=None, help="mu_k / mu_s")
    g.add_argument("--F-ext", dest="F_ext", type=number("--F-ext"), default=0.0, help="constant force, N (default 0)")
    b.add_argument("--v-belt", dest="v_belt", type=number("--v-belt"), required=True, help="belt speed, m/s (nonzero)")
    b.add_argument("--law", choices=("coulomb", "stribeck"), default="coulomb", help="friction law (default coulomb)")
    b.add_argument("--v-s", dest="v_s", type=number("--v-s", 0.0, True), default=None,
                   help="Stribeck velocity, m/s (--law stribeck; default 0.1)")
    b.add_argument("--delta", type=number("--delta", 1.0), default=None, help="Stribeck exponent >= 1 (default 1)")
    b.add_argument("--scheme", choices=("located", "exact"), default="located",
                   help="the FMU's scheme (default located; exact: coulomb, the FMU's sensitivity as the Jacobian)")
    b.add_argument("--steps-per-period", type=count("--steps-per-period", 20), default=2000,
                   help="internal steps per natural period (default 2000)")
    b.add_argument("--periods", type=number("--periods", 0.0, True), default=40.0,
                   help="natural periods of the transient that gives the guess (default 40)")
    b.add_argument("--out", type=path_arg("--out"), default=None, help="folder of the PNG (default results/belt)")
    b.add_argument("--no-plot", action="store_true", help="no PNG")
    b.add_argument("--json", action="store_true", help="print one JSON object")


def work(args: argparse.Namespace) -> tuple[float, str]:
    """The transient, the orbit's search and its cycle: about three times ``--periods``."""
    from ..budget import EXACT_PERIOD_STEPS, fmt

    spp = EXACT_PERIOD_STEPS if args.scheme == "exact" else float(args.steps_per_period)
    periods = float(args.periods) * 3.0
    return periods * spp, f"about {fmt(periods)} periods x {fmt(spp)} steps"


def _problem(args: argparse.Namespace) -> Any:
    from ..analysis.self_excited import BeltProblem
    from ..params import Oscillator

    if args.c is not None and args.zeta is not None:
        raise UsageError("give the damping as --c or --zeta, not both")
    if args.mu_k is not None and args.chi is not None:
        raise UsageError("give the kinetic friction as --mu-k or --chi, not both")
    if args.law == "coulomb" and (args.v_s is not None or args.delta is not None):
        raise UsageError("--v-s and --delta are parameters of --law stribeck")
    if args.v_belt == 0.0:
        raise UsageError("--v-belt must be nonzero (a belt at rest excites nothing), not 0")
    c = args.c if args.c is not None else 2.0 * (args.zeta or 0.0) * math.sqrt(args.k * args.m)
    mu_k = args.mu_k if args.mu_k is not None else (args.chi * args.mu_s if args.chi is not None else 0.3)
    try:
        osc = Oscillator(m=args.m, k=args.k, c=c, P0=0.0, omega=0.0, phi=0.0, N=args.N, mu_s=args.mu_s,
                         chi=mu_k / args.mu_s, x0=0.0, v0=0.0)
        w0 = math.sqrt(args.k / args.m)
        return BeltProblem(osc, args.v_belt, law=args.law, v_s=0.1 if args.v_s is None else args.v_s,
                           delta=1.0 if args.delta is None else args.delta, F_ext=args.F_ext, scheme=args.scheme,
                           h=2.0 * math.pi / w0 / args.steps_per_period)
    except ValueError as e:
        raise UsageError(str(e).replace("Oscillator: ", "")) from None


def _cplx(m: complex) -> list[float | None]:
    return [finite(m.real), finite(m.imag)]


def belt_json(res: Any) -> dict[str, Any]:
    """The ``--json`` object of a :class:`~dryfriction.analysis.self_excited.SelfExcited`."""
    pr, eq, o = res.problem, res.equilibrium, res.orbit
    out: dict[str, Any] = {
        "motion": res.motion, "reason": res.reason or None, "v_belt": pr.v_belt, "law": pr.law,
        "scheme": pr.scheme, "h": pr.step, "x_eq": eq.x_eq,
        "equilibrium": {"x_eq": eq.x_eq, "stable": eq.stable, "multipliers": [_cplx(m) for m in eq.multipliers],
                        "neutral": eq.neutral, "slowest_multiplier": eq.mu_max, "tau": eq.tau,
                        "growth_rate": finite(eq.growth_rate),
                        "jacobian": eq.jacobian},
        "hopf_formula": finite(res.hopf_formula),
        "orbit": None,
        "units": {"period": "s", "amplitude": "m", "offset": "m", "x_eq": "m", "v_belt": "m/s", "tau": "s",
                  "growth_rate": "1/s", "stick_fraction": "1", "h": "s", "hopf_formula": "m/s"},
    }
    if pr.law == "stribeck":
        out.update({"v_s": pr.v_s, "delta": pr.delta})
    if o is not None:
        out["orbit"] = {"period": o.period, "amplitude": o.amplitude, "offset": o.offset, "x_max": o.x_max,
                        "x_min": o.x_min, "stick_fraction": o.stick_fraction, "stable": o.stable,
                        "multipliers": [_cplx(m) for m in o.multipliers], "v0": o.v0, "residual": finite(o.residual),
                        "converged": o.converged, "reason": o.reason or None, "iterations": o.iterations,
                        "transitions": o.transitions, "jacobian": o.jacobian}
    moving = res.motion in ("stick-slip", "slip orbit")
    for k in ("period", "amplitude", "stick_fraction"):
        out[k] = out["orbit"][k] if moving else None
    # the motion's stability: the orbit's, or steady sliding's
    out["stable"] = out["orbit"]["stable"] if moving else (eq.stable if res.motion == "steady sliding" else None)
    out["coexists_with_steady_sliding"] = bool(moving and eq.stable)
    return out


def plot_belt(res: Any, fmu: Any, path: Path) -> Path:
    """x(t) over a few periods (of the orbit, else of the transient from the belt) and the phase
    portrait with the belt's speed line."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..analysis.self_excited import transient
    from ..atomic import atomic_path

    pr, o = res.problem, res.orbit
    if o is not None and o.converged:
        T = o.period
        tr = transient(pr, o.x_eq, o.v0, periods=4 * T / pr.natural_period, fmu=fmu)
        title = (f"{res.motion}: T = {o.period:.5g} s, amplitude {o.amplitude:.4g} m, stuck "
                 f"{100 * o.stick_fraction:.1f} %, |mu| = {abs(o.multipliers[1]):.3g}")
    else:
        tr = transient(pr, periods=20, fmu=fmu)
        title = f"{res.motion}: the motion from riding on the belt at x_eq (slowest multiplier " \
                f"{res.equilibrium.mu_max:.4g} over {res.equilibrium.tau:.3g} s)"
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.2))
    a1.plot(tr.t, tr.x, lw=1.0)
    a1.axhline(pr.x_eq, color="0.5", ls=":", lw=0.8, label="x_eq (steady sliding)")
    a1.set_xlabel("t (s)")
    a1.set_ylabel("x (m)")
    a1.legend(fontsize=7)
    a2.plot(tr.x, tr.v, lw=1.0)
    a2.axhline(pr.v_belt, color="C3", ls="--", lw=0.8, label=f"belt speed {pr.v_belt:g} m/s")
    a2.plot([pr.x_eq], [0.0], "k+", label="steady sliding")
    a2.set_xlabel("x (m)")
    a2.set_ylabel("v (m/s)")
    a2.legend(fontsize=7)
    for a in (a1, a2):
        a.grid(alpha=0.3)
    fig.suptitle(f"{pr.law} friction on a belt: {title}", fontsize=9)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=120, bbox_inches="tight")
    plt.close(fig)
    return path


def run(args: argparse.Namespace) -> int:
    """Run ``dryfriction belt``; the exit status."""
    from ..analysis.self_excited import self_excited
    from ..drivers.oscillator import OscillatorFMU2
    from .console import check_output_folder, result_set

    prob = _problem(args)
    out = None
    if not args.no_plot and (args.out is not None or not args.json):
        out = check_output_folder(args.out or Path("results/belt"))
    with OscillatorFMU2(args.fmu) as fmu:
        res = self_excited(prob, fmu=fmu, periods=args.periods)
        files: list[Path] = []
        if out is not None:
            with result_set(out) as stage:
                plot_belt(res, fmu, stage / "belt.png")
            files.append(out / "belt.png")
    if args.json:
        doc = belt_json(res)
        doc["files"] = [str(f) for f in files]
        print_json(doc)
        return 0
    o, eq = res.orbit, res.equilibrium
    print(f"belt {prob.v_belt:g} m/s, {prob.law} friction, scheme {prob.scheme} (h = {prob.step:.3g} s)")
    if res.motion in ("stick-slip", "slip orbit"):
        assert o is not None
        print(f"{res.motion}: period {o.period:.8g} s, amplitude {o.amplitude:.6g} m, offset {o.offset:.6g} m, "
              f"stuck {100 * o.stick_fraction:.2f} % of the cycle, stable (multipliers "
              f"{abs(o.multipliers[0]):.6g}, {abs(o.multipliers[1]):.3g}; residual {o.residual:.1e}, "
              f"Jacobian by {o.jacobian})")
        if eq.stable:
            print("steady sliding is stable too: the two motions coexist (the start decides)")
    else:
        print(f"{res.motion}" + (f": {res.reason}" if res.reason else ""))
    state = "neutral" if eq.neutral else ("stable" if eq.stable else "unstable")
    print(f"steady sliding at x_eq = {eq.x_eq:.6g} m: {state}, slowest multiplier "
          f"{eq.mu_max:.6g} over tau = {eq.tau:.4g} s (growth rate {eq.growth_rate:.4g} 1/s)")
    if math.isfinite(res.hopf_formula):
        print(f"Hopf belt speed v* = v_s ln(N (mu_s - mu_k) / (c v_s)) = {res.hopf_formula:.6g} m/s")
    for f in files:
        print(f"wrote {f}")
    return 0
