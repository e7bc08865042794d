"""Time-optimal jerk-limited straight moves in joint space.

A move from ``q_a`` to ``q_b`` follows the straight joint-space line ``q_a + s (q_b -
q_a)`` with the path parameter ``s`` on the fastest profile the joints allow: joint j
caps ``s'`` at ``v_j / |dq_j|``, ``s''`` at ``a_j / |dq_j|`` and ``s'''`` at
``jerk_j / |dq_j|`` (its jerk bound: ``planner.hand.drive``), so the tightest joint sets
one speed cap ``V``, one acceleration cap ``A`` and one jerk cap ``J`` for ``s``, and
the time-optimal rest-to-rest profile under them is the double S (seven segments: jerk
+J, 0, -J while accelerating, a cruise at ``V``, the mirror image while braking; the
cruise, or the constant acceleration, is left out of a move too short to reach ``V``,
or ``A``; Biagiotti & Melchiorri, Trajectory Planning for Automatic Machines and Robots,
2008, section 3.4). That is the shortest time along that line under the joints' box
limits, and it keeps the line, so a path checked by sampling the line stays checked.
Speed and acceleration are zero at both ends, so moves one after another join with
every speed, acceleration and jerk within bounds.

A move's timing is its duration ``T``, the length of its acceleration phase ``ta`` and
of each of its jerk ramps ``tj``: with them the peak speed is ``1 / (T - ta)``, the
peak acceleration ``vp / (ta - tj)`` and the jerk ``ap / tj``.

``LIMIT_FRACTION`` of each limit is used: a sampled trajectory whose continuous speed,
acceleration and jerk respect their limits has row differences that do too (they are
averages: the k-th difference over dt^k is the k-th derivative weighed by a B-spline
kernel), and the fraction keeps float rounding well inside the check's 1 % tolerance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

LIMIT_FRACTION = 0.995


@dataclass(frozen=True)
class Move:
    """A straight joint-space move: from ``q_a`` by ``dq`` over ``duration_s``, its path
    parameter on a double S with acceleration phases of ``ta_s`` and jerk ramps of
    ``tj_s`` (``path_s``). A move of zero length has duration 0."""

    q_a: np.ndarray
    dq: np.ndarray
    duration_s: float
    ta_s: float
    tj_s: float

    back = False  # (it ends at ``q_a + dq``; a ``Bounce`` comes back to ``q_a``)

    @property
    def q_end(self) -> np.ndarray:
        return self.q_a + self.dq

    @property
    def peak_speed(self) -> float:
        """The path parameter's largest speed (1/s; 0 for a zero move)."""
        return 0.0 if self.duration_s == 0.0 else 1.0 / (self.duration_s - self.ta_s)

    @property
    def peak_acceleration(self) -> float:
        """The path parameter's largest acceleration (1/s^2; 0 for a zero move)."""
        return 0.0 if self.duration_s == 0.0 else self.peak_speed / (self.ta_s - self.tj_s)

    @property
    def jerk(self) -> float:
        """The path parameter's jerk while it ramps (1/s^3; 0 for a zero move)."""
        return 0.0 if self.duration_s == 0.0 else self.peak_acceleration / self.tj_s

    def s(self, t_s: np.ndarray) -> np.ndarray:
        """Path parameter in [0, 1] at times ``t_s`` after the move's start (clamped)."""
        return path_s(np.asarray(t_s, dtype=float), self.duration_s, self.ta_s, self.tj_s)

    def at(self, t_s) -> np.ndarray:
        """Joint positions (len(t), n) at times after the start."""
        s = self.s(np.atleast_1d(t_s))
        return self.q_a[None, :] + s[:, None] * self.dq[None, :]

    def time_at_s(self, s_target: float) -> float:
        """The first time (s after the start) at which the path parameter reaches
        ``s_target`` (bisection of the increasing ``path_s`` to the last float)."""
        s_target = min(max(float(s_target), 0.0), 1.0)
        if self.duration_s == 0.0 or s_target == 0.0:
            return 0.0
        lo, hi = 0.0, self.duration_s
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            if mid in (lo, hi):
                break
            if _s_at(mid, self.duration_s, self.ta_s, self.tj_s) >= s_target:
                hi = mid
            else:
                lo = mid
        return hi


