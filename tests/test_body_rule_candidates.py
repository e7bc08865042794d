"""The body rule's candidates (``keybodies._collect``): the (row, shape) pairs that can
reach a key's column found first, then their rectangles. The depths and bodies must be
the whole (rows x shapes x rectangles) test's to the bit (plans stay byte-identical)."""

from __future__ import annotations

import numpy as np
import pytest

from planner.check.criteria import DOWN_DEPTH_M
from planner.check.kinematics import Kinematics
from planner.hand.bodies import body_links, collision_bodies, place
from planner.music import keybodies as kbod
from planner.music.keybodies import column_depths, footprints, keep_deepest, swept_lowest_z
from planner.trajfile import read_trajectory


def straight_collect(depth, which, fp, z_cut, bounds, index, lowest) -> None:
    """``_collect`` as first written: every (row, shape, rectangle) tested at once (the
    deepest of them kept as ``_collect`` keeps them: ``keep_deepest``)."""
    xlo, xhi, ylo, yhi, zlo = bounds
    candidates = np.nonzero((xlo[..., None] <= fp.hi[:, 0]) & (xhi[..., None] >= fp.lo[:, 0])
                            & (ylo[..., None] <= fp.hi[:, 1]) & (yhi[..., None] >= fp.lo[:, 1])
                            & (zlo[..., None] <= z_cut))
    keep_deepest(depth, which, fp, candidates, index, lowest)  # (``_collect``'s own end)


@pytest.fixture(scope="module")
def placed(planned, hand):
    """The bodies at every row of a real plan (``cli.py play songs/scale.mid``), and the
    same rows with the hand 3 cm lower (many bodies in the keys' columns)."""
    q = read_trajectory(str(planned)).q
    bodies = collision_bodies(hand.spec)
    kin = Kinematics(hand, hand.T_world_root)
    low = np.array(hand.T_world_root, dtype=float)
    low[2, 3] -= 0.03
    return [place(bodies, k.link_poses(q, body_links(bodies)))
            for k in (kin, Kinematics(hand, low))]


@pytest.mark.parametrize("reach_m", [DOWN_DEPTH_M, 0.0, -0.02])
def test_candidates_first_give_the_whole_tests_depths(placed, reach_m: float,
                                                      monkeypatch) -> None:
    for pb in placed:
        got = column_depths(pb, reach_m)
        monkeypatch.setattr(kbod, "_collect", straight_collect)
        want = column_depths(pb, reach_m)
        monkeypatch.undo()
        assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1])
        assert (got[1] >= 0).any()


def test_lowest_functions_see_the_same_candidates(placed) -> None:
    """The search functions are called on the candidates in the whole test's order
    (their arrays equal, element for element)."""
    fp = footprints()
    seen = {}
    pb = placed[1]
    a, b, r = pb.a, pb.b, pb.radius_m[None, :]
    bounds = (np.minimum(a[..., 0], b[..., 0]) - r, np.maximum(a[..., 0], b[..., 0]) + r,
              np.minimum(a[..., 1], b[..., 1]) - r, np.maximum(a[..., 1], b[..., 1]) + r,
              np.minimum(a[..., 2], b[..., 2]) - r)
    calls: list = []

    def lowest(t, s, k):
        calls.append((t.copy(), s.copy(), k.copy()))
        return swept_lowest_z(a[t, s], b[t, s], pb.radius_m[s], fp.lo[k], fp.hi[k])

    for name, collect in (("new", kbod._collect), ("straight", straight_collect)):
        depth = np.full((pb.a.shape[0], 88), -np.inf)
        which = np.full(depth.shape, -1)
        collect(depth, which, fp, fp.top_m - DOWN_DEPTH_M, bounds, pb.swept, lowest)
        seen[name] = list(calls)
        calls.clear()
    assert len(seen["new"]) == len(seen["straight"]) == 1
    for x, y in zip(seen["new"][0], seen["straight"][0]):
        assert np.array_equal(x, y)


def straight_swept_lowest_z(a, b, r, lo, hi):
    """``swept_lowest_z`` as first written: whole 3-D axis points, a reduction for the
    distance."""
    ab = b - a

    def at(t):
        return a + t[:, None] * ab

    def dist(t):
        return kbod._rect_dist(at(t)[:, :2], lo, hi)

    t_near = kbod._golden(lambda t: dist(t), len(a))
    ok = dist(t_near) <= r
    t_lo = kbod._edge(dist, r, t_near, np.zeros(len(a)))
    t_hi = kbod._edge(dist, r, t_near, np.ones(len(a)))

    def f(u):
        t = t_lo + u * (t_hi - t_lo)
        d = np.minimum(dist(t), r)
        return at(t)[:, 2] - np.sqrt(np.maximum(r * r - d * d, 0.0))

    u = kbod._golden(f, len(a))
    z = np.minimum(np.minimum(f(u), f(np.zeros(len(a)))), f(np.ones(len(a))))
    return np.where(ok, z, np.inf)


def test_swept_lowest_z_is_the_straight_computation_to_the_bit() -> None:
    rng = np.random.default_rng(5)
    n = 3000
    a = rng.uniform(-0.05, 0.05, (n, 3))
    b = np.where(rng.uniform(size=(n, 1)) < 0.2, a, a + rng.uniform(-0.04, 0.04, (n, 3)))
    r = rng.uniform(0.003, 0.012, n)
    lo = rng.uniform(-0.03, 0.0, (n, 2))
    hi = lo + rng.uniform(0.005, 0.05, (n, 2))
    got = swept_lowest_z(a, b, r, lo, hi)
    assert np.isfinite(got).sum() > n // 4
    assert np.array_equal(got, straight_swept_lowest_z(a, b, r, lo, hi))
