"""The FMU drivers: one Python class per FMU over the FMI layer (:mod:`dryfriction.fmi`).

- :mod:`.base`: what every driver shares (the FMU unzipped once, the instance's life, states);
- :mod:`.oscillator`: the FMI 2.0 oscillator (:class:`~.oscillator.OscillatorFMU2`, ``Settings``);
- :mod:`.oscillator3`: the FMI 3.0 oscillator (:class:`~.oscillator3.OscillatorFMU3`: events,
  early return, the intermediate update);
- :mod:`.chain`: the chain of oscillators, FMI 2.0 and 3.0 (:class:`~.chain.ChainFMU2`,
  :class:`~.chain.ChainFMU3`);
- :mod:`.scenes`: the named parameter scenes a run starts from;
- :mod:`.chain_me`: the FMI 3.0 chain's Model Exchange under fmpy (n set in Configuration Mode);
- :mod:`.modelica`: the Modelica Standard Library's spring-and-friction pendulum (the FMIZoo's
  ``SpringFrictionPendulum1D``) as the oscillator's start values.

Nothing is imported with the package: ``import dryfriction.drivers`` loads no FMU code.
"""
