"""The ball of a catch replay: its flight from the file's metadata (a live plan's end
marker: the flight it was last re-planned for), and the catch audit (intercept, early
touches, grasp closing and holding, and the force and motor torques of stopping and
holding the ball, ``ball_loads``)."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from planner.balls import file_inertia_ratio
from planner.check.ballbodies import finger_hit, finger_hit_problem
from planner.check.ballroll import ROLL_TOL_M, roll_judged, roll_problem, roll_towards_wrist_m
from planner.check.ballstop import PALM_MU, cone_margin_n, pad_force_n, pad_time_s, ride_force_n
from planner.check.criteria import GRASP_MIN_TIPS, GRASP_TOL_M, GRASP_WINDOW_S, INTERCEPT_TOL_M
from planner.check.kinematics import GRAVITY, G, Kinematics
from planner.check.limits import RATE_TOL
from planner.check.motormap import motor_torque_matrix
from planner.check.results import BallLoad, CatchResult, TipTouch
from planner.errors import InputError
from planner.hand.bodies import collision_bodies
from planner.hand.spec import FINGERS
from planner.hand.tendon import actuator_capacity
from planner.trajfile import Trajectory, is_num

BALL_STEP_S = 1e-3  # RK4 step of the ball flight with drag
BODY_TOL_M = 1e-5  # the fingers' bodies' tolerance on a file's rows (their 1e-6 rad
# rounding moves a body ~0.3 um at the arm's 0.3 m)
CONE_TOL_N = 1e-3  # the cone margin's tolerance (N): the file's rounding of the rows
STILL_M_S = 1e-3  # the palm target slower than this (1 mm/s) has brought the ball to rest
PAD_TOL_M = 1e-9  # a plan's stated pad against its hand's (m): the same number (a file keeps a float's digits)
STOP_DIFF_S = 1e-4  # central differences of the ball and the palm at the intercept (s): the
# ball's speed changes by g h = 1 mm/s over it, the palm's rows are piecewise linear


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
    claims = end_claims(tr.end, path)
    live = is_live(meta)
    src = judged_source(tr, path, claims)
    ball = ball_params(src, path)
    ti = src.get("intercept_t")
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

    touches = early_touches(tr, kin, tips, ball, ti, problems)
    g_time, g_fingers, held, d_after = _grasp_after(t, ti, tips, palm, r, problems)
    roll = None if err is None else _roll(t, palm, ball, ti, file_inertia_ratio(src))
    # every file alike, planned or live (not on a hand whose room is not measured:
    # ``roll_judged``)
    judged = roll is not None and roll_judged(meta.get("hand"))
    rolled = roll_problem(roll, ROLL_TOL_M) if judged else None
    if rolled is not None:
        problems.append(rolled)
    loads: tuple[BallLoad, ...] = ()
    # the plan's stopping distance, judged as it states it, is no more than its hand's pad
    # gives (the hand file's ``[palm] pad_give_m``: a plan stopped over less is judged by
    # its own, harder stop)
    stop_m, pad_m = _stop_distance(meta, path), kin.hand.pad_give_m
    if stop_m is None:
        problems.append("the plan states no stopping distance (catch.stop_distance_m): the "
                        "force of stopping the ball cannot be judged")
    else:
        if stop_m > pad_m + PAD_TOL_M:
            problems.append(f"the plan stops the ball over {stop_m * 1000:g} mm; the hand's "
                            f"pad gives {pad_m * 1000:g} mm (its file's [palm] pad_give_m)")
        if err is not None:
            loads = ball_loads(tr.t_s, tr.q, kin, palm, ball, ti, stop_m, g_time)
        for ld in loads:
            what = "stopping" if ld.phase == "stop" else "holding"
            if ld.headroom < -RATE_TOL:
                problems.append(f"{what} the ball needs {ld.force_n:.1f} N at {ld.time_s:.3f} s: "
                                f"motor.{ld.motor} {abs(ld.torque_nm):.2f} N m > its "
                                f"{ld.limiting_part} limit {ld.capacity_nm:.2f} N m")
            if ld.cone_margin_n is not None and ld.cone_margin_n < -CONE_TOL_N:
                problems.append(f"{what} the ball: the palm's force leaves its friction cone "
                                f"(mu {PALM_MU:g}) by {-ld.cone_margin_n:.2f} N before the "
                                "grasp: the ball slides off the palm")
    problems += claim_problems(claims, src, live, bool(problems))
    load = np.where(t >= ti, ball["mass"], 0.0)
    res = CatchResult(ti, r, tuple(float(x) for x in b_i), tuple(float(x) for x in target), err,
                      err is not None and err <= INTERCEPT_TOL_M, touches, g_time,
                      g_fingers, held,
                      float(d_after.min()) if d_after.size else None, tuple(problems), loads,
                      {k: claims.get(k) for k in ("catch", "reason")} if live else None, roll)
    return res, load


def early_touches(tr: Trajectory, kin: Kinematics, tips: np.ndarray, ball: dict[str, Any],
                  ti: float, problems: list[str]) -> tuple[TipTouch, ...]:
    """Before the intercept the hand must not meet the ball's flight: no fingertip inside
    the ball on the rows, nor any finger's body between them (``planner.check.ballbodies``).
    The fingertips' touches; the failures are appended to ``problems``."""
    t, r = tr.t_s, ball["radius"]
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
    hit = finger_hit(collision_bodies(kin.hand.spec), kin.link_poses, t, tr.q, ti,
                     lambda ts: ball_positions(ball["p0"], ball["v0"], ball["drag"], ts), r)
    hit_problem = finger_hit_problem(hit, BODY_TOL_M)
    if hit_problem is not None:
        problems.append(hit_problem)
    return tuple(touches)


