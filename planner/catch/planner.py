"""The catch planner of one hand and mount: what is built once (the reference-mounted
hand, its IK, joint groups, wrist geometry, rest pose, closing moves per ball size) and
the plan of one throw (``CatchPlanner.plan``: the steps of ``planner.catch.plan``)."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from itertools import pairwise
from typing import Any

import numpy as np

from planner.catch import grasp as gq
from planner.catch.arm import catch_joints, open_from, palm_target, rest_pose, zero_pose
from planner.catch.closing import close_start, make_closing
from planner.catch.flight import Flight
from planner.catch.geometry import interp_row, rot1
from planner.catch.intercept import Intercept, Wrist, closest_time, find_intercept, refine_time
from planner.catch.mount import CatchMount
from planner.catch.observe import FitResult, predict_intercept
from planner.catch.results import CatchPlan, Closing
from planner.catch.rowcheck import RowCheck
from planner.check.criteria import GRASP_TOL_M
from planner.errors import InfeasibleError, PlannerError
from planner.hand.model import HandModel
from planner.ik import HandIK
from planner.trajectory import Phase, phase_duration, sample

SIGNAL_S = 0.025  # seed (Markus): 25 ms of signal processing
PLAN_BUDGET_S = 0.005  # planning latency budget (bench target p99)
INTERCEPT_PLAN_TOL_M = 0.001  # what the planner aims for
HOLD_AFTER_S = 0.5  # rows until intercept_t + this


@dataclass(frozen=True)
class _Pose:
    """The hand meeting the ball: the intercept, the open and closed poses there, the
    time the ball reaches the palm on them, its velocity then, the IK's iterations."""

    ic: Intercept
    q_open: np.ndarray
    q_closed: np.ndarray
    t_i: float
    v_i: np.ndarray
    misalign_deg: float
    ik_iterations: int


