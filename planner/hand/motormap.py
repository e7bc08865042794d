"""The hand's motors and the drives between them and the joints.

Each motor drives one independent joint (``Actuator.drives``); the joints coupled to it
follow. A linear drive's motor angle is ``q_motor = C q`` (``Actuator.coefficients``:
rad per rad, rad per m for a rig axis); an Mk5 motor's follows the seed's tables. Built
once per hand (``HandModel.motor_map``); ``HandModel`` answers ``motor_angles``,
``motor_ratio``, ``motor_velocities`` and ``motor_torques`` through it.
"""

from __future__ import annotations

import numpy as np

from planner.hand.couplings import CouplingMap


class MotorMap:
    """The motor map of a hand: ``actuators`` (the hand file's), the joint each drives
    (``drive``) and the linear map ``C`` (n_motor, n) from joint to motor angles."""

    def __init__(self, actuators, index: dict[str, int], coupling_map: CouplingMap) -> None:
        self.actuators = actuators
        self.coupling_map = coupling_map
        n = coupling_map.n
        self.motor_names = tuple(a.name for a in actuators)
        self.n_motor = len(actuators)
        self.motor_speed = np.array([a.speed_rad_s for a in actuators])
        self.motor_peak_torque = np.array([a.peak_torque_nm for a in actuators])
        self.drive = np.array([index[a.drives] for a in actuators])
        C = np.zeros((self.n_motor, n))
        for m, a in enumerate(actuators):
            for jn, c in a.coefficients:
                C[m, index[jn]] = c
        self.C = C
        col = {int(j): k for k, j in enumerate(coupling_map.independent)}
        self._drive_col = [col[int(d)] for d in self.drive]
        self._efficiency = [a.efficiency for a in actuators]
        self._index = index
        # (every law linear, no Mk5 motor: ``dq_dindependent`` and ``motor_ratio`` are the
        # same at every q whose coupling sources are finite; found once, ``_of``)
        self.fixed = None
        if coupling_map.all_linear and all(a.mk5 is None for a in actuators):
            self.fixed = self._at(np.zeros(n))
            for a in (*self.fixed[0], self.fixed[1]):
                a.setflags(write=False)

    def motor_angles(self, q: np.ndarray) -> np.ndarray:
        """Motor shaft angles (rad) for joint positions ``q``; works on (..., n) arrays."""
        q = np.asarray(q, dtype=float)
        qm = q @ self.C.T
        for m, a in enumerate(self.actuators):
            if a.mk5 is not None:
                from planner.hand import mk5
                from planner.hand.mk5_tables import MK5_TABLES  # (an Mk5 hand's only)

                qm[..., m] = mk5.qmot_of_q1(MK5_TABLES[a.mk5.table][a.mk5.finger],
                                            q[..., self._index[a.mk5.source]])
        return qm

    def motor_sensitivity(self, q: np.ndarray, step: float = 1e-4) -> np.ndarray:
        """Per row of ``q`` (T, n) and motor: the sum over joints of |d q_motor / d q_j|
        (how far a motor's angle moves when every joint moves by one unit): the rows of
        the linear transmissions' matrix, and finite differences of ``step`` where a
        motor's law is not linear (the Mk5's)."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        out = np.tile(np.abs(self.C).sum(axis=1), (len(q), 1))
        nonlinear = [m for m, a in enumerate(self.actuators) if a.mk5 is not None]
        if nonlinear:
            qm = self.motor_angles(q)
            fd = np.zeros_like(qm)
            for j in range(q.shape[1]):
                qp = q.copy()
                qp[:, j] += step
                fd += np.abs(self.motor_angles(qp) - qm) / step
            out[:, nonlinear] = fd[:, nonlinear]
        return out

    def _at(self, q: np.ndarray) -> tuple[list[np.ndarray], np.ndarray]:
        """(each motor's column of ``dq_dindependent(q)``, ``motor_ratio(q)``), computed."""
        S = self.coupling_map.dq_dindependent(q)
        return [S[:, c] for c in self._drive_col], self._ratio(q, S)

    def _of(self, q: np.ndarray) -> tuple[list[np.ndarray], np.ndarray]:
        """``_at(q)``; for a hand whose laws are all linear the one found at set-up (a
        linear law's slope is its ratio at every finite source: the same numbers, so the
        same arithmetic on them gives the same bits)."""
        if self.fixed is not None and np.isfinite(q[self.coupling_map.sources]).all():
            return self.fixed
        return self._at(q)

    def key(self, q: np.ndarray) -> bytes:
        """What ``motor_torques`` and ``motor_ratio`` read of ``q``: at two poses of equal
        keys they are the same functions, bit for bit (an all-linear hand's: one key at
        every pose whose coupling sources are finite; else the whole pose)."""
        q = np.asarray(q, dtype=float)
        if self.fixed is not None and np.isfinite(q[self.coupling_map.sources]).all():
            return b"fixed"
        return q.tobytes()

    def motor_ratio(self, q: np.ndarray) -> np.ndarray:
        """dq_motor / dq_drive for each motor (rad per rad of its driven joint) at ``q``."""
        return self._of(np.asarray(q, dtype=float))[1].copy()

    def _ratio(self, q: np.ndarray, S: np.ndarray) -> np.ndarray:
        """``motor_ratio`` with ``S = dq_dindependent(q)``."""
        r = np.empty(self.n_motor)
        for m, a in enumerate(self.actuators):
            if a.mk5 is not None:
                from planner.hand import mk5
                from planner.hand.mk5_tables import MK5_TABLES  # (an Mk5 hand's only)

                p = MK5_TABLES[a.mk5.table][a.mk5.finger]
                r[m] = mk5.dqmot_dq1(p, q[self.drive[m]])
            else:
                r[m] = float(self.C[m] @ S[:, self._drive_col[m]])
        return r

    def motor_velocities(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """Motor shaft speeds (rad/s) for joint speeds ``qd`` at ``q`` (couplings respected)."""
        return self.motor_ratio(q) * qd[self.drive]

    def motor_torques(self, q: np.ndarray, tau_joint: np.ndarray) -> np.ndarray:
        """Motor torques (N m) that supply joint torques ``tau_joint`` by virtual work.

        ``tau_m = (dq/dq_m)^T tau_joint / efficiency`` where ``dq/dq_m`` moves
        the motor's driven joint and every joint coupled to it.
        """
        cols, ratio = self._of(np.asarray(q, dtype=float))
        out = np.empty(self.n_motor)
        for m, (dq_ddrive, eff) in enumerate(zip(cols, self._efficiency)):
            out[m] = float(dq_ddrive @ tau_joint) / ratio[m] / eff
        return out
