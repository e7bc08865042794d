"""The wrist's turn that holds the ball (``docs/history/physics-replay.md``, "Catch"): when it starts
and how it runs. Once the pad has stopped the ball the wrist turns the closed hand palm up,
its downhill ``HOLD_TILT_DEG`` into the fingers (``holdturn.hold_turn``); it starts from
the grasp (``TurnMode.EARLY``), after the arm's stop (``TurnMode.LATE``) or, by the roll rule
(``TurnMode.AHEAD``, ``HoldTurn.ahead_rows``), under way before the ball lands.

A palm steep at the intercept (66-73 deg from level on the 20 deg throws: the geometry of
the wrist and the path fixes the palm's angle where the ball meets the palm centre) lets
the landed ball roll towards the wrist at up to k g sin(tilt) (``planner.check.ballroll``: k
= 5/7 a solid ball, 0.62 a tennis ball) while a turn from rest (``holdturn.hold_turn``) is
still slow. Started before the ball, the turn passes the intercept pose at speed: the
flexion's speed rises (min-jerk) to w exactly at the intercept, holds it and falls to rest
(min-jerk) where the hold's pose is (palm up, ``HOLD_TILT_DEG`` downhill into the fingers;
a turning palm also carries the ball outwards, towards the fingers, at w^2 times its
distance from the wrist axis); the stop's own flexion speed, when it turns the same way, is
kept after the stop's ramp to rest. It does not speed up after the intercept: a palm turning
away from the ball faster than gravity's part along its normal (g cos(tilt): 2.9 m/s^2 at
73 deg) lifts off it (the check's friction cone refuses it). The pre-catch pose lies the
ramp's travel (w T_up / 2) short of the intercept pose, so that the rows pass the intercept
pose at the intercept, turning: the ball's crossing of the moving palm, judged by the
check's rule on the rows (the contact point and the relative velocity at the crossing, the
pad's force and friction cone there, the motors).

The profiles are the stopping motion's (``stopping.SoftStop``: contact share 1, no recoil,
no pad), over the flexion alone: one speed profile of the arm, not two.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from enum import Enum
from typing import Any, NamedTuple

import numpy as np

from planner.catch.flight.path import Flight
from planner.catch.grasp import motor_torque_matrix
from planner.catch.plan.arm import calm_move_time, move_time
from planner.catch.plan.holdturn import TURN_SHARE, hold_turn
from planner.catch.plan.reasons import CatchReason, Reason
from planner.catch.plan.results import Closing
from planner.catch.plan.softstop import SoftStop
from planner.catch.plan.stopping import StopDynamics
from planner.trajectory import LIMIT_MARGIN


class TurnMode(Enum):
    """When the wrist's turn that holds the ball starts."""

    AHEAD = "ahead"  # by the roll rule: under way before the ball lands (``ahead_rows``)
    EARLY = "early"  # from the grasp
    LATE = "late"  # after the arm's stop


class Turn(NamedTuple):
    """The wrist's turn that holds the ball, as the rows run it (``CatchPlanner._rows``):
    its ``delta`` (the joints' travel), ``duration_s`` and ``start_s``; ``profiles``, the
    flexion's speed profiles of a turn under way at the intercept (``ahead_turn``), or None:
    one min-jerk move from ``start_s``."""

    delta: np.ndarray
    duration_s: float
    start_s: float
    profiles: tuple[SoftStop, ...] | None = None


class HoldStart(NamedTuple):
    """The wrist's turn that holds the ball before it is placed in time: the joints'
    travel and its duration (``HoldTurn.hold``)."""

    delta: np.ndarray
    duration_s: float


@dataclass(frozen=True)
class RowsArgs:
    """What a plan's rows are made of, but the turn (``CatchPlanner._rows``): the hand
    meeting the ball (``CatchPlanner.meet``'s ``MeetPose``), the pre-catch pose, the
    stopping motion, the closing move, when the hand moves and for how long, when the
    fingers start closing, the rows' rate."""

    pose: Any
    q_pre: np.ndarray
    stop: SoftStop
    closing: Closing
    t_react: float
    T_m: float
    s_c: float
    rate_hz: float
    inertia_ratio: float | None = None  # the ball's I / (m R^2) where the rows fall with it on
    # the reach axis (``planner.catch.plan.drop``; None: they do not)


class TurnRows(NamedTuple):
    """The rows of a plan with its wrist's turn: the ``Turn``, times, joint rows and the
    move-in's duration (a turn under way at the intercept may lengthen it)."""

    turn: Turn
    t: np.ndarray
    Q: np.ndarray
    T_m: float


