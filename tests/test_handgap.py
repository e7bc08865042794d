"""A hand's poses measured once (``planner.play.handgap.PoseExtents``): the pair's gap
(``hand_reach``) and each place's own reach (``planner.play.handclear.PlaceReach``) read
the same measurement, and it is each pose's own, as measured alone."""

from __future__ import annotations

import numpy as np
import pytest

from planner.hand.model import load_hand
from planner.music import keyboard as kb
from planner.play.handclear import PlaceReach
from planner.play.handgap import InnerEdge, hand_gap, hand_poses, hand_reach, pose_extents
from planner.play.hands import LEFT, RIGHT, SIDES
from planner.play.places import RAIL_STEP_M
from planner.play.twohands import PairPlanner


@pytest.fixture(scope="module")
def pair() -> PairPlanner:
    return PairPlanner(load_hand("default-left"), load_hand("default"))


@pytest.mark.parametrize("side", SIDES)
def test_each_places_extents_are_its_four_poses_measured_alone(pair, side) -> None:
    places, edge = pair.planners[side].places, pair.edges[side]
    ext = pose_extents(places, edge)
    h = places.hand
    assert len(ext.keys) > 1000 and ext.rows.shape == (len(ext.keys), 4)
    for j in range(0, len(ext.keys), 97):  # (a sample over every finger and posture)
        p, f, pc, k = ext.keys[j]
        at = places.atlases[p]
        tucked = places.idle.tuck(at.base)
        e = at.entry_at(f, pc, k)
        Q = h.apply_couplings(np.array([at.full_q(e, pose, 0.0, tucked)
                                        for pose in ("press", "rise", "hover", "high")]))
        lo, hi = InnerEdge(h).extents_m(Q)  # (a fresh edge: its own kinematics)
        assert np.array_equal(lo, ext.lo_m[ext.rows[j]])
        assert np.array_equal(hi, ext.hi_m[ext.rows[j]])
        # (the place's reach, as the loosened rule reads it: the most of its four poses',
        # at a rail position whose grid index for the finger on the key is ``k``)
        want = float((-lo if side == RIGHT else hi).max())
        pitch = 60 + pc
        rails = [i for i in range(round(at.rail_for(f, pitch, k) / RAIL_STEP_M) - 2,
                                  round(at.rail_for(f, pitch, k) / RAIL_STEP_M) + 3)
                 if at.grid_index(f, pitch, places.rail_m(places.place(p, i))) == k]
        for i in rails:
            assert pair.place_reach[side].reach_m(f, pitch, places.place(p, i)) == want


def test_the_gap_is_the_farthest_of_every_pose_measured_at_once(pair) -> None:
    # (main's measurement: every pose of ``hand_poses``, once each, in one batch)
    for side in SIDES:
        places = pair.planners[side].places
        lo, hi = InnerEdge(places.hand).extents_m(np.unique(hand_poses(places), axis=0))
        want = -float(lo.min()) if side == RIGHT else float(hi.max())
        assert hand_reach(places).inner_extent_m == want
        assert pair.reach(side).inner_extent_m == want
    fresh = hand_gap(pair.planners[LEFT].places, pair.planners[RIGHT].places)
    assert fresh == pair.gap
    for side in SIDES:  # (a PlaceReach measuring its own poses: the same reaches)
        alone = PlaceReach(pair.planners[side].places, pair.edges[side])
        shared = pair.place_reach[side]
        places = pair.planners[side].places
        for f in places.hand.fingers:
            for pitch in (48, 61, 72):
                mid = round((kb.key(pitch).center_x_m - places.natural_dx[f]) / RAIL_STEP_M)
                for p in range(places.postures):
                    for i in range(mid - 12, mid + 13, 3):
                        q = places.place(p, i)
                        assert alone.reach_m(f, pitch, q) == shared.reach_m(f, pitch, q)
