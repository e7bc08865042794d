"""The limit audit of a replay, judged in blocks of rows (``LimitAudit``; a file or a plan
being written is audited as it streams, ``limit_audit`` audits rows held whole as one
block, with the same result to the bit): joint positions, speeds, accelerations, motor speeds,
motor columns against the joints, couplings, static motor torque and the tendons'
tensions (planner.hand.tendon: tension at the spool = motor torque / spool radius,
bounded by the cable's design force), the joints' jerks (third differences) and the rows
closer to a hard stop than the joint's stop margin (planner.hand.drive: rows a controller
can run): every category the hand file bounds, of every file (play, planned or live
catch) alike; of a play's rows the motor torques also move the hand (its inertia)."""

from __future__ import annotations

import numpy as np

from planner.check.kinematics import GRAVITY, Kinematics
from planner.check.results import LimitCheck, TendonLoad
from planner.check.worst import Worst, beats
from planner.hand.model import HandModel
from planner.hand.tendon import spool_tensions_n, tendon_motors
from planner.trajfile import Trajectory, distinct_rows

FILE_QUANTUM = 1e-6  # the writer's 6 decimals
POSITION_TOL = 1e-6  # rad or m beyond a joint limit
RATE_TOL = 0.01  # 1 % of a speed / acceleration / torque limit
MOTOR_TOL_RAD = 1e-5  # motor column vs motor_angles(q), plus file rounding
COUPLING_TOL_RAD = 1e-5  # |coupling error|, plus file rounding
KEY_FORCE_N = 0.5  # nominal key reaction on a pressing fingertip


CARRY_ROWS = 3  # the rows before a block its differences reach (jerk: third differences)
AUDIT_ROWS = 8192  # rows gathered before they are judged (smaller blocks: measured slower
# per row, 2000 rows 1.8x the time of one block; 8192 as fast; 3 MB of rows waiting)


def limit_audit(hand: HandModel, kin: Kinematics, tr: Trajectory, pressing_tips: np.ndarray | None,
                ball_load: np.ndarray | None, inertia: bool = False
                ) -> tuple[list[LimitCheck], tuple[TendonLoad, ...]]:
    """The limit checks (one per category) and the worst tension of every tendon of rows
    held whole (``LimitAudit`` with one block); with ``inertia`` the motor torques also
    move the hand as its rows do (a play)."""
    audit = LimitAudit(hand, kin, inertia)
    audit.add(tr.t_s, tr.q, tr.q_motor, pressing_tips, ball_load)
    return audit.finish()


