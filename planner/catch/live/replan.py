"""The re-planning of a live catch (``live.session``, steps 2-3 of its docstring): for
each new estimate of the flight, the intercept (``LiveSearch``) and its pose
(``CatchPlanner.meet``), the soft stop for it (``LiveStopper``), the hand's move
(``LiveMotion``: waiting, starting, re-aiming) and the closing's start, computed only when a
row or a decision needs it (``DeferredClosing``). The observations, their fit and the rows
written are the session's."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from planner.catch.flight.path import Flight
from planner.catch.live.motion import LiveMotion, rest_by_s
from planner.catch.live.search import LiveSearch
from planner.catch.live.stop import RAMP_MARGIN_S, START_SLACK_S, moves
from planner.catch.live.stopper import LiveStopper
from planner.catch.plan.closing import close_start, earliest_close_start
from planner.catch.plan.planner import PLAN_BUDGET_S, SIGNAL_S, CatchPlanner, MeetPose
from planner.catch.plan.results import Closing
from planner.catch.plan.softstop import SoftStop
from planner.hand.model import HandModel


class CloseAsk(NamedTuple):
    """``close_start``'s inputs of one re-plan (the flight, the open pose, the intercept,
    the fingers open, the ball's stop) and the time that re-plan acted from."""

    flight: Flight
    q_open: np.ndarray
    t_i: float
    ready: float
    stop_t: float
    t_b: float
    stop: SoftStop | None = None  # the palm's stopping motion (None: at rest)


class DeferredClosing:
    """A moving hand's closing start, re-timed for each estimate (``retime``) but computed
    (``close_start``) only once a row or a decision needs it (``due``). Its time changes no
    row before it (the fingers' closing phase is zero there), so while even its earliest
    (``earliest_close_start``) lies beyond the rows written, that earliest stands in its
    place: the same rows and decisions."""

    def __init__(self, hand: HandModel, C: np.ndarray, closing, radius_m: float) -> None:
        self.hand, self.C, self.closing, self.radius_m = hand, C, closing, radius_m
        self.ask: CloseAsk | None = None  # the inputs of the estimate deferred
        self.computed = 0  # closing starts computed (``close_start``)

    def compute(self, flight: Flight, q_open: np.ndarray, t_i: float, ready: float,
                stop_t: float, stop: SoftStop | None = None) -> float:
        """``close_start`` for these inputs (the ball in the frame of the palm on its
        stopping motion ``stop``), counted."""
        self.computed += 1
        return close_start(self.hand, flight, self.C, q_open, self.closing, t_i, ready,
                           stop_t, self.radius_m, stop)

    def retime(self, m: LiveMotion, ask: CloseAsk, rows_to_s: float) -> None:
        """The closing re-timed for the newest estimate; this observation's rows end at
        ``rows_to_s``."""
        low = earliest_close_start(self.closing, ask.t_i, ask.ready, ask.stop_t)
        self.ask = ask
        if low > rows_to_s:
            m.set_closing(low, self.closing.duration_s)
        else:
            self.due(m, math.inf)

    def due(self, m: LiveMotion, t_b: float) -> None:
        """The deferred estimate's closing start, computed when its earliest is no longer
        after ``t_b`` (it may have begun by then: the re-plan's test ``close_start_s >
        t_b`` needs the time itself)."""
        ask = self.ask
        if ask is None or m.close_start_s > t_b:
            return
        s_c = self.compute(ask.flight, ask.q_open, ask.t_i, ask.ready, ask.stop_t, ask.stop)
        m.set_closing(max(s_c, ask.t_b), self.closing.duration_s)
        self.ask = None


