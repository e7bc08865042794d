"""The servos' tracking margin: a moving finger keeps from the black keys the distance
its drive lags behind its rows.

Each joint of the hand is a position servo (``planner.simulate.actuators``); following a
ramp it lags behind its target by an error that grows with the ramp's speed. Measured in
the physics replay (``docs/history/2026-12-06-play-lift.md``, the wrong key of
``dance_oneills1850_0051-0100_0``: the middle finger's ``mcp_flex`` and ``pip`` lagging
0.0128 and 0.011 rad while moving at 9.28 rad/s) and carried to the finger's end by
forward kinematics, that is ``TRACKING_MARGIN_M`` (1.06 mm) at ``TRACKING_SPEED_RAD_S``;
the lag scales with the speed. The body rule lets a planned body touch another key by
``OTHER_KEY_TOLERANCE_M`` (0.5 mm: it does not sound); a lagging body touches it by the
lag more. So each move between an entry's poses (``Moves``' ``SCALE_PAIRS``) is tested at
``MOMENTS`` moments of its timed profile against every black key but its own: the body's
reach into the key's box plus the lag at the finger's speed then must stay within the
tolerance. A move that does not is slowed (never refused) until it does: its lag shrinks
with its speed (a uniform time scale keeps the path). A moment whose body already
reaches further than the tolerance at rest is the body rule's (the atlas's), not this
margin's: it is not weighed here.
"""

from __future__ import annotations

import json

import numpy as np

from planner.music import keyboard as kb
from planner.play.fingerbody import OTHER_KEY_TOLERANCE_M, many_box_penetration
from planner.play.profile import Move

TRACKING_MARGIN_M = 0.00106  # the lag at the finger's end at ``TRACKING_SPEED_RAD_S``
TRACKING_SPEED_RAD_S = 9.28  # (the measured row above: mcp_flex 0.0128 rad, pip 0.011 rad)
MOMENTS = 49  # moments of a move's timed profile tested (its ends included)
SPEED_STEP = 1e-4  # the path's speed at a moment: a central difference of this share of
# the move's duration (the profile is smooth: a double S with jerk ramps)


def params() -> str:
    """What the margin's scales depend on (in the move table's parameters)."""
    return json.dumps({"tracking_margin_m": TRACKING_MARGIN_M,
                       "tracking_speed_rad_s": TRACKING_SPEED_RAD_S, "moments": MOMENTS,
                       "speed_step": SPEED_STEP, "tolerance_m": OTHER_KEY_TOLERANCE_M},
                      sort_keys=True)


def lag_m(speed_rad_s: np.ndarray) -> np.ndarray:
    """The lag at the finger's end (m) of a finger whose fastest joint moves at
    ``speed_rad_s``."""
    return TRACKING_MARGIN_M * np.asarray(speed_rad_s) / TRACKING_SPEED_RAD_S


def margin_scale(atlas, finger: str, pitch_class: int, dx_m: float, move: Move) -> float:
    """How much slower ``move`` (``finger``'s joints, of the entry over key ``60 +
    pitch_class`` at ``dx_m``, the rest of the hand at ``atlas``'s natural pose, the rail
    where it puts the finger over that key) must run for its lag to fit beside every other
    black key (1: it fits as it is; always 1 without the atlas's body rule)."""
    bodies = atlas.bodies
    if bodies is None or move.duration_s <= 0.0:
        return 1.0
    hand = atlas.hand
    js = hand.joint_slice(finger)
    pitch = 60 + pitch_class
    t = np.linspace(0.0, move.duration_s, MOMENTS)
    h = SPEED_STEP * move.duration_s
    ds = (move.s(t + h) - move.s(t - h)) / (np.minimum(t + h, move.duration_s)
                                           - np.maximum(t - h, 0.0))
    lag = lag_m(ds * float(np.max(np.abs(move.dq))))  # (the fastest joint's speed)
    Q = np.repeat(atlas.base[None, :], MOMENTS, axis=0)
    Q[:, js] = move.at(t)
    if atlas.rail is not None:
        Q[:, atlas.rail] = kb.key(pitch).center_x_m - dx_m
    P = bodies.points_many(hand.apply_couplings(Q), finger)
    r = bodies.radii(finger)
    black = np.array([kb.is_black(int(p)) and int(p) != pitch for p in bodies.box_pitch])
    reach = float(r.max()) + float(lag.max())  # (a box further off leaves the lag room)
    flat = P.reshape(-1, 3)
    lo, hi = bodies.box_lo, bodies.box_hi
    near = black & np.all((lo <= flat.max(axis=0) + reach) & (hi >= flat.min(axis=0) - reach),
                          axis=1)
    if not near.any():
        return 1.0
    depth = many_box_penetration(P, r, lo[near], hi[near]).max(axis=1)  # (MOMENTS,)
    room = OTHER_KEY_TOLERANCE_M - depth
    weighed = (room > 0.0) & (lag > room)
    if not weighed.any():
        return 1.0
    return float(np.max(lag[weighed] / room[weighed]))
