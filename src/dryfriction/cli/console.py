"""The command line as a process: interrupts, result sets written all or nothing, and the output
paths checked before any work.

    dryfriction ...                         # the console script: main() below, then the command

**Interrupts.** While a command runs (:func:`guarded`), the first SIGINT (Ctrl-C) or SIGTERM stops
it: the library code unwinds (a result set being staged is removed, Dask is closed) with every
library's output silenced (logging, stderr, and in the console script also the stderr of the
processes it started, Dask's workers included), then exactly one line is printed,
``dryfriction: interrupted`` (``terminated`` for SIGTERM), and the exit status is 130 (143). A
second signal while it unwinds exits at once (the console script) or is ignored (in a Python
caller). Once a command's results are complete and being committed (:func:`result_set`,
:func:`result_file`), a signal no longer stops it: the files are moved into place and the command
ends as it would have, exit status 0. Outside :func:`guarded` nothing here changes how a signal
is handled (the library API is interrupted as usual).

**FMU warnings.** While a command runs (:func:`fmu_warnings_on_stderr`), every warning an FMU logs
is one line on stderr, ``dryfriction: warning: ...`` (``--strict``: an error).

**Result sets.** ``with result_set(folder) as stage:`` writes a command's files into a staging
folder beside ``folder`` and moves them into it as one step (:func:`dryfriction.atomic.staged_outputs`);
``with result_file(path) as tmp:`` does the same for one file. :func:`check_output_folder` and
:func:`check_output_file` refuse, before the computation, an output path that cannot be written
(read-only, a file where a folder is meant or the reverse, a name too long), by creating and
removing a probe exactly where the results will be staged.

The result sets, the output checks and the command's state shared with them live in
:mod:`dryfriction.atomic` (imported from here too). This module imports only the standard library
and :mod:`dryfriction.atomic` at the top, so that the console script installs its signal handlers
before the package's heavy imports.
"""

from __future__ import annotations

import os
import signal
import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any, NoReturn

from ..atomic import (COMMAND, OutputError, check_output_file, check_output_folder, committed, interrupt_note,
                      interrupted, result_file, result_set, short_text as _short)

__all__ = ["main", "guarded", "result_set", "result_file", "check_output_folder", "check_output_file", "OutputError",
           "committed", "interrupted", "interrupt_note", "fmu_warnings_on_stderr", "MAX_WARNING_LINES",
           "EXIT_INTERRUPTED", "EXIT_FAILED", "EXIT_USAGE", "PREFIX"]

PREFIX = "dryfriction"
EXIT_FAILED = 1
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130      # 128 + SIGINT, as the shell reports it
EXIT_BROKEN_PIPE = 141      # 128 + SIGPIPE

_SIGNALS = tuple(s for s in (getattr(signal, "SIGINT", None), getattr(signal, "SIGTERM", None)) if s is not None)


#: the running command (its result sets commit it, the signal handler reads it)
_STATE = COMMAND


def _message(signum: int) -> str:
    word = "terminated" if signum == getattr(signal, "SIGTERM", -1) else "interrupted"
    return f"{PREFIX}: {word}" + (f"; {_STATE.note}" if _STATE.note and word == "interrupted" else "")


def _silence() -> None:
    """From now on no library says anything: logging off, Python's stderr to /dev/null, the
    children's stderr (the console script's gate) dropped."""
    import logging

    logging.disable(logging.CRITICAL)
    if _STATE.stderr is None:
        _STATE.stderr = sys.stderr
        sys.stderr = open(os.devnull, "w")  # noqa: SIM115 (closed when the command ends)
    if _STATE.gate is not None:
        _STATE.gate.drop()


def _unsilence() -> None:
    logging = sys.modules.get("logging")   # (not imported: nothing was silenced through it)
    if logging is not None:
        logging.disable(logging.NOTSET)
    if _STATE.stderr is not None:
        quiet, sys.stderr = sys.stderr, _STATE.stderr
        _STATE.stderr = None
        if quiet is not sys.stderr:
            quiet.close()


def _say(line: str) -> None:
    """One line on the real stderr (also while library output is silenced)."""
    out = _STATE.stderr or sys.stderr
    try:
        out.write(line + "\n")
        out.flush()
    except (OSError, ValueError):
        pass


def _on_signal(signum: int, frame: Any) -> None:
    st = _STATE
    if st.committed:
        return                       # the results are moving into place: the command completes
    if st.signum:
        if st.console:               # a second Ctrl-C while the first unwinds: leave now
            _say(_message(st.signum))
            _flush_and_exit(128 + st.signum)
        return
    st.signum = signum
    _silence()
    raise KeyboardInterrupt


def _flush_and_exit(code: int) -> None:
    try:
        sys.stdout.flush()
    except (OSError, ValueError):
        pass
    os._exit(code)


