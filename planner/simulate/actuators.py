"""The motors of the replay: one position servo per motor of the hand's actuator model,
on the joint it drives, limited to the torque that motor gives through its transmission.

* Torque limit. A motor of peak torque ``tau_m`` moving its driven joint through the
  transmission ratio ``r = dq_motor/dq_joint`` (``HandModel.motor_ratio``: spool and
  moment arms, gears, belt, the coupled joints included) at efficiency ``eta`` gives the
  joint ``tau_m r eta`` (by virtual work, as ``HandModel.motor_torques`` maps torques
  back): the servo's force range, updated every row (the Mk5 law's ratio varies with q).
  A coupled joint (DIP = k PIP) gets its torque through the equality constraint, so the
  servo's generalised force on the coupled pair is what the motor gives.
* Reflected rotor inertia (armature) ``J r^2``: ``J`` is the motor's rotor inertia as
  its hand file gives it (``Actuator.rotor_inertia_kg_m2``; the seed's Faulhaber 3564 B,
  34.9 g cm^2, for the tendon motors and the AGH's end joints, its 4490 B, 130 g cm^2,
  for the wrist, the rail and the AGH's shafts); the splay servos' gearing is not
  documented: no armature. (Until session 29 ``J`` came from the actuator's kind, and
  the AGH's geared 3564 B end motors got the 4490 B's rotor: 3.7x their inertia.)
* Gains. Stiffness: the servo reaches its motor's peak torque at ``MOTOR_ERROR_AT_PEAK_RAD``
  of motor-shaft error (a design choice of the replay's controller, not of the plan:
  ``kp = tau_m eta r^2 / e``). Damping: critical for the joint's own inertia (its
  diagonal of the mass matrix at the neutral pose, armature included).
* Control law (PD with feedforward, what a joint servo with a model runs):
  ``force = kp (q_ref - q) + kv (qd_ref - qd) + tau_ff``, clamped to the force range;
  ``qd_ref`` and ``qdd_ref`` are the rows' central differences, ``tau_ff`` the inverse
  dynamics of the rows (``M(q_ref) qdd_ref + c(q_ref, qd_ref)``: inertia, rotor
  inertia, Coriolis and gravity) on the driven joint and its coupled joints. Without
  the inertia term (the first version: gravity only) the servos make each joint's
  acceleration from a lag: the catch's closing (30 deg / 1.5 m) tracked its wrist to
  0.79 deg, 0.21 deg with it. It is realised
  through MuJoCo's position-servo form (``ctrl = q_ref + kv/kp qd_ref + tau_ff/kp``)
  so that the damping is integrated implicitly. The control moves linearly from one row's value to the next
  (a speed reference held constant over a row would jump by a*dt at every row: 0.4 m/s
  on the rail at 40 m/s^2, a 770 N step through its damping).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from planner.hand.model import HandModel

MOTOR_ERROR_AT_PEAK_RAD = 0.06  # motor-shaft error (3.4 deg) at which a servo gives its peak
DAMPING_RATIO = 1.0  # critical


@dataclass(frozen=True)
class ServoSet:
    """The servos of a hand: per motor, its driven joint (index into the hand's joints),
    transmission ratio, efficiency and peak torque at the neutral pose, armature."""

    names: tuple[str, ...]
    drive: np.ndarray  # (n_motor,) joint index
    ratio: np.ndarray  # (n_motor,) dq_motor / dq_joint at the neutral pose
    efficiency: np.ndarray
    peak_torque_nm: np.ndarray
    armature: np.ndarray  # (n_motor,) kg m^2 (kg for the rail) on the driven joint
    kp: np.ndarray  # (n_motor,) N m/rad (N/m for the rail)

    def force_limit(self, ratio: np.ndarray) -> np.ndarray:
        """Joint-side force range of every servo at transmission ``ratio`` (n_motor,)."""
        return self.peak_torque_nm * np.abs(ratio) * self.efficiency


def servo_set(hand: HandModel) -> ServoSet:
    ratio = np.abs(hand.motor_ratio(hand.q_neutral))
    eff = np.array([a.efficiency for a in hand.actuators])
    peak = np.array(hand.motor_peak_torque, dtype=float)
    arm = np.array([a.rotor_inertia_kg_m2 for a in hand.actuators]) * ratio ** 2
    kp = peak * eff * ratio ** 2 / MOTOR_ERROR_AT_PEAK_RAD
    return ServoSet(hand.motor_names, np.array(hand.motor_map.drive), ratio, eff, peak, arm, kp)


def joined_servos(sets: list[ServoSet], prefixes: list[str], n_joints: list[int]) -> ServoSet:
    """The servos of a scene's hands as one set (one hand: its own): names prefixed,
    each driven joint's index into the hands' joints in order."""
    if len(sets) == 1:
        return sets[0]
    offset = np.cumsum([0, *n_joints[:-1]])
    return ServoSet(tuple(p + n for s, p in zip(sets, prefixes) for n in s.names),
                    np.concatenate([s.drive + o for s, o in zip(sets, offset)]),
                    *(np.concatenate([getattr(s, f) for s in sets])
                      for f in ("ratio", "efficiency", "peak_torque_nm", "armature", "kp")))


def critical_damping(kp: np.ndarray, inertia: np.ndarray) -> np.ndarray:
    """``kv = 2 zeta sqrt(kp I)`` for each servo."""
    return 2.0 * DAMPING_RATIO * np.sqrt(kp * inertia)


class Transmission:
    """``HandModel.dq_dindependent`` and ``motor_ratio`` at many poses, each computed once
    per distinct value of the joints they read: a nonlinear coupling's source joint and
    an Mk5 motor's driven joint (a linear coupling's slope, a mimic's ratio, reads none:
    for such a hand one computation serves every row). The same functions on the same
    numbers: the results are the hand's own, bit for bit (tests/test_simulate_speed.py);
    the replay's rows cost 0.2 ms each less (a fifth of a 10 s song's replay)."""

    def __init__(self, hand: HandModel) -> None:
        self.hand = hand
        reads = {int(c.src) for c in hand.couplings if c.kind != "linear"}
        reads |= {int(hand.motor_map.drive[m]) for m, a in enumerate(hand.actuators)
                  if a.mk5 is not None}
        self._reads = np.array(sorted(reads), dtype=int)
        col = {int(j): k for k, j in enumerate(hand.independent)}
        self._cols = [col[int(d)] for d in hand.motor_map.drive]
        self._eff = [a.efficiency for a in hand.actuators]
        self._cache: dict[bytes, tuple] = {}

    def at(self, q: np.ndarray) -> tuple[list[np.ndarray], np.ndarray]:
        """(each motor's column of ``dq_dindependent(q)``: the joints moving with its
        driven joint, per unit of it; ``motor_ratio(q)``)."""
        key = np.asarray(q, dtype=float)[self._reads].tobytes()
        hit = self._cache.get(key)
        if hit is None:
            S = self.hand.dq_dindependent(q)
            hit = ([S[:, c] for c in self._cols], self.hand.motor_ratio(q))
            self._cache[key] = hit
        return hit

    def servo_motor_torques(self, q: np.ndarray, force: np.ndarray,
                            drive: np.ndarray) -> np.ndarray:
        """(T, n_motor) ``motor_torques`` of rows ``q`` (T, n) whose joint torques are
        the servos' ``force`` (T, n_motor) on their driven joints ``drive``. Where the
        transmission reads no joint and each motor's column meets one driven joint
        only, ``c @ tau`` is one product ``c[d] tau[d]`` (the other terms exact zeros):
        all the rows at once, the same numbers (``+ 0.0``: a zero's sign as the sum's);
        else row by row."""
        T = len(q)
        out = np.empty((T, len(self._cols)))
        if T and not len(self._reads):
            cols, ratio = self.at(q[0])
            hits = [np.flatnonzero(c[drive] != 0.0) for c in cols]
            if all(len(h) == 1 for h in hits):
                for m, (c, h) in enumerate(zip(cols, hits)):
                    j = int(h[0])
                    out[:, m] = (c[drive[j]] * force[:, j] + 0.0) / ratio[m] / self._eff[m]
                return out
        tau = np.zeros(self.hand.n)
        for k in range(T):
            tau[drive] = force[k]
            out[k] = self.motor_torques(q[k], tau)
        return out

    def motor_torques(self, q: np.ndarray, tau_joint: np.ndarray) -> np.ndarray:
        """``HandModel.motor_torques(q, tau_joint)``, its arithmetic in its order."""
        cols, ratio = self.at(q)
        out = np.empty(len(cols))
        for m, c in enumerate(cols):
            out[m] = float(c @ tau_joint) / ratio[m] / self._eff[m]
        return out


@dataclass(frozen=True)
class Reference:
    """The servos' reference, row by row: what each servo is asked for."""

    q_rad: np.ndarray  # (T, n_motor) driven joints' positions (m for the rail)
    qd_rad_s: np.ndarray  # (T, n_motor) their speeds (central differences of the rows)
    feedforward_nm: np.ndarray  # (T, n_motor) inverse dynamics of the rows on each servo
    ratio: np.ndarray  # (T, n_motor) transmission ratio at the row's pose


