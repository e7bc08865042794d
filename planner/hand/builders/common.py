"""What every hand's builder shares: the part every hand has (mount, rail, forearm,
wrist, palm: ``start_hand``), the long fingers' tables, a segment's link and a finger's
pad point, and the ``HandSpec`` of the parts built (``assemble_spec``)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from planner.errors import InputError
from planner.hand.builders.values import (
    get_length,
    get_positive,
    get_value,
    get_vec,
    rotor_inertia,
)
from planner.hand.drive import apply_drive
from planner.hand.pad import palm_pad
from planner.hand.spec import (
    FINGERS,
    Actuator,
    HandSpec,
    Joint,
    LinearCoupling,
    Link,
    Mk5Coupling,
    PlayPosture,
    rpy_matrix,
)
from planner.music.keyboard import DOWN_DEPTH_M, KEY_DIP_M

MAX_POSTURES = 4  # reach positions a hand file's [play] may give (each an atlas, a move table)


@dataclass
class HandParts:
    """What a hand's builder fills, from the part every hand has (``start_hand``) on;
    ``assemble_spec`` makes its ``HandSpec``."""

    T_world_root: tuple[tuple[float, ...], ...]
    rail_enabled: bool
    links: list[Link] = field(default_factory=list)
    joints: list[Joint] = field(default_factory=list)
    actuators: list[Actuator] = field(default_factory=list)
    couplings: list[LinearCoupling | Mk5Coupling] = field(default_factory=list)
    finger_joints: list[tuple[str, tuple[str, ...]]] = field(default_factory=list)


def rig_axis(parts: HandParts, table: dict[str, Any], name: str, parent: str, link: str,
             axis: tuple[float, float, float]) -> str:
    """One prismatic axis of the rig (``rail``, ``reach``): its carriage link, its joint
    (travel ``lower_m``..``upper_m``, speed the least of ``velocity_m_s`` and what its
    belt's motor gives, ``acceleration_m_s2``) and its belt motor. Returns the carriage
    (the next part's parent)."""
    lo, hi = get_value(table, "lower_m"), get_value(table, "upper_m")
    if not lo < hi:
        raise InputError(f"{name}: lower_m must be below upper_m")
    motor = get_value(table, "motor", dict)
    r_pulley = get_value(motor, "radius_m")
    v_motor = get_value(motor, "speed_rad_s")
    v = min(get_value(table, "velocity_m_s"), v_motor * r_pulley)
    parts.links.append(Link(link, get_value(table, "mass_kg"), (0.0, 0.0, 0.0),
                            (0.08, 0.06, 0.04)))
    parts.joints.append(Joint(name, "prismatic", parent, link, (0.0, 0.0, 0.0), axis=axis,
                              lower=lo, upper=hi, velocity=v,
                              acceleration=get_value(table, "acceleration_m_s2"),
                              effort=get_value(motor, "peak_torque_nm") / r_pulley))
    parts.actuators.append(Actuator(name, "belt", name, ((name, 1.0 / r_pulley),), v_motor,
                                    get_value(motor, "peak_torque_nm"), 1.0, r_pulley,
                                    rotor_inertia_kg_m2=rotor_inertia(motor)))
    return link


def start_hand(data: dict[str, Any]) -> HandParts:
    """The part every hand has: mount pose, optional rail, forearm, 2-DOF wrist, palm.

    The palm link is ``palm`` with its frame at the wrist axis, y towards the
    fingers, z out of the back of the hand; ``palm_center`` sits on the palmar
    surface with +z the outward palm normal.
    """
    mount = get_value(data, "mount", dict)
    T = np.eye(4)
    T[:3, :3] = rpy_matrix(tuple(math.radians(a) for a in get_vec(mount, "rpy_deg")))
    T[:3, 3] = get_vec(mount, "xyz_m")
    rail = get_value(data, "rail", dict)
    rail_enabled = get_value(rail, "enabled", bool)
    parts = HandParts(tuple(tuple(float(x) for x in row) for row in T), rail_enabled)
    links, joints, actuators = parts.links, parts.joints, parts.actuators
    fa = get_value(data, "forearm", dict)
    fa_len, fa_r = get_value(fa, "length_m"), get_value(fa, "radius_m")
    links.append(Link("rail_base", 0.0, (0.0, 0.0, 0.0), (0.01, 0.01, 0.01)))
    base = "rail_base"
    if rail_enabled:  # along the keyboard (x)
        base = rig_axis(parts, rail, "rail", base, "carriage", (1.0, 0.0, 0.0))
    reach = data.get("reach")
    if reach is not None:  # towards and away from the player (y), on the rail's carriage
        if not isinstance(reach, dict):
            raise InputError("reach: expected a table")
        if get_value(reach, "enabled", bool):
            base = rig_axis(parts, reach, "reach", base, "reach_carriage", (0.0, 1.0, 0.0))
    links.append(Link("forearm", get_value(fa, "mass_kg"), (0.0, fa_len / 2, 0.0), (2 * fa_r, fa_len, 2 * fa_r)))
    joints.append(Joint("forearm_mount", "fixed", base, "forearm", (0.0, 0.0, 0.0)))

    wr = get_value(data, "wrist", dict)
    gear = get_value(wr, "gear_ratio")
    wmotor = get_value(wr, "motor", dict)
    links.append(Link("wrist", 0.05, (0.0, 0.0, 0.0), (0.04, 0.02, 0.03)))
    palm = get_value(data, "palm", dict)
    p_len, p_wid, p_thk = get_length(palm, "length"), get_length(palm, "width"), get_value(palm, "thickness_m")
    links.append(Link("palm", get_value(palm, "mass_kg"), (0.0, p_len / 2, 0.0), (p_wid, p_len, p_thk)))
    for jname, parent, child, axis, key in (
        ("wrist_flex", "forearm", "wrist", (-1.0, 0.0, 0.0), "flex"),
        ("wrist_dev", "wrist", "palm", (0.0, 0.0, 1.0), "dev"),
    ):
        d = get_value(wr, key, dict)
        lo, hi = math.radians(get_value(d, "lower_deg")), math.radians(get_value(d, "upper_deg"))
        if not lo < hi:
            raise InputError(f"wrist {key}: lower_deg must be below upper_deg")
        v = min(get_value(d, "velocity_cap_rad_s"), get_value(wmotor, "speed_rad_s") / gear)
        xyz = (0.0, fa_len, 0.0) if jname == "wrist_flex" else (0.0, 0.0, 0.0)
        joints.append(Joint(jname, "revolute", parent, child, xyz, axis=axis, lower=lo, upper=hi,
                            velocity=v, acceleration=get_value(d, "acceleration_rad_s2"),
                            effort=get_value(wmotor, "peak_torque_nm") * gear))
        actuators.append(Actuator(jname, "gear", jname, ((jname, gear),), get_value(wmotor, "speed_rad_s"),
                                  get_value(wmotor, "peak_torque_nm"), 1.0,
                                  rotor_inertia_kg_m2=rotor_inertia(wmotor)))
    links.append(Link("palm_center", 0.0, (0.0, 0.0, 0.0), (0.001, 0.001, 0.001)))
    joints.append(Joint("palm_center_fixed", "fixed", "palm", "palm_center",
                        (0.0, p_len / 2, -p_thk / 2), rpy_rad=(math.pi, 0.0, 0.0)))
    return parts


def long_fingers(data: dict[str, Any]) -> list[dict[str, Any]]:
    """The hand file's ``[[finger]]`` tables: exactly one of each finger but the thumb."""
    fingers = get_value(data, "finger", list)
    names = [f.get("name") if isinstance(f, dict) else None for f in fingers]
    if sorted(map(str, names)) != sorted(FINGERS[1:]):
        raise InputError(f"[[finger]] entries must be exactly {', '.join(FINGERS[1:])}; got {names}")
    return fingers


def assemble_spec(data: dict[str, Any], parts: HandParts) -> HandSpec:
    """The HandSpec of a built hand, with the file's name, description and sources.

    Every ``tendon`` actuator gets the cable's design force, ``[tendon] design_force_n``
    (required when the hand has tendons; seed 000, line 96: 40 N, PBO cable 0.25 mm)."""
    actuators, finger_joints = parts.actuators, parts.finger_joints
    if any(a.kind == "tendon" for a in actuators):
        force = get_positive(get_value(data, "tendon", dict), "design_force_n")
        actuators = [replace(a, tendon_force_n=force) if a.kind == "tendon" else a
                     for a in actuators]
    names = tuple(f for f, _ in finger_joints)
    if names != FINGERS[:len(names)] or not names:
        raise InputError(f"fingers must be a prefix of {', '.join(FINGERS)} in that order; "
                         f"got {', '.join(names) or 'none'}")
    src = data.get("sources", {})
    sources = tuple(sorted((str(k), str(v)) for k, v in src.items())) if isinstance(src, dict) else ()
    return HandSpec(
        name=get_value(data, "name", str),
        description=str(data.get("description", "")),
        links=tuple(parts.links),
        joints=tuple(apply_drive(data, parts.joints, actuators, parts.couplings)),
        couplings=tuple(parts.couplings),
        actuators=tuple(actuators),
        T_world_root=parts.T_world_root,
        # one pad per finger, in the fingers' order (a prefix of FINGERS: ``check`` reads
        # the tips in FINGERS order)
        tip_frames=tuple(f"{f}_tip" for f, _ in finger_joints),
        rail_enabled=parts.rail_enabled,
        sources=sources,
        finger_joints=tuple(finger_joints),
        play_posture=play_posture(data, parts),
        palm_pad=palm_pad(data),
    )


def play_posture(data: dict[str, Any], parts: HandParts) -> PlayPosture | None:
    """The hand file's ``[play]`` posture (``PlayPosture``), each number within its joint's
    travel and the press depth between the spec's key-down depth and the key's dip."""
    play = data.get("play")
    if play is None:
        return None
    if not isinstance(play, dict):
        raise InputError("play: expected a table")
    joints = {j.name: j for j in parts.joints}
    reach = play.get("reach_m")
    reach = reach if isinstance(reach, list) else [reach]
    if not reach or len(reach) > MAX_POSTURES:
        raise InputError(f"play.reach_m: expected 1 to {MAX_POSTURES} positions, got {len(reach)}")
    values = [_play_value({"reach_m": r}, "reach_m", joints.get("reach"), 1.0) for r in reach]
    if len(set(values)) != len(values):
        raise InputError("play.reach_m: a position is given twice")
    flex, dev = (_play_value(play, key, joints.get(name), math.pi / 180) for key, name in
                 (("wrist_flex_deg", "wrist_flex"), ("wrist_dev_deg", "wrist_dev")))
    depth = get_value(play, "press_depth_m")
    if not DOWN_DEPTH_M < depth <= KEY_DIP_M:
        raise InputError(f"play.press_depth_m = {depth} must be deeper than the key-down depth "
                         f"({DOWN_DEPTH_M} m) and at most the key's dip ({KEY_DIP_M} m)")
    return PlayPosture(tuple(values), flex, dev, depth)


def _play_value(play: dict[str, Any], key: str, joint: Joint | None, scale: float) -> float:
    """One number of ``[play]`` (scaled to the joint's unit), within its joint's travel."""
    v = get_value(play, key) * scale
    if joint is None:
        if v != 0.0:
            raise InputError(f"play.{key}: the hand has no {key.rsplit('_', 1)[0]} joint")
    elif not joint.lower <= v <= joint.upper:
        raise InputError(f"play.{key} = {get_value(play, key)} is outside the {joint.name} "
                         "joint's travel")
    return v


def seg_link(name: str, length: float, width: float, mass: float) -> Link:
    return Link(name, mass, (0.0, length / 2, 0.0), (width, length, 0.8 * width))


def tip(finger: str, parent: str, length: float, width: float) -> tuple[Link, Joint]:
    """The pad point: on the palmar side of the distal segment, half a pad radius from its end."""
    pad = 0.4 * width
    link = Link(f"{finger}_tip", 0.0, (0.0, 0.0, 0.0), (0.001, 0.001, 0.001))
    joint = Joint(f"{finger}_tip_fixed", "fixed", parent, f"{finger}_tip",
                  (0.0, length - 0.5 * pad, -pad))
    return link, joint