OUTCOMES = ("held", "given_up", "infeasible")  # a catch's claim (spec section 4, version 2)


def judged_source(tr: Trajectory, path: str, claims: dict[str, Any] | None = None
                  ) -> dict[str, Any]:
    """The metadata whose ball and intercept time a catch file is judged against (by the
    check, and replayed by ``simulate``): the metadata's; a live plan's last estimate (its
    end marker), a claim judged by the same rules as any ball (spec section 4, version 2)."""
    meta = tr.metadata
    claims = end_claims(tr.end, path) if claims is None else claims
    if is_live(meta) and "ball" in claims:
        return {**meta, "ball": claims["ball"], "intercept_t": claims["intercept_t"]}
    return meta


def is_live(meta: dict[str, Any]) -> bool:
    """A live plan's file: its metadata says so (``catch.live``), not its end marker."""
    c = meta.get("catch")
    return isinstance(c, dict) and c.get("live") is True


def end_claims(end: dict[str, Any], path: str) -> dict[str, Any]:
    """A catch file's end-marker claims (``catch``, ``reason``, ``ball``, ``intercept_t``),
    each of its type (InputError naming the key otherwise)."""
    out: dict[str, Any] = {}
    if "catch" in end:
        if end["catch"] not in OUTCOMES:
            raise InputError(f"{path}: end marker's 'catch' must be one of "
                             f"{', '.join(OUTCOMES)}, got {end['catch']!r}")
        out["catch"] = end["catch"]
    if "reason" in end:
        if not isinstance(end["reason"], str):
            raise InputError(f"{path}: end marker's 'reason' must be text")
        out["reason"] = end["reason"]
    if ("ball" in end) != ("intercept_t" in end):
        raise InputError(f"{path}: end marker's 'ball' and 'intercept_t' come together")
    if "ball" in end:
        ball_params({"ball": end["ball"]}, f"{path}: end marker")
        ti = end["intercept_t"]
        if not is_num(ti) or not math.isfinite(ti):
            raise InputError(f"{path}: end marker's 'intercept_t' must be a finite number")
        out["ball"], out["intercept_t"] = end["ball"], float(ti)
    return out


