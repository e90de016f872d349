"""The main job: validate the FMU against the exact solution, print the errors and orders, and
write results/validation.csv and results/validation.png."""

from __future__ import annotations

import csv
import io
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..atomic import atomic_write_bytes
from ..drivers.oscillator import OscillatorFMU2
from .validation import CASES, Convergence, FirstCycle, convergence, first_cycle



def run_validation(fmu: OscillatorFMU2, cases: Sequence[str], steps: Sequence[int],
                   progress: bool = True) -> tuple[FirstCycle, dict[tuple[str, str], Convergence]]:
    """The main job's runs: the first cycle against the exact solution and, for every case and scheme, the
    errors over ``steps`` steps per period."""
    from tqdm import tqdm

    fc = first_cycle(fmu, steps_per_period=1000)
    results: dict[tuple[str, str], Convergence] = {}
    jobs = [(c, s) for c in cases for s in reversed(fmu.md.schemes)]
    for case, scheme in tqdm(jobs, desc="convergence", disable=not progress, unit="case"):
        results[case, scheme] = convergence(fmu, CASES[case][0], scheme, steps_per_period=steps)
    return fc, results


def table(results: dict[tuple[str, str], Convergence]) -> str:
    """The convergence results as a text table: the error of each case and scheme per step and the observed
    orders."""
    lines = []
    steps = next(iter(results.values())).steps_per_period
    head = f"{'case':16s} {'scheme':11s} " + " ".join(f"{'T/' + str(n):>9s}" for n in steps) + "   orders"
    lines.append(head)
    lines.append("-" * len(head))
    for (case, scheme), c in results.items():
        errs = " ".join(f"{e:9.2e}" for e in c.errors)
        # the exact scheme has no step: its error is rounding whatever h, it has no order
        orders = "(no step)" if scheme == "exact" else " ".join(f"{o:5.2f}" for o in c.orders)
        lines.append(f"{case:16s} {scheme:11s} {errs}   {orders}")
    return "\n".join(lines)


def write_csv(path: Path, results: dict[tuple[str, str], Convergence]) -> None:
    """Write the convergence results to a CSV file (one row per case, scheme and step), atomically."""
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(["case", "scheme", "steps_per_period", "max_error_z", "observed_order"])
    for (case, scheme), c in results.items():
        orders = [float("nan"), *c.orders]
        for n, e, o in zip(c.steps_per_period, c.errors, orders):
            w.writerow([case, scheme, n, f"{e:.6e}", f"{o:.4f}"])
    atomic_write_bytes(path, buf.getvalue().encode())


def plot(path: Path, fc: FirstCycle, results: dict[tuple[str, str], Convergence]) -> None:
    """Draw the first cycle against the exact solution and the errors against the step into one PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(12, 8), constrained_layout=True)
    labels = {"x": "x (m)", "v": "v (m/s)", "a": "a (m/s$^2$)"}
    for ax, k in zip(axes.flat[:3], ("x", "v", "a")):
        ax.plot(fc.t, fc.exact[k], "k-", lw=2.5, alpha=0.35, label="exact")
        ax.plot(fc.t, fc.fmu[k], "C0-", lw=1.0, label="FMU (located, h = T/1000)")
        stuck = fc.exact["mode"] == 0
        ax.fill_between(fc.t, 0, 1, where=stuck, transform=ax.get_xaxis_transform(), color="C1", alpha=0.12,
                        label="stick (exact)")
        ax.set_xlabel("t (s)")
        ax.set_ylabel(labels[k])
        ax.set_title(f"first cycle: {k}, max error {fc.errors[k]:.1e} of its range")
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=8)
    ax = axes[1, 1]
    # one marker per scheme of the model description (exact: no step, its error is rounding)
    styles = {"located": "-o", "consistent": "--s", "paper": ":^", "exact": "-.*"}
    for (case, scheme), c in results.items():
        if case not in ("stick-dominated", "chi-small"):
            continue
        color = "C0" if case == "stick-dominated" else "C3"
        ax.loglog(c.steps_per_period, c.errors, styles.get(scheme, "-x"), color=color, ms=4,
                  label=f"{case}, {scheme}")
    n = np.array(next(iter(results.values())).steps_per_period, dtype=float)
    ax.loglog(n, 3e-4 * (n / n[0]) ** -2, "k-", lw=0.8, alpha=0.5, label="slope 2")
    ax.set_xlabel("steps per excitation period")
    ax.set_ylabel("max |z - z_exact| over 10 periods")
    ax.set_title("convergence against the exact solution")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    atomic_write_bytes(path, buf.getvalue())


def validate(out: Path, quick: bool = False, fmu_path: Path | None = None, progress: bool = True) -> str:
    """Validate the FMU (every case and scheme, or two cases with ``quick``), write
    ``out/validation.csv`` and ``out/validation.png`` together (all or nothing:
    :func:`dryfriction.atomic.result_set`) and return the report's text."""
    from ..atomic import result_set

    cases = ["stick-dominated", "chi-small"] if quick else list(CASES)
    steps = (400, 800, 1600) if quick else (400, 800, 1600, 3200)
    with OscillatorFMU2(fmu_path) as fmu:
        fc, results = run_validation(fmu, cases, steps, progress)
    with result_set(out) as stage:
        write_csv(stage / "validation.csv", results)
        plot(stage / "validation.png", fc, results)
    lines = [
        "First cycle (lambda 0.3, mu_s sigma 0.7, chi 0.5, h = T/1000): max error / range:",
        "  " + ", ".join(f"{k} {v:.2e}" for k, v in fc.errors.items())
        + f"   (modes in order: {' -> '.join(map(str, fc.modes_seen))})",
        "",
        "Max |z - z_exact| over 10 excitation periods, z = k x / P0:",
        table(results),
        "",
        f"wrote {out / 'validation.csv'} and {out / 'validation.png'}",
    ]
    return "\n".join(lines)