_FINE_S = 0.002  # the motors' room before the intercept judged every 2 ms
# (``_motors_within``)
AHEAD_SHARES = tuple(k / 20 for k in range(1, 21))  # the roll rule's turns under way at the
# intercept, slowest first: their speed then, as a share of what the stop leaves the flexion
# (its speed limit less the stop's own flexion speed: ``ahead_turn``), in steps of 5 % (with
# steps of 25 %, 20 deg / 1.5 m had 43 mm of roll at 0.25 and its 0.5 beyond the motors: the
# 5 % steps find 40 mm within them)
TURN_GROW = 1.25  # an early turn too fast on top of the stop is made this much longer
TURN_TRIES = 6  # ... up to this many times (1.25^6 = 3.8 x)


def ahead_turn(dyn: StopDynamics, stop: SoftStop, q_land: np.ndarray, q_held: np.ndarray,
               delta: np.ndarray, share: float, load: np.ndarray
               ) -> tuple[SoftStop, ...] | None:
    """The turn ``delta`` (flexion alone, to ``q_held`` from the pose the stop leaves)
    under way at ``share`` of the speed the stop leaves the flexion (its limit less the
    stop's flexion speed) when the ball lands on ``q_land`` at the stop's intercept; the
    flexion's own part of the stop, when it turns the same way, kept at its speed after the
    stop's ramp to rest (a second profile rising as the stop's falls: their sum holds its
    speed), both at speed until they fall to rest together at the hold's pose. The ramps
    the shortest within the acceleration limit and every motor within ``TURN_SHARE`` of its
    capacity with the hand's inertia (``StopDynamics.ramp_time``; the ramp to rest with the
    riding ball's ``load``). None when no speed is left or the turn is too short for it."""
    arm = list(dyn.arm)
    i = dyn.joints.i_flex
    c = arm.index(i)
    d = float(delta[i])
    sgn = float(np.sign(d))
    qs = float(stop.qd[c]) * sgn if stop.ramp_out_of(c) > 0 else 0.0  # the stop's, along the turn
    w = share * (float(dyn.v_max[c]) - abs(qs))
    if d == 0.0 or w <= 0.0:
        return None
    keep = max(qs, 0.0)
    qd = np.zeros(len(arm))
    qd[c] = sgn * w
    up = dyn.ramp_time(q_land, qd, share=TURN_SHARE)
    qd_all = qd.copy()
    qd_all[c] = sgn * (w + keep)
    down = dyn.ramp_time(q_held, qd_all, load, share=TURN_SHARE)
    if not (np.isfinite(up) and np.isfinite(down)):
        return None
    t_i, z = stop.t_i, np.zeros(3)
    out_s = stop.ramp_out_of(c)  # the flexion's own ramp to rest (per-joint ramps: its own)
    t_k = stop.t_i + stop.recoil_s + stop.hold_s + out_s  # the kept part at speed
    # the fall to rest starts at t_c: w (t_c - t_i + down/2) + keep (t_c - t_k + out/2 +
    # down/2) = |d| (the travel after the intercept)
    t_c = (abs(d) - 0.5 * down * (w + keep) - 0.5 * keep * out_s + w * t_i
           + keep * t_k) / (w + keep)
    if t_c < (t_k if keep > 0 else t_i):
        return None
    out = [SoftStop(0.0, tuple(arm), qd, 1.0, float(t_i), 0.0, float(up), 0.0,
                    float(t_c - t_i), float(down), 0.0, z, z.copy(), z.copy(),
                    np.zeros(len(dyn.cap)), 0.0)]
    if keep > 0:
        qk = np.zeros(len(arm))
        qk[c] = sgn * keep
        out.append(SoftStop(0.0, tuple(arm), qk, 1.0, float(t_k), 0.0, float(out_s),
                            0.0, float(t_c - t_k), float(down), 0.0, z, z.copy(), z.copy(),
                            np.zeros(len(dyn.cap)), 0.0))
    return tuple(out)


