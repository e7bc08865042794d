"""The hand falling with the ball on the rig's reach axis (a person's palm-up catch of a
short or a steep throw: the hand gives way downwards with the ball while the wrist turns
the palm up under it).

After the pad has stopped the ball on the palm it rolls along the palm's +y (towards the
wrist, where nothing stops it) at k ((g - a) . y) (``planner.check.ballroll``: k the rolling
ball's share of the tangential force, a the palm target's acceleration). The reach axis is
a translation upstream of the wrist: it moves the palm target along one fixed direction
e_r without turning the palm, so it changes a by a_r e_r and nothing else. Where e_r . y is
far from 0 (a steep palm: e_r . y = -0.95 on 15 deg / 1 m's intercept pose) the reach
accelerating at a_r = ((g - a_0) . y - w) / (e_r . y) makes the along-palm acceleration w,
chosen to bring the ball's roll towards the wrist to rest (``DROP_SETTLE_S``): the hand
falls with the ball, as in free fall when w = 0, while the wrist's turn (already in the
rows) levels the palm. The fall is bounded by the reach's travel, speed and acceleration
(its limits at ``LIMIT_MARGIN``): the axis brakes in time to stop within its range and by
the rows' end, and brakes when the palm is level enough that braking does not roll the
ball towards the wrist. Each row's fall also keeps every motor within its room with the
hand's inertia and the riding ball's force inside the palm's friction cone
(``allowed_accel``).

``add_drop`` adds that motion to a plan's rows (the law row by row, as the check integrates
the roll: ``roll_towards_wrist_m``); the check then judges the rows as any other (the roll
rule, every motor at the rows' accelerations).
"""

from __future__ import annotations

import numpy as np

from planner.check.ballpalm import BallOnPalm
from planner.check.ballroll import roll_factor, roll_towards_wrist_m
from planner.check.ballstop import PALM_MU
from planner.hand.model import GRAVITY_WORLD
from planner.trajectory import LIMIT_MARGIN

DROP_SETTLE_S = 0.03  # the law brings the ball's roll towards the wrist to rest in about
# this long: three rows at 100 Hz (the rows' own rate is the finest the check sees)
CONE_SHARE = 0.95  # the fall keeps the ball's force within this share of the palm's friction
# (tan of the cone's half angle): on the cone's edge itself the check's rule on the written
# rows (rounded, their accelerations second differences) found it 0.00 N outside
MIN_LEVER = 0.2  # below this |e_r . y| the reach barely moves the ball along the palm (a
# palm near perpendicular to the forearm's line): the axis then only brakes
ROLLS_KEPT = 8  # ``rolled_m``'s last answers kept: a plan's rows are judged for the roll by
# ``add_drop`` (with and without the fall), by the turn's search and by the plan's reasons


_rolls: dict[bytes, float] = {}


def rolled_m(t: np.ndarray, palm: np.ndarray, radius_m: float, t_land_s: float,
             v_ball: np.ndarray, inertia_ratio: float) -> float:
    """``roll_towards_wrist_m`` (the check's roll model on the palm poses ``palm`` at
    ``t``), its last ``ROLLS_KEPT`` answers kept by their arguments' bytes (a function of
    them: the same answer as computed anew)."""
    key = b"".join((np.ascontiguousarray(t, dtype=float).tobytes(),
                    np.ascontiguousarray(palm, dtype=float).tobytes(),
                    np.array([radius_m, t_land_s, inertia_ratio], dtype=float).tobytes(),
                    np.ascontiguousarray(v_ball, dtype=float).tobytes()))
    hit = _rolls.pop(key, None)
    if hit is None:
        hit = roll_towards_wrist_m(t, palm, radius_m, t_land_s, v_ball, inertia_ratio)
        if len(_rolls) >= ROLLS_KEPT:
            _rolls.pop(next(iter(_rolls)))
    _rolls[key] = hit  # the newest last: the least recently asked for goes first
    return hit


def reach_direction(kin, q: np.ndarray, i_reach: int, radius_m: float) -> np.ndarray:
    """The palm target's motion per metre of the reach axis (reference frame): constant
    (the axis is a translation upstream of the wrist)."""
    d = 1e-4
    q1 = q.copy()
    q1[i_reach] += d
    _, P = kin.frames(np.vstack([q, q1]))
    c = P[:, :3, 3] + radius_m * P[:, :3, 2]
    return (c[1] - c[0]) / d


