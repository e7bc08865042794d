"""Trajectory files built without the planner, for the tests of planner.check and
planner.report (no test here).

A tiny damped-least-squares IK puts one fingertip on a key (wrist flexed 20 deg, the
other fingers hyperextended so their tips stay ~10 cm above the keys), and keyframes
are joined by minimum-jerk segments, which keep speeds and accelerations inside the
hand's limits. A catch: the ball arrives along the palm's normal onto the palm while
thumb, index and middle close around it.
"""

from __future__ import annotations

from functools import cache, lru_cache
from pathlib import Path

import numpy as np

from planner.check.bodykeys import body_keys
from planner.check.kinematics import Kinematics
from planner.hand.bodies import collision_bodies
from planner.hand.model import load_hand
from planner.music.keyboard import LOWEST_PITCH, key
from planner.music.midi import Note, write_notes_midi
from planner.trajfile import end_line, format_rows, header_line, metadata_line

RATE = 100.0
RAMP_S = 0.08  # press / release ramp; the 5 mm threshold is crossed at its middle
HOVER_M = -0.008  # a finger waiting to press: its deepest body this far above the key's top


def meta(h, task="play", **extra):
    return {"task": task, "hand": "default", "urdf_sha256": h.urdf_sha256,
            "T_world_root": h.T_world_root.tolist(), "rate_hz": RATE, **extra}


def write_traj(path, hand, t, q, qm=None, metadata=None, joint_names=None, motor_names=None,
               end_info=None):
    """A file in the planner's format, written without its writer's guard: the check's
    tests need files no planner may write (rows out of the limits, other columns)."""
    q = np.asarray(q, dtype=float)
    rows = format_rows(t, q, hand.motor_angles(q) if qm is None else np.asarray(qm))
    text = (metadata_line(metadata or meta(hand))
            + header_line(joint_names or hand.joint_names, motor_names or hand.motor_names)
            + rows.text + end_line(len(rows.t_s), end_info))
    with open(path, "w", encoding="utf-8", newline="") as f:
        f.write(text)
    return str(path)


# ---------------------------------------------------------------- a tiny IK


def _idx(hand, *names):
    return [hand.index[n] for n in names]


def base_posture(hand, wrist_deg=None):
    """The neutral hand, the long fingers hyperextended: every joint its stop margin off
    its stops (``HandModel.plan_lower``, ``plan_upper``), as a plan's rows keep them; the
    wrist in the hand file's play posture (``[play]``; reach mid-travel) unless ``wrist_deg``
    is given (the default hand's forearm is 0.05 m over the keys since session 37; the
    tests built with the wrist 20 deg down over a rail 0.17 m high until then)."""
    q = hand.q_neutral.copy()
    for f in ("index", "middle", "ring", "pinky"):
        q[hand.index[f"{f}_mcp_flex"]] = np.radians(-20.0)
    p = hand.spec.play_posture
    if wrist_deg is not None or p is None:
        q[hand.index["wrist_flex"]] = np.radians(20.0 if wrist_deg is None else wrist_deg)
    else:
        q[hand.index["reach"]] = 0.5 * (hand.plan_lower[hand.index["reach"]]
                                         + hand.plan_upper[hand.index["reach"]])  # (mid-travel:
        # the tiny IK moves it)
        q[hand.index["wrist_flex"]] = p.wrist_flex_rad
        q[hand.index["wrist_dev"]] = p.wrist_dev_rad
    return hand.apply_couplings(np.clip(q, hand.plan_lower, hand.plan_upper))


@cache
def _press_posture(pitch, finger, depth, y_m=None):
    """Joints putting ``finger``'s tip ``depth`` below the top of key ``pitch``
    (negative: above), rail (and reach) + that finger's MCP/PIP, the rest at base_posture."""
    hand = load_hand("default")
    q = base_posture(hand)
    fi = hand.fingers.index(finger)
    act = _idx(hand, "rail", *(["reach"] if "reach" in hand.index else []),
               f"{finger}_mcp_flex", f"{finger}_pip")
    k = key(pitch)
    y = y_m if y_m is not None else 0.09 if k.black else 0.045  # (inside the footprint; a
    # white key in front of the black keys, as the default hand presses it)
    target = np.array([k.center_x_m, y, k.top_z_m - depth])
    indep = list(hand.independent)
    cols = [indep.index(a) for a in act]
    q[0] += target[0] - hand.tip_positions(q)[fi][0]
    for _ in range(500):
        e = target - hand.tip_positions(q)[fi]
        if np.linalg.norm(e) < 1e-10:
            break
        Ja = (hand.tip_jacobians(q)[fi] @ hand.dq_dindependent(q))[:, cols]
        dq = Ja.T @ np.linalg.solve(Ja @ Ja.T + 1e-6 * np.eye(3), e)
        dq *= min(1.0, 0.1 / np.max(np.abs(dq)))
        q[act] += dq
        q = hand.apply_couplings(np.clip(q, hand.plan_lower, hand.plan_upper))
    assert np.linalg.norm(target - hand.tip_positions(q)[fi]) < 1e-7, "test IK failed"
    return q