class HoldTurn:
    """The turn's choices of one planner: its hand, joints, dynamics, kinematics and rest
    pose, and ``rows`` (``CatchPlanner._rows``: the rows of a plan with a given turn)."""

    def __init__(self, hand, joints, dyn: StopDynamics, kin, q_rest: np.ndarray, rows) -> None:
        self.hand, self.joints, self.dyn, self.kin = hand, joints, dyn, kin
        self.q_rest, self.rows = q_rest, rows
        M = motor_torque_matrix(hand, q_rest)  # the motors that move the arm
        self._arm_motors = np.flatnonzero(np.any(M[:, list(joints.arm)] != 0, axis=1))

    def hold(self, pose: Any, stop: SoftStop) -> HoldStart:
        """The wrist's turn that holds the ball (``holdturn.hold_turn``) from the closed hand
        where the stopping motion leaves it (delta, duration); when it starts is the mode's
        (``turned_rows``: ``turn_start``; ``ahead_rows``: under way at the intercept)."""
        q_end = pose.q_closed.copy()
        q_end[list(self.joints.arm)] += stop.last_offset
        return HoldStart(*hold_turn(self.dyn, q_end))

    def turned_rows(self, turn0: HoldStart, mode: TurnMode | None, rows_args: RowsArgs):
        """The rows (``rows(rows_args, turn)``) with the wrist's turn (delta, duration)
        started as ``mode`` says (``turn_start``). An early turn (from the grasp, while the
        arm may still be stopping) adds its speeds and accelerations to the stop's: it is
        lengthened by ``TURN_GROW`` until every joint is within its speed and acceleration
        limits on the rows (at most ``TURN_TRIES`` times; then as it is, for the self-check
        to refuse). Returns the ``TurnRows`` (its ``Turn`` without profiles)."""
        a = rows_args
        turn = Turn(turn0.delta, turn0.duration_s,
                    turn_start(a.stop, a.closing, a.s_c, mode == TurnMode.EARLY))
        t, Q = self.rows(rows_args, turn)
        if mode != TurnMode.EARLY or turn0.duration_s <= 0:
            return TurnRows(turn, t, Q, a.T_m)
        for _ in range(TURN_TRIES):
            if rows_within_limits(self.hand, t, Q):
                break
            turn = turn._replace(duration_s=turn.duration_s * TURN_GROW)
            t, Q = self.rows(rows_args, turn)
        return TurnRows(turn, t, Q, a.T_m)

    def ahead_rows(self, turn0: HoldStart, rows_args: RowsArgs, flight: Flight):
        """The roll rule (TurnMode.AHEAD): the slowest of the wrist's turns -- from the grasp
        (TurnMode.EARLY's), then under way at the intercept at ``AHEAD_SHARES`` of the speed the
        stop leaves the flexion (``ahead_turn``) -- on whose rows the ball, landing on the
        palm, rolls at most ``ROLL_ROOM_M`` towards the wrist (``planner.check.ballroll``: its
        inertia, gravity along the palm and the rows' accelerations); the least rolling when
        none does. A turn under way needs the pre-catch pose short of the intercept pose by
        its travel before the ball, within the flexion's range and reached (``move_time``)
        before the stop begins (the move-in and the turn's ramp may overlap), its rows within
        every joint's speed and acceleration limit and, from the turn's start to the
        intercept (the check judges the hand's inertia from there on), the arm's motors within
        ``STOP_SHARE`` of their capacity, the closing fingers' reaction included (``_motors_within``);
        a candidate that is not is skipped. A plan whose least rolling turn lets the ball roll
        beyond the room is infeasible (the roll rule's reason). Returns the ``TurnRows``."""
        # (first used by the ending of a live session: not imported at its start)
        from planner.check.ballroll import ROLL_ROOM_M

        pose, q_pre, stop = rows_args.pose, rows_args.q_pre, rows_args.stop
        early = self.turned_rows(turn0, TurnMode.EARLY, rows_args)
        best_roll, best = self.rolled(early.t, early.Q, pose.t_i, flight), early
        if best_roll <= ROLL_ROOM_M or turn0.duration_s <= 0:
            return best
        h, i = self.hand, self.joints.i_flex
        arm = list(self.joints.arm)
        q_end = pose.q_closed.copy()
        q_end[arm] += stop.last_offset
        J = self.dyn.target_jacobian(q_end + turn0.delta, float(flight.ball.radius_m))
        load = np.zeros((h.n, len(arm)))
        load[arm] = float(flight.ball.mass_kg) * J.T @ J
        pad = 0.5 * (1.0 - LIMIT_MARGIN) * (h.upper[i] - h.lower[i])
        for share in AHEAD_SHARES:
            prof = ahead_turn(self.dyn, stop, pose.q_open, q_end + turn0.delta, turn0.delta, share,
                              load)
            if prof is None:
                continue
            pre = q_pre + ahead_shift(prof, pose.t_i, h.n)
            start = min(p.start_s for p in prof)
            if not h.lower[i] + pad <= pre[i] <= h.upper[i] - pad:
                continue
            T_pre = move_time(self.dyn, self.q_rest, pre)
            due = stop.start_s if np.any(stop.qd) else pose.t_i
            if rows_args.t_react + T_pre > due:
                continue
            T_pre = calm_move_time(self.dyn, self.q_rest, pre, rows_args.t_react,
                                   min(due, rows_args.s_c))
            turn = Turn(turn0.delta, max(p.end_s for p in prof) - start, start, prof)
            args = replace(rows_args, T_m=T_pre)
            if not self._motors_within(turn, args):  # (before the rows: their fall, where
                continue  # they fall with the ball, is most of their time)
            t, Q = self.rows(args, turn)
            if not rows_within_limits(self.hand, t, Q, 1e-9):
                continue
            rolled = self.rolled(t, Q, pose.t_i, flight)
            if rolled < best_roll:
                best_roll, best = rolled, TurnRows(turn, t, Q, T_pre)
            if rolled <= ROLL_ROOM_M:
                break
        return best

    def rolled(self, t: np.ndarray, Q: np.ndarray, t_i: float, flight: Flight) -> float:
        """The ball's largest roll towards the wrist on the rows (``roll_towards_wrist_m``,
        by ``drop.rolled_m``: the rows' rolls asked for again are not computed again)."""
        # (first used by the ending of a live session: not imported at its start)
        from planner.catch.plan.drop import rolled_m

        _, palm = self.kin.frames(Q)
        return rolled_m(t, palm, float(flight.ball.radius_m), t_i, flight.velocity(t_i),
                        flight.ball.inertia_ratio)

    def roll_reasons(self, flight: Flight, t: np.ndarray, Q: np.ndarray,
                     t_i: float) -> list[Reason]:
        """The roll rule's reason on these rows (``planner.check.ballroll``: the ball landing
        at ``t_i``, ``rolled``; on a hand the rule judges), if any."""
        # (first used by the ending of a live session: not imported at its start)
        from planner.check.ballroll import roll_judged, roll_problem

        if not roll_judged(self.hand.name):
            return []
        rolled = roll_problem(self.rolled(t, Q, t_i, flight))
        return [] if rolled is None else [Reason(CatchReason.ROLL, rolled)]

    def _motors_within(self, turn: Turn, rows_args: RowsArgs) -> bool:
        """From the turn's start to the intercept (where the check's rule takes over) the
        arm's motors within ``STOP_SHARE`` of their capacity with the hand's inertia at the
        rows' accelerations (``accel_room``, as ``move_time``), the closing fingers'
        included: their reaction on the wrist (0.8 N m of the wrist flexion motor's 2 N m on
        20 deg / 1.5 m, where the arm's own part asks 1.4), judged on the rows' motion
        sampled every ``_FINE_S`` (the rows' second differences smooth the short ramps'
        peaks). (``ahead_rows`` also holds every joint within its speed and acceleration
        limits on the rows themselves.)"""
        # (without the hand's fall on the reach axis, ``planner.catch.plan.drop``: it moves
        # only rows after the landing, and only rows up to the intercept are judged here; it
        # was two thirds of the fall's plans' time at this rate)
        t_f, Q_f = self.rows(replace(rows_args, rate_hz=1.0 / _FINE_S, inertia_ratio=None),
                             turn)
        a_f = np.diff(Q_f, 2, axis=0) / (_FINE_S * _FINE_S)
        for k in np.flatnonzero((t_f[1:-1] >= turn.start_s) & (t_f[1:-1] <= rows_args.pose.t_i)):
            MH, room = self.dyn.accel_room(Q_f[k + 1])
            if np.any(np.abs(MH[self._arm_motors] @ a_f[k]) > room[self._arm_motors]):
                return False
        return True