def claim_problems(claims: dict[str, Any], judged: dict[str, Any], live: bool,
                   failed: bool) -> list[str]:
    """The end marker's claims held against the replay: a planned file's ball is its
    metadata's (an end marker that names another one is refused); a catch that says it is
    not held (given up, infeasible) is not a catch; one that says it is held while the
    rows fail is named."""
    out = []
    if not live and "ball" in claims and (claims["ball"] != judged["ball"]
                                          or claims["intercept_t"] != judged["intercept_t"]):
        out.append("the end marker names a ball other than the metadata's: a planned "
                   "catch is judged against the ball it was planned for")
    said = claims.get("catch")
    if said in ("given_up", "infeasible"):
        out.append(f"the plan says the catch is {said.replace('_', ' ')}: "
                   f"{claims.get('reason') or 'no reason given'}")
    elif said == "held" and (failed or out):
        out.append("the end marker claims the catch held; the rows above say otherwise")
    return out


def _roll(t: np.ndarray, palm: np.ndarray, ball: dict[str, Any], ti: float,
          inertia_ratio: float) -> float:
    """The landed ball's largest roll towards the wrist on the rows (``roll_towards_wrist_m``,
    the planner's model) from its landing at ``ti`` at its flight's velocity there."""
    h = STOP_DIFF_S
    b = ball_positions(ball["p0"], ball["v0"], ball["drag"], [ti - h, ti + h])
    return roll_towards_wrist_m(t, palm, ball["radius"], ti, (b[1] - b[0]) / (2 * h),
                                inertia_ratio)


def _grasp_after(t: np.ndarray, ti: float, tips: np.ndarray, palm: np.ndarray, r: float,
                 problems: list[str]):
    """After the intercept the ball rides on the palm; the grasp must close within
    ``GRASP_WINDOW_S`` and hold to the end: its time, fingers, whether it holds, and every
    fingertip's distance from the ball's centre on the palm (rows from the intercept on).
    Its failures are appended to ``problems``."""
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
    return g_time, g_fingers, held, d_after


def _stop_distance(meta: dict[str, Any], path: str) -> float | None:
    """The plan's stopping distance (m): its metadata's ``catch.stop_distance_m`` (None
    when it states none; InputError when it is not a positive number)."""
    c = meta.get("catch")
    d = c.get("stop_distance_m") if isinstance(c, dict) else None
    if d is None:
        return None
    if not is_num(d) or not math.isfinite(d) or d <= 0:
        raise InputError(f"{path}: catch.stop_distance_m must be a positive number, got {d!r}")
    return float(d)


def ball_loads(t: np.ndarray, Q: np.ndarray, kin: Kinematics, palm: np.ndarray,
               ball: dict[str, Any], ti: float, pad_m: float, grasp_t: float | None = None
               ) -> tuple[BallLoad, BallLoad]:
    """The stopping and the holding phase's worst instants (``ball_load_instants``)."""
    return phase_loads(ball_load_instants(t, Q, kin, palm, ball, ti, pad_m, grasp_t), t[-1],
                       kin, Q[-1], palm[-1], ball["mass"])


@dataclass(frozen=True)
class ContactLoads:
    """The ball's load named by what causes it: ``impact``, the pad stopping the ball at
    contact (its speed relative to the palm over the pad's give); ``riding``, the worst
    instant of the ball riding the palm afterwards (its weight and the palm's acceleration;
    None: the arm still from the pad's stop on). Each with every motor's headroom."""

    impact: BallLoad
    riding: BallLoad | None


def contact_loads(instants: list[BallLoad]) -> ContactLoads:
    """``ball_load_instants``' loads named apart: the impact (the first instant, at the
    intercept) and the riding ball's worst (the instants after the pad's stop)."""
    rides = [x for x in instants[1:] if x.speed_m_s == 0.0]
    return ContactLoads(instants[0], _worst(rides) if rides else None)


def phase_loads(inst: list[BallLoad], t_end: float, kin: Kinematics, q_end: np.ndarray,
                palm_end: np.ndarray, mass: float) -> tuple[BallLoad, BallLoad]:
    """The instants' worst while the palm target moves (``stop``) and after (``hold``; the
    ball's weight on the last row when no instant is after)."""
    stop = _worst([x for x in inst if x.phase == "stop"])
    holds = [x for x in inst if x.phase == "hold"]
    if holds:
        return stop, _worst(holds)
    n = len(q_end)
    cap = actuator_capacity(kin.hand)
    return stop, _load("hold", kin, q_end, float(t_end), ride_force_n(mass, np.zeros(3)), 0.0,
                       0.0, np.zeros(n), np.zeros(n), palm_end[:3, 2], False, cap)


