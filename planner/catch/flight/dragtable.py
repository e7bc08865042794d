"""The RK4 table of a drag flight (``flight.Flight``): fixed-step RK4 nodes of the planar
state (s, z, ds/dt, dz/dt) -- s the horizontal distance along the launch direction, z the
height, both from the launch point -- grown on demand, and the cubic Hermite
interpolation between nodes (positions with the stored rates, rates with the
accelerations). Its step, the accuracy it buys and how a flight uses it: the module
docstring of ``planner.catch.flight.path``."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from planner.errors import InputError

G_M_S2 = 9.81
"""Gravity, m/s^2 (down, along -z)."""
_MAX_STEP = 0.01  # s, coarsest RK4 step of a drag table
_STEP_SCALE = 0.005  # step <= _STEP_SCALE / (k * speed scale)


def step_for(k: float, speed: float) -> float:
    """RK4 step for a drag flight: small against the drag time 1/(k v)."""
    scale = max(speed, math.sqrt(G_M_S2 / k))
    return min(_MAX_STEP, _STEP_SCALE / (k * scale))


def rk4_run(S, Z, U, W, k, h, n_steps, s_stop=math.inf, z_floor=-math.inf):
    """Append up to ``n_steps`` RK4 steps of size ``h`` (may be < 0) to the lists.

    State (s, z, u, w) = horizontal distance, height and their rates;
    du/dt = -k|v|u, dw/dt = -g - k|v|w. Stops after the step where s >= s_stop,
    or where the ball descends below z_floor (it never climbs back: w < 0 stays < 0).
    """
    g = G_M_S2
    s, z, u, w = S[-1], Z[-1], U[-1], W[-1]
    h2 = 0.5 * h
    h6 = h / 6.0
    sqrt = math.sqrt
    for _ in range(n_steps):
        sp = sqrt(u * u + w * w)
        a1u = -k * sp * u
        a1w = -g - k * sp * w
        u2 = u + h2 * a1u
        w2 = w + h2 * a1w
        sp = sqrt(u2 * u2 + w2 * w2)
        a2u = -k * sp * u2
        a2w = -g - k * sp * w2
        u3 = u + h2 * a2u
        w3 = w + h2 * a2w
        sp = sqrt(u3 * u3 + w3 * w3)
        a3u = -k * sp * u3
        a3w = -g - k * sp * w3
        u4 = u + h * a3u
        w4 = w + h * a3w
        sp = sqrt(u4 * u4 + w4 * w4)
        a4u = -k * sp * u4
        a4w = -g - k * sp * w4
        s += h6 * (u + 2.0 * (u2 + u3) + u4)
        z += h6 * (w + 2.0 * (w2 + w3) + w4)
        u += h6 * (a1u + 2.0 * (a2u + a3u) + a4u)
        w += h6 * (a1w + 2.0 * (a2w + a3w) + a4w)
        S.append(s)
        Z.append(z)
        U.append(u)
        W.append(w)
        if s >= s_stop or (z < z_floor and w < 0.0):
            break


def hermite(y0: float, y1: float, d0: float, d1: float, h: float, th: float) -> float:
    """Cubic Hermite on one step: values y0, y1, derivatives d0, d1, fraction th."""
    m0 = h * d0
    m1 = h * d1
    dy = y1 - y0
    return y0 + th * (m0 + th * ((3.0 * dy - 2.0 * m0 - m1) + th * (m0 + m1 - 2.0 * dy)))


def cross_fraction(s0: float, s1: float, u0: float, u1: float, h: float, target: float) -> float:
    """Fraction th in [0, 1] of the step where the Hermite s(th) equals ``target``."""
    m0 = h * u0
    m1 = h * u1
    ds = s1 - s0
    c2 = 3.0 * ds - 2.0 * m0 - m1
    c3 = m0 + m1 - 2.0 * ds
    r = target - s0
    th = r / ds if ds > 0 else 0.0
    th = min(1.0, max(0.0, th))
    for _ in range(30):
        f = th * (m0 + th * (c2 + th * c3)) - r
        df = m0 + th * (2.0 * c2 + 3.0 * th * c3)
        if df <= 0:
            break
        step = f / df
        th = min(1.0, max(0.0, th - step))
        if abs(step) <= 1e-15:
            break
    return th


class RK4Table:
    """RK4 nodes of a drag flight at t = i h (i in [-len(bwd)+1, len(fwd)-1]), grown on demand."""

    def __init__(self, u0: float, w0: float, k: float, h: float) -> None:
        self.k = k
        self.h = h
        self.fwd = ([0.0], [0.0], [u0], [w0])
        self.bwd = ([0.0], [0.0], [u0], [w0])
        self._arrays: tuple | None = None
        self._lists: tuple | None = None
        self._pairs: tuple | None = None

    def _grow(self, lists: tuple, h: float, n: int) -> None:
        n0 = len(lists[0])
        rk4_run(*lists, self.k, h, n)
        last = (lists[0][-1], lists[1][-1], lists[2][-1], lists[3][-1])
        if not all(map(math.isfinite, last)) or math.hypot(last[2], last[3]) > 1e6:
            t_end = h * (len(lists[0]) - 1)
            for col in lists:  # keep the table as it was
                del col[n0:]
            raise InputError(
                f"the drag flight cannot be integrated to t = {t_end:.3g} s (its speed "
                "diverges going back in time); ask for later times"
            )
        self._arrays = self._lists = self._pairs = None

    def ensure(self, t_lo: float, t_hi: float) -> None:
        """Integrate until the nodes bracket [t_lo, t_hi]."""
        h = self.h
        need = math.ceil(t_hi / h) + 1 - (len(self.fwd[0]) - 1)
        if need > 0:
            self._grow(self.fwd, h, max(need, len(self.fwd[0]) // 2))
        need = math.ceil(-t_lo / h) + 1 - (len(self.bwd[0]) - 1)
        if need > 0 and t_lo < 0.0:  # (t >= 0 is looked up on the forward nodes)
            self._grow(self.bwd, -h, max(need, len(self.bwd[0]) // 2))

    def arrays(self) -> tuple:
        """(i_lo, S, Z, U, W, AS, AW) as numpy arrays over all nodes."""
        if self._arrays is None:
            cols = []
            for f, b in zip(self.fwd, self.bwd):
                cols.append(np.array(b[:0:-1] + f, dtype=float))
            S, Z, U, W = cols
            sp = np.hypot(U, W)
            AS = -self.k * sp * U
            AW = -G_M_S2 - self.k * sp * W
            self._arrays = (-(len(self.bwd[0]) - 1), S, Z, U, W, AS, AW)
        return self._arrays

    def pairs(self) -> tuple:
        """``arrays`` as (i_lo, [S Z], [U W], [AS AW]) (n, 2) each: s and z interpolated
        together."""
        if self._pairs is None:
            i_lo, S, Z, U, W, AS, AW = self.arrays()
            self._pairs = (i_lo, np.column_stack([S, Z]), np.column_stack([U, W]),
                           np.column_stack([AS, AW]))
        return self._pairs

    def lists(self) -> tuple:
        """``arrays`` as Python lists (the same numbers), for one time at a time."""
        if self._lists is None:
            i_lo, *cols = self.arrays()
            self._lists = (i_lo, *(c.tolist() for c in cols))
            # the times ``ensure`` leaves as they are (each bound a node short of the ends)
            self._covered = ((i_lo + 1) * self.h, (len(cols[0]) + i_lo - 2) * self.h)
        return self._lists

    def node1(self, t: float) -> tuple:
        """``Flight._lookup`` for one time: (j, th, lists) with plain floats."""
        lists = self._lists
        if lists is None or not self._covered[0] <= t <= self._covered[1]:
            self.ensure(t, t)
            lists = self.lists()
        q = t / self.h - lists[0]
        j = min(max(math.floor(q), 0), len(lists[1]) - 2)
        return j, q - j, lists


def hermite_np(y0, y1, d0, d1, h, th):
    m0 = h * d0
    m1 = h * d1
    dy = y1 - y0
    return y0 + th * (m0 + th * ((3.0 * dy - 2.0 * m0 - m1) + th * (m0 + m1 - 2.0 * dy)))


class DragNodes(NamedTuple):
    """A drag flight's RK4 table (``Flight.nodes``): its step, the array index of the node
    at t = 0, per node (s, z) (along the launch direction and up, from p0) and their rates
    (u, w), (n, 2) each, and the launch direction's horizontal unit vector (ex, ey)."""

    step_s: float
    i0: int
    sz: np.ndarray
    uw: np.ndarray
    direction: tuple[float, float]
