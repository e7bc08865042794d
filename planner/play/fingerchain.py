"""A finger's tip and body points for many configurations at once, in one pass down its
chain: what ``FrameChain.positions`` (the tip) and ``FingerBodies.points_many`` (the
shapes' sampled axes) give, for the follow test (``planner.play.follow``), which asks
them of one move's samples at a time, thousands of times a song.

``FingerBodies.points_many`` carries each shape's two ends down the chain from its own
link, one ``FrameChain`` per shape (seven for a long finger, four frames deep or more
each); the tip is carried once more. The links of one finger are one chain (the arm's
joints, the wrist, the finger's joints: each shape's link a prefix of the tip's), so here
every point starts at its own link's joint and all of them go on together from there to
the root: the same rigid transforms (Rodrigues for a revolute joint, a translation for a
prismatic one, then the joint's placement), applied once per joint to every point.
The numbers are those of ``FrameChain``'s to rounding (the matrix products are the same
BLAS calls on other shapes of array: ``tests/test_fingerchain.py``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from planner.hand.chain import FrameChain
from planner.hand.model import HandModel

if TYPE_CHECKING:
    from planner.play.fingerbody import FingerShapes


class FingerChain:
    """One finger's tip (``tip``) and body shapes' ends (``FingerBodies.shapes``: ``s``,
    each capsule's axis sampled at ``axis_samples`` points), carried together (see the
    module docstring). ValueError when the finger's links are not one chain."""

    def __init__(self, hand: HandModel, s: FingerShapes, finger: str, axis_samples: int) -> None:
        names = hand.pin_model.frames
        tip = FrameChain(hand, f"{finger}_tip")
        chains = [FrameChain(hand, names[fid].name) for fid in s.frames]
        self.joints = max([tip, *chains], key=lambda c: len(c.joints)).joints
        for c in (tip, *chains):  # (one chain: every link's a prefix of the deepest)
            if any(a[0] != b[0] or a[1] != b[1] for a, b in zip(c.joints, self.joints)):
                raise ValueError(f"finger {finger!r}: its links are not one chain")
        self.T_world_root = tip.T_world_root
        # (each joint's column of the configurations; a joint not ours stays at 0: a
        # column of zeros, its cosine 1 and sine 0, as ``FrameChain``'s)
        self._cols = [hand.n if j[0] is None else j[0] for j in self.joints]
        self._pad = any(j[0] is None for j in self.joints)
        # the points each joint's frame holds (its links' shape ends, the tip: in the
        # frame's parent joint, as ``FrameChain.points``), by joint depth, and where each
        # lands in the carried array (point-major rows: point i's at i N .. i N + N - 1)
        local: dict[int, list[np.ndarray]] = {}
        order: list[tuple[int, int]] = []  # (depth, index in the depth's list) per point
        for c, pts in [(tip, np.zeros((1, 3))), *[(c, np.stack([a, b])) for c, a, b
                                                    in zip(chains, s.p0, s.p1)]]:
            depth = len(c.joints)
            block = local.setdefault(depth, [])
            for p in pts @ c.R_frame.T + c.tip:
                order.append((depth, len(block)))
                block.append(p)
        self._local = {d: np.array(v) for d, v in local.items()}
        depths = sorted(self._local, reverse=True)
        start, first = 0, {}
        for d in depths:
            first[d] = start
            start += len(self._local[d])
        self._row = np.array([first[d] + i for d, i in order])  # (each point's place)
        self.n_points = start
        self.n_shape = tuple(s.n_points)
        self._t = np.linspace(0.0, 1.0, axis_samples)[:, None]  # (``points_many``'s)
        # (Rodrigues' k x p in three array operations: each column's two products and
        # their difference, k[1] p[2] - k[2] p[1] and so on, gathered by these columns)
        self._cross = [(k[[1, 2, 0]], k[[2, 0, 1]]) for _, _, k, _, _ in self.joints]
        self._identity = [bool(np.array_equal(R, np.eye(3))) for _, _, _, R, _ in self.joints]
        self._moved = [bool(t.any()) for _, _, _, _, t in self.joints]
        # (the shapes' axes: every axis point's shape and its fraction of the axis, in
        # ``points_many``'s order, shape by shape)
        self._shape_of = np.repeat(np.arange(len(self.n_shape)), self.n_shape)
        self._t_of = np.concatenate([self._t[:m, 0] for m in self.n_shape])[None, :, None]
        self._axes = axis_steps(self.joints, self.T_world_root)
        self.axis_aligned = self._axes is not None  # (``carry_axes``' chains)
        # (``_carried``'s start: every point of ``_local``, (3, points, 1), in its rows'
        # order; and how many rows the points of each joint and the deeper ones fill)
        self._local_c = np.concatenate([self._local[d] for d in depths]).T[:, :, None].copy()
        self._rows_at = {d: sum(len(self._local[e]) for e in depths if e >= d)
                         for d in range(1, len(self.joints) + 1)}
        # (``carry_coords``: each axis point's two ends, the rows of ``_axes_of``'s
        # ``w[1::2]`` and ``w[2::2]`` gathered by ``_shape_of``)
        self._end_a = self._row[1::2][self._shape_of]
        self._end_b = self._row[2::2][self._shape_of]

    def carry(self, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """At configurations ``Q`` (N, n; the hand's joint order, couplings applied): the
        tip's world position (N, 3) and the shapes' sampled axis points (N, m, 3), as
        ``FrameChain.positions`` and ``FingerBodies.points_many``; a chain of axis-aligned
        joints by ``carry_axes`` (the same numbers), any other by ``carry_general``."""
        if self._axes is None:
            return self.carry_general(Q)
        if len(np.atleast_2d(Q)) == 0:
            return np.empty((0, 3)), np.empty((0, len(self._shape_of), 3))
        return self.carry_axes(Q)

    def carry_general(self, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``carry`` of any chain: Rodrigues on the points' rows, the placements' matrix
        products."""
        Q = np.atleast_2d(np.asarray(Q, dtype=float))
        n = len(Q)
        if n == 0:
            return np.empty((0, 3)), np.empty((0, len(self._shape_of), 3))
        if self._pad:
            Q = np.concatenate([Q, np.zeros((n, 1))], axis=1)
        # (every joint's value, cosine and sine for each configuration, broadcast over
        # the points: the rows of ``p`` are point-major, the points of the deepest links
        # first, ``_local``; (points, n) as a view)
        q = Q[:, self._cols]
        cos_q = np.cos(q)
        sin_q, vers_q = np.sin(q), 1.0 - cos_q
        p = np.empty((0, 3))
        for depth in range(len(self.joints), 0, -1):
            loc = self._local.get(depth)
            if loc is not None:  # (this joint's links' points join the others here)
                p = np.concatenate([p, np.repeat(loc, n, axis=0)])
            _, prismatic, k, R, t = self.joints[depth - 1]
            j = depth - 1
            if prismatic:
                p = (p.reshape(-1, n, 3) + (q[:, j, None] * k)[None]).reshape(-1, 3)
            else:  # Rodrigues, as ``FrameChain``: p cos + (k x p) sin + k (k . p)(1 - cos)
                k_a, k_b = self._cross[j]
                kxp = k_a * p[:, _NEXT2]
                kxp -= k_b * p[:, _NEXT1]
                kxp.reshape(-1, n, 3)[...] *= sin_q[None, :, j, None]  # (views: in place)
                along = (p @ k)[:, None] * k
                along.reshape(-1, n, 3)[...] *= vers_q[None, :, j, None]
                p = (p.reshape(-1, n, 3) * cos_q[None, :, j, None]).reshape(-1, 3)
                p += kxp
                p += along
            # (the joint's placement; a rotation that is the identity and a translation
            # of zeros change no number but an exact zero's sign, which no comparison sees)
            if not self._identity[depth - 1]:
                p = p @ R.T
            if self._moved[depth - 1]:
                p = p + t
        T = self.T_world_root
        return self._axes_of((p @ T[:3, :3].T + T[:3, 3]).reshape(self.n_points, n, 3))

    def carry_coords(self, Q: np.ndarray) -> tuple[np.ndarray, tuple[np.ndarray, ...]]:
        """``carry``'s numbers with each coordinate of the shapes' points an array of its
        own: the tip (N, 3) and the points' x, y and z, (m, N) each (``carry_stacked``)."""
        tips, c = self.carry_stacked(Q)
        return tips, (c[0], c[1], c[2])

    def carry_stacked(self, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``carry``'s numbers, the shapes' points as one array of coordinates: the tip
        (N, 3) and the points (3, m, N). A chain of axis-aligned joints (``carry_axes``'
        steps) carries them so; any other's ``carry_general`` points are taken apart."""
        if self._axes is None or len(np.atleast_2d(Q)) == 0:
            tips, P = self.carry(Q)
            return tips, np.ascontiguousarray(P.transpose(2, 1, 0))
        c = self._carried(Q)  # (3, carried points, N)
        # (each shape's axis, as ``_axes_of``: wa + t (wb - wa), its two ends gathered
        # for every axis point at once: the same differences, taken after the gather)
        a = c[:, self._end_a]
        return c[:, self._row[0]].T, a + self._t_of[0] * (c[:, self._end_b] - a)

    def carry_axes(self, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``carry``'s answer by ``_carried``: the chain's points with each coordinate an
        array of its own."""
        return self._axes_of(np.moveaxis(self._carried(Q), 0, -1))

    def _carried(self, Q: np.ndarray) -> np.ndarray:
        """Every point of ``_local`` carried to the world (N > 0 configurations), for a
        chain whose joint axes are coordinate axes (``axis_steps``): x, y and z, (3,
        points, N), each joint's Rodrigues on the two coordinates it turns, in place on
        the rows of the points its links hold (the deepest links' first: a prefix). The
        numbers are ``carry_general``'s, operation by operation: with ``k = s e_i``
        (s = +-1) the cross product ``k x p`` is the other two coordinates exchanged, one
        negated (its products by 0 and +-1 exact), ``k . p`` is ``s p_i`` (a dot product
        whose other terms are exact zeros), so coordinate i becomes
        ``p_i cos + p_i (1 - cos)`` and the others ``p_a cos -+ p_b sin``, each rounded
        where ``carry_general`` rounds it; the terms it adds that are exact zeros (and a
        translation's zero components, and an identity rotation) change no number but a
        zero's sign, which no comparison sees."""
        Q = np.atleast_2d(np.asarray(Q, dtype=float))
        n = len(Q)
        if self._pad:
            Q = np.concatenate([Q, np.zeros((n, 1))], axis=1)
        q = Q[:, self._cols]  # (the cosines and sines of ``carry_general``'s arrays,
        cos_q = np.cos(q)  # then a row per joint)
        sin_q, vers_q = np.sin(q).T, (1.0 - cos_q).T
        q, cos_q = q.T, cos_q.T
        c = np.empty((3, self.n_points, n))
        c[...] = self._local_c  # (every point where its own link's joint holds it)
        for depth in range(len(self.joints), 0, -1):
            j = depth - 1
            v = c[:, :self._rows_at[depth]]  # (the points of this joint's links and deeper)
            i, s, shift = self._axes[j]
            if self.joints[j][1]:  # (prismatic: p + q k)
                v[i] += q[j] if s > 0 else -q[j]
            else:
                a, b = (i + 1) % 3, (i + 2) % 3
                turned = v * sin_q[j]  # (p_a sin, p_b sin; p_i sin unused)
                along = v[i] * vers_q[j]
                v *= cos_q[j]
                if s > 0:
                    v[a] -= turned[b]
                    v[b] += turned[a]
                else:
                    v[a] += turned[b]
                    v[b] -= turned[a]
                v[i] += along
            for k, w in shift:
                v[k] += w
        for k, w in self._axes[-1]:  # (the root's placement: a translation)
            c[k] += w
        return c

    def _axes_of(self, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The tip and the shapes' sampled axes from every carried point ``w``
        (points, N, 3; point-major rows, ``_row``'s order)."""
        w = w[self._row]
        # (each shape's axis, as ``points_many``: wa + t (wb - wa), every shape at once)
        wa, wb = w[1::2].transpose(1, 0, 2), w[2::2].transpose(1, 0, 2)
        return w[0], wa[:, self._shape_of] + self._t_of * (wb - wa)[:, self._shape_of]


def axis_steps(joints: list, T_world_root: np.ndarray) -> list | None:
    """``carry_axes``' steps when every joint's axis is a coordinate axis (+-1 in one
    component, exact zeros in the others), every joint's placement rotation and the
    root's are the identity: per joint (the axis's coordinate, its sign, the placement's
    non-zero translation components (coordinate, value)), then the root's translation;
    None otherwise (``carry_general``)."""
    eye = np.eye(3)
    if not np.array_equal(T_world_root[:3, :3], eye):
        return None
    steps = []
    for _, _, k, R, t in joints:
        nz = np.flatnonzero(k)
        if len(nz) != 1 or abs(k[nz[0]]) != 1.0 or not np.array_equal(R, eye):
            return None
        steps.append((int(nz[0]), float(k[nz[0]]),
                      [(c, float(t[c])) for c in range(3) if t[c] != 0.0]))
    steps.append([(c, float(T_world_root[c, 3])) for c in range(3)
                  if T_world_root[c, 3] != 0.0])
    return steps


_NEXT1 = np.array([1, 2, 0])  # (each column's next, and the one after: ``carry``'s k x p)
_NEXT2 = np.array([2, 0, 1])
