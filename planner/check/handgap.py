"""Between two hands: at every row, the least distance between any collision body of one
hand and any of the other (``planner.hand.bodies``: capsules, spheres and boxes, the rail
carriages' boxes included); a row where it is under ``criteria.HANDS_GAP_M`` is a
collision (``docs/user/two-hands.md``).

The distance of two bodies is exact (the Coal library's GJK/EPA, which Pinocchio is built
on: signed, so negative when they overlap). Each row's least distance is found by bounds
first: two hands whose bodies' bounding boxes (each body in its bounding sphere) are apart
by g are at least g apart, and two bodies at least their spheres' gap; exact distances are
taken in the order of those bounds until the next bound is no less than the least found.
Every row whose bound is under the gap is measured (a collision is never missed), and the
least distance of the whole plan is exact: rows are measured, block by block, in the order
of their bounds until the next is no less than the least found so far.
"""

from __future__ import annotations

from dataclasses import dataclass

import coal
import numpy as np

from planner.check.criteria import HANDS_GAP_M
from planner.check.kinematics import Kinematics
from planner.hand.bodies import BOX, CAPSULE, Body, PlacedBodies, body_links, place
from planner.trajfile import distinct_rows


@dataclass(frozen=True)
class HandsCollision:
    """Rows ``row``.. (``start_s`` to ``end_s``: the time after its last row) in which
    the hands are closer than the gap: the least distance (m, negative when the bodies
    overlap), when, and its two bodies (each named with its hand's prefix)."""

    start_s: float
    row: int
    end_s: float
    rows: int
    least_m: float
    time_s: float
    left_body: str
    right_body: str


@dataclass(frozen=True)
class HandsGap:
    """The hands' least distance over the plan (``least_m``, at ``time_s``, between
    ``left_body`` and ``right_body``), the gap a row must keep (``limit_m``) and the
    collisions (runs of rows under it; ``collision_rows`` rows in all)."""

    least_m: float
    time_s: float
    left_body: str
    right_body: str
    limit_m: float
    collisions: tuple[HandsCollision, ...]
    collision_rows: int

    @property
    def ok(self) -> bool:
        return not self.collisions


class _Shapes:
    """One hand's bodies as Coal shapes, in ``place``'s order (sphere-swept, then boxes)."""

    def __init__(self, bodies: tuple[Body, ...], prefix: str) -> None:
        swept = [b for b in bodies if b.kind != BOX]
        boxes = [b for b in bodies if b.kind == BOX]
        self.names = tuple(prefix + b.name for b in swept + boxes)
        self.kinds = tuple(b.kind for b in swept + boxes)
        self.shapes = [coal.Capsule(b.radius_m, b.length_m) if b.kind == CAPSULE
                       else coal.Sphere(b.radius_m) for b in swept]
        self.shapes += [coal.Box(*(2.0 * np.asarray(b.half_m))) for b in boxes]
        self.radius_m = np.array([b.radius_m + 0.5 * b.length_m for b in swept]
                                 + [float(np.linalg.norm(b.half_m)) for b in boxes])

    def poses(self, pb: PlacedBodies) -> tuple[np.ndarray, np.ndarray]:
        """Every body's centre (T, S, 3) and orientation (T, S, 3, 3): a capsule's z along
        its axis (Coal's capsule), a sphere's any, a box's its link's."""
        centre = np.concatenate([0.5 * (pb.a + pb.b), pb.centre], axis=1)
        R = np.concatenate([_z_along(pb.b - pb.a), pb.axes], axis=1)
        return centre, R


def _z_along(d: np.ndarray) -> np.ndarray:
    """Rotations (..., 3, 3) whose z column is along ``d`` (..., 3) (identity where
    ``d`` is zero: a sphere)."""
    n = np.linalg.norm(d, axis=-1, keepdims=True)
    z = np.where(n > 0, d / np.where(n > 0, n, 1.0), [0.0, 0.0, 1.0])
    helper = np.where(np.abs(z[..., :1]) < 0.9, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x, axis=-1, keepdims=True)
    return np.stack([x, np.cross(z, x), z], axis=-1)


