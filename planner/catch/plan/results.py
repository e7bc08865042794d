"""What a catch plan is: the closing move of a ball size, the plan of one throw, and what
``plan_catch`` returns."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING, Any

import numpy as np

from planner.catch import grasp as gq
from planner.catch.flight.path import Flight
from planner.catch.plan.reasons import CatchReason, Reason, reasons_text
from planner.catch.plan.rowcheck import RowVerdict
from planner.check.criteria import GRASP_WINDOW_S
from planner.hand.model import HandModel
from planner.trajfile import KeptText

if TYPE_CHECKING:
    from planner.catch.plan.softstop import SoftStop


@dataclass(frozen=True)
class Closing:
    """The closing move for one ball radius (palm-frame data, throw-independent)."""

    radius: float
    q_closed: np.ndarray  # full configuration at the reference wrist pose
    duration_s: float
    u_grasp: float | None  # fraction of the move after which the grasp holds (None: never)
    tip_dist_m: np.ndarray  # (5,) closed fingertip distance from the ball centre
    grasp_fingers: tuple[str, ...]
    u: np.ndarray  # (K,) move fractions of the table
    tips_pc: np.ndarray  # (K, 5, 3) fingertips in the palm_center frame
    reason: str | None
    reach_m: float  # farthest fingertip from the ball centre during the move
    min_gap_m: np.ndarray  # (5,) closest each fingertip comes to the ball's surface
    bodies_pc: np.ndarray  # (K, G, P, 3) the fingers' bodies, shape by shape (pad spheres,
    # segments' capsules), as points (``FingerBodies.points``) in the palm_center frame
    bodies_r_m: np.ndarray  # (G, P) each point's radius
    bound_pc: np.ndarray  # (K, G, 3) a sphere around each shape: its centre
    bound_r_m: np.ndarray  # (K, G) ... and radius (the points' radii included)


@dataclass(frozen=True)
class ThrowInfo:
    """The throw as asked: its angle and where it passes (the live one's, the angle of its
    last estimate), the ball, drag, the observations fitted (None: predicted)."""

    angle_deg: float
    dist_m: float
    height_m: float
    ball: str
    drag: bool
    observations: int | None
    live: bool = False

    def to_dict(self) -> dict[str, Any]:
        out = {"angle_deg": self.angle_deg, "dist_m": self.dist_m, "height_m": self.height_m,
               "ball": self.ball, "drag": self.drag, "observations": self.observations}
        if self.live:
            out["live"] = True
        return out


@dataclass(frozen=True)
class InterceptInfo:
    """Where and when the palm meets the ball (catch frame)."""

    t_s: float
    point_m: np.ndarray  # ball centre at t_s
    arrival_velocity: np.ndarray
    error_m: float  # the palm's distance from the ball then, on the rows (the check's rule)
    misalignment_deg: float  # palm normal off the ball's path
    launch_speed_m_s: float
    flight_time_s: float | None  # time at x = dist (None: never)


@dataclass(frozen=True)
class Timing:
    """The catch's timeline (s from the launch)."""

    move_start_s: float
    move_s: float
    close_start_s: float
    close_s: float
    grasp_t: float | None  # first row time with the grasp
    grasp_fingers: tuple[str, ...]
    min_clearance_before_m: float  # min fingertip distance to the ball surface before it
    t_info_s: float  # the last observation (0: predicted)

    @property
    def ready_s(self) -> float:
        return self.move_start_s + self.move_s


@dataclass(frozen=True)
class Poses:
    """The hand at rest, open (the pre-catch pose) and closed (holding the ball)."""

    q_rest: np.ndarray
    q_open: np.ndarray
    q_closed: np.ndarray


@dataclass(frozen=True)
class Forces:
    """``stop``: the stopping load on the rows (the check's ``BallLoad``: worst motor, every
    motor's headroom, the friction cone's margin); ``hold``: the grasp QP's holding forces
    (None: infeasible); ``soft``: the arm's stopping motion (None when the palm does not give
    with the ball: at rest, or turning with the wrist's turn under way)."""

    stop: Any
    hold: gq.GraspResult | None
    soft: SoftStop | None = None
    contact: Any = None  # the check's ContactLoads: the impact at contact and the riding
    # ball's worst, named apart (``planner.check.ball.contact_loads``)


@dataclass(frozen=True)
class ForcesVerdict:
    """``CatchPlanner.forces``: the forces, the reasons they fail, the ball's centre on the
    palm at the intercept (reference frame)."""

    forces: Forces
    reasons: tuple[Reason, ...]
    centre_i: np.ndarray


@dataclass(frozen=True)
class Rows:
    """The rows: times, joint positions, motor angles."""

    t: np.ndarray
    q: np.ndarray
    q_motor: np.ndarray


