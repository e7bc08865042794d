"""The catch planner of one hand and mount: what is built once (the reference-mounted
hand, its IK, joint groups, wrist geometry, rest pose, closing moves per ball size) and
the plan of one throw (``CatchPlanner.plan``: the steps of ``planner.catch.plan.api``)."""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from itertools import pairwise

import numpy as np

from planner.catch.flight.observe import FitResult, predict_intercept
from planner.catch.flight.path import Flight
from planner.catch.plan.arm import (
    calm_move_time,
    catch_joints,
    move_time,
    open_from,
    palm_target_of,
    rest_pose,
    zero_pose,
)
from planner.catch.plan.ballforces import BallForces
from planner.catch.plan.closing import close_start, closed_pose, closing_from
from planner.catch.plan.closingtable import shipped_closed_pose
from planner.catch.plan.contactqp import ROLL_WEIGHT
from planner.catch.plan.geometry import rot1
from planner.catch.plan.intercept import Intercept, Wrist, closest_time, refine_time
from planner.catch.plan.mount import CatchMount
from planner.catch.plan.reasons import CatchReason, Reason, reasons_text
from planner.catch.plan.results import (
    CatchPlan,
    Closing,
    ForcesVerdict,
    Rows,
    ThrowInfo,
    make_catch_plan,
)
from planner.catch.plan.rowcheck import RowCheck
from planner.catch.plan.stopping import (
    COARSE_STOP,
    SoftStop,
    StopDynamics,
    StopGrid,
    plan_stop,
)
from planner.catch.plan.turnahead import (
    HoldStart,
    HoldTurn,
    RowsArgs,
    Turn,
    TurnMode,
    ahead_shift,
)
from planner.check.ballstop import pad_time_s
from planner.check.kinematics import Kinematics
from planner.errors import InfeasibleError, PlannerError
from planner.hand.model import HandModel
from planner.ik import HandIK
from planner.trajectory import Phase, sample

SIGNAL_S = 0.025  # seed (Markus): 25 ms of signal processing
PLAN_BUDGET_S = 0.005  # planning latency budget (bench target p99)
INTERCEPT_PLAN_TOL_M = 0.001  # what the planner aims for
HOLD_AFTER_S = 0.5  # rows until intercept_t + this
_CLOSE_STEP_S = 0.005  # a closing that would touch the arriving ball starts this much later
_CLOSE_TRIES = 8  # ... up to this many times
_NOT_THE_TURN = {CatchReason.OUT_OF_REACH, CatchReason.TOO_SOON}  # before the ball: no turn
# changes them (a plan failing only for these is not tried again without its turn)


@dataclass(frozen=True)
class MeetPose:
    """The hand meeting the ball: the intercept, the open and closed poses there, the
    time the ball reaches the palm on them, its velocity then, the IK's iterations."""

    ic: Intercept
    q_open: np.ndarray
    q_closed: np.ndarray
    t_i: float
    v_i: np.ndarray
    misalign_deg: float
    ik_iterations: int


@dataclass(frozen=True)
class MoveIn:
    """The move from rest to the pre-catch pose (``q_pre``: the open pose, the stopping
    motion's first offset on the arm): its duration, when the closing starts, and why the
    hand is not there in time (None: it is)."""

    q_pre: np.ndarray
    move_s: float
    close_start_s: float
    too_soon: Reason | None


def move_in(h: HandModel, dyn: StopDynamics, flight: Flight, C: np.ndarray, r: float, closing: Closing,
            pose: MeetPose, soft_stop: SoftStop, q_rest: np.ndarray, t_react: float) -> MoveIn:
    """The move to the pre-catch pose, starting at ``t_react``: due before the ball and the
    stopping motion's ramp; where it is in time, calmer (``StopDynamics.calm_move_time``)
    as long as it is still there before the ramp and the closing's start."""
    q_pre = pose.q_open.copy()
    q_pre[list(soft_stop.arm)] += soft_stop.first_offset
    move_s = move_time(dyn, q_rest, q_pre)
    ready = t_react + move_s
    due = min(pose.t_i, soft_stop.start_s if np.any(soft_stop.qd) else pose.t_i)
    too_soon = None
    if ready > due:
        too_soon = Reason(CatchReason.TOO_SOON,
                          f"too fast: the open pre-catch pose is reached at {ready:.3f} s, "
                          f"{1000 * (ready - pose.t_i):.0f} ms after the ball "
                          f"(t = {pose.t_i:.3f} s)")
    s_c = close_start(h, flight, C, pose.q_open, closing, pose.t_i, ready,
                      pad_time_s(soft_stop.v_rel, h.pad_give_m), r)
    if too_soon is None:
        move_s = calm_move_time(dyn, q_rest, q_pre, t_react, min(s_c, due))
    return MoveIn(q_pre, move_s, s_c, too_soon)


