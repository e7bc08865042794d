"""The end of a live catch (``CatchSession``): the rest of the plan written, judged once,
and the end marker.

The session ends when an observation can no longer act before the ball reaches the palm
(its reaction time is past the planned intercept), or when the observations end
(``CatchSession.finish``: the rest of the rows follow the last estimate). ``LiveEnding``
then starts the hand if it is still waiting, fixes the stopping motion, writes the rows
the ending observation must (up to its reach, as every observation's) where no wrist turn
can start among them, computes the wrist's turn that holds the ball palm up
(``live.turn``) within the joints' limits, writes the rest, and judges the whole plan once
by the planner's own self-check on every row (``RowCheck``), the roll rule and its grasp
forces (stopping and holding, ``CatchPlanner.forces``): the end marker says
``"catch": "held"`` when that plan catches the ball it last estimated, ``"given_up"``
with the reasons otherwise, and carries that estimate (``ball``, ``intercept_t``), which
``check`` judges.

The force QPs change no row, so they run on the final plan only, after the rows the
ending observation's latency is measured to.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from planner.catch.live.stop import arm_offset, moves
from planner.catch.live.turn import HeldTurn, LiveTurn, live_turn
from planner.catch.plan.closing import close_start
from planner.catch.plan.planner import HOLD_AFTER_S
from planner.catch.plan.reasons import CatchReason, Reason, reasons_text
from planner.catch.plan.results import GIVEN_UP, HELD, CatchPlan, make_catch_plan
from planner.errors import InfeasibleError

if TYPE_CHECKING:
    from planner.catch.flight.dragfit import DragEstimate
    from planner.catch.live.session import CatchSession, Written


class LiveEnding:
    """The end of one live session: its outcome, reason, final plan, the wrist's turn (None
    until the end, or when the hold has no turn), and the last estimate's uncertainty and
    drag. ``session``: the session it ends (its hand, motion, stop, fit and rows)."""

    def __init__(self, session: CatchSession) -> None:
        self.session = session
        self.turn: LiveTurn | None = None
        self.outcome: str | None = None
        self.reason = ""
        self.plan: CatchPlan | None = None
        self.uncertainty: dict[str, float] | None = None
        self.drag_estimate: DragEstimate | None = None
        self.held_turn = HeldTurn(session.pl.dyn)  # (the turn computed ahead, ``warm``)

    def finish(self, why: str, near_s: float = -math.inf) -> Written:
        """The rest of the plan (started now if the hand is still waiting), written; then
        judged, and the end marker. The rows up to ``near_s`` (the ending observation's
        reach, as every observation's rows) are written first where no wrist turn can
        start among them (its earliest start, ``turn_from``, after them: the same rows),
        the turn and the rest after them: the latency is to those first rows."""
        s = self.session
        m, sp = s.motion, s.stopper
        self._start_if_waiting()
        if not sp.fixed:
            sp.fix(s.pose, max(s.written_to_s, 0.0))
        s.pose = pose = sp.met(s.pose, s.flight)
        t_static, q_held = self._held()
        grasp = max(m.close_start_s + (s.closing.u_grasp or 1.0) * m.close_s,
                    pose.t_i + sp.pad_s(pose), m.seg.end_s)
        first_free_s = s.formatted_rows * s.dt
        near = (s.write_to(near_s) if math.isfinite(near_s)
                and s.last_row_s(near_s) <= max(grasp, first_free_s) else None)
        self.turn = sp.within_limits(live_turn(s.pl.dyn, q_held, grasp, first_free_s,
                                               self.held_turn.of(q_held)))
        if self.turn is not None:
            t_static = max(t_static, self.turn.end_s)
        rest = s.write_to(max(pose.t_i + HOLD_AFTER_S, t_static + s.dt))
        self._close(why, t_static)
        if near is None or not len(near.rows):
            return rest
        return near if not len(rest.rows) else near._replace(
            rows=np.concatenate([near.rows, rest.rows]))

    def _held(self) -> tuple[float, np.ndarray]:
        """When the hand comes to rest holding the ball (before its wrist's turn) and the
        pose it holds it in: the motion's and the stop's ends."""
        s = self.session
        m, stop = s.motion, s.stopper.stop
        t_static = max(m.close_start_s + m.close_s, m.seg.end_s, m.fingers_open_s,
                       stop.end_s if moves(stop) else -math.inf)
        t2 = np.array([t_static, t_static + s.dt])
        off = arm_offset(stop, t2, s.pl.hand.n)
        return t_static, m.rows(t2)[0] + (0.0 if off is None else off[0])

    def warm(self) -> None:
        """After an observation's rows, once the stop is fixed and the hand moving: the
        wrist's turn from the pose the hand will hold the ball in, computed ahead
        (``HeldTurn``)."""
        s = self.session
        if s.stopper.fixed and s.motion.moving and s.stopper.stop is not None:
            self.held_turn.warm(self._held()[1])

    def _start_if_waiting(self) -> None:
        """A hand still waiting for its move starts it now, to the stop's pre-catch pose,
        and its closing is timed."""
        s = self.session
        m, sp, pose = s.motion, s.stopper, s.pose
        s.replanner.closings.due(m, math.inf)
        if m.moving:
            return
        t_b = max(s.written_to_s, 0.0)
        if not sp.fixed:
            sp.stop_for(pose, t_b)
        T_m = m.move_time(s.pl.q_rest, sp.q_pre)
        m.start(t_b, sp.q_pre, T_m)
        m.set_closing(close_start(s.pl.hand, s.flight, s.C, pose.q_open, s.closing, pose.t_i,
                                  t_b + T_m, sp.pad_s(pose), s.ball.radius_m),
                      s.closing.duration_s)

    def _close(self, why: str, t_static: float) -> None:
        """Judge the written plan, set the outcome and write the end marker."""
        s = self.session
        fit, flight = s.fit, s.flight
        self.uncertainty = fit.intercept_sigma(flight, s.pose.t_i)  # (of the last estimate
        # only: what the plan reports)
        from planner.catch.flight.dragfit import estimate_drag  # (the ending's alone)

        self.drag_estimate = (estimate_drag(fit.times, fit.positions, flight, s.ball)
                              if s.drag else None)
        self.plan = self._judge(t_static)
        if self.plan.feasible:
            self.outcome = HELD
            g = self.plan
            self.reason = (f"grasp at t = {g.timing.grasp_t:.3f} s "
                           f"({', '.join(g.timing.grasp_fingers)}) of "
                           f"the ball estimated from {fit.n} observations; {why}")
        else:
            self.outcome = GIVEN_UP
            self.reason = reasons_text(self.plan.reasons) + f" ({why})"
        s.writer.close({"catch": self.outcome, "reason": self.reason,
                        "observations": fit.n,
                        "last_observation_s": float(fit.times[-1]),
                        "ball": flight.to_metadata(), "intercept_t": float(s.pose.t_i),
                        **({} if self.drag_estimate is None else
                           {"drag_estimate": self.drag_estimate.to_dict()})})

    def _judge(self, t_static: float) -> CatchPlan:
        """The final plan: every row through the planner's self-check, the grasp forces."""
        s = self.session
        pl, pose, fl, r, m = s.pl, s.pose, s.flight, s.ball.radius_m, s.motion
        t, Q = s.written_rows()
        verdict = pl.rows.check(fl, s.C, r, t, Q, pose.t_i, t_static, s.rate_hz,
                                s.closing.reason is not None)
        reasons = ([Reason(CatchReason.GRASP, s.closing.reason)] if s.closing.reason
                   else []) + list(verdict.reasons)
        if pose.ic.reason:
            reasons.append(Reason(CatchReason.OUT_OF_REACH, pose.ic.reason))
        reasons += pl.turn.roll_reasons(fl, t, Q, pose.t_i)
        stop = s.stopper.stop
        if self.turn is not None or moves(stop):  # the ball is held where the rows end
            pose = replace(pose, q_closed=Q[-1].copy())
        fv = pl.forces(fl, pose, t, Q, r, soft=stop if moves(stop) else None)
        reasons += fv.reasons
        try:
            t_f = float(fl.time_at_x(float(s.C[0])))
        except InfeasibleError:
            t_f = None
        return make_catch_plan(
            reasons=reasons, flight=fl, catch_point=s.C,
            T_world_root=pl.mount.T_world_root(s.C), base_hand=pl.base_hand, hand=pl.hand,
            rate_hz=s.rate_hz, throw=s.throw_info(), pose=pose, verdict=verdict,
            q_rest=pl.q_rest, q_open=s.stopper.q_pre, move_start_s=m.t_move,
            move_s=m.open_s,
            close_start_s=m.close_start_s, close_s=m.close_s, forces=fv.forces,
            t=t, Q=Q, t_info_s=float(s.fit.times[-1]), flight_time_s=t_f,
            uncertainty=self.uncertainty, notes=self._notes())

    def _notes(self) -> list[str]:
        s = self.session
        notes = [(f"live: {s.fit.n} observations (rms residual "
                  f"{1000 * s.fit.result.residual_rms:.1f} mm), the first plan from "
                  f"{s.first['observations']}")]
        if self.drag_estimate is not None:
            notes.append(f"live: {self.drag_estimate.describe()}")
        if s.replanner.kept_targets:
            notes.append(f"{s.replanner.kept_targets} re-aims could not reach their target at "
                         "rest before the ball within the limits: part of the way, or the older "
                         "target kept")
        return notes