class LimitAudit:
    """The limit audit of rows given block by block, in order (``add``), then ``finish``:
    the limit checks (one per category) and the worst tension of every tendon, equal to
    one pass over every row (each block's differences reach back into the ``CARRY_ROWS``
    rows before it, kept from the blocks before; a row's motor torque, which with
    ``inertia`` needs the row after it, waits for it). Memory: a few rows."""

    def __init__(self, hand: HandModel, kin: Kinematics, inertia: bool = False,
                 block_rows: int = AUDIT_ROWS) -> None:
        """``block_rows``: rows gathered from ``add`` before they are judged (1: each
        block as given)."""
        self._hand, self._kin, self._inertia = hand, kin, inertia
        self._block_rows = block_rows
        self._waiting: list[tuple] = []  # blocks given, not judged yet
        self._waiting_rows = 0
        self._motor_map = linear_motor_map(hand)
        peak = hand.motor_peak_torque
        cats = [("joint_position", "rad|m", 0.0), ("joint_stop_margin", "rad|m", 0.0),
                ("joint_velocity", "rad/s|m/s", 0.0), ("motor_velocity", "rad/s", 0.0),
                ("joint_acceleration", "rad/s^2|m/s^2", 0.0), ("motor_consistency", "rad", 0.0),
                ("coupling", "rad", 0.0 if hand.couplings else COUPLING_TOL_RAD),
                ("joint_jerk", "rad/s^3|m/s^3", 0.0),
                ("motor_torque", "N m", float(np.max(peak)) if np.size(peak) else 0.0),
                ("tendon_tension", "N", 0.0)]
        self._worst = {c: Worst(c, u, e) for c, u, e in cats}
        self._tendons = _TendonLoads(hand)
        self._tail: tuple | None = None  # (t, Q, QM, pressing, ball) of the last rows
        self._rows = 0  # rows given
        self._torqued = 0  # rows whose motor torques are judged

    def add(self, t: np.ndarray, Q: np.ndarray, QM: np.ndarray,
            pressing_tips: np.ndarray | None = None, ball_load: np.ndarray | None = None) -> None:
        """Rows: times (s), joints, motor columns, the pressing fingertips (T, 5) of a play,
        the ball's load (T,) of a catch."""
        if len(t) == 0:
            return
        self._waiting.append((t, Q, QM, pressing_tips,
                              None if ball_load is None else np.asarray(ball_load, dtype=float)))
        self._waiting_rows += len(t)
        if self._waiting_rows >= self._block_rows:
            self._judge_waiting()

    def _judge_waiting(self) -> None:
        if not self._waiting:
            return
        block = self._waiting[0] if len(self._waiting) == 1 else tuple(
            None if parts[0] is None else np.concatenate(parts) for parts in zip(*self._waiting))
        self._waiting, self._waiting_rows = [], 0
        self._judge(block)

    @np.errstate(over="ignore", invalid="ignore")  # absurd values give inf: counted, not printed
    def _judge(self, block: tuple) -> None:
        t, Q, QM = block[:3]
        self._row_rules(t, Q, QM)
        c = 0 if self._tail is None else len(self._tail[0])
        ext = block if self._tail is None else tuple(
            None if b is None else np.concatenate([a, b]) for a, b in zip(self._tail, block))
        self._differences(ext[0], ext[1], ext[2], c)
        self._rows += len(t)
        self._torques(ext, self._rows - len(ext[0]), len(ext[0]) - 1, self._inertia)
        self._tail = tuple(None if a is None else a[-CARRY_ROWS:] for a in ext)

    @np.errstate(over="ignore", invalid="ignore")
    def finish(self) -> tuple[list[LimitCheck], tuple[TendonLoad, ...]]:
        """The checks in the report's order, and the tendons' loads."""
        self._judge_waiting()
        if self._tail is not None:  # the last row: no row after it, no inertia
            self._torques(self._tail, self._rows - len(self._tail[0]), len(self._tail[0]),
                          False)
        names = ["joint_position", "joint_stop_margin", "joint_velocity", "motor_velocity",
                 "joint_acceleration", "motor_consistency", "coupling", "joint_jerk",
                 "motor_torque", "tendon_tension"]
        return [self._worst[n].result() for n in names], self._tendons.loads()

    def _row_rules(self, t: np.ndarray, Q: np.ndarray, QM: np.ndarray) -> None:
        """The rules of a row alone: position, stop margin, motor columns, couplings."""
        hand, w = self._hand, self._worst
        _position_rule(hand, t, Q, w["joint_position"])
        _stop_margin_rule(hand, t, Q, w["joint_stop_margin"])
        QMc = hand.motor_angles(Q)
        sens = hand.motor_sensitivity(Q)
        err = np.abs(QM - QMc)
        tol = MOTOR_TOL_RAD + 0.5 * FILE_QUANTUM * (1.0 + sens)
        w["motor_consistency"].offer_values(err / tol, err, tol, 0.0, _motor_columns(hand), t)
        if hand.couplings:
            ce = np.abs(hand.coupling_errors(Q))
            slope = np.stack([np.abs(c.slope(Q[:, c.src])) for c in hand.couplings], axis=-1)
            tol = COUPLING_TOL_RAD + 0.5 * FILE_QUANTUM * (1.0 + slope)
            names = [hand.joint_names[c.dep] for c in hand.couplings]
            w["coupling"].offer_values(ce / tol, ce, tol, 0.0, names, t)

    def _differences(self, t: np.ndarray, Q: np.ndarray, QM: np.ndarray, c: int) -> None:
        """Speeds (row differences), accelerations (second differences) and jerks
        (third) of rows ``t, Q, QM`` whose first ``c`` were judged before: each
        sample whose last row is new, with the file's rounding in its tolerance."""
        hand, w, m = self._hand, self._worst, len(t)
        jn = hand.joint_names
        if m < 2:
            return
        dt = np.diff(t)
        V = np.diff(Q, axis=0) / dt[:, None]
        s = slice(max(c - 1, 0), None)
        tol = RATE_TOL * hand.velocity + FILE_QUANTUM / dt[:, None]
        w["joint_velocity"].offer_values(np.abs(V[s]) / hand.velocity, np.abs(V[s]),
                                         hand.velocity, tol[s], jn, t[1:][s])
        VM = np.diff(QM, axis=0) / dt[:, None]
        tol = RATE_TOL * hand.motor_speed + FILE_QUANTUM / dt[:, None]
        w["motor_velocity"].offer_values(np.abs(VM[s]) / hand.motor_speed, np.abs(VM[s]),
                                         hand.motor_speed, tol[s], _motor_columns(hand),
                                         t[1:][s])
        if m < 3:
            return
        A = np.diff(V, axis=0) / (0.5 * (dt[1:] + dt[:-1]))[:, None]  # at t[1:-1]
        s = slice(max(c - 2, 0), None)
        tol = RATE_TOL * hand.acceleration + 2 * FILE_QUANTUM / (dt[1:] * dt[:-1])[:, None]
        w["joint_acceleration"].offer_values(np.abs(A[s]) / hand.acceleration, np.abs(A[s]),
                                             hand.acceleration, tol[s], jn, t[1:-1][s])
        if m < 4:
            return
        J = np.diff(A, axis=0) / np.diff(t[1:-1])[:, None]  # between t[1:-2] and t[2:-1]
        s = slice(max(c - 3, 0), None)
        tol = RATE_TOL * hand.jerk + 4 * FILE_QUANTUM / (dt[2:] * dt[1:-1] * dt[:-2])[:, None]
        w["joint_jerk"].offer_values(np.abs(J[s]) / hand.jerk, np.abs(J[s]), hand.jerk, tol[s],
                                     jn, t[2:-1][s])

    def _torques(self, rows: tuple, first: int, upto: int, inertia: bool) -> None:
        """Motor torques and tendon tensions of ``rows`` (t, Q, QM, pressing, ball; row 0
        is the song's row ``first``) not judged yet, up to row ``upto`` (exclusive)."""
        t, Q, _, P, B = rows
        lo = self._torqued - first
        if upto <= lo:
            return
        s = max(lo - 1, 0) if inertia else lo  # (row 0 of the song has no row before
        # it: no inertia)
        gravity = self._kin.gravities(Q[s:upto + 1] if inertia else Q[lo:upto])
        tau = _joint_torques(self._kin, Q[lo:upto], None if P is None else P[lo:upto],
                             None if B is None else B[lo:upto], gravity[lo - s:upto - s])
        if inertia:
            tau += _inertial_torques(self._kin, t[s:upto + 1], Q[s:upto + 1],
                                     gravity)[lo - s:upto - s]
        hand = self._hand
        # (einsum, not a matrix product: each row summed in one order whatever the block's
        # size, so a stream's rows equal the whole file's to the bit)
        TM = (np.einsum("tj,mj->tm", tau, self._motor_map) if self._motor_map is not None
              else _motor_torques(hand, Q[lo:upto], tau))
        peak = hand.motor_peak_torque
        self._worst["motor_torque"].offer_values(np.abs(TM) / peak, np.abs(TM), peak,
                                                 RATE_TOL * peak, _motor_columns(hand),
                                                 t[lo:upto])
        self._tendons.add(TM, t[lo:upto], self._worst["tendon_tension"])
        self._torqued = first + upto