class CatchPlanner:
    """Everything built once per hand and mount: reference-mounted hand, IK, poses,
    wrist geometry, closing tables (per ball radius, on first use)."""

    def __init__(self, hand: HandModel, mount: CatchMount) -> None:
        self.base_hand = hand
        self.mount = mount
        self.T_ref = mount.T_ref()
        self.hand = hand.mounted(self.T_ref)
        self.joints = catch_joints(self.hand)
        self.ik = HandIK(self.hand)
        self.q_zero = zero_pose(self.hand)
        self.wrist = Wrist(self.hand, self.joints)
        self.q_rest = rest_pose(self.hand, self.joints)
        self.near_m = self._tip_reach()
        self.rows = RowCheck(self.hand, self.T_ref, self.near_m)
        self._closings: dict[float, Closing] = {}

    def _tip_reach(self) -> float:
        """Bound on any fingertip's distance from palm_center over the joint box (m):
        the sum of each finger's segment lengths from the palm centre (triangle
        inequality), plus 1 cm."""
        h, q0 = self.hand, self.q_zero
        pc = h.palm_pose(q0)[:3, 3]
        tips = h.tip_positions(q0)
        best = 0.0
        for k, f in enumerate(h.fingers):
            pts = [pc] + [h.frame_pose(q0, j)[:3, 3] for j in h.spec.joints_of(f)] + [tips[k]]
            best = max(best, sum(float(np.linalg.norm(b - a)) for a, b in pairwise(pts)))
        return best + 0.01

    def closing(self, radius: float) -> Closing:
        """The closing move for a ball of ``radius`` (cached)."""
        key = round(float(radius), 9)
        c = self._closings.get(key)
        if c is None:
            c = self._closings[key] = make_closing(self.hand, self.ik, self.joints,
                                                   self.wrist, float(radius))
        return c

    # ------------------------------------------------------------ plan
    def plan(self, flight: Flight, catch_point: np.ndarray, rate_hz: float = 100.0,
             t_info: float = 0.0, throw: dict[str, Any] | None = None,
             flight_time_s: float | None = None, fit: FitResult | None = None) -> CatchPlan:
        """Plan the catch of ``flight`` with the hand mounted at ``catch_point`` (catch
        frame). ``t_info``: when the flight is known (last observation); the hand moves
        from ``t_info + SIGNAL_S + PLAN_BUDGET_S``. No file is written."""
        t0 = time.perf_counter()
        h = self.hand
        C = np.asarray(catch_point, dtype=float)
        r = float(flight.ball.radius_m)
        closing = self.closing(r)
        reasons = [closing.reason] if closing.reason else []
        reasons += [f"fingers in the way: the {f} tip passes {1000 * -gap:.1f} mm inside the "
                    "ball while the hand closes" for f, gap in zip(h.fingers, closing.min_gap_m)
                    if gap < 0]
        if flight_time_s is None:
            try:
                flight_time_s = float(flight.time_at_x(float(C[0])))
            except InfeasibleError:
                flight_time_s = None
        t_c = flight_time_s if flight_time_s is not None else closest_time(flight, C)
        pose = self.meet(flight, C, r, closing, find_intercept(self.wrist, flight, C, r, t_c))
        if pose.ic.reason:
            reasons.append(pose.ic.reason)
        # timing: the move to the open pose, then the closing move
        t_react = max(0.0, t_info) + SIGNAL_S + PLAN_BUDGET_S
        T_m = phase_duration(pose.q_open - self.q_rest, h.velocity, h.acceleration)
        ready = t_react + T_m
        if ready > pose.t_i:
            reasons.append(f"too fast: the open pre-catch pose is reached at {ready:.3f} s, "
                           f"{1000 * (ready - pose.t_i):.0f} ms after the ball "
                           f"(t = {pose.t_i:.3f} s)")
        s_c = close_start(h, flight, C, pose.q_open, closing, pose.t_i, ready,
                          gq.stop_time(pose.v_i), r)
        t, Q = self._rows(pose, closing, t_react, T_m, s_c, rate_hz)
        err, clear, g_t, g_f, check_reasons = self.rows.check(
            flight, C, r, t, Q, pose.t_i, s_c + closing.duration_s, rate_hz,
            closing.reason is not None)
        reasons += check_reasons
        stop, hold, force_reasons, centre_i = self.forces(flight, pose, t, Q, r)
        reasons += force_reasons
        unc = None if fit is None else uncertainty(fit, float(C[0] + centre_i[0]))
        return CatchPlan(
            feasible=not reasons, reasons=reasons, flight=flight, catch_point=C,
            T_world_root=self.mount.T_world_root(C), base_hand=self.base_hand,
            rate_hz=float(rate_hz), throw=dict(throw or {}), launch_speed=flight.speed,
            flight_time_s=flight_time_s, intercept_t=float(pose.t_i),
            intercept_point=flight.position(pose.t_i), arrival_velocity=pose.v_i,
            intercept_error_m=err, misalignment_deg=pose.misalign_deg, q_rest=self.q_rest,
            q_open=pose.q_open, q_closed=pose.q_closed, move_start_s=t_react, move_s=T_m,
            close_start_s=float(s_c), close_s=closing.duration_s, grasp_t=g_t,
            grasp_fingers=g_f, min_clearance_before_m=clear, stop=stop, hold=hold, t=t, q=Q,
            q_motor=h.motor_angles(Q), ik_iterations=pose.ik_iterations,
            t_info_s=float(t_info), uncertainty=unc, planning_s=time.perf_counter() - t0)

    def meet(self, flight: Flight, C: np.ndarray, r: float, closing: Closing,
             ic: Intercept) -> _Pose:
        """The hand meeting the ball at the intercept ``ic`` (``find_intercept``): its pose
        confirmed with placo (warm-started: usually zero or one iteration) and the
        intercept time refined on the confirmed pose."""
        h, j = self.hand, self.joints
        q_arm = self.q_zero.copy()
        q_arm[j.i_flex], q_arm[j.i_dev] = ic.theta, ic.dev
        if j.i_rail is not None:
            q_arm[j.i_rail] = ic.rail
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
        t_i = refine_time(flight, C, palm_target(h, q_open, r), ic.t)
        q_closed = q_open.copy()
        q_closed[j.finger_idx] = closing.q_closed[j.finger_idx]
        v_i = flight.velocity(t_i)
        n_i = h.palm_pose(q_open)[:3, 2]
        misalign = math.degrees(math.acos(np.clip(-(v_i @ n_i) / np.linalg.norm(v_i), -1, 1)))
        return _Pose(ic, q_open, q_closed, t_i, v_i, misalign, ik_iter)

    def _rows(self, pose: _Pose, closing: Closing, t_react: float, T_m: float, s_c: float,
              rate_hz: float) -> tuple[np.ndarray, np.ndarray]:
        """The rows: rest -> open from ``t_react`` (``T_m``), open -> closed from ``s_c``,
        until ``HOLD_AFTER_S`` after the intercept."""
        h = self.hand
        phases = [Phase(delta=pose.q_open - self.q_rest, duration_s=T_m),
                  Phase(delta=pose.q_closed - pose.q_open, duration_s=closing.duration_s)]
        n_rows = math.floor((pose.t_i + HOLD_AFTER_S) * rate_hz + 1e-9) + 1
        t = np.arange(n_rows) * (1.0 / rate_hz)
        Q = h.apply_couplings(sample(phases, np.array([t_react, s_c]), t, self.q_rest))
        return t, Q

    def forces(self, flight: Flight, pose: _Pose, t: np.ndarray, Q: np.ndarray, r: float):
        """Stopping the ball on the palm and holding it in the closed hand (the grasp QPs):
        their results (None where infeasible), the reasons, and the ball's centre on the
        palm at the intercept."""
        h, mass = self.hand, float(flight.ball.mass_kg)
        stop = hold = None
        reasons = []
        q_i = interp_row(t, Q, pose.t_i)
        centre_i = palm_target(h, q_i, r)
        try:
            stop = gq.grasp_forces(h, q_i, centre_i, r, gq.stop_force(mass, pose.v_i),
                                   case="stop", tip_tol_m=0.001, moment_balance=False)
        except InfeasibleError as e:
            reasons.append(f"{_kind(e)} (stopping the ball over {100 * gq.STOP_DISTANCE_M:g} "
                           f"cm): {e}")
        try:
            hold = gq.grasp_forces(h, pose.q_closed, palm_target(h, pose.q_closed, r), r,
                                   gq.hold_force(mass), case="hold", tip_tol_m=GRASP_TOL_M,
                                   moment_balance=True)
        except InfeasibleError as e:
            reasons.append(f"{_kind(e)} (holding the ball): {e}")
        return stop, hold, reasons, centre_i


def _kind(e: InfeasibleError) -> str:
    """'torque' when a motor's capacity is what fails, else 'friction' (no force split lies
    inside the contacts' friction cones)."""
    return "torque" if "needs motor." in str(e) else "friction"


def uncertainty(fit: FitResult, x_plane: float) -> dict[str, float] | None:
    try:
        t, _, cov, sig_t = predict_intercept(fit, x_plane)
    except PlannerError:
        return None
    return {"x_plane_m": x_plane, "t_s": t, "sigma_t_s": sig_t,
            "sigma_y_m": float(math.sqrt(max(cov[1, 1], 0.0))),
            "sigma_z_m": float(math.sqrt(max(cov[2, 2], 0.0)))}
