"""The one way files are written: to a temporary name beside the target, then renamed over it,
so that a reader (or a restarted sweep) never sees a half-written file::

    with atomic_path(path) as tmp:     # any writer that takes a path (to_netcdf, savefig, np.save)
        write(tmp)
    atomic_write_bytes(path, data)
    atomic_write_text(path, text)

The temporary name is ``.<name>.<random>.tmp`` in the same folder (so the rename is atomic); it is
removed when the writer fails. The final file gets the usual permissions (0666 minus the umask).

A command's outputs, all or nothing, with the output paths checked before any work::

    check_output_folder(out)           # before the work: a path that cannot be written is refused
    with result_set(out) as stage:     # the files written into stage move into out together
        write(stage / "table.csv")

When a result set is complete it commits the running command (:data:`COMMAND`, :func:`committed`):
from then on the command line's signal handling (:mod:`dryfriction.cli.console`) lets it finish.
"""

from __future__ import annotations

import errno
import os
import tempfile
from collections.abc import Callable, Iterator
from contextlib import AbstractContextManager, contextmanager
from pathlib import Path
from typing import IO, Any

from .errors import UsageError

__all__ = ["atomic_path", "atomic_write_bytes", "atomic_write_text", "staged_outputs", "signals_held", "TMP_SUFFIX",
           "COMMAND", "Command", "committed", "interrupted", "interrupt_note", "result_set", "result_file",
           "check_output_folder", "check_output_file", "nearest_existing", "OutputError", "short_text"]

TMP_SUFFIX = ".tmp"


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """A temporary path beside ``path``; renamed to ``path`` when the block ends without error,
    removed otherwise. The parent folder is created if missing."""
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, name = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.", suffix=TMP_SUFFIX)
    os.close(fd)
    tmp = Path(name)
    try:
        yield tmp
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, target)
    finally:
        tmp.unlink(missing_ok=True)


def atomic_write_bytes(path: str | os.PathLike[str], data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically (a temporary file beside it, then a rename); returns the path."""
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def atomic_write_text(path: str | os.PathLike[str], text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically; returns the path."""
    return atomic_write_bytes(path, text.encode())


@contextmanager
def signals_held() -> Iterator[None]:
    """SIGINT and SIGTERM held (blocked) while the block runs, in the main thread; one that arrives
    meanwhile is delivered when the block ends (as KeyboardInterrupt for SIGINT). Elsewhere than in
    the main thread, or where signals cannot be blocked, the block runs as is."""
    import signal
    import threading

    mask = {signal.SIGINT, signal.SIGTERM}
    if threading.current_thread() is not threading.main_thread() or not hasattr(signal, "pthread_sigmask"):
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, mask)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


@contextmanager
def staged_outputs(folder: str | os.PathLike[str]) -> Iterator[Path]:
    """A command's result set, all or nothing: yields an empty staging folder beside ``folder``
    (same file system); when the block ends without error every file written into it is moved into
    ``folder`` (created if missing: then the staging folder itself is renamed, one step), with
    SIGINT and SIGTERM held until the last one is in place. On an error or an interrupt inside the
    block the staging folder is removed and ``folder`` is left exactly as it was::

        with staged_outputs(out) as stage:
            write_csv(stage / "response.csv"); write_png(stage / "response.png")
        # here every file is in out/, or (on an exception) none of them
    """
    import shutil

    target = Path(folder)
    target.parent.mkdir(parents=True, exist_ok=True)
    stage = Path(tempfile.mkdtemp(dir=target.parent, prefix=f".{target.name or 'out'}.staging-"))
    try:
        yield stage
        mode = 0o777 & ~_umask()
        with signals_held():
            if not target.exists():
                os.chmod(stage, mode)
                os.replace(stage, target)
                return
            files = sorted(p for p in stage.rglob("*") if not p.is_dir())
            for src in files:
                dst = target / src.relative_to(stage)
                dst.parent.mkdir(parents=True, exist_ok=True)
                os.replace(src, dst)
    finally:
        shutil.rmtree(stage, ignore_errors=True)


