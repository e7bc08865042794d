"""Hand descriptions: a TOML file per hand -> a ``HandSpec`` (pure data).

A ``HandSpec`` is the kinematic tree (links and joints with limits), the
coupling laws between joints, the actuators (which joints each motor drives
and how), the frames the planner uses, and the mount pose in the world. The
URDF is generated from it (``planner.hand.urdf``); nothing else builds a hand.

Units: SI throughout (metres, radians, kg, N m, rad/s, m/s). The TOML files
may give lengths in inches (keys ending ``_in``) and angles in degrees
(``_deg``); they are converted here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import tomllib

from planner.errors import InputError
from planner.hand.drive import apply_drive

INCH_M = 0.0254
FINGERS = ("thumb", "index", "middle", "ring", "pinky")
TIP_FRAMES = tuple(f"{f}_tip" for f in FINGERS)
PALM_FRAME = "palm_center"


@dataclass(frozen=True)
class Link:
    """A rigid body: a box of ``size_m`` (x, y, z) centred at ``com_m`` in the link frame."""

    name: str
    mass_kg: float
    com_m: tuple[float, float, float]
    size_m: tuple[float, float, float]

    def inertia(self) -> tuple[float, float, float]:
        """Principal moments (Ixx, Iyy, Izz) of a solid box, kg m^2."""
        a, b, c = self.size_m
        m = self.mass_kg
        return (m * (b * b + c * c) / 12.0, m * (a * a + c * c) / 12.0, m * (a * a + b * b) / 12.0)


@dataclass(frozen=True)
class Joint:
    """A URDF joint. Movable joints have limits in rad (m for prismatic), rad/s, rad/s^2."""

    name: str
    kind: str  # "revolute", "prismatic" or "fixed"
    parent: str
    child: str
    xyz_m: tuple[float, float, float]
    rpy_rad: tuple[float, float, float] = (0.0, 0.0, 0.0)
    axis: tuple[float, float, float] = (1.0, 0.0, 0.0)
    lower: float = 0.0
    upper: float = 0.0
    velocity: float = 0.0
    acceleration: float = 0.0
    effort: float = 0.0
    jerk: float = 0.0  # rad/s^3 or m/s^3 (``planner.hand.drive``)
    stop_margin: float = 0.0  # rad or m kept from each hard stop (``planner.hand.drive``)

    @property
    def movable(self) -> bool:
        return self.kind != "fixed"


@dataclass(frozen=True)
class LinearCoupling:
    """``joint = ratio * source + offset`` (hard constraint; also a URDF mimic)."""

    joint: str
    source: str
    ratio: float
    offset: float = 0.0


@dataclass(frozen=True)
class Mk5Coupling:
    """The Mk5 leverism: the second phalanx follows the first through a four-bar.

    ``joint`` (relative angle of the second phalanx) = q2(q1) - q1 where q1 is
    the ``source`` joint and q2 the absolute second-phalanx angle of the seed
    (003_c67a0a60de048708). ``table``/``finger`` name the row of the seed's tables.
    """

    joint: str
    source: str
    table: str
    finger: str


@dataclass(frozen=True)
class Actuator:
    """A motor and its transmission.

    ``kind`` is "tendon" (forearm motor pulling a tendon over a spool of
    ``radius_m`` across joints with moment arms), "servo" (in-hand servo),
    "gear" (geared motor) or "belt" (rail). For linear transmissions the motor
    shaft angle is ``q_motor = sum(coeff_j * q_j)`` over ``coefficients``
    (rad per rad, or rad per m for the rail). ``drives`` is the independent
    joint whose motion the motor sets (the others follow by coupling).
    """

    name: str
    kind: str
    drives: str
    coefficients: tuple[tuple[str, float], ...]
    speed_rad_s: float
    peak_torque_nm: float
    efficiency: float
    radius_m: float = 0.0
    mk5: Mk5Coupling | None = None  # nonlinear: q_motor from the leverism chain
    # a tendon's design force (N): the largest tension its cable may carry anywhere
    # (planner.hand.tendon); None for a motor that pulls no tendon
    tendon_force_n: float | None = None
    # the motor's rotor inertia (kg m^2, on its own shaft: the motor's data sheet);
    # 0 where the hand file names none (a servo whose gearing is not documented)
    rotor_inertia_kg_m2: float = 0.0


@dataclass(frozen=True)
class HandSpec:
    name: str
    description: str
    links: tuple[Link, ...]
    joints: tuple[Joint, ...]
    couplings: tuple[LinearCoupling | Mk5Coupling, ...]
    actuators: tuple[Actuator, ...]
    T_world_root: tuple[tuple[float, ...], ...]
    tip_frames: tuple[str, ...]
    rail_enabled: bool
    sources: tuple[tuple[str, str], ...] = field(default_factory=tuple)
    finger_joints: tuple[tuple[str, tuple[str, ...]], ...] = field(default_factory=tuple)

    @property
    def movable_joints(self) -> tuple[Joint, ...]:
        return tuple(j for j in self.joints if j.movable)

    def joint(self, name: str) -> Joint:
        for j in self.joints:
            if j.name == name:
                return j
        raise KeyError(name)

    def joints_of(self, finger: str) -> tuple[str, ...]:
        return dict(self.finger_joints)[finger]


# ---------------------------------------------------------------- loading


def hands_dir() -> Path:
    return Path(str(resources.files("planner.hand") / "hands"))


def list_hands() -> list[str]:
    """Names of the hands shipped with the planner (one TOML file each): ``default``
    first (the hand every command uses unless told otherwise), then the others by name."""
    return sorted((p.stem for p in hands_dir().glob("*.toml")), key=lambda n: (n != "default", n))


def load_hand_spec(name_or_path: str) -> HandSpec:
    """Load a shipped hand by name, or a hand file by path (.toml)."""
    path = Path(name_or_path)
    if path.suffix != ".toml":
        path = hands_dir() / f"{name_or_path}.toml"
        if not path.is_file():
            raise InputError(
                f"unknown hand {name_or_path!r}; valid hands: {', '.join(list_hands())}"
            )
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as e:
        raise InputError(f"cannot read hand file {path}: {e.strerror or e}") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        raise InputError(f"malformed hand file {path.name}: {e}") from None
    try:
        return build_spec(data)
    except InputError as e:
        raise InputError(f"malformed hand file {path.name}: {e}") from None
    except (KeyError, TypeError, ValueError, IndexError, ZeroDivisionError, AttributeError) as e:
        raise InputError(f"malformed hand file {path.name}: bad or missing entry {e}") from None


def _get(d: dict[str, Any], key: str, kind: type = float) -> Any:
    if key not in d:
        raise InputError(f"missing key {key!r}")
    v = d[key]
    if kind is float:
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise InputError(f"{key!r} must be a finite number, got {v!r}")
        return float(v)
    if not isinstance(v, kind):
        raise InputError(f"{key!r} must be a {kind.__name__}, got {v!r}")
    return v


def _length(d: dict[str, Any], key: str) -> float:
    """A length given as ``key_in`` (inches) or ``key_m`` (metres), in metres; must be > 0."""
    if f"{key}_in" in d:
        v = _get(d, f"{key}_in") * INCH_M
    else:
        v = _get(d, f"{key}_m")
    if v <= 0:
        raise InputError(f"length {key!r} must be positive")
    return v


ROTOR_KEY = "rotor_inertia_g_cm2"  # a motor table's rotor inertia, as data sheets give it


def rotor_inertia(d: dict[str, Any], key: str = ROTOR_KEY) -> float:
    """A motor's rotor inertia (kg m^2) from its table's ``key`` (g cm^2, optional: 0)."""
    if key not in d:
        return 0.0
    v = _get(d, key)
    if v < 0:
        raise InputError(f"{key!r} must not be negative, got {v!r}")
    return v * 1e-7


def _positive(d: dict[str, Any], key: str) -> float:
    v = _get(d, key)
    if v <= 0:
        raise InputError(f"{key!r} must be positive, got {v!r}")
    return v


def _range(d: dict[str, Any], key: str) -> tuple[float, float]:
    r = _get(d, key, dict)
    lo, hi = math.radians(_get(r, "lower_deg")), math.radians(_get(r, "upper_deg"))
    if not lo < hi:
        raise InputError(f"{key!r}: lower_deg must be below upper_deg")
    return lo, hi


def _vec(d: dict[str, Any], key: str, n: int = 3) -> tuple[float, ...]:
    v = _get(d, key, list)
    if len(v) != n or not all(isinstance(x, (int, float)) and math.isfinite(x) for x in v):
        raise InputError(f"{key!r} must be a list of {n} finite numbers")
    return tuple(float(x) for x in v)


def rpy_matrix(rpy: tuple[float, float, float]) -> np.ndarray:
    """URDF roll-pitch-yaw (fixed axes x, y, z) to a rotation matrix."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def build_spec(data: dict[str, Any]) -> HandSpec:
    """Build the kinematic tree of a hand from its parsed TOML."""
    kind = data.get("kind", "tendon")
    if kind == "tendon":
        return _build_tendon_hand(data)
    if kind == "mk5":
        from planner.hand.mk5_hand import build_mk5_hand

        return build_mk5_hand(data)
    if kind == "agh":
        from planner.hand.agh_hand import build_agh_hand

        return build_agh_hand(data)
    raise InputError(f"unknown hand kind {kind!r}; valid kinds: tendon, mk5, agh")


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


