"""Self-excited stick-slip: periodic orbits of the autonomous belt oscillator (no excitation, a belt
at a constant speed), the stability of steady sliding, the Hopf belt speed located from the model
and the orbit branch continued in the belt speed (docs/self_excited.md).

    m x'' + c x' + k x = F_0 + F,   F the friction on v_rel = v - v_belt (coulomb or stribeck),

F_0 a constant force (the input F_ext; or P0 cos(phi) with omega = 0). Steady sliding is the
equilibrium x_eq = (F_0 + sign(v_belt) N mu(|v_belt|)) / k, v = 0.

**The orbit.** The period T is an unknown. The Poincare section is x = x_eq crossed with
sign(dx/dt) = -sign(v_belt), where the block always slides (it moves against the belt); the phase
condition is the section itself: the unknowns are the velocity v0 on it and T, the residual

    R(v0, T) = (x(T) - x_eq, v(T) - v0)        from (x_eq, v0) at t = 0,

with one run of the FMU (:class:`~dryfriction.drivers.oscillator.OscillatorFMU2`, the belt speed its input v_belt)
per evaluation. Newton on R with dR/dT = the vector field at the end, (v(T), a(T)), and dR/dv0 the
second column of the flow's Jacobian M = d(x, v)(T) / d(x, v)(0):

- scheme ``exact`` (coulomb): M is the FMU's own sensitivity (``sensitivity = true``: dx_dx0, ...);
- scheme ``located`` (coulomb or stribeck): M by central finite differences of the located map
  (steps of 1e-6 of the state's scales), said in the result (``jacobian``).

M's eigenvalues are the Floquet multipliers: the trivial one 1 (along the flow) and the nontrivial
one (the section map's derivative). A stick phase on the orbit makes M rank one (the block rides on
the belt whatever it started from): the nontrivial multiplier is then exactly 0 and the trivial one
trace(M). Converged when the scaled residual max(|R_x| / X, |R_v| / (X w0)) is at most ``tol``
(X = mu_s N / k, the friction's deflection; w0 = sqrt(k / m)).

**Steady sliding** is stable when both multipliers of the flow over a fixed time tau (a natural
period) from the equilibrium are inside the unit circle (by more than NEUTRAL = 1e-6; within it of
the circle: neutral) (M by central differences with ``located``,
the sensitivity with ``exact``). With Stribeck friction (delta = 1) it loses stability at the Hopf
belt speed where c + N mu'(|v_belt|) = 0: :func:`locate_hopf` finds it from the model, by Brent's
method on ln |mu|max / tau (the growth rate of the equilibrium's flow) in the belt speed.

**The branch.** :func:`~dryfriction.analysis.self_excited.branch.continue_orbits` follows the orbit in v_belt by pseudo-arclength
continuation in (v0, T, v_belt) (dR/dv_belt by central differences: the section moves with x_eq),
from stick-slip at low belt speed up to where the branch turns and on to where its amplitude vanishes
(the Hopf), with the continuation engine of :mod:`dryfriction.analysis.continuation`.

One module per concern: ``problem`` (the problem and its model), ``flow`` (the FMU's flow and its
Jacobian), ``equilibrium`` (steady sliding), ``orbit`` (Newton on R, the section map), ``transient``
(sampled runs), ``motion`` (what the block does), ``hopf`` (the Hopf speed), ``branch`` (the branch
in v_belt); every public name is importable from here.
"""

from __future__ import annotations

from .branch import BeltBranch, Branch, BranchPoint, continue_orbits
from .equilibria import Equilibrium, equilibrium
from .hopf import HopfPoint, hopf_formula, locate_hopf
from .motion import SelfExcited, self_excited
from .orbit import BeltOrbit, find_orbit, section_map
from .problem import (EQ_FD_STEP, FD_STEP, JACOBIAN, LAWS, MAX_SAMPLES, NEUTRAL, SCHEMES, STABILITY_MARGIN,
                      STEPS_PER_PERIOD, TRIVIAL, BeltProblem)
from .transients import Transient, transient

__all__ = ["BeltProblem", "BeltOrbit", "Equilibrium", "SelfExcited", "HopfPoint", "Branch", "BranchPoint",
           "LAWS", "SCHEMES", "equilibrium", "find_orbit", "self_excited", "locate_hopf", "continue_orbits",
           "transient", "section_map", "hopf_formula", "Transient", "BeltBranch", "STABILITY_MARGIN", "NEUTRAL",
           "TRIVIAL", "MAX_SAMPLES", "STEPS_PER_PERIOD", "FD_STEP", "EQ_FD_STEP", "JACOBIAN"]
