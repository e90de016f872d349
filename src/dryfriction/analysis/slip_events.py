"""Slip events of a chain of blocks on belts, found in a sampled record (docs/burridge_knopoff.md).

A record is the blocks' positions ``x`` and velocities ``v`` [nt, n] at communication points ``t``
[nt], on belts moving at ``v_belt`` (one speed or n). Over each interval ``[t_j, t_j+1]`` block
``i`` has slipped on its belt by

    d_ij = x_i(t_j+1) - x_i(t_j) - v_belt,i (t_j+1 - t_j)          (the integral of v - v_belt)

which is exactly what a stuck block (carried by its belt) does not do. A *cell* (interval j, block
i) slides when ``|d_ij| > d_threshold`` or the relative speed ``|v - v_belt|`` exceeds
``v_threshold`` at either end of the interval (so a slip shorter than a sample interval is not
lost). A *slip event* is a connected set of sliding cells: neighbours in time (the same block in
consecutive intervals), in space (neighbouring blocks in the same interval) and, with
``diagonal=True`` (the default), both at once (a front that moves a block per interval). Per event:

- ``start``, ``stop``: the start of its first interval and the end of its last (the sample
  resolution), ``duration = stop - start``;
- ``n_blocks``: the number of distinct blocks that slipped, ``block_lo``, ``block_hi`` its extent;
- ``moment``: the sum over its cells of ``d`` (the sum over the blocks of their slip);
- ``position``: the epicentre, the mean index of the blocks sliding in its first interval;
- ``complete``: False when it touches the first or the last interval of the record (it may have
  started before or go on after; statistics should drop it).

Block indices here count from 0. The cells are kept sparse (only the sliding ones), so a long
record can be fed segment by segment (:class:`EventDetector`) without holding it whole.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

__all__ = ["SlipEvents", "EventDetector", "detect_events", "slip_cells"]


def slip_cells(t: np.ndarray, x: np.ndarray, v: np.ndarray, v_belt: float | np.ndarray,
               v_threshold: float, d_threshold: float) -> tuple[np.ndarray, np.ndarray]:
    """The sliding cells of a record: (mask [nt - 1, n] of bool, d [nt - 1, n], the slip over each
    interval). ValueError with a sentence for shapes that do not match or negative thresholds."""
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    v = np.asarray(v, dtype=float)
    if t.ndim != 1 or t.size < 2:
        raise ValueError(f"t must hold at least 2 sample times, not {t.size}")
    if x.ndim != 2 or x.shape[0] != t.size or v.shape != x.shape:
        raise ValueError(f"x and v must both have the shape [len(t), n] = [{t.size}, n], not {x.shape} and {v.shape}")
    if not np.all(np.diff(t) > 0):
        raise ValueError("t must increase strictly")
    if not (v_threshold >= 0 and d_threshold >= 0):
        raise ValueError(f"v_threshold and d_threshold must be >= 0, not {v_threshold} and {d_threshold}")
    vb = np.broadcast_to(np.asarray(v_belt, dtype=float), (x.shape[1],))
    d = np.diff(x, axis=0) - np.diff(t)[:, None] * vb[None, :]
    fast = np.abs(v - vb[None, :]) > v_threshold
    mask = (np.abs(d) > d_threshold) | fast[:-1] | fast[1:]
    return mask, d


@dataclass
class SlipEvents:
    """The events of a record (arrays of one value per event, in the order of their start)."""

    start: np.ndarray
    stop: np.ndarray
    n_blocks: np.ndarray
    moment: np.ndarray
    position: np.ndarray
    block_lo: np.ndarray
    block_hi: np.ndarray
    complete: np.ndarray
    t_first: float
    t_last: float
    n: int
    # the sliding cells (interval index j, block i, slip d, event label) for pictures
    cells: dict[str, np.ndarray] = field(default_factory=dict, repr=False)

    @property
    def duration(self) -> np.ndarray:
        """Each event's duration, s."""
        return self.stop - self.start

    @property
    def count(self) -> int:
        """The number of events."""
        return int(self.start.size)

    def select(self, keep: np.ndarray) -> "SlipEvents":
        """The events where ``keep`` is true (the cells are kept as they are)."""
        k = np.asarray(keep, dtype=bool)
        return SlipEvents(self.start[k], self.stop[k], self.n_blocks[k], self.moment[k], self.position[k],
                          self.block_lo[k], self.block_hi[k], self.complete[k], self.t_first, self.t_last,
                          self.n, self.cells)