def start_hand(data: dict[str, Any]) -> HandParts:
    """The part every hand has: mount pose, optional rail, forearm, 2-DOF wrist, palm.

    The palm link is ``palm`` with its frame at the wrist axis, y towards the
    fingers, z out of the back of the hand; ``palm_center`` sits on the palmar
    surface with +z the outward palm normal.
    """
    mount = _get(data, "mount", dict)
    T = np.eye(4)
    T[:3, :3] = rpy_matrix(tuple(math.radians(a) for a in _vec(mount, "rpy_deg")))
    T[:3, 3] = _vec(mount, "xyz_m")
    rail = _get(data, "rail", dict)
    rail_enabled = _get(rail, "enabled", bool)
    parts = HandParts(tuple(tuple(float(x) for x in row) for row in T), rail_enabled)
    links, joints, actuators = parts.links, parts.joints, parts.actuators
    fa = _get(data, "forearm", dict)
    fa_len, fa_r = _get(fa, "length_m"), _get(fa, "radius_m")
    links.append(Link("rail_base", 0.0, (0.0, 0.0, 0.0), (0.01, 0.01, 0.01)))
    if rail_enabled:
        lo, hi = _get(rail, "lower_m"), _get(rail, "upper_m")
        if not lo < hi:
            raise InputError("rail: lower_m must be below upper_m")
        motor = _get(rail, "motor", dict)
        r_pulley = _get(motor, "radius_m")
        v_motor = _get(motor, "speed_rad_s")
        v = min(_get(rail, "velocity_m_s"), v_motor * r_pulley)
        links.append(Link("carriage", _get(rail, "mass_kg"), (0.0, 0.0, 0.0), (0.08, 0.06, 0.04)))
        joints.append(Joint("rail", "prismatic", "rail_base", "carriage", (0.0, 0.0, 0.0),
                            axis=(1.0, 0.0, 0.0), lower=lo, upper=hi, velocity=v,
                            acceleration=_get(rail, "acceleration_m_s2"),
                            effort=_get(motor, "peak_torque_nm") / r_pulley))
        actuators.append(Actuator("rail", "belt", "rail", (("rail", 1.0 / r_pulley),), v_motor,
                                  _get(motor, "peak_torque_nm"), 1.0, r_pulley,
                                  rotor_inertia_kg_m2=rotor_inertia(motor)))
        base = "carriage"
    else:
        base = "rail_base"
    links.append(Link("forearm", _get(fa, "mass_kg"), (0.0, fa_len / 2, 0.0), (2 * fa_r, fa_len, 2 * fa_r)))
    joints.append(Joint("forearm_mount", "fixed", base, "forearm", (0.0, 0.0, 0.0)))

    wr = _get(data, "wrist", dict)
    gear = _get(wr, "gear_ratio")
    wmotor = _get(wr, "motor", dict)
    links.append(Link("wrist", 0.05, (0.0, 0.0, 0.0), (0.04, 0.02, 0.03)))
    palm = _get(data, "palm", dict)
    p_len, p_wid, p_thk = _length(palm, "length"), _length(palm, "width"), _get(palm, "thickness_m")
    links.append(Link("palm", _get(palm, "mass_kg"), (0.0, p_len / 2, 0.0), (p_wid, p_len, p_thk)))
    for jname, parent, child, axis, key in (
        ("wrist_flex", "forearm", "wrist", (-1.0, 0.0, 0.0), "flex"),
        ("wrist_dev", "wrist", "palm", (0.0, 0.0, 1.0), "dev"),
    ):
        d = _get(wr, key, dict)
        lo, hi = math.radians(_get(d, "lower_deg")), math.radians(_get(d, "upper_deg"))
        if not lo < hi:
            raise InputError(f"wrist {key}: lower_deg must be below upper_deg")
        v = min(_get(d, "velocity_cap_rad_s"), _get(wmotor, "speed_rad_s") / gear)
        xyz = (0.0, fa_len, 0.0) if jname == "wrist_flex" else (0.0, 0.0, 0.0)
        joints.append(Joint(jname, "revolute", parent, child, xyz, axis=axis, lower=lo, upper=hi,
                            velocity=v, acceleration=_get(d, "acceleration_rad_s2"),
                            effort=_get(wmotor, "peak_torque_nm") * gear))
        actuators.append(Actuator(jname, "gear", jname, ((jname, gear),), _get(wmotor, "speed_rad_s"),
                                  _get(wmotor, "peak_torque_nm"), 1.0,
                                  rotor_inertia_kg_m2=rotor_inertia(wmotor)))
    links.append(Link("palm_center", 0.0, (0.0, 0.0, 0.0), (0.001, 0.001, 0.001)))
    joints.append(Joint("palm_center_fixed", "fixed", "palm", "palm_center",
                        (0.0, p_len / 2, -p_thk / 2), rpy_rad=(math.pi, 0.0, 0.0)))
    return parts