def ball_load_instants(t: np.ndarray, Q: np.ndarray, kin: Kinematics, palm: np.ndarray,
                       ball: dict[str, Any], ti: float, pad_m: float,
                       grasp_t: float | None = None) -> list[BallLoad]:
    """The ball's load on the hand (``planner.check.ballstop``, one definition with the
    planner), judged on the rows as they move: its velocity relative to the palm target at
    ``ti`` stopped by the pad over ``pad_m`` (at ``ti`` and at every row within the pad's
    time after it), then the ball riding the palm target of every later row (the rows'
    second differences); at each, the joint torques g(q) + J^T F + the hand's own inertia
    as its arm moves (RNEA of the rows' central differences of the joints outside the
    fingers) through the transmissions, each motor against
    its capacity, and while the ball slows (until the grasp at ``grasp_t``) F inside the
    palm's friction cone.
    ``stop``: the worst instant while the palm target still moves (the stopping motion);
    ``hold``: the worst after it comes to rest. The cone is judged where the ball slows: at
    the pad and where the palm target decelerates faster than g (slower than that the ball
    lies on the palm as on one at rest, which the closing fingers catch)."""
    r, m = ball["radius"], ball["mass"]
    h = STOP_DIFF_S
    b = ball_positions(ball["p0"], ball["v0"], ball["drag"], [ti - h, ti + h])
    qa = _rows_at(t, Q, np.array([ti - h, ti, ti + h]))
    _, P = kin.frames(qa)
    c = P[:, :3, 3] + r * P[:, :3, 2]
    v_rel = (b[1] - b[0] - (c[2] - c[0])) / (2 * h)
    t_pad = pad_time_s(v_rel, pad_m)
    V, A, centre_v, centre_a = _row_rates(t, Q, palm, r)
    # the hand's inertia of the arm's motion (the stopping motion); the fingers' own moves
    # are not the ball's load (nor judged dynamically elsewhere in a catch)
    still_fingers = _finger_mask(kin.hand)
    V[:, still_fingers] = 0.0
    A[:, still_fingers] = 0.0
    # at the intercept: the rows' rates there (speed of its segment, acceleration of the
    # nearer row)
    k0 = int(np.clip(np.searchsorted(t, ti, side="right") - 1, 0, len(t) - 2))
    kn = k0 if ti - t[k0] <= t[k0 + 1] - ti else k0 + 1
    v_i = np.where(still_fingers, 0.0, (Q[k0 + 1] - Q[k0]) / (t[k0 + 1] - t[k0]))
    held = grasp_t if grasp_t is not None else math.inf
    cap = actuator_capacity(kin.hand)
    inst = [_load("stop", kin, qa[1], ti, pad_force_n(m, v_rel, centre_a[kn], pad_m),
                  float(np.linalg.norm(v_rel)), pad_m, v_i, A[kn], P[1, :3, 2], ti < held, cap)]
    still = None
    for k in np.flatnonzero(t > ti):
        F, sp, dist = ride_force_n(m, centre_a[k]), 0.0, 0.0
        if t[k] < ti + t_pad:
            F, sp, dist = pad_force_n(m, v_rel, centre_a[k], pad_m), inst[0].speed_m_s, pad_m
        if still is None and t[k] >= ti + t_pad and np.linalg.norm(centre_v[k]) < STILL_M_S:
            still = k
        phase = "stop" if still is None else "hold"
        if phase == "hold" and k > still and not np.any(V[k]) and not np.any(A[k]) \
                and not np.any(centre_a[k]):
            continue  # the arm still: the ball's weight on the palm, judged on every row by
            # the limit audit (``planner.check.limits``, its static torques)
        slows = sp > 0 or float(np.linalg.norm(centre_a[k])) > G  # the arm, not gravity, sets F
        inst.append(_load(phase, kin, Q[k], float(t[k]), F, sp, dist, V[k], A[k],
                          palm[k, :3, 2], phase == "stop" and slows and t[k] < held, cap))
    return inst