def tip_reach_m(h: HandModel, q0: np.ndarray) -> float:
    """Bound on any fingertip's distance from palm_center over the joint box (m): the sum
    of each finger's segment lengths from the palm centre at ``q0`` (triangle inequality),
    plus 1 cm."""
    pc = h.palm_pose(q0)[:3, 3]
    tips = h.tip_positions(q0)
    best = 0.0
    for k, f in enumerate(h.fingers):
        pts = [pc] + [h.frame_pose(q0, j)[:3, 3] for j in h.spec.joints_of(f)] + [tips[k]]
        best = max(best, sum(float(np.linalg.norm(b - a)) for a, b in pairwise(pts)))
    return best + 0.01


class CatchPlanner:
    """Everything built once per hand and mount: reference-mounted hand, IK, poses,
    wrist geometry, closing tables (per ball radius, on first use)."""

    def __init__(self, hand: HandModel, mount: CatchMount) -> None:
        self.base_hand = hand
        self.mount = mount
        self.T_ref = mount.T_ref()
        self.hand = hand.mounted(self.T_ref).within_margins()  # (every row a stop margin
        # inside the hard stops: ``check``'s ``joint_stop_margin``)
        self.joints = catch_joints(self.hand)
        self.ik = HandIK(self.hand)
        self.q_zero = zero_pose(self.hand)
        self.wrist = Wrist(self.hand, self.joints)
        self.q_rest = rest_pose(self.hand, self.joints)
        self.near_m = tip_reach_m(self.hand, self.q_zero)
        self.rows = RowCheck(self.hand, self.T_ref, self.near_m)
        self.kin = Kinematics(self.base_hand, self.T_ref)
        self.dyn = StopDynamics(self.hand, self.joints, self.kin)
        self.turn = HoldTurn(self.hand, self.joints, self.dyn, self.kin, self.q_rest, self._rows)
        # the rig's reach axis moving too (``plan``: where the arm alone fails)
        self.rig = catch_joints(self.hand, reach=True)
        self.rig_dyn = StopDynamics(self.hand, self.rig, self.kin)
        self.rig_turn = HoldTurn(self.hand, self.rig, self.rig_dyn, self.kin, self.q_rest,
                                 self._falling_rows)
        # the arm alone meeting the ball, the hand then falling with it on the reach axis
        # (``plan``: where the arm alone loses the ball to the roll and the reach's plan fails)
        self.arm_fall_turn = HoldTurn(self.hand, self.joints, self.dyn, self.kin, self.q_rest,
                                      self._falling_rows)
        self.ball_forces = BallForces(self.hand, self.kin)
        self._closings: dict[tuple[float, bool], Closing] = {}

    def closing(self, radius: float, bodies: bool = True) -> Closing:
        """The closing move for a ball of ``radius`` (cached); ``bodies``: the fingers'
        bodies kept clear of the ball, not only their tips (``make_closing``; the closed pose
        shipped where ``closingtable`` has it)."""
        key = (round(float(radius), 9), bool(bodies))
        c = self._closings.get(key)
        if c is None:
            h, j, w, r = self.hand, self.joints, self.wrist, float(radius)
            q = shipped_closed_pose(h, j, w, r, bool(bodies))  # (``closingtable``)
            if q is None:
                q = closed_pose(h, self.ik, j, w, r, bool(bodies))
            c = self._closings[key] = closing_from(h, j, w, r, q)
        return c

    # ------------------------------------------------------------ plan
    def plan(self, flight: Flight, catch_point: np.ndarray, rate_hz: float = 100.0,
             t_info: float = 0.0, throw: ThrowInfo | None = None,
             flight_time_s: float | None = None, fit: FitResult | None = None,
             soft: bool = True) -> CatchPlan:
        """Plan the catch of ``flight`` with the hand mounted at ``catch_point`` (catch
        frame). ``t_info``: when the flight is known (last observation); the hand moves
        from ``t_info + SIGNAL_S + PLAN_BUDGET_S``. No file is written. ``soft``: the
        soft catch (``planner.catch.plan.stopping``), or the palm waiting at rest when that
        alone passes the self-check (a palm that moves can bring the ball to a fingertip
        the closing would miss otherwise); False: the palm at rest. The hold (the roll term
        of the contact speeds, the wrist's turn: ``planner.catch.plan.stopping``): the turn from
        the grasp on or earlier, so that the ball does not roll off the palm's wrist side before
        the turn has levelled it (``TurnMode.AHEAD``: ``HoldTurn.ahead_rows``), else from the grasp on
        (``TurnMode.EARLY``, when the rule started it earlier), else after the arm has stopped
        (``TurnMode.LATE``), else none (the plan without the hold) -- the first of those that is
        feasible. Where every plan is infeasible and too fast to stop among its reasons, they
        are planned again with the soft stop searched in finer steps, then with per-joint
        ramps and recoils (``planner.catch.plan.stopstages``)."""
        t0 = time.perf_counter()
        args = (flight, catch_point, rate_hz, t_info, throw, flight_time_s, fit)
        stops: dict = {}  # this plan's stops (``stop_of``), made once each
        plan = self._on_the_rig(args, soft, stops=stops)
        if plan.feasible:
            return replace(plan, planning_s=time.perf_counter() - t0)
        if soft:
            from planner.catch.plan.stopstages import joint_stop_fallbacks  # (a planned
            # catch's fallbacks: not imported at a live session's start)

            finer = joint_stop_fallbacks(lambda g: self._on_the_rig(args, soft, g, stops), plan)
            if finer.feasible:
                return replace(finer, planning_s=time.perf_counter() - t0)
        if CatchReason.GRASP in plan.reason_kinds:
            # the closing with the fingers' bodies clear of the ball grasps a little later
            # (its fingertips end a few mm further out): the fingertips' closing, if that is
            # what was too late
            other = self._plans(args, soft, False, stops=stops)
            if other.feasible:
                plan = replace(other, notes=other.notes + (
                    "the fingertips' closing (bodies not kept clear of the ball): the "
                    "closing failed (" + reasons_text(plan.reasons) + ")",))
        if soft and not plan.feasible:  # the palm turned up past facing the ball (the roll)
            from planner.catch.plan.palmup import palm_up_fallback

            plan = palm_up_fallback(lambda **kw: self._plans(args, soft, True, stops=stops, **kw), plan,
                                    self.wrist, self.rig.i_reach is not None,
                                    lambda p: stop_stages(self, p))
        if soft:
            plan = stop_stages(self, plan)
        return replace(plan, planning_s=time.perf_counter() - t0)

    def _on_the_rig(self, args: tuple, soft: bool, grid: StopGrid = COARSE_STOP,
                    stops: dict | None = None) -> CatchPlan:
        """``_plans`` of the arm alone, then (where infeasible) ``reach_fallbacks`` on the
        rig's reach axis; ``grid``: the soft stop's search steps; ``stops``: ``stop_of``'s."""
        plan = self._plans(args, soft, True, grid=grid, stops=stops)
        if not plan.feasible and soft and self.rig.i_reach is not None:
            plan = reach_fallbacks(lambda **kw: self._plans(args, soft, True, grid=grid,
                                                            stops=stops, **kw), plan)
        return plan

    def _plans(self, args: tuple, soft: bool, bodies: bool, rig: bool = False,
               fall: bool = False, grid: StopGrid = COARSE_STOP, stops: dict | None = None
               ) -> CatchPlan:
        """``plan``'s fallbacks (the turn's modes, the palm at rest) with one closing;
        ``rig``: the reach axis moves too; ``grid``: the soft stop's search steps."""
        plan, ahead = self._plan(*args, soft=soft, bodies=bodies, rig=rig, fall=fall,
                                 grid=grid, stops=stops)
        for mode in ((TurnMode.EARLY,) if ahead else ()) + (TurnMode.LATE, None):
            if plan.feasible or set(plan.reason_kinds) <= _NOT_THE_TURN:
                break
            other = self._plan(*args, soft=soft, turn_mode=mode, bodies=bodies, rig=rig,
                               fall=fall, grid=grid, stops=stops)[0]
            if other.feasible:
                what = {TurnMode.EARLY: "the turn from the grasp", TurnMode.LATE:
                        "after the arm has stopped", None: "no turn to hold the ball"}[mode]
                plan = replace(other, notes=other.notes + (
                    f"{what}: the earlier turn failed (" + reasons_text(plan.reasons) + ")",))
        if soft and not plan.feasible and not rig:
            still = self._plan(*args, soft=False, bodies=bodies, stops=stops)[0]
            if still.feasible:
                plan = replace(still, notes=still.notes + (
                    "the palm waits at rest: the soft catch failed (" +
                    reasons_text(plan.reasons) + ")",))
        return plan

    def _plan(self, flight: Flight, catch_point: np.ndarray, rate_hz: float, t_info: float,
              throw: ThrowInfo | None, flight_time_s: float | None,
              fit: FitResult | None, soft: bool, turn_mode: TurnMode | None = TurnMode.AHEAD,
              bodies: bool = True, rig: bool = False, fall: bool = False,
              grid: StopGrid = COARSE_STOP, stops: dict | None = None
              ) -> tuple[CatchPlan, bool]:
        """``plan`` with the soft catch on or off, the wrist's turn by the roll rule
        (TurnMode.AHEAD), from the grasp (TurnMode.EARLY), after the arm's stop (TurnMode.LATE) or none
        (None: nor the contact speeds' roll term); and whether the turn starts before the
        grasp (the roll rule moved it). Without the soft catch the palm waits for the ball at
        rest: no turn under way then (the roll rule's turn is the grasp's). ``rig``: the
        rig's reach axis moves too (``catch_joints(..., reach=True)``): the intercept may put
        the palm square to the throw on it, and the stopping motion uses it. ``fall``: the
        rows fall with the ball on the reach axis once it lands (``planner.catch.plan.drop``).
        ``grid``: the soft stop's search steps (``plan_stop``); ``stops``: the stops this
        ``plan`` has made (``stop_of``)."""
        t0 = time.perf_counter()
        if not soft and turn_mode == TurnMode.AHEAD:
            turn_mode = TurnMode.EARLY
        dyn, hold = (self.rig_dyn, self.rig_turn) if rig else \
            (self.dyn, self.arm_fall_turn if fall else self.turn)
        h, C = self.hand, np.asarray(catch_point, dtype=float)
        r = float(flight.ball.radius_m)
        closing = self.closing(r, bodies)
        reasons = [Reason(CatchReason.GRASP, closing.reason)] if closing.reason else []
        reasons += [Reason(CatchReason.FINGERS, f"fingers in the way: the {f} tip passes "
                           f"{1000 * -gap:.1f} mm inside the ball while the hand closes")
                    for f, gap in zip(h.fingers, closing.min_gap_m) if gap < 0]
        if flight_time_s is None:
            try:
                flight_time_s = float(flight.time_at_x(float(C[0])))
            except InfeasibleError:
                flight_time_s = None
        t_c = flight_time_s if flight_time_s is not None else closest_time(flight, C)
        t_react = max(0.0, t_info) + SIGNAL_S + PLAN_BUDGET_S

        def ready_by(q_pre: np.ndarray) -> float:
            return t_react + move_time(dyn, self.q_rest, q_pre)

        rw = ROLL_WEIGHT if turn_mode else 1.0
        ic, _, soft_stop = stop_of(stops, (rig, soft, bodies, rw, grid), lambda: plan_stop(
            dyn, self.wrist, flight, C, r, self.q_zero, closing, t_c, ready_by, 1.0 / rate_hz,
            soft, rw, grid=grid))
        pose = self.meet(flight, C, r, closing, ic)
        soft_stop = replace(soft_stop, t_i=float(pose.t_i))
        if pose.ic.reason:
            reasons.append(Reason(CatchReason.OUT_OF_REACH, pose.ic.reason))
        move = move_in(h, dyn, flight, C, r, closing, pose, soft_stop, self.q_rest, t_react)
        reasons += [move.too_soon] if move.too_soon else []
        q_pre, T_m, s_c = move.q_pre, move.move_s, move.close_start_s
        turn0 = hold.hold(pose, soft_stop) if turn_mode else HoldStart(np.zeros(h.n), 0.0)
        turn, t, Q, T_m, s_c, verdict = closing_rows(
            self.rows, flight, C, hold, turn0, turn_mode, RowsArgs(pose, q_pre, soft_stop, closing, t_react, T_m,
                                                  s_c, rate_hz, float(flight.ball.inertia_ratio) if fall else None))
        reasons += verdict.reasons
        reasons += hold.roll_reasons(flight, t, Q, pose.t_i)
        ahead = turn.profiles is not None  # the roll rule's turn under way at the intercept: the
        if ahead:  # pre-catch pose short of the intercept pose by the turn's travel before it
            q_pre = q_pre + ahead_shift(turn.profiles, pose.t_i, h.n)
        q_closed = pose.q_closed.copy()
        q_closed[list(soft_stop.arm)] += soft_stop.last_offset
        q_closed += turn.delta  # the pose the ball is held in (the turn ends at rest)
        pose = replace(pose, q_closed=q_closed)
        fv = self.forces(flight, pose, t, Q, r, verdict.grasp_t,
                         soft_stop if np.any(soft_stop.qd) else None)
        reasons += fv.reasons
        unc = None if fit is None else uncertainty(fit, float(C[0] + fv.centre_i[0]))
        return make_catch_plan(
            reasons=reasons, flight=flight, catch_point=C,
            T_world_root=self.mount.T_world_root(C), base_hand=self.base_hand, hand=h,
            rate_hz=rate_hz, throw=throw, pose=pose, verdict=verdict, q_rest=self.q_rest,
            q_open=q_pre, move_start_s=t_react, move_s=T_m, close_start_s=s_c,
            close_s=closing.duration_s,
            forces=fv.forces,
            t=t, Q=Q, t_info_s=float(t_info), flight_time_s=flight_time_s, uncertainty=unc,
            notes=_turn_note(turn, pose.t_i), planning_s=time.perf_counter() - t0), ahead

    def meet(self, flight: Flight, C: np.ndarray, r: float, closing: Closing,
             ic: Intercept) -> MeetPose:
        """The hand meeting the ball at the intercept ``ic`` (``find_intercept``): its pose
        confirmed with placo (warm-started: usually zero or one iteration) and the
        intercept time refined on the confirmed pose."""
        h, j = self.hand, self.rig
        q_arm = self.q_zero.copy()
        q_arm[j.i_flex], q_arm[j.i_dev] = ic.theta, ic.dev
        if j.i_rail is not None:
            q_arm[j.i_rail] = ic.rail
        if j.i_reach is not None:
            q_arm[j.i_reach] = ic.reach
        q_open = open_from(h, j, q_arm, closing.q_closed)
        ik_iter = 0
        if ic.reason is None:
            b_i = flight.position(ic.t) - C
            n_des = rot1(self.wrist.e_f, ic.theta, self.wrist.n0)
            # the fingers are not masked (their hard coupling tasks would lose rank); the
            # palm does not depend on them and the posture/stay tasks hold them
            res = self.ik.solve_palm(b_i, n_des, q_open, q_open, offset_m=r, max_iter=5,
                                     tol_m=INTERCEPT_PLAN_TOL_M, tol_rad=0.02)
            ik_iter = res.iterations
            if res.iterations:
                q_open = open_from(h, j, res.q, closing.q_closed)
        # intercept time on the confirmed pose: closest approach to palm_center + r n
        P = h.palm_pose(q_open)
        t_i = refine_time(flight, C, palm_target_of(P, r), ic.t)
        q_closed = q_open.copy()
        q_closed[j.finger_idx] = closing.q_closed[j.finger_idx]
        v_i = flight.velocity(t_i)
        n_i = P[:3, 2]
        misalign = math.degrees(math.acos(np.clip(-(v_i @ n_i) / np.linalg.norm(v_i), -1, 1)))
        return MeetPose(ic, q_open, q_closed, t_i, v_i, misalign, ik_iter)

    def _rows(self, a: RowsArgs, turn: Turn) -> tuple[np.ndarray, np.ndarray]:
        """The rows (``a``): rest -> the pre-catch pose ``q_pre`` from ``t_react`` (``T_m``), the arm's
        stopping motion (``stop``), open -> closed fingers from ``s_c``, the wrist's ``turn``
        (``Turn``) that holds the ball, until ``HOLD_AFTER_S`` after
        the intercept (and the arm at rest). The turn is a min-jerk move, or (its profiles,
        ``SoftStop``s of the flexion: ``planner.catch.plan.turnahead``) under way at the intercept:
        the move-in then ends short of ``q_pre`` by the turn's travel before the ball."""
        pose, q_pre, stop, closing = a.pose, a.q_pre, a.stop, a.closing
        t_react, T_m, s_c, rate_hz = a.t_react, a.T_m, a.s_c, a.rate_hz
        h = self.hand
        delta, T_turn, t_turn, prof = turn.delta, turn.duration_s, turn.start_s, turn.profiles
        arm = list(stop.arm)
        shift = ahead_shift(prof, pose.t_i, h.n) if prof is not None else np.zeros(h.n)
        phases = [Phase(delta=q_pre + shift - self.q_rest, duration_s=T_m),
                  Phase(delta=pose.q_closed - pose.q_open, duration_s=closing.duration_s)]
        starts = [t_react, s_c]
        t_end = max(pose.t_i + HOLD_AFTER_S, stop.end_s + 2.0 / rate_hz)
        if T_turn > 0 and prof is None:
            phases.append(Phase(delta=delta, duration_s=T_turn))
            starts.append(t_turn)
        if T_turn > 0:
            t_end = max(t_end, t_turn + T_turn + 2.0 / rate_hz)
        n_rows = math.floor(t_end * rate_hz + 1e-9) + 1
        t = np.arange(n_rows) * (1.0 / rate_hz)
        Q = sample(phases, np.array(starts), t, self.q_rest)
        Q += stop.offset(t, h.n)
        Q[:, arm] -= stop.first_offset
        for p in prof or ():
            Q += p.offset(t, h.n) - p.offset(np.array([-math.inf]), h.n)[0]
        return t, h.apply_couplings(Q)

    def _falling_rows(self, a: RowsArgs, turn: Turn) -> tuple[np.ndarray, np.ndarray]:
        """``_rows`` with the hand falling with the ball on the reach axis after it lands
        (``planner.catch.plan.drop``)."""
        t, Q = self._rows(a, turn)
        if a.inertia_ratio is None or self.rig.i_reach is None:
            return t, Q
        # (first used by the ending of a live session: not imported at its start)
        from planner.catch.plan.drop import add_drop

        return t, add_drop(self.rig_dyn, t, Q, self.rig.i_reach, float(a.pose.t_i),
                           a.pose.v_i, float(a.closing.radius), a.inertia_ratio)

    def forces(self, flight: Flight, pose: MeetPose, t: np.ndarray, Q: np.ndarray, r: float,
               grasp_t: float | None = None, soft: SoftStop | None = None) -> ForcesVerdict:
        """``BallForces.forces`` of this hand (stopping and holding the ball judged)."""
        return self.ball_forces.forces(flight, pose, t, Q, r, grasp_t, soft)


