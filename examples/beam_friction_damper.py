"""A cantilever beam with a friction damper, driven through its first bending resonance.

A steel strip (0.5 m x 30 mm x 4 mm, E = 210 GPa, rho = 7850 kg/m^3) clamped at its root, modelled
by 12 Euler-Bernoulli elements (2 DOFs per node: deflection and slope; 24 DOFs once the root is
clamped), 2 % modal damping on every mode (System.with_modal_damping), a harmonic force of 1 N at
its tip. A friction damper presses on the deflection of the node at a third of the length (a rigid
Coulomb contact, mu_s = 0.3, mu_k = 0.25). The tip's steady response amplitude against the forcing
frequency, run as the DryFrictionSystem FMU (FMI 3.0) through the package's driver (dryfriction.drivers.system), for

- N = 0: the linear beam, checked against the modal closed form |sum_r phi_r phi_r' F /
  (w_r^2 - w^2 + 2 i zeta w_r w)| at the tip;
- a few normal loads in the stick-slip range: the resonance flattened and moved up;
- N large: the damper never slips, the beam pinned at that node, checked against the closed form
  of that linear system (the same beam with the node's deflection removed).

Each run starts from the linear steady state (the closed form at t = 0), settles for a number of
forcing periods and is sampled over the last ones; the amplitude is half the peak-to-peak of the
tip's deflection (40 samples a period), and for the two linear cases also the first harmonic
fitted by least squares (what the closed form gives).

The same sweeps by periodic orbits (``frequency_response`` of a System: Newton shooting with the
FMU's Jacobian, each frequency from the last orbit) of the beam reduced by Craig-Bampton to the
damper's DOF, the tip and 8 modes (``dryfriction.system.craig_bampton``): the mesh's fastest mode
(206,000 rad/s) is beyond the located scheme's step, so the full beam runs on the consistent
scheme's fallback (first order), the reduced one (fastest 22,500 rad/s) on the located scheme; the
linear cases are checked against their closed forms, the stick-slip ones printed against the
transients (where they differ: coexisting orbits, a sweep follows one; transients settle on another
or have not settled). An orbit that did not converge is printed with its reason and left out.
Writes beam_friction_damper.png (markers: transients; lines: orbits) to --out.

    python examples/beam_friction_damper.py [--quick] [--k-t 0] [--out results/example_beam]

The damper is Contact(dof=..., N=..., k_t=K_T): a Jenkins contact (a tangential stiffness in
series with the slider) is --k-t > 0, once the FMU builds them. The FMU: $DFO_SYSTEM_FMU3, else
the package's or the build tree's fmi3/DryFrictionSystem.fmu. Exits non-zero when a check fails.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from dryfriction import Contact, System, frequency_response
from dryfriction.drivers.system import trajectory
from dryfriction.system import craig_bampton
from dryfriction.system.cases import cantilever

# the strip
LENGTH, WIDTH, THICK = 0.5, 0.03, 0.004
E_MOD, RHO = 210e9, 7850.0
ELEMENTS = 12
ZETA = 0.02
F_TIP = 1.0
DAMPER_NODE = 4  # of 12: at a third of the length
MU_S, MU_K = 0.3, 0.25
SAMPLES_PER_PERIOD = 40
STEPS_PER_PERIOD = 400
CB_MODES = 8  # the fixed-interface modes the reduced beam keeps


def beam_matrices(elements: int = ELEMENTS) -> tuple[np.ndarray, np.ndarray]:
    """M and K of the clamped steel strip (dryfriction.system.cases.cantilever: consistent
    Euler-Bernoulli elements, the root's two DOFs removed). DOF 2 (k - 1) is node k's deflection,
    2 (k - 1) + 1 its slope (k = 1 .. elements)."""
    return cantilever(elements, LENGTH, E_MOD * WIDTH * THICK**3 / 12.0, RHO * WIDTH * THICK)


def damper(N: float, k_t: float = 0.0) -> Contact:
    """The friction damper on the deflection of DAMPER_NODE: rigid (k_t = 0) or Jenkins (k_t > 0)."""
    return Contact(dof=2 * (DAMPER_NODE - 1), N=N, mu_s=MU_S, mu_k=MU_K, k_t=k_t)


def tip_dof(n: int) -> int:
    """The tip's deflection."""
    return n - 2


def modal_response(M: np.ndarray, K: np.ndarray, zeta: float, F: np.ndarray, w: float) -> np.ndarray:
    """The complex steady amplitude X (x = Re(X e^{i w t})) of M x'' + C x' + K x = F cos(w t), C the
    modal damping zeta on every mode, by modal superposition: sum_r phi_r (phi_r' F) / (w_r^2 - w^2
    + 2 i zeta w_r w), phi_r mass-normalised."""
    from scipy.linalg import eigh

    lam, phi = eigh(K, M)
    wr = np.sqrt(lam)
    return phi @ ((phi.T @ F) / (wr**2 - w**2 + 2j * zeta * wr * w))


def pinned_response(M: np.ndarray, C: np.ndarray, K: np.ndarray, F: np.ndarray, w: float, pin: int) -> np.ndarray:
    """The complex steady amplitude with DOF pin held at 0 (the stuck damper): (K - w^2 M + i w C) X = F
    on the other DOFs (C restricted to them: no longer modal for the pinned beam), X_pin = 0."""
    keep = np.delete(np.arange(M.shape[0]), pin)
    A = K - w**2 * M + 1j * w * C
    X = np.zeros(M.shape[0], complex)
    X[keep] = np.linalg.solve(A[np.ix_(keep, keep)], F[keep])
    return X


def first_harmonic(t: np.ndarray, x: np.ndarray, w: float) -> float:
    """|a + i b| of the least-squares fit a cos(w t) + b sin(w t) + c."""
    A = np.column_stack([np.cos(w * t), np.sin(w * t), np.ones_like(t)])
    a, b, _ = np.linalg.lstsq(A, x, rcond=None)[0]
    return float(np.hypot(a, b))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="a few frequencies and loads (CI)")
    ap.add_argument("--k-t", type=float, default=0.0, help="the damper's tangential stiffness (N/m; 0: rigid)")
    ap.add_argument("--out", type=Path, default=Path("results/example_beam"))
    args = ap.parse_args()

    M, K = beam_matrices()
    n = M.shape[0]
    F = np.zeros(n)
    F[tip_dof(n)] = F_TIP
    base = System(M=M, K=K).with_modal_damping(ZETA)
    w1 = float(base.modes()[0][0])
    pin = 2 * (DAMPER_NODE - 1)
    # the load that holds the damper at every frequency of the sweep: its holding force's amplitude,
    # the reaction of the pinned beam (K_pin,: - w^2 M_pin,: + i w C_pin,:) X, at most
    ratios = np.linspace(0.6, 2.6, 11) if args.quick else np.concatenate([np.linspace(0.6, 1.5, 19),
                                                                          np.linspace(1.6, 2.6, 11)])
    C = base.C
    react = max(abs((K[pin] - (w * w1) ** 2 * M[pin] + 1j * w * w1 * C[pin]) @ pinned_response(M, C, K, F, w * w1, pin)
                    - F[pin]) for w in np.linspace(0.5, 3.0, 101))
    N_hold = react / min(MU_S, MU_K)
    # the stick-slip loads: fractions of the one that holds the damper at the first resonance
    X1 = pinned_response(M, C, K, F, w1, pin)
    N_1 = abs((K[pin] - w1**2 * M[pin] + 1j * w1 * C[pin]) @ X1 - F[pin]) / min(MU_S, MU_K)
    slip = (0.3, 1.0) if args.quick else (0.1, 0.3, 0.6, 1.2)
    loads = [0.0, *(f * N_1 for f in slip), 10.0 * N_hold]
    settle, keep = (20, 4) if args.quick else (40, 5)
    print(f"{n} DOFs, first bending frequency {w1 / (2 * np.pi):.3f} Hz; damper at node {DAMPER_NODE} "
          f"(x = {DAMPER_NODE * LENGTH / ELEMENTS:.3f} m); the damper's largest holding force {react:.4g} N, "
          f"held for N >= {N_hold:.4g} N (at the first resonance: {N_1:.4g} N)")
    t_start = time.process_time()
    amp = np.zeros((len(loads), len(ratios)))
    fit = np.zeros_like(amp)
    stuck_share = np.zeros_like(amp)
    closed_lin = np.array([abs(modal_response(M, K, ZETA, F, r * w1)[tip_dof(n)]) for r in ratios])
    closed_pin = np.array([abs(pinned_response(M, C, K, F, r * w1, pin)[tip_dof(n)]) for r in ratios])
    for i, N in enumerate(loads):
        for k, r in enumerate(ratios):
            w = r * w1
            T = 2 * np.pi / w
            X0 = pinned_response(M, C, K, F, w, pin) if N >= N_hold else modal_response(M, K, ZETA, F, w)
            s = base.replace(contacts=[damper(N, args.k_t)], F_c=F, omega=w, x0=X0.real, v0=-w * X0.imag,
                             h=T / STEPS_PER_PERIOD)
            t_obs = settle * T + np.arange(keep * SAMPLES_PER_PERIOD + 1) * T / SAMPLES_PER_PERIOD
            times = np.concatenate([[0.0], t_obs])
            res = trajectory(s, times)  # the FMI 3.0 DryFrictionSystem FMU (dryfriction.drivers.system)
            x, modes = res.x[:, tip_dof(n)], res.mode[:, 0]
            amp[i, k] = 0.5 * (x[1:].max() - x[1:].min())
            fit[i, k] = first_harmonic(t_obs, x[1:], w)
            stuck_share[i, k] = float(np.mean(modes[1:] == 0))
        print(f"N = {N:8.4g} N: tip amplitude (mm) " + " ".join(f"{1e3 * a:.3g}" for a in amp[i]) +
              f"; stuck {100 * stuck_share[i].mean():.0f} % of the samples")

    t_transient = time.process_time() - t_start
    # the same sweep by periodic orbits (find_orbits' shooting with the FMU's Jacobian, each frequency
    # from the last orbit) of the beam reduced to the damper's DOF, the tip and CB_MODES modes: the
    # full mesh's fastest mode is beyond the located scheme's step (it falls back to first order),
    # the reduced one's is not
    tip = tip_dof(n)
    amp_orb, err_orb = np.zeros_like(amp), np.zeros_like(amp)
    conv = np.zeros(amp.shape, dtype=bool)
    failed: list[str] = []
    t_start = time.process_time()
    for i, N in enumerate(loads):
        s = base.replace(contacts=[damper(N, args.k_t)], F_c=F, omega=w1, h=2 * np.pi / w1 / STEPS_PER_PERIOD)
        red = craig_bampton(s, CB_MODES, boundary=[pin, tip])
        ds = frequency_response(red.system, ratios * w1 / (2 * np.pi), dof=red.coordinate(tip))
        conv[i] = ds["converged"].values
        amp_orb[i] = np.where(conv[i], ds["amplitude_dof_m"].values, np.nan)  # (not converged: no value)
        err_orb[i] = ds["error_m"].values
        failed += [f"N = {N:.4g} N, {r:.3g} f_1: {why}" for r, why, c in zip(ratios, ds["reason"].values, conv[i])
                   if not c]
    t_orbits = time.process_time() - t_start
    w_red = craig_bampton(base.replace(contacts=[damper(0.0)]), CB_MODES, boundary=[pin, tip]).system.modes()[0]
    print(f"by orbits of the beam reduced to {2 + CB_MODES} coordinates (Craig-Bampton: the damper's DOF, the tip, "
          f"{CB_MODES} modes; its fastest mode {w_red[-1]:.4g} rad/s, the mesh's {base.modes()[0][-1]:.4g}): "
          f"{conv.sum()} of {conv.size} orbits converged, largest estimated error "
          f"{np.nanmax(err_orb / amp_orb):.1e} of the amplitude")
    for line in failed:
        print(f"  NOT CONVERGED (no value): {line}")
    for i, N in enumerate(loads):
        print(f"N = {N:8.4g} N: tip amplitude (mm) " + " ".join(f"{1e3 * a:.3g}" for a in amp_orb[i]) +
              f"; against the transients {np.nanmax(np.abs(amp_orb[i] / amp[i] - 1.0)):.1e}")
    print(f"CPU per point: transients of the full beam {t_transient / amp.size:.3f} s, orbits of the reduced "
          f"beam {t_orbits / amp.size:.3f} s")

    ok = bool(conv[0].all() and conv[-1].all())  # (the linear cases' orbits: every one)
    e_lin = float(np.max(np.abs(fit[0] / closed_lin - 1.0)))
    e_pin = float(np.max(np.abs(fit[-1] / closed_pin - 1.0)))
    print(f"N = 0: the first harmonic against the modal closed form: largest relative difference {e_lin:.2e}")
    print(f"N = {loads[-1]:.4g} N: against the pinned beam's closed form: largest relative difference {e_pin:.2e}; "
          f"stuck at {100 * stuck_share[-1].min():.0f} % of the samples or more")
    ok &= e_lin < 1e-2 and e_pin < 1e-2 and bool(np.all(stuck_share[-1] == 1.0))
    o_lin = float(np.max(np.abs(amp_orb[0] / closed_lin - 1.0)))
    o_pin = float(np.max(np.abs(amp_orb[-1] / closed_pin - 1.0)))
    print(f"orbits: N = 0 against the modal closed form {o_lin:.2e}, stuck against the pinned beam's {o_pin:.2e}")
    ok &= o_lin < 1e-3 and o_pin < 1e-3
    # with friction in the stick-slip range, the resonance peak lies below the linear one and above the
    # pinned beam's response at the linear resonance
    for i in range(1, len(loads) - 1):
        ok &= bool(amp[i].max() < amp[0].max())
    print("checks: " + ("pass" if ok else "FAIL"))

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rr = np.linspace(ratios[0], ratios[-1], 400)
    fig, ax = plt.subplots(figsize=(7.5, 4.5))
    ax.semilogy(rr, [1e3 * abs(modal_response(M, K, ZETA, F, r * w1)[tip_dof(n)]) for r in rr], "k-", lw=1,
                label="N = 0, modal closed form")
    ax.semilogy(rr, [1e3 * abs(pinned_response(M, C, K, F, r * w1, pin)[tip_dof(n)]) for r in rr], "k--",
                lw=1, label="damper stuck (pinned node), closed form")
    for i, N in enumerate(loads):
        label = "N = 0" if N == 0 else (f"N = {N:.3g} N (stuck)" if N >= N_hold else f"N = {N:.3g} N")
        line, = ax.semilogy(ratios, 1e3 * amp[i], "o", ms=4, label=f"FMU, transients, {label}")
        ax.semilogy(ratios, 1e3 * amp_orb[i], "-", color=line.get_color(), lw=1)
    ax.set_xlabel(r"forcing frequency / first bending frequency ($f_1$ = " f"{w1 / (2 * np.pi):.2f} Hz)")
    ax.set_ylabel("tip amplitude (mm)")
    ax.set_title(f"Cantilever, {n} DOFs, friction damper at node {DAMPER_NODE} of {ELEMENTS} "
                 f"(lines: orbits, reduced to {2 + CB_MODES})", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    args.out.mkdir(parents=True, exist_ok=True)
    png = args.out / "beam_friction_damper.png"
    fig.savefig(png, dpi=120)
    print(f"wrote {png}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
