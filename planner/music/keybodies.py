"""The hand's bodies against the keys: geometry only, no rule and no kinematics.

Two questions, each exact for the shapes of ``planner.hand.bodies`` (placed in the world
by ``bodies.place``):

* **How far below a key's top does a body reach inside its footprint** (spec section 2's
  body rule, judged by ``planner.check.bodykeys``): ``column_depths`` -- for every body
  and every key, the lowest point of the body inside the key's footprint column (its x-y
  rectangles, ``keyboard.footprint``), as a depth below the key's resting top. A capsule's
  lowest point in a rectangle's column is the minimum of a convex function of its axis
  parameter (``z(t) - sqrt(r^2 - d(t)^2)``, d the axis point's distance to the
  rectangle, on the interval where d <= r), found by bisection and golden section to
  ``SEARCH_TOL``; a box's is a vertex of the box cut by the column (a box corner inside
  it, a box edge through a column face, or a column edge through a box face).
* **How deep a sphere-swept point set enters the physical key boxes** (the physics
  replay's keys, ``planner.simulate.keyboard``): ``box_penetration``, the planner's body
  clearance (``planner.play.fingerbody``).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np

from planner.music import keyboard as kb

SEARCH_STEPS = 48  # bisection / golden-section steps: 0.618^48 of an axis ~ 1e-10
GOLDEN = (np.sqrt(5.0) - 1.0) / 2.0


@dataclass(frozen=True)
class Footprints:
    """Every key's footprint rectangles: ``key`` (R,) key index (pitch - 21), ``lo``/``hi``
    (R, 2) the x-y corners, ``top_m`` (R,) the key's resting top."""

    key: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    top_m: np.ndarray


@cache
def footprints() -> Footprints:
    rows = [(p - kb.LOWEST_PITCH, r, kb.key(p).top_z_m) for p in kb.ALL_PITCHES
            for r in kb.footprint(p)]
    return Footprints(np.array([k for k, _, _ in rows]),
                      np.array([(r[0], r[2]) for _, r, _ in rows]),
                      np.array([(r[1], r[3]) for _, r, _ in rows]),
                      np.array([t for _, _, t in rows]))


def _rect_dist(p: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """2-D distance of points ``p`` (..., 2) to rectangles [lo, hi] (..., 2)."""
    d = np.maximum(np.maximum(lo - p, p - hi), 0.0)
    return np.sqrt((d * d).sum(axis=-1))


def _rect_dist_xy(x: np.ndarray, y: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """``_rect_dist`` of points (``x``, ``y``) (N,) to rectangles [lo, hi] (N, 2), the same
    numbers (a sum of two squares in either order) without a reduction's overhead."""
    dx = np.maximum(np.maximum(lo[:, 0] - x, x - hi[:, 0]), 0.0)
    dy = np.maximum(np.maximum(lo[:, 1] - y, y - hi[:, 1]), 0.0)
    return np.sqrt(dx * dx + dy * dy)


def swept_lowest_z(a: np.ndarray, b: np.ndarray, r: np.ndarray, lo: np.ndarray,
                   hi: np.ndarray) -> np.ndarray:
    """The lowest z of each capsule (axis ``a``-``b`` (N, 3), radius ``r`` (N,); a sphere:
    a = b) inside the column of the rectangle [lo, hi] (N, 2); +inf where it does not
    enter the column."""
    ab = b - a
    ax, ay, az = (np.ascontiguousarray(a[:, i]) for i in range(3))
    bx, by, bz = (np.ascontiguousarray(ab[:, i]) for i in range(3))

    def dist(t):  # (the axis point at t: a + t (b - a), coordinate by coordinate)
        return _rect_dist_xy(ax + t * bx, ay + t * by, lo, hi)

    # the axis point nearest the rectangle (d is convex in t): golden section
    t_near = _golden(lambda t: dist(t), len(a))
    d_near = dist(t_near)
    ok = d_near <= r
    # the interval where d <= r, each side by bisection (d is monotone on either side)
    t_lo = _edge(dist, r, t_near, np.zeros(len(a)))
    t_hi = _edge(dist, r, t_near, np.ones(len(a)))

    def f(u):  # u in [0, 1] over [t_lo, t_hi]
        t = t_lo + u * (t_hi - t_lo)
        d = np.minimum(dist(t), r)
        return (az + t * bz) - np.sqrt(np.maximum(r * r - d * d, 0.0))

    u = _golden(f, len(a))
    z = np.minimum(np.minimum(f(u), f(np.zeros(len(a)))), f(np.ones(len(a))))
    return np.where(ok, z, np.inf)


def _golden(f, n: int) -> np.ndarray:
    """The minimiser in [0, 1] of a convex (or unimodal) function of each of n rows."""
    lo, hi = np.zeros(n), np.ones(n)
    for _ in range(SEARCH_STEPS):
        m1 = hi - GOLDEN * (hi - lo)
        m2 = lo + GOLDEN * (hi - lo)
        left = f(m1) <= f(m2)
        hi = np.where(left, m2, hi)
        lo = np.where(left, lo, m1)
    return 0.5 * (lo + hi)


def _edge(dist, r: np.ndarray, inside: np.ndarray, outside: np.ndarray) -> np.ndarray:
    """Where between ``inside`` (d <= r there, when any) and ``outside`` d reaches r: the
    last point with d <= r (``outside`` itself when d <= r there)."""
    good = dist(outside) <= r
    lo, hi = inside.copy(), outside.copy()
    for _ in range(SEARCH_STEPS):
        mid = 0.5 * (lo + hi)
        inn = dist(mid) <= r
        lo = np.where(inn, mid, lo)
        hi = np.where(inn, hi, mid)
    return np.where(good, outside, lo)


_CORNERS = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)],
                    dtype=float)
