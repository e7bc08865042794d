"""Why a catch is infeasible: a kind (``CatchReason``) and the sentence the summary prints,
made where the failure is found (the row self-check, the roll rule, the force QPs, the
intercept search), never recovered from the text."""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum


class CatchReason(Enum):
    """Why a catch is infeasible. Only the first three are limits no motion of the hand
    overcomes (too fast to stop: where the stop bound says so too); the others are this
    plan's shortfalls."""

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
    NO_STOP = "no stop found"  # the planner's stops keep no motor within its capacity, and
    # the stop bound (``planner.catch.plan.stopbound``) does not exclude one that does


HARD_LIMITS = frozenset({CatchReason.OUT_OF_REACH, CatchReason.TOO_SOON,
                         CatchReason.TOO_FAST_TO_STOP})  # no motion of this hand overcomes them


@dataclass(frozen=True)
class Reason:
    """A reason a catch is infeasible: its ``kind`` and its ``detail`` (what the summary
    prints, ``str(reason)``)."""

    kind: CatchReason
    detail: str

    def __str__(self) -> str:
        return self.detail


def reasons_text(reasons: tuple[Reason, ...] | list[Reason]) -> str:
    """The reasons as one line ("; " between them)."""
    return "; ".join(r.detail for r in reasons)
