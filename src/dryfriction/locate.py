"""The former name of :mod:`dryfriction.paths` (where the FMUs and the study configs come from).

``import dryfriction.locate`` gives the very same module object as ``dryfriction.paths``, so that
a name patched or read through either is the one every module uses."""

import sys

from . import paths
from .paths import *  # noqa: F401,F403  (for static readers; at run time the module is paths itself)
from .paths import FMUFileError, Kind, OSCILLATOR, OSCILLATOR3, CHAIN, CHAIN3, KINDS  # noqa: F401

sys.modules[__name__] = paths
