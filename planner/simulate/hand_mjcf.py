"""The hand's URDF (``HandModel.urdf``, the text ``cli.py hand --urdf`` writes) as an
MJCF body tree: links -> bodies, revolute/prismatic joints -> hinge/slide joints with
the URDF's limits, inertials as they are, ``<mimic>`` -> joint equality constraints.

Collision geometry (the URDF has visual boxes only, as the kinematic check uses only
the fingertip pad points): a finger segment (a link whose subtree holds some of the
fingertips but not all, its box longest along its link's y) is a capsule of the box's thickness along it; the distal segment's capsule ends in the
fingertip pad, a sphere whose bottom is the pad point (the tip link's origin, a pad
radius below the segment's axis: ``planner.hand.spec``'s pad); the palm, wrist and
forearm are their boxes. The hand's own parts do not collide with each other (the
kinematic check does not test that either); they collide with the keys and the ball.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np

from planner.errors import InputError

HAND_CONTYPE, HAND_CONAFFINITY = 1, 2  # hand geoms touch the world's (keys, ball), not their own
PAD_FRICTION = 0.8
PAD_POINT_RADIUS_M = 0.001  # contact "pads": the pad point as a 1 mm sphere resting on it  # rubber pad on a key or ball: seed 000 ("rubber ... coefficient of friction 0.8")


@dataclass(frozen=True)
class UrdfJoint:
    name: str
    kind: str  # revolute, prismatic, fixed, continuous
    parent: str
    child: str
    xyz_m: tuple[float, float, float]
    rpy_rad: tuple[float, float, float]
    axis: tuple[float, float, float]
    lower: float
    upper: float
    mimic: tuple[str, float, float] | None  # (source joint, multiplier, offset)


@dataclass(frozen=True)
class UrdfLink:
    name: str
    mass_kg: float
    com_m: tuple[float, float, float]
    inertia_diag: tuple[float, float, float]
    box_center_m: tuple[float, float, float] | None
    box_size_m: tuple[float, float, float] | None


def _floats(text: str | None, n: int, default: float = 0.0) -> tuple[float, ...]:
    if text is None:
        return (default,) * n
    vals = tuple(float(v) for v in text.split())
    if len(vals) != n:
        raise InputError(f"URDF: expected {n} numbers, got {text!r}")
    return vals


def parse_urdf(text: str) -> tuple[dict[str, UrdfLink], list[UrdfJoint]]:
    """The links and joints of a URDF text (the subset ``planner.hand.urdf`` writes)."""
    root = ET.fromstring(text)
    links: dict[str, UrdfLink] = {}
    for el in root.findall("link"):
        inert = el.find("inertial")
        mass, com, diag = 0.0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
        if inert is not None:
            mass = float(inert.find("mass").get("value"))
            com = _floats(inert.find("origin").get("xyz"), 3)
            i = inert.find("inertia")
            diag = (float(i.get("ixx")), float(i.get("iyy")), float(i.get("izz")))
        box_c = box_s = None
        vis = el.find("visual")
        if vis is not None and vis.find("geometry/box") is not None:
            box_c = _floats(vis.find("origin").get("xyz"), 3)
            box_s = _floats(vis.find("geometry/box").get("size"), 3)
        links[el.get("name")] = UrdfLink(el.get("name"), mass, com, diag, box_c, box_s)
    joints = []
    for el in root.findall("joint"):
        origin = el.find("origin")
        lim = el.find("limit")
        mim = el.find("mimic")
        joints.append(UrdfJoint(
            el.get("name"), el.get("type"), el.find("parent").get("link"),
            el.find("child").get("link"),
            _floats(origin.get("xyz") if origin is not None else None, 3),
            _floats(origin.get("rpy") if origin is not None else None, 3),
            _floats(el.find("axis").get("xyz") if el.find("axis") is not None else "1 0 0", 3),
            float(lim.get("lower")) if lim is not None else -math.inf,
            float(lim.get("upper")) if lim is not None else math.inf,
            None if mim is None else (mim.get("joint"), float(mim.get("multiplier", "1")),
                                      float(mim.get("offset", "0")))))
    return links, joints


def rpy_quat(rpy: tuple[float, float, float]) -> tuple[float, float, float, float]:
    """URDF roll-pitch-yaw (R = Rz(y) Ry(p) Rx(r)) as a MuJoCo quaternion (w, x, y, z)."""
    r, p, y = (0.5 * a for a in rpy)
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), \
        math.cos(y), math.sin(y)
    return (cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy)


def matrix_quat(R: np.ndarray) -> tuple[float, float, float, float]:
    """A rotation matrix as a unit quaternion (w, x, y, z)."""
    import mujoco

    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.asarray(R, dtype=float).reshape(9))
    return tuple(float(v) for v in q)


def mjcf_vec(xs) -> str:
    """Numbers as an MJCF attribute writes them (space-separated, 12 significant digits)."""
    return " ".join(f"{float(x):.12g}" for x in xs)


def segment_capsule(link: UrdfLink, pad: tuple[float, float, float] | None
                    ) -> tuple[tuple[float, ...], tuple[float, ...], float] | None:
    """A finger segment's capsule in its link's frame (its two end points and radius), or
    None when the link's box is not a segment's (not longest along its y): the box's
    thickness, along y, ending at the pad sphere's centre ``pad`` on the distal segment.
    (The one definition of the finger's body: the MJCF's geoms and the planner's body
    clearance, ``planner.play.fingerbody``.)"""
    if link.box_size_m is None:
        return None
    sx, sy, sz = link.box_size_m
    cx, cy, cz = link.box_center_m
    if not (sy > sx and sy > sz):
        return None
    r = 0.5 * min(sx, sz)
    y0 = cy - 0.5 * sy + r
    y1 = cy + 0.5 * sy - r if pad is None else pad[1]
    return (cx, y0, cz), (cx, max(y1, y0 + 1e-4), cz), r


def _geoms(body: ET.Element, link: UrdfLink, pad: tuple[float, float, float] | None,
           segment: bool, collide: bool = True) -> None:
    """Collision geoms of a link (see the module docstring); ``segment``: the link is a
    finger segment (its subtree holds some of the fingertips, not all of them);
    ``collide`` False: the same shapes drawn only (contact "pads": the pictures)."""
    common = {"contype": str(HAND_CONTYPE if collide else 0),
              "conaffinity": str(HAND_CONAFFINITY if collide else 0),
              "friction": f"{PAD_FRICTION:g} 0.005 0.0001", "mass": "0",
              "rgba": "0.75 0.6 0.5 1"}
    if link.box_size_m is None:
        return
    cap = segment_capsule(link, pad) if segment else None
    if cap is not None:
        p0, p1, r = cap
        ET.SubElement(body, "geom", name=f"{link.name}_capsule", type="capsule",
                      fromto=mjcf_vec((*p0, *p1)), size=f"{r:.12g}", **common)
        return
    sx, sy, sz = link.box_size_m
    ET.SubElement(body, "geom", name=f"{link.name}_box", type="box", pos=mjcf_vec(link.box_center_m),
                  size=mjcf_vec((0.5 * sx, 0.5 * sy, 0.5 * sz)), **common)


def hand_bodies(urdf: str, parent: ET.Element, tip_links: tuple[str, ...],
                armature: dict[str, float], pads_only: bool = False) -> list[UrdfJoint]:
    """Add the URDF's tree under ``parent`` (the root link's body); returns its joints.

    ``pads_only``: the only collision geometry is a ``PAD_POINT_RADIUS_M`` sphere on each
    pad point (the kinematic check's contact model, with the physics of the rest).

    ``armature``: a joint's reflected rotor inertia (kg m^2), by joint name. Each tip
    link gets a pad sphere geom ``<finger>_pad`` and a site ``<link>`` at the pad point.
    """
    links, joints = parse_urdf(urdf)
    children: dict[str, list[UrdfJoint]] = {}
    for j in joints:
        children.setdefault(j.parent, []).append(j)
    # the pad of each tip: (pad centre in the parent link's frame, radius)
    pads = {}
    for j in joints:
        if j.child in tip_links:
            r = PAD_POINT_RADIUS_M if pads_only else abs(j.xyz_m[2])
            pads[j.parent] = (j.xyz_m[0], j.xyz_m[1], j.xyz_m[2], r, j.child)

    tips_below: dict[str, set[str]] = {}

    def below(link_name: str) -> set[str]:
        if link_name not in tips_below:
            out = {link_name} if link_name in tip_links else set()
            for j in children.get(link_name, []):
                out |= below(j.child)
            tips_below[link_name] = out
        return tips_below[link_name]

    def add(body_el: ET.Element, link_name: str) -> None:
        link = links[link_name]
        if link.mass_kg > 0:
            ET.SubElement(body_el, "inertial", pos=mjcf_vec(link.com_m), mass=f"{link.mass_kg:.12g}",
                          diaginertia=mjcf_vec(link.inertia_diag))
        pad = pads.get(link_name)
        # (with pads only, the same shapes without contact: drawn in the pictures)
        _geoms(body_el, link, None if pad is None else (pad[0], pad[1], pad[2] + pad[3]),
               segment=0 < len(below(link_name)) < len(tip_links), collide=not pads_only)
        if pad is not None:
            x, y, z, r, tip = pad
            ET.SubElement(body_el, "geom", name=f"{tip.removesuffix('_tip')}_pad", type="sphere",
                          pos=mjcf_vec((x, y, z + r)), size=f"{r:.12g}",
                          contype=str(HAND_CONTYPE), conaffinity=str(HAND_CONAFFINITY),
                          friction=f"{PAD_FRICTION:g} 0.005 0.0001", mass="0",
                          rgba="0.9 0.5 0.4 1")
        for j in children.get(link_name, []):
            child = ET.SubElement(body_el, "body", name=j.child, pos=mjcf_vec(j.xyz_m),
                                  quat=mjcf_vec(rpy_quat(j.rpy_rad)))
            if j.kind in ("revolute", "continuous", "prismatic"):
                attrs = {"name": j.name, "type": "slide" if j.kind == "prismatic" else "hinge",
                         "axis": mjcf_vec(j.axis), "armature": f"{armature.get(j.name, 0.0):.6g}"}
                if j.kind != "continuous" and math.isfinite(j.lower):
                    attrs.update(limited="true", range=mjcf_vec((j.lower, j.upper)))
                ET.SubElement(child, "joint", **attrs)
            if j.child in tip_links:
                ET.SubElement(child, "site", name=j.child, size="0.002")
            add(child, j.child)

    root = [n for n in links if all(j.child != n for j in joints)]
    if len(root) != 1:
        raise InputError(f"URDF: expected one root link, found {root}")
    add(parent, root[0])
    return joints