_EDGES = [(i, j) for i in range(8) for j in range(i + 1, 8)
          if np.abs(_CORNERS[i] - _CORNERS[j]).sum() == 2]


def box_lowest_z(c: np.ndarray, R: np.ndarray, h: np.ndarray, lo: np.ndarray,
                 hi: np.ndarray) -> np.ndarray:
    """The lowest z of each box (centre ``c`` (N, 3), axes ``R`` (N, 3, 3) as columns,
    half sizes ``h`` (N, 3)) inside the column of the rectangle [lo, hi] (N, 2); +inf
    where it does not enter the column. (A linear programme: its optimum is a vertex of
    the box cut by the column; every kind of vertex is a candidate.)"""
    eps = 1e-12
    corners = c[:, None, :] + np.einsum("nij,nkj->nki", R, _CORNERS * h[:, None, :])  # (N, 8, 3)

    def inside_xy(p):  # p (N, k, 3)
        return np.all((p[..., :2] >= lo[:, None] - eps) & (p[..., :2] <= hi[:, None] + eps),
                      axis=-1)

    best = np.where(inside_xy(corners), corners[..., 2], np.inf).min(axis=1)
    # box edges through the column's four faces
    p0 = corners[:, [i for i, _ in _EDGES]]  # (N, 12, 3)
    p1 = corners[:, [j for _, j in _EDGES]]
    for axis in (0, 1):
        for bound in (lo[:, axis], hi[:, axis]):
            den = p1[..., axis] - p0[..., axis]
            with np.errstate(divide="ignore", invalid="ignore"):
                s = (bound[:, None] - p0[..., axis]) / den
            valid = (np.abs(den) > eps) & (s >= 0.0) & (s <= 1.0)
            p = p0 + np.nan_to_num(s)[..., None] * (p1 - p0)
            z = np.where(valid & inside_xy(p), p[..., 2], np.inf)
            best = np.minimum(best, z.min(axis=1))
    # the column's four vertical edges through the box (slabs along each box axis)
    for x in (lo[:, 0], hi[:, 0]):
        for y in (lo[:, 1], hi[:, 1]):
            o = np.stack([x, y, np.zeros_like(x)], axis=1) - c  # the line: o + z e_z
            oo = np.einsum("nij,ni->nj", R, o)  # in box axes
            dz = R[:, 2, :]  # e_z in box axes
            zlo, zhi = np.full(len(c), -np.inf), np.full(len(c), np.inf)
            for k in range(3):
                with np.errstate(divide="ignore", invalid="ignore"):
                    a1 = (-h[:, k] - oo[:, k]) / dz[:, k]
                    a2 = (h[:, k] - oo[:, k]) / dz[:, k]
                flat = np.abs(dz[:, k]) <= eps
                lo_k = np.where(flat, np.where(np.abs(oo[:, k]) <= h[:, k], -np.inf, np.inf),
                                np.minimum(a1, a2))
                hi_k = np.where(flat, np.where(np.abs(oo[:, k]) <= h[:, k], np.inf, -np.inf),
                                np.maximum(a1, a2))
                zlo, zhi = np.maximum(zlo, lo_k), np.minimum(zhi, hi_k)
            best = np.minimum(best, np.where(zlo <= zhi, zlo, np.inf))
    return best