# ---- the running command and its result sets --------------------------------------------------

class Command:
    """The command that runs in this process, as its result sets and the command line's signal
    handling (:mod:`dryfriction.cli.console`) share it."""

    def __init__(self) -> None:
        self.active = False          # a guarded command runs (its handlers are installed)
        self.console = False         # we are the console script (a second signal exits at once)
        self.committed = False       # the results are complete and being put in place
        self.signum = 0              # the signal that interrupted the command (0: none)
        self.note = ""               # said after "interrupted" (e.g. the study's chunks are kept)
        self.stderr: IO[str] | None = None   # the real stderr while library output is silenced
        self.gate: Any = None               # the console script's stderr gate


#: the one running command of the process
COMMAND = Command()


def committed() -> None:
    """The running command's results are complete: from here on a signal no longer interrupts it
    (called by :func:`result_set` and :func:`result_file` just before the files move into place;
    without a guarded command it does nothing that matters)."""
    COMMAND.committed = True


def interrupted() -> bool:
    """Whether the running command has been interrupted (a signal arrived before its results
    were committed)."""
    return bool(COMMAND.signum)


def interrupt_note(text: str) -> None:
    """Said after ``interrupted`` if the running command is interrupted (e.g. that a study's
    finished chunks are kept)."""
    COMMAND.note = text


def short_text(text: str, limit: int = 240) -> str:
    """``text`` whole up to ``limit`` characters (every ordinary path), else its two ends and its
    length (a name too long to be one, shown readably)."""
    return text if len(text) <= limit else f"{text[:limit // 2]}...{text[-limit // 3:]} ({len(text)} characters)"


class OutputError(OSError):
    """A result set (or file) that could not be written, with the cause; nothing of it was kept
    (the command line: one line, exit status 1)."""


@contextmanager
def _all_or_nothing(writer: Callable[[Any], Any], target: str | os.PathLike[str], kept: str) -> Iterator[Path]:
    """``writer(target)``'s temporary place, the command committed when the block ends without
    error; a write the system refuses is :class:`OutputError` naming ``target``, the cause and
    ``kept`` (what is left)."""
    try:
        with writer(target) as place:
            yield place
            committed()
    except OSError as e:
        if interrupted():
            raise
        raise OutputError(f"cannot write {short_text(str(target))}: {_cause(e)}; {kept}") from None


def result_set(folder: str | os.PathLike[str]) -> AbstractContextManager[Path]:
    """A command's result set in ``folder``, all or nothing: yields the staging folder to write
    the files into (:func:`dryfriction.atomic.staged_outputs`); when the block ends without error
    the command is committed (:func:`committed`) and every file moves into ``folder``. The paths of
    the files in ``folder`` are ``folder / path.relative_to(stage)``."""
    return _all_or_nothing(staged_outputs, folder, "nothing of it was kept")


def result_file(path: str | os.PathLike[str]) -> AbstractContextManager[Path]:
    """One result file, all or nothing: yields a temporary path beside ``path``
    (:func:`dryfriction.atomic.atomic_path`), renamed to ``path`` when the block ends without
    error, the command committed (:func:`committed`) just before."""
    return _all_or_nothing(atomic_path, path, "it was left as it was")


def nearest_existing(path: Path) -> Path:
    """``path`` or its nearest parent that exists."""
    p = path
    while not os.path.lexists(p) and p != p.parent:
        p = p.parent
    return p


