"""A move's time profile within the tendons' capacity, with the hand's inertia.

``check`` finds a row's tendon tensions (``planner.check.limits``) from its motor
torques: gravity and the keys pushing back on the pressing fingertips (``KEY_FORCE_N``),
plus the torques that move the hand as its rows do (``Kinematics.inertial``:
RNEA(q, v, a) - RNEA(q, 0, 0)), through the transmissions (``motor_torque_matrix``),
at the spool (``planner.hand.tendon``: a tendon motor's torque within its design force
times its spool radius, and its peak torque: ``actuator_capacity``). Those definitions
are imported here, not copied.

A move (``planner.play.profile``) runs along ``q(s) = couplings(q_a + s dq)``; with the
path's speed ``s'`` and acceleration ``s''`` the joints move at ``v = q_s s'`` and
``a = q_s s'' + q_ss s'^2``. RNEA is linear in the accelerations and quadratic in the
speeds, so at each point of the path the motor torques are exactly

    tau_static(q) + K(q) s'' + C(q) s'^2,   K = inertial(q, 0, q_s),  C = inertial(q, q_s, q_ss).

The rows' differences along a straight line are averages of ``s'`` and ``s''``
(``profile``'s docstring): every row has ``|s''| <= A``, the profile's peak acceleration,
and ``s'^2 <= W(s) = min(V^2, 2 A min(s, 1 - s))``, its peak speed, or what an
acceleration within ``A`` reaches from rest over ``s`` or stops within over ``1 - s``
(``v dv/ds = s''``); at a sample, ``s`` the next sample's towards the move's middle
(a row's average speed reaches a row's width along the path, less than a sample's
spacing where the move is slow: 18 ms or more for its last twelfth). So a motor's torque
on the move is at most ``|K| A + max(|tau_static|, |tau_static + C W|)``, ``tau_static`` with and without
the key's push where the finger may be pressing: as ``check`` says, where its pad point is
``DOWN_DEPTH_M`` below its key's top, and at the samples beside those (the rows between). Played ``sigma`` times slower (every
phase of the double S times ``sigma``: still within every speed, acceleration and jerk
bound) the move has ``A / sigma^2`` and ``V^2 / sigma^2``; ``time_scale`` is the
smallest ``sigma >= 1`` that keeps every tendon motor within ``TENDON_SHARE`` of its
capacity at ``PATH_SAMPLES`` points of the path, exactly 1 (the same move, the same
floats) for a move already within it. The bound is the move's own: its configurations,
its direction, its load, its profile.
"""

from __future__ import annotations

import math
from functools import cache

import numpy as np

from planner.check.criteria import DOWN_DEPTH_M
from planner.check.kinematics import Kinematics
from planner.check.limits import KEY_FORCE_N
from planner.check.motormap import motor_torque_matrix
from planner.hand.model import HandModel
from planner.hand.tendon import actuator_capacity, tendon_motors
from planner.play.atlas import PATH_SAMPLES
from planner.play.profile import Move
from planner.play.tendonproof import TendonProof

TENDON_SHARE = 0.95  # a move's own bound keeps each tendon motor within 95 % of its
# capacity: the rest for what that bound leaves out, the rail accelerating while a finger
# crosses at height (its reaction on a finger's tendon: 1.4 N of 40 N, 3.6 %, at the default
# rail's 23 m/s^2, measured in docs/history/2026-12-06-tendon.md) and the load between the
# bound's samples
MAX_SCALE = 1.5  # a move is slowed at most this much (to 44 % of its inertial load): a
# sample that needs more has a static load next to its motor's capacity, which no timing
# lowers (the atlas bounds the press poses' static forces, planner.play.atlas; the Mk5's
# pinky passes 95 % with the key's push on its way from the press to the repeat pose, and
# would be slowed 15-fold for it)
_STEP = 1e-4  # the path parameter's step for the path's tangent and curvature (central
# differences of the couplings: exact for linear laws, within 1e-8 for the Mk5's)


@cache
def tendon_load(hand: HandModel) -> TendonLoad:
    """The hand's ``TendonLoad`` (one per hand object: every posture's moves share it)."""
    return TendonLoad(hand)


@cache
def hand_load(hand: HandModel) -> TendonLoad:
    """The bound on every motor of the hand (``TendonLoad`` with ``every_motor``): for a
    move of several joint groups at once (the arm with the fingers that follow it), whose
    reactions add up on the motors they share, the wrist's and the arm's."""
    return TendonLoad(hand, every_motor=True)


