"""Every motor within its capacity while several joint groups move at once.

``planner.play.tendonload`` times each move within its own tendons' capacity; a finger
moves on its own joints and tendons, but the wrist's and the arm's motors carry the
reactions of every group that moves: the rail and the fingers crossing at height while
it moves, a chord's fingers on their way to their keys. Those add up: four fingers'
sideways motors accelerating together with the rail put 2.16 N m on the default hand's
wrist deviation motor, past its 2.00 N m (docs/history/2026-12-06-tendon.md).

So a note's moves are judged with the whole hand as it will then move: the rows they
span (the row clock's, one row more on each side: a row's speed and acceleration are
central differences), every group's track with the new moves added, through ``check``'s
own motor torques (``planner.check.limits.row_motor_torques``: gravity, the keys' push
where a fingertip is ``DOWN_DEPTH_M`` down, RNEA of the rows' differences, through the
transmissions). Where a motor passes ``TENDON_SHARE`` of its capacity
(``actuator_capacity``), and would not with the hand still there (a static load no
timing lowers), the note's moves are played ``sigma`` times slower (``slowed``: the
inertial load goes as ``1 / sigma^2``) and placed again: the least ``sigma`` up to
``MAX_SCALE`` that keeps every motor within (bisection, to one row's time over the note's
moves; at ``MAX_SCALE`` when none does). A note whose rows stay within is placed as
before: the same moves, the same floats. Moves placed outside a note's placing (a key let
up at the rows' commit, the arm's moves) are judged only with the notes placed after
them: rows between 95 % and 100 % of a motor's capacity remain possible there.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from functools import cache

import numpy as np

from planner.check.criteria import DOWN_DEPTH_M, tip_depths
from planner.check.kinematics import Kinematics
from planner.check.limits import linear_motor_map, row_motor_torques
from planner.hand.model import HandModel
from planner.hand.tendon import actuator_capacity
from planner.play.moves import Timed
from planner.play.profile import Move
from planner.play.tendonload import MAX_SCALE, TENDON_SHARE, slowed


@cache
def rows_load(hand: HandModel) -> RowsLoad:
    """The hand's ``RowsLoad`` (one per hand object)."""
    return RowsLoad(hand)


class RowsLoad:
    """Rows' motor torques as ``check`` computes them, against ``TENDON_SHARE`` of each
    motor's capacity."""

    def __init__(self, hand: HandModel) -> None:
        self.hand = hand
        self.kin = Kinematics(hand, hand.T_world_root)
        self.capacity_nm = TENDON_SHARE * actuator_capacity(hand).torque_nm
        self.motor_map = linear_motor_map(hand)

    def torques(self, t_s: np.ndarray, Q: np.ndarray, inertia: bool = True) -> np.ndarray:
        """Motor torques (rows 1 .. len - 2 of ``t_s, Q``, motors)."""
        depth = np.nan_to_num(tip_depths(self.kin.tips(Q))[1], nan=-1.0)
        return row_motor_torques(self.hand, self.kin, t_s, Q, depth >= DOWN_DEPTH_M,
                                 self.motor_map, inertia)

    def excess(self, t_s: np.ndarray, Q: np.ndarray) -> float:
        """The largest ratio of a motor's torque to its share of capacity over rows
        1 .. len - 2, of the motors within their share with the hand still there; 0.0
        with fewer than three rows."""
        if len(t_s) < 3:
            return 0.0
        load = np.abs(self.torques(t_s, Q)) / self.capacity_nm
        if not np.any(load > 1.0):  # (most rows: the static torques are not needed)
            return float(np.max(load))
        still = np.abs(self.torques(t_s, Q, inertia=False)) / self.capacity_nm
        return float(np.max(np.where(still <= 1.0, load, 0.0)))


class SlowedPlaces:
    """``planner.play.places.Places`` whose finger moves are played ``sigma`` times
    slower (their key crossings with them); everything else as the places say."""

    def __init__(self, places, sigma: float) -> None:
        self._places, self._sigma = places, sigma

    def __getattr__(self, name: str):
        return getattr(self._places, name)

    def _timed(self, timed: Timed) -> Timed:
        s = self._sigma
        return Timed(slowed(timed.move, s), None if timed.cross_s is None else timed.cross_s * s)

    def descend(self, e, start: str) -> Timed:
        return self._timed(self._places.descend(e, start))

    def lift(self, e, end: str) -> Timed:
        return self._timed(self._places.lift(e, end))

    def rise(self, e) -> Timed:
        return self._timed(self._places.rise(e))

    def repeat(self, e) -> Timed | None:
        got = self._places.repeat(e)
        return None if got is None else Timed(got.move.slowed(self._sigma),
                                              got.cross_s * self._sigma)

    def repeat_pair(self, e) -> tuple[Timed, Timed] | None:
        got = self._places.repeat_pair(e)
        return None if got is None else (self._timed(got[0]), self._timed(got[1]))

    def to_hover(self, e) -> Move:
        return slowed(self._places.to_hover(e), self._sigma)

    def across(self, a, b) -> Move | None:
        move = self._places.across(a, b)
        return None if move is None else slowed(move, self._sigma)


def span_rows(motion, finger: str, steps: list[tuple[float, Move]]
              ) -> tuple[np.ndarray, np.ndarray]:
    """The rows (times on the row clock, whole-hand configurations) over the time
    ``steps`` of ``finger`` span once added to its track, one row more on each side;
    ``motion`` itself is left as it was."""
    st = motion.fingers[finger]
    track = st.track
    trial = dataclasses.replace(track, segments=list(track.segments),
                                starts=list(track.starts))
    lo = math.inf
    for t0, move in steps:
        if move.duration_s > 0.0:
            lo = min(lo, max(t0, trial.free_s))
        trial.add(t0, move)
    if not math.isfinite(lo):
        return np.empty(0), np.empty((0, motion.hand.n))
    dt = motion.dt
    k = np.arange(max(0, math.floor(lo / dt) - 1), math.ceil(trial.free_s / dt) + 2)
    t = k * dt
    st.track = trial
    try:
        return t, motion.rows(t)
    finally:
        st.track = track


def within_motors(motion, finger: str, found, redo: Callable):
    """``found`` (``approach``'s: key-down moment, steps, start pose) of ``finger``, or
    the same note's moves placed again ``sigma`` times slower (``redo(places)``) with
    every motor within its share over the rows they span (module docstring); and the
    places they were timed with."""
    load = rows_load(motion.hand)
    if load.excess(*span_rows(motion, finger, found[1])) <= 1.0:
        return found, motion.moves
    tries: dict[float, tuple] = {}

    def fits(sigma: float) -> bool:
        places = SlowedPlaces(motion.moves, sigma)
        again = redo(places)
        tries[sigma] = (again, places)
        return again is not None and load.excess(*span_rows(motion, finger, again[1])) <= 1.0

    if not fits(MAX_SCALE):  # (the most it is slowed: placed so, the best it gets)
        again, places = tries[MAX_SCALE]
        return (found, motion.moves) if again is None else (again, places)
    lo, hi = 1.0, MAX_SCALE
    span_s = sum(move.duration_s for _, move in found[1])
    while (hi - lo) * span_s > motion.dt:  # (to a row's time over the note's moves)
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if fits(mid) else (mid, hi)
    return tries[hi]