def long_fingers(data: dict[str, Any]) -> list[dict[str, Any]]:
    """The hand file's ``[[finger]]`` tables: exactly one of each finger but the thumb."""
    fingers = _get(data, "finger", list)
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
        force = _positive(_get(data, "tendon", dict), "design_force_n")
        actuators = [replace(a, tendon_force_n=force) if a.kind == "tendon" else a
                     for a in actuators]
    names = tuple(f for f, _ in finger_joints)
    if names != FINGERS[:len(names)] or not names:
        raise InputError(f"fingers must be a prefix of {', '.join(FINGERS)} in that order; "
                         f"got {', '.join(names) or 'none'}")
    src = data.get("sources", {})
    sources = tuple(sorted((str(k), str(v)) for k, v in src.items())) if isinstance(src, dict) else ()
    return HandSpec(
        name=_get(data, "name", str),
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
    )


def _seg_link(name: str, length: float, width: float, mass: float) -> Link:
    return Link(name, mass, (0.0, length / 2, 0.0), (width, length, 0.8 * width))


def _tip(finger: str, parent: str, length: float, width: float) -> tuple[Link, Joint]:
    """The pad point: on the palmar side of the distal segment, half a pad radius from its end."""
    pad = 0.4 * width
    link = Link(f"{finger}_tip", 0.0, (0.0, 0.0, 0.0), (0.001, 0.001, 0.001))
    joint = Joint(f"{finger}_tip_fixed", "fixed", parent, f"{finger}_tip",
                  (0.0, length - 0.5 * pad, -pad))
    return link, joint


