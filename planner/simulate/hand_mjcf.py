"""The hand's URDF (``HandModel.urdf``, the text ``cli.py hand --urdf`` writes) as an
MJCF body tree: links -> bodies, revolute/prismatic joints -> hinge/slide joints with
the URDF's limits, inertials as they are, ``<mimic>`` -> joint equality constraints.

Collision geometry: the hand's collision bodies (``planner.hand.bodies``, the shapes the
URDF's ``<collision>`` elements and ``check``'s body rule are made of), a capsule as a
MuJoCo capsule: each finger segment a slab of two capsules, the fingertip pad a sphere
whose bottom is the pad point, the palm, knuckles, wrist and forearm their boxes. The
hand's own parts do not collide with each other (the kinematic check does not test that
either); they collide with the keys and the ball.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np

from planner.errors import InputError
from planner.hand.bodies import CAPSULE, SPHERE, Body

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


def _geoms(body: ET.Element, shapes: tuple[Body, ...], pads_only: bool,
           collide_bits: tuple[int, int] = (HAND_CONTYPE, HAND_CONAFFINITY)) -> None:
    """A link's collision geoms: its bodies (``planner.hand.bodies``, the one definition),
    a capsule as a capsule; ``pads_only``: the pad spheres become ``PAD_POINT_RADIUS_M``
    spheres resting on the pad points and the other shapes are drawn only (the pictures)."""
    for b in shapes:
        pad = b.kind == SPHERE and b.name.endswith("_pad")
        collide = pad or not pads_only
        attrs = {"contype": str(collide_bits[0] if collide else 0),
                 "conaffinity": str(collide_bits[1] if collide else 0),
                 "friction": f"{PAD_FRICTION:g} 0.005 0.0001", "mass": "0",
                 "rgba": "0.9 0.5 0.4 1" if pad else "0.75 0.6 0.5 1"}
        if b.kind == CAPSULE:
            ET.SubElement(body, "geom", name=b.name, type="capsule",
                          fromto=mjcf_vec((*b.p0_m, *b.p1_m)), size=f"{b.radius_m:.12g}", **attrs)
        elif b.kind == SPHERE:
            r, (x, y, z) = b.radius_m, b.p0_m
            if pad and pads_only:  # (the sphere's bottom stays on the pad point)
                z, r = z - r + PAD_POINT_RADIUS_M, PAD_POINT_RADIUS_M
            ET.SubElement(body, "geom", name=b.name, type="sphere", pos=mjcf_vec((x, y, z)),
                          size=f"{r:.12g}", **attrs)
        else:
            ET.SubElement(body, "geom", name=b.name, type="box", pos=mjcf_vec(b.p0_m),
                          size=mjcf_vec(b.half_m), **attrs)


def hand_bodies(urdf: str, parent: ET.Element, tip_links: tuple[str, ...],
                armature: dict[str, float], shapes: tuple[Body, ...],
                pads_only: bool = False,
                collide_bits: tuple[int, int] = (HAND_CONTYPE, HAND_CONAFFINITY)
                ) -> list[UrdfJoint]:
    """Add the URDF's tree under ``parent`` (the root link's body); returns its joints.
    ``shapes``: the hand's collision bodies (``planner.hand.bodies.collision_bodies``).

    ``pads_only``: the only collision geometry is a ``PAD_POINT_RADIUS_M`` sphere on each
    pad point (the kinematic check's contact model, with the physics of the rest).
    ``collide_bits``: the geoms' (contype, conaffinity) (two hands: each its own bit, so
    that each touches the other's, ``scene.pair_bits``).

    ``armature``: a joint's reflected rotor inertia (kg m^2), by joint name. Each tip
    link gets a pad sphere geom ``<finger>_pad`` and a site ``<link>`` at the pad point.
    """
    links, joints = parse_urdf(urdf)
    children: dict[str, list[UrdfJoint]] = {}
    for j in joints:
        children.setdefault(j.parent, []).append(j)
    by_link: dict[str, list[Body]] = {}
    for b in shapes:
        by_link.setdefault(b.link, []).append(b)

    def add(body_el: ET.Element, link_name: str) -> None:
        link = links[link_name]
        if link.mass_kg > 0:
            ET.SubElement(body_el, "inertial", pos=mjcf_vec(link.com_m), mass=f"{link.mass_kg:.12g}",
                          diaginertia=mjcf_vec(link.inertia_diag))
        _geoms(body_el, tuple(by_link.get(link_name, ())), pads_only, collide_bits)
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