def reach_fallbacks(plans, plan: CatchPlan) -> CatchPlan:
    """``CatchPlanner.plan``'s fallbacks on the rig's reach axis for ``plan`` (the arm
    alone's, infeasible); ``plans(rig=, fall=)``: ``CatchPlanner._plans`` of the throw. The
    reach moves too (the palm square to the throw on it); where that loses the ball to the
    roll, the hand falls with the ball on the reach axis once it lands; where the arm alone
    loses it to the roll and those fail, the arm alone meets the ball (the reach held until
    it lands) and the hand then falls with it (``CatchPlanner.arm_fall_turn``). The first
    feasible, with a note naming what failed; else ``plan`` with their reasons in a note."""
    other = plans(rig=True)
    fell_why = ""
    if not other.feasible and CatchReason.ROLL in other.reason_kinds:
        # the hand falling with the ball on the reach axis while the wrist turns
        fell = plans(rig=True, fall=True)
        fell_why = "; the hand falling with the ball on it: " + reasons_text(fell.reasons)
        if fell.feasible:
            other = replace(fell, notes=fell.notes + (
                "the hand falls with the ball on the reach axis while the wrist turns: "
                "on the reach without the fall " + reasons_text(other.reasons),))
    if not other.feasible and CatchReason.ROLL in plan.reason_kinds:
        # the arm alone meets the ball, then the hand falls with it on the reach axis: where
        # the reach's own intercept fails (too fast to stop there, or the roll with the fall)
        fell = plans(fall=True)
        if fell.feasible:
            return replace(fell, notes=fell.notes + (
                "the arm alone meets the ball, the hand then falls with it on the "
                "reach axis: without the fall " + reasons_text(plan.reasons)
                + "; with the rig's reach axis moving too: "
                + reasons_text(other.reasons) + fell_why,))
        fell_why += "; the arm alone, the hand falling on the reach axis: " + \
            reasons_text(fell.reasons)
    if other.feasible:
        return replace(other, notes=other.notes + (
            "the rig's reach axis moves (the palm square to the throw on it where it "
            "reaches): the arm alone failed (" + reasons_text(plan.reasons) + ")",))
    return replace(plan, notes=plan.notes + (
        "with the rig's reach axis moving too: " + reasons_text(other.reasons) + fell_why,))


