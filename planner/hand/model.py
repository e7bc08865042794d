"""The hand model the whole planner shares: URDF, Pinocchio kinematics,
limits, coupling laws and the actuator model.

Built once per run (``load_hand``) and passed down. Joint vectors ``q`` are in
the hand's joint order (``HandModel.joint_names``: the URDF's movable joints
in file order), SI units (rad, m). The IK (placo) and the independent check
both read limits, couplings and actuators from here, never from a copy.

The model holds the joints, their limits and the Pinocchio kinematics; its couplings
(``planner.hand.couplings``) and its motors and drives (``planner.hand.motormap``)
are objects of their own that it builds at set-up and answers through.
"""

from __future__ import annotations

import copy
from functools import lru_cache

import numpy as np
import pinocchio as pin

from planner.errors import InputError
from planner.hand.builders import load_hand_spec
from planner.hand.couplings import CouplingLaw, CouplingMap
from planner.hand.motormap import MotorMap
from planner.hand.pad import pad_give_m
from planner.hand.spec import PALM_FRAME, HandSpec
from planner.hand.urdf import urdf_sha256, urdf_text

GRAVITY_WORLD = np.array([0.0, 0.0, -9.81])


class HandModel:
    """A loaded hand: kinematics (Pinocchio), limits, couplings and actuators."""

    def __init__(self, spec: HandSpec) -> None:
        self.spec = spec
        self.name = spec.name
        self.urdf = urdf_text(spec)
        self.urdf_sha256 = urdf_sha256(self.urdf)
        mov = spec.movable_joints
        self.joint_names: tuple[str, ...] = tuple(j.name for j in mov)
        self.index = {n: i for i, n in enumerate(self.joint_names)}
        # the rig's axes (rail along the keyboard, reach towards the player): metres
        self.rig_joints: tuple[str, ...] = tuple(j.name for j in mov if j.kind == "prismatic")
        self.n = len(mov)
        self.lower = np.array([j.lower for j in mov])
        self.upper = np.array([j.upper for j in mov])
        self.velocity = np.array([j.velocity for j in mov])
        self.acceleration = np.array([j.acceleration for j in mov])
        self.jerk = np.array([j.jerk for j in mov])  # (planner.hand.drive)
        # the planner's limits: the hard stops less each joint's margin (``check`` counts
        # the rows beyond them, ``joint_stop_margin``; the guard refuses only past a stop)
        self.stop_margin = np.array([j.stop_margin for j in mov])
        self.plan_lower = self.lower + self.stop_margin
        self.plan_upper = self.upper - self.stop_margin
        self.T_world_root = np.array(spec.T_world_root, dtype=float)

        self.pin_model = pin.buildModelFromXML(self.urdf)
        self.pin_model.gravity.linear = self.T_world_root[:3, :3].T @ GRAVITY_WORLD
        self.pin_data = self.pin_model.createData()
        # our order -> pinocchio's q index
        self._pin_idx = np.array(
            [self.pin_model.idx_qs[self.pin_model.getJointId(n)] for n in self.joint_names]
        )
        self.tip_frames = spec.tip_frames
        # the hand's fingers (a prefix of FINGERS, in that order: five, or the AGH's four)
        self.fingers: tuple[str, ...] = tuple(f for f, _ in spec.finger_joints)
        # which hand (``planner.hand.mirror``), and its fingers in the order of the keys
        # they play, the lowest first: a right hand's thumb is on its bass side, a left
        # hand's (its mirror image) on its treble side
        self.side = spec.side
        # the palm's pad: the give (m) the catch planner and ``check`` stop a ball over,
        # and the pad the replay's palm-ball contact is made of (``planner.hand.pad``)
        self.palm_pad = spec.palm_pad
        self.pad_give_m = pad_give_m(spec.palm_pad)
        self.fingers_low_to_high: tuple[str, ...] = (
            self.fingers if self.side == "right" else self.fingers[::-1])
        self._tip_ids = [self.pin_model.getFrameId(f) for f in self.tip_frames]
        self._palm_id = self.pin_model.getFrameId(PALM_FRAME)

        # couplings (``planner.hand.couplings``), motors and drives (``planner.hand.motormap``)
        self.coupling_map = CouplingMap(spec.couplings, self.index, self.n)
        self.couplings: tuple[CouplingLaw, ...] = self.coupling_map.laws
        self.independent = self.coupling_map.independent
        self.dependent = self.coupling_map.dependent
        self.motor_map = MotorMap(spec.actuators, self.index, self.coupling_map)
        self.actuators = spec.actuators
        self.motor_names = self.motor_map.motor_names
        self.n_motor = self.motor_map.n_motor
        self.motor_speed = self.motor_map.motor_speed
        self.motor_peak_torque = self.motor_map.motor_peak_torque

        lo = np.where(np.isfinite(self.lower), self.lower, -1.0)
        hi = np.where(np.isfinite(self.upper), self.upper, 1.0)
        self.q_neutral = self.apply_couplings(np.clip(np.zeros(self.n), lo, hi))

    def mounted(self, T_world_root: np.ndarray) -> HandModel:
        """The same hand with its root at another pose in the world (4x4), e.g. the catch frame.

        Shares the spec, URDF and Pinocchio model; has its own data and gravity."""
        other = copy.copy(self)
        other.T_world_root = np.array(T_world_root, dtype=float)
        other.pin_model = self.pin_model.copy()
        other.pin_model.gravity.linear = other.T_world_root[:3, :3].T @ GRAVITY_WORLD
        other.pin_data = other.pin_model.createData()
        return other

    def within_margins(self) -> HandModel:
        """The same hand whose limits are its planner's (``plan_lower``, ``plan_upper``:
        the hard stops less each joint's stop margin), its margins then 0: a planner that
        keeps its rows within ``lower``/``upper`` of this hand keeps every joint its stop
        margin inside its hard stops (the catch planner). Shares the spec, URDF, Pinocchio
        model and data."""
        other = copy.copy(self)
        other.lower, other.upper = self.plan_lower.copy(), self.plan_upper.copy()
        other.plan_lower, other.plan_upper = other.lower, other.upper
        other.stop_margin = np.zeros_like(self.stop_margin)
        return other

    # ------------------------------------------------------------ joints
    def joint_slice(self, finger: str) -> np.ndarray:
        """Indices of a finger's joints (thumb: cmc_abd, cmc_flex, ip; others: abd, mcp, pip, dip)."""
        return np.array([self.index[j] for j in self.spec.joints_of(finger)])

    def own_independent(self, finger: str) -> list[int]:
        """The finger's joints that no coupling drives: its degrees of freedom (one for
        the Mk5's fingers, and for the AGH's whose base follows another finger's)."""
        dep = set(self.dependent.tolist())
        return [int(j) for j in self.joint_slice(finger) if int(j) not in dep]

    def apply_couplings(self, q: np.ndarray) -> np.ndarray:
        """A copy of ``q`` with every dependent joint set from its source."""
        return self.coupling_map.apply(q)

    def coupling_errors(self, q: np.ndarray) -> np.ndarray:
        """``q[dep] - f(q[src])`` for every coupling (rad); shape (..., n_couplings)."""
        return self.coupling_map.errors(q)

    def coupling_jacobian(self, q: np.ndarray) -> np.ndarray:
        """d(coupling_errors)/dq, shape (n_couplings, n)."""
        return self.coupling_map.jacobian(q)

    def dq_dindependent(self, q: np.ndarray) -> np.ndarray:
        """Map from independent joint velocities to all joint velocities, (n, n_independent)."""
        return self.coupling_map.dq_dindependent(q)

    # ------------------------------------------------------------ kinematics
    def pin_q(self, q: np.ndarray) -> np.ndarray:
        """Pinocchio's configuration vector (nq,) of ``q`` (the hand's joint order)."""
        qp = np.zeros(self.pin_model.nq)
        qp[self._pin_idx] = q
        return qp

    def update_frames(self, q: np.ndarray) -> None:
        """Every frame's placement at ``q`` in ``pin_data`` (``oMf``)."""
        pin.framesForwardKinematics(self.pin_model, self.pin_data, self.pin_q(q))

    def tip_position(self, q: np.ndarray, finger: int) -> np.ndarray:
        """World position of one fingertip pad point (index in ``FINGERS``), m."""
        pin.forwardKinematics(self.pin_model, self.pin_data, self.pin_q(q))
        p = pin.updateFramePlacement(self.pin_model, self.pin_data, self._tip_ids[finger]).translation
        return self.T_world_root[:3, :3] @ p + self.T_world_root[:3, 3]

    def tip_positions(self, q: np.ndarray) -> np.ndarray:
        """World positions of the five fingertip pad points, (5, 3) in m, order ``FINGERS``."""
        # joint placements, then only the five tip frames (twice as fast as every frame)
        pin.forwardKinematics(self.pin_model, self.pin_data, self.pin_q(q))
        m, d = self.pin_model, self.pin_data
        tips = np.array([pin.updateFramePlacement(m, d, i).translation for i in self._tip_ids])
        return tips @ self.T_world_root[:3, :3].T + self.T_world_root[:3, 3]

    def frame_pose(self, q: np.ndarray, frame: str) -> np.ndarray:
        """4x4 world pose of a URDF frame."""
        self.update_frames(q)
        return self.T_world_root @ self.pin_data.oMf[self.pin_model.getFrameId(frame)].homogeneous

    def palm_pose(self, q: np.ndarray) -> np.ndarray:
        return self.frame_pose(q, PALM_FRAME)

    def palm_poses(self, Q: np.ndarray) -> np.ndarray:
        """``palm_pose`` of each row of ``Q``, (K, 4, 4): the joints' placements and the
        palm frame's alone (the same numbers; the other frames' in ``pin_data`` are left
        as they were)."""
        m, d = self.pin_model, self.pin_data
        out = np.empty((len(Q), 4, 4))
        for k, q in enumerate(Q):
            pin.forwardKinematics(m, d, self.pin_q(q))
            out[k] = self.T_world_root @ pin.updateFramePlacement(m, d, self._palm_id).homogeneous
        return out

    def tip_jacobians(self, q: np.ndarray) -> np.ndarray:
        """World-frame position Jacobians of the fingertips, (5, 3, n) in our joint order."""
        pin.computeJointJacobians(self.pin_model, self.pin_data, self.pin_q(q))
        pin.updateFramePlacements(self.pin_model, self.pin_data)
        R = self.T_world_root[:3, :3]
        out = np.empty((len(self._tip_ids), 3, self.n))
        for k, fid in enumerate(self._tip_ids):
            J = pin.getFrameJacobian(self.pin_model, self.pin_data, fid,
                                     pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
            out[k] = R @ J[:3, self.pin_v_idx]
        return out

    @property
    def pin_v_idx(self) -> np.ndarray:
        """Each of the hand's joints' index in Pinocchio's velocity vector."""
        return self._pin_idx  # all joints are 1-DOF: idx_q == idx_v

    def gravity_torques(self, q: np.ndarray) -> np.ndarray:
        """Joint torques holding the hand still against gravity (N m, N for the rail)."""
        g = pin.computeGeneralizedGravity(self.pin_model, self.pin_data, self.pin_q(q))
        return g[self._pin_idx]

    def within_limits(self, q: np.ndarray, tol: float = 1e-9) -> bool:
        return bool(np.all(q >= self.lower - tol) and np.all(q <= self.upper + tol))

    def within_plan_limits(self, q: np.ndarray, tol: float = 1e-9) -> bool:
        """Within the hard stops less their margins (``plan_lower``, ``plan_upper``)."""
        return bool(np.all(q >= self.plan_lower - tol) and np.all(q <= self.plan_upper + tol))

    # ------------------------------------------------------------ actuators
    def motor_angles(self, q: np.ndarray) -> np.ndarray:
        """Motor shaft angles (rad) for joint positions ``q``; works on (..., n) arrays."""
        return self.motor_map.motor_angles(q)

    def motor_sensitivity(self, q: np.ndarray, step: float = 1e-4) -> np.ndarray:
        """Per row of ``q`` (T, n) and motor: the sum over joints of |d q_motor / d q_j|
        (``MotorMap.motor_sensitivity``)."""
        return self.motor_map.motor_sensitivity(q, step)

    def transmission_key(self, q: np.ndarray) -> bytes:
        """What ``motor_torques`` and ``motor_ratio`` read of ``q``: at two poses of equal
        keys they are the same functions, bit for bit (``MotorMap.key``)."""
        return self.motor_map.key(q)

    def motor_ratio(self, q: np.ndarray) -> np.ndarray:
        """dq_motor / dq_drive for each motor (rad per rad of its driven joint) at ``q``."""
        return self.motor_map.motor_ratio(q)

    def motor_velocities(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """Motor shaft speeds (rad/s) for joint speeds ``qd`` at ``q`` (couplings respected)."""
        return self.motor_map.motor_velocities(q, qd)

    def motor_torques(self, q: np.ndarray, tau_joint: np.ndarray) -> np.ndarray:
        """Motor torques (N m) that supply joint torques ``tau_joint`` by virtual work
        (``MotorMap.motor_torques``)."""
        return self.motor_map.motor_torques(q, tau_joint)

    def press_torques(self, q: np.ndarray, forces_n: dict[str, float]) -> np.ndarray:
        """Motor torques (N m) holding ``q`` against gravity while the named
        fingertips push down on keys with the given forces (N)."""
        tau = self.gravity_torques(q)
        J = self.tip_jacobians(q)
        for f, F in forces_n.items():
            # the key pushes the fingertip up with F: the joints must resist it
            tau = tau - J[self.fingers.index(f)].T @ np.array([0.0, 0.0, F])
        return self.motor_torques(q, tau)


@lru_cache(maxsize=8)
def load_hand(name: str = "default") -> HandModel:
    """The hand model of a shipped hand name or a hand file path (cached per process)."""
    try:
        return HandModel(load_hand_spec(name))
    except InputError:
        raise
    except (ValueError, RuntimeError) as e:  # pinocchio refuses the generated URDF
        raise InputError(f"hand {name!r} cannot be built: {e}") from None