class TendonLoad:
    """The tendon bound of one hand's moves (``time_scale``); with ``every_motor`` the
    bound of every motor (tendon, wrist, arm), each within ``TENDON_SHARE`` of its
    capacity (``actuator_capacity``: the smaller of its peak torque and its tendon's)."""

    def __init__(self, hand: HandModel, every_motor: bool = False) -> None:
        self.hand = hand
        self.kin = Kinematics(hand, hand.T_world_root)
        self.motors = np.arange(hand.n_motor) if every_motor else tendon_motors(hand)
        self.capacity_nm = TENDON_SHARE * actuator_capacity(hand).torque_nm[self.motors]
        self.samples = np.linspace(0.0, 1.0, PATH_SAMPLES)
        # (every coupling and transmission linear: one motor matrix for every pose,
        # ``motor_torque_matrix``'s own test, and the couplings elementwise)
        self.linear = (all(c.kind == "linear" for c in hand.couplings)
                       and all(getattr(a, "mk5", None) is None for a in hand.actuators))
        # (a finger's moves with no key pushing back shown within the share at once where
        # they can be: ``planner.play.tendonproof``)
        self.proof = TendonProof(hand, self.kin, motor_torque_matrix(
            hand, hand.apply_couplings(np.zeros(hand.n)))[self.motors], self.capacity_nm,
            _STEP) if self.linear and not every_motor and self.motors.size else None

    def params(self) -> dict:
        """What the bound depends on besides the hand (for the move table's parameters)."""
        return {"tendon_share": TENDON_SHARE, "key_force_n": KEY_FORCE_N,
                "tendon_step": _STEP}

    def terms(self, q_a: np.ndarray, dq: np.ndarray, pressing: tuple[int, ...] = (),
              key_top_z_m: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The tendon motors' torques along the move from ``q_a`` by ``dq`` (whole-hand
        vectors, couplings applied to every point) at each sample: the static ones
        (samples, 2, motors: gravity alone, and with the keys of fingers ``pressing``
        pushing back: everywhere, or with ``key_top_z_m`` where they may press a key whose
        top is there), ``K`` and ``C`` (samples, motors)."""
        hand, kin, m = self.hand, self.kin, self.motors
        n = len(self.samples)
        static, K, C = np.empty((n, 2, len(m))), np.empty((n, len(m))), np.empty((n, len(m)))
        zero = np.zeros(hand.n)
        Q = hand.apply_couplings(q_a[None, :] + self.samples[:, None] * dq[None, :])
        pushes = self._pushes(Q, pressing, key_top_z_m)
        Q_s, Q_ss = self._tangents(q_a, dq, Q)
        M_lin = motor_torque_matrix(hand, Q[0])[m] if self.linear else None
        for i in range(n):
            q, q_s, q_ss = Q[i], Q_s[i], Q_ss[i]
            M = motor_torque_matrix(hand, q)[m] if M_lin is None else M_lin
            g = kin.gravity(q)
            pushed = g.copy()
            if pushes[i]:
                for J in kin.point_jacobians(q, [kin.tip_ids[f] for f in pressing]):
                    pushed -= J.T @ np.array([0.0, 0.0, KEY_FORCE_N])
            static[i, 0], static[i, 1] = M @ g, M @ pushed
            tau_k, tau_c = kin.inertials(q, ((zero, q_s), (q_s, q_ss)), g)
            K[i], C[i] = M @ tau_k, M @ tau_c
        return static, K, C

    def _tangents(self, q_a: np.ndarray, dq: np.ndarray, Q: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
        """The path's tangent and curvature at each sample (``Q``: the samples' points),
        central differences ``_STEP`` either side. With linear couplings every sample's
        at once (each row's numbers those of the row alone: elementwise operations, and
        ``s -+ _STEP`` and its product by ``dq`` rounded as Python's floats); otherwise
        sample by sample (a law solved iteratively may take as many steps as its
        hardest row)."""
        if self.linear:
            S = self.samples[:, None]
            Q0 = self.hand.apply_couplings(q_a[None, :] + (S - _STEP) * dq[None, :])
            Q1 = self.hand.apply_couplings(q_a[None, :] + (S + _STEP) * dq[None, :])
        else:
            Q0, Q1 = (np.array([self.hand.apply_couplings(q_a + x * dq)
                                for x in (self.samples + h).tolist()]) for h in (-_STEP, _STEP))
        return (Q1 - Q0) / (2.0 * _STEP), (Q1 - 2.0 * Q + Q0) / (_STEP * _STEP)

    def _pushes(self, Q: np.ndarray, pressing: tuple[int, ...], key_top_z_m: float | None
                ) -> np.ndarray:
        """Whether the keys push back at each sample of ``Q``: a pressing finger's pad
        point ``DOWN_DEPTH_M`` below ``key_top_z_m`` there or at a sample beside it
        (every sample without ``key_top_z_m``; none without ``pressing``)."""
        if not pressing or key_top_z_m is None:
            return np.full(len(Q), bool(pressing))
        tips, _ = self.kin.frames(Q)
        down = np.any(key_top_z_m - tips[:, list(pressing), 2] >= DOWN_DEPTH_M, axis=1)
        near = down.copy()
        near[1:] |= down[:-1]
        near[:-1] |= down[1:]
        return near

    def time_scale(self, move: Move, q_a: np.ndarray, dq: np.ndarray,
                   pressing: tuple[int, ...] = (), key_top_z_m: float | None = None) -> float:
        """The smallest ``sigma >= 1`` by which ``move`` (from whole-hand ``q_a`` by
        whole-hand ``dq``) slowed keeps every tendon motor within its share of capacity
        (module docstring); 1.0 when it is already, or when it does not move. A motor
        past its share with the hand still (a static load no timing helps: the atlas's
        press forces bound those) does not slow it, nor more than ``MAX_SCALE``."""
        if move.duration_s == 0.0 or self.motors.size == 0:
            return 1.0
        if not pressing and self.proof is not None and self.proof.proves(
                q_a, dq, move.peak_acceleration, move.peak_speed):
            return 1.0
        static, K, C = self.terms(q_a, dq, pressing, key_top_z_m)
        return scale_for(static, K, C, speed_squared_bound(
            self.samples, move.peak_acceleration, move.peak_speed), move.peak_acceleration,
            self.capacity_nm)


def speed_squared_bound(samples: np.ndarray, peak_acceleration: float, peak_speed: float
                        ) -> np.ndarray:
    """``W`` at each sample of the path (module docstring): the square of the path's
    speed there is at most this."""
    a = np.r_[samples[1:], 1.0]  # (the next sample towards the end, and towards the start)
    b = np.r_[0.0, samples[:-1]]
    return np.minimum(peak_speed * peak_speed,
                      2.0 * peak_acceleration * np.minimum(a, 1.0 - b))


def scale_for(static: np.ndarray, K: np.ndarray, C: np.ndarray, speed2: np.ndarray,
              peak_acceleration: float, capacity_nm: np.ndarray) -> float:
    """``TendonLoad.time_scale`` of terms ``static`` (samples, 2, motors), ``K``, ``C``
    (samples, motors) and the bound on the path's speed squared at each sample
    (``speed_squared_bound``): with ``u = 1 / sigma^2`` each bound is the largest of three
    lines in ``u`` (``|S| + |K| A u``, ``+-(S + C W u) + |K| A u``), each within the
    capacity up to its own ``u``; ``sigma`` from the smallest."""
    ka = np.abs(K)[:, None, :] * peak_acceleration
    cv = C[:, None, :] * speed2[:, None, None]
    # (the three lines' values at u = 0 and slopes as one array each: the same numbers,
    # and the smallest room of all, a minimum being exact in any order)
    h0 = np.stack((np.abs(static), static, -static))
    slope = np.empty(h0.shape)
    slope[0], slope[1], slope[2] = ka, ka + cv, ka - cv
    grows = (slope > 0.0) & (h0 < capacity_nm)  # (a static overload: not the timing's)
    u = 1.0
    if grows.any():
        room = float(np.min((np.broadcast_to(capacity_nm, h0.shape)[grows] - h0[grows])
                            / slope[grows]))
        if not room >= 0.0:  # (not a number: each line on its own, as Python's ``min``
            return _scale_by_line(h0, slope, grows, capacity_nm)  # passes one by)
        u = min(u, room)
    return 1.0 if u >= 1.0 else min(MAX_SCALE, 1.0 / math.sqrt(u))


def _scale_by_line(h0: np.ndarray, slope: np.ndarray, grows: np.ndarray,
                   capacity_nm: np.ndarray) -> float:
    """``scale_for`` line by line (each line's smallest room, then the smallest of
    those, ``min`` passing by a line's that is not a number)."""
    u = 1.0
    for k in range(len(h0)):
        if grows[k].any():
            room = (np.broadcast_to(capacity_nm, h0[k].shape)[grows[k]] - h0[k][grows[k]]) \
                / slope[k][grows[k]]
            u = min(u, float(np.min(room)))
    return 1.0 if u >= 1.0 else min(MAX_SCALE, 1.0 / math.sqrt(u))


def slowed(move: Move, sigma: float) -> Move:
    """``move`` played ``sigma`` times slower (every phase times ``sigma``); the move
    itself when ``sigma`` is 1."""
    if sigma == 1.0:
        return move
    return Move(move.q_a, move.dq, move.duration_s * sigma, move.ta_s * sigma,
                move.tj_s * sigma)
