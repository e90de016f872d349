"""Steady states that are steady, and the frequency response of an oscillator in physical units.

Two methods (``frequency_response(..., method=...)``, ``dryfriction response --method``):

``orbit`` (the default with the exact scheme): the steady states are the periodic orbits of
:func:`dryfriction.analysis.orbits.find_orbits` (Newton shooting on the exact stroboscopic map, the Floquet
multipliers from the FMU's own Jacobian): every orbit found at each frequency, stable or not, along
a dimension ``orbit`` (padded NaN). Each orbit of one frequency is followed to the next (Newton from
a polynomial prediction of its state at its section, :class:`dryfriction.analysis.orbits.OrbitFollower`, no
sampled cycle runs); :func:`~dryfriction.analysis.orbits.find_orbits` from transients at the first frequency
and wherever the followed orbits include no stable one (a bifurcation of the branch followed; with
no stable orbit of K periods, of 2 K too: a period doubling);
every :data:`COLD_EVERY` frequencies the transients of that search are followed too (a branch born
away from the ones followed).

``transient``: :func:`steady_state` runs the FMU from the initial conditions for n = ``min_periods``,
2 n, 4 n, ... excitation periods (one ``doStep`` each, the in-FMU observables over the last half of
the run, so that successive runs observe successive, adjacent windows [n/2, n] T and [n, 2n] T).
It stops when the error left in the last window, estimated from the last three windows, is within
the tolerance:

    e_A <= tol A_j,   e_o <= tol A_j,   |s_j - s_{j-1}| <= tol_stick

(A the amplitude, half the peak-to-peak of x over the window, m; o the offset, the window's
mid-range, m; s the share of the window spent stuck). The estimate fits the decay of a transient to
the last three windows: a window's amplitude is taken as A_inf + B u^(2^j) (a free vibration
decaying geometrically in time, each window starting at twice the time of the one before), so that
with the differences d_j = A_j - A_{j-1} and q = d_j / d_{j-1} = u (u + 1) the error left is
e = |d_j| u^2 / (1 - u^2), times the safety factor :data:`SAFETY`. A change that does not shrink
(|q| >= 2: u >= 1, e.g. a free vibration that decays slowly against the run) is never converged,
however small it is. Without friction (mu_k N = 0) the decay rate is known, zeta w0, and the larger
of the two estimates is used. ``tol`` thus bounds the estimated error of the amplitude, not the
change between two windows. ``converged = False`` is reported with the last window's values when
``max_periods`` is reached first. A window covers many periods, so period-n motions and slow beats
are compared as wholes. An undamped oscillator excited at its resonance with 4 mu_k N < pi P0 never
converges (the amplitude grows by (pi P0 - 4 mu_k N) / k per period): it is reported so, never as
a steady amplitude.

:func:`frequency_response` does either for a list of frequencies in Hz (in this process, or on Dask
workers for long sweeps) and returns an xarray Dataset with units; :func:`plot_response` draws it
with Den Hartog's and Inman's amplitudes where they apply and the stick share below.
"""

from __future__ import annotations

from .orbit import COLD_EVERY, ORBIT_COLUMNS, ORBIT_FLAGS, ORBIT_SAMPLES, _Branch
from .plot import plot_response
from .sweep import (MAX_CHUNK, METHODS, ORBIT_FREQUENCY_STEPS, RESPONSE_BYTES, frequency_response, never_converges_note,
                    response_work, with_omega)
from .transient import (MAX_PERIODS, MIN_PERIODS, ROUNDOFF, SAFETY, SPAN, TOL, TOL_STICK, SteadyState, default_settings,
                        remaining_error, steady_state)

__all__ = ["SteadyState", "steady_state", "frequency_response", "plot_response", "TOL", "TOL_STICK",
           "MIN_PERIODS", "MAX_PERIODS", "METHODS", "default_settings", "remaining_error", "response_work",
           "never_converges_note", "with_omega", "COLD_EVERY", "ORBIT_COLUMNS", "ORBIT_FLAGS", "ORBIT_SAMPLES",
           "MAX_CHUNK", "RESPONSE_BYTES", "ORBIT_FREQUENCY_STEPS", "ROUNDOFF", "SAFETY", "SPAN"]