def rows_within_limits(hand, t: np.ndarray, Q: np.ndarray, rel: float = 0.0) -> bool:
    """Every joint's speed and acceleration on the rows ``t``, ``Q`` (their first and second
    differences) within ``LIMIT_MARGIN`` of its limit (times 1 + ``rel``)."""
    dt = float(t[1] - t[0])
    v = np.abs(np.diff(Q, axis=0)) / dt
    a = np.abs(np.diff(Q, 2, axis=0)) / (dt * dt)
    return bool(np.all(v <= LIMIT_MARGIN * hand.velocity * (1.0 + rel))
                and np.all(a <= LIMIT_MARGIN * hand.acceleration * (1.0 + rel)))


def ahead_shift(profiles: tuple[SoftStop, ...], t_i: float, n: int) -> np.ndarray:
    """How far the pre-catch pose lies from where the rows are at the intercept ``t_i``
    without the turn's ``profiles`` (``CatchPlanner._rows``): minus their travel before it."""
    t = np.array([-math.inf, t_i])
    return -sum((np.diff(p.offset(t, n), axis=0)[0] for p in profiles), np.zeros(n))


def turn_start(stop: SoftStop, closing: Closing, s_c: float, early: bool) -> float:
    """When the wrist's turn starts: once the grasp is made (``u_grasp`` of the closing from
    ``s_c``; before it the ball lies on the palm alone, whose friction cone the check judges
    then) and the pad has stopped the ball; not ``early``: also the arm at rest."""
    grasp = s_c + (closing.u_grasp or 1.0) * closing.duration_s
    return max(stop.t_i + stop.pad_s if early else stop.end_s, grasp)