def _s_at(t: float, T: float, ta: float, tj: float) -> float:
    """``path_s`` of one time, in floats (``Move.time_at_s`` asks it many times)."""
    t = min(max(t, 0.0), T)
    vp = 1.0 / (T - ta)
    if t > T - ta:
        return 1.0 - _s_acc(T - t, ta, tj, vp)
    if t >= ta:
        return 0.5 * vp * ta + vp * (t - ta)
    return _s_acc(t, ta, tj, vp)


def _s_acc(t: float, ta: float, tj: float, vp: float) -> float:
    ap = vp / (ta - tj)
    if t < tj:
        return ap / tj * t * t * t / 6.0
    if t <= ta - tj:
        return ap / 6.0 * (3.0 * t * t - 3.0 * tj * t + tj * tj)
    u = ta - t
    return 0.5 * vp * ta - vp * u + ap / tj * u * u * u / 6.0


@np.errstate(divide="ignore", invalid="ignore")  # (a zero move's phases: it is at 1)
def path_s(t_s: np.ndarray, duration_s, ta_s, tj_s) -> np.ndarray:
    """Path parameter in [0, 1] at times ``t_s`` after the start of double-S moves of
    ``duration_s`` with acceleration phases ``ta_s`` and jerk ramps ``tj_s`` (clamped):
    element by element, one move's floats for every time or one move per time
    (``planner.play.motion`` samples a track's segments at once). A move of zero length
    is at its end (1)."""
    T, ta_s, tj_s = (np.asarray(x, dtype=float) for x in (duration_s, ta_s, tj_s))
    t = np.clip(t_s, 0.0, T)
    vp = 1.0 / (T - ta_s)  # the peak speed (the cruise covers the rest: vp (T - ta) = 1)
    ap = vp / (ta_s - tj_s)  # the peak acceleration
    jm = ap / tj_s  # the jerk
    late = t > T - ta_s
    u = np.where(late, T - t, t)  # (the braking phase mirrors the accelerating one)
    w = ta_s - u
    acc = np.where(u < tj_s, jm * u * u * u / 6.0,
                   np.where(u <= ta_s - tj_s, ap / 6.0 * (3.0 * u * u - 3.0 * tj_s * u + tj_s * tj_s),
                            0.5 * vp * ta_s - vp * w + jm * w * w * w / 6.0))
    cruise = 0.5 * vp * ta_s + vp * (t - ta_s)
    s = np.where(late, 1.0 - acc, np.where(t >= ta_s, cruise, acc))
    return np.where(np.equal(T, 0.0), 1.0, s)


def straight_move(q_a: np.ndarray, q_b: np.ndarray, v_max: np.ndarray, a_max: np.ndarray,
                  j_max: np.ndarray) -> Move:
    """The time-optimal straight move from ``q_a`` to ``q_b`` under per-joint speed,
    acceleration and jerk limits (any joints: a finger's, the arm's, the whole hand's)."""
    q_a = np.asarray(q_a, dtype=float)
    dq = np.asarray(q_b, dtype=float) - q_a
    caps = path_caps(dq.tolist(), np.asarray(v_max, dtype=float).tolist(),
                     np.asarray(a_max, dtype=float).tolist(),
                     np.asarray(j_max, dtype=float).tolist())
    return capped_move(q_a, dq, caps)


def capped_move(q_a: np.ndarray, dq: np.ndarray, caps: tuple[float, float, float] | None
                ) -> Move:
    """The move by ``dq`` from ``q_a`` on the double S of the path caps ``caps`` (speed,
    acceleration, jerk of ``s``; None: it does not move)."""
    if caps is None:
        return Move(q_a, dq, 0.0, 0.0, 0.0)
    return Move(q_a, dq, *phases(*caps))


