"""Analyses built on the drivers and the references: periodic orbits and their continuation,
self-excited motion, frequency responses, validation and its report, slip events, and
:mod:`.chaos` (Lyapunov exponents, attractors, the stroboscopic map).

Nothing is imported with the package: each analysis is imported where it is used.
"""
