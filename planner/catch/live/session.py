"""A live catch: the plan re-made after every camera observation of the ball
(``cli.py catch --live``; ``CatchSession.observe(t_s, xyz)`` returns the new rows).

Time is the catch frame's (spec section 5): t = 0 when the ball leaves the launch
point, positions in metres from it. An observation seen at ``t`` can change the hand
from ``t_react = t + SIGNAL_S + PLAN_BUDGET_S`` on (the seed's 25 ms of signal
processing, the planning budget): every row up to then is written already, and after
each observation the rows are written up to ``t_react`` plus the last interval between
observations (the time the next observation can act from), so the hardware always has
the rows it is executing and a row, once written, never changes.

After each observation (``observe``):

1. Fit (``livefit.LiveFit``): the flight's state and its covariance from every
   observation so far (vacuum, or drag with the ball's k), once there are
   ``LiveFit.min_obs`` of them (before that there is no file: the hand rests, and the
   first rows are written from t = 0 with the first fit; those up to an earlier
   observation's ``t_react``, rest rows whatever the fit finds, formatted at that one).
2. Intercept (``livesearch.LiveSearch``): near the previous intercept time, the whole
   path searched from out of reach once per ``REACH_RETRY_S``; the pose confirmed by
   ``CatchPlanner.meet`` (placo, warm: the previous pose is the closed form's). The first
   fit's starts from the intercept of the flight fitted to the observations before it
   (``LiveFit.first_look``: with drag, the chord iteration the first fit would do, which
   it then continues by one step; its intercept searched along the whole path), both at
   the observation before the first fit, which plans nothing else, so that no
   observation carries the whole search or the fit's iteration together with the first
   plan.
3. Motion (``livemotion.LiveMotion``): until the hand moves, it waits while waiting for
   the next observation would not make it late (the open pose reached before the closing
   move must start, ``closing.close_start``), then starts the planner's move to the open
   pose; afterwards the arm is re-aimed at each new intercept pose from the state of the
   rows written, and the closing start is re-timed until it has begun.
4. Rows: only the ones not yet written are sampled, guarded and appended.

The session ends (``finish``; the end marker) when an observation can no longer act
before the ball reaches the palm (its ``t_react`` is past the planned intercept), or
when the observations end (``finish()`` at the end of the input: the rest of the rows
follow the last estimate). Then the rest of the plan is written and judged once by the
planner's own self-check on every row (``RowCheck``) and its grasp forces (stopping and
holding, ``CatchPlanner.forces``): the end marker says ``"catch": "held"`` when that
plan catches the ball it last estimated, ``"given_up"`` with the reasons otherwise, and
carries that estimate (``ball``, ``intercept_t``), which ``check`` judges. The file's
metadata holds the first fit's (spec section 4 asks for one on the first line).

Steps 2-3 are ``live.replan.LiveReplan``'s (the re-plan of each estimate); the session
keeps the observations, their fit, the rows written and the end.

The force QPs change no row, so they run on the final plan only; the latency of an
observation (to its rows) is the fit, the intercept, the motion and the new rows.
"""

from __future__ import annotations

import math
import time
from dataclasses import replace
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from planner.catch import grasp as gq
from planner.catch.flight.dragfit import DragEstimate, estimate_drag
from planner.catch.flight.livefit import LiveFit
from planner.catch.flight.path import Ball, Flight, finite_float, get_ball
from planner.catch.live.motion import LiveMotion
from planner.catch.live.replan import LiveReplan
from planner.catch.live.search import LiveSearch
from planner.catch.live.stop import arm_offset, moves
from planner.catch.live.stopper import LiveStopper
from planner.catch.live.turn import LiveTurn, live_turn
from planner.catch.plan.arm import open_from
from planner.catch.plan.closing import close_start
from planner.catch.plan.planner import (
    HOLD_AFTER_S,
    PLAN_BUDGET_S,
    SIGNAL_S,
    CatchPlanner,
    roll_reasons,
)
from planner.catch.plan.reasons import CatchReason, Reason, reasons_text
from planner.catch.plan.results import (
    GIVEN_UP,
    HELD,
    CatchPlan,
    ThrowInfo,
    catch_metadata,
    make_catch_plan,
)
from planner.catch.plan.stopping import SoftStop
from planner.errors import InfeasibleError, InputError
from planner.hand.model import HandModel
from planner.trajfile import FormattedRows, TrajectoryWriter, format_rows