def path_caps(dq: list[float], v_max: list[float], a_max: list[float], j_max: list[float]
              ) -> tuple[float, float, float] | None:
    """The path parameter's speed, acceleration and jerk caps of a straight move by
    ``dq`` (floats: a few joints), set by its tightest joint; None when it does not move.
    ``move_time_s(*caps)`` is its duration (the programme asks only that, for many
    moves: no ``Move`` made)."""
    v = a = j = math.inf
    moving = False
    for d, vj, aj, jj in zip(dq, v_max, a_max, j_max):  # (``min`` and ``abs`` spelt out:
        if d:  # the same floats in less than half the time; a fresh process asks thousands)
            if d < 0.0:
                d = -d
            moving = True
            x = LIMIT_FRACTION * vj / d
            if x < v:  # noqa: PLR1730
                v = x
            x = LIMIT_FRACTION * aj / d
            if x < a:  # noqa: PLR1730
                a = x
            x = LIMIT_FRACTION * jj / d
            if x < j:  # noqa: PLR1730
                j = x
    return (v, a, j) if moving else None


def move_times_s(dq: np.ndarray, v_max: np.ndarray, a_max: np.ndarray,
                 j_max: np.ndarray) -> np.ndarray:
    """``straight_move``'s durations of the moves by the rows of ``dq`` (n, joints), all
    at once and bit for bit: the caps of ``path_caps`` per row in the same float
    operations, element by element, and ``move_time_s`` of each (``tests/
    test_play_profile.py`` holds them equal)."""
    d = np.abs(dq)
    moving = d != 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        caps = [np.where(moving, LIMIT_FRACTION * np.asarray(x, dtype=float) / d,
                         math.inf).min(axis=1) for x in (v_max, a_max, j_max)]
    return np.array([move_time_s(v, a, j) if m else 0.0
                     for v, a, j, m in zip(*(c.tolist() for c in caps),
                                           moving.any(axis=1).tolist())], dtype=float)


def move_time_s(v: float, a: float, j: float) -> float:
    """Duration of a unit move on the double S of caps ``v``, ``a`` and ``j``."""
    return phases(v, a, j)[0]


def phases(v: float, a: float, j: float) -> tuple[float, float, float]:
    """(duration, acceleration phase, jerk ramp) of the time-optimal rest-to-rest unit
    move under caps ``v``, ``a``, ``j`` of speed, acceleration and jerk (Biagiotti &
    Melchiorri 2008, eq. 3.30-3.32 with q1 - q0 = 1 and zero speeds at the ends)."""
    if v * j >= a * a:  # the acceleration cap is reached before the speed cap
        tj = a / j
        ta = tj + v / a
    else:
        tj = math.sqrt(v / j)
        ta = 2.0 * tj
    if 1.0 / v >= ta:  # the speed cap is reached: a cruise of 1 / v - ta
        return 1.0 / v + ta, ta, tj
    tj = a / j  # not reached: the peak speed a (ta - tj) with ta (ta - tj) a = 1
    ta = 0.5 * tj + math.sqrt(0.25 * tj * tj + 1.0 / a)
    if ta >= 2.0 * tj:
        return 2.0 * ta, ta, tj
    tj = (0.5 / j) ** (1.0 / 3.0)  # nor the acceleration cap: 2 j tj^3 = 1
    return 4.0 * tj, 2.0 * tj, tj


# A bounce (``Bounce``): out from rest to a turn at ``s`` = 1 and back to rest along one
# straight line, its second half the first played backwards (the acceleration continuous
# at the turn: braking both ways). Its half is the time-optimal move from rest to a stop
# with the end acceleration free under the path caps V, A, J (Pontryagin: the jerk at
# +-J or 0): a double-S acceleration phase to the peak speed ``vp`` (jerk +J for ``tj``,
# the acceleration held at its peak, -J for ``tj``: ``ta`` in all), a cruise at ``vp``
# (only where V binds), then braking: jerk -J for ``tb`` and the acceleration held at
# -J ``tb`` (at -A where A binds) until the speed is 0 at the turn; the peak speed is the
# largest whose distance is 1 (``bounce_move``). With A and V unbound that is jerk +J for
# 1 ramp, -J for 1 + sqrt 2 (-sqrt 2 ramps' acceleration at the turn); with A bound, a
# constant braking through the turn (the shape ``Move``'s double S has at its ends).


