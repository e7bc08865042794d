"""What a hand is: a ``HandSpec`` (pure data), built from its TOML file by the builder
its ``kind`` names (``planner.hand.builders``, ``load_hand_spec``).

A ``HandSpec`` is the kinematic tree (links and joints with limits), the
coupling laws between joints, the actuators (which joints each motor drives
and how), the frames the planner uses, and the mount pose in the world. The
URDF is generated from it (``planner.hand.urdf``); nothing else builds a hand.

Units: SI throughout (metres, radians, kg, N m, rad/s, m/s). The TOML files
may give lengths in inches (keys ending ``_in``) and angles in degrees
(``_deg``); the builders convert them (``planner.hand.builders.values``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from planner.hand.pad import PalmPad

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
class PlayPosture:
    """The arm's postures while the hand plays (the hand file's ``[play]``): where the
    rig's reach axis may hold the forearm (m, one or more: the fingering chooses one per
    hand position; the first is the rest pose's), the wrist's flexion and deviation (rad,
    the same in every posture: a change of posture is a translation of the hand), and how
    deep below a key's top the pad point presses (m). Without it the planner fits the
    wrist (``planner.play.atlas``), holds reach at 0 and presses to the key's full dip."""

    reach_m: tuple[float, ...]
    wrist_flex_rad: float
    wrist_dev_rad: float
    press_depth_m: float


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
    play_posture: PlayPosture | None = None
    # which hand: "right" (as built) or "left" (its mirror image, ``planner.hand.mirror``)
    side: str = "right"
    # the palm's pad (the hand file's ``[palm] pad_give_m``, ``planner.hand.pad``): None
    # where the file names none
    palm_pad: PalmPad | None = None

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


HANDS_DIR = Path(__file__).parent / "hands"  # the shipped hands' files (the package's own
# folder, as its other shipped tables are read: ``importlib.resources`` would import
# ``tempfile`` and ``zipfile`` on every start, ~5 ms of CPU, for a plain folder)


def hands_dir() -> Path:
    return HANDS_DIR


def list_hands() -> list[str]:
    """Names of the hands shipped with the planner (one TOML file each): ``default``
    first (the hand every command uses unless told otherwise) and its variants
    (``default-left``), then the others by name."""
    return sorted((p.stem for p in hands_dir().glob("*.toml")),
                  key=lambda n: (n.split("-")[0] != "default", n))


ROTOR_KEY = "rotor_inertia_g_cm2"  # a motor table's rotor inertia, as data sheets give it


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
