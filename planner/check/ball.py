"""The ball of a catch replay: its flight from the file's metadata, and the catch
audit (intercept, early touches, grasp closing and holding)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from planner.check.criteria import GRASP_MIN_TIPS, GRASP_TOL_M, GRASP_WINDOW_S, INTERCEPT_TOL_M
from planner.check.kinematics import GRAVITY, Kinematics
from planner.check.results import CatchResult, TipTouch
from planner.errors import InputError
from planner.hand.spec import FINGERS
from planner.trajfile import Trajectory

BALL_STEP_S = 1e-3  # RK4 step of the ball flight with drag


def ball_params(meta: dict[str, Any], path: str) -> dict[str, Any]:
    b = meta.get("ball")
    if not isinstance(b, dict):
        raise InputError(f"{path}: catch metadata lacks 'ball'")
    out: dict[str, Any] = {}
    for k in ("p0", "v0"):
        v = b.get(k)
        if (not isinstance(v, list) or len(v) != 3
                or not all(is_num(x) and math.isfinite(x) for x in v)):
            raise InputError(f"{path}: ball {k!r} must be a list of 3 finite numbers")
        out[k] = np.array(v, dtype=float)
    for k, lo, strict in (("radius", 0.0, True), ("mass", 0.0, False), ("drag", 0.0, False)):
        v = b.get(k)
        if not is_num(v) or not math.isfinite(v) or v < lo or (strict and v == lo):
            what = "positive" if strict else "non-negative"
            raise InputError(f"{path}: ball {k!r} must be a {what} number, got {v!r}")
        out[k] = float(v)
    return out


def is_num(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def ball_positions(p0, v0, drag: float, times) -> np.ndarray:
    """Ball centre at ``times`` (s, from launch at t = 0), acceleration g - k|v|v.

    Closed form when ``drag`` is 0; otherwise classic RK4 with steps of at most
    ``BALL_STEP_S`` that land exactly on every requested time. Times before 0
    give ``p0`` (the ball has not left).
    """
    p0 = np.asarray(p0, dtype=float)
    v0 = np.asarray(v0, dtype=float)
    times = np.atleast_1d(np.asarray(times, dtype=float))
    tt = np.maximum(times, 0.0)
    if drag == 0.0:
        return p0 + np.outer(tt, v0) + 0.5 * np.outer(tt * tt, GRAVITY)
    k = float(drag)

    def acc(v):
        return GRAVITY - k * math.sqrt(v @ v) * v

    out = np.empty((len(tt), 3))
    order = np.argsort(tt, kind="stable")
    t, p, v = 0.0, p0.copy(), v0.copy()
    for i in order:
        target = tt[i]
        n = max(1, math.ceil((target - t) / BALL_STEP_S - 1e-9)) if target > t else 0
        h = (target - t) / n if n else 0.0
        for _ in range(n):
            a1 = acc(v)
            v2 = v + 0.5 * h * a1
            a2 = acc(v2)
            v3 = v + 0.5 * h * a2
            a3 = acc(v3)
            v4 = v + h * a3
            a4 = acc(v4)
            p = p + h / 6.0 * (v + 2 * v2 + 2 * v3 + v4)
            v = v + h / 6.0 * (a1 + 2 * a2 + 2 * a3 + a4)
        t = target
        out[i] = p
    return out


def catch_audit(tr: Trajectory, kin: Kinematics, tips: np.ndarray, palm: np.ndarray, path: str
           ) -> tuple[CatchResult, np.ndarray]:
    meta = tr.metadata
    ball = ball_params(meta, path)
    ti = meta.get("intercept_t")
    if not is_num(ti) or not math.isfinite(ti):
        raise InputError(f"{path}: catch metadata 'intercept_t' must be a finite number")
    ti = float(ti)
    r = ball["radius"]
    t = tr.t_s
    problems = []

    # intercept: joints interpolated linearly at ti
    b_i = ball_positions(ball["p0"], ball["v0"], ball["drag"], [ti])[0]
    target = np.full(3, np.nan)
    err = None
    if t[0] <= ti <= t[-1]:
        qi = np.array([np.interp(ti, t, tr.q[:, j]) for j in range(tr.q.shape[1])])
        _, P = kin.frames(qi[None])
        target = P[0, :3, 3] + r * P[0, :3, 2]
        err = float(np.linalg.norm(b_i - target))
        if err > INTERCEPT_TOL_M:
            problems.append(f"ball misses the palm: {err * 1000:.1f} mm from palm_center + radius"
                            f" * normal at t={ti:.3f} s (max {INTERCEPT_TOL_M * 1000:g} mm)")
    else:
        problems.append(f"intercept_t {ti:.3f} s is outside the trajectory "
                        f"({t[0]:.3f}..{t[-1]:.3f} s)")

    # before the intercept: no fingertip inside the ball
    before = t < ti
    touches = []
    if before.any():
        bp = ball_positions(ball["p0"], ball["v0"], ball["drag"], t[before])
        d = np.linalg.norm(tips[before] - bp[:, None, :], axis=-1)
        for k, f in zip(*np.nonzero(d < r)):
            touches.append(TipTouch(float(t[before][k]), FINGERS[f], float(d[k, f])))
    if touches:
        problems.append(f"{len(touches)} fingertip contacts with the ball before the intercept "
                        f"(first: {touches[0].finger} at {touches[0].time_s:.3f} s)")

    # after: the ball rides on the palm; the grasp must close and hold
    after = np.flatnonzero(t >= ti)
    centre = palm[after, :3, 3] + r * palm[after, :3, 2]
    d_after = np.linalg.norm(tips[after] - centre[:, None, :], axis=-1)
    closed = d_after <= r + GRASP_TOL_M
    thumb = FINGERS.index("thumb")
    grasped = (closed.sum(axis=1) >= GRASP_MIN_TIPS) & closed[:, thumb]
    in_window = t[after] <= ti + GRASP_WINDOW_S + 1e-9
    g_time, g_fingers, held = None, (), False
    first = np.flatnonzero(grasped & in_window)
    if first.size:
        k = int(first[0])
        g_time = float(t[after[k]])
        g_fingers = tuple(FINGERS[f] for f in np.flatnonzero(closed[k]))
        held = bool(grasped[k:].all())
        if not held:
            lost = k + int(np.argmin(grasped[k:]))
            problems.append(f"grasp lost at t={t[after[lost]]:.3f} s")
    else:
        best = int(closed.sum(axis=1)[in_window].max()) if in_window.any() else 0
        problems.append(f"no grasp within {GRASP_WINDOW_S * 1000:g} ms of the intercept "
                        f"(needs {GRASP_MIN_TIPS} fingertips including the thumb within "
                        f"radius + {GRASP_TOL_M * 1000:g} mm; best row had {best})")
    load = np.where(t >= ti, ball["mass"], 0.0)
    res = CatchResult(ti, r, tuple(float(x) for x in b_i), tuple(float(x) for x in target), err,
                      err is not None and err <= INTERCEPT_TOL_M, tuple(touches), g_time,
                      g_fingers, held,
                      float(d_after.min()) if d_after.size else None, tuple(problems))
    return res, load


