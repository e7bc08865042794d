"""The live catch's soft stop (issue 31, item 3): the planned catch's stopping motion
(``planner.catch.plan.stopping``: ``SoftStop``, made by ``stop_profile``, one definition)
on the live estimate. After each observation, until its ramp is about to begin, the
session asks for the stopping motion through the newest intercept pose (``live_stop``):
the arm's speeds when the palm meets the ball (the planned catch's contact-speed QP,
solved here exactly by its active set, ``box_qp``: three variables, no solver set-up),
the ramps as short as the motors allow, slowed where the joints' range or the time
before the ball is short. The arm's move (``live.motion``) goes to the pre-catch pose
(the intercept pose less the ramp's travel) and is at rest there when the ramp starts;
once the rows reach the ramp (``fixes``) the motion is fixed: the rows never change
once written, and the ramp, the contact, the recoil and the ramp out follow it.

The motion (``StopTable``): for throws through the catch point at ``TABLE_ANGLES_DEG``,
made at set-up, the planned catch's tilt (``stopping.stop_tilt``) and the stopping motion
at its intercept; the session takes the one of the throw nearest the estimate's launch
angle, through the estimate's own intercept pose, until the hand moves (then it keeps its
speeds and ramps, and follows the estimate's intercept). Not searched live (the planned catch does,
``plan_stop``): the contact share (``LIVE_CONTACT_SHARE``); the check's rule judges the
rows at the end as it judges the planned ones.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from planner.catch.flight.path import Ball, Flight, predict_throw
from planner.catch.live import stopcache
from planner.catch.live.search import NEAR_S
from planner.catch.plan.arm import move_time
from planner.catch.plan.contactqp import ROLL_WEIGHT, contact_qp
from planner.catch.plan.stopping import (
    SoftStop,
    StopAsk,
    StopDynamics,
    stop_profile,
    stop_tilt,
)
from planner.errors import InfeasibleError, InputError

LIVE_CONTACT_SHARE = 0.9  # the arm's speed when the palm meets the ball, as a share of its
# speed after the recoil: the planned catch's first contact share tried
# (``stopping.CONTACT_SHARES[0]``), which its greedy search kept on 5 of the 9 feasible
# throws of bench_live's first 10 (0.8 on 3, 0.7 on 1; measured with plan_throw)
START_SLACK_S = 0.02  # the live hand starts its move to the pre-catch pose this much before
# it must (two observations at 100 Hz): room for the re-aims that follow newer estimates,
# each of which must end at rest before the ramp begins
OVERLAP_STEP_S = 0.0005  # the arm's move and the ramp, where they overlap, checked this
# finely (the rows are 1-10 ms apart; the guard and the check read their differences)
RAMP_MARGIN_S = 0.005  # the arm's re-aims end at rest this long before the ramp starts: a
# newer estimate moves the intercept, and with it the ramp's start, by ~1 ms (1 sigma of a
# 5 mm camera's late in the flight, ``live.search.NEAR_S``); a re-aim that ended at the
# older start would then run into the ramp and no later one could end in time
LATE_TOL_S = 0.010  # an arm this little late for the ramp (one 100 Hz row) keeps the
# table's motion: a newer estimate's target moves by a few mrad (the noise of its
# deviation), which the shortest re-aim cannot make in less (``phase_duration``'s 10 ms
# floor); what it leaves of the move where the ramp starts is checked within the joints'
# limits when the stop is fixed (``session._adds_within_limits``)
LATE_STEPS = 6  # a late hand's slower stop: its share of the speeds found to 1/64 by
# bisection (a ramp of ~0.12 s to within ~2 ms)
_KKT_TOL = 1e-12  # the active set's multipliers and steps: rounding, not a choice


def box_qp(P: np.ndarray, c: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """min x^T P x / 2 + c^T x within lo <= x <= hi (lo <= 0 <= hi), P positive definite:
    the exact minimiser by the primal active-set method (from x = 0; a bound met on the
    way is held; a held bound whose multiplier says the objective falls off it is
    released). Finite for a strictly convex problem: a few steps for three variables.
    (The steps' scalar tests in Python floats: the same IEEE arithmetic as numpy's
    scalars, without their overhead.)"""
    n = len(c)
    x = np.zeros(n)
    at = [0] * n  # 0 free, -1 at lo, +1 at hi
    lo_l, hi_l = lo.tolist(), hi.tolist()
    for _ in range(8 * n + 8):
        f = [i for i in range(n) if at[i] == 0]
        target = x.copy()
        if f:
            fixed = [i for i in range(n) if at[i] != 0]
            rhs = -(c[f] + P[f][:, fixed] @ x[fixed])
            target[f] = np.linalg.solve(P[f][:, f], rhs)
        d = target - x
        dl, xl = d.tolist(), x.tolist()
        alpha, block = 1.0, -1
        for i in f:
            if dl[i] > _KKT_TOL and xl[i] + dl[i] > hi_l[i]:
                a = (hi_l[i] - xl[i]) / dl[i]
            elif dl[i] < -_KKT_TOL and xl[i] + dl[i] < lo_l[i]:
                a = (lo_l[i] - xl[i]) / dl[i]
            else:
                continue
            if a < alpha:
                alpha, block = a, i
        x = x + alpha * d
        if block >= 0:
            at[block] = 1 if dl[block] > 0 else -1
            x[block] = hi_l[block] if at[block] > 0 else lo_l[block]
            continue
        g = (P @ x + c).tolist()  # the multipliers, >= 0 at a true optimum
        lam = [g[i] if at[i] < 0 else -g[i] if at[i] > 0 else math.inf for i in range(n)]
        k = min(range(n), key=lam.__getitem__)
        if lam[k] >= -_KKT_TOL:
            return np.clip(x, lo, hi)
        at[k] = 0
    return np.clip(x, lo, hi)


def giving_contact_speeds(k_flex: int):
    """``contactqp.contact_speeds``' QP (``contact_qp``) solved exactly (``box_qp``), the
    wrist flexion (column ``k_flex``) bounded to the side on which it moves the palm
    against its normal (away from the arriving ball): the palm gives with the ball. (Unbounded, a noisy early estimate's
    optimum can turn the palm into the ball, trading the pad's normal speed for the roll
    term's tangential one: bench_live's 100 Hz / 5 mm throws 5, 11 and 13 rolled 338-500 mm
    so; the planned catch's flexion gives with the ball on every one of them.)"""

    def speeds(J: np.ndarray, v_ball: np.ndarray, bound: np.ndarray, normal: np.ndarray,
               roll_weight: float = ROLL_WEIGHT) -> np.ndarray:
        P, c = contact_qp(J, v_ball, normal, roll_weight)
        lo, hi = -bound.copy(), bound.copy()
        if float(J[:, k_flex] @ normal) > 0.0:  # (the palm's normal faces the ball: giving
            hi[k_flex] = 0.0  # is moving against it)
        else:
            lo[k_flex] = 0.0
        return box_qp(P, c, lo, hi)

    return speeds


def live_stop(dyn: StopDynamics, v_ball: np.ndarray, mass: float, r: float,
              q_open: np.ndarray, t_i: float, ready_by, row_s: float) -> SoftStop:
    """The stopping motion through ``q_open`` for the ball arriving at ``t_i`` with
    ``v_ball`` (``stop_profile`` at ``LIVE_CONTACT_SHARE``, tilt 0), or the palm at rest
    when no motion of that family is left."""
    speeds = giving_contact_speeds(dyn.arm.index(dyn.joints.i_flex))
    ask = StopAsk(0.0, LIVE_CONTACT_SHARE, dyn.v_max.copy(), ROLL_WEIGHT, speeds)
    stop = stop_profile(dyn, v_ball, mass, r, q_open, t_i, ready_by, row_s, ask)
    if stop is None:
        rest = StopAsk(0.0, 1.0, np.zeros(len(dyn.arm)), ROLL_WEIGHT, speeds)
        stop = stop_profile(dyn, v_ball, mass, r, q_open, t_i, ready_by, row_s, rest)
    return stop


def scaled(stop: SoftStop, k: float) -> SoftStop:
    """``stop`` at ``k`` (0..1) of its speeds, its ramps ``k`` times as long: the same peak
    accelerations (the ramps' motor loads no higher), the palm slower at the contact (the
    pad's recoil and hold as they were: the rows' check judges the contact)."""
    return replace(stop, qd=k * stop.qd, ramp_in_s=k * stop.ramp_in_s,
                   ramp_out_s=k * stop.ramp_out_s)


def moves(stop: SoftStop | None) -> bool:
    """Whether ``stop`` moves the arm (not the palm at rest)."""
    return stop is not None and bool(stop.qd.any())


def arm_offset(stop: SoftStop | None, t_s: np.ndarray, n: int) -> np.ndarray | None:
    """The stopping motion's part of the rows at ``t_s`` (T, n): the arm's travel from the
    pre-catch pose (zero up to the ramp's start); None where no row is after it."""
    if not moves(stop) or t_s[-1] <= stop.start_s:
        return None
    return stop.offset(t_s, n) - stop.offset(np.array([-np.inf]), n)[0]


def met_on_the_moving_palm(stop: SoftStop, target_m: np.ndarray, ball_m: np.ndarray,
                           v_ball: np.ndarray) -> float:
    """When a ball at ``ball_m`` (velocity ``v_ball``) at the fixed stop's intercept time
    is nearest the palm target, which passes ``target_m`` then at the contact velocity
    ``stop.v_palm`` (both straight over the few ms a newer estimate moves it): the
    intercept time of a newer estimate on the fixed motion, within ``NEAR_S`` of the fixed
    one (the palm moves nearly with the ball, so an estimate centimetres off the palm's path
    would move it by far more: such a ball misses the palm whenever it is judged)."""
    d0 = ball_m - target_m
    vr = v_ball - stop.v_palm
    vv = float(vr @ vr)
    shift = float(d0 @ vr) / vv if vv > 0 else 0.0
    return stop.t_i - min(max(shift, -NEAR_S), NEAR_S)


def column_medians(P: np.ndarray) -> np.ndarray:
    """``np.median(P, axis=0)``'s numbers for finite ``P`` (each column's middle value
    sorted; the mean of the middle two for an even count), without ``numpy.ma``, which
    ``np.median`` imports on its first use: ~20 ms of ``catch --live``'s set-up CPU."""
    s = np.sort(P, axis=0)
    h = len(s) // 2
    return s[h].copy() if len(s) % 2 else (s[h - 1] + s[h]) / 2.0


TABLE_ANGLES_DEG = tuple(range(10, 81, 5))  # launch angles of the table's throws: the
# issue's envelope (15-75 deg) and 5 deg beyond, 5 deg apart (the planned catch's tilts
# are 5 deg apart; its choice changes a few times over the envelope). Its set-up: ~0.2 s
# (10 deg apart: ~0.07 s, but tests/test_live.py's 30 deg / 1.5 m throw then misses the
# palm by 15.2 mm, beyond the check's 15)
_TABLES: dict[tuple, StopTable] = {}


class StopTable:
    """The stopping motions of the throws through one catch point at ``TABLE_ANGLES_DEG``
    (made at set-up): per throw the palm's tilt the planned catch chooses (``stop_tilt``)
    and the stopping motion at that tilt's intercept (``stop_profile`` at
    ``LIVE_CONTACT_SHARE``, from the planned catch's start), looked up by a flight's launch
    angle: the live hand's motion is the nearest throw's, through its own intercept."""

    def __init__(self, angles_deg: np.ndarray, tilts_rad: np.ndarray,
                 stops: tuple[SoftStop, ...], prior: np.ndarray) -> None:
        self.angles_deg, self.tilts_rad, self.stops = angles_deg, tilts_rad, stops
        self.prior = prior  # the arm joints' median pre-catch pose over the table's throws
        # (where a live hand goes before its first estimate)

    @classmethod
    def of(cls, pl, C: np.ndarray, ball: Ball, drag: bool, row_s: float) -> StopTable:
        """The table of planner ``pl`` at the catch point ``C`` (made once, kept)."""
        key = (id(pl), tuple(float(x) for x in C), ball.name, ball.radius_m, bool(drag),
               float(row_s))
        table = _TABLES.get(key)
        if table is None:
            table = _TABLES[key] = cls.kept(pl, C, ball, drag, row_s)
        return table

    @classmethod
    def kept(cls, pl, C: np.ndarray, ball: Ball, drag: bool, row_s: float) -> StopTable:
        """The table read from the cache between runs where one is kept for this key
        (``live.stopcache``: ``HAND_PLANNER_CACHE`` set), else made (and kept there)."""
        d = stopcache.cache_dir()
        if d is None:
            return cls.make(pl, C, ball, drag, row_s)
        path = stopcache.table_path(d, stopcache.table_key(pl, C, ball, drag, row_s))
        parts = stopcache.load(path) if path.exists() else None
        if parts is not None:
            return cls(*parts)
        table = cls.make(pl, C, ball, drag, row_s)
        stopcache.save(path, table.angles_deg, table.tilts_rad, table.stops, table.prior)
        return table

    @classmethod
    def make(cls, pl, C: np.ndarray, ball: Ball, drag: bool, row_s: float) -> StopTable:
        from planner.catch.plan.arm import open_from
        from planner.catch.plan.intercept import find_intercept
        from planner.catch.plan.planner import PLAN_BUDGET_S, SIGNAL_S

        closing = pl.closing(ball.radius_m)
        r, dyn = float(ball.radius_m), pl.dyn
        angles, tilts, stops, pres = [], [], [], []

        def ready_by(q: np.ndarray) -> float:  # (the planned catch's, from t = 0)
            return SIGNAL_S + PLAN_BUDGET_S + move_time(dyn, pl.q_rest, q)

        for a in TABLE_ANGLES_DEG:
            try:
                fl = predict_throw(float(a), float(C[0]), float(C[2]), ball, drag)
                t_c = float(fl.time_at_x(float(C[0])))
            except (InputError, InfeasibleError):
                continue
            placed: dict = {}  # (the search's intercepts by tilt: the one chosen not found again)
            tilt = stop_tilt(dyn, pl.wrist, fl, C, r, pl.q_zero, closing, t_c, ready_by, row_s,
                             giving_contact_speeds(dyn.arm.index(dyn.joints.i_flex)), placed)
            ic = placed.get(tilt)
            if ic is None:
                ic = find_intercept(pl.wrist, fl, C, r, t_c, tilt)
            if ic.reason is not None:
                continue
            q = pl.q_zero.copy()
            j = pl.joints
            q[j.i_flex], q[j.i_dev] = ic.theta, ic.dev
            if j.i_rail is not None:
                q[j.i_rail] = ic.rail
            q_open = open_from(pl.hand, j, q, closing.q_closed)
            angles.append(float(a))
            tilts.append(float(tilt))
            stops.append(live_stop(dyn, fl.velocity(ic.t), float(ball.mass_kg), r, q_open,
                                   float(ic.t), ready_by, row_s))
            pres.append(q_open[list(dyn.arm)] + stops[-1].first_offset)
        prior = column_medians(np.array(pres)) if pres else pl.q_rest[list(dyn.arm)].copy()
        return cls(np.array(angles), np.array(tilts), tuple(stops), prior)

    def entry_for(self, flight: Flight) -> tuple[float, SoftStop | None]:
        """The tilt and stopping motion of the table's throw nearest ``flight``'s launch
        angle ((0, None): no throw in the table)."""
        if not len(self.angles_deg):
            return 0.0, None
        v = flight.v0
        a = math.degrees(math.atan2(float(v[2]), math.hypot(float(v[0]), float(v[1]))))
        k = int(np.argmin(np.abs(self.angles_deg - a)))
        return float(self.tilts_rad[k]), self.stops[k]