@contextmanager
def _handlers(restore: bool = True) -> Iterator[None]:
    """Our handler for SIGINT and SIGTERM while the block runs (main thread only; elsewhere the
    block runs with the handlers as they are), the previous ones restored after it (``restore``)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = {s: signal.signal(s, _on_signal) for s in _SIGNALS}
    try:
        yield
    finally:
        for s, h in old.items() if restore else ():
            signal.signal(s, h if h is not None else signal.SIG_DFL)


def guarded(command: Callable[[], int]) -> int:
    """Run ``command`` (returns an exit status) as a command of the program: signals handled as
    described in the module docstring, and every error a user can cause as one line
    ``dryfriction: error: ...`` (exit 2: bad input, an unusable FMU, an error the FMU reports;
    exit 1: the system refused, e.g. a full disk, or the Dask workers were lost too often) instead
    of a traceback."""
    from ..errors import UsageError
    from ..diagnostics import DryFrictionWarning
    from ..errors import FMUError

    st = _STATE
    if st.active:                            # already guarded (a command inside a command)
        return command()
    st.active, st.committed, st.signum, st.note = True, False, 0, ""
    try:
        with _handlers():
            try:
                code = command()
                st.committed = True          # done: a signal now changes nothing
                return code
            except KeyboardInterrupt:
                if not st.signum:            # raised without our handler (e.g. by another thread)
                    st.signum = int(signal.SIGINT)
                    _silence()
                _say(_message(st.signum))
                return 128 + st.signum
            except BaseException as e:
                if st.signum:                # the libraries' teardown after the interrupt raised
                    _say(_message(st.signum))
                    return 128 + st.signum
                if not isinstance(e, Exception):
                    raise
                if isinstance(e, (UsageError, FileNotFoundError, FMUError)):
                    _say(f"{PREFIX}: error: {e}")
                    return EXIT_USAGE
                if isinstance(e, DryFrictionWarning):
                    _say(f"{PREFIX}: error: {e} (an FMU warning, an error under --strict)")
                    return EXIT_USAGE
                if isinstance(e, BrokenPipeError):
                    # the output piped into head & co., which stopped reading: quiet, as the
                    # shell's tools (the rest of the output goes nowhere, so that the flush at exit
                    # does not raise again)
                    devnull = os.open(os.devnull, os.O_WRONLY)
                    os.dup2(devnull, sys.stdout.fileno())
                    return EXIT_BROKEN_PIPE
                if isinstance(e, OSError):
                    _say(f"{PREFIX}: error: {_os_error(e)}")
                    return EXIT_FAILED
                from ..cluster import ClusterLost

                if isinstance(e, ClusterLost):       # the Dask workers lost too often: one line
                    _say(f"{PREFIX}: error: {e}")
                    return EXIT_FAILED
                raise
    finally:
        st.active = False
        if st.console:
            st.committed = True              # the command is over: a signal now changes nothing
        else:
            _unsilence()
            st.committed, st.signum, st.note = False, 0, ""


def _os_error(e: OSError) -> str:
    """An OSError as a sentence: the cause and the file."""
    if e.strerror and e.filename:
        return f"{e.strerror}: {_short(str(e.filename))}"
    return str(e)


# ---- FMU warnings ------------------------------------------------------------------------------

#: distinct FMU warnings printed in full by one command; the rest are counted in one line at its end
MAX_WARNING_LINES = 5


@contextmanager
def fmu_warnings_on_stderr(prog: str, strict: bool) -> Iterator[None]:
    """While the block runs, an FMU warning (:class:`~dryfriction.diagnostics.DryFrictionWarning`)
    is one line on stderr, ``<prog>: warning: <the FMU's sentence>`` (each sentence once; past
    :data:`MAX_WARNING_LINES` of them, one line at the end counts the others); ``strict``: raised
    instead."""
    import warnings

    from ..diagnostics import DryFrictionWarning

    more = 0
    with warnings.catch_warnings():
        shown = warnings.showwarning
        printed = 0

        def show(message: Warning | str, category: type[Warning], filename: str, lineno: int,
                 file: Any = None, line: str | None = None) -> None:
            nonlocal printed, more
            if not issubclass(category, DryFrictionWarning):
                shown(message, category, filename, lineno, file, line)
            elif printed < MAX_WARNING_LINES:
                printed += 1
                print(f"{prog}: warning: {message}", file=sys.stderr, flush=True)
            else:
                more += 1

        warnings.showwarning = show
        warnings.simplefilter("error" if strict else "default", DryFrictionWarning)
        try:
            yield
        finally:
            if more:
                print(f"{prog}: warning: {more} more FMU warning{'s' if more > 1 else ''} like these "
                      "(--strict stops at the first)", file=sys.stderr, flush=True)


# ---- the console script ------------------------------------------------------------------------

class _StderrGate:
    """File descriptor 2 of this process, and so of every process it starts (Dask's workers, the
    multiprocessing resource tracker), goes through a pipe that a thread copies to the real stderr
    :data:`DELAY` seconds late; from the moment a SIGINT or SIGTERM arrives (seen at once through
    the signal module's wakeup fd, even while the main thread is busy in C) whatever came through
    and comes through is dropped, so that no child's traceback follows or precedes the one line.
    Python's ``sys.stderr`` of this process writes to the real stderr directly."""

    #: how long the output of the other processes is held back (a child that got the same Ctrl-C
    #: prints its traceback within milliseconds; the drop comes first)
    DELAY = 0.5

    def __init__(self) -> None:
        self.real = os.dup(2)
        r, w = os.pipe()
        os.dup2(w, 2)
        os.close(w)
        self._r = r
        self._wake_r, wake_w = os.pipe()
        os.set_blocking(wake_w, False)
        self._wake_w = wake_w
        self._old_wakeup = signal.set_wakeup_fd(wake_w, warn_on_full_buffer=False)
        self._drop = False
        self._closing = False
        self._thread = threading.Thread(target=self._pump, name="dryfriction-stderr", daemon=True)
        self._thread.start()
        enc = getattr(sys.stderr, "encoding", None) or "utf-8"
        sys.stderr = open(os.dup(self.real), "w", buffering=1, encoding=enc,  # noqa: SIM115
                          errors="backslashreplace")

    def _write(self, data: bytes) -> None:
        while data and not self._drop:
            try:
                data = data[os.write(self.real, data):]
            except OSError:
                return

    def _pump(self) -> None:
        import select
        import time

        held: list[tuple[float, bytes]] = []
        open_ = True
        while open_ or held:
            now = time.monotonic()
            timeout = None if not held else max(0.0, held[0][0] + self.DELAY - now)
            if self._closing:
                timeout = 0.0
            ready, _, _ = select.select([self._r, self._wake_r] if open_ else [self._wake_r], [], [], timeout)
            if self._wake_r in ready:
                if any(b in (int(signal.SIGINT), int(signal.SIGTERM)) for b in os.read(self._wake_r, 512)):
                    self._drop = True
            if self._r in ready:
                try:
                    data = os.read(self._r, 65536)
                except OSError:
                    data = b""
                if data:
                    held.append((time.monotonic(), data))
                else:
                    open_ = False
            if self._drop:
                held.clear()
                if not open_:
                    return
                continue
            now = time.monotonic()
            while held and (self._closing or held[0][0] + self.DELAY <= now):
                self._write(held.pop(0)[1])
            if self._closing and not ready:
                return

    def drop(self) -> None:
        self._drop = True

    def close(self) -> None:
        """fd 2 back to the real stderr; what is held is copied out now."""
        try:
            os.dup2(self.real, 2)
        except OSError:
            pass
        self._closing = True
        os.write(self._wake_w, b"\0")          # wake the pump: it flushes what it holds and ends
        self._thread.join(timeout=1.0)
        signal.set_wakeup_fd(self._old_wakeup)


def main(command: Callable[[list[str]], int] | None = None) -> NoReturn:
    """The console script ``dryfriction`` (and ``python -m dryfriction``): the signal handlers first,
    then ``command(sys.argv[1:])`` (default: the command line, :func:`dryfriction.cli.main`); exits
    with its status. After an interrupt the process ends without running the libraries' exit
    handlers (every file is in place or removed by then, the one line printed)."""
    st = _STATE
    st.console = True
    with _handlers(restore=False):
        gate = None
        try:
            from ..atomic import signals_held

            if os.name == "posix":  # (pipes in select, a pipe as the wakeup fd)
                with signals_held():   # no signal half-way (and none ever handled by the pump thread)
                    gate = st.gate = _StderrGate()
            if command is None:
                from . import main as command   # the dispatcher (dryfriction.cli.main)
            code = command(sys.argv[1:])
        except KeyboardInterrupt:            # during the imports, before the command is guarded
            if not st.signum:
                st.signum = int(signal.SIGINT)
                _silence()
            _say(_message(st.signum))
            code = 128 + st.signum
        except BaseException:
            # after the interrupt, a library's failure that it caused (a KeyboardInterrupt swallowed
            # inside an import by a bare except leaves a module half made, and the next import of it
            # fails): the interrupt is the news, as in guarded (stderr is silenced by then, so
            # Python's own report of the error would be an empty exit 1)
            if not st.signum:
                raise
            _say(_message(st.signum))
            code = 128 + st.signum
        if st.signum:
            _flush_and_exit(code)
        if gate is not None:
            gate.close()
            st.gate = None
        # the command is over: a signal from here to the end of the process changes nothing (and
        # is not left to Python's finalization, which restores the default action: death by it)
        for s in _SIGNALS:
            signal.signal(s, signal.SIG_IGN)
    raise SystemExit(code)
