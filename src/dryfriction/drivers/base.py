"""What the four FMU drivers share (:class:`~dryfriction.drivers.oscillator.OscillatorFMU2`,
:class:`~dryfriction.drivers.oscillator3.OscillatorFMU3`, :class:`~dryfriction.drivers.chain.ChainFMU2`,
:class:`~dryfriction.drivers.chain.ChainFMU3`): the FMU found and checked (:mod:`dryfriction.paths`),
its model description (:mod:`dryfriction.model`), unzipped once, one instance of the FMI layer
(:mod:`dryfriction.fmi`); values set and read by name (arrays as numpy arrays), FMU states saved,
restored and serialised, ``close`` and the context manager.

Every driver steps with ``do_step(dt)`` from its current :attr:`Driver.time` and runs with
``run(t_stop, dt, ...)``.
"""

from __future__ import annotations

import ctypes
import os
import shutil
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from .. import model, paths
from ..errors import FMUError
from ..fmi import fmi2, fmi3
from ..fmi._base import BaseInstance, State

__all__ = ["Driver", "State", "Run", "Switch", "grid"]


@dataclass(frozen=True)
class Switch:
    """One stick/slip event of the oscillator: time, mode before and after, and (FMI 3.0 event
    mode) the left and right limits of the friction force and the acceleration."""

    t: float
    mode_before: int
    mode_after: int
    F_left: float = float("nan")
    F_right: float = float("nan")
    a_left: float = float("nan")
    a_right: float = float("nan")

    @property
    def kind(self) -> str:
        """What the switch is: ``breakaway`` (from stuck), ``stop`` (to stuck) or ``reversal``."""
        if self.mode_before == 0:
            return "breakaway"
        if self.mode_after == 0:
            return "stop"
        return "reversal"


@dataclass
class Run:
    """An oscillator driver's run: samples at every communication point (and, FMI 3.0, every
    early return), and the switches met (FMI 3.0 early return or event mode)."""

    time: np.ndarray
    values: dict[str, np.ndarray]
    switches: list[Switch] = field(default_factory=list)

    @property
    def switch_times(self) -> np.ndarray:
        """The times of the run's switches, s."""
        return np.array([s.t for s in self.switches])

    def __getitem__(self, name: str) -> np.ndarray:
        return self.time if name in ("t", "time") else self.values[name]


def grid(t0: float, t_stop: float, dt: float) -> np.ndarray:
    """The communication points ``t0 + k dt`` up to ``t_stop`` (the last step shortened to end
    there), t0 first; ValueError for a dt or t_stop that makes no grid."""
    if not (np.isfinite(dt) and dt > 0):
        raise ValueError(f"dt must be a finite number > 0, not {dt!r}")
    if not (np.isfinite(t_stop) and t_stop > t0):
        raise ValueError(f"t_stop must be finite and after the current time {t0!r}, not {t_stop!r}")
    k_end = max(1, int(np.ceil((t_stop - t0) / dt - 1e-9)))
    times = np.minimum(t0 + np.arange(k_end + 1) * dt, t_stop)
    times[-1] = t_stop
    return times