def closing_rows(rows: RowCheck, flight: Flight, C: np.ndarray, hold: HoldTurn,
             turn0: HoldStart, turn_mode: TurnMode | None, rows_args: RowsArgs):
    """The rows with the wrist's turn as ``turn_mode`` says and their self-check (``rows``:
    ``RowCheck.check``); ``close_start`` sees the palm at rest: a palm moving with the ball
    keeps it near the fingers longer, so the closing waits a little more when a tip meets
    it. Returns the turn, the rows, the move-in's duration, the closing's start and the
    self-check's results; ``hold``: the turn's choices (the arm's joints it moves with)."""
    pose, stop, closing = rows_args.pose, rows_args.stop, rows_args.closing
    s_c = rows_args.s_c
    r = float(flight.ball.radius_m)
    for _ in range(_CLOSE_TRIES):
        args = replace(rows_args, s_c=s_c)
        if turn_mode == TurnMode.AHEAD:
            made = hold.ahead_rows(turn0, args, flight)
        else:
            made = hold.turned_rows(turn0, turn_mode, args)
        turn, t, Q, T_used = made.turn, made.t, made.Q, made.T_m
        t_static = max(s_c + closing.duration_s, stop.end_s, turn.start_s + turn.duration_s)
        checked = rows.check(flight, C, r, t, Q, pose.t_i, t_static, rows_args.rate_hz,
                             closing.reason is not None)
        if all(x.kind is not CatchReason.FINGERS for x in checked.reasons) or \
                not np.any(stop.qd) or s_c >= pose.t_i:
            break
        s_c = min(pose.t_i, s_c + _CLOSE_STEP_S)
    return turn, t, Q, T_used, s_c, checked


