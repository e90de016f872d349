"""The chain's Model Exchange (``DryFrictionChain.fmu``, FMI 3.0) integrated by fmpy's solvers.

fmpy sizes an FMI 3.0 FMU's arrays, its continuous states and its event indicators by the start
values of their structural parameters (the chain's n = 2), and ``simulate_fmu`` cannot set one. For
n blocks the instance is made here, n set in Configuration Mode, and fmpy is given the model
description sized for n (2 n states x, v; 2 n event indicators)::

    from dryfriction.drivers.chain_me import simulate_chain_me
    from dryfriction.references.chain import Chain
    ch = Chain.make(4, omega=0.6, N=0.5)
    r = simulate_chain_me(ch, t_end=50.0, relative_tolerance=1e-10)   # r["x"]: [nt, 4]

The result is fmpy's (``time``, ``x``, ``v``, ``a``, ``F_friction``, ``mode``; every array output
[nt, n]). docs/model_exchange.md says what the host sees.
"""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import numpy as np

from .chain import default_chain_fmu3

__all__ = ["chain_me_description", "simulate_chain_me"]


def chain_me_description(fmu: Path | str, n: int) -> Any:
    """fmpy's model description of the FMI 3.0 chain ``fmu`` with its arrays, continuous states
    (2 n) and event indicators (2 n) sized for n blocks."""
    from fmpy import read_model_description
    md = read_model_description(str(fmu))
    for v in md.modelVariables:
        if v.dimensions:
            v.shape = (n,)
    md.numberOfContinuousStates = md.numberOfEventIndicators = 2 * n
    return md


def simulate_chain_me(ch: Any, t_end: float, fmu: Path | str | None = None, solver: str = "CVode",
                      start: dict[str, Any] | None = None, **kwargs: Any) -> np.ndarray:
    """fmpy's ``simulate_fmu`` of the FMI 3.0 chain as Model Exchange for the chain ``ch``
    (n = ch.n blocks, its parameters; ``start``: more start values) from 0 to ``t_end`` with
    ``solver`` (CVode or Euler); ``kwargs`` go to ``simulate_fmu`` (relative_tolerance,
    output_interval, record_events ...)."""
    from fmpy import extract, simulate_fmu
    from fmpy.fmi3 import FMU3Model
    path = Path(fmu) if fmu is not None else default_chain_fmu3()
    md = chain_me_description(path, ch.n)
    vr_n = next(v.valueReference for v in md.modelVariables if v.name == "n")
    unzipped = extract(str(path))
    inst = FMU3Model(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.modelExchange.modelIdentifier,
                     instanceName="chain-me")
    inst.instantiate()
    try:
        inst.enterConfigurationMode()
        inst.setUInt64([vr_n], [ch.n])
        inst.exitConfigurationMode()
        return simulate_fmu(unzipped, fmi_type="ModelExchange", solver=solver, stop_time=t_end,
                            start_values={**ch.fmu_params(), **(start or {})}, model_description=md,
                            fmu_instance=inst, **kwargs)
    finally:
        inst.freeInstance()
        shutil.rmtree(unzipped, ignore_errors=True)