def _rows_at(t: np.ndarray, Q: np.ndarray, times: np.ndarray) -> np.ndarray:
    """The rows interpolated linearly at ``times`` (held at the ends), like ``np.interp``
    on every column."""
    if len(t) < 2:
        return np.repeat(Q[:1], len(times), axis=0)
    k = np.clip(np.searchsorted(t, times, side="right") - 1, 0, len(t) - 2)
    w = np.clip((times - t[k]) / (t[k + 1] - t[k]), 0.0, 1.0)[:, None]
    return (1.0 - w) * Q[k] + w * Q[k + 1]


_FINGER_MASKS: dict[tuple[str, str], np.ndarray] = {}


def _finger_mask(hand) -> np.ndarray:
    """True for the joints of the hand's fingers (once per hand)."""
    key = (hand.name, hand.urdf_sha256)
    mask = _FINGER_MASKS.get(key)
    if mask is None:
        fingers = {n for f in hand.fingers for n in hand.spec.joints_of(f)}
        mask = _FINGER_MASKS[key] = np.array([n in fingers for n in hand.joint_names])
        mask.setflags(write=False)
    return mask


def _row_rates(t: np.ndarray, Q: np.ndarray, palm: np.ndarray, r: float):
    """Joint speeds and accelerations of every row (central differences; zero at the first
    and the last row) and the palm target's velocity and acceleration likewise."""
    centre = palm[:, :3, 3] + r * palm[:, :3, 2]
    out = []
    for X in (Q, centre):
        Vx, Ax = np.zeros_like(X), np.zeros_like(X)
        if len(t) >= 3:
            dt0, dt1 = np.diff(t)[:-1, None], np.diff(t)[1:, None]
            Vx[1:-1] = (X[2:] - X[:-2]) / (dt0 + dt1)
            Ax[1:-1] = 2.0 * ((X[2:] - X[1:-1]) / dt1 - (X[1:-1] - X[:-2]) / dt0) / (dt0 + dt1)
        out += [Vx, Ax]
    return out[0], out[1], out[2], out[3]


def _worst(loads: list[BallLoad]) -> BallLoad:
    """The instant closest to a motor's capacity, carrying the phase's worst headroom of
    every motor and its least cone margin."""
    w = min(loads, key=lambda x: x.headroom)
    per = tuple(float(x) for x in np.min([x.motor_headroom for x in loads], axis=0))
    cones = [x.cone_margin_n for x in loads if x.cone_margin_n is not None]
    cone = min(cones) if cones else None
    return replace(w, motor_headroom=per, cone_margin_n=cone)


def _load(phase: str, kin: Kinematics, q: np.ndarray, time_s: float, F: np.ndarray,
          speed: float, dist: float, v: np.ndarray, a: np.ndarray, normal: np.ndarray,
          on_palm: bool, cap) -> BallLoad:
    """The hand applying ``F`` to the ball at the palm centre at ``q``, moving at joint speeds
    ``v`` and accelerations ``a``: every motor's headroom, the one closest to its capacity;
    the cone margin of ``F`` when the palm alone holds the ball (``on_palm``)."""
    hand = kin.hand
    (J,) = kin.point_jacobians(q, [kin.palm_id])
    tau_j = kin.gravity(q) + J.T @ F
    if np.any(v != 0.0) or np.any(a != 0.0):
        tau_j = tau_j + kin.inertial(q, v, a)
    tau = motor_torque_matrix(hand, q) @ tau_j
    ratio = np.abs(tau) / cap.torque_nm
    i = int(np.argmax(ratio))
    cone = cone_margin_n(F, normal) if on_palm else None
    return BallLoad(phase, float(time_s), float(np.linalg.norm(F)), float(speed), float(dist),
                    hand.motor_names[i], float(tau[i]), float(cap.torque_nm[i]), cap.limiting(i),
                    tuple(float(x) for x in 1.0 - ratio), cone)