class EventDetector:
    """Slip events of a record given segment by segment: each :meth:`feed` takes the samples
    ``t, x, v`` of the next segment, whose first sample is the last one of the previous segment
    (the record of ``ChainFMU3.record``), or a first segment. :meth:`events` labels the cells."""

    def __init__(self, v_belt: float | np.ndarray, v_threshold: float, d_threshold: float,
                 diagonal: bool = True) -> None:
        self.v_belt = v_belt
        self.v_threshold = float(v_threshold)
        self.d_threshold = float(d_threshold)
        self.diagonal = bool(diagonal)
        self._times: list[np.ndarray] = []
        self._j: list[np.ndarray] = []
        self._i: list[np.ndarray] = []
        self._d: list[np.ndarray] = []
        self._nt = 0            # samples so far
        self._last: float | None = None
        self.n: int | None = None

    def feed(self, t: np.ndarray, x: np.ndarray, v: np.ndarray) -> None:
        """Add the next segment of a record (times [nt], positions and velocities [nt, n]); it must start at
        the previous segment's last sample (ValueError otherwise)."""
        t = np.asarray(t, dtype=float)
        if self._last is not None and t[0] != self._last:
            raise ValueError(f"a segment must start at the previous segment's last sample {self._last}, not {t[0]}")
        if self.n is None:
            self.n = int(np.shape(x)[1])
        elif np.shape(x)[1] != self.n:
            raise ValueError(f"every segment must hold the same {self.n} blocks, not {np.shape(x)[1]}")
        mask, d = slip_cells(t, x, v, self.v_belt, self.v_threshold, self.d_threshold)
        j, i = np.nonzero(mask)
        offset = max(self._nt - 1, 0)
        self._j.append(j.astype(np.int64) + offset)
        self._i.append(i.astype(np.int64))
        self._d.append(d[j, i])
        self._times.append(t if self._last is None else t[1:])
        self._nt += t.size if self._last is None else t.size - 1
        self._last = float(t[-1])

    def events(self) -> SlipEvents:
        """The slip events of everything fed so far (ValueError when nothing was fed)."""
        if self.n is None:
            raise ValueError("no record was fed")
        t = np.concatenate(self._times)
        return _label(t, self.n, np.concatenate(self._j), np.concatenate(self._i), np.concatenate(self._d),
                      self.diagonal)


def detect_events(t: np.ndarray, x: np.ndarray, v: np.ndarray, v_belt: float | np.ndarray,
                  v_threshold: float, d_threshold: float, diagonal: bool = True) -> SlipEvents:
    """The slip events of a whole record (see the module's text)."""
    det = EventDetector(v_belt, v_threshold, d_threshold, diagonal)
    det.feed(t, x, v)
    return det.events()


def _label(t: np.ndarray, n: int, j: np.ndarray, i: np.ndarray, d: np.ndarray, diagonal: bool) -> SlipEvents:
    """Connected components of the sparse sliding cells (j, i) and their sums."""
    ncell = j.size
    nint = t.size - 1
    order = np.lexsort((i, j))
    j, i, d = j[order], i[order], d[order]
    key = j * n + i
    rows: list[np.ndarray] = []
    cols: list[np.ndarray] = []
    offsets = [(0, 1), (1, 0)] + ([(1, -1), (1, 1)] if diagonal else [])
    for dj, di in offsets:
        ii = i + di
        ok = (ii >= 0) & (ii < n)
        target = (j + dj) * n + ii
        pos = np.searchsorted(key, target)
        pos_c = np.minimum(pos, max(ncell - 1, 0))
        hit = ok & (pos < ncell) & (key[pos_c] == target) if ncell else ok[:0]
        rows.append(np.flatnonzero(hit))
        cols.append(pos_c[hit])
    r = np.concatenate(rows) if rows else np.zeros(0, np.int64)
    c = np.concatenate(cols) if cols else np.zeros(0, np.int64)
    if ncell:
        graph = coo_matrix((np.ones(r.size, dtype=np.int8), (r, c)), shape=(ncell, ncell))
        nev, lab = connected_components(graph, directed=False)
    else:
        nev, lab = 0, np.zeros(0, dtype=np.int64)
    # order the events by their first cell (cells are sorted by time, then block)
    first = np.full(nev, ncell, dtype=np.int64)
    np.minimum.at(first, lab, np.arange(ncell))
    rank = np.empty(nev, dtype=np.int64)
    rank[np.argsort(first, kind="stable")] = np.arange(nev)
    lab = rank[lab]
    jmin = np.full(nev, nint, dtype=np.int64)
    jmax = np.full(nev, -1, dtype=np.int64)
    np.minimum.at(jmin, lab, j)
    np.maximum.at(jmax, lab, j)
    lo = np.full(nev, n, dtype=np.int64)
    hi = np.full(nev, -1, dtype=np.int64)
    np.minimum.at(lo, lab, i)
    np.maximum.at(hi, lab, i)
    moment = np.bincount(lab, weights=d, minlength=nev)
    # distinct blocks per event
    pairs = np.unique(lab * n + i)
    n_blocks = np.bincount(pairs // n, minlength=nev)
    # epicentre: the mean block of the cells in the event's first interval
    at_first = j == jmin[lab]
    position = (np.bincount(lab[at_first], weights=i[at_first].astype(float), minlength=nev)
                / np.maximum(np.bincount(lab[at_first], minlength=nev), 1))
    complete = (jmin > 0) & (jmax < nint - 1)
    return SlipEvents(start=t[jmin], stop=t[jmax + 1], n_blocks=n_blocks, moment=moment, position=position,
                      block_lo=lo, block_hi=hi, complete=complete, t_first=float(t[0]), t_last=float(t[-1]), n=n,
                      cells={"j": j, "i": i, "d": d, "event": lab, "t": t})
