"""The one way files are written: to a temporary name beside the target, then renamed over it,
so that a reader (or a restarted sweep) never sees a half-written file::

    with atomic_path(path) as tmp:     # any writer that takes a path (to_netcdf, savefig, np.save)
        write(tmp)
    atomic_write_bytes(path, data)
    atomic_write_text(path, text)

The temporary name is ``.<name>.<random>.tmp`` in the same folder (so the rename is atomic); it is
removed when the writer fails. The final file gets the usual permissions (0666 minus the umask).
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

__all__ = ["atomic_path", "atomic_write_bytes", "atomic_write_text", "staged_outputs", "signals_held", "TMP_SUFFIX"]

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
