"""How many runs of the Fig. 8/9 study end on a different motion with one scheme than with another.

    python scripts/compare_fig8_9.py A.nc B.nc [--threshold 0.01] [--markdown]

A and B are two `fig8_9.nc` datasets of the same sweep (e.g. `dryfriction study fig8_9` with
`numerics.scheme=located` and with `numerics.scheme=exact`). A run ends on a different motion when
the extremes of the observed period differ by more than the threshold (in static deflections,
z = k x / P0): max(|z_max,A - z_max,B|, |z_min,A - z_min,B|) > threshold. At h = T/1000 the located
scheme's own error in the extremes is about 1e-4 ... 1e-3, so 0.01 separates a different motion
from discretisation error; the count at ten times the threshold is printed alongside. Prints, per
chi, the runs that differ, and the total; exits 2 with one line on bad input.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("a", type=Path)
    ap.add_argument("b", type=Path)
    ap.add_argument("--threshold", type=float, default=0.01)
    ap.add_argument("--markdown", action="store_true", help="one markdown table row per chi")
    args = ap.parse_args(argv)
    try:
        import xarray as xr
        A, B = xr.load_dataset(args.a), xr.load_dataset(args.b)
    except Exception as e:  # noqa: BLE001 - one readable line
        print(f"compare_fig8_9: cannot read the datasets: {e}", file=sys.stderr)
        return 2
    if not args.threshold > 0:
        print("compare_fig8_9: --threshold must be > 0", file=sys.stderr)
        return 2
    for c in ("chi", "z0", "dz0"):
        if c not in A.coords or c not in B.coords or not np.array_equal(A[c].values, B[c].values):
            print(f"compare_fig8_9: the two datasets are not the same sweep (coordinate {c} differs)", file=sys.stderr)
            return 2
    d = np.maximum(np.abs(A["z_max"].values - B["z_max"].values), np.abs(A["z_min"].values - B["z_min"].values))
    n_runs = d.shape[1] * d.shape[2]
    lo = (d > args.threshold).sum(axis=(1, 2))
    hi = (d > 10 * args.threshold).sum(axis=(1, 2))
    sa, sb = A.attrs.get("scheme", "A"), B.attrs.get("scheme", "B")
    print(f"runs ending on a different motion, {sa} vs {sb} (of {n_runs} per chi; extremes differ by more than "
          f"{args.threshold:g} / {10 * args.threshold:g} static deflections)")
    if args.markdown:
        print(f"| chi | differ by > {args.threshold:g} | differ by > {10 * args.threshold:g} | median difference |")
        print("|---|---|---|---|")
    for i, chi in enumerate(A["chi"].values):
        if args.markdown:
            print(f"| {chi:.2f} | {lo[i]} | {hi[i]} | {np.median(d[i]):.1e} |")
        else:
            print(f"chi {chi:5.2f}: {lo[i]:5d} {hi[i]:5d}   median |difference| {np.median(d[i]):.1e}")
    print(f"total: {lo.sum()} / {hi.sum()} of {d.size} runs")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
