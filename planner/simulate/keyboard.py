"""The physical keyboard of the replay: 88 hinged keys with the spec's geometry.

Geometry (spec section 2, from ``planner.music.keyboard``, never typed in again):
every key's footprint, resting top and 10 mm dip. A white key is two boxes: its front
(y in [0, 0.060], full width) and its back between the black keys (its footprint less
the black rectangles, as the spec's key-down rule has it). A black key is one box.

Each key is a lever on its balance rail: it turns about a hinge along x
``PIVOT_Y_M`` = 0.25 m behind its front (a grand piano's key is about 0.45-0.5 m long
with the balance rail near its middle; the spec shows only the front 0.150 m, the rest
lies under the fallboard and is modelled as the same stick without collision), at the
height of its top, so its front dips ``KEY_DIP_M`` when the key has turned
``dip_angle_rad`` and its front is ``DOWN_DEPTH_M`` (5 mm) down at
``down_angle_rad``: the spec's key-down depth at the key front, as an angle. The
joint's upper limit is the key bed (a hard stop); a return spring holds the key up
against its rest stop with the key's down-weight and pushes it back when released.

Constants (each a physical value with its source):

* ``WHITE_KEY_MASS_KG`` 0.040, ``BLACK_KEY_MASS_KG`` 0.020: RoboPianist's key masses.
* ``DOWN_WEIGHT_N`` 0.5: the force at the key front that just starts a key down (a
  grand piano's down-weight is about 50 g, 0.49 N; ``planner.play.force.MIN_FORCE_N``
  is the same 0.5 N, "a real key's weight"). It sets the spring's preload.
* ``KEY_STIFFNESS_NM_RAD`` 2.0: RoboPianist's key return spring (N m/rad).
* Damping: critical (no bounce at the rest stop) for each key's own inertia about its
  hinge: ``2 sqrt(k I)``; RoboPianist's 0.05 N m s/rad is that value for its white key.
* No hammer action: the key is the stick alone (a digital keyboard's action), its mass
  spread over the lever (front to balance rail).

(RoboPianist hinges its keys at the back end of the visible 0.150 m; there a press
between the black keys, 25 mm in front of the hinge, could dip only 1.7 mm: this
hand's plans press there, which a real key allows.)
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache

import numpy as np

from planner.music import keyboard as kb

WHITE_KEY_MASS_KG = 0.040  # RoboPianist (Zakka et al. 2023), piano_constants.WHITE_KEY_MASS
BLACK_KEY_MASS_KG = 0.020  # RoboPianist, piano_constants.BLACK_KEY_MASS
KEY_STIFFNESS_NM_RAD = 2.0  # RoboPianist, piano_constants.WHITE_KEY_STIFFNESS
DOWN_WEIGHT_N = 0.5  # grand piano down-weight ~50 g (0.49 N); play.force.MIN_FORCE_N
KEY_THICKNESS_M = kb.WHITE_WIDTH_M  # a key stick as tall as a white key is wide (RoboPianist)
PIVOT_Y_M = 0.25  # balance rail: about mid-length of a 0.45-0.5 m grand piano key
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
    """A key as the replay builds it: boxes, hinge, mass, spring and the key-down angle."""

    pitch: int
    black: bool
    boxes: tuple[KeyBox, ...]  # the visible key (collides)
    hidden: KeyBox  # the stick under the fallboard, to the balance rail (mass only)
    pivot_m: tuple[float, float, float]  # a point of the hinge axis (along +x)
    lever_m: float  # pivot to the key front, along y
    mass_kg: float
    com_m: tuple[float, float, float]
    inertia_kg_m2: float  # about the hinge
    down_angle_rad: float  # the front DOWN_DEPTH_M down
    dip_angle_rad: float  # the front KEY_DIP_M down: the key bed
    springref_rad: float  # spring rest angle (< 0: the preload against the rest stop)
    damping_nms_rad: float

    @property
    def name(self) -> str:
        return f"key_{self.pitch}"


def _white_back_x(pitch: int) -> tuple[float, float]:
    """x range of a white key's back part: its footprint less its black neighbours'."""
    k = kb.key(pitch)
    lo, hi = k.x_min_m, k.x_max_m
    if pitch - 1 >= kb.LOWEST_PITCH and kb.is_black(pitch - 1):
        lo = max(lo, kb.key(pitch - 1).x_max_m)
    if pitch + 1 <= kb.HIGHEST_PITCH and kb.is_black(pitch + 1):
        hi = min(hi, kb.key(pitch + 1).x_min_m)
    return lo, hi


def _boxes(pitch: int) -> tuple[KeyBox, ...]:
    k = kb.key(pitch)
    hz = 0.5 * KEY_THICKNESS_M
    zc = k.top_z_m - hz

    def box(x0: float, x1: float, y0: float, y1: float) -> KeyBox:
        return KeyBox((0.5 * (x0 + x1), 0.5 * (y0 + y1), zc),
                      (0.5 * (x1 - x0), 0.5 * (y1 - y0), hz))

    if k.black:
        return (box(k.x_min_m, k.x_max_m, k.y_min_m, k.y_max_m),)
    lo, hi = _white_back_x(pitch)
    return (box(k.x_min_m, k.x_max_m, k.y_min_m, kb.BLACK_Y0_M),
            box(lo, hi, kb.BLACK_Y0_M, k.y_max_m))


def _hidden(pitch: int) -> KeyBox:
    k = kb.key(pitch)
    hz = 0.5 * KEY_THICKNESS_M
    x0, x1 = (k.x_min_m, k.x_max_m) if k.black else _white_back_x(pitch)
    return KeyBox((0.5 * (x0 + x1), 0.5 * (k.y_max_m + PIVOT_Y_M), k.top_z_m - hz),
                  (0.5 * (x1 - x0), 0.5 * (PIVOT_Y_M - k.y_max_m), hz))


@cache
def key_body(pitch: int) -> KeyBody:
    """The physical key of a MIDI pitch 21..108."""
    k = kb.key(pitch)
    boxes = _boxes(pitch)
    hidden = _hidden(pitch)
    mass = BLACK_KEY_MASS_KG if k.black else WHITE_KEY_MASS_KG
    parts = (*boxes, hidden)
    vol = sum(b.volume_m3 for b in parts)
    pivot = (0.0, PIVOT_Y_M, k.top_z_m)
    com = tuple(sum(b.center_m[i] * b.volume_m3 for b in parts) / vol for i in range(3))
    inertia = 0.0
    for b in parts:  # each box about the hinge axis (x): own inertia + parallel axis
        m = mass * b.volume_m3 / vol
        dy, dz = b.center_m[1] - pivot[1], b.center_m[2] - pivot[2]
        own = m * ((2 * b.half_m[1]) ** 2 + (2 * b.half_m[2]) ** 2) / 12.0
        inertia += own + m * (dy * dy + dz * dz)
    lever = PIVOT_Y_M - k.y_min_m
    # at rest the spring holds the key up with the down-weight at its front beyond the
    # key's own weight: k (0 - springref) = DOWN_WEIGHT_N lever + m g (pivot - com)
    preload_nm = DOWN_WEIGHT_N * lever + mass * GRAVITY_M_S2 * (PIVOT_Y_M - com[1])
    return KeyBody(
        pitch=pitch, black=k.black, boxes=boxes, hidden=hidden, pivot_m=pivot, lever_m=lever,
        mass_kg=mass, com_m=com, inertia_kg_m2=inertia,
        down_angle_rad=math.atan(kb.DOWN_DEPTH_M / lever),
        dip_angle_rad=math.atan(kb.KEY_DIP_M / lever),
        springref_rad=-preload_nm / KEY_STIFFNESS_NM_RAD,
        damping_nms_rad=2.0 * math.sqrt(KEY_STIFFNESS_NM_RAD * inertia))


def key_bodies() -> tuple[KeyBody, ...]:
    """All 88 keys, A0 to C8 (index = pitch - 21, as the check's key arrays)."""
    return tuple(key_body(p) for p in kb.ALL_PITCHES)


def front_force_n(key: KeyBody, angle_rad: float) -> float:
    """The static force at the key front that holds the key at ``angle_rad`` (N):
    spring minus the key's weight, over the lever."""
    spring = KEY_STIFFNESS_NM_RAD * (angle_rad - key.springref_rad)
    weight = key.mass_kg * GRAVITY_M_S2 * (key.pivot_m[1] - key.com_m[1]) * math.cos(angle_rad)
    return (spring - weight) / key.lever_m


def planned_key_angles(tips_m, contacts) -> np.ndarray:
    """(T, 88) each key's hinge angle under pad points ``tips_m`` (T, 5, 3), as far down
    as the deepest pad on it holds it (``contacts``: ``check.criteria.key_contacts`` of
    those points), at most to its bed: the keys of a kinematic replay, as angles."""
    keys = key_bodies()
    out = np.zeros((len(tips_m), len(keys)))
    T, F = np.nonzero((contacts.tip_key >= 0) & (np.nan_to_num(contacts.tip_depth) > 0))
    for t, f in zip(T, F):
        kb_ = keys[int(contacts.tip_key[t, f])]
        angle = min(kb_.dip_angle_rad, math.atan2(float(contacts.tip_depth[t, f]),
                                                  kb_.pivot_m[1] - float(tips_m[t, f, 1])))
        k = int(contacts.tip_key[t, f])
        out[t, k] = max(out[t, k], angle)
    return out