class _Chunk(NamedTuple):
    """Rows sampled, guarded and formatted (``trajfile.format_rows``), to be written."""

    t: np.ndarray
    Q: np.ndarray
    rows: FormattedRows


class CatchSession:
    """One throw, planned live: ``observe`` each observation, ``finish`` at the end of
    the input. ``out_path``: a file, '-' (stdout) or None (in memory: ``text``)."""

    def __init__(self, dist_m: float, height_m: float = 0.0,
                 hand: HandModel | str = "default", ball: Ball | str = "tennis",
                 drag: bool = False, rate_hz: float = 100.0, out_path: str | None = None,
                 planner: CatchPlanner | None = None, soft_stop: bool = True) -> None:
        from planner.catch.plan.api import get_planner, validate_live

        d, hgt, rate = validate_live(dist_m, height_m, rate_hz)
        self.ball = get_ball(ball)
        self.drag = bool(drag)
        self.pl = planner or get_planner(hand)
        self.closing = self.pl.closing(self.ball.radius_m)
        self.C = np.array([d, 0.0, hgt])
        self.rate_hz, self.dt = rate, 1.0 / rate
        if out_path is not None and out_path != "-":
            parent = Path(out_path).parent
            if not parent.is_dir():
                raise InputError(f"cannot write {out_path}: no such directory {parent}")
        self.out_path = out_path
        self.latencies_s: list[float] = []  # per observation: to its rows written
        self.cpu_s: list[float] = []  # ... and the CPU time of this thread in it (the
        # latency less the time the machine ran other work)
        self.fit = LiveFit(self.ball, self.ball.drag_per_m if drag else 0.0)
        h, j = self.pl.hand, self.pl.joints
        q_open = open_from(h, j, self.pl.q_zero, self.closing.q_closed)
        self.motion = LiveMotion(h, j.arm, self.pl.q_rest, q_open, self.closing.q_closed,
                                 self.pl.dyn)
        self.writer: TrajectoryWriter | None = None
        self._T_root = self.pl.mount.T_world_root(self.C).tolist()  # (the file's metadata)
        self._t: list[np.ndarray] = []
        self._q: list[np.ndarray] = []
        self._ahead: list[_Chunk] = []  # rows formatted before the file is opened
        self.next_row = 0
        self.pose = self.flight = None
        self.t_i: float | None = None
        self._search = LiveSearch(self.pl.wrist, self.C, self.ball.radius_m)  # (step 2)
        # default: docs/history/live-catch.md, issue 31)
        self.first: dict[str, Any] | None = None  # the first plan's flight and intercept
        self.uncertainty: dict[str, float] | None = None
        self.outcome: str | None = None
        self.reason = ""
        self.plan: CatchPlan | None = None
        self.drag_estimate: DragEstimate | None = None  # (drag: at the end)
        self.turn: LiveTurn | None = None  # the wrist's turn that holds the ball (at the end)
        self.stopper = LiveStopper(self.pl, self.motion, self.ball, self.C, self.dt, self.drag,
                                   soft_stop)  # the soft stop (``live.stopper``)
        self.replanner = LiveReplan(self.pl, self.closing, self.C, self.dt, self.ball.radius_m,
                                    self.motion, self.stopper, self._search)  # (steps 2-3)
        self.rows_out_s = math.nan  # perf_counter when the last rows were flushed
        self.rows_cpu_s = math.nan  # thread_time then

    # ------------------------------------------------------------ observations
    @property
    def stop(self) -> SoftStop | None:
        """The arm's stopping motion (``live.stopper``): of the newest estimate, fixed
        (``stop_fixed``) once the rows reach its ramp."""
        return self.stopper.stop

    @property
    def stop_fixed(self) -> bool:
        return self.stopper.fixed

    @property
    def fallbacks(self) -> int:
        """Soft stops given up for the palm at rest (``LiveStopper.fix``)."""
        return self.stopper.fallbacks

    @property
    def done(self) -> bool:
        return self.outcome is not None

    @property
    def written_to_s(self) -> float:
        """Time of the last row written (-inf before any)."""
        return (self.next_row - 1) * self.dt if self.next_row else -math.inf

    @property
    def text(self) -> str | None:
        """The file's text, for a session kept in memory, once finished."""
        return None if self.writer is None else self.writer.text

    def observe(self, t_s: Any, xyz: Any) -> np.ndarray:
        """One observation: the ball's centre ``xyz`` (m, catch frame) at ``t_s`` (s from
        the launch). Refits, re-plans and writes the rows the plan adds; returns them as
        the file holds them, (n, columns) (none before the first fit, nor after the end).
        InputError (one line) on an observation that cannot follow the ones before."""
        if self.done:
            return np.empty((0, 0))
        t0, c0 = time.perf_counter(), time.thread_time()
        rows = self._observe(t_s, xyz)
        self.latencies_s.append((self.rows_out_s if len(rows) else time.perf_counter()) - t0)
        self.cpu_s.append((self.rows_cpu_s if len(rows) else time.thread_time()) - c0)
        return rows

    def _observe(self, t_s: Any, xyz: Any) -> np.ndarray:
        t = finite_float("t", t_s)
        p = _point(xyz)
        period = t - self.fit.times[-1] if self.fit.n else 0.0
        fit = self.fit.add(t, p)
        if fit is None:
            if self.fit.n == 1 and self.stopper.soft and not self.motion.moving:
                self.stopper.start_early(t + SIGNAL_S + PLAN_BUDGET_S)
            if self.fit.n == self.fit.min_obs - 1:  # the observation before the first fit
                look = self.fit.first_look()
                tilt = None if look is None else self.stopper.look(look)
                if tilt is not None:
                    self._search.tilt = tilt
                self._search.look(look)
            # the hand rests at least until this observation could act: those rows
            # formatted here, written with the first fit's
            chunk = self._format(t + SIGNAL_S + PLAN_BUDGET_S)
            self._ahead += [chunk] if chunk else []
            return np.empty((0, 0))
        t_react = t + SIGNAL_S + PLAN_BUDGET_S
        t_b = max(self.written_to_s, t_react)
        if self.t_i is not None and t_b >= self.t_i and self.pose.ic.reason is None:  # too
            # late to act before the ball (an estimate out of reach has no such time: a
            # first fit of a few noisy observations may put its nearest point in the past)
            return self._finish(f"the observation at t = {t:.3f} s acts after the intercept",
                                t_react + period)
        old_seg = self.motion.seg
        self.pose = self.replanner.replan(fit.flight, t, t_b, period,
                                          self._last_row_s(t_react + period), self.pose, self.t_i)
        self.flight, self.t_i = fit.flight, self.pose.t_i
        if self.writer is None:
            self._open()
        return self._write_to(t_react + period, t_b, old_seg)

    def finish(self) -> np.ndarray:
        """The end of the observations: the rest of the plan follows the last estimate
        (InputError when there were too few to fit a flight)."""
        if self.done:
            return np.empty((0, 0))
        if self.flight is None:
            raise InputError(f"{self.fit.n} observation{'' if self.fit.n == 1 else 's'} of the "
                             f"ball: at least {self.fit.min_obs} are needed to fit its flight")
        last = float(self.fit.times[-1])
        return self._finish(f"the observations ended at t = {last:.3f} s")

    def abort(self, discard: bool = False) -> None:
        """Stop without the end marker (the file stays visibly incomplete)."""
        if self.writer is not None:
            self.writer.abort(discard=discard)

    # ------------------------------------------------------------ re-plan
    # ------------------------------------------------------------ rows
    def _open(self) -> None:
        ball = self.flight.to_metadata()
        self.first = {"ball": dict(ball), "intercept_t": float(self.t_i),
                      "observations": self.fit.n}
        meta = catch_metadata(self.pl.base_hand, self._T_root, self.rate_hz, self.flight,
                              self.t_i, {"live": True, "throw": self._throw_info().to_dict(),
                                         "catch_point": [float(x) for x in self.C],
                                         "stop_distance_m": gq.STOP_DISTANCE_M,
                                         "observations": self.fit.n})
        h = self.pl.base_hand
        self.writer = TrajectoryWriter(self.out_path, meta, h)

    def _throw_info(self) -> ThrowInfo:
        return live_throw(self.flight, self.C, self.ball, self.drag, self.fit.n)

    @property
    def closings_computed(self) -> int:
        """Re-plans' closing starts computed (``close_start``; the rest deferred)."""
        return self.replanner.closings.computed

    def _last_row_s(self, t_end_s: float) -> float:
        """The time of the last row ``_write_to(t_end_s)`` writes."""
        return math.floor(t_end_s / self.dt + 1e-9) * self.dt

    def _format(self, t_end_s: float, t_b: float = -math.inf, old_seg=None) -> _Chunk | None:
        """The rows after those written (and formatted ahead) up to ``t_end_s`` (those up
        to ``t_b`` on the arm's move ``old_seg``, from before this re-plan), guarded and
        formatted, not written (None: no row)."""
        ahead = self._ahead
        first = self.next_row + sum(len(c.t) for c in ahead)
        n = math.floor(t_end_s / self.dt + 1e-9) + 1
        if n <= first:
            return None
        t = np.arange(first, n) * self.dt
        Q = self.motion.rows(t, old_seg, t_b)  # (the writer guards them as it writes them)
        sp = self.stopper
        off = arm_offset(sp.stop if sp.fixed else None, t, self.pl.hand.n)
        if off is not None:
            Q = Q + off
        if self.turn is not None:
            Q = Q + self.turn.offset(t)
        return _Chunk(t, Q, format_rows(t, Q, self.pl.hand.motor_angles(Q)))

    def _write_to(self, t_end_s: float, t_b: float = -math.inf, old_seg=None) -> np.ndarray:
        """The rows formatted ahead and the rest up to ``t_end_s`` (``_format``), written;
        returns them as written."""
        chunks = self._ahead + [c for c in (self._format(t_end_s, t_b, old_seg),) if c]
        self._ahead = []
        if not chunks:
            return np.empty((0, 0))
        out = [self.writer.append(c.rows) for c in chunks]
        self.rows_out_s, self.rows_cpu_s = time.perf_counter(), time.thread_time()
        for c in chunks:
            self._t.append(c.t)
            self._q.append(c.Q)
            self.next_row += len(c.t)
        return out[0] if len(out) == 1 else np.concatenate(out)

    # ------------------------------------------------------------ the end
    def _finish(self, why: str, near_s: float = -math.inf) -> np.ndarray:
        """The rest of the plan (started now if the hand is still waiting), written; then
        judged, and the end marker. The rows up to ``near_s`` (the ending observation's
        reach, as every observation's rows) are written first where no wrist turn can
        start among them (its earliest start, ``turn_from``, after them: the same rows),
        the turn and the rest after them: the latency is to those first rows."""
        m, cl, sp = self.motion, self.closing, self.stopper
        pose, h = self.pose, self.pl.hand
        self.replanner.closings.due(m, math.inf)
        t_b = max(self.written_to_s, 0.0)
        if not m.moving:
            if not sp.fixed:
                sp.stop_for(pose, t_b)
            T_m = m.move_time(self.pl.q_rest, sp.q_pre)
            m.start(t_b, sp.q_pre, T_m)
            m.set_closing(close_start(h, self.flight, self.C, pose.q_open, cl, pose.t_i,
                                      t_b + T_m, sp.pad_s(pose), self.ball.radius_m),
                          cl.duration_s)
        if not sp.fixed:
            sp.fix(pose, t_b)
        self.pose = pose = sp.met(pose, self.flight)
        stop = sp.stop
        t_static = max(m.close_start_s + m.close_s, m.seg.end_s, m.fingers_open_s,
                       stop.end_s if moves(stop) else -math.inf)
        t2 = np.array([t_static, t_static + self.dt])
        off = arm_offset(stop, t2, h.n)
        q_held = m.rows(t2)[0] + (0.0 if off is None else off[0])
        grasp = max(m.close_start_s + (cl.u_grasp or 1.0) * m.close_s,
                    pose.t_i + sp.pad_s(pose), m.seg.end_s)
        first_free_s = (self.next_row + sum(len(c.t) for c in self._ahead)) * self.dt
        near = (self._write_to(near_s) if math.isfinite(near_s)
                and self._last_row_s(near_s) <= max(grasp, first_free_s) else np.empty((0, 0)))
        out_s, out_cpu_s = self.rows_out_s, self.rows_cpu_s
        self.turn = sp.within_limits(live_turn(self.pl.dyn, q_held, grasp, first_free_s))
        if self.turn is not None:
            t_static = max(t_static, self.turn.end_s)
        rows = self._write_to(max(pose.t_i + HOLD_AFTER_S, t_static + self.dt))
        if len(near):
            self.rows_out_s, self.rows_cpu_s = out_s, out_cpu_s
            rows = near if not len(rows) else np.concatenate([near, rows])
        self.uncertainty = self.fit.intercept_sigma(self.flight, pose.t_i)  # (of the last
        # estimate only: what the plan reports)
        self.drag_estimate = (estimate_drag(self.fit.times, self.fit.positions, self.flight,
                                            self.ball) if self.drag else None)
        self.plan = self._judge(t_static)
        if self.plan.feasible:
            self.outcome = HELD
            g = self.plan
            self.reason = (f"grasp at t = {g.timing.grasp_t:.3f} s "
                           f"({', '.join(g.timing.grasp_fingers)}) of "
                           f"the ball estimated from {self.fit.n} observations; {why}")
        else:
            self.outcome = GIVEN_UP
            self.reason = reasons_text(self.plan.reasons) + f" ({why})"
        self.writer.close({"catch": self.outcome, "reason": self.reason,
                           "observations": self.fit.n,
                           "last_observation_s": float(self.fit.times[-1]),
                           "ball": self.flight.to_metadata(), "intercept_t": float(pose.t_i),
                           **({} if self.drag_estimate is None else
                              {"drag_estimate": self.drag_estimate.to_dict()})})
        return rows

    def _judge(self, t_static: float) -> CatchPlan:
        """The final plan: every row through the planner's self-check, the grasp forces."""
        pl, pose, fl, r, m = self.pl, self.pose, self.flight, self.ball.radius_m, self.motion
        t, Q = np.concatenate(self._t), np.concatenate(self._q)
        verdict = pl.rows.check(fl, self.C, r, t, Q, pose.t_i, t_static, self.rate_hz,
                                self.closing.reason is not None)
        reasons = ([Reason(CatchReason.GRASP, self.closing.reason)] if self.closing.reason
                   else []) + list(verdict.reasons)
        if pose.ic.reason:
            reasons.append(Reason(CatchReason.OUT_OF_REACH, pose.ic.reason))
        reasons += roll_reasons(pl.turn, fl, t, Q, pose.t_i)
        stop = self.stopper.stop
        if self.turn is not None or moves(stop):  # the ball is held where the rows end
            pose = replace(pose, q_closed=Q[-1].copy())
        fv = pl.forces(fl, pose, t, Q, r, soft=stop if moves(stop) else None)
        reasons += fv.reasons
        try:
            t_f = float(fl.time_at_x(float(self.C[0])))
        except InfeasibleError:
            t_f = None
        notes = [(f"live: {self.fit.n} observations (rms residual "
                  f"{1000 * self.fit.result.residual_rms:.1f} mm), the first plan from "
                  f"{self.first['observations']}")]
        if self.drag_estimate is not None:
            notes.append(f"live: {self.drag_estimate.describe()}")
        if self.replanner.kept_targets:
            notes.append(f"{self.replanner.kept_targets} re-aims could not reach their target at rest "
                         "before the ball within the limits: part of the way, or the older "
                         "target kept")
        return make_catch_plan(
            reasons=reasons, flight=fl, catch_point=self.C,
            T_world_root=pl.mount.T_world_root(self.C), base_hand=pl.base_hand, hand=pl.hand,
            rate_hz=self.rate_hz, throw=self._throw_info(), pose=pose, verdict=verdict,
            q_rest=pl.q_rest, q_open=self.stopper.q_pre, move_start_s=m.t_move,
            move_s=m.open_s,
            close_start_s=m.close_start_s, close_s=m.close_s, forces=fv.forces,
            t=t, Q=Q, t_info_s=float(self.fit.times[-1]), flight_time_s=t_f,
            uncertainty=self.uncertainty, notes=notes)


def _point(xyz: Any) -> np.ndarray:
    try:
        p = np.array(xyz, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise InputError(f"an observation's position must be 3 numbers, got {xyz!r}") from None
    if p.shape != (3,):
        raise InputError(f"an observation's position must be 3 numbers, got {p.size}")
    return p


def live_throw(flight: Flight, C: np.ndarray, ball: Ball, drag: bool, n_obs: int) -> ThrowInfo:
    """The throw a live estimate ``flight`` describes (its launch angle, the catch point
    ``C``, the ball, drag, ``n_obs`` observations)."""
    v = flight.v0
    return ThrowInfo(math.degrees(math.atan2(float(v[2]), math.hypot(v[0], v[1]))),
                     float(C[0]), float(C[2]), ball.name, drag, n_obs, live=True)