def stop_of(stops: dict | None, key: tuple, make: Callable[[], tuple]) -> tuple:
    """``make()`` (``plan_stop``'s result), made once per ``key`` within one
    ``CatchPlanner.plan`` (``stops``, that plan's; None: made anew): the same throw's stop
    for the same hand joints, soft catch, closing, roll weight and grid is the same stop,
    and the turn's modes (three of them with one roll weight), the hand falling on the
    reach axis and the fallbacks' plans ask for it again."""
    if stops is None:
        return make()
    if key not in stops:
        stops[key] = make()
    return stops[key]


def _turn_note(turn: Turn, t_i: float) -> tuple[str, ...]:
    """The plan's note on a turn under way at the intercept (the roll rule's), else none."""
    if turn.profiles is None:
        return ()
    return ((f"the wrist's turn under way at {np.abs(turn.profiles[0].qd).max():.1f} rad/s "
            f"when the ball lands (from {1000 * (t_i - turn.start_s):.0f} ms before it): from the grasp the "
            "ball would roll off the palm's wrist side"),)


def uncertainty(fit: FitResult, x_plane: float) -> dict[str, float] | None:
    try:
        t, _, cov, sig_t = predict_intercept(fit, x_plane)
    except PlannerError:
        return None
    return {"x_plane_m": x_plane, "t_s": t, "sigma_t_s": sig_t,
            "sigma_y_m": float(math.sqrt(max(cov[1, 1], 0.0))),
            "sigma_z_m": float(math.sqrt(max(cov[2, 2], 0.0)))}