def row_motor_torques(hand: HandModel, kin: Kinematics, t: np.ndarray, Q: np.ndarray,
                      pressing_tips: np.ndarray, motor_map: np.ndarray | None,
                      inertia: bool = True) -> np.ndarray:
    """The motor torques (rows, motors) that a play's audit judges (``LimitAudit`` with
    ``inertia``) at rows ``1 .. len(t) - 2`` of rows ``t, Q`` held whole, with the
    fingertips ``pressing_tips`` (T, 5) pressing: gravity, the keys' push, and moving the
    hand as its rows do (central differences: each needs the rows beside it; without
    ``inertia`` the static torques alone; ``motor_map``: the hand's
    ``linear_motor_map``). The audit's own definition, for a planner bounding its rows
    before it writes them."""
    gravity = kin.gravities(Q)
    tau = _joint_torques(kin, Q, pressing_tips, None, gravity)
    if inertia:
        tau += _inertial_torques(kin, t, Q, gravity)
    tau = tau[1:-1]
    return (np.einsum("tj,mj->tm", tau, motor_map) if motor_map is not None
            else _motor_torques(hand, Q[1:-1], tau))


class _TendonLoads:
    """Spool tensions (N) against each tendon's design force (1 %): the category's worst
    and every tendon's own."""

    def __init__(self, hand: HandModel) -> None:
        self._hand = hand
        self._idx = tendon_motors(hand)
        self._names = tuple(f"motor.{hand.motor_names[m]}" for m in self._idx)
        self._force = np.array([hand.actuators[m].tendon_force_n for m in self._idx],
                               dtype=float)
        self._tol = RATE_TOL * self._force
        self._each: list[list] = [[0, None, 0.0, 0.0] for _ in self._idx]  # count, rank, T, t

    def add(self, TM: np.ndarray, t: np.ndarray, worst: Worst) -> None:
        if self._idx.size == 0:
            return
        T = np.abs(spool_tensions_n(self._hand, TM))
        for k, each in enumerate(self._each):
            r = int(np.argmax(T[:, k]))
            each[0] += int(np.count_nonzero(~(T[:, k] <= self._force[k] + self._tol[k])))
            if beats(float(T[r, k]), each[1]):
                each[1:] = [float(T[r, k]), float(T[r, k]), float(t[r])]
        worst.offer_values(T / self._force, T, self._force, self._tol, self._names, t)

    def loads(self) -> tuple[TendonLoad, ...]:
        return tuple(TendonLoad(name, each[0], each[2], float(f), each[3])
                     for name, each, f in zip(self._names, self._each, self._force))


