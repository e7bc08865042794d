"""Per-joint ramps of the soft stop (``planner.catch.plan.softstop``): each arm joint ramps
between rest and its speed in its own time, so that a joint with a short range (the rig's
reach axis: 0.25 m) ramps quickly while the joint whose motor the stop loads most (the
wrist flexion) ramps slowly.

With one ramp time for every joint (``StopDynamics.ramp_time``) the slowest joint's sets
it, and a quick joint travels as far as that time asks: on the steep throws the reach's
ramp-in towards the ball needs more room than the reach has above the intercept, and the
profile then slows every joint (docs/history/2026-12-07-catch-finer.md, "Why the reach
cannot meet the steep ball lower on its travel").

The rule (``joint_ramps``): the ramps end together (the ramp-in, at one row before the
intercept) or start together (the ramp-out, after the hold), each a min-jerk rise of its
speed (peak acceleration ``PEAK_VEL`` |qd_j| / T_j at its middle). Every joint within its
acceleration limit; every motor within ``share`` of its capacity at every instant of the
overlapping ramps (its torque: gravity and the speeds' terms at full speed, as
``ramp_time``'s, plus the sum over the joints of their accelerations' inertia, sampled in
time: peaks that do not coincide are not added); a joint whose travel over the common
ramp would leave its range (``room``) ramps in the longest time its range allows, the
others in the shortest common time the motors then allow.
"""

from __future__ import annotations

import math
from dataclasses import replace
from enum import Enum

import numpy as np

from planner.catch.grasp import motor_torque_matrix
from planner.catch.plan.softstop import SoftStop
from planner.trajectory import MIN_PHASE_S, PEAK_VEL


class JointRamps(Enum):
    """How the soft stop's arm joints ramp and recoil (``planner.catch.plan.stopping``)."""

    NONE = "one"  # one ramp time and one contact share for every joint (every plan's)
    EACH = "each"  # each joint's ramps in its own time; every joint recoils
    LOADED = "loaded"  # ... only the joints whose own motor the pad loads beyond the
    # stop's share recoil


RAMP_SAMPLES = 161  # instants per ramp (its longest) at which the motors are judged: the
# min-jerk acceleration 30 u^2 (1 - u)^2 varies by < 0.1 % of its peak between samples
# 1/160 apart near the peak (and each joint's own peak, u = 1/2, is sampled exactly)
_BISECT = 40  # bisection steps of the common time (to 1e-12 of the bracket)
_T_MAX_S = 10.0  # no ramp is searched longer than this (a stop lasts well under 1 s)


def min_jerk_acc(u: np.ndarray) -> np.ndarray:
    """The min-jerk rise's acceleration per unit speed change and unit time at phase ``u``
    (0 outside [0, 1]): 30 u^2 (1 - u)^2, its peak ``PEAK_VEL`` at u = 1/2."""
    w = np.clip(u, 0.0, 1.0)
    return 30.0 * w * w * (1.0 - w) ** 2


class RampLoads:
    """The motors' load of the arm's ramps at one pose: every motor's torque at full speed
    (gravity and the speeds' terms) and per unit acceleration of each joint's ramp."""

    def __init__(self, dyn, q: np.ndarray, qd: np.ndarray, load: np.ndarray | None,
                 share: float, sign: float) -> None:
        M = motor_torque_matrix(dyn.hand, q)
        z = np.zeros_like(qd)
        self.base = M @ dyn.joint_torques(q, qd, z)
        g = dyn.joint_torques(q, z, z)
        cols = []
        for j in range(len(qd)):
            a = np.zeros_like(qd)
            a[j] = sign * qd[j]  # speeding up (+1) or slowing down (-1)
            tau = dyn.joint_torques(q, z, a) - g
            if load is not None:
                tau = tau + load @ a
            cols.append(M @ tau)
        self.per = np.column_stack(cols)  # (motors, k): torque per unit of the ramp's
        # acceleration (a_j = sign qd_j x the rise's acceleration per unit time)
        self.limit = share * dyn.cap
        self.need = np.any(np.abs(self.per) > 1e-12, axis=1)
        self.qd = qd

    def peak_ratio(self, T: np.ndarray) -> float:
        """The worst |torque| / (share x capacity) of the motors the ramps load, over the
        ramps of durations ``T`` started together (ended together: the mirror, the same)."""
        moving = np.abs(self.qd) > 0
        if not np.any(self.need):
            return 0.0
        t_end = float(np.max(T[moving]))
        t = np.union1d(np.linspace(0.0, t_end, RAMP_SAMPLES), 0.5 * T[moving])
        acc = np.zeros((len(t), len(T)))
        for j in np.flatnonzero(moving):
            acc[:, j] = min_jerk_acc(t / T[j]) / T[j]
        tau = self.base[self.need][None, :] + acc @ self.per[self.need].T
        return float(np.max(np.abs(tau) / self.limit[self.need]))


