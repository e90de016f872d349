#!/usr/bin/python3
"""The Siconos side of bench/siconos_system.py, run under the SYSTEM Python: bench/siconos_run.py's
worker (one JSON job a line in, one JSON answer a line out, the stepped run sampled, ``run()``
timed by the process CPU time) with the job a general structure instead of a chain:

    M X'' + C X' + K X = F_c cos(omega t) + F_s sin(omega t) + W' (mu N lambda),
    x = (X, V),  x' = A x + b(t) + B lambda,   y = W V,   lambda_j in [-1, 1], -y in N(lambda)
    A = [[0, I], [-M^-1 K, -M^-1 C]],  B = [0; M^-1 W' diag(mu_j N_j)],
    b(t) = [0; a_i cos(omega t + phi_i)],  a_i cos(phi_i) = (M^-1 F_c)_i, a_i sin(phi_i) = -(M^-1 F_s)_i

one relay per contact (``RelayNSL(nc, -1, 1)``: lambda_j = -sign(y_j) while contact j slips), one
friction coefficient per contact; ``EulerMoreauOSI(theta)``, the one-step ``Relay`` by Lemke; b(t)
by the C plugin of bench/siconos_side.py (no Python per step).

Job keys: n, nc, M, C, K (n x n, row-major lists), F_c, F_s, x0, v0 (n), W (nc x n), muN (nc),
omega, t_end, h, theta, sample_every, reps, id.
"""

from __future__ import annotations

import sys


def build(job: dict, plugin: str) -> tuple[object, object]:
    """The TimeStepping simulation of the structure, initialised, and its dynamical system."""
    import numpy as np
    import siconos.kernel as sk
    import siconos.numerics as sn

    n, nc = int(job["n"]), int(job["nc"])
    M = np.asarray(job["M"], float).reshape(n, n)
    K = np.asarray(job["K"], float).reshape(n, n)
    Cd = np.asarray(job["C"], float).reshape(n, n)
    W = np.asarray(job["W"], float).reshape(nc, n)
    Minv = np.linalg.inv(M)
    A = np.zeros((2 * n, 2 * n))
    A[:n, n:] = np.eye(n)
    A[n:, :n] = -Minv @ K
    A[n:, n:] = -Minv @ Cd
    x0 = np.concatenate([np.asarray(job["x0"], float), np.asarray(job["v0"], float)])
    ds = sk.FirstOrderLinearDS(x0, A)
    c = Minv @ np.asarray(job["F_c"], float)
    s = Minv @ np.asarray(job["F_s"], float)
    if np.any(c != 0.0) or np.any(s != 0.0):
        ds.setzPtr(np.concatenate([[float(job["omega"])], np.hypot(c, s), np.arctan2(-s, c)]))
        ds.setComputebFunction(plugin, "dfo_harmonic_b")
    B = np.zeros((2 * n, nc))
    B[n:, :] = Minv @ W.T @ np.diag(np.asarray(job["muN"], float))
    Cy = np.zeros((nc, 2 * n))
    Cy[:, n:] = W
    inter = sk.Interaction(sk.RelayNSL(nc, -1.0, 1.0), sk.FirstOrderLinearTIR(Cy, B))
    nsds = sk.NonSmoothDynamicalSystem(0.0, float(job["t_end"]))
    nsds.insertDynamicalSystem(ds)
    nsds.link(inter, ds)
    sim = sk.TimeStepping(nsds, sk.TimeDiscretisation(0.0, float(job["h"])))
    sim.insertIntegrator(sk.EulerMoreauOSI(float(job["theta"])))
    sim.insertNonSmoothProblem(sk.Relay(sn.SICONOS_RELAY_LEMKE))
    sim.initialize()
    return sim, ds


if __name__ == "__main__":
    import siconos_run

    siconos_run.build = build  # the chain worker's loop, timing and protocol, this structure
    sys.exit(siconos_run.main())
