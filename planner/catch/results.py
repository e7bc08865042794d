"""What a catch plan is: the closing move of a ball size, the plan of one throw, and what
``plan_catch`` returns."""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from planner.catch import grasp as gq
from planner.catch.flight import Flight
from planner.check.criteria import GRASP_WINDOW_S
from planner.hand.model import HandModel


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


@dataclass
class CatchPlan:
    """A planned catch (no file written yet)."""

    feasible: bool
    reasons: list[str]
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
    stop: gq.GraspResult | None
    hold: gq.GraspResult | None
    t: np.ndarray
    q: np.ndarray
    q_motor: np.ndarray
    ik_iterations: int
    t_info_s: float
    uncertainty: dict[str, float] | None = None
    planning_s: float = 0.0
    notes: list[str] = field(default_factory=list)

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
                "stop_distance_m": gq.STOP_DISTANCE_M,
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
    def reasons(self) -> list[str]:
        return self.plan.reasons

    def __getattr__(self, name: str) -> Any:  # convenience: result.intercept_t etc.
        if name == "plan":
            raise AttributeError(name)
        return getattr(self.plan, name)


# ====================================================================== geometry helpers