def column_depths(placed, reach_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Every body of ``placed`` (``planner.hand.bodies.PlacedBodies``, T configurations)
    against every key's footprint: ``(depth, body)``, both (T, 88): how far below the
    key's resting top the deepest body reaches inside the footprint, and which body
    (index into the bodies placed). Bodies that stay above ``reach_m`` below the key's top
    (the shallowest depth the caller judges) are skipped before the exact search: where
    no body reaches that deep, depth may be -inf (body -1) or a value under ``reach_m``."""
    fp = footprints()
    T = placed.a.shape[0] if placed.a.size else placed.centre.shape[0]
    depth = np.full((T, kb.HIGHEST_PITCH - kb.LOWEST_PITCH + 1), -np.inf)
    which = np.full(depth.shape, -1, dtype=int)
    z_cut = fp.top_m - reach_m  # (R,) a body must reach below this in the column
    if placed.a.size:
        a, b, r = placed.a, placed.b, placed.radius_m[None, :]
        xlo = np.minimum(a[..., 0], b[..., 0]) - r
        xhi = np.maximum(a[..., 0], b[..., 0]) + r
        ylo = np.minimum(a[..., 1], b[..., 1]) - r
        yhi = np.maximum(a[..., 1], b[..., 1]) + r
        zlo = np.minimum(a[..., 2], b[..., 2]) - r
        _collect(depth, which, fp, z_cut, (xlo, xhi, ylo, yhi, zlo), placed.swept,
                 lambda t, s, k: swept_lowest_z(a[t, s], b[t, s], placed.radius_m[s],
                                                fp.lo[k], fp.hi[k]))
    if placed.centre.size:
        c, R, h = placed.centre, placed.axes, placed.half_m
        ext = np.einsum("tbij,bj->tbi", np.abs(R), h)  # half the world AABB's sizes
        _collect(depth, which, fp, z_cut,
                 (c[..., 0] - ext[..., 0], c[..., 0] + ext[..., 0], c[..., 1] - ext[..., 1],
                  c[..., 1] + ext[..., 1], c[..., 2] - ext[..., 2]), placed.boxes,
                 lambda t, s, k: box_lowest_z(c[t, s], R[t, s], h[s], fp.lo[k], fp.hi[k]))
    return depth, which


def _collect(depth, which, fp: Footprints, z_cut, bounds, index, lowest) -> None:
    """Candidates (row, shape, rectangle) whose bounding box overlaps the rectangle's column
    below ``z_cut``; their exact lowest points, the deepest per key kept in place."""
    xlo, xhi, ylo, yhi, zlo = bounds  # (T, S)
    # (first the (row, shape) pairs whose box reaches below the highest cut and overlaps
    # the keyboard's extent: a few in a hundred; then their rectangles. The candidates
    # come in the order of the whole (T, S, R) test: by row, shape, rectangle)
    t, s = np.nonzero((zlo <= z_cut.max()) & (xlo <= fp.hi[:, 0].max())
                      & (xhi >= fp.lo[:, 0].min()) & (ylo <= fp.hi[:, 1].max())
                      & (yhi >= fp.lo[:, 1].min()))
    xlo, xhi, ylo, yhi, zlo = (v[t, s] for v in bounds)
    p, k = np.nonzero((xlo[:, None] <= fp.hi[:, 0]) & (xhi[:, None] >= fp.lo[:, 0])
                      & (ylo[:, None] <= fp.hi[:, 1]) & (yhi[:, None] >= fp.lo[:, 1])
                      & (zlo[:, None] <= z_cut))
    keep_deepest(depth, which, fp, (t[p], s[p], k), index, lowest)


def keep_deepest(depth, which, fp: Footprints, candidates, index, lowest) -> None:
    """Of the ``candidates`` (row, shape, rectangle index arrays), their exact lowest
    points (``lowest``), below each rectangle's top: the deepest per row and key kept in
    ``depth`` (and its shape's ``index`` in ``which``) where deeper than it holds."""
    t, s, k = candidates
    if len(t) == 0:
        return
    d = fp.top_m[k] - lowest(t, s, k)
    key = fp.key[k]
    order = np.lexsort((d, key, t))  # by row, key, then depth: each group's deepest last
    t, key, d, s = t[order], key[order], d[order], s[order]
    last = np.ones(len(t), dtype=bool)
    last[:-1] = (t[1:] != t[:-1]) | (key[1:] != key[:-1])
    t, key, d, s = t[last], key[last], d[last], s[last]
    better = d > depth[t, key]
    depth[t[better], key[better]] = d[better]
    which[t[better], key[better]] = np.asarray(index)[s[better]]


def _column_depths_of_spheres(p: np.ndarray, r: np.ndarray, lo: np.ndarray,
                              hi: np.ndarray) -> np.ndarray:
    """How far below z = 0 spheres at ``p`` (K, m, 3), radii ``r`` (m,), reach inside each
    column [lo, hi] (R, 2): (K, R), -inf where none enters it (the lowest sphere point
    inside a column: ``z - sqrt(r^2 - d^2)``, d its centre's distance to the rectangle)."""
    d = _rect_dist(p[:, :, None, :2], lo[None, None], hi[None, None])  # (K, m, R)
    r2 = (r * r)[None, :, None] - d * d
    low = np.where(r2 >= 0.0, p[:, :, None, 2] - np.sqrt(np.maximum(r2, 0.0)), np.inf)
    return -low.min(axis=1)


def sphere_depths(p: np.ndarray, r: np.ndarray, grow_m: float = 0.0) -> np.ndarray:
    """How far below each key's resting top spheres at ``p`` (m, 3), radii ``r`` (m,),
    reach inside its footprint column (spec section 2's body rule for a sampled body,
    ``column_depths``' question), each footprint grown by ``grow_m`` on every side:
    (88,), -inf for a key no sphere enters."""
    fp = footprints()
    per_rect = fp.top_m + _column_depths_of_spheres(p[None], r, fp.lo - grow_m,
                                                    fp.hi + grow_m)[0]  # (R,)
    out = np.full(kb.HIGHEST_PITCH - kb.LOWEST_PITCH + 1, -np.inf)
    np.maximum.at(out, fp.key, per_rect)
    return out


def key_depths(p: np.ndarray, r: np.ndarray, pitches, grow_m: float = 0.0) -> np.ndarray:
    """``sphere_depths`` of many configurations at once, for the keys ``pitches`` only:
    spheres at ``p`` (K, m, 3), radii ``r`` (m,) -> (K, len(pitches)), -inf where none
    enters a key's footprint column (grown by ``grow_m``)."""
    fp = footprints()
    keys = np.asarray(pitches) - kb.LOWEST_PITCH
    out = np.full((len(p), len(keys)), -np.inf)
    for i, k in enumerate(keys):
        sel = fp.key == k
        depth = fp.top_m[sel][None] + _column_depths_of_spheres(p, r, fp.lo[sel] - grow_m,
                                                                 fp.hi[sel] + grow_m)
        out[:, i] = depth.max(axis=1)
    return out


def box_penetration(p: np.ndarray, r: np.ndarray, lo: np.ndarray, hi: np.ndarray
                    ) -> np.ndarray:
    """How deep (m) sphere-swept points ``p`` (m, 3), radii ``r`` (m,), reach into each
    box [lo, hi] (boxes, 3): (boxes,), <= 0 where clear; of many configurations' points
    ``p`` (K, m, 3) at once: (K, boxes)."""
    d = np.maximum(np.maximum(lo - p[..., None, :], p[..., None, :] - hi), 0.0)
    dist = np.sqrt((d * d).sum(axis=-1))  # (..., points, boxes); 0 inside
    return (r[:, None] - dist).max(axis=-2)
