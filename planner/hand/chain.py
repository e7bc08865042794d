"""Forward kinematics of one frame for many configurations at once (numpy).

Pinocchio computes one configuration per call; checking a straight move at a dozen
points along it costs a dozen calls from Python, each mostly call overhead. A
``FrameChain`` walks the frame's chain of joints from the model's root once (their
placements, kinds and axes) and then carries a whole batch of configurations down it
with array operations: the same products of rigid transforms, to rounding.
"""

from __future__ import annotations

import numpy as np

from planner.hand.model import HandModel

_AXES = {"X": (1.0, 0.0, 0.0), "Y": (0.0, 1.0, 0.0), "Z": (0.0, 0.0, 1.0)}


class FrameChain:
    """The world position of frame ``frame`` of ``hand`` (and of points fixed in it) as a
    function of its joints."""

    def __init__(self, hand: HandModel, frame: str) -> None:
        m = hand.pin_model
        fid = m.getFrameId(frame)
        if fid >= len(m.frames):
            raise ValueError(f"hand {hand.name!r} has no frame {frame!r}")
        ours = {m.idx_qs[m.getJointId(n)]: i for i, n in enumerate(hand.joint_names)}
        self.joints = []  # (our joint index or None, prismatic?, axis, R, t), root first
        j = m.frames[fid].parentJoint
        while j > 0:
            self.joints.append(self._joint(m, j, ours))
            j = m.parents[j]
        self.joints.reverse()
        placement = m.frames[fid].placement
        self.tip = np.array(placement.translation, dtype=float)
        self.R_frame = np.array(placement.rotation, dtype=float)
        self.T_world_root = np.array(hand.T_world_root, dtype=float)

    @staticmethod
    def _joint(m, j: int, ours: dict[int, int]):
        jm = m.joints[j]
        kind = jm.shortname().removeprefix("JointModel")
        if kind in ("RevoluteUnaligned", "PrismaticUnaligned"):
            axis = np.array(jm.extract().axis, dtype=float)
            prismatic = kind.startswith("Prismatic")
        elif len(kind) == 2 and kind[0] in "RP" and kind[1] in _AXES:
            axis = np.array(_AXES[kind[1]])
            prismatic = kind[0] == "P"
        else:
            raise ValueError(f"joint {m.names[j]!r}: {jm.shortname()} is not a revolute or "
                             "prismatic joint")
        if jm.nq != 1:
            raise ValueError(f"joint {m.names[j]!r} has {jm.nq} coordinates")
        M = m.jointPlacements[j]
        return (ours.get(m.idx_qs[j]), prismatic, axis, np.array(M.rotation, dtype=float),
                np.array(M.translation, dtype=float))

    def positions(self, Q: np.ndarray) -> np.ndarray:
        """World positions (N, 3) of the frame at configurations ``Q`` (N, n), in the
        hand's joint order with its couplings applied."""
        Q = np.atleast_2d(np.asarray(Q, dtype=float))
        return self._carry(Q, np.broadcast_to(self.tip, (len(Q), 3)).copy(), 1)

    def points(self, Q: np.ndarray, local_m: np.ndarray) -> np.ndarray:
        """World positions (N, m, 3) of points ``local_m`` (m, 3) fixed in the frame, at
        configurations ``Q`` (N, n) as in ``positions``."""
        Q = np.atleast_2d(np.asarray(Q, dtype=float))
        local = np.asarray(local_m, dtype=float) @ self.R_frame.T + self.tip
        p = np.broadcast_to(local, (len(Q),) + local.shape).reshape(-1, 3).copy()
        return self._carry(Q, p, len(local)).reshape(len(Q), len(local), 3)

    def _carry(self, Q: np.ndarray, p: np.ndarray, m: int) -> np.ndarray:
        """Points ``p`` (N m, 3; configuration k's in rows k m .. k m + m - 1) in the
        frame's parent joint, carried to the world through the chain."""
        for i, prismatic, k, R, t in reversed(self.joints):
            q = np.zeros(len(p)) if i is None else (Q[:, i] if m == 1 else np.repeat(Q[:, i], m))
            if prismatic:
                p = p + q[:, None] * k
            else:  # Rodrigues: p cos + (k x p) sin + k (k . p)(1 - cos)
                c, s = np.cos(q)[:, None], np.sin(q)[:, None]
                kxp = np.stack([k[1] * p[:, 2] - k[2] * p[:, 1], k[2] * p[:, 0] - k[0] * p[:, 2],
                                k[0] * p[:, 1] - k[1] * p[:, 0]], axis=1)
                p = p * c + kxp * s + (p @ k)[:, None] * k * (1.0 - c)
            p = p @ R.T + t
        T = self.T_world_root
        return p @ T[:3, :3].T + T[:3, 3]
