"""The limit audit of a replay: joint positions, speeds, accelerations, motor speeds,
motor columns against the joints, couplings, static motor torque and the tendons'
tensions (planner.hand.tendon: tension at the spool = motor torque / spool radius,
bounded by the cable's design force); of a play's rows also the joints' jerks (third
differences) and the rows closer to a hard stop than the joint's stop margin
(planner.hand.drive: rows a controller can run)."""

from __future__ import annotations

import numpy as np

from planner.check.kinematics import GRAVITY, Kinematics
from planner.check.results import LimitCheck, TendonLoad
from planner.hand.model import HandModel
from planner.hand.tendon import spool_tensions_n, tendon_motors
from planner.trajfile import Trajectory, distinct_rows

FILE_QUANTUM = 1e-6  # the writer's 6 decimals
POSITION_TOL = 1e-6  # rad or m beyond a joint limit
RATE_TOL = 0.01  # 1 % of a speed / acceleration / torque limit
MOTOR_TOL_RAD = 1e-5  # motor column vs motor_angles(q), plus file rounding
COUPLING_TOL_RAD = 1e-5  # |coupling error|, plus file rounding
KEY_FORCE_N = 0.5  # nominal key reaction on a pressing fingertip


def _worst(category: str, excess: np.ndarray, value: np.ndarray, limit: np.ndarray,
           tol: np.ndarray, names, times: np.ndarray, unit: str) -> LimitCheck:
    """Build a LimitCheck from (R, C) arrays: ``excess`` ranks samples (bigger is
    worse), a sample violates when its ``value`` is beyond ``limit + tol``."""
    if excess.size == 0:
        return LimitCheck(category, 0, 0.0, float(np.max(limit)) if np.size(limit) else 0.0,
                          "", 0.0, unit)
    count = int(np.count_nonzero(~(value <= limit + tol)))  # NaN (inf - inf) is no pass
    r, c = np.unravel_index(int(np.argmax(excess)), excess.shape)
    lim = np.broadcast_to(limit, value.shape)
    return LimitCheck(category, count, float(value[r, c]), float(lim[r, c]), names[c],
                      float(times[r]), unit)


@np.errstate(over="ignore", invalid="ignore")  # absurd values give inf: counted, not printed
def limit_audit(hand: HandModel, kin: Kinematics, tr: Trajectory, pressing_tips: np.ndarray | None,
                ball_load: np.ndarray | None, inertia: bool = False
                ) -> tuple[list[LimitCheck], tuple[TendonLoad, ...]]:
    """The limit checks (one per category) and the worst tension of every tendon; with
    ``inertia`` the motor torques also move the hand as its rows do (a play)."""
    t, Q, QM = tr.t_s, tr.q, tr.q_motor
    out = [_position_check(hand, t, Q), *_rate_checks(hand, t, Q, QM),
           _motor_consistency(hand, t, Q, QM), _coupling_check(hand, t, Q)]
    if inertia:  # (a play: rows for the hand's controller)
        out[1:1] = [stop_margin_check(hand, t, Q)]
        out.append(jerk_check(hand, t, Q))
    tau = _joint_torques(kin, Q, pressing_tips, ball_load)
    if inertia:
        tau += _inertial_torques(kin, t, Q)
    TM = _motor_torques(hand, Q, tau)
    ratio = np.abs(TM) / hand.motor_peak_torque
    out.append(_worst("motor_torque", ratio, np.abs(TM), hand.motor_peak_torque,
                      RATE_TOL * hand.motor_peak_torque, _motor_columns(hand), t, "N m"))
    tendon_check, tendons = _tendon_audit(hand, TM, t)
    out.append(tendon_check)
    return out, tendons


def _motor_columns(hand: HandModel) -> tuple[str, ...]:
    return tuple(f"motor.{m}" for m in hand.motor_names)


def _position_check(hand: HandModel, t: np.ndarray, Q: np.ndarray) -> LimitCheck:
    """Excess beyond the nearer bound (<= 0 inside); infinite bounds never bind."""
    lo = np.where(np.isfinite(hand.lower), hand.lower, -np.inf)
    hi = np.where(np.isfinite(hand.upper), hand.upper, np.inf)
    below, above = lo - Q, Q - hi
    excess = np.maximum(below, above)
    bound = np.where(below > above, lo, hi)
    r, c = np.unravel_index(int(np.argmax(excess)), excess.shape)
    return LimitCheck("joint_position", int(np.count_nonzero(excess > POSITION_TOL)),
                      float(Q[r, c]), float(bound[r, c]), hand.joint_names[c], float(t[r]),
                      "rad|m")


