"""The analytical and independent references the FMUs are checked against.

- :mod:`.exact`: the exact piecewise solution of the single oscillator;
- :mod:`.steady`: the steady-state (den Hartog) solution;
- :mod:`.belt`: the oscillator on a moving belt;
- :mod:`.chain`: the chain of oscillators.

Nothing is imported with the package.
"""
