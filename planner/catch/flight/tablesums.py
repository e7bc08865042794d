"""Sums over camera observations of a drag flight's table values, kept per table interval
(``livefit.LiveFit``'s drag fit: its cost per observation does not grow with their number).

A drag flight (``flight.Flight``) stores RK4 nodes every ``h`` seconds: the distance s
along the launch direction, the height z above the launch point and their rates u, w.
Between nodes n and n + 1 it interpolates by cubic Hermite: for an observation at t, with
th = t / h - n,

    s(t) = b . (S[n], S[n+1], U[n], U[n+1]),  b = (h00, h01, h h10, h h11)(th)

(h00 = 1 - 3 th^2 + 2 th^3, h01 = 3 th^2 - 2 th^3, h10 = th - 2 th^2 + th^3, h11 = th^3 -
th^2), the same for z with (Z, W). The weights b depend on the observation's time and the
table's step only, not on the flight, so any sum over the observations of s, t s, p s or s^2
(p an observed coordinate) is a sum over the intervals of the interval's nodes against the
sums of b, t b, p b and b b^T of its observations -- kept as each observation arrives. A
new flight's sums then cost a few array operations over its ~30 intervals whatever the
number of observations (500 Hz: up to ~500 of them), where evaluating it at every
observation cost ~0.1-0.3 ms.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from planner.catch.flight.path import DragNodes


class TableSums(NamedTuple):
    """Sums over the observations (times t, positions p) of the table's s and z at their
    times: s, t s, p_x s, p_y s, s^2 and z, t z, p_z z, z^2."""

    s: float
    ts: float
    pxs: float
    pys: float
    ss: float
    z: float
    tz: float
    pzz: float
    zz: float


class IntervalSums:
    """The observations so far, as their Hermite weights summed per interval of a table
    of step ``step_s`` whose node 0 is at t = 0."""

    def __init__(self, step_s: float) -> None:
        self.h = float(step_s)
        self.n_int = 0  # intervals 0 .. n_int - 1 hold observations
        self._alloc(32)

    def _alloc(self, cap: int) -> None:
        old = None if not hasattr(self, "W") else (self.W, self.M)
        self.W = np.zeros((cap, 5, 4))  # per interval: the sums of b, t b, p_x b, p_y b,
        # p_z b (one array: an observation adds one outer product to it)
        self.M = np.zeros((cap, 4, 4))  # ... and of b b^T
        if old is not None:
            k = len(old[0])
            self.W[:k], self.M[:k] = old

    def add(self, t_s: float, p: np.ndarray) -> None:
        """One observation (t >= 0) at position ``p``."""
        q = t_s / self.h
        n = math.floor(q)
        th = q - n
        th2 = th * th
        th3 = th2 * th
        b = np.array([1.0 - 3.0 * th2 + 2.0 * th3, 3.0 * th2 - 2.0 * th3,
                      self.h * (th - 2.0 * th2 + th3), self.h * (th3 - th2)])
        if n >= len(self.W):
            self._alloc(2 * (n + 1))
        px, py, pz = p.tolist()
        self.W[n] += np.outer((1.0, t_s, px, py, pz), b)
        self.M[n] += np.outer(b, b)
        self.n_int = max(self.n_int, n + 1)

    def sums(self, nodes: DragNodes) -> TableSums:
        """The sums for the table ``nodes`` (its step this one's, covering the last
        observation's interval)."""
        k, i0 = self.n_int, nodes.i0
        P, D = nodes.sz[i0:i0 + k + 1], nodes.uw[i0:i0 + k + 1]
        X = np.stack([P[:-1], P[1:], D[:-1], D[1:]], axis=-1)  # (k, (s z), 4): b's nodes
        # (1, t, p_x, p_y, p_z) x (s, z)
        (s, z), (ts, tz), (pxs, _), (pys, _), (_, pzz) = np.einsum(
            "nri,nci->rc", self.W[:k], X).tolist()
        ss, zz = np.einsum("nci,nij,ncj->c", X, self.M[:k], X).tolist()
        return TableSums(s, ts, pxs, pys, ss, z, tz, pzz, zz)
