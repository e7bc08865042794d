"""What a catch plan is: the closing move of a ball size, the plan of one throw, and what
``plan_catch`` returns."""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from functools import cached_property
from typing import TYPE_CHECKING, Any

import numpy as np

from planner.catch import grasp as gq
from planner.catch.flight.path import Flight
from planner.check.ballstop import PAD_GIVE_M
from planner.check.criteria import GRASP_WINDOW_S
from planner.hand.model import HandModel

if TYPE_CHECKING:
    from planner.catch.plan.stopping import SoftStop


class CatchReason(Enum):
    """Why a catch is infeasible. Only the first three are limits no motion of the hand
    overcomes; the others are this plan's shortfalls."""

    OUT_OF_REACH = "out of reach"  # no wrist/rail pose puts the palm on the ball's path
    TOO_SOON = "too soon"  # the ball arrives before the hand can open
    TOO_FAST_TO_STOP = "too fast to stop"  # no stopping motion within the joints' limits
    # keeps every motor within its capacity
    FRICTION = "friction"  # the ball would slide off the palm
    TORQUE = "torque"  # holding the ball needs more than a motor gives
    GRASP = "grasp"  # the fingers do not close around the ball (in time)
    FINGERS = "fingers in the way"  # a fingertip would hit the arriving ball
    MISS = "miss"  # the rows put the palm elsewhere
    ROLL = "roll"  # the ball rolls off the palm's wrist side before the wrist's turn levels
    # the palm (``planner.check.ballroll``)


class Reason(str):
    """A reason a catch is infeasible: the text (``str``: what the summary prints) and its
    ``kind`` (a ``CatchReason``)."""

    __slots__ = ("kind",)

    def __new__(cls, kind: CatchReason, detail: str) -> Reason:  # noqa: PYI034
        out = super().__new__(cls, detail)
        out.kind = kind
        return out

    def __reduce__(self):
        return (Reason, (self.kind, str(self)))


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
class CatchPlan:
    """A planned catch (no file written yet). ``stop``: the stopping load on the rows (the
    check's ``BallLoad``: worst motor, every motor's headroom, the friction cone's margin);
    ``soft``: the arm's stopping motion (None when the palm does not give with the ball: at
    rest, or turning with the wrist's turn under way, ``planner.catch.plan.turnahead``)."""

    feasible: bool
    reasons: tuple[Reason, ...]
    flight: Flight
    catch_point: np.ndarray
    T_world_root: np.ndarray
    base_hand: HandModel
    rate_hz: float
    throw: dict[str, Any]
    launch_speed: float
    flight_time_s: float | None  # time at x = dist
    intercept_t: float
    intercept_point: np.ndarray  # ball centre at intercept_t (catch frame)
    arrival_velocity: np.ndarray
    intercept_error_m: float  # on the rows, as the independent check computes it
    misalignment_deg: float
    q_rest: np.ndarray
    q_open: np.ndarray
    q_closed: np.ndarray
    move_start_s: float
    move_s: float
    close_start_s: float
    close_s: float
    grasp_t: float | None  # first row time with the grasp
    grasp_fingers: tuple[str, ...]
    min_clearance_before_m: float  # min fingertip distance to the ball surface before intercept
    stop: Any
    hold: gq.GraspResult | None
    t: np.ndarray
    q: np.ndarray
    q_motor: np.ndarray
    ik_iterations: int
    t_info_s: float
    uncertainty: dict[str, float] | None = None
    planning_s: float = 0.0
    notes: tuple[str, ...] = ()
    soft: SoftStop | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "reasons", tuple(self.reasons))
        object.__setattr__(self, "notes", tuple(self.notes))

    @property
    def reason_kinds(self) -> tuple[CatchReason, ...]:
        return tuple(getattr(r, "kind", CatchReason.MISS) for r in self.reasons)

    @cached_property
    def hand(self) -> HandModel:
        """The hand mounted in the catch frame (``T_world_root``)."""
        return self.base_hand.mounted(self.T_world_root)

    @property
    def ready_s(self) -> float:
        return self.move_start_s + self.move_s

    def margins(self) -> dict[str, float]:
        out = {
            "reaction_s": self.move_start_s,
            "move_s": self.move_s,
            "ready_s": self.ready_s,
            "wait_open_s": self.close_start_s - self.ready_s,
            "close_s": self.close_s,
            "close_lead_s": self.intercept_t - self.close_start_s,
        }
        if self.grasp_t is not None:
            out["grasp_after_s"] = self.grasp_t - self.intercept_t
            out["grasp_slack_s"] = self.intercept_t + GRASP_WINDOW_S - self.grasp_t
        return out

    def metadata(self) -> dict[str, Any]:
        hand = self.base_hand
        return {
            "task": "catch", "hand": hand.name, "urdf_sha256": hand.urdf_sha256,
            "T_world_root": self.T_world_root.tolist(), "rate_hz": self.rate_hz,
            "ball": self.flight.to_metadata(), "intercept_t": float(self.intercept_t),
            "catch": {
                "throw": self.throw,
                "catch_point": [float(x) for x in self.catch_point],
                "stop_distance_m": PAD_GIVE_M,
                "close_start": float(self.close_start_s),
                "grasp_t": None if self.grasp_t is None else float(self.grasp_t),
                "feasible": bool(self.feasible),
                "reasons": list(self.reasons),
            },
        }


@dataclass
class CatchResult:
    """What ``plan_catch`` returns: the plan and where it was written."""

    plan: CatchPlan
    out_path: str
    rows: int
    planning_s: float  # per throw: flight, intercept, timing, rows, forces, self-check
    writing_s: float
    setup_s: float = 0.0  # one-time: hand, IK, closing table (cached across calls)

    @property
    def feasible(self) -> bool:
        return self.plan.feasible

    @property
    def reasons(self) -> tuple[str, ...]:
        return self.plan.reasons

    def __getattr__(self, name: str) -> Any:  # convenience: result.intercept_t etc.
        if name == "plan":
            raise AttributeError(name)
        return getattr(self.plan, name)


# ====================================================================== geometry helpers