class Driver:
    """The common part of the drivers; a subclass sets :attr:`KIND`, calls :meth:`_open` and
    makes :attr:`inst`."""

    #: which FMU this driver runs (:mod:`dryfriction.paths`)
    KIND: ClassVar[paths.Kind]
    path: Path
    md: model.ModelDescription
    unzip_dir: str
    inst: Any  # fmi2.Instance or fmi3.Instance
    #: the current communication point
    time: float = 0.0
    #: call fmiTerminate before freeing the instance (the FMI 3.0 drivers)
    TERMINATE_ON_CLOSE: ClassVar[bool] = False

    def _open(self, fmu_path: str | os.PathLike[str] | None, prefix: str) -> None:
        """Find and check the FMU, read its model description, unzip it."""
        self.path = paths.fmu_path(self.KIND, fmu_path)
        self.md = model.from_fmu(self.path)
        self.unzip_dir = paths.extract(self.path, prefix)
        self.time = 0.0
        self._arrays = self.md.arrays()

    @property
    def messages(self) -> list[tuple[int, str, str]]:
        """(status, category, sentence) of everything the FMU logged (the layer's list)."""
        inst = getattr(self, "inst", None)
        return inst.messages if inst is not None else []

    @property
    def fmi_version(self) -> int:
        """The FMI version of the loaded FMU, 2 or 3."""
        return 3 if isinstance(self.inst, fmi3.Instance) else 2

    # ---- names --------------------------------------------------------------------------------
    def vr(self, name: str) -> int:
        """The value reference of the variable ``name`` (FMUError for an unknown name)."""
        return self.md.vr(name)

    def size(self, name: str) -> int:
        """The number of values of a variable: 1 for a scalar, the array's size otherwise."""
        v = self.md.variables.get(name)
        if v is not None and v.dimension is None:
            return 1
        elements = self._arrays.get(name)
        if elements is None:
            raise FMUError(f"unknown variable {name!r}")
        return self.array_size(name) if v is not None else len(elements)

    def array_size(self, name: str) -> int:
        """The size of an FMI 3.0 array (the current value of its structural parameter)."""
        raise FMUError(f"{name} is an array whose size this driver does not know")

    def _refs(self, name: str) -> tuple[str, list[int], int]:
        """(call type, value references, number of values) of a variable or an FMI 2.0 array name."""
        v = self.md.variables.get(name)
        if v is not None:
            return v.call_type, [v.vr], self.size(name)
        elements = self._arrays.get(name)
        if elements is None:
            raise FMUError(f"unknown variable {name!r}")
        first = self.md.variables[elements[0]]
        return first.call_type, [self.md.vr(e) for e in elements], len(elements)

    # ---- values by name -------------------------------------------------------------------------
    def set(self, values: Mapping[str, Any]) -> None:
        """Set variables by name (a scheme by its name too; an array: all its values, or one for
        every element), one checked call per variable."""
        for name, value in values.items():
            kind, vrs, n = self._refs(name)
            var = self.md.variables.get(name)
            if var is not None and var.type == "Enumeration" and isinstance(value, str):
                try:
                    value = self.md.scheme_value(value)
                except ValueError as e:
                    raise FMUError(str(e)) from None
            vals = np.ravel(np.asarray(value))
            if n > 1 and vals.size == 1:
                vals = np.repeat(vals, n)
            self.inst.set(kind, vrs, vals.tolist())

    def get(self, names: str | Sequence[str]) -> Any:
        """One variable's value (``get("h_used")``; an array's as a numpy array), or a dict of
        several (``get(["x", "mode"])``: one typed call per type, its arrays built once per list
        of names and array size)."""
        if isinstance(names, str):
            return self._get_one(names)
        key = (tuple(names), self._size_token())
        plans: dict[Any, Any] | None = getattr(self, "_get_plans3", None)
        if plans is None:
            plans = self._get_plans3 = {}
        plan = plans.get(key)
        if plan is None:
            plan = plans[key] = self._plan(key[0])
        inst = self.inst
        c, mark, out = inst.component, len(inst.messages), {}
        fmi3_call = isinstance(inst, fmi3.Instance)
        for fname, fn, vrs, nvr, buf, nval, group in plan:
            st = fn(c, vrs, nvr, buf, nval) if fmi3_call else fn(c, vrs, nvr, buf)
            if st:
                inst.check(fname, st, mark)
            k = 0
            for name, size, array in group:
                out[name] = np.array(buf[k:k + size]) if array else buf[k]
                k += size
        return {name: out[name] for name in key[0]}

    def _size_token(self) -> int:
        """What the sizes of the arrays depend on (the chain's n)."""
        return int(getattr(self, "n", 0))

    def _plan(self, names: tuple[str, ...]) -> list[tuple[Any, ...]]:
        groups: dict[str, list[tuple[str, list[int], int, bool]]] = {}
        for name in names:
            kind, vrs, n = self._refs(name)
            var = self.md.variables.get(name)
            groups.setdefault(kind, []).append((name, vrs, n, var is None or var.dimension is not None))
        plan = []
        inst = self.inst
        for kind, group in groups.items():
            vrs = [vr for _, v, _, _ in group for vr in v]
            nval = sum(n for _, _, n, _ in group)
            vr_arr = (ctypes.c_uint32 * len(vrs))(*vrs)
            buf = (inst.ctypes_of[kind] * nval)()
            plan.append((f"{inst.prefix}Get{kind}", getattr(inst.f, f"Get{kind}"), vr_arr, len(vrs), buf, nval,
                         [(name, n, array) for name, _, n, array in group]))
        return plan

    def _get_one(self, name: str) -> Any:
        kind, vrs, n = self._refs(name)
        if isinstance(self.inst, fmi3.Instance):
            vals = self.inst.get(kind, vrs, n)
        else:
            vals = self.inst.get(kind, vrs)
        is_array = self.md.variables.get(name) is None or self.md.var(name).dimension is not None
        return np.array(vals) if is_array else vals[0]

    # ---- FMU states -----------------------------------------------------------------------------
    def get_state(self) -> State:
        """The FMU's current state (free it with ``state.free()`` or ``with``)."""
        return self.inst.get_state()

    def set_state(self, state: State) -> None:
        """Go back to a state of this instance; :attr:`time` follows it."""
        self.inst.set_state(state)
        self.time = self._state_time()

    def _state_time(self) -> float:
        if isinstance(self.inst, fmi2.Instance):
            return self.inst.last_successful_time()
        return float(self.inst.get("Float64", [0])[0])  # FMI 3.0: the independent variable, value reference 0

    def serialize_state(self, state: State | None = None) -> bytes:
        """The bytes of a state (default: the current one)."""
        if state is not None:
            return self.inst.serialize_state(state)
        with self.inst.get_state() as st:
            return self.inst.serialize_state(st)

    def deserialize_state(self, data: bytes) -> State:
        """A state of this instance from serialised bytes (validated by the FMU)."""
        return self.inst.deserialize_state(data)

    def restore(self, data: bytes) -> None:
        """Deserialise ``data`` and make it the current state."""
        with self.inst.deserialize_state(data) as st:
            self.set_state(st)

    # ---- stepping (the subclasses' own) ---------------------------------------------------------
    def do_step(self, dt: float) -> Any:
        """One communication step of ``dt`` seconds from the current time; each driver implements it."""
        raise NotImplementedError

    def run(self, t_stop: float, dt: float, *args: Any, **kwargs: Any) -> Any:
        """A whole run to ``t_stop`` on a grid of ``dt``; each driver implements it."""
        raise NotImplementedError

    # ---- the end --------------------------------------------------------------------------------
    def close(self) -> None:
        """Free the instance (and its states) and remove the unzipped FMU (idempotent)."""
        inst: BaseInstance | None = getattr(self, "inst", None)
        if inst is not None:
            try:
                if self.TERMINATE_ON_CLOSE and not inst.freed:
                    mark = len(inst.messages)
                    if inst.f.Terminate(inst.component) > 1:  # not allowed in every state: free anyway
                        del inst.messages[mark:]
                inst.free()
            finally:
                self.inst = None
        d = getattr(self, "unzip_dir", None)
        if d:
            shutil.rmtree(d, ignore_errors=True)
            self.unzip_dir = ""

    def __enter__(self) -> Any:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