class LiveReplan:
    """The re-plan of each estimate for one live catch: the planner ``pl``, its ``closing``,
    the catch point ``C``, the rows' step ``dt``, the ball's ``radius_m``; the session's
    ``motion``, ``stopper`` and ``search`` (shared: the session writes the rows they make).
    ``kept_targets``: re-aims that could not reach their target at rest before the ball
    within the limits (part of the way made, or the older target kept)."""

    def __init__(self, pl: CatchPlanner, closing: Closing, C: np.ndarray, dt: float,
                 radius_m: float, motion: LiveMotion, stopper: LiveStopper,
                 search: LiveSearch) -> None:
        self.pl, self.closing, self.C, self.dt, self.radius_m = pl, closing, C, dt, radius_m
        self.motion, self.stopper, self.search = motion, stopper, search
        self.closings = DeferredClosing(pl.hand, C, closing, radius_m)
        self.kept_targets = 0

    def replan(self, flight: Flight, t_s: float, t_b: float, period: float,
               rows_to_s: float, prev: MeetPose | None, prev_t_i: float | None) -> MeetPose:
        """Steps 2-3 of ``live.session``'s docstring for the newest ``flight`` (observed up
        to ``t_s``), acting from ``t_b`` (this observation's rows end at ``rows_to_s``;
        ``prev``, ``prev_t_i``: the previous estimate's pose and intercept time, None before
        the first): the new pose, the hand's motion and closing re-planned for it."""
        pl, r, cl = self.pl, self.radius_m, self.closing
        prev_ic = None if prev is None else prev.ic
        m = self.motion
        tilt = self.stopper.look(flight)  # (a fixed stop keeps its tilt)
        if tilt is not None:
            self.search.tilt = tilt
        pose = pl.meet(flight, self.C, r, cl, self.search.next(flight, t_s, prev_ic, prev_t_i))
        # the next observation's rows (to its t_react + period) or re-aim reach this far
        fix_s = max(t_s + SIGNAL_S + PLAN_BUDGET_S + period, t_b) + period
        sp = self.stopper
        stop = (sp.fixed_stop(pose) if sp.fixed else sp.for_estimate(pose, t_b, fix_s)
                if sp.soft else sp.shifted(pose))
        if sp.fixed and moves(stop):  # the ball meets the fixed motion's palm then (the
            pose = sp.met(pose, flight)  # closing is timed for it)
        stop_t = sp.pad_s(pose)
        rest_by = rest_by_s(pose.t_i, self.dt)  # the arm still when the ball arrives, or
        if moves(stop):  # at the pre-catch pose when the stopping motion's ramp starts
            rest_by = min(rest_by, stop.start_s - RAMP_MARGIN_S)
        q_pre = sp.q_pre
        if not m.moving:
            T_m = m.move_time(pl.q_rest, q_pre)
            go = t_b + period + T_m  # the open pose reached if the hand waits one more
            # observation; wait while that is early enough: before the arm must be at rest
            # (with room for the re-aims) and before the closing's start, which is no
            # earlier than its earliest (then no closing time is needed: the same decision)
            late = go + (START_SLACK_S if moves(stop) else 0.0) >= rest_by
            if late or go >= earliest_close_start(cl, pose.t_i, t_b + T_m, stop_t):
                s_c = self.closings.compute(flight, pose.q_open, pose.t_i, t_b + T_m, stop_t,
                                            stop)
                if go >= s_c or late:
                    if moves(stop) and t_b + T_m > stop.start_s:  # too late for it: its
                        stop, q_pre, T_m = sp.slower(pose, t_b)  # ramp shorter
                    m.start(t_b, q_pre, T_m)
                    m.set_closing(s_c, cl.duration_s)
        else:
            self.closings.due(m, t_b)
            if not (sp.fixed and moves(stop)) and m.reaim(t_b, q_pre, rest_by) < 1.0:
                self.kept_targets += 1
            if m.close_start_s > t_b:
                self.closings.retime(m, CloseAsk(flight, pose.q_open, pose.t_i,
                                                   m.fingers_open_s, stop_t, t_b, stop),
                                     rows_to_s)
        if moves(stop) and m.moving and not sp.fixed and fix_s >= stop.start_s:
            sp.fix(pose, t_b)  # the next rows reach its ramp: the motion is the rows' now
        return pose