def _check_names(path: Path, option: str, extra: int) -> None:
    """Every component of ``path`` (the last one ``extra`` bytes longer: the staging name) and
    the whole path within the file system's limits, else UsageError naming the option."""
    base = nearest_existing(path.absolute().parent)
    try:
        name_max = os.pathconf(base, "PC_NAME_MAX")
        path_max = os.pathconf(base, "PC_PATH_MAX")
    except (OSError, ValueError, AttributeError):  # (no pathconf on Windows)
        name_max, path_max = 255, 4096
    parts = path.absolute().parts
    for i, part in enumerate(parts):
        limit = name_max - (extra if i == len(parts) - 1 else 0)
        if len(os.fsencode(part)) > limit:
            raise UsageError(f"{option} {short_text(str(path), 60)}: the name {short_text(part, 40)!r} is "
                             f"{len(os.fsencode(part))} bytes long, more than the {limit} it may have here "
                             f"({name_max} per name on this file system"
                             + (", less the temporary name's suffix)" if limit < name_max else ")"))
    if len(os.fsencode(str(path.absolute()))) + extra + 64 > path_max:
        raise UsageError(f"{option} {short_text(str(path), 60)}: the path is too long for this file system "
                         f"(at most {path_max - extra - 64} bytes here)")


def _cause(e: OSError) -> str:
    """The cause of an OSError in a few words."""
    return {errno.EACCES: "permission denied", errno.EPERM: "permission denied",
            errno.EROFS: "a read-only file system", errno.ENOSPC: "no space left on the device",
            errno.EDQUOT: "the disk quota is exceeded", errno.ENAMETOOLONG: "a name too long",
            errno.ENOTDIR: "not a folder"}.get(e.errno or 0, e.strerror or str(e))


def _probe_error(option: str, path: Path, where: Path, e: OSError) -> Exception:
    return UsageError(f"{option} {short_text(str(path))}: cannot write in {short_text(str(where))} ({_cause(e)})")


def check_output_folder(folder: str | os.PathLike[str], option: str = "--out") -> Path:
    """Refuse (UsageError, one line naming ``option``) a result folder the command could not
    write, before any work: a file where the folder is meant, a name too long, a place not
    writable (a probe created and removed where :func:`result_set` will stage; an existing folder
    asked whether it may be written). Nothing is left behind; a missing folder is not created."""
    import shutil
    import tempfile

    path = Path(folder)
    if str(folder) == "":
        raise UsageError(f"{option} must name a folder, not ''")
    _check_names(path, option, extra=len(".staging-") + 9)
    if path.exists() and not path.is_dir():
        raise UsageError(f"{option} {short_text(str(path))} is a file, not a folder")
    parent = path.parent
    where = nearest_existing(parent)
    if not where.is_dir():
        raise UsageError(f"{option} {short_text(str(path))}: {short_text(str(where))} is a file, not a folder")
    try:
        probe = tempfile.mkdtemp(dir=where, prefix=f".{path.name or 'out'}.staging-")
    except OSError as e:
        raise _probe_error(option, path, where, e) from None
    shutil.rmtree(probe, ignore_errors=True)
    if path.is_dir() and not os.access(path, os.W_OK | os.X_OK):  # (the folder itself left untouched)
        raise UsageError(f"{option} {short_text(str(path))}: cannot write in it (permission denied)")
    return path


def check_output_file(file: str | os.PathLike[str], option: str = "--out") -> Path:
    """As :func:`check_output_folder` for one result file (:func:`result_file`): a folder where
    the file is meant, a name too long, a place not writable are refused before any work."""
    import tempfile

    path = Path(file)
    if str(file) == "" or path.name in ("", ".", ".."):
        raise UsageError(f"{option} must name a file, not {str(file)!r}")
    _check_names(path, option, extra=len("..") + 8 + len(".tmp"))
    if path.is_dir():
        raise UsageError(f"{option} {short_text(str(path))} is a folder, not a file")
    where = nearest_existing(path.parent)
    if not where.is_dir():
        raise UsageError(f"{option} {short_text(str(path))}: {short_text(str(where))} is a file, not a folder")
    try:
        fd, probe = tempfile.mkstemp(dir=where, prefix=f".{path.name}.", suffix=".tmp")
    except OSError as e:
        raise _probe_error(option, path, where, e) from None
    os.close(fd)
    os.unlink(probe)
    return path