class GapJudge:
    """The hands' distance over rows given block by block (``add``: the rows' times and
    each hand's joint rows), then ``finish``."""

    def __init__(self, kins: tuple[Kinematics, Kinematics], bodies: tuple[tuple[Body, ...], ...],
                 prefixes: tuple[str, str], limit_m: float = HANDS_GAP_M,
                 hits_only: bool = False) -> None:
        self._kins, self._bodies = kins, bodies
        # (``hits_only``: only which rows are under the limit, the collisions' rows and
        # times exact, as the planner's confirmation reads them: a row is measured to its
        # first pair of bodies under the limit, and the plan's least distance is not
        # sought; a collision's ``least_m`` is then a distance under the limit, not the
        # least, and the result's ``least_m`` is inf)
        self._hits_only = hits_only
        self._shapes = tuple(_Shapes(b, p) for b, p in zip(bodies, prefixes))
        self._limit = limit_m
        self._best = (np.inf, 0.0, -1, -1)  # (least distance, time, left body, right body)
        self._runs: list[HandsCollision] = []
        self._open: list | None = None  # [start_s, row, rows, least, time, i, j]
        self._rows = 0
        self._req = coal.DistanceRequest()
        self._req.enable_signed_distance = True

    def add(self, t: np.ndarray, q_left: np.ndarray, q_right: np.ndarray) -> None:
        new, of = distinct_rows(np.concatenate([q_left, q_right], axis=1))
        first = np.flatnonzero(new)  # (each distinct row's first row)
        poses = []
        for kin, bodies, sh, q in zip(self._kins, self._bodies, self._shapes,
                                      (q_left, q_right)):
            pb = place(bodies, kin.link_poses(q[new], body_links(bodies)))
            poses.append(sh.poses(pb))
        lb = self._row_bounds(poses[0][0], poses[1][0])
        measured: dict[int, tuple[float, int, int]] = {}
        row = self._row_hit if self._hits_only else self._row_least
        for k in np.flatnonzero(lb < self._limit):  # (every row that may collide)
            measured[int(k)] = row(poses, int(k))
        # (the plan's least distance, exact; not sought for hits only)
        for k in ([] if self._hits_only else np.argsort(lb, kind="stable")):
            if lb[k] >= self._best[0]:
                break
            d, i, j = measured.get(int(k)) or self._row_least(poses, int(k))
            measured[int(k)] = (d, i, j)
            if d < self._best[0]:
                self._best = (d, float(t[first[k]]), i, j)
        self._collisions(t, of, measured)
        self._rows += len(t)

    def _row_bounds(self, cl: np.ndarray, cr: np.ndarray) -> np.ndarray:
        """Per distinct row, a lower bound of the hands' distance: their bodies'
        bounding boxes' gap (each body in its bounding sphere)."""
        rl, rr = self._shapes[0].radius_m[:, None], self._shapes[1].radius_m[:, None]
        lo_l, hi_l = (cl - rl).min(axis=1), (cl + rl).max(axis=1)
        lo_r, hi_r = (cr - rr).min(axis=1), (cr + rr).max(axis=1)
        return np.maximum(np.maximum(lo_r - hi_l, lo_l - hi_r).max(axis=1), 0.0)

    def _sphere_gaps(self, poses, k: int) -> tuple[np.ndarray, int]:
        """Distinct row ``k``'s gaps between every pair of bodies' bounding spheres
        (left body major, flattened) and the right hand's body count."""
        (cl, _), (cr, _) = poses
        sl, sr = self._shapes
        d = cl[k][:, None] - cr[k][None]
        gap = (np.sqrt(np.einsum("ijk,ijk->ij", d, d))
               - sl.radius_m[:, None] - sr.radius_m[None]).ravel()
        return gap, len(sr.radius_m)

    def _pair_distance(self, poses, k: int, i: int, j: int) -> float:
        """The exact distance of distinct row ``k``'s left body ``i`` and right body ``j``."""
        (cl, Rl), (cr, Rr) = poses
        sl, sr = self._shapes
        return float(coal.distance(sl.shapes[i], coal.Transform3s(Rl[k, i], cl[k, i]),
                                   sr.shapes[j], coal.Transform3s(Rr[k, j], cr[k, j]),
                                   self._req, coal.DistanceResult()))

    def _row_least(self, poses, k: int) -> tuple[float, int, int]:
        """The exact least distance of distinct row ``k`` and its two bodies: the pair of
        the least sphere gap measured first, then only the pairs whose gap is under the
        least found, in the order of their gaps."""
        gap, n = self._sphere_gaps(poses, k)

        def measure(flat: int) -> float:
            return self._pair_distance(poses, k, *divmod(flat, n))

        first = int(np.argmin(gap))
        best, at = measure(first), first
        near = np.flatnonzero(gap < best)
        for flat in near[np.argsort(gap[near], kind="stable")].tolist():
            if gap[flat] >= best:
                break
            if flat != first:
                dist = measure(flat)
                if dist < best:
                    best, at = dist, flat
        i, j = divmod(at, n)
        return best, i, j

    def _row_hit(self, poses, k: int) -> tuple[float, int, int]:
        """Whether distinct row ``k`` is under the limit: (a distance under it and its two
        bodies), the pairs measured in the order of their spheres' gaps, only those whose
        gap is under the limit (a pair at least its gap apart); (inf, -1, -1) when none is
        under it. The same rows as ``_row_least`` finds under the limit."""
        gap, n = self._sphere_gaps(poses, k)
        near = np.flatnonzero(gap < self._limit)
        for flat in near[np.argsort(gap[near], kind="stable")].tolist():
            i, j = divmod(flat, n)
            dist = self._pair_distance(poses, k, i, j)
            if dist < self._limit:
                return dist, i, j
        return np.inf, -1, -1

    def _collisions(self, t: np.ndarray, of: np.ndarray,
                    measured: dict[int, tuple[float, int, int]]) -> None:
        """Runs of rows under the gap, carried across blocks."""
        hit = np.array([k in measured and measured[k][0] < self._limit for k in of.tolist()],
                       dtype=bool)
        for r in range(len(t)):
            if hit[r]:
                d, i, j = measured[int(of[r])]
                if self._open is None:
                    self._open = [float(t[r]), self._rows + r, 0, np.inf, 0.0, i, j]
                run = self._open
                run[2] += 1
                if d < run[3]:
                    run[3:] = [d, float(t[r]), i, j]
            elif self._open is not None:
                self._close(float(t[r]))

    def _close(self, end_s: float) -> None:
        s, row, rows, d, at, i, j = self._open
        self._runs.append(HandsCollision(s, row, end_s, rows, d, at, self._shapes[0].names[i],
                                         self._shapes[1].names[j]))
        self._open = None

    def finish(self, t_end_s: float) -> HandsGap:
        """The result; ``t_end_s``: the time after the last row (a run open at the end
        ends there)."""
        if self._open is not None:
            self._close(float(t_end_s))
        d, at, i, j = self._best
        names = (self._shapes[0].names[i] if i >= 0 else "",
                 self._shapes[1].names[j] if j >= 0 else "")
        return HandsGap(float(d), at, *names, self._limit, tuple(self._runs),
                        sum(c.rows for c in self._runs))
