"""The move table's pairs across play postures (``planner.play.movetable``): a finger's
move across from another posture's entry, as shipped, is what ``Moves`` finds by forward
kinematics; the arm's moves to another posture are ``Places.arm_move``'s."""

from __future__ import annotations

import numpy as np
import pytest

from planner.hand.model import load_hand
from planner.play.moves import Moves
from planner.play.movetable import MoveTable, table_path
from planner.play.places import RAIL_STEP_M, Places


@pytest.fixture(scope="module")
def places():
    return Places(load_hand("default"))


def _entries(atlas, finger=None):
    return [e for e in atlas.solved().values()
            if finger is None or e.finger == finger]


def test_the_default_hand_ships_its_pairs_across_postures(places):
    assert places.postures >= 2
    for b, m in enumerate(places.moves):
        others = [p for p in range(places.postures) if p != b]
        assert sorted(m.table.cross_keys) == others
        for p in others:  # (made with the other posture's entries, in its table's order)
            assert m.table.cross_keys[p] == places.moves[p].table.keys


def test_shipped_moves_across_postures_equal_the_forward_kinematics(places):
    rng = np.random.default_rng(6)
    hand, seen = places.hand, 0
    for b_p, a_p in ((0, 1), (1, 2), (2, 0)):
        by_fk = Moves(hand, places.atlases[b_p])
        by_fk.table = MoveTable(hand.fingers, places.natural_dx, b_p)
        theirs = _entries(places.atlases[a_p])
        for _ in range(60):
            a = theirs[rng.integers(len(theirs))]
            mine = _entries(places.atlases[b_p], a.finger)
            b = mine[rng.integers(len(mine))]
            shipped = places.moves[b_p].table.across_clear(a, b)
            assert shipped is not None and shipped is by_fk._across_clear(a, b)
            seen += 1
    assert seen == 180


def test_pairs_made_with_other_entries_are_not_used(places):
    hand = places.hand
    t = places.moves[0].table
    got = MoveTable(hand.fingers, places.natural_dx, 0)
    got.load(table_path(hand.urdf_sha256, 0), places.moves[0].params())
    a = _entries(places.atlases[1])[0]
    b = next(e for e in _entries(places.atlases[0], a.finger))
    assert got.across_clear(a, b) is t.across_clear(a, b) is not None
    assert got.arm_s(1, 3) == t.arm_s(1, 3) > 0.0
    got.drop_cross(1)  # (``Places`` drops them when the keys differ)
    assert got.across_clear(a, b) is None and got.arm_s(1, 3) is None


def test_shipped_arm_moves_across_postures_are_the_arm_move(places):
    seen = 0
    for pa, pb in ((0, 1), (0, 2), (1, 2)):
        for steps in (-60, -7, 0, 1, 33, 60):
            got = places.moves[pa].table.arm_s(pb, steps)
            made = places.arm_move((0.0, places.reach_m(pa)),
                                   (steps * RAIL_STEP_M, places.reach_m(pb))).duration_s
            assert got == made
            seen += got > 0.0
    assert seen == 18  # (none is free: the reach moves, with or without the rail)