def _bounce_knots(H, tj, ta, tb):
    """The half's jerk ``J``, peak speed ``vp``, cruise ``tc`` and braking hold ``tk`` of
    bounces with half ``H`` and ramps ``tj``, ``ta``, ``tb`` (distance 1 to the turn;
    floats or arrays alike)."""
    p = tj * (ta - tj)  # (vp / J)
    tk = (p - 0.5 * tb * tb) / tb  # (the hold that brings the speed to 0: J tb tk = v1)
    tc = H - ta - tb - tk
    v1 = p - 0.5 * tb * tb  # (the speed at the hold's start, / J)
    jerk = 1.0 / (0.5 * p * ta + p * tc + p * tb - tb * tb * tb / 6.0 + 0.5 * v1 * v1 / tb)
    return jerk, jerk * p, tc, tk


def _half_s(h, H, tj, ta, tb):
    """The path parameter at times ``h`` (in [0, ``H``]) of the half of bounces (arrays)."""
    jerk, vp, tc, tk = _bounce_knots(H, tj, ta, tb)
    ap = jerk * tj
    u = np.minimum(h, ta)
    w = ta - u
    acc = np.where(u < tj, jerk * u * u * u / 6.0,
                   np.where(u <= ta - tj, ap / 6.0 * (3.0 * u * u - 3.0 * tj * u + tj * tj),
                            0.5 * vp * ta - vp * w + jerk * w * w * w / 6.0))
    x = np.clip(h - ta - tc, 0.0, tb)  # (into the braking ramp)
    fwd = acc + vp * np.clip(h - ta, 0.0, tc) + vp * x - jerk * x * x * x / 6.0
    r = H - h  # (the hold, counted back from the turn: 1 there exactly)
    return np.where(r <= tk, 1.0 - 0.5 * jerk * tb * r * r, fwd)


def _half_scalar(h: float, H: float, tj: float, ta: float, tb: float) -> float:
    """``_half_s`` of one time in floats (``Bounce.time_at_s`` asks it many times)."""
    jerk, vp, tc, tk = _bounce_knots(H, tj, ta, tb)
    if H - h <= tk:
        return 1.0 - 0.5 * jerk * tb * (H - h) ** 2
    x = min(max(h - ta - tc, 0.0), tb)
    cruise = vp * min(max(h - ta, 0.0), tc) + vp * x - jerk * x * x * x / 6.0
    return _s_acc(min(h, ta), ta, tj, vp) + cruise


def bounce_s(t_s: np.ndarray, duration_s, tj_s, ta_s, tb_s) -> np.ndarray:
    """Path parameter of bounces of ``duration_s`` and ramps ``tj_s``, ``ta_s``, ``tb_s``
    at times ``t_s`` after their start: 0 at both ends (clamped), 1 at the turn halfway
    (element by element, as ``path_s``)."""
    T, tj, ta, tb = (np.asarray(x, dtype=float) for x in (duration_s, tj_s, ta_s, tb_s))
    h = np.clip(np.minimum(t_s, T - t_s), 0.0, 0.5 * T)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(T > 0.0, _half_s(h, 0.5 * T, tj, ta, tb), 0.0)


