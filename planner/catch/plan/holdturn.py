"""The wrist's turn that holds the caught ball (``planner.catch.plan.api``, step 4): once the
grasp is made the wrist turns the closed hand (``hold_turn``: flexion alone, within its
range, every motor within ``TURN_SHARE``) until the palm faces up with its downhill
``HOLD_TILT_DEG`` towards the fingers: the ball rolls into the closed fingers and the palm
carries its weight (``docs/history/physics-replay.md``, "Catch")."""

from __future__ import annotations

import math

import numpy as np

from planner.catch.plan.stopping import StopDynamics
from planner.hand.model import HandModel
from planner.trajectory import LIMIT_MARGIN

HOLD_TILT_DEG = 5.0  # the held palm's downhill: this far from level towards the fingers
# (a ball on it rolls at 5/7 g sin 5 deg = 0.6 m/s^2 into the closed fingers). Measured
# (bench_simulate.py --catch-grid, held of 25): 0 -> 21, 5 -> 23, 10 -> 23


TURN_SHARE = 0.75  # the turn loads every motor to at most 75 % of its capacity with the
# hand's inertia (5 % under the stop's STOP_SHARE): it runs with the ball in the hand, whose
# weight the room of move_time does not carry. Measured (bench_catch.py --grid: 30 deg /
# 1.5 m wrist flexion headroom), a turn after the arm's stop: 0.8 -> 19.1 % (under issue
# 15's 20 %), 0.75 -> 23.5 %; the turn from the grasp (the plans' first choice, its length
# also set by the joints' limits on top of the stop): 0.6 / 0.75 / 0.8 -> 52.0 / 54.7 /
# 52.5 %, 23 of 25 held each


def hold_turn(dyn: StopDynamics, q_end: np.ndarray, tilt_deg: float = HOLD_TILT_DEG
              ) -> tuple[np.ndarray, float]:
    """The wrist's turn after the stop that holds the ball in the fingers' cage: the arm
    at rest in ``q_end``, its flexion turned (within its range, keeping LIMIT_MARGIN) so
    that the palm faces up and its downhill points ``tilt_deg`` from level towards the
    fingers (a ball on it rolls into the closed fingers, not off the open wrist side).
    Returns the joint delta and the move's duration (the speed and acceleration limits,
    every motor within ``TURN_SHARE`` of its capacity); no turn (zeros, 0) when gravity
    alone leaves a motor no room."""
    h, i = dyn.hand, dyn.joints.i_flex
    z = np.zeros(h.n)
    lo, hi = h.lower[i], h.upper[i]
    pad = 0.5 * (1.0 - LIMIT_MARGIN) * (hi - lo)
    want = -math.sin(math.radians(tilt_deg))
    coarse = np.linspace(lo + pad, hi - pad, 53)  # ~0.05 rad apart, then 0.005 about the best
    best = best_flex(h, q_end, i, coarse, want)
    if best is None:
        return z, 0.0
    d = float(coarse[1] - coarse[0])
    best = best_flex(h, q_end, i, np.clip(np.linspace(best - d, best + d, 21), lo + pad,
                                           hi - pad), want)
    z[i] = best - q_end[i]
    T = turn_time(dyn, q_end, z)
    return (z, T) if math.isfinite(T) else (np.zeros(h.n), 0.0)


def turn_time(dyn: StopDynamics, q_from: np.ndarray, delta: np.ndarray) -> float:
    """The shortest min-jerk turn ``delta`` from ``q_from`` within every joint's speed and
    acceleration limit and every motor within ``TURN_SHARE`` of its capacity with the
    hand's inertia at either end (``move_time``'s rule); inf when gravity alone leaves a
    motor no room."""
    return dyn.room_time((q_from, q_from + delta), delta, TURN_SHARE)


def best_flex(h: HandModel, q_end: np.ndarray, i: int, cand: np.ndarray, want: float
               ) -> float | None:
    """Among flexion angles ``cand`` (joint ``i``; the rest as ``q_end``) the one whose palm
    faces up with gravity's share along its +y (towards the wrist) nearest ``want``, the
    nearest to ``q_end``'s between equals; None when the palm faces up at none."""
    best, best_err = None, math.inf
    for f in cand:
        q = q_end.copy()
        q[i] = f
        R = h.palm_pose(q)[:3, :3]
        if R[2, 2] <= 0.0:
            continue
        err = abs(-R[2, 1] - want) + 1e-3 * abs(f - q_end[i])  # gravity (0, 0, -1) . y
        if err < best_err:
            best, best_err = float(f), err
    return best
