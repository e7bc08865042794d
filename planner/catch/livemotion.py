"""The motion of a live catch (``planner.catch.session``): the hand at rest, the move to
the open pose, the arm re-aimed at every newer intercept, the fingers' closing move.

* Fingers: a min-jerk phase from the rest pose to the open one (``trajectory.Phase``;
  the open fingers are the same for every throw of a ball size) starting at ``t_move``,
  then the closing phase from ``close_start_s``: the catch planner's moves.
* Arm (rail, wrist flexion and deviation): a ``Quintic`` from the state (q, dq, ddq) it
  has at ``t0`` to the newest intercept pose, at rest, at ``t0 + duration``. The first
  one starts at rest at ``t_move`` (a min-jerk move, as the planner's) and lasts as long
  as the fingers' phase; each re-plan replaces it by one from the state of the rows
  already written, so the rows stay twice continuously differentiable and the written
  rows never change. Its duration: the longer of the old one's remaining time and the
  min-jerk duration of the change (``trajectory.phase_duration``), lengthened by
  ``GROW`` until its speed, acceleration and position stay within every arm joint's
  limits on a grid of ``VERIFY_STEP_S`` (a quintic that starts moving may overshoot);
  when none does, the old target is kept.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from planner.hand.model import HandModel
from planner.trajectory import min_jerk, phase_duration

GROW = 1.25  # a re-aim that leaves the limits is tried this much longer ...
MAX_GROW = 8  # ... up to this many times (1.25^8 ~ 6x the shortest duration)
VERIFY_STEP_S = 0.001  # the limits are verified on this grid (rows are 2-10 ms apart)


@dataclass(frozen=True)
class Quintic:
    """A move of the arm joints from (q0, v0, a0) at ``t0`` to (q1, 0, 0) at ``t0 +
    duration_s``, held there after (q(t) = q0 + v0 tau + a0 tau^2 / 2 + c3 tau^3 + c4
    tau^4 + c5 tau^5, tau = t - t0; the boundary conditions fix c3..c5)."""

    t0: float
    duration_s: float
    q0: np.ndarray
    v0: np.ndarray
    a0: np.ndarray
    q1: np.ndarray
    c: np.ndarray  # (3, k): c3, c4, c5

    @classmethod
    def between(cls, t0: float, duration_s: float, q0: np.ndarray, v0: np.ndarray,
                a0: np.ndarray, q1: np.ndarray) -> Quintic:
        D = float(duration_s)
        h = q1 - q0
        c3 = (20.0 * h - 12.0 * v0 * D - 3.0 * a0 * D * D) / (2.0 * D ** 3)
        c4 = (-30.0 * h + 16.0 * v0 * D + 3.0 * a0 * D * D) / (2.0 * D ** 4)
        c5 = (12.0 * h - 6.0 * v0 * D - a0 * D * D) / (2.0 * D ** 5)
        return cls(float(t0), D, q0, v0, a0, q1, np.stack([c3, c4, c5]))

    @classmethod
    def hold(cls, q: np.ndarray) -> Quintic:
        z = np.zeros_like(q)
        return cls(0.0, 1.0, q, z, z, q, np.zeros((3, len(q))))

    @property
    def end_s(self) -> float:
        return self.t0 + self.duration_s

    def state(self, t_s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions, speeds and accelerations (T, k) at times ``t_s`` (clamped to the move:
        q0 before it, q1 after)."""
        tau = np.clip(np.asarray(t_s, dtype=float) - self.t0, 0.0, self.duration_s)[:, None]
        c3, c4, c5 = self.c
        q = self.q0 + tau * (self.v0 + tau * (0.5 * self.a0 + tau * (c3 + tau * (c4 + tau * c5))))
        v = self.v0 + tau * (self.a0 + tau * (3 * c3 + tau * (4 * c4 + tau * 5 * c5)))
        a = self.a0 + tau * (6 * c3 + tau * (12 * c4 + tau * 20 * c5))
        after = (np.asarray(t_s) >= self.end_s)[:, None]
        return q, np.where(after, 0.0, v), np.where(after, 0.0, a)

    def state1(self, t_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``state`` at one time (k,) each, with the time's arithmetic in floats."""
        tau = min(max(t_s - self.t0, 0.0), self.duration_s)
        c3, c4, c5 = self.c
        q = self.q0 + tau * (self.v0 + tau * (0.5 * self.a0 + tau * (c3 + tau * (c4 + tau * c5))))
        if t_s >= self.end_s:
            z = np.zeros_like(q)
            return q, z, z
        v = self.v0 + tau * (self.a0 + tau * (3 * c3 + tau * (4 * c4 + tau * 5 * c5)))
        a = self.a0 + tau * (6 * c3 + tau * (12 * c4 + tau * 20 * c5))
        return q, v, a

    def positions(self, t_s: np.ndarray) -> np.ndarray:
        """``state``'s positions alone (what a row needs)."""
        tau = np.minimum(np.maximum(t_s - self.t0, 0.0), self.duration_s)[:, None]
        c3, c4, c5 = self.c
        return self.q0 + tau * (self.v0 + tau * (0.5 * self.a0 + tau * (c3 + tau * (c4 + tau * c5))))

    def within(self, lo: np.ndarray, hi: np.ndarray, v_max: np.ndarray, a_max: np.ndarray,
               step_s: float) -> bool:
        """Positions in [lo, hi], |speed| <= v_max, |acceleration| <= a_max on a grid of
        ``step_s`` over the move (both ends included)."""
        n = max(2, math.ceil(self.duration_s / step_s) + 1)
        tau = np.linspace(0.0, self.duration_s, n)[:, None]
        c3, c4, c5 = self.c
        a = self.a0 + tau * (6 * c3 + tau * (12 * c4 + tau * 20 * c5))
        if np.any(np.abs(a) > a_max):
            return False
        v = self.v0 + tau * (self.a0 + tau * (3 * c3 + tau * (4 * c4 + tau * 5 * c5)))
        if np.any(np.abs(v) > v_max):
            return False
        q = self.q0 + tau * (self.v0 + tau * (0.5 * self.a0 + tau * (c3 + tau * (c4 + tau * c5))))
        return bool(np.all(q >= lo - 1e-12) and np.all(q <= hi + 1e-12))


class LiveMotion:
    """The rows' motion: rest, the fingers' phases, the arm's newest ``Quintic``."""

    def __init__(self, hand: HandModel, arm: tuple[int, ...], q_rest: np.ndarray,
                 q_open_fingers: np.ndarray, q_closed_fingers: np.ndarray) -> None:
        self.hand = hand
        self.arm = np.array(arm, dtype=int)
        self.q_rest = q_rest.copy()
        fingers = np.setdiff1d(np.arange(hand.n), self.arm)
        self._open = np.zeros(hand.n)
        self._open[fingers] = (q_open_fingers - q_rest)[fingers]
        self._close = np.zeros(hand.n)
        self._close[fingers] = (q_closed_fingers - q_open_fingers)[fingers]
        self._lo, self._hi = hand.lower[self.arm], hand.upper[self.arm]
        self._v, self._a = hand.velocity[self.arm], hand.acceleration[self.arm]
        self.seg = Quintic.hold(q_rest[self.arm])
        self.t_move = math.inf
        self.open_s = 0.0
        self.close_start_s = math.inf
        self.close_s = 0.0

    @property
    def moving(self) -> bool:
        return math.isfinite(self.t_move)

    @property
    def fingers_open_s(self) -> float:
        """When the fingers reach the open pose (inf before the move is planned)."""
        return self.t_move + self.open_s

    def start(self, t_s: float, q_open: np.ndarray, duration_s: float) -> None:
        """The move to the open pose ``q_open`` from ``t_s``, lasting ``duration_s``."""
        self.t_move, self.open_s = float(t_s), float(duration_s)
        q0 = self.q_rest[self.arm]
        z = np.zeros_like(q0)
        self.seg = Quintic.between(t_s, duration_s, q0, z, z, q_open[self.arm].copy())

    def set_closing(self, start_s: float, duration_s: float) -> None:
        self.close_start_s, self.close_s = float(start_s), float(duration_s)

    def reaim(self, t_s: float, q_target: np.ndarray) -> bool:
        """The arm re-aimed at ``q_target``'s arm joints from its state at ``t_s``: the
        shortest quintic (see the module docstring) within the limits; False (the old
        target kept) when none is."""
        q1 = q_target[self.arm]
        if np.array_equal(q1, self.seg.q1):
            return True
        q, v, a = self.seg.state1(t_s)
        D = max(self.seg.end_s - t_s,
                phase_duration(q1 - q, self._v, self._a) if np.any(q1 != q) else 0.0)
        D = max(D, VERIFY_STEP_S)
        for _ in range(MAX_GROW + 1):
            seg = Quintic.between(t_s, D, q, v, a, q1)
            if seg.within(self._lo, self._hi, self._v, self._a, VERIFY_STEP_S):
                self.seg = seg
                return True
            D *= GROW
        return False

    def rows(self, t_s: np.ndarray, seg: Quintic | None = None, t_new_s: float = math.inf
             ) -> np.ndarray:
        """Joint positions at times ``t_s`` (couplings applied): the fingers' phases
        (``trajectory.sample``'s sum, on the finger joints) and the arm on ``seg`` (the arm's
        move to use instead of the newest) up to ``t_new_s``, on the newest after it."""
        Q = self.q_rest + min_jerk((t_s - self.t_move) / (self.open_s or 1.0))[:, None] * self._open
        Q += min_jerk((t_s - self.close_start_s) / (self.close_s or 1.0))[:, None] * self._close
        arm = self.seg.positions(t_s)
        if seg is not None:
            old = t_s <= t_new_s
            if old.any():
                arm[old] = seg.positions(t_s[old])
        Q[:, self.arm] = arm
        return self.hand.apply_couplings(Q)