@dataclass(frozen=True)
class _TendonDrive:
    """What every tendon finger of a hand file shares: the spool and its motor, the
    tendons' efficiency, the abduction servos, the fingers' speed and acceleration caps."""

    spool: float
    w_motor: float
    eff: float
    tau_peak: float
    servo: dict
    v_cap: float
    a_max: float
    rotor: float = 0.0  # the tendon motors' rotor inertia, kg m^2

    def speed(self, arm: float) -> float:
        """A joint's speed cap: the motor's speed through its moment arm, or the cap."""
        return min(self.v_cap, self.w_motor * self.spool / arm)


def _build_tendon_hand(data: dict[str, Any]) -> HandSpec:
    hp = start_hand(data)
    palm = _get(data, "palm", dict)
    p_len = _length(palm, "length")
    tendon = _get(data, "tendon", dict)
    spool = _positive(tendon, "spool_radius_m")
    eff = _get(tendon, "efficiency")
    if not 0 < eff <= 1:
        raise InputError("tendon efficiency must be in (0, 1]")
    fs = _get(data, "finger_speed", dict)
    tp = _TendonDrive(spool, _get(tendon, "motor_speed_rad_s"), eff,
                      _get(tendon, "motor_peak_torque_nm"), _get(data, "servo", dict),
                      _get(fs, "velocity_cap_rad_s"), _get(fs, "acceleration_rad_s2"),
                      rotor_inertia(tendon, "motor_" + ROTOR_KEY))
    fingers = long_fingers(data)
    _tendon_thumb(_get(data, "thumb", dict), tp, hp.links, hp.joints, hp.actuators,
                  hp.finger_joints)
    for f in sorted(fingers, key=lambda f: FINGERS.index(f["name"])):
        _tendon_finger(f, tp, p_len, hp.links, hp.joints, hp.actuators, hp.couplings,
                       hp.finger_joints)
    return assemble_spec(data, hp)


