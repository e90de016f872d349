"""Is it chaos? Tools that tell chaos, coexisting periodic motions and long transients apart.

- :mod:`.maps`: the stroboscopic (time-T) map through the FMU (:class:`FMUMap`) or the exact
  solution (:class:`ExactMap`);
- :mod:`.lyapunov`: the largest Lyapunov exponent by Benettin's two-trajectory method;
- :mod:`.attractors`: period detection and an attractor catalogue (basins);
- :mod:`.batch`: chunked runs on Dask workers; :mod:`.cli`: ``dryfriction lyapunov``.

The studies are ``chaos_scan``, ``chaos_basins`` and ``chaos_transients`` (docs/chaos.md).
"""

from .attractors import NONPERIODIC, Attractor, Catalogue, period_of
from .lyapunov import LyapunovResult, benettin
from .maps import ExactMap, FMUMap, NDParams, StroboscopicMap

__all__ = ["Attractor", "Catalogue", "ExactMap", "FMUMap", "LyapunovResult", "NDParams", "NONPERIODIC",
           "StroboscopicMap", "benettin", "period_of"]
