"""The worst sample of a limit category, merged block by block (``planner.check.limits``
judges rows in blocks): the same worst value, row and count as one pass over every row.

The whole-file rule is ``numpy.argmax`` over the samples in row order (the first NaN if
any, else the first maximum); ``Worst.offer`` keeps a block's worst only when it is
NaN (and the kept one is not) or strictly greater, so the first occurrence wins as it
does in one pass."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from planner.check.results import LimitCheck

# (row, column) of the block's worst sample -> (value, limit, name, time_s)
Pick = Callable[[int, int], tuple[float, float, str, float]]


def first_worst(excess: np.ndarray) -> tuple[int, int, float]:
    """Row, column and rank of the first worst sample of ``excess`` (R, C), R * C > 0."""
    r, c = np.unravel_index(int(np.argmax(excess)), excess.shape)
    return int(r), int(c), float(excess[r, c])


def beats(rank: float, kept: float | None) -> bool:
    """Whether a later block's worst ``rank`` replaces the ``kept`` one (argmax's order)."""
    if kept is None:
        return True
    if math.isnan(kept):  # NaN kept: argmax would have stopped there
        return False
    return math.isnan(rank) or rank > kept


class Worst:
    """One category's count and worst sample over the blocks offered so far."""

    def __init__(self, category: str, unit: str, empty_limit: float = 0.0) -> None:
        self.category, self.unit, self.empty_limit = category, unit, empty_limit
        self.count = 0
        self._rank: float | None = None
        self._found: tuple[float, float, str, float] | None = None

    def offer(self, count: int, excess: np.ndarray, pick: Pick) -> None:
        """A block's ``count`` of violations and its samples' ranks ``excess`` (R, C);
        ``pick`` reads the worst sample's value, limit, name and time."""
        self.count += count
        if excess.size == 0:
            return
        r, c, rank = first_worst(excess)
        if beats(rank, self._rank):
            self._rank, self._found = rank, pick(r, c)

    def offer_values(self, excess: np.ndarray, value: np.ndarray, limit, tol, names,
                     times: np.ndarray) -> None:
        """``offer`` of samples that violate when their ``value`` is beyond ``limit + tol``
        (NaN, inf - inf, is no pass)."""
        if excess.size == 0:
            return
        count = int(np.count_nonzero(~(value <= limit + tol)))

        def pick(r: int, c: int) -> tuple[float, float, str, float]:
            lim = np.broadcast_to(limit, value.shape)
            return float(value[r, c]), float(lim[r, c]), names[c], float(times[r])

        self.offer(count, excess, pick)

    def result(self) -> LimitCheck:
        if self._found is None:
            return LimitCheck(self.category, 0, 0.0, self.empty_limit, "", 0.0, self.unit)
        return LimitCheck(self.category, self.count, *self._found, self.unit)