def _motor_columns(hand: HandModel) -> tuple[str, ...]:
    return tuple(f"motor.{m}" for m in hand.motor_names)


def _position_rule(hand: HandModel, t: np.ndarray, Q: np.ndarray, worst: Worst) -> None:
    """Excess beyond the nearer bound (<= 0 inside); infinite bounds never bind."""
    lo = np.where(np.isfinite(hand.lower), hand.lower, -np.inf)
    hi = np.where(np.isfinite(hand.upper), hand.upper, np.inf)
    below, above = lo - Q, Q - hi
    excess = np.maximum(below, above)
    bound = np.where(below > above, lo, hi)
    worst.offer(int(np.count_nonzero(excess > POSITION_TOL)), excess,
                lambda r, c: (float(Q[r, c]), float(bound[r, c]), hand.joint_names[c],
                              float(t[r])))


def _stop_margin_rule(hand: HandModel, t: np.ndarray, Q: np.ndarray, worst: Worst) -> None:
    """Rows closer to a hard stop than the joint's stop margin (outside the planner's
    limits, ``HandModel.plan_lower``/``plan_upper``), the file's rounding allowed:
    ``worst`` is the least room to a stop (rad or m), ``limit`` that joint's margin."""
    lo = np.where(np.isfinite(hand.lower), hand.lower, -np.inf)
    hi = np.where(np.isfinite(hand.upper), hand.upper, np.inf)
    room = np.minimum(Q - lo, hi - Q)
    short = hand.stop_margin - room  # > 0: inside the margin (or past the stop)
    margin = np.broadcast_to(hand.stop_margin, Q.shape)
    worst.offer(int(np.count_nonzero(short > POSITION_TOL)), short,
                lambda r, c: (float(room[r, c]), float(margin[r, c]), hand.joint_names[c],
                              float(t[r])))


