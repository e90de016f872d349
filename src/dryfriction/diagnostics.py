"""How the FMUs' warnings reach the user: one warning category, :class:`DryFrictionWarning`.

The package's FMI layer (:mod:`dryfriction.fmi.fmi2`, :mod:`dryfriction.fmi.fmi3`, under every
driver) collects the sentences an FMU logs with a warning status and hands
them to :func:`emit` right after the call returns, as Python warnings of this one category with
the FMU's own sentence. A Python program filters them as usual::

    import warnings
    from dryfriction import DryFrictionWarning
    warnings.simplefilter("error", DryFrictionWarning)    # a warning ends the run (python -W error too)

The command line prints each as one line on stderr (``dryfriction: warning: ...``); ``--strict``
turns them into errors (exit status 2). Work done on Dask workers records its warnings there
(:func:`recorded`) and the client emits them again (:func:`emit`), so that a sweep's warnings are
not lost in the workers' logs.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Iterable
from typing import Any, TypeVar

__all__ = ["DryFrictionWarning", "emit", "emit_new", "recorded"]


class DryFrictionWarning(UserWarning):
    """A warning an FMU of this package logged (e.g. an internal step that does not resolve the
    dynamics); the message is the FMU's own sentence."""


def emit(messages: Iterable[str], stacklevel: int = 3) -> None:
    """Each message as a :class:`DryFrictionWarning` (raised if the filters say ``error``)."""
    for m in messages:
        warnings.warn(m, DryFrictionWarning, stacklevel=stacklevel)


def emit_new(messages: Iterable[str], seen: set[str]) -> None:
    """:func:`emit` the messages not in ``seen`` (a sweep's workers repeat the same sentence), and
    add them to it."""
    new = [m for m in dict.fromkeys(messages) if m not in seen]
    seen.update(new)
    emit(new, stacklevel=3)


T = TypeVar("T")


def recorded(func: Callable[..., T], *args: Any) -> tuple[T, list[str]]:
    """``func(*args)`` and the distinct :class:`DryFrictionWarning` messages it raised, in order
    (for a worker process: the client emits them again with :func:`emit`)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", DryFrictionWarning)
        out = func(*args)
    seen: dict[str, None] = {}
    for w in caught:
        if issubclass(w.category, DryFrictionWarning):
            seen.setdefault(str(w.message))
        else:  # not ours: shown as it would have been
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return out, list(seen)
