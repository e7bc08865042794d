"""The hand's joints as a catch uses them: the arm (rail, the rig's reach axis where the hand
has one, wrist flexion and deviation), which puts the palm on the ball's path, and the
fingers (abduction, flexion), which close on it; and the poses every throw starts from
(zero, rest, open). The planned catch moves the reach axis (``catch_joints(..., reach=True)``:
where along the forearm's line the palm meets the ball, and the palm giving with it); the
live session holds it at 0, where the rail alone held the hand."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from planner.errors import PlannerError
from planner.hand.model import HandModel
from planner.trajectory import jerk_duration

REST_CURL = 0.3  # rest pose: flexion joints at this fraction of their upper limit
WRIST = ("wrist_flex", "wrist_dev")


@dataclass(frozen=True)
class CatchJoints:
    """Indices (into the hand's joints) of the arm and of the fingers' joints."""

    i_flex: int
    i_dev: int
    i_rail: int | None
    arm: tuple[int, ...]  # rail (if any), reach (if moved), wrist flexion, wrist deviation
    finger_idx: np.ndarray  # every other joint
    abd_idx: np.ndarray  # the fingers' abduction joints
    flexion_idx: np.ndarray  # the fingers' flexion joints
    locked: tuple[str, ...]  # the arm's and the held rig axes' names (masked while the
    # fingers close)
    i_reach: int | None = None  # the rig's reach axis when the arm moves it


def catch_joints(hand: HandModel, reach: bool = False) -> CatchJoints:
    """The joint groups of ``hand``; PlannerError without the 2-DOF wrist. ``reach``: the
    rig's reach axis (if the hand has one) is one of the arm's joints, else held at 0."""
    idx = hand.index
    for n in WRIST:
        if n not in idx:
            raise PlannerError(f"hand {hand.name!r} has no joint {n!r}: the catch planner "
                               "needs the 2-DOF wrist")
    i_flex, i_dev, i_rail = idx["wrist_flex"], idx["wrist_dev"], idx.get("rail")
    i_reach = idx.get("reach") if reach and "reach" in hand.rig_joints else None
    arm = tuple(i for i in (i_rail, i_reach, i_flex, i_dev) if i is not None)
    held = {idx[n] for n in hand.rig_joints if n != "rail" and idx[n] != i_reach}  # (at
    # their zero pose's value)
    finger_idx = np.array(sorted(set(range(hand.n)) - set(arm) - held))
    abd = [i for i in finger_idx if "abd" in hand.joint_names[i]]
    flexion = [i for i in finger_idx if i not in set(abd)]
    return CatchJoints(i_flex, i_dev, i_rail, arm, finger_idx, np.array(abd, dtype=int),
                       np.array(flexion, dtype=int),
                       tuple(hand.joint_names[i] for i in (*arm, *sorted(held))), i_reach)


def zero_pose(hand: HandModel) -> np.ndarray:
    """Every joint at 0 (inside its limits), couplings applied."""
    return hand.apply_couplings(np.clip(np.zeros(hand.n), hand.lower, hand.upper))


def rest_pose(hand: HandModel, joints: CatchJoints) -> np.ndarray:
    """The hand before the throw: the zero pose with the fingers curled ``REST_CURL``."""
    q = zero_pose(hand)
    for i in joints.flexion_idx:
        q[i] = REST_CURL * hand.upper[i] if hand.upper[i] > 0 else 0.0
    return hand.apply_couplings(np.clip(q, hand.lower, hand.upper))


def open_from(hand: HandModel, joints: CatchJoints, q_arm: np.ndarray,
              q_closed: np.ndarray) -> np.ndarray:
    """Open hand: the arm joints of ``q_arm``, abduction as in ``q_closed``, flexion 0
    (``straight``: where a joint's limit holds it flexed, the finger's first joint takes it
    back)."""
    q = zero_pose(hand)
    q[list(joints.arm)] = q_arm[list(joints.arm)]
    q[joints.abd_idx] = q_closed[joints.abd_idx]
    return straight(hand, joints, hand.apply_couplings(np.clip(q, hand.lower, hand.upper)))


def straight(hand: HandModel, joints: CatchJoints, q: np.ndarray) -> np.ndarray:
    """``q`` with each finger's flexion joints summing to 0 where its first flexion joint's
    limits allow: the flexion its later joints keep (a limit above 0, as the stop margin
    of a joint whose hard stop is straight: 2 deg on the AGH's end joints, whose 140 mm
    element then leaned its tip 4.9 mm into the ball's way between the pairs) is taken
    back by the first one, so the finger's last segment points as with every flexion at 0
    (the fingers' flexions turn about parallel axes)."""
    flexion = {int(i) for i in joints.flexion_idx}
    q = q.copy()
    for f in hand.fingers:
        chain = [hand.index[n] for n in hand.spec.joints_of(f) if hand.index[n] in flexion]
        if len(chain) < 2:
            continue
        first, rest = chain[0], float(q[chain[1:]].sum())
        q[first] = np.clip(-rest, hand.lower[first], hand.upper[first])
    return hand.apply_couplings(q)


def palm_target(hand: HandModel, q: np.ndarray, r: float) -> np.ndarray:
    """Where the centre of a ball of radius ``r`` resting on the palm is: palm_center +
    r n (n the palm's normal), in the hand's frame."""
    return palm_target_of(hand.palm_pose(q), r)


def palm_target_of(P: np.ndarray, r: float) -> np.ndarray:
    """``palm_target`` from the palm's pose ``P`` (4x4) already at hand."""
    return P[:3, 3] + r * P[:3, 2]


def move_time(dyn, q_from: np.ndarray, q_to: np.ndarray, arm_alone: bool = False) -> float:
    """The move in from rest (min-jerk): ``StopDynamics.move_time`` (``dyn``), no shorter
    than the joints' jerk bounds allow (``jerk_duration``: short moves of the abduction
    joints, whose bound is the lowest, measured 1.1-1.6 x their bounds at 1000 Hz rows
    otherwise)."""
    return max(dyn.move_time(q_from, q_to, arm_alone), jerk_duration(q_to - q_from, dyn.hand.jerk))


def calm_move_time(dyn, q_from: np.ndarray, q_to: np.ndarray, t_start: float,
                   due: float) -> float:
    """``StopDynamics.calm_move_time`` within the joints' jerk bounds (``move_time``)."""
    return max(dyn.calm_move_time(q_from, q_to, t_start, due),
               jerk_duration(q_to - q_from, dyn.hand.jerk))
