"""How hard a key is pressed, and how hard a finger can press it.

``press_force_n``: MIDI velocity -> press force at the fingertip, ``force_n = 0.5 + 2.5
(v/127)^2``: 0.5 N is a real key's weight (the force that just holds a piano key down),
3 N a forte press (set when every press pose of the default hand held 3.58 N or more,
docs/history/hand-strength.md). The atlas's poses carry the largest force each can press
within the motors' torque (``AtlasEntry.max_force_n``). ``pressed_force_n``: a pose presses
a note with the note's force, or with all it holds where that is less (a forte note
softer, never past the motors' bound): the key goes down all the same, the rows are the
same poses, and the replay and ``check`` push the key with its own force whatever the
velocity. Since the tendons' design force, the default hand's poses hold 2.35-3.16 N:
3 N only by the index, so a note asking it was the index's alone, a forte line an arm move
at every note and every other note left out (``too_late``:
docs/history/2026-12-07-play-forte.md). A pose whose descent does not drive the key down
(``press_capacity_n``: 0) presses no note.

``press_capacity_n``: that force for one press, along the whole descent, not at the press
pose alone. The key must be driven down from its top: at each depth ``d`` of its travel
its spring asks ``front_force_n(d)`` (``planner.simulate.keyboard``: the replay's key, its
0.5 N down-weight at the top, 0.94 N at the 5 mm key-down depth), and the pad slides on
the key top as the finger's path moves it along the key (a finger of one degree of
freedom presses along its arc; any finger along its joint-space move from hover to
press), so the key's push on the pad has, beside its normal ``N`` up, the pad's kinetic
friction ``mu N`` against that slide (``PAD_FRICTION``, the replay's rubber pad). The
motors must hold ``N (z - mu s)`` (``s`` the slide's horizontal unit direction) with
gravity, each within its capacity (``actuator_capacity``). A press counts only if at every
sampled depth down to the key-down depth that ``N`` is at least the spring's force; its
capacity is then the force the motors hold at the press pose (the key at its depth, the
pad at rest: no friction), the most a note is pressed with there (a note's force is the
one it is held down with; on the way down the key asks its spring's). Where the
descent fails, 0: no note is pressed there (its notes are left out for ``torque``). (On the
default hand the descent with friction holds 1.8-1.9 N where its spring asks 0.94 N at
most: no press of its atlas fails it.)

Measured on the Mk5's pinky (docs/history/2026-12-06-three-hands.md): the press pose
alone holds 1.79 N, the descent with the pad's friction 0.39 N against the key's 0.51 N at
its top; in the replay the pinky stalls on the key's top.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from planner.hand.model import HandModel
from planner.hand.tendon import actuator_capacity
from planner.music import keyboard as kb
from planner.simulate.hand_mjcf import PAD_FRICTION
from planner.simulate.keyboard import front_force_n, key_body

MIN_FORCE_N = 0.5
MAX_FORCE_N = 3.0
DESCENT_SAMPLES = 12  # poses along the move hover -> press (both ends), as the atlas's path
# test (``PATH_SAMPLES``): from 5.5 mm above the key to 6 mm into it, about 1 mm apart, the
# first below the key's top within about 1 mm of it
SLIDE_MIN_M = 1e-7  # a pad moving less than this along the key between samples rests


def press_force_n(velocity: int) -> float:
    """Press force (N) for a MIDI velocity 0..127."""
    v = min(max(velocity, 0), 127) / 127.0
    return MIN_FORCE_N + (MAX_FORCE_N - MIN_FORCE_N) * v * v


def pressed_force_n(force_n: float, max_force_n: float) -> float:
    """The force (N) a press pose holding at most ``max_force_n`` (``AtlasEntry``) presses a
    note asking ``force_n`` with: the note's, or all the pose holds where that is less; 0
    (no note pressed there) where the pose's descent does not drive the key down."""
    return min(force_n, max_force_n)


def held_force_n(hand: HandModel, q: np.ndarray, finger: str,
                 slide_xy: np.ndarray | None = None, friction: float = 0.0) -> float:
    """The largest normal key force ``N`` (N) on ``finger``'s pad point that every motor
    holds at ``q`` with gravity, the key pushing the pad with ``N (-mu s_x, -mu s_y, 1)``
    (``slide_xy``: the pad's sliding direction on the key, unit, or None at rest):
    tau(N) = tau(0) + N (tau(1) - tau(0)), each |tau_m| within its capacity."""
    tau0 = hand.press_torques(q, {})
    if slide_xy is None:  # (a vertical push: ``HandModel.press_torques``, to the bit)
        tau1 = hand.press_torques(q, {finger: 1.0}) - tau0
    else:
        push = np.array([*(-friction * np.asarray(slide_xy, dtype=float)), 1.0])
        J = hand.tip_jacobians(q)[hand.fingers.index(finger)]
        tau1 = hand.motor_torques(q, hand.gravity_torques(q) - J.T @ push) - tau0
    peak = actuator_capacity(hand).torque_nm
    best = math.inf
    for t0, t1, p in zip(tau0, tau1, peak):
        if abs(t0) > p:
            return 0.0
        if t1 > 1e-12:
            best = min(best, (p - t0) / t1)
        elif t1 < -1e-12:
            best = min(best, (-p - t0) / t1)
    return float(best)


def descent_poses(hand: HandModel, hover: np.ndarray, press: np.ndarray) -> list[np.ndarray]:
    """``DESCENT_SAMPLES`` poses on the straight joint-space move hover -> press (the
    couplings applied: a one-DOF finger's are on its arc), the last ``press`` itself."""
    return [*(hand.apply_couplings(hover + s * (press - hover))
              for s in np.linspace(0.0, 1.0, DESCENT_SAMPLES)[:-1]), press]


def press_capacity_n(hand: HandModel, poses: Sequence[np.ndarray], finger: str,
                     pitch: int) -> float:
    """The press force (N) ``finger`` can give on key ``pitch`` along ``poses`` (hover
    to press, ``descent_poses``): 0 where at some depth to the key-down depth the motors
    cannot hold the key's spring with the pad's friction; else the force they hold on
    the key at the press pose (see the module docstring)."""
    f = hand.fingers.index(finger)
    top = kb.key(pitch).top_z_m
    key = key_body(pitch)
    tips = np.array([hand.tip_positions(q)[f] for q in poses])
    for i in range(len(poses) - 1):
        depth = top - tips[i + 1, 2]
        if depth <= 0.0:
            continue  # (above the key: nothing to push)
        step = tips[i + 1, :2] - tips[i, :2]
        n = float(np.linalg.norm(step))
        slide = step / n if n > SLIDE_MIN_M else None
        # the segment's deeper end, where the spring asks more (down to the key-down depth)
        held = held_force_n(hand, poses[i + 1], finger, slide, PAD_FRICTION)
        if held < front_force_n(key, min(depth, kb.DOWN_DEPTH_M)):
            return 0.0
    return held_force_n(hand, poses[-1], finger)
