"""Time-optimal straight moves in joint space.

A move from ``q_a`` to ``q_b`` follows the straight joint-space line ``q_a + s (q_b -
q_a)`` with the path parameter ``s`` on the fastest profile the joints allow: joint j
caps ``s'`` at ``v_j / |dq_j|`` and ``s''`` at ``a_j / |dq_j|``, so the tightest joint
sets one speed cap ``V`` and one acceleration cap ``A`` for ``s``, and the time-optimal
profile under them is bang-coast-bang (a trapezoid in speed; a triangle when the move is
too short to reach ``V``). That is the shortest time along that line under the joints'
box limits, and it keeps the line, so a path checked by sampling the line stays checked.
A min-jerk profile of the same peak acceleration takes sqrt(10 / sqrt(3)) / 2 = 1.20
times as long (acceleration-limited moves), the 17 % issue 13 measured.

``LIMIT_FRACTION`` of each limit is used: a sampled trajectory whose continuous speed and
acceleration respect their limits has row differences that do too (they are averages),
and the fraction keeps float rounding well inside the check's 1 % tolerance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

LIMIT_FRACTION = 0.995


@dataclass(frozen=True)
class Move:
    """A straight joint-space move: from ``q_a`` by ``dq`` over ``duration_s``, its path
    parameter on a trapezoid with speed cap ``v`` (1/s) and acceleration cap ``a``
    (1/s^2). A move of zero length has duration 0."""

    q_a: np.ndarray
    dq: np.ndarray
    duration_s: float
    v: float
    a: float

    def s(self, t_s: np.ndarray) -> np.ndarray:
        """Path parameter in [0, 1] at times ``t_s`` after the move's start (clamped)."""
        return path_s(np.asarray(t_s, dtype=float), self.duration_s, self.v, self.a)

    def at(self, t_s) -> np.ndarray:
        """Joint positions (len(t), n) at times after the start."""
        s = self.s(np.atleast_1d(t_s))
        return self.q_a[None, :] + s[:, None] * self.dq[None, :]

    def time_at_s(self, s_target: float) -> float:
        """The time (s after the start) at which the path parameter reaches ``s_target``."""
        s_target = min(max(float(s_target), 0.0), 1.0)
        if self.duration_s == 0.0:
            return 0.0
        a, v, T = self.a, self.v, self.duration_s
        ta = min(v / a, 0.5 * T)
        vp = a * ta
        s_ta = 0.5 * a * ta * ta
        if s_target <= s_ta:
            return math.sqrt(2.0 * s_target / a)
        if s_target <= 1.0 - s_ta:
            return ta + (s_target - s_ta) / vp
        return T - math.sqrt(max(0.0, 2.0 * (1.0 - s_target) / a))


def path_s(t_s: np.ndarray, duration_s, v, a) -> np.ndarray:
    """Path parameter in [0, 1] at times ``t_s`` after the start of trapezoid moves of
    ``duration_s`` with caps ``v`` and ``a`` (clamped): element by element, one move's
    floats for every time or one move per time (``planner.play.motion`` samples a track's
    segments at once). A move of zero length is at its end (1)."""
    t = np.clip(t_s, 0.0, duration_s)
    ta = np.minimum(v / a, 0.5 * duration_s)  # end of the acceleration phase
    vp = a * ta  # the peak speed reached
    s_acc = 0.5 * a * t * t
    s_mid = 0.5 * a * ta * ta + vp * (t - ta)
    tr = duration_s - t
    s_dec = 1.0 - 0.5 * a * tr * tr
    s = np.where(t < ta, s_acc, np.where(t <= duration_s - ta, s_mid, s_dec))
    return np.where(np.equal(duration_s, 0.0), 1.0, s)


def straight_move(q_a: np.ndarray, q_b: np.ndarray, v_max: np.ndarray,
                  a_max: np.ndarray) -> Move:
    """The time-optimal straight move from ``q_a`` to ``q_b`` under per-joint speed and
    acceleration limits (any joints: a finger's, the arm's, the whole hand's)."""
    q_a = np.asarray(q_a, dtype=float)
    dq = np.asarray(q_b, dtype=float) - q_a
    caps = path_caps(dq.tolist(), np.asarray(v_max, dtype=float).tolist(),
                     np.asarray(a_max, dtype=float).tolist())
    if caps is None:
        return Move(q_a, dq, 0.0, 1.0, 1.0)
    return Move(q_a, dq, move_time_s(*caps), *caps)


def path_caps(dq: list[float], v_max: list[float], a_max: list[float]) -> tuple[float, float] | None:
    """The path parameter's speed and acceleration caps of a straight move by ``dq``
    (floats: a few joints), set by its tightest joint; None when it does not move.
    ``move_time_s(*caps)`` is its duration (the programme asks only that, for many
    moves: no ``Move`` made)."""
    v = a = math.inf
    moving = False
    for d, vj, aj in zip(dq, v_max, a_max):  # (``min`` and ``abs`` spelt out: the same
        if d:  # floats in less than half the time; a fresh process asks thousands)
            if d < 0.0:
                d = -d
            moving = True
            x = LIMIT_FRACTION * vj / d
            if x < v:  # noqa: PLR1730
                v = x
            x = LIMIT_FRACTION * aj / d
            if x < a:  # noqa: PLR1730
                a = x
    return (v, a) if moving else None


def move_times_s(dq: np.ndarray, v_max: np.ndarray, a_max: np.ndarray) -> np.ndarray:
    """``straight_move``'s durations of the moves by the rows of ``dq`` (n, joints), all
    at once and bit for bit: ``path_caps`` per row and ``move_time_s`` in the same float
    operations, element by element (``tests/test_play_profile.py`` holds them equal)."""
    d = np.abs(dq)
    moving = d != 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        v = np.where(moving, LIMIT_FRACTION * np.asarray(v_max, dtype=float) / d, math.inf)
        a = np.where(moving, LIMIT_FRACTION * np.asarray(a_max, dtype=float) / d, math.inf)
        v, a = v.min(axis=1), a.min(axis=1)
        t = np.where(v * v >= a, 2.0 / np.sqrt(a), 1.0 / v + v / a)
    return np.where(moving.any(axis=1), t, 0.0)


def move_time_s(v: float, a: float) -> float:
    """Duration of a unit move on a trapezoid with caps ``v`` and ``a`` (triangle if
    the unit distance is reached before ``v``)."""
    if v * v >= a:  # 1 <= v^2 / a: the speed cap is never reached
        return 2.0 / math.sqrt(a)
    return 1.0 / v + v / a