@dataclass(frozen=True)
class CatchPlan:
    """A planned catch (no file written yet), made by ``make_catch_plan``."""

    feasible: bool
    reasons: tuple[Reason, ...]
    flight: Flight
    catch_point: np.ndarray
    T_world_root: np.ndarray
    base_hand: HandModel
    rate_hz: float
    throw: ThrowInfo | None
    intercept: InterceptInfo
    timing: Timing
    poses: Poses
    forces: Forces
    rows: Rows
    ik_iterations: int
    uncertainty: dict[str, float] | None = None
    planning_s: float = 0.0
    notes: tuple[str, ...] = ()

    @property
    def reason_kinds(self) -> tuple[CatchReason, ...]:
        return tuple(r.kind for r in self.reasons)

    @cached_property
    def hand(self) -> HandModel:
        """The hand mounted in the catch frame (``T_world_root``)."""
        return self.base_hand.mounted(self.T_world_root)

    def margins(self) -> dict[str, float]:
        tm, t_i = self.timing, self.intercept.t_s
        out = {
            "reaction_s": tm.move_start_s,
            "move_s": tm.move_s,
            "ready_s": tm.ready_s,
            "wait_open_s": tm.close_start_s - tm.ready_s,
            "close_s": tm.close_s,
            "close_lead_s": t_i - tm.close_start_s,
        }
        if tm.grasp_t is not None:
            out["grasp_after_s"] = tm.grasp_t - t_i
            out["grasp_slack_s"] = t_i + GRASP_WINDOW_S - tm.grasp_t
        return out

    def metadata(self) -> dict[str, Any]:
        """The file's first line (a planned catch's)."""
        tm = self.timing
        return catch_metadata(self.base_hand, self.T_world_root.tolist(), self.rate_hz,
                              self.flight, self.intercept.t_s, {
            "throw": {} if self.throw is None else self.throw.to_dict(),
            "catch_point": [float(x) for x in self.catch_point],
            "stop_distance_m": self.base_hand.pad_give_m,
            "close_start": float(tm.close_start_s),
            "grasp_t": None if tm.grasp_t is None else float(tm.grasp_t),
            "feasible": bool(self.feasible),
            "reasons": [r.detail for r in self.reasons],
        })

    def end_claims(self) -> dict[str, Any]:
        """The plan's claims for the end marker (spec section 4, version 2): ``"catch"``
        ``held`` or ``infeasible`` with its reason."""
        if self.feasible:
            tm = self.timing
            return {"catch": HELD, "reason": f"grasp at t = {tm.grasp_t:.3f} s "
                                             f"({', '.join(tm.grasp_fingers)})"}
        return {"catch": INFEASIBLE, "reason": reasons_text(self.reasons),
                "reason_kinds": [k.value for k in self.reason_kinds]}


HELD = "held"
GIVEN_UP = "given_up"
INFEASIBLE = "infeasible"
CATCH_FILE_VERSION = 2  # spec section 4: the end marker carries the catch's claims


def catch_metadata(hand: HandModel, T_world_root: list, rate_hz: float, flight: Flight,
                   intercept_t: float, catch: dict[str, Any]) -> dict[str, Any]:
    """A catch file's metadata (spec section 4, version 2: its end marker says whether the
    catch is held, given up or infeasible, and why), planned or live: ``catch`` is the
    ``"catch"`` entry (the plan's or the session's facts)."""
    return {"version": CATCH_FILE_VERSION, "task": "catch", "hand": hand.name,
            "urdf_sha256": hand.urdf_sha256,
            "T_world_root": T_world_root, "rate_hz": rate_hz,
            "ball": flight.to_metadata(), "intercept_t": float(intercept_t), "catch": catch}


def make_catch_plan(*, reasons: list[Reason] | tuple[Reason, ...], flight: Flight,
                    catch_point: np.ndarray, T_world_root: np.ndarray, base_hand: HandModel,
                    hand: HandModel, rate_hz: float, throw: ThrowInfo | None, pose: Any,
                    verdict: RowVerdict, q_rest: np.ndarray, q_open: np.ndarray,
                    move_start_s: float, move_s: float, close_start_s: float, close_s: float,
                    forces: Forces, t: np.ndarray, Q: np.ndarray, t_info_s: float,
                    flight_time_s: float | None, uncertainty: dict[str, float] | None,
                    notes: tuple[str, ...] | list[str] = (), planning_s: float = 0.0
                    ) -> CatchPlan:
    """The one way a ``CatchPlan`` is made (the planner's and the live session's): ``pose``
    the hand meeting the ball (``CatchPlanner.meet``'s, its ``q_closed`` the pose that holds
    it), ``verdict`` the rows' self-check, ``hand`` the reference-mounted hand (the motor
    angles of ``Q``)."""
    return CatchPlan(
        feasible=not reasons, reasons=tuple(reasons), flight=flight, catch_point=catch_point,
        T_world_root=T_world_root, base_hand=base_hand, rate_hz=float(rate_hz), throw=throw,
        intercept=InterceptInfo(float(pose.t_i), flight.position(pose.t_i), pose.v_i,
                                verdict.error_m, pose.misalign_deg, flight.speed,
                                flight_time_s),
        timing=Timing(move_start_s, move_s, float(close_start_s), close_s, verdict.grasp_t,
                      verdict.grasp_fingers, verdict.clearance_m, float(t_info_s)),
        poses=Poses(q_rest, q_open, pose.q_closed), forces=forces,
        rows=Rows(t, Q, hand.motor_angles(Q)), ik_iterations=pose.ik_iterations,
        uncertainty=uncertainty, planning_s=planning_s, notes=tuple(notes))


@dataclass(frozen=True)
class CatchResult(KeptText):
    """What ``plan_catch`` returns: the plan and where it was written."""

    plan: CatchPlan
    out_path: str | None  # None: planned in memory (``text``)
    rows: int
    planning_s: float  # per throw: flight, intercept, timing, rows, forces, self-check
    writing_s: float
    setup_s: float = 0.0  # one-time: hand, IK, closing table (cached across calls)
    text: str | None = None  # the file's text, when planned in memory

    @property
    def feasible(self) -> bool:
        return self.plan.feasible

    @property
    def reasons(self) -> tuple[Reason, ...]:
        return self.plan.reasons
