"""The tables of bench/siconos_peer.py as markdown (also its plain-text output)."""

from __future__ import annotations

import os
import platform
import time
from collections.abc import Sequence

THETAS = (0.5, 1.0)


def meta(versions: dict, cfg, seconds: float) -> dict:
    from report import _machine

    try:
        from importlib.metadata import version

        fmpy = version("fmpy")
    except Exception:  # noqa: BLE001 - a version string only
        fmpy = "?"
    return {**versions, "machine": _machine(), "venv_python": platform.python_version(), "fmpy": fmpy,
            "quick": cfg.quick, "budget_s": cfg.budget_s, "seconds": seconds, "date": time.strftime("%Y-%m-%d %H:%M"),
            "load": os.getloadavg()[0]}


def _s(x: float | None) -> str:
    if x is None:
        return "not reached"
    if x < 1e-3:
        return f"{x * 1e6:.3g} us"
    if x < 1:
        return f"{x * 1e3:.3g} ms"
    return f"{x:.3g} s"


def _ratio(x: float | None) -> str:
    if x is None:
        return "n/a"
    return f"{x:.3g}x" if x < 100 else f"{x:.3g}x".replace("e+0", "e")


def markdown(results: Sequence[dict], notes: Sequence[str], m: dict, targets: Sequence[float]) -> str:
    from report import cost_at

    L: list[str] = []
    add = L.append
    add("## Siconos side by side" + (" (quick: a smoke test, not the study)" if m["quick"] else ""))
    add("")
    cmd = "bench/siconos_peer.py" + (" --quick" if m["quick"] else "")
    add(f"Measured by `{cmd}` on {m['date']} in {m['seconds']:.0f} s: "
        f"Siconos from Debian's python3-siconos {m['siconos_deb']} (its module calls itself "
        f"{m['siconos_module']}; "
        f"system Python {m['system_python']}), the FMU through fmpy {m['fmpy']} (Python {m['venv_python']}); "
        f"{m['machine']}, "
        f"load average {m['load']:.2f} at the end. CPU time = process CPU time of the stepping loop alone on both "
        "sides (Siconos: `TimeStepping.run()`, its C++ loop, on a freshly built model; the FMU: the one "
        "`doStep` over the run after reset and initialisation), the minimum over repetitions. Siconos: "
        "`EulerMoreauOSI(theta)` + `Relay` solved by Lemke, the harmonic force as the system's b(t) in a C "
        f"plugin; h = 1e-2, 5e-3, ... until its error reaches 1e-6 or the next h would pass {m['budget_s']:g} s "
        "per case and theta. The FMU: `located` (alpha = -0.1) over h and `exact`. Time to reach an error: "
        "read off each method's Pareto front, interpolated log-log, never extrapolated; ratio = Siconos's best "
        "time (either theta) over the FMU's best (either scheme).")
    add("")
    add("Distinct static and kinetic coefficients are outside Siconos's relay law (`RelayNSL`: one "
        "coefficient, lambda in [-1, 1]): the five work-precision cases (chi = 0.6, 0.8, 0.9, 1.5, 0.05) cannot "
        "be compared as they are, so they are compared at chi = 1 (mu_k = mu_s, `wp_<case>_chi1`), and no "
        "number here stands for chi != 1.")
    add("")
    add("### CPU time to reach an error")
    add("")
    head = "| case | error unit | " + " | ".join(f"E = {E:.0e}" for E in targets) + " |"
    add(head)
    add("|---|---|" + "---|" * len(targets))
    for r in results:
        c = r["case"]
        cells = []
        for E in targets:
            s = [cost_at([(x["error"], x["cpu_s"]) for x in r["siconos"] if x["theta"] == th], E) for th in THETAS]
            f = [cost_at([(x["error"], x["cpu_s"]) for x in r["fmu"] if x["scheme"] == sc], E)
                 for sc in ("located", "exact")]
            sb = min((v for v in s if v is not None), default=None)
            fb = min((v for v in f if v is not None), default=None)
            cells.append(f"Siconos {_s(sb)}, FMU {_s(fb)}: {_ratio(r['ratio_at'][f'{E:.0e}'])}")
        add(f"| {c.name} | {c.error_unit} | " + " | ".join(cells) + " |")
    add("")
    add("### Every run")
    add("")
    for r in results:
        c = r["case"]
        add(f"**{c.name}**: {c.note}. Error: max |x - x_ref| over the run, in {c.error_unit}.")
        add("")
        add("| method | h | steps | CPU time | ns per block-step | error |")
        add("|---|---|---|---|---|---|")
        for x in r["siconos"]:
            add(f"| Siconos theta = {x['theta']:g} | {x['h']:.4g} | {x['steps']} | {_s(x['cpu_s'])} | "
                f"{x['cpu_s'] / x['steps'] / c.n * 1e9:.0f} | {x['error']:.3g} |")
        for x in r["fmu"]:
            h = "no effect" if x["h"] is None else f"{x['h']:.4g}"
            per = "" if x["h"] is None else f"{x['cpu_s'] / x['steps'] / c.n * 1e9:.1f}"
            add(f"| FMU {x['scheme']} | {h} | {x['steps'] if x['h'] is not None else ''} | {_s(x['cpu_s'])} | "
                f"{per} | {x['error']:.3g} |")
        add("")
        add("Siconos's sweep stopped at " + "; ".join(f"theta = {k}: {v}" for k, v in r["stops"].items()) + ".")
        if c.kind == "chain":
            add("The chain FMU has no exact scheme (no closed form for n blocks): located only.")
        add("")
    for n in notes:
        add(f"- {n}")
    if notes:
        add("")
    return "\n".join(L) + "\n"