def fall_accel(x: float, vx: float, along: float, lever: float, k_roll: float, u: float,
               dt: float, a_max: float) -> float:
    """The law (module docstring) at one row: the reach's acceleration (m/s^2) for a ball
    ``x`` (m) from the palm target towards the wrist rolling at ``vx`` (m/s), where the rows
    alone roll it at ``along`` (m/s^2) and a unit of the reach's acceleration at -``k_roll``
    ``lever`` (e_r . y); the reach moving at ``u`` (m/s). It brakes (to rest within a row,
    at most ``a_max``) once the ball rests on the fingers' side and braking keeps it there."""
    a_brake = float(np.clip(-u / dt, -a_max, a_max))
    if x <= 0.0 and vx <= 0.0 and along - k_roll * a_brake * lever <= 0.0:
        return a_brake
    if abs(lever) < MIN_LEVER:
        return 0.0
    w = -vx / DROP_SETTLE_S if x > 0.0 or vx > 0.0 else min(along, 0.0)
    return (along - w) / (k_roll * lever)


def allowed_accel(dyn, q: np.ndarray, qdd: np.ndarray, i_reach: int, b: np.ndarray,
                  e_r: np.ndarray, normal: np.ndarray) -> tuple[float, float]:
    """The reach's accelerations a (m/s^2) that row ``q`` (joint accelerations ``qdd``
    without the fall) may add: every motor within ``STOP_SHARE`` of its capacity with the
    hand's inertia (``StopDynamics.accel_room``, as the stop's ramps), and the ball riding
    the palm, whose force m (b + a e_r) (b: the palm target's acceleration less g) stays in
    the palm's friction cone (``CONE_SHARE`` of ``PALM_MU``): the palm neither leaves the ball nor drags it.
    (lo, hi); lo > hi: none."""
    MH, room = dyn.accel_room(q)
    base, per = MH @ qdd, MH[:, i_reach]
    lo, hi = -np.inf, np.inf
    for m in np.flatnonzero(np.abs(per) > 1e-12):
        ends = sorted(((-room[m] - base[m]) / per[m], (room[m] - base[m]) / per[m]))
        lo, hi = max(lo, ends[0]), min(hi, ends[1])
    # the cone: |F_t|^2 <= mu^2 F_n^2 with F_n >= 0, F = b + a e_r (per unit mass)
    bn, en = float(b @ normal), float(e_r @ normal)
    bt, et = b - bn * normal, e_r - en * normal
    mu2 = (CONE_SHARE * PALM_MU) ** 2
    qa, qb, qc = float(et @ et) - mu2 * en * en, float(bt @ et) - mu2 * bn * en, \
        float(bt @ bt) - mu2 * bn * bn
    disc = qb * qb - qa * qc
    if qa > 1e-12:  # between the roots
        if disc < 0.0:
            return 0.0, -1.0
        lo = max(lo, (-qb - disc ** 0.5) / qa)
        hi = min(hi, (-qb + disc ** 0.5) / qa)
    elif qa < -1e-12 and disc >= 0.0 and abs(en) > 1e-12:  # outside the roots, on the side
        r1, r2 = sorted(((-qb - disc ** 0.5) / qa, (-qb + disc ** 0.5) / qa))  # F_n >= 0
        lo, hi = (max(lo, r2), hi) if en > 0 else (lo, min(hi, r1))
    if abs(en) > 1e-12:  # F_n >= 0
        edge = -bn / en
        lo, hi = (max(lo, edge), hi) if en > 0 else (lo, min(hi, edge))
    return float(lo), float(hi)


def brake_room(u: float, lo_a: float, hi_a: float, a_max: float) -> float:
    """The deceleration (m/s^2, > 0) a row lets the reach brake its speed ``u`` with: at
    most ``a_max``, and within the row's ``allowed_accel`` (``lo_a``, ``hi_a``: the motors'
    room and the riding ball's contact, which cannot pull: a palm braked faster than that
    leaves the ball; a fall stopped within one row at the rows' end threw the resting ball
    off the palm in the replay). ``a_max`` where the row allows no braking at all."""
    room = -lo_a if u > 0.0 else hi_a
    return min(a_max, room) if room > 1e-9 else a_max


def can_stop(u: float, pos: float, lo: float, hi: float, a_max: float, left_s: float,
             a_end: float | None = None) -> bool:
    """Whether the reach at ``pos`` moving at ``u`` can still stop (at ``a_max``) within
    [``lo``, ``hi``], and (at ``a_end``, ``a_max`` if not given) within ``left_s``."""
    stop_d = u * u / (2.0 * a_max)
    a_end = a_max if a_end is None else a_end
    return not ((u < 0 and pos - stop_d < lo) or (u > 0 and pos + stop_d > hi)
                or abs(u) > a_end * left_s)