def press_posture(pitch, finger, depth, y_m=None):
    return _press_posture(pitch, finger, round(depth, 6), y_m).copy()


FRONT_Y_M = 0.03  # a white key pressed this far behind its front edge: the finger's
# segments, rising behind the pad, stay clear of the black keys (y >= 0.06)


def _pad_for(pitch, finger, depth, lo, hi):
    """The pad point's depth in [lo, hi] (bisection) that puts ``finger``'s deepest body
    ``depth`` (> the key-down depth) below key ``pitch``'s top (a white key in front)."""
    hand = load_hand("default")
    kin = Kinematics(hand, hand.T_world_root)
    bodies = collision_bodies(hand.spec)
    y = None if key(pitch).black else FRONT_Y_M
    for _ in range(24):
        mid = 0.5 * (lo + hi)
        q = _press_posture(pitch, finger, round(mid, 7), y)
        if body_keys(kin, q[None], bodies).depth_m[0, pitch - LOWEST_PITCH] < depth:
            lo = mid
        else:
            hi = mid
    return round(0.5 * (lo + hi), 7)


@cache
def _below_pad(pitch, finger):
    """How far ``finger``'s deepest body lies below its pad point pressing ``pitch``:
    found where the body is 8 mm down."""
    return 0.008 - _pad_for(pitch, finger, 0.008, 0.0, 0.008)


def body_press_posture(pitch, finger, depth):
    """``finger`` on key ``pitch`` with its deepest collision body ``depth`` below the
    key's top (spec section 2's body rule; negative: above), a white key in front of the
    black keys: the other keys clear (the pad point ``_below_pad`` above it)."""
    return _body_press(pitch, finger, round(depth, 6)).copy()


@cache
def _body_press(pitch, finger, depth):
    y = None if key(pitch).black else FRONT_Y_M
    pad = depth - _below_pad(pitch, finger)
    if depth > 0.005:  # (above the key-down depth the rule reports no depth: the offset)
        pad = _pad_for(pitch, finger, depth, pad - 0.002, pad + 0.002)
    return _press_posture(pitch, finger, round(pad, 7), y)


def min_jerk(times, keyframes, t):
    """Minimum-jerk blend between consecutive (time, q) keyframes, at rest at each."""
    times = np.asarray(times)
    Q = np.asarray(keyframes)
    t = np.clip(t, times[0], times[-1])
    i = np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 2)
    s = (t - times[i]) / (times[i + 1] - times[i])
    b = (10 * s**3 - 15 * s**4 + 6 * s**5)[:, None]
    return Q[i] * (1 - b) + Q[i + 1] * b


def play_trajectory(presses, t_end, depth=0.010):
    """Rows at RATE for presses = [(pitch, finger, onset, offset[, depth])] (``depth``:
    the finger's deepest body below the key's top): the key goes down at the frame of
    ``onset`` and up at the frame of ``offset``."""
    hand = load_hand("default")
    times, frames = [0.0], [body_press_posture(presses[0][0], presses[0][1], HOVER_M)]
    half = 0.5 / RATE  # the threshold crossing sits between two frames
    for p in presses:
        pitch, finger, on, off = p[:4]
        d = p[4] if len(p) > 4 else depth
        hover, up, down = (body_press_posture(pitch, finger, x) for x in (HOVER_M, 0.0, d))
        ramp_on = on - half - RAMP_S / 2
        if times[-1] < ramp_on - 0.1 - 1e-9:
            times.append(ramp_on - 0.1)
            frames.append(hover)
        times += [ramp_on, on - half + RAMP_S / 2, off - half - RAMP_S / 2, off - half + RAMP_S / 2]
        frames += [up, down, down, up]
    times.append(times[-1] + 0.1)
    frames.append(body_press_posture(presses[-1][0], presses[-1][1], HOVER_M))
    assert np.all(np.diff(times) >= RAMP_S - 1e-9), times
    t = np.arange(round(t_end * RATE) + 1) / RATE
    q = hand.apply_couplings(min_jerk(times, frames, t))
    return t, q


SONG = [(60, "index", 0.30, 0.60), (62, "middle", 1.10, 1.40),
        (64, "ring", 1.90, 2.20), (61, "index", 2.70, 3.00)]


def song_file(tmp_path, presses=SONG):
    path = tmp_path / "song.mid"
    # times on the MIDI tick grid (1/960 s) so that the file reads back exactly
    write_notes_midi([Note(p, on, off, 80) for p, _, on, off, *_ in presses], path)
    return str(path)


