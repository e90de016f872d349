#!/usr/bin/python3
"""The Siconos side of bench/siconos_peer.py, run under the SYSTEM Python (Debian's
python3-siconos is built for it, not for the project's .venv).

    /usr/bin/python3 bench/siconos_run.py PLUGIN.so < jobs (one JSON object a line)

A long-lived worker: it reads one job per line on stdin and answers one JSON line per job on the
stdout it was started with (Siconos's C++ prints progress lines on std::cout, so the worker moves
its fd 1 to /dev/null and answers on a duplicate). A job is a chain of n blocks with Coulomb
friction (n = 1: the single oscillator) written as Siconos's first-order linear system with a relay:

    x = (X, V),  x' = A x + b(t) + B lambda,   y = C x = V,   lambda_i in [-1, 1], -y in N(lambda)
    A = [[0, I], [-M^-1 K, -M^-1 Cd]],  B = [0; diag(mu_i N_i / m_i)],  b(t) = [0; P0_i/m_i cos(w t + phi_i)]

so that lambda_i = -sign(V_i) while sliding and the friction force is mu N lambda: one coefficient
per block (Siconos's relay law has no distinct static and kinetic coefficients). b(t) is a C
plugin (``dfo_harmonic_b`` in PLUGIN.so, compiled by the caller), so no Python runs per step.
The integrator is ``EulerMoreauOSI(theta)``, the one-step problem ``Relay`` solved by Lemke.

Per job: one run stepped from Python (computeOneStep / nextStep), sampling X every
``sample_every`` steps (for the error, not timed); then ``reps`` runs of the C++ loop
``TimeStepping.run()`` on freshly built models, each timed by the process CPU time
(time.process_time_ns) around ``run()`` alone; the minimum is reported. The two runs must end in
the same state (checked: ``end_mismatch``).
"""

from __future__ import annotations

import json
import os
import sys
import time


def build(job: dict, plugin: str) -> tuple[object, object]:
    """The TimeStepping simulation of the job, initialised, and its dynamical system."""
    import numpy as np
    import siconos.kernel as sk
    import siconos.numerics as sn

    n = int(job["n"])
    m = np.asarray(job["m"], float)
    K = np.asarray(job["K"], float).reshape(n, n)
    Cd = np.asarray(job["C"], float).reshape(n, n)
    A = np.zeros((2 * n, 2 * n))
    A[:n, n:] = np.eye(n)
    A[n:, :n] = -K / m[:, None]
    A[n:, n:] = -Cd / m[:, None]
    x0 = np.concatenate([np.asarray(job["x0"], float), np.asarray(job["v0"], float)])
    ds = sk.FirstOrderLinearDS(x0, A)
    P0 = np.asarray(job["P0"], float)
    if np.any(P0 != 0.0):
        ds.setzPtr(np.concatenate([[float(job["omega"])], P0 / m, np.asarray(job["phi"], float)]))
        ds.setComputebFunction(plugin, "dfo_harmonic_b")
    muN = np.asarray(job["muN"], float)
    B = np.zeros((2 * n, n))
    B[n:, :] = np.diag(muN / m)
    Cy = np.zeros((n, 2 * n))
    Cy[:, n:] = np.eye(n)
    inter = sk.Interaction(sk.RelayNSL(n, -1.0, 1.0), sk.FirstOrderLinearTIR(Cy, B))
    nsds = sk.NonSmoothDynamicalSystem(0.0, float(job["t_end"]))
    nsds.insertDynamicalSystem(ds)
    nsds.link(inter, ds)
    sim = sk.TimeStepping(nsds, sk.TimeDiscretisation(0.0, float(job["h"])))
    sim.insertIntegrator(sk.EulerMoreauOSI(float(job["theta"])))
    sim.insertNonSmoothProblem(sk.Relay(sn.SICONOS_RELAY_LEMKE))
    sim.initialize()
    return sim, ds


def run_job(job: dict, plugin: str) -> dict:
    n = int(job["n"])
    every = max(1, int(job["sample_every"]))
    sim, ds = build(job, plugin)
    x = ds.x()
    ts, xs = [0.0], [[float(v) for v in x[:n]]]
    k = 0
    while sim.hasNextEvent():
        sim.computeOneStep()
        k += 1
        if k % every == 0 or not sim.hasNextEvent():
            ts.append(float(sim.nextTime()))
            xs.append([float(v) for v in ds.x()[:n]])
        sim.nextStep()
    end_loop = [float(v) for v in ds.x()]
    best = float("inf")
    end_run: list[float] = []
    for _ in range(max(1, int(job.get("reps", 1)))):
        sim, ds = build(job, plugin)
        t0 = time.process_time_ns()
        sim.run()
        t1 = time.process_time_ns()
        best = min(best, (t1 - t0) * 1e-9)
        end_run = [float(v) for v in ds.x()]
    mismatch = max(abs(a - b) for a, b in zip(end_loop, end_run))
    return {"id": job.get("id"), "steps": k, "cpu_s": best, "t": ts, "x": xs, "end_mismatch": mismatch}


def main() -> int:
    plugin = sys.argv[1]
    out = os.fdopen(os.dup(1), "w")
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)  # Siconos's own progress lines
    import siconos

    out.write(json.dumps({"ready": True, "siconos": str(getattr(siconos, "version", "?")),
                          "python": sys.version.split()[0]}) + "\n")
    out.flush()
    for line in sys.stdin:
        if not line.strip():
            continue
        job = json.loads(line)
        try:
            res = run_job(job, plugin)
        except Exception as e:  # reported to the caller, never swallowed
            res = {"id": job.get("id"), "error": f"{type(e).__name__}: {e}"}
        out.write(json.dumps(res) + "\n")
        out.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
