"""Study configurations: one readable TOML file per study (``configs/<study>.toml``).

The file of a study is its schema: every key a user may change is there with its default, and the
type of the default is the type a new value must have. Three layers go on top, in order:

1. ``[quick]`` of the same file (a table with the same structure) when ``--quick`` is given;
2. ``--config FILE``: a TOML file with any subset of the keys;
3. ``--set key=value`` (dotted keys, TOML values: ``--set sweep.chi.num=20``,
   ``--set params.lam=0.6``, ``--set numerics.scheme=consistent``, ``--set fig11.chi=[0.7,0.5]``).

An unknown key or a value of the wrong type is a :class:`ConfigError` with one readable sentence.
"""

from __future__ import annotations

import copy
import os
import tomllib
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import UsageError

__all__ = [
    "ConfigError",
    "config_dir",
    "load_toml",
    "build_config",
    "parse_set",
    "grid",
    "require",
]


class ConfigError(UsageError):
    """An invalid argument or configuration value (reported as one line, exit status 2)."""


def config_dir() -> Path:
    """Where the study configs live: ``$DFO_CONFIGS``, else the installed package's
    (``dryfriction/configs``), else ``configs/`` of the repository (:func:`dryfriction.paths.configs_dir`)."""
    from ..paths import configs_dir

    return configs_dir()


def load_toml(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Read a TOML file (ConfigError with the file and the parser's sentence when it cannot be read)."""
    p = Path(path)
    try:
        with open(p, "rb") as f:
            return tomllib.load(f)
    except FileNotFoundError:
        raise ConfigError(f"config file not found: {p}") from None
    except tomllib.TOMLDecodeError as e:
        raise ConfigError(f"config file {p} is not valid TOML: {e}") from None
    except OSError as e:
        raise ConfigError(f"cannot read config file {p}: {e.strerror}") from None


def _type_name(v: Any) -> str:
    if isinstance(v, bool):
        return "a boolean (true/false)"
    if isinstance(v, int):
        return "an integer"
    if isinstance(v, float):
        return "a number"
    if isinstance(v, str):
        return "a string"
    if isinstance(v, list):
        return "a list"
    if isinstance(v, dict):
        return "a table"
    return type(v).__name__


def _coerce(value: Any, template: Any, key: str) -> Any:
    """``value`` converted to the type of ``template`` (ints widen to floats), else ConfigError."""
    if isinstance(template, bool):
        if isinstance(value, bool):
            return value
    elif isinstance(template, int):
        if isinstance(value, int) and not isinstance(value, bool):
            return value
    elif isinstance(template, float):
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            v = float(value)
            if not np.isfinite(v):
                raise ConfigError(f"{key} must be a finite number, not {value!r}")
            return v
    elif isinstance(template, str):
        if isinstance(value, str):
            return value
    elif isinstance(template, list):
        if isinstance(value, list):
            if template:
                return [_coerce(x, template[0], f"{key}[{i}]") for i, x in enumerate(value)]
            return list(value)
    elif isinstance(template, dict):
        if isinstance(value, dict):
            return value
    raise ConfigError(f"{key} must be {_type_name(template)}, not {value!r}")


def _merge(base: dict[str, Any], over: Mapping[str, Any], where: str, prefix: str = "") -> None:
    for k, v in over.items():
        key = f"{prefix}{k}"
        if k not in base:
            known = ", ".join(sorted(base)) or "none"
            raise ConfigError(f"unknown key {key!r} in {where} (known here: {known})")
        if isinstance(base[k], dict):
            if not isinstance(v, dict):
                raise ConfigError(f"{key} must be a table, not {v!r} ({where})")
            _merge(base[k], v, where, f"{key}.")
        else:
            base[k] = _coerce(v, base[k], key)


def parse_set(expr: str) -> tuple[list[str], Any]:
    """``"a.b.c=value"`` -> (["a", "b", "c"], value); the value is read as TOML, else as text."""
    if "=" not in expr:
        raise ConfigError(f"--set needs key=value, not {expr!r}")
    key, raw = expr.split("=", 1)
    key = key.strip()
    if not key or any(not part for part in key.split(".")):
        raise ConfigError(f"--set needs a dotted key like sweep.chi.num, not {key!r}")
    raw = raw.strip()
    try:
        value = tomllib.loads(f"v = {raw}")["v"]
    except tomllib.TOMLDecodeError:
        if raw and not any(c in raw for c in "[]{}=\"'"):
            value = raw  # a bare word: a string
        else:
            raise ConfigError(f"--set {key}: cannot read the value {raw!r}") from None
    return key.split("."), value


def _nest(path: list[str], value: Any) -> dict[str, Any]:
    d: Any = value
    for part in reversed(path):
        d = {part: d}
    return d


def build_config(
    default: Mapping[str, Any],
    quick: bool = False,
    config_file: str | os.PathLike[str] | None = None,
    sets: Iterable[str] = (),
) -> dict[str, Any]:
    """The effective configuration of a study (without its ``[quick]`` table)."""
    cfg = copy.deepcopy(dict(default))
    quick_table = cfg.pop("quick", {})
    if quick:
        _merge(cfg, quick_table, "the [quick] table")
    if config_file is not None:
        user = load_toml(config_file)
        user.pop("quick", None)
        _merge(cfg, user, str(config_file))
    for expr in sets:
        path, value = parse_set(expr)
        _merge(cfg, _nest(path, value), "--set")
    return cfg


# ---- helpers for the studies' checks ----------------------------------------------------------

#: the most values of one range table (a sweep's axis; 80 MB of float64): more is refused while the
#: configuration is checked, before its values are made
MAX_GRID = 10_000_000


def grid(spec: Mapping[str, Any], key: str) -> np.ndarray:
    """Values of a range table ``{start, stop, num}`` (both ends included; ``num`` from 1 to
    :data:`MAX_GRID`)."""
    num = spec["num"]
    if not 1 <= num <= MAX_GRID:
        raise ConfigError(f"{key}.num must be in [1, {MAX_GRID:,}], not {num}")
    if num == 1:
        return np.array([float(spec["start"])])
    return np.linspace(float(spec["start"]), float(spec["stop"]), int(num))


def require(ok: bool, message: str) -> None:
    """Raise ConfigError with ``message`` unless ``ok``."""
    if not ok:
        raise ConfigError(message)