def add_drop(dyn, t: np.ndarray, Q: np.ndarray, i_reach: int, t_land_s: float,
             v_ball: np.ndarray, radius_m: float, inertia_ratio: float) -> np.ndarray:
    """The rows ``Q`` (at times ``t``) of ``dyn``'s hand with the reach axis falling with
    the ball from its landing at ``t_land_s`` (velocity ``v_ball``) and braking to rest
    within its range by the last rows (module docstring), every row's fall within
    ``allowed_accel``; ``Q`` unchanged where that rolls the ball no less towards the wrist
    (``roll_towards_wrist_m``) than the rows alone."""
    hand, kin = dyn.hand, dyn.kin
    after = np.flatnonzero(t > t_land_s)
    if len(after) < 4 or after[0] < 1:
        return Q
    dt = float(t[1] - t[0])
    qdd = np.zeros_like(Q)
    qdd[1:-1] = (Q[2:] - 2.0 * Q[1:-1] + Q[:-2]) / (dt * dt)
    k0 = int(after[0])
    _, palm = kin.frames(Q)
    y = palm[:, :3, 1]
    centre = palm[:, :3, 3] + radius_m * palm[:, :3, 2]
    acc = np.zeros_like(centre)
    acc[1:-1] = (centre[2:] - 2.0 * centre[1:-1] + centre[:-2]) / (dt * dt)
    e_r = reach_direction(kin, Q[k0], i_reach, radius_m)
    lever = y @ e_r
    k_roll = roll_factor(inertia_ratio)
    along0 = k_roll * np.einsum("ij,ij->i", GRAVITY_WORLD - acc, y)
    a_max = LIMIT_MARGIN * float(hand.acceleration[i_reach])
    v_max = LIMIT_MARGIN * float(hand.velocity[i_reach])
    pad = 0.5 * (1.0 - LIMIT_MARGIN) * float(hand.upper[i_reach] - hand.lower[i_reach])
    lo, hi = float(hand.lower[i_reach]) + pad, float(hand.upper[i_reach]) - pad
    base = Q[:, i_reach]
    n = len(t)
    p = np.zeros(n)  # the reach's offset from the rows' own
    u = 0.0  # its speed
    # the ball on the palm as the fall so far moves it (the check's model, ``BallOnPalm``):
    # the law's feedback, its state row by row
    ball = BallOnPalm(radius_m, inertia_ratio, PALM_MU)
    fallen = palm.copy()
    ball.land(fallen, t, k0 - 1, t_land_s, np.asarray(v_ball, dtype=float))
    # the braking the rows' last pose allows the ball (the stop by the rows' end is there)
    end_room = allowed_accel(dyn, Q[n - 3], qdd[n - 3], i_reach, acc[n - 3] - GRAVITY_WORLD,
                             e_r, palm[n - 3, :3, 2])
    for k in range(k0, n - 2):
        fallen[k, :3, 3] = palm[k, :3, 3] + p[k] * e_r
        x = max(ball.step_to(fallen, t, k), 0.0)
        vx = ball.along_speed(fallen)
        a_o = fall_accel(x, vx, float(along0[k]), float(lever[k]), k_roll, u, dt, a_max)
        lo_a, hi_a = allowed_accel(dyn, Q[k], qdd[k], i_reach, acc[k] - GRAVITY_WORLD, e_r,
                                   palm[k, :3, 2])
        # (rows already outside the cone or the motors' room without the fall: the fall is
        # bounded to make it no worse)
        lo_a, hi_a = (min(lo_a, 0.0), max(hi_a, 0.0)) if lo_a <= hi_a else (0.0, 0.0)
        a_o = float(np.clip(a_o, max(-a_max, lo_a), min(a_max, hi_a)))
        # the range and the rows' end: able to stop in time after this step (by the rows'
        # end braking no harder than the ball on the palm allows)
        u1 = float(np.clip(u + a_o * dt, -v_max, v_max))
        a_stop = brake_room(u1, *end_room, a_max)  # (the ball stays on the palm meanwhile)
        if not can_stop(u1, base[k + 1] + p[k] + u1 * dt, lo, hi, a_max, (n - 3 - k) * dt,
                        a_stop):
            # brake: within the motors' room where that still stops within the travel
            a_o = float(np.clip(-u / dt, max(-a_max, lo_a), min(a_max, hi_a)))
            if not can_stop(u + a_o * dt, base[k + 1] + p[k] + (u + a_o * dt) * dt, lo, hi,
                            a_max, (n - 3 - k) * dt):
                a_o = float(np.clip(-u / dt, -a_max, a_max))
            u1 = u + a_o * dt
        u = u1
        p[k + 1] = p[k] + u * dt
    p[n - 1] = p[n - 2]
    if not np.any(p):
        return Q
    out = Q.copy()
    out[:, i_reach] = base + p
    _, palm_out = kin.frames(out)
    rolled = [rolled_m(t, P, radius_m, t_land_s, v_ball, inertia_ratio)
              for P in (palm, palm_out)]
    return out if rolled[1] < rolled[0] else Q  # the law's fall only where it rolls less
    # (its braking can roll the ball more than the rows alone where the travel is short)
