"""Where a finger that cannot move its tip along the keyboard presses a key.

A finger whose own joints all turn about axes along the keyboard's x (the AGH's: a base
and an end joint, both flexing in the plane along the keys' length, with the wrist's
deviation at 0) moves its tip in y and z only: with the arm held, its tip's x is the one
the rail puts it at. The atlas's IK target (``planner.ik.press_target``) is the key's
centre line; such a finger reaches it from one rail position alone (to the IK's 1 mm),
so of the rail's hand positions (``planner.play.places``: every 6 mm) only the one that
happens to lie within 1 mm of it gives the finger the key: on the AGH hand on main, 54 of
the seven sample songs' 192 notes, the rest ``out_of_reach``. A one-DOF finger's arc
presses where it comes down, anywhere across the part of the key it presses
(``EntrySolver._arc_poses``); this does the same for a finger locked in x: its press
target's x is its tip's own, if that lies on the part of the key it presses (inset by
the pad's radius, ``press_x_range``); otherwise it has no press there. Its bodies are
judged by the atlas's body rule as every press's are.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from planner.hand.model import HandModel
from planner.ik import PressTarget, press_x_range

X_LOCK_M_PER_RAD = 1e-9  # own joints moving the tip less than this along x: locked (the
# AGH index's is 0 to rounding, 1e-17 m/rad; any deviation of the wrist makes it mm/rad)


def locked_in_x(hand: HandModel, finger: str, q: np.ndarray) -> bool:
    """True when none of ``finger``'s own joints moves its tip along x at ``q``."""
    J = hand.tip_jacobians(q)[hand.fingers.index(finger)]
    return bool(np.all(np.abs(J[0, hand.joint_slice(finger)]) < X_LOCK_M_PER_RAD))


def planar_press_target(hand: HandModel, target: PressTarget, q_base: np.ndarray,
                        inset_m: float, front: bool) -> PressTarget | None:
    """``target`` with its x moved to the tip's at ``q_base`` for a finger locked in x
    (unchanged for any other); None when that x is off the part of the key it presses."""
    if not locked_in_x(hand, target.finger, q_base):
        return target
    x = float(hand.tip_positions(q_base)[hand.fingers.index(target.finger), 0])
    lo, hi = press_x_range(target.finger, target.pitch, inset_m, front)
    if not lo <= x <= hi:
        return None
    return replace(target, point_m=(x, *target.point_m[1:]))