def _inertial_torques(kin: Kinematics, t: np.ndarray, Q: np.ndarray,
                      gravity: np.ndarray | None = None) -> np.ndarray:
    """Joint torques moving the hand through its rows (gravity apart): speeds and
    accelerations by central differences of the rows (none at the first and last row);
    only the rows where something moves are computed (``gravity``: each row's
    ``Kinematics.gravities``, when known)."""
    out = np.zeros_like(Q)
    if len(t) < 3:
        return out
    dt0, dt1 = np.diff(t)[:-1, None], np.diff(t)[1:, None]
    V = (Q[2:] - Q[:-2]) / (dt0 + dt1)
    A = 2.0 * ((Q[2:] - Q[1:-1]) / dt1 - (Q[1:-1] - Q[:-2]) / dt0) / (dt0 + dt1)
    moving = np.flatnonzero(np.any(V != 0.0, axis=1) | np.any(A != 0.0, axis=1))
    if len(moving):
        still = kin.gravities(Q[moving + 1]) if gravity is None else gravity[moving + 1]
        out[moving + 1] = kin.moving(Q[moving + 1], V[moving], A[moving], still)
    return out


def _joint_torques(kin: Kinematics, Q: np.ndarray, pressing_tips: np.ndarray | None,
                   ball_load: np.ndarray | None, gravity: np.ndarray | None = None
                   ) -> np.ndarray:
    """Static joint torques of every row: gravity (``gravity``: each row's, when known),
    the keys pushing back on the pressing fingertips (``KEY_FORCE_N``), the ball's weight
    on the palm. They depend on the row alone: a row equal to the one before it (a hand
    holding still, with the same keys pressed) is computed once (``distinct_rows``)."""
    key = [Q] + ([] if pressing_tips is None else [pressing_tips]) \
        + ([] if ball_load is None else [np.asarray(ball_load, dtype=float)[:, None]])
    new, of = distinct_rows(np.hstack(key))
    Qn = Q[new]
    tau = kin.gravities(Qn) if gravity is None else gravity[new]
    if pressing_tips is not None:
        kin.tips_pushed(Qn, pressing_tips[new], np.array([0.0, 0.0, KEY_FORCE_N]), tau)
    if ball_load is not None:
        bn = np.asarray(ball_load)[new]
        for k in np.flatnonzero(bn > 0):
            (J,) = kin.point_jacobians(Qn[k], [kin.palm_id])
            tau[k] -= J.T @ (bn[k] * GRAVITY)
    return tau[of]


def linear_motor_map(hand: HandModel) -> np.ndarray | None:
    """The matrix of ``hand.motor_torques`` when every law is linear (else None)."""
    if not (all(c.kind == "linear" for c in hand.couplings)
            and all(a.mk5 is None for a in hand.actuators)):
        return None
    q0 = hand.q_neutral
    return np.stack([hand.motor_torques(q0, e) for e in np.eye(hand.n)], axis=1)


def _motor_torques(hand: HandModel, Q: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """``hand.motor_torques`` of every row (a law not linear)."""
    return np.array([hand.motor_torques(q, g) for q, g in zip(Q, tau)])


