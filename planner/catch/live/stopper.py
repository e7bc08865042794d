"""The live soft stop's state (``session.CatchSession``, issue 31 item 3): which stopping
motion (``live.stop``) the live hand is making for the newest estimate, its pre-catch pose
(the arm's move's target), whether it is fixed (the rows have reached its ramp), and the
palm at rest when it cannot be made (the live catch before the soft stop).

* Before the first estimate the hand starts for the table's typical pre-catch pose
  (``start_early``); for each estimate the table's motion of the nearest throw
  (``StopTable``) through the estimate's intercept pose (``for_estimate``, ``shifted``), slower
  when the arm cannot reach its pre-catch pose before its ramp (``slower``); with no
  table throw, one chosen for the estimate (``stop_for``).
* Fixed (``fix``) once the next observation's rows or re-aim would reach its ramp; the
  palm at rest instead when what is left of the arm's move, added to the ramp, would
  leave the joints' limits; a newer estimate's intercept is then where its ball meets the
  moving palm (``met``).
* Without the soft stop (``soft`` False) the palm waits at rest at each intercept pose.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from planner.catch import grasp as gq
from planner.catch.flight.path import Flight
from planner.catch.live.motion import LiveMotion, rest_by_s
from planner.catch.live.stop import (
    LATE_STEPS,
    LATE_TOL_S,
    OVERLAP_STEP_S,
    StopTable,
    arm_offset,
    live_stop,
    met_on_the_moving_palm,
    moves,
    scaled,
)
from planner.catch.live.turn import LiveTurn
from planner.catch.plan.arm import palm_target
from planner.catch.plan.softstop import SoftStop, stop_knots
from planner.catch.plan.turnahead import TURN_GROW, TURN_TRIES, rows_within_limits
from planner.trajectory import phase_duration


class LiveStopper:
    """The soft stop of one live throw: planner ``pl``, the session's ``motion``, the ball,
    the catch point ``C``, the rows' interval ``dt``; ``soft`` False: the palm at rest."""

    def __init__(self, pl, motion: LiveMotion, ball, C: np.ndarray, dt: float, drag: bool,
                 soft: bool) -> None:
        self.pl, self.motion, self.ball, self.C, self.dt = pl, motion, ball, C, dt
        self.soft = bool(soft)
        self.table = StopTable.of(pl, C, ball, drag, dt) if self.soft else None
        self.nominal: SoftStop | None = None  # the table's motion for the estimate
        self.stop: SoftStop | None = None  # the stopping motion of the newest estimate
        self.fixed = False  # ... fixed: the rows follow it
        self.fallbacks = 0  # soft stops given up for the palm at rest (``fix``)
        self.q_pre: np.ndarray | None = None  # its pre-catch pose (the arm's move's target)
        self.target_m: np.ndarray | None = None  # the fixed stop's palm target at its t_i

    def look(self, flight: Flight) -> float | None:
        """The palm's tilt for ``flight`` (the table's, kept once the stop is fixed), and
        the table's motion for it; None without the soft stop."""
        if self.fixed or self.table is None:
            return None
        tilt, self.nominal = self.table.entry_for(flight)
        return tilt

    def stop_for(self, pose, t_b: float) -> SoftStop | None:
        """The stopping motion through ``pose`` (``live.stop``), its pre-catch pose
        (``q_pre``) reached in time from the hand's state at ``t_b`` (-inf: any time)."""
        m, arm = self.motion, list(self.pl.joints.arm)
        if not self.soft:
            self.stop, self.q_pre = None, pose.q_open
            return None

        def ready_by(q: np.ndarray) -> float:
            if t_b == -math.inf:
                return t_b
            if not m.moving:
                return t_b + m.move_time(self.pl.q_rest, q)
            q_now = m.row1(t_b, m.seg.state1(t_b)[0])  # (its move from there: from rest)
            return t_b + m.move_time(q_now, q)

        self.stop = stop = live_stop(self.pl.dyn, pose.v_i, float(self.ball.mass_kg),
                                     self.ball.radius_m, pose.q_open, float(pose.t_i), ready_by,
                                     self.dt)
        self.q_pre = pose.q_open.copy()
        self.q_pre[arm] += stop.first_offset
        return stop

    def pad_s(self, pose) -> float:
        """How long the pad takes to stop the ball: at the stopping motion's contact
        speed, or on a palm at rest (no soft stop)."""
        if moves(self.stop):
            return self.stop.pad_s
        return gq.stop_time(pose.v_i, self.pl.hand.pad_give_m)

    def start_early(self, t_s: float) -> None:
        """The soft stop's hand moves from the first observation's ``t_s`` on, to the table's
        typical pre-catch pose (``StopTable.prior``): the ramp of a short throw's stopping
        motion starts ~0.2-0.3 s after the launch (bench_live's 1-1.5 m throws), too soon
        for a move begun at the first fit (~0.1 s); the re-aims then take it to the
        estimate's."""
        q = self.pl.q_rest.copy()
        q[list(self.pl.joints.arm)] = self.table.prior
        m = self.motion
        m.start(t_s, q, m.move_time(self.pl.q_rest, q))

    def slower(self, pose, t_b: float) -> tuple[SoftStop | None, np.ndarray, float]:
        """The stopping motion (the newest, through ``pose``) for a hand that is at its
        pre-catch pose too late for the ramp (``ready``) from ``t_b``: its speeds and
        ramps scaled down together (``scaled``: the ramps' peak accelerations, hence every
        motor's load, no higher; a slower ramp starts later and nearer the intercept pose),
        the largest share that is in time found by bisection (``LATE_STEPS``); the palm at
        rest when none is. Returns the stop, its pre-catch pose and the move's duration
        from ``t_b``."""
        base = self.nominal if self.nominal is not None else self.stop
        m, arm = self.motion, list(self.pl.joints.arm)
        q_now = m.seg.state1(t_b)[0] if m.moving else None  # (the same at every step)
        lo, hi = 0.0, 1.0
        for _ in range(LATE_STEPS):  # (each step's stop in numbers: ``scaled`` then
            k = 0.5 * (lo + hi)  # ``shifted``, their arithmetic, no stop made)
            qd, ramp_in_s = k * base.qd, k * base.ramp_in_s
            s = stop_knots(base.contact_share, base.t_i, base.row_s, ramp_in_s,
                           base.recoil_s, base.hold_s, k * base.ramp_out_s)
            qd = qd * self.range_scale(pose.q_open[arm], qd * s[0], qd * s[4])
            q_pre = pose.q_open.copy()
            q_pre[arm] += qd * s[0]
            start_s = float(pose.t_i) - base.row_s - ramp_in_s
            lo, hi = (k, hi) if self.ready(t_b, q_pre, q_now) <= start_s else (lo, k)
        self.stop = scaled(base, lo)
        self.shifted(pose)
        return self.stop, self.q_pre, self.ready(t_b) - t_b

    def ready(self, t_b: float, q_pre: np.ndarray | None = None,
              q_now: np.ndarray | None = None) -> float:
        """When the arm can be at rest at the pre-catch pose ``q_pre`` (None: ``self.q_pre``)
        if it goes there from ``t_b`` (from rest: ``LiveMotion.move_time``); ``q_now``: the
        moving arm's joints at ``t_b`` when known."""
        m, q_pre = self.motion, self.q_pre if q_pre is None else q_pre
        if not m.moving:
            return t_b + m.move_time(self.pl.q_rest, q_pre)
        arm = list(self.pl.joints.arm)  # (a re-aim from the moving arm's state: its shortest,
        # the joints' limits alone; ``LiveMotion.reaim`` then keeps the motors within theirs)
        q_now = m.seg.state1(t_b)[0] if q_now is None else q_now
        return t_b + phase_duration(q_pre[arm] - q_now, m.hand.velocity[arm],
                                    m.hand.acceleration[arm], 0.0, m.hand.jerk[arm])

    def for_estimate(self, pose, t_b: float, fix_s: float) -> SoftStop | None:
        """The table's stopping motion for the estimate (``StopTable``) through ``pose``;
        slower (``slower``) when the arm cannot be at its pre-catch pose before its ramp,
        unless the rows reach the ramp by ``fix_s`` (then it is fixed as it is, the re-aim's
        share made); one chosen for the estimate when the table has no throw."""
        if self.nominal is None:
            return self.stop_for(pose, t_b if self.motion.moving else -math.inf)
        self.stop = self.nominal
        stop = self.shifted(pose)
        if self.motion.moving and moves(stop) and (self.ramp_passed(t_b) or (
                fix_s < stop.start_s and self.ready(t_b) > stop.start_s + LATE_TOL_S)):
            stop = self.slower(pose, t_b)[0]
        return stop

    def ramp_passed(self, t_b: float) -> bool:
        """Whether the stopping motion's ramp starts before ``t_b``, the first time the
        re-plan acts from (the rows up to it written, or being written, without the ramp):
        fixed, it would add the ramp's travel so far to the next row at once, against the
        joints' speed limits (a first fit of a few noisy observations may put the intercept,
        hence the ramp, in the past); such a stop is made slower, or the palm waits at rest."""
        return moves(self.stop) and self.stop.start_s < t_b

    def shifted(self, pose) -> SoftStop | None:
        """The moving hand's stopping motion (chosen when it started to move: its speeds
        and ramps kept, so that the re-aims follow the estimate, not a new motion) through
        ``pose``, the newest intercept."""
        stop, arm = self.stop, list(self.pl.joints.arm)
        if stop is None:
            self.q_pre = pose.q_open
            return None
        s = stop.knots()
        scale = self.range_scale(pose.q_open[arm], stop.qd * s[0], stop.qd * s[4])
        stop = self.stop = replace(stop, t_i=float(pose.t_i), qd=stop.qd * scale)
        self.q_pre = pose.q_open.copy()
        self.q_pre[arm] += stop.qd * s[0]  # (its first offset: the knot s[0] is not t_i's)
        return stop

    def range_scale(self, q: np.ndarray, first: np.ndarray, last: np.ndarray) -> np.ndarray:
        """The arm joints' speed factors that keep a stop's travel from ``q`` (the arm
        joints of the intercept pose) to its ``first`` and ``last`` offsets within their
        range: a joint that would leave it slower (as ``stop_profile`` slows it)."""
        arm, h = list(self.pl.joints.arm), self.pl.hand
        lo, hi = h.lower[arm], h.upper[arm]
        scale = np.ones(len(arm))
        for off in (first, last):
            room = np.where(off < 0, q - lo, hi - q)
            over = np.abs(off) > room
            scale[over] = np.minimum(scale[over], np.maximum(room[over], 0.0) / np.abs(off[over]))
        return scale

    def adds_within_limits(self) -> bool:
        """Whether the arm's move, where it still runs after the ramp starts, and the
        stopping motion added keep every arm joint within its speed and acceleration limits
        (``turnahead.rows_within_limits`` on a ``OVERLAP_STEP_S`` grid)."""
        m, stop = self.motion, self.stop
        if m.seg.end_s <= stop.start_s:
            return True
        t = np.arange(stop.start_s - 2 * OVERLAP_STEP_S, m.seg.end_s + 2 * OVERLAP_STEP_S,
                      OVERLAP_STEP_S)
        Q = m.rows(t) + arm_offset(stop, t, self.pl.hand.n)
        return rows_within_limits(self.pl.hand, t, Q)

    def fixed_stop(self, pose) -> SoftStop | None:
        """The fixed stop (its rows follow it); a palm at rest (the fallback of
        ``fix``) waits at the newest intercept pose."""
        if not moves(self.stop):
            self.q_pre = pose.q_open
        return self.stop

    def fix(self, pose, t_b: float) -> None:
        """The stopping motion fixed: the palm target where the rows have it at its
        intercept kept (a newer estimate's intercept is where its ball meets the moving
        palm, ``met``)."""
        self.fixed = True
        if self.stop is None:
            return
        m = self.motion
        if moves(self.stop) and (self.ramp_passed(t_b) or not self.adds_within_limits()):
            # the ramp started before the rows it could change (``ramp_passed``), or the
            # arm's move (a re-aim that could not reach the pre-catch pose in time) would
            # still run when the ramp starts: the rows would add the two beyond the joints'
            # limits; the palm waits at rest at the intercept pose instead (the live catch
            # before the soft stop), its re-aims going on
            self.stop, self.q_pre = scaled(self.stop, 0.0), pose.q_open
            m.reaim(t_b, pose.q_open, rest_by_s(pose.t_i, self.dt))
            self.fallbacks += 1
            return
        # the arm's travel from where its move ends (a re-aim may have kept an older
        # target) within the joints' range: a joint that would leave it slower
        stop, h, arm = self.stop, self.pl.hand, list(self.pl.joints.arm)
        q, travel = self.motion.seg.q1, stop.last_offset - stop.first_offset
        room = np.where(travel < 0, q - h.lower[arm], h.upper[arm] - q)
        over = np.abs(travel) > room
        if over.any():
            scale = np.ones(len(arm))
            scale[over] = np.maximum(room[over], 0.0) / np.abs(travel[over])
            self.stop = replace(stop, qd=stop.qd * scale)
        t = np.array([self.stop.t_i])
        off = arm_offset(self.stop, t, self.pl.hand.n)
        q = self.motion.rows(t)[0] + (0.0 if off is None else off[0])
        self.target_m = palm_target(self.pl.hand, q, self.ball.radius_m)

    def met(self, pose, flight: Flight):
        """``pose`` with the intercept time of its flight on the fixed moving palm."""
        if not (self.fixed and moves(self.stop)):
            return pose
        fl, stop = flight, self.stop
        t_i = met_on_the_moving_palm(stop, self.target_m, fl.position(stop.t_i) - self.C,
                                     fl.velocity(stop.t_i))
        return replace(pose, t_i=t_i, v_i=fl.velocity(t_i))

    def within_limits(self, turn: LiveTurn | None) -> LiveTurn | None:
        """The turn lengthened (``TURN_GROW``, at most ``TURN_TRIES`` times, as the planned
        catch's turn from the grasp) until every joint is within its speed and acceleration
        limits on its rows, where it runs on top of the stopping motion's end."""
        if turn is None or not moves(self.stop):
            return turn
        n = self.pl.hand.n
        for _ in range(TURN_TRIES):
            t = np.arange(math.floor(turn.start_s / self.dt) - 1,
                          math.ceil(turn.end_s / self.dt) + 2) * self.dt
            Q = self.motion.rows(t) + turn.offset(t)
            off = arm_offset(self.stop, t, n)
            if rows_within_limits(self.pl.hand, t, Q + (0.0 if off is None else off)):
                break
            turn = turn._replace(duration_s=turn.duration_s * TURN_GROW)
        return turn
