"""The package's FMI layer: one thin ctypes layer per FMI version over an FMU's C functions.

- :mod:`dryfriction.fmi.fmi2`: FMI 2.0 co-simulation (``Instance``),
- :mod:`dryfriction.fmi.fmi3`: FMI 3.0 co-simulation (``Instance``: Configuration Mode, arrays,
  UInt64, early return, event mode, the intermediate-update callback).

Both share :mod:`dryfriction.fmi._base`: the library loaded once per instance, every function typed
once, every status checked (OK and Warning pass, anything else is an
:class:`~dryfriction.errors.FMUCallError` with the FMU's logged sentence), the sentences logged
with a warning status emitted as :class:`~dryfriction.diagnostics.DryFrictionWarning`, FMU states
that free themselves with their instance, and the fast path of hot loops (:meth:`~dryfriction.fmi.fmi2.Instance.bulk_get` /
:meth:`~dryfriction.fmi.fmi2.Instance.bulk_set`: one typed call into preallocated numpy buffers, the status checked only when it
is not OK), and the coupling calls (input, output, directional and adjoint derivatives,
inputs set during an FMI 3.0 step, the capabilities the model description declares; used by
:mod:`dryfriction.cosim`). fmpy is not used to call the FMU; it only unzips archives and names the platform's
binary folder.
"""

from . import fmi2, fmi3

__all__ = ["fmi2", "fmi3"]
