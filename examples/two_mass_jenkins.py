"""A friction damper's classic design curve: two masses, a Jenkins element between them.

A primary mass m1 on a spring k1 (3 % damping) is driven by F0 cos(w t); a damper mass m2 (a light
dashpot to the ground) rides on it through a Jenkins element (a tangential spring k_t in series with a dry-friction slider, limit
mu N). Swept through the structure's resonances at several normal loads N, run as the
DryFrictionSystem FMU (FMI 3.0) through the package's driver (dryfriction.drivers.system):

- N = 0: the damper carries no force, m1 is a linear oscillator (checked against its closed form);
- N large: the slider never slips, the two masses are a linear two-DOF system coupled by k_t
  (checked against its closed form);
- in between the slider slips part of each cycle and dissipates energy: the resonant amplitude of
  m1 against N falls from the free peak, reaches a minimum, and rises again to the stuck system's
  peak -- the curve a damper's normal load is chosen on (the example checks that minimum lies
  strictly inside the range of loads and below both ends).

Each steady amplitude is a periodic orbit of the located scheme's map, found by Newton shooting with
the FMU's own Jacobian and followed from one frequency to the next (``frequency_response`` of the
System: dryfriction.analysis.system_response), with its stability and the amplitude's error estimated
against h / 2. Writes the response curves and the resonant amplitude against N as one PNG.

    python examples/two_mass_jenkins.py [--quick] [--out results/example_two_mass_jenkins]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from dryfriction import Contact, System, frequency_response

M1, M2, K1, ZETA, K_T, MU, F0 = 1.0, 0.1, 1.0, 0.03, 0.3, 0.5, 0.05
C1, C2 = 2.0 * ZETA * np.sqrt(K1 * M1), 2.0 * ZETA * np.sqrt(K_T * M2)  # dashpots to the ground


def linear(w: float, stuck: bool) -> np.ndarray:
    """The complex steady amplitudes (x1, x2) of the linear limits: N = 0 (m2 at rest) or stuck."""
    if not stuck:
        return np.array([F0 / (K1 - w * w * M1 + 1j * w * C1), 0.0])
    A = np.array([[K1 + K_T - w * w * M1 + 1j * w * C1, -K_T], [-K_T, K_T - w * w * M2 + 1j * w * C2]], complex)
    return np.linalg.solve(A, np.array([F0, 0.0], complex))


def structure(N: float, w: float) -> System:
    """The two masses at the forcing frequency w (rad/s), starting from the linear limit's motion."""
    X0 = linear(w, stuck=False)
    return System(M=np.diag([M1, M2]), K=np.diag([K1, 0.0]), C=np.diag([C1, C2]),
                  contacts=[Contact(between=(0, 1), N=N, mu_s=MU, mu_k=MU, k_t=K_T)],
                  F_c=[F0, 0.0], omega=w, x0=X0.real, v0=-w * X0.imag)


def amplitudes(N: float, freqs: np.ndarray) -> tuple[np.ndarray, float, int]:
    """m1's steady amplitude at each frequency (rad/s) by periodic orbits, the largest estimated error,
    the frequencies whose orbit did not converge."""
    ds = frequency_response(structure(N, float(freqs[0])), freqs / (2 * np.pi), dof=0)
    return ds["amplitude_dof_m"].values, float(np.nanmax(ds["error_m"].values)), int((~ds["converged"].values).sum())


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer frequencies and loads (CI)")
    ap.add_argument("--out", type=Path, default=Path("results/example_two_mass_jenkins"))
    args = ap.parse_args()

    w_stuck = np.sort(np.sqrt(np.abs(np.linalg.eigvals(np.linalg.solve(np.diag([M1, M2]),
                                                                       [[K1 + K_T, -K_T], [-K_T, K_T]])))))
    ratios = np.linspace(0.6, 1.4, 9 if args.quick else 33)
    freqs = np.unique(np.concatenate([ratios * np.sqrt(K1 / M1), ratios[::2] * w_stuck[0]]))
    # the load that holds the slider at every frequency: the stuck system's spring force, at most
    N_stuck = max(abs(K_T * (linear(w, True)[0] - linear(w, True)[1])) for w in np.linspace(0.3, 3.0, 271)) / MU
    loads = np.concatenate([[0.0], np.geomspace(0.003, 0.6, 5 if args.quick else 12) * N_stuck, [10.0 * N_stuck]])
    print(f"resonances: m1 alone {np.sqrt(K1 / M1):.4f} rad/s, stuck {w_stuck[0]:.4f} and {w_stuck[1]:.4f} rad/s; "
          f"the slider holds for N >= {N_stuck:.4g}")
    runs = [amplitudes(N, freqs) for N in loads]
    amp = np.array([r[0] for r in runs])
    peak = amp.max(axis=1)
    for N, a, (_, err, bad) in zip(loads, peak, runs):
        print(f"N = {N:9.4g}: resonant amplitude of m1 {a:.5g} (estimated error at most {err:.2g}"
              + (f", {bad} frequencies not converged)" if bad else ")"))

    closed_free = np.array([abs(linear(w, False)[0]) for w in freqs])
    closed_stuck = np.array([abs(linear(w, True)[0]) for w in freqs])
    e_free = float(np.max(np.abs(amp[0] / closed_free - 1.0)))
    e_stuck = float(np.max(np.abs(amp[-1] / closed_stuck - 1.0)))
    k = int(np.argmin(peak))
    print(f"N = 0 against the closed form: largest relative difference {e_free:.2e}; "
          f"stuck against its closed form: {e_stuck:.2e}")
    print(f"the smallest resonant amplitude {peak[k]:.5g} at N = {loads[k]:.4g} "
          f"({peak[k] / peak[0]:.3f} of the free peak, {peak[k] / peak[-1]:.3f} of the stuck one)")
    ok = (e_free < 1e-4 and e_stuck < 1e-4 and 0 < k < len(loads) - 1 and peak[k] < min(peak[0], peak[-1])
          and not any(r[2] for r in runs))
    print("checks: " + ("pass" if ok else "FAIL"))

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
    ww = np.linspace(freqs[0], freqs[-1], 400)
    a1.semilogy(ww, [abs(linear(w, False)[0]) for w in ww], "k-", lw=1, label="N = 0, closed form")
    a1.semilogy(ww, [abs(linear(w, True)[0]) for w in ww], "k--", lw=1, label="stuck, closed form")
    for N, a in zip(loads, amp):
        a1.semilogy(freqs, a, "o-" if 0 < N < N_stuck else "o", ms=3, label=f"orbits, N = {N:.3g}")
    a1.set_xlabel("forcing frequency (rad/s)")
    a1.set_ylabel("amplitude of m1")
    a1.legend(fontsize=7)
    a1.grid(True, which="both", alpha=0.3)
    a2.loglog(loads[1:-1], peak[1:-1], "o-", label="resonant amplitude")
    a2.axhline(peak[0], color="k", lw=1, label="N = 0")
    a2.axhline(peak[-1], color="k", ls="--", lw=1, label="stuck")
    a2.set_xlabel("normal load N")
    a2.set_ylabel("resonant amplitude of m1")
    a2.legend(fontsize=7)
    a2.grid(True, which="both", alpha=0.3)
    fig.suptitle("Two masses, a Jenkins friction element between them")
    fig.tight_layout()
    args.out.mkdir(parents=True, exist_ok=True)
    png = args.out / "two_mass_jenkins.png"
    fig.savefig(png, dpi=120)
    print(f"wrote {png}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
