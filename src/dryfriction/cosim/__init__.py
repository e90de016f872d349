"""A co-simulation master for the package's FMUs (docs/coupling.md): :class:`~dryfriction.cosim.system.System` couples
started drivers (FMI 2.0 or FMI 3.0) under instance names through :class:`Connection` s
(``"a.x" -> "b.F_ext"``) and coupling elements the master computes (:class:`SpringDamper`),
by Jacobi or Gauss-Seidel, with inputs held, extrapolated from output derivatives or sent as
input derivatives, an interface-Jacobian correction for stiff couplings, and rollback with FMU
states where a step's error estimate is above a tolerance. Not a general co-simulation
platform: what the tests and users need to couple these FMUs correctly.

    from dryfriction.cosim import System, SpringDamper
    sys = System()
    sys.add("b1", fmu1); sys.add("b2", fmu2)
    sys.couple(SpringDamper("b1", "b2", k=1.0, c=0.1))
    res = sys.run(t_stop=60.0, H=0.05, inputs="extrapolate")    # res.t, res["b1.x"], res.to_dataset()
"""

from .coupling import Connection, SpringDamper, coupling_matrix
from .result import CosimResult
from .system import INPUT_MODES, JACOBIANS, METHODS, System
from .unit import DEFAULT_DERIVATIVES, Unit

__all__ = ["System", "Connection", "SpringDamper", "CosimResult", "Unit", "coupling_matrix", "METHODS",
           "INPUT_MODES", "JACOBIANS", "DEFAULT_DERIVATIVES"]
