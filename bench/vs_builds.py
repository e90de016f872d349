"""Step cost of two builds side by side: bench_stepper and bench_chain of an old build and a new one,
run in turn for several rounds (old, new, old, new, ...), the minimum per case over the rounds, and
the ratio new / old per case.

    python bench/vs_builds.py --old OLD_BUILD --new NEW_BUILD [--rounds 5] [--n 1,8,64,512]
                              [--steps-per-period 100,1000] [--md FILE]

OLD_BUILD and NEW_BUILD are CMake build folders (each with bench/bench_stepper and bench/bench_chain).
Rows: the oscillator's bare stepper per case and scheme (bench_stepper's bare_ns_per_step), the same
with its observables on (observe_on_ns_per_step), and the chain per n (bench_chain's ns_per_step).
Bad arguments or a missing executable: one line on stderr, exit status 2.
"""

from __future__ import annotations

import argparse
import csv
import io
import subprocess
import sys
from pathlib import Path

Key = tuple[str, ...]


def _run(exe: Path, args: list[str]) -> list[dict[str, str]]:
    """One run of a bench executable: its CSV rows."""
    out = subprocess.run([str(exe), *args], check=True, capture_output=True, text=True).stdout
    return list(csv.DictReader(io.StringIO(out)))


def _stepper(build: Path, spp: str) -> dict[Key, float]:
    """bench_stepper's bare and observed ns per step per (case, scheme, steps per period)."""
    rows = _run(build / "bench" / "bench_stepper", ["--reps", "3", "--steps-per-period", spp])
    out: dict[Key, float] = {}
    for r in rows:
        if r["kind"] != "step":
            continue
        base = (r["case"], r["scheme"], r["steps_per_period"])
        out[("oscillator",) + base] = float(r["bare_ns_per_step"])
        if r.get("observe_on_ns_per_step"):
            out[("oscillator observed",) + base] = float(r["observe_on_ns_per_step"])
    return out


def _chain(build: Path, ns: str) -> dict[Key, float]:
    """bench_chain's ns per step per n."""
    rows = _run(build / "bench" / "bench_chain", ["--reps", "3", "--periods", "2", "--n", ns])
    return {("chain", "located", r["n"]): float(r["ns_per_step"]) for r in rows if r["model"] == "chain"}


def _merge_min(acc: dict[Key, float], new: dict[Key, float]) -> None:
    for k, v in new.items():
        acc[k] = min(acc.get(k, v), v)


def main(argv: list[str] | None = None) -> int:
    """Run the comparison; print (and optionally write) the table."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old", type=Path, required=True)
    ap.add_argument("--new", type=Path, required=True)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--n", default="1,8,64,512")
    ap.add_argument("--steps-per-period", default="100,1000")
    ap.add_argument("--md", type=Path)
    a = ap.parse_args(argv)
    for b in (a.old, a.new):
        for exe in ("bench_stepper", "bench_chain"):
            if not (b / "bench" / exe).is_file():
                print(f"vs_builds: {b / 'bench' / exe} not found (build it first)", file=sys.stderr)
                return 2
    if a.rounds < 1:
        print("vs_builds: --rounds must be >= 1", file=sys.stderr)
        return 2
    best: dict[str, dict[Key, float]] = {"old": {}, "new": {}}
    for k in range(a.rounds):
        for tag, build in (("old", a.old), ("new", a.new)):
            _merge_min(best[tag], _stepper(build, a.steps_per_period))
            _merge_min(best[tag], _chain(build, a.n))
        print(f"round {k + 1}/{a.rounds} done", file=sys.stderr)
    lines = ["| model | case | old ns/step | new ns/step | new / old |", "|---|---|---|---|---|"]
    worst = 0.0
    def order(key: Key) -> tuple[object, ...]:
        return tuple(int(x) if x.isdigit() else x for x in key)

    for key in sorted(best["old"], key=order):
        if key not in best["new"]:
            continue
        o, n = best["old"][key], best["new"][key]
        worst = max(worst, n / o)
        lines.append(f"| {key[0]} | {' '.join(key[1:])} | {o:.2f} | {n:.2f} | {n / o:.3f} |")
    lines.append(f"\nlargest new / old: {worst:.3f} ({a.rounds} rounds, minimum per case)")
    text = "\n".join(lines)
    print(text)
    if a.md:
        a.md.write_text(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
