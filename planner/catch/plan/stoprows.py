"""The stop optimised on the plan's own rows: a linear programme of the check's stopping rule.

Where every stop the planner searches (one profile of the arm, ``planner.catch.plan.stopping``)
leaves a motor over its capacity and the stop bound (``planner.catch.plan.stopbound``) does
not exclude a stop (``CatchReason.NO_STOP``), this module changes the arm's rows around the
touch by the offset ``dq`` (rows x arm joints) that least loads the most loaded motor in the
check's own rule (``planner.check.ball.ball_load_instants``) on the rows, at the plan's rate:

* every instant the rule judges (the touch: the pad's force at the touch's row acceleration;
  every later row: the pad's or the riding ball's force from the rows' second differences),
  each motor's torque ``M (g + J^T F + H a + c)`` within ``s`` times its capacity, the torque
  linear in the offset's second differences (the row's mass matrix ``H``, the palm target's
  Jacobian carrying the ball's force ``F = m (a_target - g)``);
* the ball's force inside the friction cone (its inscribed pyramid, ``PALM_MU / sqrt 2`` on
  two tangents, ``CONE_MARGIN_N`` within its faces or as far as the rows are) where the rule
  judges it (the pad, a palm decelerating faster than g, before
  the grasp); where the rows' force is outside it but not judged (the palm slower than g),
  the palm target's acceleration kept below g (inside a box within g's sphere);
* every joint's row speed, acceleration and third difference (jerk) within the hand file's
  limits times ``LIMIT_MARGIN`` (the planner's 98 %; no worse than the rows' own where they
  are already beyond), positions within the planned range;
* the rows that carry the touch (the two about the intercept) unchanged: the palm meets the
  ball where and as fast as the plan's; the rows outside the window (``STOP_PRE_S`` before the
  touch, ``STOP_POST_S`` after) unchanged: the move-in, the closing and the hold turn as
  planned.

Objective: ``s`` plus ``SMOOTH_WEIGHT`` times the offset's third differences (as shares of
each joint's jerk bound): a controller's motion, not a bang-bang one. The torques are
linearised at the current rows; the programme is solved again on the changed rows
(``ROUNDS`` times, each offset within ``TRUST_RAD``/``TRUST_M``) and every round judged by
the check's own rule (``ball_load_instants``), the best kept. Fingers are not moved (the
closing's rows as planned: the offset moves the palm and the fingers together)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linprog

from planner.catch.plan.stopbound import SparseRows, cone_tangents
from planner.check.ball import STOP_DIFF_S, ball_load_instants, ball_positions, phase_loads
from planner.check.ballstop import PALM_MU, pad_force_n, pad_time_s, ride_force_n
from planner.check.kinematics import G, Kinematics
from planner.check.motormap import motor_torque_matrix
from planner.hand.tendon import actuator_capacity
from planner.trajectory import LIMIT_MARGIN

STOP_PRE_S = 0.03  # rows before the touch the offset may move: 3 rows at 100 Hz (the touch's
# own acceleration is the row before or after it)
STOP_POST_S = 0.25  # rows after it: the planner's stops bring the arm to rest within 0.2 s
SMOOTH_WEIGHT = 1e-3  # share of capacity per (jerk bound x row) of the offset's third
# differences: a tie-break of equal loads, 0.001 of a motor's share for a full jerk bound
ROUNDS = 4  # re-linearisations (the second usually lands within 1 % of the check's torque)
SETTLED = 1e-3  # a round whose share moved less than this from the last ends them (0.1 %
# of a motor: below the check's 1 % tolerance)
TRUST_RAD = 0.05  # largest offset of a revolute joint per round (rad): the linearisation's
TRUST_M = 0.02  # and of a prismatic one (m): the mass matrix changes little over these
CONE_MARGIN_N = 0.3  # the ball's force kept this far inside the cone's pyramid (or as far
# as the rows keep it, where less): with none,
# -0.3 m / 15 deg / 4.0 m planned at 1000 Hz sat on its face and the written rows (6
# decimals) left the cone by 0.06 N in the check; five times that
_FD = 1e-6  # finite-difference step of the palm target's Jacobian (rad or m)


@dataclass(frozen=True)
class RowStop:
    """The optimised rows ``Q`` (None: no round improved on the plan's), the check's worst
    stopping instant on them (``stop``: a ``BallLoad``), the programme's last share ``share``
    (its linear model) and why it failed (``failure``: '' when it solved)."""

    Q: np.ndarray | None
    stop: object
    share: float
    failure: str


@dataclass(frozen=True)
class Instant:
    """One instant the check judges, linearised: the row ``row`` whose second difference
    carries its acceleration, the motors' torques ``tau`` (signed, N m), their change per
    arm acceleration ``S`` (motors x arm) and per force on the palm ``SJ`` (motors x 3), the
    ball's force ``F``, the palm's normal ``n``, whether the cone is judged (``cone``), the
    palm target's acceleration ``acc`` (m/s^2) and its Jacobians over the arm at the rows
    ``row`` - 1, ``row``, ``row`` + 1 (``Jt3``, 3 x 3 x arm: the target's second difference
    is their rows' offsets' through them)."""

    row: int
    tau: np.ndarray
    S: np.ndarray
    SJ: np.ndarray
    F: np.ndarray
    n: np.ndarray
    cone: bool
    acc: np.ndarray
    Jt3: np.ndarray


def row_rates(t: np.ndarray, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Central first and second differences of rows ``X`` at times ``t`` (zero at the ends),
    as the check takes them."""
    V, A = np.zeros_like(X), np.zeros_like(X)
    if len(t) >= 3:
        dt0, dt1 = np.diff(t)[:-1, None], np.diff(t)[1:, None]
        V[1:-1] = (X[2:] - X[:-2]) / (dt0 + dt1)
        A[1:-1] = 2.0 * ((X[2:] - X[1:-1]) / dt1 - (X[1:-1] - X[:-2]) / dt0) / (dt0 + dt1)
    return V, A


class RowStopModel:
    """The check's stopping rule on rows ``t``, ``Q`` of a hand (``kin``: the check's
    kinematics), linearised in the arm joints ``arm``' accelerations."""

    def __init__(self, kin: Kinematics, arm: list[int], ball: dict, t_i: float,
                 grasp_t: float | None) -> None:
        self.kin, self.arm, self.ball, self.t_i = kin, list(arm), ball, float(t_i)
        self.held = math.inf if grasp_t is None else float(grasp_t)
        hand = kin.hand
        fingers = {n for f in hand.fingers for n in hand.spec.joints_of(f)}
        self.fingers = np.array([n in fingers for n in hand.joint_names])
        self.cap = actuator_capacity(hand).torque_nm

    def target(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The palm target (centre + radius x normal) and the palm's normal at ``q``."""
        _, P = self.kin.frames(q[None, :])
        return P[0, :3, 3] + self.ball["radius"] * P[0, :3, 2], P[0, :3, 2]

    def target_jacobian(self, q: np.ndarray) -> np.ndarray:
        """The palm target's Jacobian over the arm joints at ``q`` (3 x arm)."""
        c0 = self.target(q)[0]
        Jt = np.empty((3, len(self.arm)))
        for c, j in enumerate(self.arm):
            dq = q.copy()
            dq[j] += _FD
            Jt[:, c] = (self.target(dq)[0] - c0) / _FD
        return Jt

    def instant(self, row: int, q: np.ndarray, v: np.ndarray, a: np.ndarray,
                F: np.ndarray, acc: np.ndarray, cone: bool, Jt3: np.ndarray) -> Instant:
        """The instant at pose ``q`` (joint speeds ``v``, accelerations ``a``, the ball's force
        ``F``, the palm target's acceleration ``acc``), linearised in the arm's accelerations."""
        kin = self.kin
        (J,) = kin.point_jacobians(q, [kin.palm_id])
        Mm = motor_torque_matrix(kin.hand, q)
        base = kin.inertial(q, v, a)
        tau = Mm @ (kin.gravity(q) + J.T @ F + base)
        H = np.empty((len(q), len(self.arm)))
        for c, j in enumerate(self.arm):
            da = a.copy()
            da[j] += 1.0
            H[:, c] = kin.inertial(q, v, da) - base
        return Instant(row, tau, Mm @ H, Mm @ J.T, F, self.target(q)[1], cone, acc, Jt3)

    def instants(self, t: np.ndarray, Q: np.ndarray, last: int) -> list[Instant]:
        """Every instant the check judges on the rows (``ball_load_instants``' own) up to row
        ``last`` (the later ones do not change with the offset)."""
        b, r, m = self.ball, self.ball["radius"], float(self.ball["mass"])
        ti, h = self.t_i, STOP_DIFF_S
        bp = ball_positions(b["p0"], b["v0"], b["drag"], [ti - h, ti + h])
        qa = np.array([np.interp(x, t, Q[:, j]) for x in (ti - h, ti, ti + h)
                       for j in range(Q.shape[1])]).reshape(3, -1)
        ca = [self.target(q)[0] for q in qa]
        v_rel = (bp[1] - bp[0] - (ca[2] - ca[0])) / (2 * h)
        give = self.kin.hand.pad_give_m  # the palm's pad (the hand file's)
        t_pad = pad_time_s(v_rel, give)
        V, A = row_rates(t, Q)
        V[:, self.fingers] = 0.0
        A[:, self.fingers] = 0.0
        _, P = self.kin.frames(Q)
        centre = P[:, :3, 3] + r * P[:, :3, 2]
        _, CA = row_rates(t, centre)
        k0 = int(np.clip(np.searchsorted(t, ti, side="right") - 1, 0, len(t) - 2))
        kn = k0 if ti - t[k0] <= t[k0 + 1] - ti else k0 + 1
        v_i = np.where(self.fingers, 0.0, (Q[k0 + 1] - Q[k0]) / (t[k0 + 1] - t[k0]))
        Jt = {k: self.target_jacobian(Q[k]) for k in range(kn - 1, last + 2)}
        out = [self.instant(kn, qa[1], v_i, A[kn], pad_force_n(m, v_rel, CA[kn], give),
                            CA[kn], ti < self.held, np.stack([Jt[kn + i] for i in (-1, 0, 1)]))]
        for k in np.flatnonzero((t > ti) & (np.arange(len(t)) <= last)):
            pad = t[k] < ti + t_pad
            F = pad_force_n(m, v_rel, CA[k], give) if pad else ride_force_n(m, CA[k])
            slows = pad or float(np.linalg.norm(CA[k])) > G
            out.append(self.instant(int(k), Q[k], V[k], A[k], F, CA[k],
                                    slows and t[k] < self.held,
                                    np.stack([Jt[k + i] for i in (-1, 0, 1)])))
        return out


class Window:
    """The rows the offset may move (``first`` .. ``last``, both kept inside the rows' ends)
    and those it keeps (``frozen``: the two about the intercept), ``k`` arm joints; the
    programme's columns of the offset in units of ``unit``."""

    def __init__(self, t: np.ndarray, t_i: float, k: int) -> None:
        dt = float(t[1] - t[0])
        k0 = int(np.clip(np.searchsorted(t, t_i, side="right") - 1, 0, len(t) - 2))
        self.dt, self.k, self.k0 = dt, k, k0
        self.unit = dt * dt  # the offset's columns in units of dt^2 (rad or m): its second
        # differences then have weight 1 (at 1 ms steps, third differences 1e9 in rad
        # left HiGHS without a solution)
        self.first = max(4, k0 - max(1, round(STOP_PRE_S / dt)))
        self.last = min(len(t) - 4, k0 + 1 + max(1, round(STOP_POST_S / dt)))
        self.frozen = {k0, k0 + 1}
        self.n = self.last - self.first + 1
        self.s = self.n * k          # the load share
        self.e = self.s + 1          # the third differences' slacks, rows first-2 .. last+1
        self.total = self.e + (self.n + 3) * k

    def col(self, row: int, c: int) -> int | None:
        """The offset's column of ``row``, arm joint ``c`` (None outside the window)."""
        return (row - self.first) * self.k + c if self.first <= row <= self.last else None

    def diff(self, row: int, c: int, weights: tuple[float, ...], start: int) -> list:
        """Columns and weights of a difference of the offset over rows ``start`` .. on."""
        out = []
        for i, w in enumerate(weights):
            col = self.col(start + i, c)
            if col is not None and (start + i) not in self.frozen:
                out.append((col, w * self.unit))
        return out

    def acc(self, row: int, c: int) -> list:
        """The offset's second difference at ``row`` (per s^2)."""
        d2 = self.dt * self.dt
        return self.diff(row, c, (1.0 / d2, -2.0 / d2, 1.0 / d2), row - 1)


def _combine(per_joint: list[list], coef: np.ndarray) -> list:
    """sum_c coef[c] * (the offset's difference of joint c) as one row's columns."""
    out: dict[int, float] = {}
    for c, cols in enumerate(per_joint):
        if coef[c] != 0.0:
            for col, w in cols:
                out[col] = out.get(col, 0.0) + float(coef[c]) * w
    return list(out.items())


def _target_acc(W: Window, x: Instant) -> list[list]:
    """The palm target's second difference at ``x.row`` (each of its 3 axes: columns and
    weights) through the rows' own Jacobians (``x.Jt3``)."""
    d2 = W.dt * W.dt
    out = []
    for axis in range(3):
        cols: dict[int, float] = {}
        for i, w in enumerate((1.0 / d2, -2.0 / d2, 1.0 / d2)):
            for c in range(W.k):
                for col, u in W.diff(x.row - 1 + i, c, (w * float(x.Jt3[i, axis, c]),),
                                     x.row - 1 + i):
                    cols[col] = cols.get(col, 0.0) + u
        out.append(list(cols.items()))
    return out


def _merge(*parts: tuple[float, list]) -> list:
    """sum of coef x columns over ``parts`` ((coef, columns) pairs) as one row's columns."""
    out: dict[int, float] = {}
    for coef, cols in parts:
        if coef != 0.0:
            for col, w in cols:
                out[col] = out.get(col, 0.0) + coef * w
    return list(out.items())


def _instant_rows(ub: SparseRows, W: Window, inst: list[Instant], cap: np.ndarray, m: float
                  ) -> None:
    """The motors within ``s`` of their capacity and the ball's force in the cone (or the
    palm target slower than g where the rows' force leaves the cone unjudged); ``m``: the
    ball's mass (kg)."""
    mu = PALM_MU / math.sqrt(2.0)  # the pyramid inscribed in the cone
    for x in inst:
        acc = [W.acc(x.row, c) for c in range(W.k)]
        ta = _target_acc(W, x)
        for r in range(len(cap)):
            cols = _merge((1.0, _combine(acc, x.S[r])),
                          *((m * float(x.SJ[r, d]), ta[d]) for d in range(3)))
            ub.add(cols + [(W.s, -float(cap[r]))], -float(x.tau[r]))
            ub.add([(c, -v) for c, v in cols] + [(W.s, -float(cap[r]))], float(x.tau[r]))
        fn = float(x.F @ x.n)
        out_of_cone = any(abs(float(x.F @ tg)) > mu * fn for tg in cone_tangents(x.n))
        if x.cone or not out_of_cone:
            for tg in cone_tangents(x.n):
                for sg in (1.0, -1.0):
                    d = sg * tg - mu * x.n
                    f0 = float(d @ x.F)  # (<= 0 inside the face; kept at least
                    # CONE_MARGIN_N inside, or as far inside as the rows are)
                    ub.add(_merge(*((m * float(d[e]), ta[e]) for e in range(3))),
                           -f0 - min(CONE_MARGIN_N, max(-f0, 0.0)))
            continue
        a_n = float(np.linalg.norm(x.acc))
        if a_n < 0.5 * G:  # each axis within 0.57 g (sqrt 3 x 0.57 < 1: within g)
            for e in range(3):
                ub.both(ta[e], float(x.acc[e]), 0.57 * G)
            continue
        u = x.acc / a_n
        w1, w2 = cone_tangents(u)
        ub.add(_merge(*((float(u[e]), ta[e]) for e in range(3))), 0.95 * G - float(u @ x.acc))
        for w in (w1, w2):  # (0.95^2 + 2 x 0.15^2 < 1: within g)
            ub.both(_merge(*((float(w[e]), ta[e]) for e in range(3))), 0.0, 0.15 * G)


def _limit_rows(ub: SparseRows, W: Window, hand, arm: list[int], Q: np.ndarray) -> list:
    """Each arm joint's row speed, acceleration and third difference within the hand file's
    limits times ``LIMIT_MARGIN`` (or no worse than the rows' own), the slacks of the third differences, and the
    bounds: positions within the planned range and the trust region, the frozen rows."""
    dt = W.dt
    _, A = row_rates(np.arange(len(Q)) * dt, Q)
    bounds: list = [(None, None)] * W.total
    for c, j in enumerate(arm):
        trust = TRUST_M if hand.joint_names[j] in hand.rig_joints else TRUST_RAD
        for row in range(W.first, W.last + 1):
            lo = max(-trust, float(hand.plan_lower[j] - Q[row, j]))
            hi = min(trust, float(hand.plan_upper[j] - Q[row, j]))
            bounds[W.col(row, c)] = (0.0, 0.0) if row in W.frozen else (
                min(lo, 0.0) / W.unit, max(hi, 0.0) / W.unit)
        vel, acc, jerk = (LIMIT_MARGIN * float(x[j])
                          for x in (hand.velocity, hand.acceleration, hand.jerk))
        for row in range(W.first - 1, W.last + 2):
            v_seg = float(Q[row + 1, j] - Q[row, j]) / dt  # (the last guard's speed: rows'
            # first differences, ``planner.guard``; the check's central ones lie between)
            ub.both(W.diff(row, c, (-1.0 / dt, 1.0 / dt), row), v_seg, max(vel, abs(v_seg)))
            ub.both(W.acc(row, c), float(A[row, j]), max(acc, abs(float(A[row, j]))))
        for i, row in enumerate(range(W.first - 2, W.last + 2)):
            d3 = dt ** 3
            cols = W.diff(row, c, (-1.0 / d3, 3.0 / d3, -3.0 / d3, 1.0 / d3), row - 1)
            j_row = float(Q[row + 2, j] - 3 * Q[row + 1, j] + 3 * Q[row, j] - Q[row - 1, j]) / d3
            if math.isfinite(jerk) and jerk > 0:
                ub.both(cols, j_row, max(jerk, abs(j_row)))
                e = W.e + i * W.k + c
                ub.add([(col, v / jerk) for col, v in cols] + [(e, -1.0)], 0.0)
                ub.add([(col, -v / jerk) for col, v in cols] + [(e, -1.0)], 0.0)
                bounds[e] = (0.0, None)
            else:
                bounds[W.e + i * W.k + c] = (0.0, 0.0)
    bounds[W.s] = (0.0, None)
    return bounds


def solve_offset(model: RowStopModel, t: np.ndarray, Q: np.ndarray
                 ) -> tuple[np.ndarray | None, float, str]:
    """One round: the offset (rows x joints, zero outside the arm's window) that least loads
    the most loaded motor in the linearised rule, the programme's share, and why it failed
    ('' when it solved)."""
    if len(t) < 8:
        return None, math.inf, "too few rows after the touch"
    W = Window(t, model.t_i, len(model.arm))
    if W.last <= W.k0 + 2:
        return None, math.inf, "too few rows after the touch"
    inst = model.instants(t, Q, W.last + 1)
    cap = model.cap
    ub = SparseRows()
    _instant_rows(ub, W, inst, cap, float(model.ball["mass"]))
    bounds = _limit_rows(ub, W, model.kin.hand, model.arm, Q)
    c = np.zeros(W.total)
    c[W.s] = 1.0
    c[W.e:] = SMOOTH_WEIGHT
    A = ub.matrix(W.total)
    if not (np.isfinite(A.data).all() and np.isfinite(ub.rhs).all()):
        return None, math.inf, "the rows' linearisation is not finite"
    res = linprog(c, A_ub=A, b_ub=np.array(ub.rhs), bounds=bounds, method="highs")
    if res.status != 0:
        return None, math.inf, f"the programme: {res.message}"
    dq = np.zeros_like(Q)
    dq[W.first:W.last + 1, model.arm] = W.unit * res.x[:W.s].reshape(W.n, W.k)
    return dq, float(res.x[W.s]), ""


def check_stop(model: RowStopModel, t: np.ndarray, Q: np.ndarray):
    """The check's own worst stopping instant on the rows (``ball_load_instants``)."""
    kin, b = model.kin, model.ball
    _, palm = kin.frames(Q)
    inst = ball_load_instants(t, Q, kin, palm, b, model.t_i, kin.hand.pad_give_m,
                              None if math.isinf(model.held) else model.held)
    return phase_loads(inst, t[-1], kin, Q[-1], palm[-1], b["mass"])[0]


def optimise_stop(model: RowStopModel, t: np.ndarray, Q: np.ndarray) -> RowStop:
    """``ROUNDS`` rounds of ``solve_offset`` from the rows ``Q`` (fewer once its share has
    settled, ``SETTLED``), each judged by the check's rule; the rows of the best (the least worst share, its cone kept) that improves on
    ``Q``'s."""
    best_stop = check_stop(model, t, Q)
    best_Q, share, failure = None, math.inf, ""
    cur = Q
    for _ in range(ROUNDS):
        dq, share_r, why = solve_offset(model, t, cur)
        if dq is None:
            failure = why
            break
        settled = abs(share_r - share) < SETTLED
        share = share_r
        cur = cur + dq
        stop = check_stop(model, t, cur)
        cone_ok = stop.cone_margin_n is None or stop.cone_margin_n >= 0
        if cone_ok and stop.headroom > best_stop.headroom:
            best_Q, best_stop = cur, stop
        if settled:
            break
    return RowStop(best_Q, best_stop, share, failure)


def ball_of(flight) -> dict:
    """The check's ball (``ball_load_instants``' dict) of ``flight``."""
    b = flight.to_metadata()
    return {"p0": np.asarray(b["p0"], dtype=float), "v0": np.asarray(b["v0"], dtype=float),
            "radius": float(b["radius"]), "mass": float(b["mass"]), "drag": float(b["drag"])}

