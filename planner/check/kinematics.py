"""Forward kinematics of the check: its own copy of the hand's Pinocchio model, with
the root where the file's metadata puts it (it never touches the planner's data)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from planner.check.criteria import key_contacts
from planner.hand.model import HandModel
from planner.hand.spec import PALM_FRAME
from planner.trajfile import distinct_rows

G = 9.81
GRAVITY = np.array([0.0, 0.0, -G])


class Kinematics:
    """A private Pinocchio model of the hand with the root at ``T_world_root``."""

    def __init__(self, hand: HandModel, T_world_root: np.ndarray) -> None:
        self.hand = hand
        self.T = np.asarray(T_world_root, dtype=float)
        self.R = self.T[:3, :3]
        self.p = self.T[:3, 3]
        self.model = hand.pin_model.copy()
        self.model.gravity.linear = self.R.T @ GRAVITY
        self.data = self.model.createData()
        m = self.model
        self.idx = np.array([m.idx_qs[m.getJointId(n)] for n in hand.joint_names])
        self.tip_ids = [m.getFrameId(f) for f in hand.tip_frames]
        self.palm_id = m.getFrameId(PALM_FRAME)

    def pin_q(self, q: np.ndarray) -> np.ndarray:
        qp = np.zeros(self.model.nq)
        qp[self.idx] = q
        return qp

    def frames(self, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World tips (T, 5, 3) and palm poses (T, 4, 4) of every row of ``Q``."""
        Q = np.atleast_2d(np.asarray(Q, dtype=float))
        # a row equal to the one before it has its frames (a hand holding still: once)
        new, of = distinct_rows(Q)
        tips, palm = self.frames_of(Q[new])
        return tips[of], palm[of]

    def tips(self, Q: np.ndarray) -> np.ndarray:
        """The world tips (T, 5, 3) of ``frames`` alone (no palm placed: the same tips)."""
        Q = np.atleast_2d(np.asarray(Q, dtype=float))
        new, of = distinct_rows(Q)
        return self.tips_of(Q[new])[of]

    def tips_of(self, U: np.ndarray) -> np.ndarray:
        """The tips of ``frames_of`` (rows already distinct)."""
        tips = np.empty((len(U), len(self.tip_ids), 3))
        QP = np.zeros((len(U), self.model.nq))
        QP[:, self.idx] = U
        m, d, tip_ids = self.model, self.data, self.tip_ids
        for k in range(len(U)):
            pin.forwardKinematics(m, d, QP[k])
            for j, f in enumerate(tip_ids):
                tips[k, j] = pin.updateFramePlacement(m, d, f).translation
        return tips @ self.R.T + self.p

    def frames_of(self, U: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``frames`` of every row of ``U`` (rows already distinct: each one computed)."""
        T = len(U)
        tips = np.empty((T, len(self.tip_ids), 3))
        palm = np.empty((T, 4, 4))
        QP = np.zeros((T, self.model.nq))
        QP[:, self.idx] = U
        m, d, tip_ids, palm_id = self.model, self.data, self.tip_ids, self.palm_id
        # (the joints' placements, then only the six frames read: the same products as
        # ``framesForwardKinematics``, which updates all of the model's frames; bit for
        # bit the same, in 60 % of its time)
        for k in range(T):
            pin.forwardKinematics(m, d, QP[k])
            for j, f in enumerate(tip_ids):
                tips[k, j] = pin.updateFramePlacement(m, d, f).translation
            palm[k] = pin.updateFramePlacement(m, d, palm_id).homogeneous
        tips = tips @ self.R.T + self.p
        palm = np.einsum("ij,tjk->tik", self.T, palm)
        return tips, palm

    def link_poses(self, Q: np.ndarray, links: tuple[str, ...]) -> dict[str, np.ndarray]:
        """World poses (T, 4, 4) of the frames of ``links`` at every row of ``Q`` (a row
        equal to the one before it computed once)."""
        Q = np.atleast_2d(np.asarray(Q, dtype=float))
        new, of = distinct_rows(Q)
        U = Q[new]
        m, d = self.model, self.data
        ids = [m.getFrameId(n) for n in links]
        out = np.empty((len(links), len(U), 4, 4))
        QP = np.zeros((len(U), m.nq))
        QP[:, self.idx] = U
        for k in range(len(U)):
            pin.forwardKinematics(m, d, QP[k])
            for i, f in enumerate(ids):
                out[i, k] = pin.updateFramePlacement(m, d, f).homogeneous
        out = np.einsum("ij,ltjk->ltik", self.T, out)
        return {n: out[i][of] for i, n in enumerate(links)}

    def gravity(self, q: np.ndarray) -> np.ndarray:
        return pin.computeGeneralizedGravity(self.model, self.data, self.pin_q(q))[self.idx]

    def gravities(self, Q: np.ndarray) -> np.ndarray:
        """``gravity`` of every row of ``Q`` (T, n); a row equal to the one before it
        computed once (the same numbers, row by row)."""
        Q = np.atleast_2d(np.asarray(Q, dtype=float))
        new, of = distinct_rows(Q)
        QP = np.zeros((int(np.count_nonzero(new)), self.model.nq))
        QP[:, self.idx] = Q[new]
        m, d, g = self.model, self.data, pin.computeGeneralizedGravity
        # (each row's vector kept whole, our joints picked from them all at once: the
        # same numbers)
        raw = [g(m, d, qp) for qp in QP]  # (fresh arrays: Pinocchio returns copies)
        return (np.array(raw)[:, self.idx] if raw else np.empty((0, self.hand.n)))[of]

    def moving(self, Q: np.ndarray, V: np.ndarray, A: np.ndarray, still: np.ndarray
               ) -> np.ndarray:
        """``inertial(q, v, a)`` of every row of ``Q, V, A`` given each row's
        ``gravity`` (``still``, ``gravities``): RNEA(q, v, a) less RNEA(q, 0, 0), which is
        the generalized gravity to the bit (the same recursion with the speeds and
        accelerations zero: every term they bring is a zero added; a test holds the two
        equal on every shipped hand)."""
        m, d, idx = self.model, self.data, self.idx
        QP = np.zeros((len(Q), m.nq))
        VP, AP = np.zeros((len(Q), m.nv)), np.zeros((len(Q), m.nv))
        QP[:, idx], VP[:, idx], AP[:, idx] = Q, V, A
        rnea = pin.rnea
        raw = [rnea(m, d, qp, vp, ap) for qp, vp, ap in zip(QP, VP, AP)]
        if not raw:
            return np.empty((0, self.hand.n))
        return np.array(raw)[:, idx] - still

    def inertial(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """Joint torques that move the hand at speeds ``v`` and accelerations ``a`` (our
        joint order), gravity apart: RNEA(q, v, a) - RNEA(q, 0, 0)."""
        qp, z = self.pin_q(q), np.zeros(self.model.nv)
        vp, ap = z.copy(), z.copy()
        vp[self.idx], ap[self.idx] = v, a
        return (pin.rnea(self.model, self.data, qp, vp, ap)
                - pin.rnea(self.model, self.data, qp, z, z))[self.idx]

    def inertials(self, q: np.ndarray, moves, gravity: np.ndarray | None = None
                  ) -> list[np.ndarray]:
        """``inertial(q, v, a)`` of each ``(v, a)`` of ``moves`` at one pose, RNEA(q, 0, 0)
        found once, or given (``gravity``: the pose's ``gravity``, the same numbers:
        ``moving``)."""
        qp, z = self.pin_q(q), np.zeros(self.model.nv)
        idx = self.idx
        still = pin.rnea(self.model, self.data, qp, z, z)[idx] if gravity is None else gravity
        out = []
        for v, a in moves:
            vp, ap = z.copy(), z.copy()
            vp[idx], ap[idx] = v, a
            out.append(pin.rnea(self.model, self.data, qp, vp, ap)[idx] - still)
        return out

    def tips_pushed(self, Q: np.ndarray, pressing: np.ndarray, force: np.ndarray,
                    tau: np.ndarray) -> None:
        """``tau[k] -= J.T @ force`` for each fingertip pressing in row ``k``
        (``pressing`` (T, 5)), ``J`` its ``point_jacobians``, tip by tip in order (the
        same numbers as a call of ``point_jacobians`` per row)."""
        m, d, idx, R, tip_ids = self.model, self.data, self.idx, self.R, self.tip_ids
        row, tip = np.nonzero(pressing)  # (each row's pressing tips in order)
        if len(row) == 0:
            return
        starts = np.flatnonzero(np.diff(row, prepend=-1))  # (each pressing row's first)
        QP = np.zeros((len(starts), m.nq))
        QP[:, idx] = Q[row[starts]]
        world = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        ends = np.append(starts[1:], len(row)).tolist()
        jac = pin.getFrameJacobian
        raw = []  # (the tips' Jacobians' position rows, in the pairs' order)
        for i, (a, b) in enumerate(zip(starts.tolist(), ends)):
            pin.computeJointJacobians(m, d, QP[i])
            raw += [jac(m, d, tip_ids[f], world)[:3] for f in tip[a:b].tolist()]
        # (the products of every pair at once, each pair's the same numbers as its own
        # ``R @ J`` and ``J.T @ force``: numpy's matmul takes a stack slice by slice; a
        # test holds them to the bit), then subtracted in each row's tip order
        J = R @ np.stack(raw)[:, :, idx]
        push = np.swapaxes(J, 1, 2) @ force
        rank = np.arange(len(row)) - np.repeat(starts, np.diff(np.append(starts, len(row))))
        for r in range(int(rank.max()) + 1):
            on = rank == r
            tau[row[on]] -= push[on]

    def point_jacobians(self, q: np.ndarray, frame_ids: list[int]) -> list[np.ndarray]:
        """World position Jacobians (3, n) of frames, our joint order."""
        pin.computeJointJacobians(self.model, self.data, self.pin_q(q))
        # (no ``updateFramePlacements``: ``getFrameJacobian`` places its frame itself, from
        # its joint's placement, the same product; the other frames are not read)
        out = []
        for fid in frame_ids:
            J = pin.getFrameJacobian(self.model, self.data, fid,
                                     pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
            out.append(self.R @ J[:3, self.idx])
        return out


def fk_frames(hand: HandModel, q: np.ndarray,
              T_world_root: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Forward kinematics of every row: fingertips (T, 5, 3) in ``FINGERS`` order
    and palm_center poses (T, 4, 4), in the world of ``T_world_root`` (default
    the hand's mount)."""
    T = hand.T_world_root if T_world_root is None else T_world_root
    return Kinematics(hand, T).frames(np.asarray(q, dtype=float))


def keys_down(hand: HandModel, t_s: np.ndarray, q: np.ndarray,
              T_world_root: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Keys down in each row of ``q`` (times ``t_s``, only used for the shape check).

    Returns ``(down, finger)``: ``down`` (T, 88) bool, column ``pitch - 21``;
    ``finger`` (T, 88) int8, the index into ``FINGERS`` of the fingertip that
    holds the key down (the deepest one if several), -1 where the key is up.
    """
    q = np.atleast_2d(np.asarray(q, dtype=float))
    if len(np.atleast_1d(t_s)) != len(q):
        raise ValueError("t_s and q must have the same number of rows")
    tips, _ = fk_frames(hand, q, T_world_root)
    c = key_contacts(tips)
    return c.down, c.finger


