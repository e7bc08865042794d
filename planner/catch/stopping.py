"""The soft catch: the palm meets the ball already moving along its path, then brings it
to rest (``planner.catch.plan``, step 3).

The arm (rail, wrist flexion and deviation) follows one profile through the intercept
pose q_i: q(t) = q_i + qd_c sigma(t), sigma a time-like scalar: at rest, a min-jerk rise
of its speed from 0 to 1 (``ramp_in_s``), speed 1 (the joints at ``qd_c``) from one row
before the intercept until one row after the pad has stopped the ball
(``planner.check.ballstop``: 2 d / |v_rel|), a min-jerk fall to rest (``ramp_out_s``).

What is chosen, by optimisation:

* ``qd_c``, the arm's speeds when the palm meets the ball: a QP (OSQP, ``planner.qp``)
  minimising |v_ball - J qd|^2 (J the palm target's Jacobian over the arm joints), i.e.
  the ball's speed relative to the palm and with it the pad's force (its square), within
  every arm joint's speed limit and the speeds the ramps can reach in the time there is
  and within the joints' range;
* the ramps' durations: the shortest whose peak acceleration keeps every joint within its
  acceleration limit and every motor within ``STOP_SHARE`` of its capacity while it moves
  the hand's own inertia (and, ramping out, the ball riding on the palm) against gravity;
* the palm's tilt (``find_intercept(..., tilt)``): among ``TILTS_DEG`` the pose whose
  stopping needs the least of the motor closest to its capacity (its force's lever about
  the wrist changes with the tilt) and whose pad force stays in the palm's friction cone.

The rows' dynamics are then judged by the check's own rule (``planner.check.ball``); a
ball that no such motion stops within every motor's capacity is "too fast to stop".
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from planner.catch.arm import CatchJoints, open_from, palm_target
from planner.catch.flight import Flight
from planner.catch.grasp import motor_torque_matrix, palm_jacobian
from planner.catch.intercept import Intercept, Wrist, find_intercept
from planner.catch.results import Closing
from planner.check.ballstop import cone_margin_n, pad_force_n, pad_time_s
from planner.hand.model import HandModel
from planner.hand.tendon import actuator_capacity
from planner.qp import DenseQp
from planner.trajectory import LIMIT_MARGIN, MIN_PHASE_S, PEAK_ACC, PEAK_VEL

STOP_SHARE = 0.8  # the ramps load every motor to at most 80 % of its capacity: issue 15's
# 20 % headroom, left for what the model does not see (friction, the fingers' moves)
TILTS_DEG = (0.0, -5.0, -10.0, 5.0, 10.0)  # palm tilts tried (deg about the flexion axis)
_SHRINK = 0.85  # a profile that leaves the joints' range is tried with speeds this much lower
_MAX_SHRINK = 12
_FD_M = 1e-6  # finite-difference step of the palm target's Jacobian (rad or m)
_QP = DenseQp(eps_abs=1e-9, eps_rel=1e-9, max_iter=4000, polishing=True)


def ramp_integral(u: np.ndarray) -> np.ndarray:
    """The integral over [0, u] of the min-jerk rise (10 s^3 - 15 s^4 + 6 s^5), u clipped to
    [0, 1]: 2.5 u^4 - 3 u^5 + u^6 (1/2 at u = 1)."""
    u = np.clip(u, 0.0, 1.0)
    return u ** 4 * (2.5 - 3.0 * u + u * u)


@dataclass(frozen=True)
class SoftStop:
    """The arm's stopping motion of one catch (see the module docstring)."""

    tilt_rad: float
    arm: tuple[int, ...]  # the arm joints' indices (hand order)
    qd_c: np.ndarray  # their speeds when the palm meets the ball
    t_i: float
    row_s: float  # one row interval: the speed is held this long on either side
    ramp_in_s: float
    pad_s: float
    ramp_out_s: float
    v_palm: np.ndarray  # palm target velocity at the intercept (m/s)
    v_rel: np.ndarray  # the ball's velocity relative to it (m/s)
    force_n: np.ndarray  # the pad's force on the ball (N)
    motor_ratio: np.ndarray  # |torque| / capacity of every motor while the pad stops it
    cone_margin_n: float

    @property
    def start_s(self) -> float:
        """When the arm starts its ramp (it holds its pre-catch pose until then)."""
        return self.t_i - self.row_s - self.ramp_in_s

    @property
    def end_s(self) -> float:
        """When the arm is at rest with the ball."""
        return self.t_i + self.pad_s + self.row_s + self.ramp_out_s

    def sigma(self, t_s: np.ndarray) -> np.ndarray:
        """The profile's time-like scalar at ``t_s`` (0 at the intercept)."""
        t = np.asarray(t_s, dtype=float)
        a, b = self.t_i - self.row_s, self.t_i + self.pad_s + self.row_s
        s0 = -(0.5 * self.ramp_in_s + self.row_s)
        out = np.clip(t, a, b) - self.t_i
        if self.ramp_in_s > 0:
            rise = s0 + self.ramp_in_s * ramp_integral((t - self.start_s) / self.ramp_in_s)
            out = np.where(t < a, rise, out)
        if self.ramp_out_s > 0:
            u = np.clip((t - b) / self.ramp_out_s, 0.0, 1.0)
            fall = (b - self.t_i) + self.ramp_out_s * (u - ramp_integral(u))
            out = np.where(t > b, fall, out)
        return out

    def offset(self, t_s: np.ndarray, n: int) -> np.ndarray:
        """(T, n) joint offsets from the intercept pose (only the arm joints move)."""
        out = np.zeros((len(np.atleast_1d(t_s)), n))
        out[:, list(self.arm)] = np.outer(self.sigma(np.atleast_1d(t_s)), self.qd_c)
        return out

    @property
    def first_offset(self) -> np.ndarray:
        return self.qd_c * -(0.5 * self.ramp_in_s + self.row_s)

    @property
    def last_offset(self) -> np.ndarray:
        return self.qd_c * (self.pad_s + self.row_s + 0.5 * self.ramp_out_s)