def joint_ramps(dyn, q: np.ndarray, qd: np.ndarray, room: np.ndarray, lead,
                common_s: float, share: float, load: np.ndarray | None = None,
                sign: float = 1.0) -> np.ndarray | None:
    """Every arm joint's ramp time (s) between rest and ``qd`` at the pose ``q`` (module
    docstring), or None where the common ramp ``common_s`` is as good (no joint would leave
    its range with it) or no per-joint ramps keep the motors within ``share`` of their
    capacity. ``room``: each joint's room (>= 0) in the direction it travels over the
    ramp; ``lead``: the time-like travel (s, at speed qd; one, or every joint's) beside the
    ramp's own half (the ramp-in's row before the intercept, the ramp-out's recoil and
    hold): a joint travels |qd_j| (lead + T_j / 2). ``load``: (n, k) extra joint torque per
    unit arm acceleration (the riding ball); ``sign``: +1 the ramp from rest to ``qd`` (its
    acceleration along qd), -1 the ramp from ``qd`` to rest."""
    if not math.isfinite(common_s) or not np.any(qd):
        return None
    moving = np.abs(qd) > 0
    speed = np.where(moving, np.abs(qd), 1.0)
    t_fit = np.where(moving, 2.0 * (room / speed - lead), math.inf)  # longest within range
    if np.all(t_fit >= common_s):
        return None
    t_acc = np.maximum(MIN_PHASE_S, PEAK_VEL * np.abs(qd) / dyn.a_max)  # shortest by the
    # acceleration limit
    cap = np.maximum(t_acc, t_fit)  # the range-bound joints' ramps (no shorter than their
    # acceleration allows: there the profile is slowed by the caller)
    loads = RampLoads(dyn, q, qd, load, share, sign)

    def ramps(t_common: float) -> np.ndarray:
        return np.where(moving, np.maximum(t_acc, np.minimum(cap, t_common)), 0.0)

    lo, hi = float(np.min(t_acc)), _T_MAX_S
    if loads.peak_ratio(ramps(hi)) > 1.0:
        return None
    for _ in range(_BISECT):
        mid = 0.5 * (lo + hi)
        if loads.peak_ratio(ramps(mid)) <= 1.0:
            hi = mid
        else:
            lo = mid
    return ramps(hi)


def recoil_shares(dyn, q: np.ndarray, qd_c: np.ndarray, ratio: np.ndarray, share: float,
                  recoil_s: float, loaded_only: bool, stop_share: float) -> np.ndarray:
    """Per-joint contact shares of the recoil (``stopping.StopAsk.per_joint``): every arm
    joint (or, ``loaded_only``, those whose own motor the pad loads beyond ``stop_share``
    of its capacity, ``stopping.STOP_SHARE``; ``ratio``: every motor's, ``pad_load``) meets
    the ball at ``share`` of its speed and recoils with it, each within its acceleration limit over ``recoil_s``
    ((1 / c_j - 1) |qd_c,j| <= a_max,j recoil_s: a joint with a low limit, the reach, meets
    it nearer its full speed); the others at their full speed (a recoil adds the palm's
    acceleration to the pad's force: along the palm it may leave the friction cone, and
    only the loaded motor's own joint relieves it)."""
    c = np.maximum(share, np.abs(qd_c) / (np.abs(qd_c) + dyn.a_max * recoil_s))
    if not loaded_only:
        return c
    M = np.abs(motor_torque_matrix(dyn.hand, q)[:, list(dyn.arm)])
    own = np.argmax(M, axis=0)  # each arm joint's own motor
    return np.where(ratio[own] > stop_share, c, 1.0)


def with_joint_ramps(dyn, stop: SoftStop, q_open: np.ndarray, load: np.ndarray,
                     share: float) -> SoftStop:
    """``stop`` with each arm joint's ramp-in and ramp-out in its own time (``joint_ramps``,
    every motor within ``share`` of its capacity) where one common time would take a joint
    out of its range; ``load``: the riding ball's (the ramp-out's)."""
    arm = list(dyn.arm)
    q, lo, hi = q_open[arm], dyn.hand.lower[arm], dyn.hand.upper[arm]
    qd_c, c = stop.qd_c, stop.joint_ramps()[2]
    # the ramp-in travels against the contact speeds (to its start), the ramp-out with them
    room_in = np.maximum(np.where(qd_c > 0, q - lo, hi - q), 0.0)
    room_out = np.maximum(np.where(stop.qd > 0, hi - q, q - lo), 0.0)
    rin = joint_ramps(dyn, q_open, qd_c, room_in, stop.row_s, stop.ramp_in_s, share)
    lead_out = 0.5 * stop.recoil_s * (1.0 + c) + stop.hold_s  # sigma at the ramp-out's start
    # (every joint's)
    rout = joint_ramps(dyn, q_open, stop.qd, room_out, lead_out, stop.ramp_out_s, share,
                       load, sign=-1.0)
    if rin is None and rout is None and stop.shares is None:
        return stop
    k = len(arm)
    rin = np.full(k, stop.ramp_in_s) if rin is None else rin
    rout = np.full(k, stop.ramp_out_s) if rout is None else rout
    return replace(stop, ramp_in_s=float(np.max(rin)), ramp_out_s=float(np.max(rout)),
                   ramps_in_s=rin, ramps_out_s=rout)
