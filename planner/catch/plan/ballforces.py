"""Stopping and holding the ball judged on a catch's rows (``CatchPlanner``'s forces step):
the check's own stopping rule (``planner.check.ball``: the pad, the hand's inertia, the
friction cone, every motor's headroom) and the grasp QP holding the ball in the closed hand
(``planner.catch.grasp``); the failures as reasons (too fast to stop, friction, torque)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from planner.catch import grasp as gq
from planner.catch.flight.path import Flight
from planner.catch.plan.arm import palm_target
from planner.catch.plan.geometry import interp_row
from planner.catch.plan.reasons import CatchReason, Reason
from planner.catch.plan.results import Forces, ForcesVerdict
from planner.catch.plan.softstop import SoftStop
from planner.check.criteria import GRASP_TOL_M
from planner.check.kinematics import Kinematics
from planner.hand.model import HandModel

if TYPE_CHECKING:
    from planner.catch.plan.planner import MeetPose


class BallForces:
    """The ball's forces on one reference-mounted hand (``hand``, ``kin``: the check's
    kinematics of it)."""

    def __init__(self, hand: HandModel, kin: Kinematics) -> None:
        self.hand, self.kin = hand, kin

    def forces(self, flight: Flight, pose: MeetPose, t: np.ndarray, Q: np.ndarray, r: float,
               grasp_t: float | None = None, soft: SoftStop | None = None) -> ForcesVerdict:
        """Stopping the ball (the check's rule on the rows, ``planner.check.ball.ball_loads``:
        the pad, the hand's inertia, the friction cone) and holding it in the closed hand
        (the grasp QP): their results (None where infeasible), the reasons, and the ball's
        centre on the palm at the intercept."""
        # (first used by the ending of a live session: not imported at its start)
        from planner.check.limits import RATE_TOL

        h, mass = self.hand, float(flight.ball.mass_kg)
        hold = None
        reasons = []
        q_i = interp_row(t, Q, pose.t_i)
        centre_i = palm_target(h, q_i, r)
        stop, contact = self._stop_load(flight, pose, t, Q, grasp_t)
        if stop.headroom < -RATE_TOL:  # the check's tolerance (one rule)
            # (the pad's force grows with the square of the ball's speed relative to the
            # palm: beside the flight's own speed it shows what the arm's recoil took off)
            reasons.append(Reason(CatchReason.TOO_FAST_TO_STOP, (
                f"too fast to stop (over the palm's {100 * h.pad_give_m:g} cm and the arm's "
                f"stopping motion): the ball meets the palm at {stop.speed_m_s:.2f} m/s "
                f"(its flight {float(np.linalg.norm(pose.v_i)):.2f} m/s), "
                f"{stop.force_n:.1f} N needs motor.{stop.motor} at "
                f"{abs(stop.torque_nm):.2f} N m > its {stop.limiting_part} limit "
                f"{stop.capacity_nm:.2f} N m")))
        if stop.cone_margin_n is not None and stop.cone_margin_n < 0:
            reasons.append(Reason(CatchReason.FRICTION, (
                f"friction (stopping the ball): the palm's force leaves its friction cone by "
                f"{-stop.cone_margin_n:.2f} N: the ball slides off")))
        try:
            hold = gq.grasp_forces(h, pose.q_closed, palm_target(h, pose.q_closed, r), r,
                                   gq.hold_force(mass), case="hold", tip_tol_m=GRASP_TOL_M,
                                   moment_balance=True)
        except gq.GraspTorqueError as e:
            reasons.append(Reason(CatchReason.TORQUE, f"torque (holding the ball): {e}"))
        except gq.GraspFrictionError as e:
            reasons.append(Reason(CatchReason.FRICTION, f"friction (holding the ball): {e}"))
        return ForcesVerdict(Forces(stop, hold, soft, contact), tuple(reasons), centre_i)

    def _stop_load(self, flight: Flight, pose: MeetPose, t: np.ndarray, Q: np.ndarray,
                   grasp_t: float | None):
        """The check's stopping load on the rows from the one before the intercept (only the
        ball's velocity enters it: its launch point needs no shift to the reference frame),
        and the impact and riding loads named apart (``ContactLoads``)."""
        # (first used by the ending of a live session: not imported at its start)
        from planner.check.ball import ball_load_instants, contact_loads, phase_loads

        k0 = max(0, int(np.searchsorted(t, pose.t_i, side="right")) - 2)
        b = flight.to_metadata()
        ball = {"p0": np.asarray(b["p0"], dtype=float), "v0": np.asarray(b["v0"], dtype=float),
                "radius": float(b["radius"]), "mass": float(b["mass"]),
                "drag": float(b["drag"])}
        _, palm = self.kin.frames(Q[k0:])
        inst = ball_load_instants(t[k0:], Q[k0:], self.kin, palm, ball, float(pose.t_i),
                                  self.hand.pad_give_m, grasp_t)
        stop = phase_loads(inst, t[-1], self.kin, Q[-1], palm[-1], ball["mass"])[0]
        return stop, contact_loads(inst)