def reference(hand: HandModel, q: np.ndarray, t_s: np.ndarray,
              inverse_dynamics: Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]
              | None = None) -> Reference:
    """The servo reference of trajectory rows ``q`` (T, n) at times ``t_s`` (the hand
    mounted as the file says: ``hand`` is ``HandModel.mounted`` for a catch).

    ``inverse_dynamics(q, qd, qdd)``: the hand's generalised forces (n,) that move it
    along the rows (the scene's ``M(q) qdd + c(q, qd)``, gravity and the rotor
    inertia included); without it, gravity alone (``HandModel.gravity_torques``). A
    servo's feedforward is that force on its driven joint and the joints coupled to it
    (``S^T tau``, ``S`` = ``HandModel.dq_dindependent``)."""
    tr = Transmission(hand)
    many = len(t_s) > 2
    qd = np.gradient(q, t_s, axis=0) if many else np.zeros_like(q)
    qdd = np.gradient(qd, t_s, axis=0) if many else np.zeros_like(q)
    ff = np.empty((len(q), hand.n_motor))
    ratio = np.empty((len(q), hand.n_motor))
    done: dict[bytes, tuple] = {}  # (a held pose repeats its row: 1/3-1/2 of a song's)
    for i, row in enumerate(q):
        key = row.tobytes() + qd[i].tobytes() + qdd[i].tobytes()
        hit = done.get(key)
        if hit is None:
            tau = (hand.gravity_torques(row) if inverse_dynamics is None
                   else inverse_dynamics(row, qd[i], qdd[i]))
            cols, r = tr.at(row)
            hit = done[key] = ([float(c @ tau) for c in cols], np.abs(r))
        ff[i], ratio[i] = hit
    drive = np.array(hand.motor_map.drive)
    return Reference(q[:, drive], qd[:, drive], ff, ratio)


def motor_torques_nm(hand: HandModel, q: np.ndarray, force: np.ndarray) -> np.ndarray:
    """Motor torques (N m) behind servo forces ``force`` (n_motor,) on the driven joints
    at ``q``: ``HandModel.motor_torques`` of those joint torques."""
    tau = np.zeros(hand.n)
    tau[np.array(hand.motor_map.drive)] = force
    return hand.motor_torques(q, tau)
