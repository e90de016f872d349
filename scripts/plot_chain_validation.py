#!/usr/bin/env python3
"""The chain FMU (FMI 3.0, through dryfriction.drivers.chain) against the event-driven reference on the
four coupled cases of docs/chain.md (tests/chain_cases.py): max |x - x_ref| over 10 periods at
h = T/400 ... T/3200 for the three schemes, printed as a table, written as CSV (next to the figure)
and drawn as a log-log figure. Part of the main job (scripts/main.sh: results/chain_validation.*).

    python scripts/plot_chain_validation.py [--out docs/img/chain/validation.png] [--fmu PATH]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))  # the validation cases live with the tests (one copy)

from chain_cases import CASES, PERIODS  # noqa: E402

from dryfriction.cli.options import make_parser  # noqa: E402
from dryfriction.drivers.chain import ChainFMU3  # noqa: E402
from dryfriction.references.chain import solve_chain  # noqa: E402

PER_PERIOD = (400, 800, 1600, 3200)
SCHEMES = ("located", "consistent", "paper")


def errors(fmu_path: Path | None) -> dict[str, dict[str, np.ndarray]]:
    out: dict[str, dict[str, np.ndarray]] = {}
    for name, ch in CASES.items():
        T = ch.period
        ref = solve_chain(ch, PERIODS * T)
        out[name] = {}
        with ChainFMU3(ch.n, fmu_path=fmu_path) as f:
            for scheme in SCHEMES:
                e = []
                for ppp in PER_PERIOD:
                    p = {k: getattr(ch, k) for k in ("m", "k", "c", "P0", "phi", "N", "mu_s", "chi", "x0", "v0")}
                    run = f.run(PERIODS * T, T / 100, {**p, "omega": ch.omega, "k_end": ch.k_end, "c_end": ch.c_end,
                                                       "h": T / ppp, "alpha": -0.1, "scheme": scheme})
                    e.append(float(np.max(np.abs(run.x - ref.evaluate(run.t)["x"]))))
                out[name][scheme] = np.array(e)
    return out


def main() -> int:
    p = make_parser("plot_chain_validation.py", __doc__.splitlines()[0], exit=True)
    p.add_argument("--out", type=Path, default=ROOT / "docs" / "img" / "chain" / "validation.png")
    p.add_argument("--fmu", type=Path, default=None, help="the FMI 3.0 chain (default build/fmi3/)")
    args = p.parse_args()
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from dryfriction.atomic import atomic_path

    errs = errors(args.fmu)
    print(f"{'case':16s} {'scheme':10s} " + " ".join(f"T/{q:<7d}" for q in PER_PERIOD) + " orders")
    for name, by in errs.items():
        for scheme, e in by.items():
            orders = np.log2(e[:-1] / e[1:])
            print(f"{name:16s} {scheme:10s} " + " ".join(f"{x:9.3g}" for x in e) + "  "
                  + " ".join(f"{o:.2f}" for o in orders))
    fig, axes = plt.subplots(1, len(errs), figsize=(3.4 * len(errs), 3.4), sharey=True)
    q = np.array(PER_PERIOD, dtype=float)
    for ax, (name, by) in zip(axes, errs.items()):
        for scheme, style in zip(SCHEMES, ("o-", "s--", "^:")):
            ax.loglog(q, by[scheme], style, label=scheme, ms=4)
        e0 = by["located"][0]
        ax.loglog(q, e0 * (q[0] / q) ** 2, color="0.6", lw=0.8, label="slope 2")
        ax.set_title(name, fontsize=9)
        ax.set_xticks(q, [f"T/{int(x)}" for x in q], minor=False)
        ax.set_xticks([], minor=True)
        ax.set_xlabel("internal step h")
    axes[0].set_ylabel("max |x - x_ref| over 10 periods")
    axes[0].legend(fontsize=7)
    fig.suptitle("Chain FMU (FMI 3.0, n = 3) against the event-driven reference: four coupled cases", fontsize=9, y=1.03)
    with atomic_path(args.out.with_suffix(".csv")) as tmp:
        rows = ["case,scheme,steps_per_period,max_abs_error_x"]
        rows += [f"{name},{scheme},{q_},{float(x)!r}" for name, by in errs.items() for scheme, e in by.items()
                 for q_, x in zip(PER_PERIOD, e)]
        Path(tmp).write_text("\n".join(rows) + "\n")
    with atomic_path(args.out) as tmp:
        fig.savefig(tmp, format="png", dpi=110, bbox_inches="tight")
    plt.close(fig)
    print(f"wrote {args.out} and {args.out.with_suffix('.csv')}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
