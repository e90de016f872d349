"""tests/refcache.py, the references kept between runs: a kept value is the computed one; inputs that
differ in one bit, another function or another code fingerprint are other entries; without a folder
nothing is kept; a reference function of a test module is refused."""

from __future__ import annotations

import math
import pickle
from pathlib import Path

import numpy as np
import pytest

from refcache import RefCache, code_fingerprint


def test_a_kept_value_is_the_computed_one(tmp_path: Path) -> None:
    calls = []

    def compute() -> np.ndarray:
        calls.append(1)
        return np.linspace(0.0, 1.0, 7) ** 3

    cache = RefCache(tmp_path)
    a = cache.get("cube", (7,), compute)
    b = RefCache(tmp_path).get("cube", (7,), compute)  # another session: read from the folder
    assert len(calls) == 1 and a.tobytes() == b.tobytes()
    assert [p.suffix for p in tmp_path.iterdir()] == [".pkl"]


def test_inputs_one_bit_apart_are_other_entries(tmp_path: Path) -> None:
    cache = RefCache(tmp_path)
    x = np.array([0.1, 0.2])
    y = x.copy()
    y[1] = np.nextafter(y[1], 1.0)
    assert cache.key("f", (x,)) != cache.key("f", (y,))
    assert cache.key("f", (x,)) != cache.key("g", (x,))
    assert cache.call(math.hypot, 3.0, 4.0) == 5.0
    assert cache.call(math.hypot, 3.0, np.nextafter(4.0, 5.0)) != 5.0
    assert (cache.hits, cache.misses) == (0, 2)
    assert cache.call(math.hypot, 3.0, 4.0) == 5.0 and cache.hits == 1


def test_another_code_fingerprint_is_another_entry(tmp_path: Path) -> None:
    a, b = RefCache(tmp_path), RefCache(tmp_path)
    assert a.fingerprint == b.fingerprint == code_fingerprint() and len(a.fingerprint) == 64
    b.fingerprint = "0" * 64  # as after an edit of a reference's source
    assert a.key("f", (1.0,)) != b.key("f", (1.0,))
    a.get("f", (1.0,), lambda: 1.0)
    assert b.get("f", (1.0,), lambda: 2.0) == 2.0


def test_a_broken_entry_is_computed_again(tmp_path: Path) -> None:
    cache = RefCache(tmp_path)
    cache.get("f", (), lambda: [1, 2, 3])
    (entry,) = tmp_path.iterdir()
    entry.write_bytes(pickle.dumps([1, 2, 3])[:5])  # cut short
    assert cache.get("f", (), lambda: [1, 2, 3]) == [1, 2, 3] and cache.misses == 2


def test_without_a_folder_nothing_is_kept() -> None:
    cache = RefCache(None)
    calls = []
    for _ in range(2):
        cache.get("f", (), lambda: calls.append(1))
    assert len(calls) == 2 and cache.fingerprint == ""


def test_a_reference_of_a_test_module_is_refused(tmp_path: Path) -> None:
    def local() -> float:
        return 1.0

    with pytest.raises(ValueError, match="test_refcache"):
        RefCache(tmp_path).call(local)


def test_a_session_removes_the_entries_of_other_code(tmp_path: Path) -> None:
    current = RefCache(tmp_path)
    old = RefCache(tmp_path)
    old.fingerprint = "f" * 64  # an earlier version of the code, run beside it
    old.get("f", (1.0,), lambda: 1.0)
    current.get("f", (1.0,), lambda: 2.0)
    assert len(list(tmp_path.glob("*.pkl"))) == 2
    RefCache(tmp_path)  # the next session of the current code
    assert [p.name[:16] for p in tmp_path.glob("*.pkl")] == [current.fingerprint[:16]]

