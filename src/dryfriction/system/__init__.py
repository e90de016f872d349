"""Any structure with dry-friction contacts (method.md section 13, docs/system.md): the structure
(:class:`~dryfriction.system.structure.System`, its :class:`~dryfriction.system.structure.Contact`
s) with its checks, damping helpers and the oscillator and the chain as systems, and the structure
file (:mod:`dryfriction.system.spec`), the field's benchmark structures (:mod:`dryfriction.system.cases`),
the Craig-Bampton reduction of a finite-element model to its contacts and a few modes
(:mod:`dryfriction.system.reduction`), the cyclic symmetry of a structure of identical sectors under a
travelling wave (:mod:`dryfriction.system.symmetry`)::

    from dryfriction import System, Contact
    sys = System(M=M, K=K, contacts=[Contact(dof=3, N=10.0, mu_s=0.3, mu_k=0.2),
                                     Contact(between=(2, 5), N=5.0, mu_s=0.2, k_t=1e4)],
                 F_c=F_c, omega=12.0).with_rayleigh(0.1, 1e-4)
    sys = System.from_file("beam.toml")
"""

from . import cases
from .cases import bladed_disk, two_mass_jenkins
from .reduction import Reduction, craig_bampton
from .spec import load
from .structure import SCHEMES, Contact, System
from .symmetry import CyclicSymmetry

__all__ = ["System", "Contact", "SCHEMES", "load", "cases", "two_mass_jenkins", "bladed_disk", "craig_bampton",
           "Reduction", "CyclicSymmetry"]