def _tendon_thumb(th: dict, tp: _TendonDrive, links, joints, actuators, finger_joints) -> None:
    """The thumb: a CMC abduction servo, CMC flexion and IP on tendons."""
    tb, tt, tw = _length(th, "base"), _length(th, "top"), _length(th, "width")
    tarm = _get(th, "moment_arm_m", dict)
    for k in ("cmc_flex", "ip"):
        _positive(tarm, k)
    tm = _get(th, "masses_kg", dict)
    cmc_xyz = _vec(th, "base_xyz_m")
    cmc_rpy = tuple(math.radians(a) for a in _vec(th, "base_rpy_deg"))
    links += [Link("thumb_cmc", 0.01, (0.0, 0.0, 0.0), (0.02, 0.02, 0.02)),
              _seg_link("thumb_base", tb, tw, _get(tm, "base")),
              _seg_link("thumb_top", tt, tw * 0.9, _get(tm, "top"))]
    lo, hi = _range(th, "cmc_abd")
    joints.append(Joint("thumb_cmc_abd", "revolute", "palm", "thumb_cmc", cmc_xyz, cmc_rpy,
                        (0.0, 0.0, 1.0), lo, hi, min(tp.v_cap, _get(tp.servo, "speed_rad_s")), tp.a_max,
                        _get(tp.servo, "peak_torque_nm")))
    lo, hi = _range(th, "cmc_flex")
    joints.append(Joint("thumb_cmc_flex", "revolute", "thumb_cmc", "thumb_base", (0.0, 0.0, 0.0),
                        axis=(-1.0, 0.0, 0.0), lower=lo, upper=hi,
                        velocity=tp.speed(_get(tarm, "cmc_flex")), acceleration=tp.a_max,
                        effort=tp.tau_peak * tp.eff / tp.spool * _get(tarm, "cmc_flex")))
    lo, hi = _range(th, "ip")
    joints.append(Joint("thumb_ip", "revolute", "thumb_base", "thumb_top", (0.0, tb, 0.0),
                        axis=(-1.0, 0.0, 0.0), lower=lo, upper=hi,
                        velocity=tp.speed(_get(tarm, "ip")), acceleration=tp.a_max,
                        effort=tp.tau_peak * tp.eff / tp.spool * _get(tarm, "ip")))
    tl, tj = _tip("thumb", "thumb_top", tt, tw * 0.9)
    links.append(tl)
    joints.append(tj)
    actuators += [
        Actuator("thumb_cmc_abd", "servo", "thumb_cmc_abd",
                 (("thumb_cmc_abd", _get(tp.servo, "gear_ratio")),), _get(tp.servo, "speed_rad_s"),
                 _get(tp.servo, "peak_torque_nm"), 1.0),
        Actuator("thumb_cmc_flex", "tendon", "thumb_cmc_flex",
                 (("thumb_cmc_flex", _get(tarm, "cmc_flex") / tp.spool),), tp.w_motor, tp.tau_peak,
                 tp.eff, tp.spool, rotor_inertia_kg_m2=tp.rotor),
        Actuator("thumb_ip", "tendon", "thumb_ip", (("thumb_ip", _get(tarm, "ip") / tp.spool),),
                 tp.w_motor, tp.tau_peak, tp.eff, tp.spool,
                 rotor_inertia_kg_m2=tp.rotor),
    ]
    finger_joints.append(("thumb", ("thumb_cmc_abd", "thumb_cmc_flex", "thumb_ip")))