def rewrite(path, fn):
    with open(path, encoding="utf-8") as f:
        lines = f.read().split("\n")
    lines = fn(lines)
    with open(path, "w", encoding="utf-8", newline="\n") as f:
        f.write("\n".join(lines))
    return path


# ---------------------------------------------------------------- a catch


BALL_R = 0.05  # m, the test ball's radius
T_I = 0.5  # s, when it reaches the palm
SPEED = 6.0  # m/s, its speed there


@lru_cache(maxsize=1)
def open_posture(hand):
    """The neutral hand with every joint its stop margin off its stops
    (``HandModel.plan_lower``, ``plan_upper``), as a plan's rows keep them: a catch's
    open hand."""
    return hand.apply_couplings(np.clip(hand.q_neutral, hand.plan_lower, hand.plan_upper))


def grasp_posture():
    """Thumb, index and middle tips 4 mm off a ball resting on the palm, every joint its
    stop margin off its stops (``HandModel.plan_lower``, ``plan_upper``), as a plan's rows
    keep them."""
    hand = load_hand("default")
    q = hand.apply_couplings(np.clip(hand.q_neutral, hand.plan_lower, hand.plan_upper))
    q[_idx(hand, "thumb_cmc_abd", "thumb_cmc_flex", "thumb_ip")] = np.radians([30, 60, 40])
    P = hand.palm_pose(q)
    C = P[:3, 3] + BALL_R * P[:3, 2]
    fj = {f: _idx(hand, *(("thumb_cmc_abd", "thumb_cmc_flex", "thumb_ip") if f == "thumb" else
                          (f"{f}_mcp_abd", f"{f}_mcp_flex", f"{f}_pip")))
          for f in ("thumb", "index", "middle")}
    indep = list(hand.independent)
    for _ in range(3000):
        tips = hand.tip_positions(q)
        Js = hand.tip_jacobians(q) @ hand.dq_dindependent(q)
        for f, act in fj.items():
            fi = hand.fingers.index(f)
            d = tips[fi] - C
            e = C + (BALL_R + 0.004) * d / np.linalg.norm(d) - tips[fi]
            Ja = Js[fi][:, [indep.index(a) for a in act]]
            dq = Ja.T @ np.linalg.solve(Ja @ Ja.T + 1e-4 * np.eye(3), e)
            q[act] += dq * min(1.0, 0.05 / max(float(np.max(np.abs(dq))), 1e-12))
        q = hand.apply_couplings(np.clip(q, hand.plan_lower, hand.plan_upper))
    dist = np.linalg.norm(hand.tip_positions(q) - C, axis=1)[:3] - BALL_R
    assert np.all(np.abs(dist - 0.004) < 1e-4), dist
    return q, C, P[:3, 2]


STOP_M = 0.10  # this test ball (0.2 kg at 6 m/s) stopped over 10 cm: 36 N, within the
# wrist flexion motor's 2 N m (over the catch planner's 2 cm it would need 180 N)
# the hand those catches name: the default hand with a pad of STOP_M (``check`` judges a
# plan's stop distance no longer than its hand's pad), its URDF the default's
PAD10_HAND = str(Path(__file__).parent / "data" / "pad10.toml")


def catch_file(path, hand, offset=(0.0, 0.0, 0.0), close_from=T_I - 0.12, close_s=0.25,
               hold_to=None, t_end=T_I + 0.4):
    """A catch: the ball arrives along -normal at SPEED onto the palm (plus
    ``offset``); the fingers close by min-jerk over [close_from, close_from + close_s]."""
    q_grasp, C, n = grasp_posture()
    q_open = open_posture(hand)
    v_i = -SPEED * n
    g = np.array([0, 0, -9.81])
    v0 = v_i - g * T_I
    p0 = C + np.asarray(offset) - v0 * T_I - 0.5 * g * T_I**2
    t = np.arange(round(t_end * RATE) + 1) / RATE
    frames = [q_open, q_open, q_grasp, q_grasp]
    times = [0.0, close_from, close_from + close_s, t_end + 1]
    if hold_to is not None:
        frames += [q_open, q_open]
        times = [0.0, close_from, close_from + close_s, hold_to, hold_to + 0.25, t_end + 1]
    q = hand.apply_couplings(min_jerk(times, frames, t))
    m = meta(hand, "catch", ball={"p0": p0.tolist(), "v0": v0.tolist(), "radius": BALL_R,
                                  "mass": 0.2, "drag": 0.0}, intercept_t=T_I,
             catch={"stop_distance_m": STOP_M}, hand=PAD10_HAND)
    return write_traj(path, hand, t, q, metadata=m)
