"""The soft catch: the palm meets the ball already moving along its path, then brings it
to rest (``planner.catch.plan.api``, step 3).

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
  and within the joints' range; where that optimum moves the palm into the ball and the
  pad's force then needs more than a motor's capacity, the palm giving with the ball along
  its normal is searched too (``contact_speeds(..., give=True)``, ``_best_tilt``);
* the ramps' durations: the shortest whose peak acceleration keeps every joint within its
  acceleration limit and every motor within ``STOP_SHARE`` of its capacity while it moves
  the hand's own inertia (and, ramping out, the ball riding on the palm) against gravity;
* the palm's tilt (``find_intercept(..., tilt)``): among ``TILTS_DEG`` the pose whose
  stopping needs the least of the motor closest to its capacity (its force's lever about
  the wrist changes with the tilt) and whose pad force stays in the palm's friction cone.

The rows' dynamics are then judged by the check's own rule (``planner.check.ball``); a
ball that no such motion stops within every motor's capacity is "too fast to stop".

Holding the ball: the contact speeds' QP (``planner.catch.plan.contactqp``) weighs the
relative speed along the palm ``ROLL_WEIGHT`` times its normal part, and once the grasp is
made the wrist turns the closed hand (``planner.catch.plan.holdturn``) until the palm faces up.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from planner.catch.flight.path import Flight
from planner.catch.grasp import motor_torque_matrix, palm_jacobian
from planner.catch.plan.arm import CatchJoints, open_from, palm_target
from planner.catch.plan.closing import closing_offsets
from planner.catch.plan.contactqp import ROLL_WEIGHT, contact_speeds, giving_speeds
from planner.catch.plan.intercept import Intercept, Wrist, find_intercept, find_intercept_square
from planner.catch.plan.ramps import JointRamps, recoil_shares, with_joint_ramps
from planner.catch.plan.results import Closing
from planner.catch.plan.softstop import SoftStop
from planner.check.ballstop import cone_margin_n, pad_force_n, pad_time_s
from planner.check.kinematics import Kinematics
from planner.hand.model import HandModel
from planner.hand.tendon import actuator_capacity
from planner.trajectory import LIMIT_MARGIN, MIN_PHASE_S, PEAK_ACC, PEAK_VEL, phase_duration

STOP_SHARE = 0.8  # the ramps load every motor to at most 80 % of its capacity: issue 15's
# 20 % headroom, left for what the model does not see (friction, the fingers' moves)
MOVE_SHARE = 0.6  # the move to the pre-catch pose, where the time allows, keeps every motor
# within 60 % of its capacity (``StopDynamics.calm_move_time``): the inertia model of
# ``move_time`` (``accel_room``, the poses at the move's ends) is 10-12 % under the replay's
# peak (MuJoCo, full contact; 30 deg from 1.5 and 3 m, the move within STOP_SHARE 0.80:
# 0.90 and 0.88 of wrist_dev's 2.00 N m), and the catch's target is 20 % headroom in physics
MOVE_SPARE_S = 0.01  # ... and still reaches its pose one row (at 100 Hz) before it is due
TILTS_DEG = (0.0, -5.0, -10.0, 5.0, 10.0)  # palm tilts tried (deg about the flexion axis)
CONTACT_SHARES = (0.9, 0.8, 0.7, 0.6, 0.5, 0.4, 0.3)  # the arm's speed when it meets the ball, tried as a
# share of its speed after the recoil

@dataclass(frozen=True)
class StopGrid:
    """The soft stop's search steps: the palm's tilts (deg, 0 first, each side outwards in
    order) and the contact shares (slower while it helps)."""

    tilts_deg: tuple[float, ...] = TILTS_DEG
    shares: tuple[float, ...] = CONTACT_SHARES
    per_joint: JointRamps = JointRamps.NONE  # one ramp time, or each arm joint's own
    every_tilt: bool = False  # every tilt's recoil judged on the rows (else the tilt whose
    # pad load at full speed is least, then its recoil)
    fingers_judged: bool = False  # the recoil judged with the fingers closing as the rows
    # close them (``StopDynamics.judge``'s ``closing``; else open)


COARSE_STOP = StopGrid()  # every plan's
_SHRINK = 0.95  # a profile that leaves the joints' range (or its time) is tried again with
# the speeds its overshoot asks for, times this (the QP then shares the speeds anew)
_MAX_SHRINK = 6
_MIN_SPEED = 0.05  # arm speeds below this share of their limits are not worth a motion
_FD_M = 1e-6  # finite-difference step of the palm target's Jacobian (rad or m)


_ROOMS_KEPT = 4  # accel_room results kept (the rest pose and the latest few; the least
# recently used dropped)



class StopDynamics:
    """The hand's dynamics the stopping motion needs (one hand, reference-mounted)."""

    def __init__(self, hand: HandModel, joints: CatchJoints, kin: Kinematics) -> None:
        self.hand, self.joints, self.kin = hand, joints, kin
        self.arm = tuple(joints.arm)
        m = hand.pin_model
        self._idx = np.array([m.idx_qs[m.getJointId(n)] for n in hand.joint_names])
        self._arm_idx = self._idx[list(self.arm)]  # (the arm's, in Pinocchio's vectors)
        self._nq, self._nv = m.nq, m.nv
        self._data = m.createData()
        i, j = self._idx[:, None], self._idx[None, :]  # the mass matrix of our joints in
        # one take from crba's result, which fills the upper triangle only: (i, j) at
        # (min, max)
        self._h_flat = np.minimum(i, j) * m.nv + np.maximum(i, j)
        self._rooms: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}  # accel_room's last
        # results by q (a live session asks for the rest pose's at every observation
        # until the hand moves)
        self._poses: dict[bytes, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}  # at_pose's
        self.cap = actuator_capacity(hand).torque_nm
        self.v_max = LIMIT_MARGIN * hand.velocity[list(self.arm)]
        self.a_max = LIMIT_MARGIN * hand.acceleration[list(self.arm)]

    def _pq(self, q: np.ndarray) -> np.ndarray:
        qp = np.zeros(self._nq)
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
        vp, ap = np.zeros(self._nv), np.zeros(self._nv)
        vp[self._arm_idx], ap[self._arm_idx] = v, a
        return pin.rnea(self.hand.pin_model, self._data, self._pq(q), vp, ap)[self._idx]

    def move_time(self, q_from: np.ndarray, q_to: np.ndarray, arm_alone: bool = False
                  ) -> float:
        """Shortest min-jerk move ``q_from`` -> ``q_to`` within every joint's speed and
        acceleration limits (``phase_duration``) and every motor within ``STOP_SHARE`` of
        its capacity while it moves the hand (its inertia at the peak acceleration PEAK_ACC
        |dq| / T^2, at either end, against gravity: ``accel_room``). ``arm_alone``: the
        arm's part of that acceleration alone within the room too (how a live session
        bounds its re-aims, ``planner.catch.live.motion``)."""
        return self.room_time((q_from, q_to), q_to - q_from, STOP_SHARE, arm_alone)

    def calm_move_time(self, q_from: np.ndarray, q_to: np.ndarray, t_start: float,
                       due: float) -> float:
        """``move_time``, or the slower move with every motor within ``MOVE_SHARE`` when,
        started at ``t_start``, it is still there ``MOVE_SPARE_S`` before ``due`` (the
        stop's ramp, the ball, the closing's start: nothing else moves later)."""
        T = self.move_time(q_from, q_to)
        calm = self.room_time((q_from, q_to), q_to - q_from, MOVE_SHARE)
        return max(T, calm) if t_start + calm <= due - MOVE_SPARE_S else T

    def room_time(self, ends: tuple[np.ndarray, np.ndarray], dq: np.ndarray, share: float,
                  arm_alone: bool = False) -> float:
        """``move_time``'s rule with every motor within ``share`` (at most STOP_SHARE) of
        its capacity: the shortest min-jerk move by ``dq`` between the poses ``ends``; inf
        when gravity alone leaves a motor no room."""
        T = phase_duration(dq, self.hand.velocity, self.hand.acceleration)
        arm = list(self.arm)
        for q in ends:
            MH, room = self.accel_room(q)
            room = room - (STOP_SHARE - share) * self.cap
            per = np.abs(MH @ dq)
            if arm_alone:
                per = np.maximum(per, np.abs(MH[:, arm] @ dq[arm]))
            need = per > 1e-12
            if (room[need] <= 0).any():  # (the arrays' own reductions: ``np.any``'s and
                # ``np.max``'s numbers without their wrappers, ~5 us a call of the set-up's)
                return math.inf
            if need.any():
                T = max(T, math.sqrt(PEAK_ACC * float((per[need] / room[need]).max())))
        return T

    def accel_room(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The motors' room for the hand's accelerations at ``q`` (``move_time``'s rule; a
        live re-aim's too): (MH, room), MH (n_motor, n) every motor's torque per unit joint
        acceleration (the hand's inertia: the motor map of the mass matrix), room =
        STOP_SHARE x its capacity - |its gravity torque|. Accelerations a with |MH @ a| <=
        room keep every motor within STOP_SHARE of its capacity at low speed."""
        key = q.tobytes()
        hit = self._rooms.pop(key, None)
        if hit is not None:  # kept as the newest: the least recently asked for goes first
            self._rooms[key] = hit
            return hit
        m = self.hand.pin_model
        qp = self._pq(q)
        H = pin.crba(m, self._data, qp).take(self._h_flat)
        M = motor_torque_matrix(self.hand, q)
        z = np.zeros(m.nv)
        g = pin.rnea(m, self._data, qp, z, z)[self._idx]
        out = (M @ H, STOP_SHARE * self.cap - np.abs(M @ g))
        for a in out:
            a.setflags(write=False)
        return _kept(self._rooms, key, out)

    def at_pose(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """What ``ramp_time`` and ``pad_load`` read of the pose ``q`` alone, computed once
        for the latest few poses (a stop's search asks for them at one open pose at every
        step): (M, gravity, J_palm), the motors' torque per joint torque
        (``motor_torque_matrix``), the joints' gravity torque (``joint_torques`` at rest)
        and the palm centre's Jacobian (``palm_jacobian``); read-only."""
        key = q.tobytes()
        hit = self._poses.pop(key, None)
        if hit is not None:
            self._poses[key] = hit
            return hit
        z = np.zeros(len(self.arm))
        out = (motor_torque_matrix(self.hand, q), self.joint_torques(q, z, z),
               palm_jacobian(self.hand, q))
        for a in out:
            a.setflags(write=False)
        return _kept(self._poses, key, out)

    def ramp_time(self, q: np.ndarray, qd: np.ndarray, load: np.ndarray | None = None,
                  share: float = STOP_SHARE) -> float:
        """Shortest min-jerk speed ramp between rest and ``qd`` (its peak acceleration is
        PEAK_VEL |qd| / T) within the acceleration limits and every motor within ``share``
        (``STOP_SHARE``) of its capacity; ``load``: (n, k) extra joint torque per unit arm
        acceleration (the riding ball). inf when gravity and speed alone leave no room."""
        if not qd.any():
            return 0.0
        M, g, _ = self.at_pose(q)
        z = np.zeros(qd.shape)
        base = M @ self.joint_torques(q, qd, z)
        per = M @ (self.joint_torques(q, z, qd) - g
                   + (load @ qd if load is not None else 0.0))
        room = share * self.cap - np.abs(base)
        need = np.abs(per) > 1e-12
        if (room[need] <= 0).any():
            return math.inf
        s_max = min(float((room[need] / np.abs(per[need])).min()) if need.any() else math.inf,
                    float((self.a_max / np.maximum(np.abs(qd), 1e-12)).min()))
        return max(MIN_PHASE_S, PEAK_VEL / s_max)

    def judge(self, stop: SoftStop, q_open: np.ndarray, flight: Flight, r: float,
              closing: Closing | None = None) -> tuple[bool, float]:
        """The check's rule (``planner.check.ball.ball_loads``) on the rows around the
        intercept that ``stop`` gives the arm (the fingers open, or ``closing``: closing as
        the rows close them, ``closing_offsets``): whether the ball stays in the palm's
        friction cone while the pad stops it, and the least motor headroom."""
        dt = stop.row_s
        k0 = math.floor(stop.t_i / dt)
        n = math.ceil((stop.pad_s + stop.recoil_s) / dt) + 3
        t = np.arange(k0 - 2, k0 + n) * dt
        Q = np.tile(q_open, (len(t), 1)) + stop.offset(t, self.hand.n)
        if closing is not None:
            Q = self.hand.apply_couplings(Q + closing_offsets(
                closing, self.joints.finger_idx, q_open, t, stop.t_i, stop.pad_s))
        _, palm = self.kin.frames(Q)
        b = flight.to_metadata()
        ball = {"p0": np.asarray(b["p0"], dtype=float), "v0": np.asarray(b["v0"], dtype=float),
                "radius": float(r), "mass": float(b["mass"]), "drag": float(b["drag"])}
        # (first used by the ending of a live session: not imported at its start)
        from planner.check.ball import ball_loads

        ld = ball_loads(t, Q, self.kin, palm, ball, stop.t_i, self.hand.pad_give_m)[0]
        return ld.cone_margin_n is None or ld.cone_margin_n >= 0, float(ld.headroom)

    def pad_load(self, q: np.ndarray, qd: np.ndarray, v_rel: np.ndarray, mass: float,
                 normal: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        """The pad's force on the ball, every motor's |torque| / capacity while it acts (the
        hand at speed ``qd``, not accelerating), and its friction-cone margin."""
        F = pad_force_n(mass, v_rel, None, self.hand.pad_give_m)
        M, _, J_palm = self.at_pose(q)
        tau = self.joint_torques(q, qd, np.zeros(qd.shape)) + J_palm.T @ F
        return F, np.abs(M @ tau) / self.cap, cone_margin_n(F, normal)


def _kept(kept: dict, key: bytes, value):
    """``value`` kept in ``kept`` under ``key`` as the newest of at most ``_ROOMS_KEPT`` (the
    least recently used dropped)."""
    if len(kept) >= _ROOMS_KEPT:
        kept.pop(next(iter(kept)))
    kept[key] = value
    return value


@dataclass(frozen=True)
class StopSearch:
    """What the soft stop's searches of one throw start from (``plan_stop``'s arguments):
    the hand's dynamics, the wrist's geometry, the flight, the catch point ``C`` (catch
    frame), the ball's radius ``r``, the hand's zero pose, the closing move, the time the
    ball reaches the catch plane ``t_c``, ``ready_by`` (a function of the pre-catch pose ->
    when the hand can be there), the rows' step and the contact speeds' roll weight. The
    tilt search and the recoil search take it whole."""

    dyn: StopDynamics
    wrist: Wrist
    flight: Flight
    C: np.ndarray
    r: float
    q_zero: np.ndarray
    closing: Closing
    t_c: float
    ready_by: Callable[[np.ndarray], float]
    row_s: float
    roll_weight: float = ROLL_WEIGHT


def plan_stop(dyn: StopDynamics, wrist: Wrist, flight: Flight, C: np.ndarray, r: float,
              q_zero: np.ndarray, closing: Closing, t_c: float, ready_by, row_s: float,
              soft: bool = True, roll_weight: float = ROLL_WEIGHT,
              speeds: Callable[..., np.ndarray] | None = None,
              grid: StopGrid = COARSE_STOP
              ) -> tuple[Intercept, np.ndarray, SoftStop]:
    """The intercept, its open pose and the stopping motion (module docstring). ``ready_by``:
    a function of the pre-catch pose -> when the hand can be there. ``soft`` False: the palm
    waits at rest (the stopping is the pad's alone). ``roll_weight``: the contact-speed QP's
    weight on the ball's speed along the palm (1: none above its speed into it). ``speeds``:
    the contact speeds' QP solver (``StopAsk``; None: ``contact_speeds``). ``grid``: the
    palm's tilts and the contact shares searched (``COARSE_STOP``, or the later stages'
    ``planner.catch.plan.stopstages``)."""
    search = StopSearch(dyn, wrist, flight, C, r, q_zero, closing, t_c, ready_by, row_s,
                        roll_weight)
    if grid.every_tilt and soft:
        # every tilt's own recoil judged on the rows (the tilt's pad load at full speed does
        # not order the recoiled stops)
        found = None
        for tilt in grid.tilts_deg:
            one = _best_tilt(search, soft, speeds, (tilt,), grid.per_joint)
            if one is not None:
                got = _recoiled(search, grid, one)
                if found is None or got[0] > found[0]:
                    found = got
        if found is not None:
            return found[1]
    best = _best_tilt(search, soft, speeds, grid.tilts_deg, grid.per_joint)
    if best is None:  # no tilt reaches: the untilted intercept says why
        ic = find_intercept(wrist, flight, C, r, t_c)
        return _candidate(search, ic, False, 0.0, 1.0, speeds=speeds)
    return _recoiled(search, grid, best)[1]


def _recoiled(search: StopSearch, grid: StopGrid, best) -> tuple:
    """``plan_stop``'s recoil search from the tilt search's ``best`` over ``grid``'s contact
    shares: (the judged key or None, (intercept, open pose, stop))."""
    dyn, flight, r = search.dyn, search.flight, search.r
    ic, q_open, stop = best[1]
    speeds = best[2]  # the palm giving with the ball, if the search chose that
    if not np.any(stop.qd):
        return (False, -math.inf), best[1]
    # the recoil: meet the ball slower and let its push speed the arm up (judged on rows)
    fingers = search.closing if grid.fingers_judged else None
    judged = (dyn.judge(stop, q_open, flight, r, fingers), stop)
    for share in grid.shares:  # slower while it helps
        # from the speeds the last one found within the joints' range
        warm = np.where(np.abs(stop.qd) < dyn.v_max - 1e-9, np.abs(stop.qd), dyn.v_max)
        cand = _candidate(search, ic, True, stop.tilt_rad, share, warm, speeds=speeds,
                          per_joint=grid.per_joint)[2]
        if cand.contact_share == 1.0:
            break
        j = (dyn.judge(cand, q_open, flight, r, fingers), cand)
        if j[0] <= judged[0]:
            break
        judged, stop = j, cand
    return judged[0], (ic, q_open, judged[1])


def stop_tilt(dyn: StopDynamics, wrist: Wrist, flight: Flight, C: np.ndarray, r: float,
              q_zero: np.ndarray, closing: Closing, t_c: float, ready_by, row_s: float,
              speeds: Callable[..., np.ndarray] | None = None,
              placed_at: dict[float, Intercept] | None = None) -> float:
    """The palm's tilt (rad) ``plan_stop`` chooses for this throw (its contact share 1:
    the tilt is chosen before the share), 0 when no tilt reaches; ``speeds``: the contact
    speeds' QP solver (``StopAsk``). ``placed_at``: a dict given is filled with the
    intercepts ``find_intercept`` gave the search (the reach held at 0), by tilt (rad)."""
    search = StopSearch(dyn, wrist, flight, C, r, q_zero, closing, t_c, ready_by, row_s)
    best = _best_tilt(search, True, speeds, placed_at=placed_at)
    return 0.0 if best is None else float(best[1][2].tilt_rad)


def _best_tilt(search: StopSearch, soft: bool, speeds: Callable[..., np.ndarray] | None = None,
               tilts_deg: tuple[float, ...] = TILTS_DEG,
               per_joint: JointRamps = JointRamps.NONE,
               placed_at: dict[float, Intercept] | None = None):
    """``plan_stop``'s tilt search (over ``tilts_deg``; ``placed_at``: ``stop_tilt``'s): (key, (intercept, open pose, stop),
    contact speeds' solver) of the tilt whose pad phase needs the least of the motor closest
    to its capacity; None: no tilt reaches. Where that stop closes the palm on the ball
    beyond a motor (``_closes_beyond_a_motor``) the search is run again with the palm giving
    with the ball (``giving_speeds``), and the better kept."""
    best = _placed_search(search, soft, speeds, tilts_deg, per_joint, placed_at)
    if best is not None and speeds is None and _closes_beyond_a_motor(best[1]):
        gave = _placed_search(search, soft, giving_speeds, tilts_deg, per_joint, placed_at)
        if gave is not None and gave[0] < best[0]:
            best = gave
    return best


def _placed_search(search: StopSearch, soft: bool, speeds: Callable[..., np.ndarray] | None,
                   tilts_deg: tuple[float, ...], per_joint: JointRamps,
                   placed_at: dict[float, Intercept] | None = None):
    """``_best_tilt``'s search with one contact speeds' solver over the palm's placements
    (``placed_at``: ``stop_tilt``'s)."""
    best = None
    s = search
    for placed in ((True, False) if s.dyn.joints.i_reach is not None else (False,)):
        # the palm square to the throw on the reach axis (``find_intercept_square``), then
        # the reach held at 0 and the deviation placing the ball (``find_intercept``)
        def place(tilt_rad: float, placed: bool = placed) -> Intercept | None:
            if placed:
                return find_intercept_square(s.wrist, s.flight, s.C, s.r, s.t_c, tilt_rad)
            ic = find_intercept(s.wrist, s.flight, s.C, s.r, s.t_c, tilt_rad)
            if placed_at is not None:
                placed_at[tilt_rad] = ic
            return ic

        found = _tilt_search(search, place, soft, speeds, tilts_deg, per_joint)
        if found is not None and (best is None or found[0] < best[0]):
            best = found
    return best


def _tilt_search(search: StopSearch, place, soft: bool,
                 speeds: Callable[..., np.ndarray] | None, tilts_deg: tuple[float, ...],
                 per_joint: JointRamps):
    """``_best_tilt`` at one placement of the palm (``place``: tilt -> intercept or None),
    over ``tilts_deg`` (0, then each side outwards in their order; a grid without 0, as
    ``planner.catch.plan.palmup``'s, in its own order)."""
    found = None
    sides = ((0.0, *(x for x in tilts_deg if x < 0)), tuple(x for x in tilts_deg if x > 0)) \
        if 0.0 in tilts_deg else (tuple(tilts_deg),)
    for side in sides:
        # outwards from 0 on each side, while the tilt keeps helping (the load's lever about
        # the wrist changes smoothly with it)
        for tilt in (side if soft else side[:1] if side and side[0] == 0.0 else ()):
            ic = place(math.radians(tilt))
            if ic is None or ic.reason is not None or (tilt != 0.0 and not ic.aligned):
                break
            cand = _candidate(search, ic, soft, math.radians(tilt), 1.0, speeds=speeds,
                              per_joint=per_joint)
            key = (cand[2].cone_margin_n < 0, float(cand[2].motor_ratio.max()))
            if found is not None and key >= found[0]:
                break
            found = (key, cand, speeds)
    return found


def _closes_beyond_a_motor(cand) -> bool:
    """Whether the stopping motion of ``cand`` (intercept, open pose, stop) moves the palm
    into the ball (against the ball's velocity relative to it) with the pad's force then
    beyond a motor's capacity.
    A palm closing on the ball adds its speed to the ball's normal speed, whose square sets
    the pad's force (m v^2 / 2 d, ``planner.check.ballstop``): the roll term's tangential
    match is bought with force. On the steep throws (75 deg from 2 m on, the arm alone) that
    met the ball 0.5-0.6 m/s faster than it flies and needed 2.9-5.4 N m of the wrist
    flexion's 2.00; there ``_best_tilt`` also searches the palm giving with the ball
    (``giving_speeds``) and keeps the better. A closing palm within every motor keeps its
    match: the roll it cancels holds steep short throws (-0.3 m / 75 deg / 1.5 m)."""
    _, _, stop = cand
    return float(stop.v_rel @ stop.v_palm) < 0.0 and float(stop.motor_ratio.max()) > 1.0


def _candidate(search: StopSearch, ic: Intercept, soft: bool, tilt_rad: float, share: float,
               bound0: np.ndarray | None = None,
               speeds: Callable[..., np.ndarray] | None = None,
               per_joint: JointRamps = JointRamps.NONE):
    """The stopping motion at the intercept ``ic`` (``stop_profile``), from its open pose;
    ``per_joint``: one ramp time for every arm joint, or each joint's own."""
    dyn, flight = search.dyn, search.flight
    h, j = dyn.hand, dyn.joints
    q = search.q_zero.copy()
    q[j.i_flex], q[j.i_dev] = ic.theta, ic.dev
    if j.i_rail is not None:
        q[j.i_rail] = ic.rail
    if j.i_reach is not None:
        q[j.i_reach] = ic.reach
    q_open = open_from(h, j, q, search.closing.q_closed)
    bound = (dyn.v_max.copy() if bound0 is None else bound0.copy()) if soft \
        else np.zeros(len(dyn.arm))
    stop = stop_profile(dyn, flight.velocity(ic.t), float(flight.ball.mass_kg), search.r,
                        q_open, float(ic.t), search.ready_by, search.row_s,
                        StopAsk(tilt_rad, share, bound, search.roll_weight, speeds, per_joint))
    if stop is None:
        return _candidate(search, ic, False, tilt_rad, 1.0, speeds=speeds)
    return ic, q_open, stop


@dataclass(frozen=True)
class StopAsk:
    """What ``stop_profile`` is asked for: the palm's tilt (rad, recorded), the contact
    share, the arm's speed bounds to start from (zeros: the palm at rest), the roll weight
    of the contact speeds' QP and its solver (``contact_speeds``'s arguments)."""

    tilt_rad: float
    share: float
    bound: np.ndarray
    roll_weight: float = ROLL_WEIGHT
    speeds: Callable[..., np.ndarray] | None = None  # None: ``contact_speeds`` (OSQP)
    per_joint: JointRamps = JointRamps.NONE  # each arm joint's ramps in its own time
    # (``with_joint_ramps``) and which joints recoil (``recoil_shares``)


def stop_profile(dyn: StopDynamics, v_ball: np.ndarray, mass: float, r: float,
                 q_open: np.ndarray, t_i: float, ready_by, row_s: float, ask: StopAsk
                 ) -> SoftStop | None:
    """The stopping motion through the open pose ``q_open`` for a ball arriving at ``t_i``
    with velocity ``v_ball``, meeting it at ``ask.share`` of the arm's full speeds (those
    speeds by the QP), the ramps as short as the motors allow, slowed where the joints'
    range or the time before the ball (``ready_by``: a function of the pre-catch pose ->
    when the hand can be there) is short. The palm at rest when the recoil would need more
    than the joints' acceleration; None when no speed is left worth a motion (then the
    palm at rest, the caller's ``StopAsk`` with zero bounds)."""
    h, arm, share = dyn.hand, list(dyn.arm), ask.share
    speeds = ask.speeds or contact_speeds
    normal = h.palm_pose(q_open)[:3, 2]
    J = dyn.target_jacobian(q_open, r)
    bound = ask.bound.copy()
    load = np.zeros((h.n, len(arm)))
    load[arm] = mass * J.T @ J  # joint torque per unit arm acceleration of the riding ball
    lo, hi = h.lower[arm], h.upper[arm]
    for _ in range(_MAX_SHRINK + 1):
        qd_c = speeds(J, v_ball, share * bound, normal, ask.roll_weight) if bound.any() \
            else 0.0 * bound
        moving = bool(qd_c.any())
        v_rel = v_ball - J @ qd_c
        F, ratio, cone = dyn.pad_load(q_open, qd_c, v_rel, mass, normal)
        t_pad = pad_time_s(v_rel, dyn.hand.pad_give_m)
        qd = qd_c / share
        recoil = max(t_pad, row_s) if moving and share < 1.0 else 0.0
        shares = None
        if recoil and ask.per_joint is not JointRamps.NONE:
            shares = recoil_shares(dyn, q_open, qd_c, ratio, share, recoil,
                                   ask.per_joint is JointRamps.LOADED, STOP_SHARE)
            qd = qd_c / shares
        elif recoil and ((1.0 - share) * np.abs(qd) > dyn.a_max * recoil).any():
            return _at_rest(t_i, ask.tilt_rad, arm, v_rel, F, ratio, cone, t_pad)
        stop = SoftStop(ask.tilt_rad, tuple(arm), qd, share if moving else 1.0, t_i,
                        row_s if moving else 0.0, dyn.ramp_time(q_open, qd_c), recoil,
                        max(0.0, t_pad - recoil) + row_s if moving else 0.0,
                        dyn.ramp_time(q_open, qd, load) if moving else 0.0, t_pad, J @ qd_c,
                        v_rel, F, ratio, cone, shares=shares)
        if not moving:
            return stop
        if ask.per_joint is not JointRamps.NONE:
            stop = with_joint_ramps(dyn, stop, q_open, load, STOP_SHARE)
        # how much slower each joint must go: its travel grows with its speed (the ramps'
        # durations are set by the joint that needs the longest), the ramp-in's time too
        scale = np.ones(len(arm))
        for off in (stop.first_offset, stop.last_offset):
            e = q_open[arm] + off
            room = np.where(off < 0, q_open[arm] - lo, hi - q_open[arm])
            over = (e < lo) | (e > hi)
            scale[over] = np.minimum(scale[over], np.maximum(room[over], 0.0)
                                     / np.abs(off[over]))
        pre = q_open.copy()
        pre[arm] += stop.first_offset
        finite = math.isfinite(stop.ramp_in_s) and math.isfinite(stop.ramp_out_s)
        late = ready_by(pre) - stop.start_s if finite else math.inf
        if late <= 0 and (scale >= 1.0).all():
            return stop
        if late > 0:  # every joint slower, its ramp shorter by the time missing
            scale = np.minimum(scale, max(0.0, 1.0 - late / max(stop.ramp_in_s, 1e-9))
                               if finite else 0.0)
        bound = np.where(scale < 1.0, _SHRINK * scale * np.abs(qd), bound)
        if not (bound > _MIN_SPEED * dyn.v_max).any():
            break
    return None


def _at_rest(t_i: float, tilt_rad: float, arm: list[int], v_rel, F, ratio, cone,
             t_pad: float) -> SoftStop:
    """A palm waiting at rest (no stopping motion)."""
    z = np.zeros(len(arm))
    return SoftStop(tilt_rad, tuple(arm), z, 1.0, float(t_i), 0.0, 0.0, 0.0, 0.0, 0.0, t_pad,
                    z.copy(), v_rel, F, ratio, cone)