def _tendon_finger(f: dict, tp: _TendonDrive, p_len: float, links, joints, actuators,
                   couplings, finger_joints) -> None:
    """A long finger: an MCP abduction servo, MCP flexion on one tendon, PIP and DIP on
    another (the DIP coupled to the PIP)."""
    n = f["name"]
    lb, lm, lt, w = _length(f, "base"), _length(f, "middle"), _length(f, "top"), _length(f, "width")
    arm = _get(f, "moment_arm_m", dict)
    ms = _get(f, "masses_kg", dict)
    ratio = _get(f, "dip_ratio")
    if not 0.0 < ratio <= 1.5:
        raise InputError(f"{n}: dip_ratio must be in (0, 1.5] (the seed uses 0.667, 0.556, 0.333)")
    links += [Link(f"{n}_knuckle", 0.005, (0.0, 0.0, 0.0), (0.01, 0.01, 0.01)),
              _seg_link(f"{n}_base", lb, w, _get(ms, "base")),
              _seg_link(f"{n}_middle", lm, w * 0.95, _get(ms, "middle")),
              _seg_link(f"{n}_top", lt, w * 0.9, _get(ms, "top"))]
    lo_a, hi_a = _range(f, "abd")
    joints.append(Joint(f"{n}_mcp_abd", "revolute", "palm", f"{n}_knuckle",
                        (_get(f, "mcp_x_m"), p_len, float(f.get("mcp_z_m", 0.0))),
                        axis=(0.0, 0.0, 1.0), lower=lo_a,
                        upper=hi_a, velocity=min(tp.v_cap, _get(tp.servo, "speed_rad_s")),
                        acceleration=tp.a_max, effort=_get(tp.servo, "peak_torque_nm")))
    a_mcp, a_pip, a_dip = _positive(arm, "mcp"), _positive(arm, "pip"), _positive(arm, "dip")
    # one tendon crosses the PIP and the DIP: its motor turns
    # (a_pip + ratio a_dip) / tp.spool per PIP radian
    a_pip_eff = a_pip + ratio * a_dip
    v_pip = tp.speed(a_pip_eff)
    for jn, parent, child, xyz, key, v, a in (
        ("mcp_flex", f"{n}_knuckle", f"{n}_base", (0.0, 0.0, 0.0), "mcp", tp.speed(a_mcp), a_mcp),
        ("pip", f"{n}_base", f"{n}_middle", (0.0, lb, 0.0), "pip", v_pip, a_pip),
        ("dip", f"{n}_middle", f"{n}_top", (0.0, lm, 0.0), "dip", ratio * v_pip, a_dip),
    ):
        lo, hi = _range(f, key)
        joints.append(Joint(f"{n}_{jn}", "revolute", parent, child, xyz, axis=(-1.0, 0.0, 0.0),
                            lower=lo, upper=hi, velocity=v, acceleration=tp.a_max,
                            effort=tp.tau_peak * tp.eff / tp.spool * a))
    # the DIP follows the PIP: its range must hold ratio x the PIP's range
    pip, dip = joints[-2], joints[-1]
    if not (dip.lower <= ratio * pip.lower + 1e-12 and ratio * pip.upper <= dip.upper + 1e-12):
        raise InputError(f"{n}: dip range does not contain dip_ratio x pip range")
    couplings.append(LinearCoupling(f"{n}_dip", f"{n}_pip", ratio))
    tl, tj = _tip(n, f"{n}_top", lt, w * 0.9)
    links.append(tl)
    joints.append(tj)
    actuators += [
        Actuator(f"{n}_abd", "servo", f"{n}_mcp_abd", ((f"{n}_mcp_abd", _get(tp.servo, "gear_ratio")),),
                 _get(tp.servo, "speed_rad_s"), _get(tp.servo, "peak_torque_nm"), 1.0),
        Actuator(f"{n}_mcp", "tendon", f"{n}_mcp_flex", ((f"{n}_mcp_flex", a_mcp / tp.spool),),
                 tp.w_motor, tp.tau_peak, tp.eff, tp.spool,
                 rotor_inertia_kg_m2=tp.rotor),
        # one tendon crosses the PIP and the DIP
        Actuator(f"{n}_pip", "tendon", f"{n}_pip",
                 ((f"{n}_pip", a_pip / tp.spool), (f"{n}_dip", a_dip / tp.spool)),
                 tp.w_motor, tp.tau_peak, tp.eff, tp.spool,
                 rotor_inertia_kg_m2=tp.rotor),
    ]
    finger_joints.append((n, (f"{n}_mcp_abd", f"{n}_mcp_flex", f"{n}_pip", f"{n}_dip")))
