"""What every picture of a checked trajectory needs: the hand rebuilt from the file, its
metadata, the motor angles and the ball; and the colours and sizes the pictures share."""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any

import numpy as np

from planner.check import (
    CheckReport,
    ball_positions,
)
from planner.errors import InputError
from planner.hand.model import HandModel, load_hand

FINGER_COLORS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b")  # never red
ERROR_COLOR = "#d62728"
DPI = 100
HTML_FPS = 25.0
HTML_MAX_FRAMES = 2000
TIP_SPHERE_M = 0.006
KEY_BODY_M = 0.020  # drawn thickness of a key
PLAY_CAMERA_OFFSET_M = (0.12, 0.36, 0.24)  # camera from its target (world frame): the
# play view looks from behind the keyboard at the fingertips (the forearm would hide them)
CATCH_CAMERA_OFFSET_M = (-0.15, -0.80, 0.20)  # side view of the flight plane (x-z)


# ====================================================================== context


@dataclass(frozen=True)
class PictureContext:
    """What the pictures of one checked trajectory share (``picture_context``)."""

    hand: HandModel
    meta: dict[str, Any]
    T_world_root: np.ndarray
    q_motor: np.ndarray
    ball: dict[str, Any] | None  # p0, v0, radius, drag (catch)


def _read_metadata(path: str) -> dict[str, Any]:
    try:
        with open(path, encoding="utf-8") as f:
            line = f.readline()
        meta = json.loads(line[2:]) if line.startswith("# ") else {}
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        meta = {}
    return meta if isinstance(meta, dict) else {}


def picture_context(report: CheckReport) -> PictureContext:
    """The hand rebuilt from the file (or the report's), its metadata, the motor angles
    of every row and the ball (a catch)."""
    if report.replay is None:
        raise ValueError("the report has no replay arrays (check_trajectory fills them)")
    meta = _read_metadata(report.trajectory)
    hand = None
    for name in (meta.get("hand"), report.hand):
        if isinstance(name, str) and name:
            try:
                h = load_hand(name)
            except InputError:
                h = None
            if h is not None and h.urdf_sha256 == report.urdf_sha256:
                hand = h
                break
    if hand is None:
        raise ValueError(f"cannot rebuild hand {report.hand!r} of {report.trajectory}")
    rp = report.replay
    # the root pose the replay used: from the palm of the first row (no file needed)
    P0 = hand.frame_pose(rp.q[0], "palm_center")
    T = rp.palm[0] @ np.linalg.inv(P0) @ hand.T_world_root
    T[3] = (0.0, 0.0, 0.0, 1.0)
    ball = None
    if report.catch is not None:
        b = meta.get("ball") if isinstance(meta.get("ball"), dict) else {}
        try:
            ball = {"p0": np.array(b["p0"], dtype=float), "v0": np.array(b["v0"], dtype=float),
                    "drag": float(b.get("drag", 0.0)), "radius": report.catch.radius_m}
        except (KeyError, TypeError, ValueError):
            ball = None
    return PictureContext(hand, meta, T, hand.motor_angles(rp.q), ball)


def ball_centres(report: CheckReport, ctx: PictureContext) -> np.ndarray | None:
    """The ball's centre in every row as the check sees it: in flight before
    ``intercept_t``, on the palm (palm_center + radius * normal) from it on."""
    if ctx.ball is None:
        return None
    rp, c = report.replay, report.catch
    t = rp.t_s
    out = ball_positions(ctx.ball["p0"], ctx.ball["v0"], ctx.ball["drag"], t)
    after = t >= c.intercept_t
    out[after] = rp.palm[after, :3, 3] + c.radius_m * rp.palm[after, :3, 2]
    return out

