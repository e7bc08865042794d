"""The physical keyboard of the replay: 88 keys with the spec's geometry and its motion.

Geometry (spec section 2, from ``planner.music.keyboard``, never typed in again):
every key's footprint, resting top and 10 mm dip. A white key is two boxes: its front
(y in [0, 0.060], full width) and its back between the black keys (its footprint less
the black rectangles, as the spec's key-down rule has it). A black key is one box.

Motion: the spec's key, which dips ``KEY_DIP_M`` (10 mm) wherever its footprint is
pressed and is down once ``DOWN_DEPTH_M`` (5 mm) below its resting top: each key moves
straight down on a slide joint whose upper limit is the key bed (a hard stop at the
10 mm dip) and whose return spring holds it up against its rest stop with the key's
down-weight and pushes it back when released. (The first version hinged each key on a
balance rail 0.25 m behind its front, as a grand piano's key turns: a press between the
black keys, 0.12 m in front of the rail, then met the bed 4.8 mm down, not the spec's
10 mm, and a pad lifted 2.7 mm between two presses of a key kept its front 5.6 mm down:
the key never rose, the repeated note never sounded -- 0.944 F1 on chords where the
spec's key gives 0.990; docs/history/physics-replay.md.)

Constants (each a physical value with its source):

* Moving mass: RoboPianist's key (``WHITE_KEY_MASS_KG`` 0.040, ``BLACK_KEY_MASS_KG``
  0.020, a uniform stick hinged at its back end: ``I = m L^2 / 3``) at its front, as its
  spring is: ``I / L^2 = m / 3`` (13.3 g, 6.7 g). A released key passes back above 5 mm
  14 ms after leaving its bed (the whole 40 g moving straight down: 20 ms).
* ``DOWN_WEIGHT_N`` 0.5: the force on the key that just starts it down (a grand
  piano's down-weight is about 50 g, 0.49 N; ``planner.play.force.MIN_FORCE_N`` is the
  same 0.5 N, "a real key's weight"). It sets the spring's preload.
* ``KEY_STIFFNESS_N_M``: RoboPianist's key return spring (2 N m/rad about its hinge at
  the back of its 0.150 m key) at that key's front, where the spec measures the dip:
  2 / 0.150^2 = 88.9 N/m (0.5 N at rest, 1.39 N at the bed).
* Damping: critical (no bounce at the rest stop) for that mass: ``2 sqrt(k m)`` = 2.18
  N s/m for a white key; RoboPianist's 0.05 N m s/rad at its front is 2.22.
* No hammer action: the key alone (a digital keyboard's action).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache

import numpy as np

from planner.music import keyboard as kb

WHITE_KEY_MASS_KG = 0.040  # RoboPianist (Zakka et al. 2023), piano_constants.WHITE_KEY_MASS
BLACK_KEY_MASS_KG = 0.020  # RoboPianist, piano_constants.BLACK_KEY_MASS
ROBOPIANIST_KEY_STIFFNESS_NM_RAD = 2.0  # RoboPianist, piano_constants.WHITE_KEY_STIFFNESS
ROBOPIANIST_KEY_LENGTH_M = 0.150  # its hinge at the back of the visible key
KEY_STIFFNESS_N_M = ROBOPIANIST_KEY_STIFFNESS_NM_RAD / ROBOPIANIST_KEY_LENGTH_M ** 2
FRONT_MASS_SHARE = 1.0 / 3.0  # a uniform stick hinged at one end, at its other end: I / L^2
DOWN_WEIGHT_N = 0.5  # grand piano down-weight ~50 g (0.49 N); play.force.MIN_FORCE_N
KEY_THICKNESS_M = kb.WHITE_WIDTH_M  # a white key as tall as it is wide (RoboPianist)
GRAVITY_M_S2 = 9.81


@dataclass(frozen=True)
class KeyBox:
    """One box of a key, in the keyboard frame: centre and half sizes (m)."""

    center_m: tuple[float, float, float]
    half_m: tuple[float, float, float]

    @property
    def volume_m3(self) -> float:
        return 8.0 * self.half_m[0] * self.half_m[1] * self.half_m[2]


@dataclass(frozen=True)
class KeyBody:
    """A key as the replay builds it: boxes, mass, spring, its key-down and bed travel."""

    pitch: int
    black: bool
    boxes: tuple[KeyBox, ...]  # the visible key (collides)
    mass_kg: float  # moving with the press (see the module docstring)
    com_m: tuple[float, float, float]
    down_m: float  # travel at which it sounds: the spec's DOWN_DEPTH_M
    dip_m: float  # travel to the key bed: KEY_DIP_M
    springref_m: float  # spring rest position (< 0: the preload against the rest stop)
    damping_ns_m: float

    @property
    def name(self) -> str:
        return f"key_{self.pitch}"


def _boxes(pitch: int) -> tuple[KeyBox, ...]:
    """Every key stands on the key frame, ``KEY_THICKNESS_M`` below the white tops: a
    black key is taller by its 12.5 mm rise, so its sides wall the slot between the
    black keys down to the frame (a box as thick as a white key, hanging 10 mm below the
    white tops, offered its bottom face to a finger pressing a white key to its bed)."""
    k = kb.key(pitch)
    bottom = -KEY_THICKNESS_M  # (the white keys' resting top is z = 0)
    hz = 0.5 * (k.top_z_m - bottom)
    zc = k.top_z_m - hz

    def box(x0: float, x1: float, y0: float, y1: float) -> KeyBox:
        return KeyBox((0.5 * (x0 + x1), 0.5 * (y0 + y1), zc),
                      (0.5 * (x1 - x0), 0.5 * (y1 - y0), hz))

    return tuple(box(*r) for r in kb.footprint(pitch))


@cache
def key_body(pitch: int) -> KeyBody:
    """The physical key of a MIDI pitch 21..108."""
    k = kb.key(pitch)
    boxes = _boxes(pitch)
    mass = FRONT_MASS_SHARE * (BLACK_KEY_MASS_KG if k.black else WHITE_KEY_MASS_KG)
    vol = sum(b.volume_m3 for b in boxes)
    com = tuple(sum(b.center_m[i] * b.volume_m3 for b in boxes) / vol for i in range(3))
    # at rest the spring holds the key up with the down-weight beyond its own weight:
    # k (0 - springref) = DOWN_WEIGHT_N + m g
    preload_n = DOWN_WEIGHT_N + mass * GRAVITY_M_S2
    return KeyBody(
        pitch=pitch, black=k.black, boxes=boxes, mass_kg=mass, com_m=com,
        down_m=kb.DOWN_DEPTH_M, dip_m=kb.KEY_DIP_M, springref_m=-preload_n / KEY_STIFFNESS_N_M,
        damping_ns_m=2.0 * math.sqrt(KEY_STIFFNESS_N_M * mass))


def key_bodies() -> tuple[KeyBody, ...]:
    """All 88 keys, A0 to C8 (index = pitch - 21, as the check's key arrays)."""
    return tuple(key_body(p) for p in kb.ALL_PITCHES)


def front_force_n(key: KeyBody, travel_m: float) -> float:
    """The static force on the key that holds it ``travel_m`` down (N): spring minus
    the key's weight."""
    return KEY_STIFFNESS_N_M * (travel_m - key.springref_m) - key.mass_kg * GRAVITY_M_S2


def planned_key_travel(contacts) -> np.ndarray:
    """(T, 88) each key's travel under the pad points of ``contacts``
    (``check.criteria.key_contacts``): as deep as the deepest pad on it, at most to its
    bed -- the keys of a kinematic replay."""
    tip_key = np.asarray(contacts.tip_key)
    depth = np.clip(np.nan_to_num(np.asarray(contacts.tip_depth)), 0.0, kb.KEY_DIP_M)
    out = np.zeros((tip_key.shape[0], len(kb.ALL_PITCHES)))
    T, F = np.nonzero(tip_key >= 0)
    np.maximum.at(out, (T, tip_key[T, F]), depth[T, F])
    return out
