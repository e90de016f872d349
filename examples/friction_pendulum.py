"""The FMIZoo's friction pendulum (SpringFrictionPendulum1D, the Modelica Standard Library's
MassWithStopAndFriction on a spring): a 1 kg mass on a 10 N/m spring relaxed at s = 1 m, viscous
friction 0.05 N s/m, Coulomb 0.25 N and Stribeck 0.5 N exp(-2 |v|), from s = 0.5 m at rest. Our
oscillator FMU runs it as Model Exchange (fmpy's CVode) and as co-simulation (the located scheme),
prints s(8 s), the stops and the stick, the difference to Dymola's published s(8) = 1.06736 m, and
plots s(t) and v(t) of both.

    python examples/friction_pendulum.py [--rtol 1e-10] [--h 2e-5] [--out results/example_pendulum]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from fmpy import simulate_fmu

from dryfriction.drivers.modelica import DYMOLA_S_AT_8, SpringFrictionPendulum
from dryfriction.model import default_fmu_path

T_END = 8.0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rtol", type=float, default=1e-10, help="CVode's relative tolerance (Model Exchange)")
    ap.add_argument("--h", type=float, default=2e-5, help="the located scheme's step, s (co-simulation)")
    ap.add_argument("--out", type=Path, default=Path("results/example_pendulum"))
    args = ap.parse_args()

    zoo = SpringFrictionPendulum()
    start = zoo.start_values()
    print("mapped onto the oscillator: " + ", ".join(f"{k} = {v:g}" for k, v in start.items()))
    fmu = str(default_fmu_path())
    me = simulate_fmu(fmu, fmi_type="ModelExchange", solver="CVode", relative_tolerance=args.rtol, stop_time=T_END,
                      output_interval=0.01, start_values=start, output=["x", "v", "mode"])
    cs = simulate_fmu(fmu, fmi_type="CoSimulation", stop_time=T_END, output_interval=0.01,
                      start_values={**start, "scheme": 3, "h": args.h}, output=["x", "v", "mode", "transitions"])

    switch = np.nonzero(np.diff(me["mode"]))[0] + 1      # fmpy records both sides of every event
    print(f"Model Exchange (CVode, rtol {args.rtol:g}): {switch.size} events")
    for i in switch:
        way = "forward" if me["mode"][i] > 0 else "backward"
        kind = "stop, stuck" if me["mode"][i] == 0 else f"reversal, sliding {way}"
        print(f"  t = {me['time'][i]:.6f} s  s = {me['x'][i]:.7f} m  {kind}")
    s_me, s_cs = float(me["x"][-1]), float(cs["x"][-1])
    stuck = me["mode"][-1] == 0 and cs["mode"][-1] == 0
    print(f"s(8) Model Exchange {s_me:.9f} m, co-simulation (located, h = {args.h:g} s, "
          f"{int(cs['transitions'][-1])} switches) {s_cs:.9f} m: {'stuck' if stuck else 'NOT stuck'}")
    print(f"difference ME - CS {s_me - s_cs:.2e} m; to Dymola's {DYMOLA_S_AT_8} m: {s_me - DYMOLA_S_AT_8:.2e} m "
          f"({100 * (s_me - DYMOLA_S_AT_8) / DYMOLA_S_AT_8:.3f} %)")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax_s, ax_v) = plt.subplots(2, 1, sharex=True, figsize=(7, 5.5))
    for r, label, style in ((me, "Model Exchange (CVode)", "-"), (cs, "co-simulation (located)", "--")):
        ax_s.plot(r["time"], r["x"], style, label=label)
        ax_v.plot(r["time"], r["v"], style, label=label)
    ax_s.plot([T_END], [DYMOLA_S_AT_8], "k+", markersize=12, label="Dymola, s(8)")
    ax_s.axhline(zoo.s_rel0, color="0.7", lw=0.8)
    ax_s.set_ylabel("s (m)")
    ax_v.set_ylabel("v (m/s)")
    ax_v.set_xlabel("t (s)")
    ax_s.legend()
    ax_s.set_title("SpringFrictionPendulum1D on the dry-friction oscillator FMU")
    args.out.mkdir(parents=True, exist_ok=True)
    png = args.out / "pendulum.png"
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    print(f"wrote {png}")
    if not stuck or abs(s_me - s_cs) > 1e-6 or abs(s_me - DYMOLA_S_AT_8) > 1e-3:
        raise SystemExit("the pendulum's runs disagree (see docs/model_exchange.md for the expected numbers)")


if __name__ == "__main__":
    main()
