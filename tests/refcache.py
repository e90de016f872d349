"""The slow pure-Python references, computed once and kept on disk between pytest runs.

scripts/test.sh runs the suite twice in one job (then again under ASan/UBSan, every test that runs
C): a reference that does not depend on the FMU (the event-driven references, the 40-digit
ones) is the same number both times. :class:`RefCache` keeps each result in the pytest cache
directory (``.pytest_cache/d/dfo-references/``), under a key that is the SHA-256 of

* the reference's name and its inputs, pickled (every bit of every float and array: two inputs that
  differ anywhere have different keys);
* the source of every Python file a reference can run: ``src/dryfriction/**/*.py`` and the tests'
  helper modules (``tests/*.py`` but the ``test_*.py`` and ``conftest.py`` files), and the versions
  of Python, numpy, scipy and mpmath, so that a change of the code or of a library computes the
  reference again.

What is compared with the reference (the FMU's or the C driver's run) is computed by every test
every time: only the reference is reused. Without the cache (``-p no:cacheprovider``) every
reference is computed. Entries are written whole (a temporary file renamed), so two xdist workers
may share the folder; a session removes the entries of other code (another fingerprint)."""

from __future__ import annotations

import hashlib
import os
import pickle
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

T = TypeVar("T")
ROOT = Path(__file__).resolve().parents[1]


def code_fingerprint() -> str:
    """The SHA-256 of the Python sources a reference may run and of the libraries' versions."""
    h = hashlib.sha256()
    files = sorted((ROOT / "src" / "dryfriction").rglob("*.py"))
    files += sorted(p for p in (ROOT / "tests").glob("*.py")
                    if not p.name.startswith("test_") and p.name != "conftest.py")
    for p in files:
        h.update(p.relative_to(ROOT).as_posix().encode() + b"\0" + p.read_bytes() + b"\0")
    versions = [sys.version]
    for mod in ("numpy", "scipy", "mpmath"):
        try:
            versions.append(f"{mod} {__import__(mod).__version__}")
        except ImportError:
            versions.append(f"{mod} none")
    h.update("\n".join(versions).encode())
    return h.hexdigest()


class RefCache:
    """References kept in a folder (None: computed every time), keyed by their inputs and the code."""

    def __init__(self, folder: Path | None) -> None:
        self.folder = folder
        self.fingerprint = code_fingerprint() if folder is not None else ""
        self.hits = 0
        self.misses = 0
        if folder is not None:  # the entries of other code can never be read again: removed
            for old in folder.glob("*.pkl"):
                if not old.name.startswith(self.fingerprint[:16] + "-"):
                    old.unlink(missing_ok=True)

    def key(self, name: str, inputs: Any) -> str:
        """The file name of a reference: the code's fingerprint (its start), the reference's name and
        the SHA-256 of its inputs and the code."""
        h = hashlib.sha256(self.fingerprint.encode())
        h.update(pickle.dumps((name, inputs), protocol=4))
        safe = "".join(c if c.isalnum() or c in "-_" else "_" for c in name)[:40]
        return f"{self.fingerprint[:16]}-{safe}-{h.hexdigest()[:32]}.pkl"

    def get(self, name: str, inputs: Any, compute: Callable[[], T]) -> T:
        """The reference `name` of these inputs: read from the folder, or computed by compute() (which
        must depend on nothing but the inputs and the code) and stored."""
        if self.folder is None:
            return compute()
        path = self.folder / self.key(name, inputs)
        try:
            with open(path, "rb") as f:
                value = pickle.load(f)
            self.hits += 1
            return value
        except (OSError, EOFError, pickle.UnpicklingError, AttributeError, ImportError):
            pass
        value = compute()
        self.misses += 1
        fd, tmp = tempfile.mkstemp(dir=self.folder, suffix=".tmp")
        try:
            with os.fdopen(fd, "wb") as f:
                pickle.dump(value, f, protocol=4)
            os.replace(tmp, path)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
        return value

    def call(self, fn: Callable[..., T], *args: Any, **kwargs: Any) -> T:
        """fn(*args, **kwargs), kept under fn's module and name and its arguments (fn: a module-level
        function of the references, whose result depends on its arguments and the code alone)."""
        if fn.__module__.startswith(("test_", "conftest")):  # not in the key's fingerprint
            raise ValueError(f"refcache.call: {fn.__qualname__} is defined in {fn.__module__}; a kept reference "
                             "must be a function of src/dryfriction or of a helper module of tests/")
        return self.get(f"{fn.__module__}.{fn.__qualname__}", (args, sorted(kwargs.items())),
                        lambda: fn(*args, **kwargs))