class StopDynamics:
    """The hand's dynamics the stopping motion needs (one hand, reference-mounted)."""

    def __init__(self, hand: HandModel, joints: CatchJoints) -> None:
        self.hand, self.joints = hand, joints
        self.arm = tuple(joints.arm)
        m = hand.pin_model
        self._idx = np.array([m.idx_qs[m.getJointId(n)] for n in hand.joint_names])
        self._data = m.createData()
        self.cap = actuator_capacity(hand).torque_nm
        self.v_max = LIMIT_MARGIN * hand.velocity[list(self.arm)]
        self.a_max = LIMIT_MARGIN * hand.acceleration[list(self.arm)]

    def _pq(self, q: np.ndarray) -> np.ndarray:
        qp = np.zeros(self.hand.pin_model.nq)
        qp[self._idx] = q
        return qp

    def target_jacobian(self, q: np.ndarray, r: float) -> np.ndarray:
        """(3, k) palm target (palm_center + r n) per unit arm joint motion."""
        h, p0 = self.hand, palm_target(self.hand, q, r)
        J = np.empty((3, len(self.arm)))
        for c, i in enumerate(self.arm):
            dq = q.copy()
            dq[i] += _FD_M
            J[:, c] = (palm_target(h, dq, r) - p0) / _FD_M
        return J

    def joint_torques(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """RNEA (gravity included) at arm speeds/accelerations ``v``, ``a``."""
        m = self.hand.pin_model
        vp, ap = np.zeros(m.nv), np.zeros(m.nv)
        vp[self._idx[list(self.arm)]], ap[self._idx[list(self.arm)]] = v, a
        return pin.rnea(m, self._data, self._pq(q), vp, ap)[self._idx]

    def ramp_time(self, q: np.ndarray, qd: np.ndarray, load: np.ndarray | None = None) -> float:
        """Shortest min-jerk speed ramp between rest and ``qd`` (peak acceleration PEAK_ACC
        / T times qd ... here 15/8 qd / T) within the acceleration limits and every motor
        within ``STOP_SHARE`` of its capacity; ``load``: (n, k) extra joint torque per unit
        arm acceleration (the riding ball). inf when gravity and speed alone leave no room."""
        if not np.any(qd):
            return 0.0
        M = motor_torque_matrix(self.hand, q)
        z = np.zeros_like(qd)
        base = M @ self.joint_torques(q, qd, z)
        per = M @ (self.joint_torques(q, z, qd) - self.joint_torques(q, z, z)
                   + (load @ qd if load is not None else 0.0))
        room = STOP_SHARE * self.cap - np.abs(base)
        need = np.abs(per) > 1e-12
        if np.any(room[need] <= 0):
            return math.inf
        s_max = min(float(np.min(room[need] / np.abs(per[need]))) if need.any() else math.inf,
                    float(np.min(self.a_max / np.maximum(np.abs(qd), 1e-12))))
        return max(MIN_PHASE_S, PEAK_VEL / s_max)

    def pad_load(self, q: np.ndarray, qd: np.ndarray, v_rel: np.ndarray, mass: float,
                 normal: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        """The pad's force on the ball, every motor's |torque| / capacity while it acts (the
        hand at speed ``qd``, not accelerating), and its friction-cone margin."""
        F = pad_force_n(mass, v_rel)
        tau = self.joint_torques(q, qd, np.zeros_like(qd)) + palm_jacobian(self.hand, q).T @ F
        M = motor_torque_matrix(self.hand, q)
        return F, np.abs(M @ tau) / self.cap, cone_margin_n(F, normal)


def _contact_speeds(J: np.ndarray, v_ball: np.ndarray, bound: np.ndarray) -> np.ndarray:
    """The QP: min |v_ball - J x|^2 + 1e-6 |x|^2, -bound <= x <= bound."""
    k = J.shape[1]
    P = 2.0 * (J.T @ J + 1e-6 * np.eye(k))
    c = -2.0 * J.T @ v_ball
    res = _QP.solve(P, c, np.eye(k), -bound, bound)
    if not res.solved:
        return np.zeros(k)
    return np.clip(res.x, -bound, bound)


def plan_stop(dyn: StopDynamics, wrist: Wrist, flight: Flight, C: np.ndarray, r: float,
              q_zero: np.ndarray, closing: Closing, t_c: float, ready_by, row_s: float,
              soft: bool = True) -> tuple[Intercept, np.ndarray, SoftStop]:
    """The intercept, its open pose and the stopping motion (module docstring). ``ready_by``:
    a function of the pre-catch pose -> when the hand can be there. ``soft`` False: the palm
    waits at rest (the stopping is the pad's alone)."""
    best = None
    for tilt in (TILTS_DEG if soft else (0.0,)):
        ic = find_intercept(wrist, flight, C, r, t_c, math.radians(tilt))
        if ic.reason is not None or (tilt != 0.0 and not ic.aligned):
            continue
        cand = _candidate(dyn, flight, C, r, q_zero, closing, ic, ready_by, row_s, soft,
                          math.radians(tilt))
        key = (cand[2].cone_margin_n < 0, float(cand[2].motor_ratio.max()))
        if best is None or key < best[0]:
            best = (key, cand)
    if best is None:  # no tilt reaches: the untilted intercept says why
        ic = find_intercept(wrist, flight, C, r, t_c)
        return _candidate(dyn, flight, C, r, q_zero, closing, ic, ready_by, row_s, False, 0.0)
    return best[1]


def _candidate(dyn: StopDynamics, flight: Flight, C: np.ndarray, r: float, q_zero: np.ndarray,
               closing: Closing, ic: Intercept, ready_by, row_s: float, soft: bool,
               tilt_rad: float):
    h, j = dyn.hand, dyn.joints
    q = q_zero.copy()
    q[j.i_flex], q[j.i_dev] = ic.theta, ic.dev
    if j.i_rail is not None:
        q[j.i_rail] = ic.rail
    q_open = open_from(h, j, q, closing.q_closed)
    v_ball = flight.velocity(ic.t)
    mass = float(flight.ball.mass_kg)
    normal = h.palm_pose(q_open)[:3, 2]
    J = dyn.target_jacobian(q_open, r)
    arm = list(dyn.arm)
    bound = dyn.v_max.copy() if soft else np.zeros(len(arm))
    ride = mass * J.T @ J  # joint torque per unit arm acceleration of the riding ball
    stop = None
    for _ in range(_MAX_SHRINK + 1):
        qd = _contact_speeds(J, v_ball, bound) if np.any(bound) else np.zeros(len(arm))
        v_rel = v_ball - J @ qd
        F, ratio, cone = dyn.pad_load(q_open, qd, v_rel, mass, normal)
        t_in = dyn.ramp_time(q_open, qd)
        load = np.zeros((h.n, len(arm)))
        load[arm] = ride
        t_out = dyn.ramp_time(q_open, qd, load)
        stop = SoftStop(tilt_rad, tuple(arm), qd, float(ic.t), row_s if np.any(qd) else 0.0,
                        t_in, pad_time_s(v_rel) if np.any(qd) else 0.0, t_out, J @ qd, v_rel,
                        F, ratio, cone)
        if not np.any(qd):
            break
        lo, hi = h.lower[arm], h.upper[arm]
        out = np.zeros(len(arm), dtype=bool)
        for e in (q_open[arm] + stop.first_offset, q_open[arm] + stop.last_offset):
            out |= (e < lo) | (e > hi)
        pre = q_open.copy()
        pre[arm] += stop.first_offset
        timely = math.isfinite(t_in) and math.isfinite(t_out) and ready_by(pre) <= stop.start_s
        if timely and not out.any():
            break
        # the joints that leave their range slow down (all of them when time is short)
        bound = np.where(out | (not timely), _SHRINK * np.abs(qd), bound)
        stop = None
    if stop is None:  # no moving profile fits: the palm waits at rest
        return _candidate(dyn, flight, C, r, q_zero, closing, ic, ready_by, row_s, False, tilt_rad)
    return ic, q_open, stop