@dataclass(frozen=True)
class Bounce:
    """Out from ``q_a`` by ``dq`` and straight back, rest to rest over ``duration_s``, the
    path parameter 1 at the turn halfway (``bounce_s``; its half's acceleration phase
    ``ta_s`` with jerk ramps ``tj_s``, its braking ramp ``tb_s``)."""

    q_a: np.ndarray
    dq: np.ndarray
    duration_s: float
    tj_s: float
    ta_s: float
    tb_s: float

    back = True

    @property
    def q_end(self) -> np.ndarray:
        return self.q_a

    def _knots(self):
        return _bounce_knots(0.5 * self.duration_s, self.tj_s, self.ta_s, self.tb_s)

    @property
    def peak_speed(self) -> float:
        return self._knots()[1] if self.duration_s > 0.0 else 0.0

    @property
    def peak_acceleration(self) -> float:
        return self._knots()[0] * max(self.tj_s, self.tb_s) if self.duration_s > 0.0 else 0.0

    @property
    def jerk(self) -> float:
        return self._knots()[0] if self.duration_s > 0.0 else 0.0

    def s(self, t_s: np.ndarray) -> np.ndarray:
        return bounce_s(np.asarray(t_s, dtype=float), self.duration_s, self.tj_s, self.ta_s,
                        self.tb_s)

    def at(self, t_s) -> np.ndarray:
        s = self.s(np.atleast_1d(t_s))
        return self.q_a[None, :] + s[:, None] * self.dq[None, :]

    def time_at_s(self, s_target: float) -> float:
        """The first time (s after the start) at which the path parameter reaches
        ``s_target`` (on the way out; bisection to the last float)."""
        s_target = min(max(float(s_target), 0.0), 1.0)
        H = 0.5 * self.duration_s
        lo, hi = 0.0, H
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            if mid in (lo, hi):
                break
            if _half_scalar(mid, H, self.tj_s, self.ta_s, self.tb_s) >= s_target:
                hi = mid
            else:
                lo = mid
        return hi

    def slowed(self, sigma: float) -> Bounce:
        return self if sigma == 1.0 else Bounce(self.q_a, self.dq, self.duration_s * sigma,
                                                self.tj_s * sigma, self.ta_s * sigma,
                                                self.tb_s * sigma)


def _bounce_half(vp: float, a: float, j: float) -> tuple[float, float, float, float]:
    """(tj, ta, tb, distance) of a bounce's half with peak speed ``vp`` under the caps
    ``a``, ``j``, without its cruise (Biagiotti & Melchiorri 2008, eq. 3.30's phases)."""
    if vp * j >= a * a:
        tj = a / j
        ta = tj + vp / a
    else:
        tj = math.sqrt(vp / j)
        ta = 2.0 * tj
    if vp * j >= 0.5 * a * a:  # (the braking reaches -A: held there to the turn)
        tb = a / j
        v1 = vp - 0.5 * j * tb * tb
        hold = 0.5 * v1 * v1 / a
    else:
        tb = math.sqrt(2.0 * vp / j)
        hold = 0.0
    return tj, ta, tb, 0.5 * vp * ta + vp * tb - j * tb * tb * tb / 6.0 + hold


def bounce_move(q_a: np.ndarray, q_turn: np.ndarray, v_max: np.ndarray, a_max: np.ndarray,
                j_max: np.ndarray) -> Bounce:
    """The fastest ``Bounce`` from ``q_a`` to ``q_turn`` and back under per-joint speed,
    acceleration and jerk limits (``path_caps``): its half's peak speed the largest whose
    distance without a cruise is at most 1 (bisection to the last float), or the speed
    cap with a cruise over the rest."""
    q_a = np.asarray(q_a, dtype=float)
    dq = np.asarray(q_turn, dtype=float) - q_a
    caps = path_caps(dq.tolist(), np.asarray(v_max, dtype=float).tolist(),
                     np.asarray(a_max, dtype=float).tolist(), np.asarray(j_max, dtype=float).tolist())
    if caps is None:
        return Bounce(q_a, dq, 0.0, 0.0, 0.0, 0.0)
    v, a, j = caps
    vp = v
    if _bounce_half(v, a, j)[3] > 1.0:  # (V not reached: the peak speed of distance 1)
        lo, hi = 0.0, v
        for _ in range(200):
            vp = 0.5 * (lo + hi)
            if vp in (lo, hi):
                break
            if _bounce_half(vp, a, j)[3] > 1.0:
                hi = vp
            else:
                lo = vp
        vp = lo
    tj, ta, tb, dist = _bounce_half(vp, a, j)
    tk = (vp - 0.5 * j * tb * tb) / (j * tb)
    half = ta + (1.0 - dist) / vp + tb + tk
    return Bounce(q_a, dq, 2.0 * half, tj, ta, tb)
