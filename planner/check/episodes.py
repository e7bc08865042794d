"""Key-down episodes found block by block: contiguous runs of True in each key column of
a (rows, 88) mask given in blocks of rows (``EpisodeStream``), the same runs as one pass
over every row (``planner.check.keys.key_episodes`` is one block of it); and a (rows,
88) bool mask kept in eight times less memory (``PackedRows``: what a note's frames need
at the end of a replay streamed block by block)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from planner.check.worst import beats


@dataclass(frozen=True, slots=True)
class Run:
    """One run of a key: its key index, first row (its index and time), the time its
    last row ends (the next row's time; one frame period past the last row at the end),
    the tags seen in it (the fingers, ascending), and the largest ``value`` in it with its tag at
    that row (the first of equal ones; None without values)."""

    key: int
    start_s: float
    start_row: int
    end_s: float
    tags: tuple[int, ...]
    best: float | None
    best_tag: int | None


class EpisodeStream:
    """The runs of a mask given block by block, in order (``add``), then ``finish``;
    ``keep`` False: only their number (``count``)."""

    def __init__(self, n_keys: int, keep: bool = True) -> None:
        self._open: dict[int, list] = {}  # key -> [start_s, start_row, tags, best, best_tag]
        self._done: list[Run] = []
        self._keep = keep
        self.count = 0
        self._n_keys = n_keys
        self._rows = 0
        self._t_last = 0.0

    def add(self, mask: np.ndarray, t_s: np.ndarray, tag: np.ndarray | None = None,
            value: np.ndarray | None = None) -> None:
        """A block of rows: ``mask`` (n, K) bool, their times, ``tag`` (n, K) int (-1: none)
        collected per run, ``value`` (n, K) whose largest per run is kept with its tag."""
        m = np.asarray(mask, dtype=bool)
        n = len(m)
        if n == 0:
            return
        prev = np.zeros((1, m.shape[1]), dtype=bool)
        prev[0, list(self._open)] = True
        edges = np.diff(np.vstack([prev, m]).astype(np.int8), axis=0)
        for k in np.flatnonzero(m.any(axis=0) | prev[0]):
            starts = ([0] if prev[0, k] else []) + np.flatnonzero(edges[:, k] == 1).tolist()
            stops = np.flatnonzero(edges[:, k] == -1).tolist() + ([n] if m[-1, k] else [])
            for a, b in zip(starts, stops):
                run = self._open.pop(int(k), None) if a == 0 and prev[0, k] else None
                if run is None:
                    run = [float(t_s[a]), self._rows + a, set(), None, None]
                self._extend(run, k, a, b, tag, value)
                if b < n:
                    self._close(int(k), run, float(t_s[b]))
                else:
                    self._open[int(k)] = run
        self._rows += n
        self._t_last = float(t_s[-1])

    @staticmethod
    def _extend(run: list, k: int, a: int, b: int, tag, value) -> None:
        if b <= a:  # (a run that ended with the block before)
            return
        if tag is not None:
            tags = tag[a:b, k]
            run[2].update(tags[tags >= 0].tolist())
        if value is not None:
            i = int(np.argmax(value[a:b, k]))
            if beats(float(value[a + i, k]), run[3]):
                run[3] = float(value[a + i, k])
                run[4] = None if tag is None else int(tag[a + i, k])

    def _close(self, k: int, run: list, end_s: float) -> None:
        self.count += 1
        if self._keep:
            self._done.append(Run(k, run[0], run[1], end_s, tuple(sorted(run[2])), run[3],
                                  run[4]))

    def finish(self, period_s: float) -> list[Run]:
        """Every run, the open ones ended ``period_s`` after the last row, by start time
        then key."""
        for k, run in sorted(self._open.items()):
            self._close(k, run, self._t_last + period_s)
        self._open = {}
        return sorted(self._done, key=lambda r: (r.start_s, r.key))


class PackedRows:
    """A (rows, K) bool mask kept as bits, given block by block (``add``); read as
    ``rows[a:b, k]`` (a bool column), rows past those given being False up to ``total``
    (frames of a song after the rows)."""

    def __init__(self, n_keys: int, total: int) -> None:
        self._k = n_keys
        self._blocks: list[np.ndarray] = []
        self._packed: np.ndarray | None = None
        self._total = total

    def add(self, mask: np.ndarray) -> None:
        self._blocks.append(np.packbits(np.asarray(mask, dtype=bool), axis=1))

    def __getitem__(self, index: tuple[slice, int]) -> np.ndarray:
        rows, k = index
        if self._packed is None:
            self._packed = (np.concatenate(self._blocks) if self._blocks
                            else np.zeros((0, (self._k + 7) // 8), dtype=np.uint8))
            self._blocks = []
        a, b, _ = rows.indices(self._total)
        have = self._packed[a:min(b, len(self._packed))]
        col = np.unpackbits(have[:, k // 8:k // 8 + 1], axis=1)[:, k % 8]  # (packbits: first column high)
        out = np.zeros(max(b - a, 0), dtype=bool)
        out[:len(col)] = col.astype(bool)
        return out
