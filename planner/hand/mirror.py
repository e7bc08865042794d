"""A left hand: a hand's ``HandSpec`` reflected through the plane of its rail's carriage.

A hand file says which hand it is (``side = "right"``, the default, or ``"left"``); the
builders build every hand as a right hand from the file's numbers, and a left one is its
mirror image (``mirror_spec``), so one set of numbers (lengths, ranges, masses, motors,
moment arms, couplings) is the source of truth for both hands.

The reflection ``S = diag(-1, 1, 1)`` of the hand's root frame (x along the rail, the
keyboard's x; y towards the fingers; z up) is applied to everything the rail carries,
in each joint's parent frame:

* a joint's origin: ``xyz -> S xyz`` and its rotation ``R -> S R S`` (URDF roll, pitch,
  yaw ``(r, p, y) -> (r, -p, -y)``: a proper rotation, so the frames stay right-handed,
  each one's x axis the reflection's opposite);
* a revolute joint's axis: ``a -> -S a``. A rotation is an axial vector: ``S Rot(a, q) S
  = Rot(-S a, q)``, so the same angle ``q`` turns the mirrored link the mirrored way:
  flexion (about -x) keeps its axis, abduction and deviation (about z) turn theirs
  over, and every joint keeps its range, its sign's anatomical meaning (+ abduction is
  away from the middle finger in both hands, + deviation towards the thumb), its
  coupling and its motor's transmission to the number (a tendon's moment arm does not
  change side: flexion is about the same -x);
* a prismatic joint's axis: ``a -> S a`` (the reach axis, keyboard y, is its own mirror);
* a link's centre of mass: ``com -> S com`` (its box, axis-aligned in its frame, is its
  own mirror: its principal inertias stay).

The **rail** itself is not reflected: both hands' carriages run along the keyboard's +x
(a rail position means the same place on the keys for either hand), so the mirror plane
is the plane through the rail's carriage normal to the rail. For every joint vector q:
``FK_left(q) = M_c FK_right(q) M_c``, ``M_c`` the reflection through the plane x =
(carriage's x) of the root frame (``tests/test_mirror.py`` checks frames, collision
bodies and Jacobians). The collision bodies (``planner.hand.bodies``) are built from the
mirrored links and joints, so they are the right hand's reflected.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from planner.hand.spec import HandSpec, Joint, Link

SIDES = ("right", "left")
RAIL_JOINT = "rail"  # the rig's axis along the keyboard: not reflected (see above)
S_MIRROR = np.diag([-1.0, 1.0, 1.0])  # the reflection, in the root frame


def _neg0(x: float) -> float:
    """-x, with -0.0 written as 0.0 (the URDF's text prints no negative zeros either)."""
    return -x + 0.0


def mirror_rpy(rpy: tuple[float, float, float]) -> tuple[float, float, float]:
    """URDF roll-pitch-yaw of ``S R S`` for the rotation ``R`` of ``rpy``: (r, -p, -y)."""
    r, p, y = rpy
    return (r, _neg0(p), _neg0(y))


def mirror_joint(j: Joint) -> Joint:
    """A joint of the mirrored hand (the module docstring); the rail stays as it is."""
    if j.name == RAIL_JOINT:
        return j
    x, y, z = j.xyz_m
    ax, ay, az = j.axis
    if j.kind == "prismatic":
        axis = (_neg0(ax), ay, az)
    else:  # revolute (or fixed: its axis unused, turned over as a revolute's)
        axis = (ax, _neg0(ay), _neg0(az))
    return replace(j, xyz_m=(_neg0(x), y, z), rpy_rad=mirror_rpy(j.rpy_rad), axis=axis)


def mirror_link(link: Link) -> Link:
    x, y, z = link.com_m
    return replace(link, com_m=(_neg0(x), y, z))


def mirror_spec(spec: HandSpec, side: str = "left") -> HandSpec:
    """``spec`` (a right hand) reflected into a left hand (``side``), every number of its
    joints' limits, couplings and motors kept."""
    if spec.side == side:
        return spec
    return replace(spec, links=tuple(mirror_link(link) for link in spec.links),
                   joints=tuple(mirror_joint(j) for j in spec.joints), side=side)


def mirror_pose(T: np.ndarray, plane_x_m: float) -> np.ndarray:
    """A pose (4x4, or stacked (..., 4, 4)) reflected through the plane x = ``plane_x_m``
    (a pose of the frame that mirrors it: position reflected, rotation ``S R S``)."""
    T = np.asarray(T, dtype=float)
    out = T.copy()
    out[..., :3, :3] = S_MIRROR @ T[..., :3, :3] @ S_MIRROR
    out[..., 0, 3] = 2.0 * plane_x_m - T[..., 0, 3]
    return out