def stop_margin_check(hand: HandModel, t: np.ndarray, Q: np.ndarray) -> LimitCheck:
    """Rows closer to a hard stop than the joint's stop margin (outside the planner's
    limits, ``HandModel.plan_lower``/``plan_upper``), the file's rounding allowed:
    ``worst`` is the least room to a stop (rad or m), ``limit`` that joint's margin."""
    lo = np.where(np.isfinite(hand.lower), hand.lower, -np.inf)
    hi = np.where(np.isfinite(hand.upper), hand.upper, np.inf)
    room = np.minimum(Q - lo, hi - Q)
    short = hand.stop_margin - room  # > 0: inside the margin (or past the stop)
    margin = np.broadcast_to(hand.stop_margin, Q.shape)
    if short.size == 0:
        return LimitCheck("joint_stop_margin", 0, 0.0, 0.0, "", 0.0, "rad|m")
    r, c = np.unravel_index(int(np.argmax(short)), short.shape)
    return LimitCheck("joint_stop_margin", int(np.count_nonzero(short > POSITION_TOL)),
                      float(room[r, c]), float(margin[r, c]), hand.joint_names[c],
                      float(t[r]), "rad|m")


def jerk_check(hand: HandModel, t: np.ndarray, Q: np.ndarray) -> LimitCheck:
    """Joint jerks: differences of the rows' accelerations (second differences, as
    ``joint_acceleration``) over their spacing, i.e. third differences, against each
    joint's jerk bound with ``RATE_TOL`` of it and the file's rounding (8 half quanta
    through the coefficients 1, 3, 3, 1)."""
    if len(t) < 4:
        return LimitCheck("joint_jerk", 0, 0.0, 0.0, "", 0.0, "rad/s^3|m/s^3")
    dt = np.diff(t)
    V = np.diff(Q, axis=0) / dt[:, None]
    A = np.diff(V, axis=0) / (0.5 * (dt[1:] + dt[:-1]))[:, None]  # at t[1:-1]
    J = np.diff(A, axis=0) / np.diff(t[1:-1])[:, None]  # between t[1:-2] and t[2:-1]
    tol = RATE_TOL * hand.jerk + 4 * FILE_QUANTUM / (dt[2:] * dt[1:-1] * dt[:-2])[:, None]
    return _worst("joint_jerk", np.abs(J) / hand.jerk, np.abs(J), hand.jerk, tol,
                  hand.joint_names, t[2:-1], "rad/s^3|m/s^3")


def _rate_checks(hand: HandModel, t: np.ndarray, Q: np.ndarray, QM: np.ndarray
                 ) -> list[LimitCheck]:
    """Joint and motor speeds (row differences), joint accelerations (second
    differences), each with the file's rounding in its tolerance."""
    jn, mn = hand.joint_names, _motor_columns(hand)
    out = []
    dt = np.diff(t)
    if len(t) >= 2:
        V = np.diff(Q, axis=0) / dt[:, None]
        tol = RATE_TOL * hand.velocity + FILE_QUANTUM / dt[:, None]
        out.append(_worst("joint_velocity", np.abs(V) / hand.velocity, np.abs(V), hand.velocity,
                          tol, jn, t[1:], "rad/s|m/s"))
        VM = np.diff(QM, axis=0) / dt[:, None]
        tol = RATE_TOL * hand.motor_speed + FILE_QUANTUM / dt[:, None]
        out.append(_worst("motor_velocity", np.abs(VM) / hand.motor_speed, np.abs(VM),
                          hand.motor_speed, tol, mn, t[1:], "rad/s"))
    else:
        out.append(LimitCheck("joint_velocity", 0, 0.0, 0.0, "", 0.0, "rad/s|m/s"))
        out.append(LimitCheck("motor_velocity", 0, 0.0, 0.0, "", 0.0, "rad/s"))
    if len(t) >= 3:
        V = np.diff(Q, axis=0) / dt[:, None]
        h = 0.5 * (dt[1:] + dt[:-1])[:, None]
        A = np.diff(V, axis=0) / h
        tol = RATE_TOL * hand.acceleration + 2 * FILE_QUANTUM / (dt[1:] * dt[:-1])[:, None]
        out.append(_worst("joint_acceleration", np.abs(A) / hand.acceleration, np.abs(A),
                          hand.acceleration, tol, jn, t[1:-1], "rad/s^2|m/s^2"))
    else:
        out.append(LimitCheck("joint_acceleration", 0, 0.0, 0.0, "", 0.0, "rad/s^2|m/s^2"))
    return out


def _motor_consistency(hand: HandModel, t: np.ndarray, Q: np.ndarray, QM: np.ndarray
                       ) -> LimitCheck:
    """The motor columns against the joints: tolerance plus the rounding of the file."""
    QMc = hand.motor_angles(Q)
    sens = hand.motor_sensitivity(Q)
    err = np.abs(QM - QMc)
    tol = MOTOR_TOL_RAD + 0.5 * FILE_QUANTUM * (1.0 + sens)
    return _worst("motor_consistency", err / tol, err, tol, 0.0, _motor_columns(hand), t, "rad")


