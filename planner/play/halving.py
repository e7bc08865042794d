"""Reductions along one axis of the small arrays the follow test and the body rule make,
as a few elementwise operations: numpy's ``min``/``max``/``all`` along an axis pay a
per-element overhead that elementwise operations do not (on a (14, 55, 3) array of a
follow's points, measured: a reduction along the middle axis 110-180 us, an elementwise
operation on the whole array 1-8 us), and the follow test asks them thousands of times a
song.

Each halves the axis, the pairs' minimum (maximum, and) at a time: the same numbers as
numpy's, because a minimum, a maximum and a logical and are exact whatever the order
(no NaN arises in these arrays). A sum is not (``sum3``: the left-to-right order of
numpy's own reduction of three numbers, checked to the bit in
``tests/test_halving.py``).
"""

from __future__ import annotations

import numpy as np


def _halve(x: np.ndarray, axis: int, op) -> np.ndarray:
    if axis not in (0, 1):
        raise ValueError("halving reduces the first or the second axis")
    if axis:
        x = x.swapaxes(0, 1)  # (the others keep their order)
    n = x.shape[0]
    if n == 0:
        raise ValueError("a reduction of an empty axis")
    if n == 1:
        return x[0].copy()
    while n > 1:
        h = n // 2
        y = op(x[:h], x[h:2 * h])
        if n % 2:
            y[0] = op(y[0], x[2 * h])
        x, n = y, h
    return x[0]


def min_along(x: np.ndarray, axis: int) -> np.ndarray:
    """``x.min(axis=axis)`` (exact: a minimum); ``axis`` 0 or 1, as every one here."""
    return _halve(x, axis, np.minimum)


def max_along(x: np.ndarray, axis: int) -> np.ndarray:
    """``x.max(axis=axis)`` (exact: a maximum)."""
    return _halve(x, axis, np.maximum)


def all_along(x: np.ndarray, axis: int) -> np.ndarray:
    """``x.all(axis=axis)`` of a boolean array; True along an empty axis, as numpy's."""
    if x.shape[axis] == 0:
        return np.ones(x.shape[:axis] + x.shape[axis + 1:], dtype=bool)
    return _halve(x, axis, np.logical_and)


def sum3(x: np.ndarray) -> np.ndarray:
    """``x.sum(axis=-1)`` of a last axis of three: (x0 + x1) + x2, numpy's order."""
    return (x[..., 0] + x[..., 1]) + x[..., 2]
