"""The package's one exception hierarchy for everything that goes wrong with an FMU::

    FMUError                   the base: ``message``, ``function`` and ``status`` (None when no FMI call is involved)
    +-- FMUCallError           an FMI call returned Discard, Error or Fatal (or a status the host cannot accept);
    |                          the message is the sentence the FMU logged (it names the variable of a bad value)
    +-- FMUFileError           an FMU file that cannot be used (missing, not a zip, another model or FMI version);
                               also a UsageError (a ValueError): one line, exit 2

An error of fmpy (still the reader of FMU archives) is translated into one of these where fmpy is
called. The command line reports every FMUError as one line with exit status 2.
"""

from __future__ import annotations

__all__ = ["UsageError", "FMUError", "FMUCallError", "FMUFileError", "status_name"]

_FMI2_STATUS = ("fmi2OK", "fmi2Warning", "fmi2Discard", "fmi2Error", "fmi2Fatal", "fmi2Pending")
_FMI3_STATUS = ("fmi3OK", "fmi3Warning", "fmi3Discard", "fmi3Error", "fmi3Fatal")


class UsageError(ValueError):
    """An invalid argument or configuration value: reported as one line, exit status 2."""


def status_name(status: int, function: str | None = None) -> str:
    """``fmi2Error``, ``fmi3Discard``, ...: the status's name in the FMI version of ``function``
    (an ``fmi3...`` function: FMI 3.0's names, else FMI 2.0's)."""
    names = _FMI3_STATUS if function is not None and function.startswith("fmi3") else _FMI2_STATUS
    return names[status] if 0 <= status < len(names) else f"status {status}"


class FMUError(RuntimeError):
    """Something an FMU (or the host, for a value it refused before the call) did not accept.

    ``function`` and ``status`` name the FMI call when there is one; ``message`` is the FMU's logged
    sentence (or the host's)."""

    def __init__(self, message: str, function: str | None = None, status: int | None = None) -> None:
        self.message, self.function, self.status = message, function, status
        text = message if function is None else f"{function} returned {status_name(status or 0, function)}: {message}"
        super().__init__(text)


class FMUCallError(FMUError):
    """An FMI call that returned Discard, Error or Fatal: ``function``, ``status`` and the last
    sentence the FMU logged during the call (for a bad value: the variable, the value and its range)."""

    def __init__(self, message: str, function: str | None = None, status: int | None = None) -> None:
        super().__init__(message, function, status)



class FMUFileError(FMUError, UsageError):
    """An FMU path that cannot be used: missing, not a zip archive, no model description, another
    model or another FMI version. A ValueError (a :class:`UsageError`): the
    command line reports it as one line with exit status 2."""

    def __init__(self, message: str) -> None:
        super().__init__(message)