def _coupling_check(hand: HandModel, t: np.ndarray, Q: np.ndarray) -> LimitCheck:
    if not hand.couplings:
        return LimitCheck("coupling", 0, 0.0, COUPLING_TOL_RAD, "", 0.0, "rad")
    ce = np.abs(hand.coupling_errors(Q))
    slope = np.stack([np.abs(c.slope(Q[:, c.src])) for c in hand.couplings], axis=-1)
    tol = COUPLING_TOL_RAD + 0.5 * FILE_QUANTUM * (1.0 + slope)
    names = [hand.joint_names[c.dep] for c in hand.couplings]
    return _worst("coupling", ce / tol, ce, tol, 0.0, names, t, "rad")


def _inertial_torques(kin: Kinematics, t: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """Joint torques moving the hand through its rows (gravity apart): speeds and
    accelerations by central differences of the rows (none at the first and last row);
    only the rows where something moves are computed."""
    out = np.zeros_like(Q)
    if len(t) < 3:
        return out
    dt0, dt1 = np.diff(t)[:-1, None], np.diff(t)[1:, None]
    V = (Q[2:] - Q[:-2]) / (dt0 + dt1)
    A = 2.0 * ((Q[2:] - Q[1:-1]) / dt1 - (Q[1:-1] - Q[:-2]) / dt0) / (dt0 + dt1)
    moving = np.flatnonzero(np.any(V != 0.0, axis=1) | np.any(A != 0.0, axis=1))
    for k in moving:
        out[k + 1] = kin.inertial(Q[k + 1], V[k], A[k])
    return out


def _joint_torques(kin: Kinematics, Q: np.ndarray, pressing_tips: np.ndarray | None,
                   ball_load: np.ndarray | None) -> np.ndarray:
    """Static joint torques of every row: gravity, the keys pushing back on the pressing
    fingertips (``KEY_FORCE_N``), the ball's weight on the palm. They depend on the row
    alone: a row equal to the one before it (a hand holding still, with the same keys
    pressed) is computed once (``distinct_rows``)."""
    key = [Q] + ([] if pressing_tips is None else [pressing_tips]) \
        + ([] if ball_load is None else [np.asarray(ball_load, dtype=float)[:, None]])
    new, of = distinct_rows(np.hstack(key))
    Qn = Q[new]
    tau = np.array([kin.gravity(q) for q in Qn])
    if pressing_tips is not None:
        tip_ids, pn = kin.tip_ids, pressing_tips[new]
        for k in np.flatnonzero(pn.any(axis=1)):
            Js = kin.point_jacobians(Qn[k], [tip_ids[f] for f in np.flatnonzero(pn[k])])
            for J in Js:
                tau[k] -= J.T @ np.array([0.0, 0.0, KEY_FORCE_N])
    if ball_load is not None:
        bn = np.asarray(ball_load)[new]
        for k in np.flatnonzero(bn > 0):
            (J,) = kin.point_jacobians(Qn[k], [kin.palm_id])
            tau[k] -= J.T @ (bn[k] * GRAVITY)
    return tau[of]


def _tendon_audit(hand: HandModel, TM: np.ndarray, t: np.ndarray
                  ) -> tuple[LimitCheck, tuple[TendonLoad, ...]]:
    """Spool tensions of every row (N) against each tendon's design force (1 %)."""
    idx = tendon_motors(hand)
    names = tuple(f"motor.{hand.motor_names[m]}" for m in idx)
    if idx.size == 0:
        return LimitCheck("tendon_tension", 0, 0.0, 0.0, "", 0.0, "N"), ()
    T = np.abs(spool_tensions_n(hand, TM))
    force = np.array([hand.actuators[m].tendon_force_n for m in idx], dtype=float)
    tol = RATE_TOL * force
    loads = []
    for k, name in enumerate(names):
        r = int(np.argmax(T[:, k]))
        loads.append(TendonLoad(name, int(np.count_nonzero(~(T[:, k] <= force[k] + tol[k]))),
                                float(T[r, k]), float(force[k]), float(t[r])))
    return _worst("tendon_tension", T / force, T, force, tol, names, t, "N"), tuple(loads)


def _motor_torques(hand: HandModel, Q: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """``hand.motor_torques`` of every row; one matrix when every law is linear."""
    linear = (all(c.kind == "linear" for c in hand.couplings)
              and all(a.mk5 is None for a in hand.actuators))
    if linear:
        q0 = hand.q_neutral
        M = np.stack([hand.motor_torques(q0, e) for e in np.eye(hand.n)], axis=1)
        return tau @ M.T
    return np.array([hand.motor_torques(q, g) for q, g in zip(Q, tau)])