def stop_stages(pl: CatchPlanner, plan: CatchPlan) -> CatchPlan:
    """``plan``'s "too fast to stop" judged by the bound over every stop (a hard limit, or
    "no stop found"), then the stop optimised on its rows where the bound leaves one."""
    if CatchReason.TOO_FAST_TO_STOP not in plan.reason_kinds or not len(plan.rows.t):
        return plan
    from planner.catch.plan.stopbound import bounded_reasons  # (where the stops all failed)

    k, b = int(np.argmin(np.abs(plan.rows.t - plan.intercept.t_s))), plan.flight.ball
    plan = replace(plan, reasons=bounded_reasons(plan.reasons, pl.rig_dyn, plan.rows.q[k],
                   plan.intercept.arrival_velocity, b.mass_kg, b.radius_m))
    return optimised_stop_plan(pl, plan) if CatchReason.NO_STOP in plan.reason_kinds else plan


def optimised_stop_plan(pl: CatchPlanner, plan: CatchPlan) -> CatchPlan:
    """``CatchPlanner.plan``'s last stage for ``plan`` (infeasible, "no stop found" among its
    reasons): the stop optimised on its rows (``optimise_stop``, the arm joints of the rig,
    ``pl.rig_dyn.arm``), the rows judged again by the planner's own rules (the check's
    stopping rule and the holding QP, the rows' self-check, the roll rule;
    ``planner.catch.plan.stoprows``). Where "no stop found" is the plan's only reason and
    the new rows pass them all: the plan on those rows, feasible, noted with the check's
    load. Else ``plan`` (its rows as they were) with the optimum's numbers in its "no stop
    found" reason."""
    # (a planned catch's last stage: not imported at a live session's start)
    from planner.catch.plan.stoprows import RowStopModel, ball_of, optimise_stop
    from planner.trajfile import as_written

    t, Q, flight = plan.rows.t, plan.rows.q, plan.flight
    t_i, grasp_t = float(plan.intercept.t_s), plan.timing.grasp_t
    model = RowStopModel(pl.kin, list(pl.rig_dyn.arm), ball_of(flight), t_i, grasp_t)
    rs = optimise_stop(model, t, Q)
    st = rs.stop
    said = (f"the stop optimised on the rows (the check's rule, linearised, at the plan's "
            f"rate): motor.{st.motor} at {abs(st.torque_nm):.2f} N m of its "
            f"{st.capacity_nm:.2f} ({1.0 - st.headroom:.2f} of it)"
            + (f"; {rs.failure}" if rs.failure else ""))
    only = set(plan.reason_kinds) == {CatchReason.NO_STOP}
    if rs.Q is not None and st.headroom >= 0.0 and only:
        r = float(flight.ball.radius_m)
        pose = MeetPose(None, plan.poses.q_open, plan.poses.q_closed, t_i,
                        plan.intercept.arrival_velocity, plan.intercept.misalignment_deg,
                        plan.ik_iterations)
        Qn = rs.Q
        Qw = as_written(Qn)  # (judged at the file's 6 decimals, as the check reads them: at
        # 1 ms rows their second differences move a light riding ball's force by 0.07 N)
        fv = pl.forces(flight, pose, t, Qw, r, grasp_t, plan.forces.soft)
        moving = np.flatnonzero(np.any(np.diff(Qn, axis=0) != 0.0, axis=1))
        t_static = float(t[moving[-1] + 1]) if moving.size else float(t[0])
        verdict = pl.rows.check(flight, plan.catch_point, r, t, Qw, t_i, t_static,
                                plan.rate_hz, False)
        rolled = pl.turn.roll_reasons(flight, t, Qw, t_i)
        reasons = list(fv.reasons) + list(verdict.reasons) + rolled
        if not reasons:
            return replace(
                plan, feasible=True, reasons=(), forces=fv.forces,
                rows=Rows(t, Qn, pl.hand.motor_angles(Qn)),
                intercept=replace(plan.intercept, error_m=verdict.error_m),
                timing=replace(plan.timing, grasp_t=verdict.grasp_t,
                               grasp_fingers=verdict.grasp_fingers,
                               min_clearance_before_m=verdict.clearance_m),
                notes=plan.notes + (f"{said}; the planner's stops: {plan.reasons[0].detail}",))
        said += "; its rows fail: " + "; ".join(x.detail for x in reasons)
    out = tuple(Reason(x.kind, f"{x.detail}; {said}") if x.kind is CatchReason.NO_STOP else x
                for x in plan.reasons)
    return replace(plan, reasons=out)
