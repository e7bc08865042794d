"""planner.play.moves: the shipped key crossings are what the forward kinematics finds,
and a table made with other parameters is not used."""

from __future__ import annotations

import numpy as np
import pytest

from planner.hand.model import load_hand
from planner.play.atlas import Atlas
from planner.play.moves import Moves, crossings_path


@pytest.fixture(scope="module")
def moves():
    hand = load_hand("default")
    return Moves(hand, Atlas(hand))


def test_the_default_hand_ships_its_crossings(moves):
    assert crossings_path(moves.hand.urdf_sha256).exists()
    assert len(moves._crossings) > 1000


def test_shipped_crossings_equal_the_forward_kinematics(moves):
    rng = np.random.default_rng(3)
    keys = list(moves._crossings)
    for i in rng.choice(len(keys), 25, replace=False):
        f, pc, k = keys[i]
        e = moves.atlas.entry_at(f, pc, k)
        row = moves._crossings[keys[i]]
        for c, start in enumerate(("high", "hover", "rise")):
            qa = getattr(e, start)
            m = moves._move(f, qa, e.press)
            assert row[c] == moves._cross(e, qa, e.press, m, True)
            qb = getattr(e, start)
            m = moves._move(f, e.press, qb)
            assert row[3 + c] == moves._cross(e, e.press, qb, m, False)
        # and a crossing lies inside its move
        d = moves.descend(e, "high")
        assert 0.0 < d.cross_s <= d.duration_s


def test_a_table_of_other_parameters_is_not_used(moves, tmp_path):
    keys, times = moves.crossing_table()
    path = tmp_path / "crossings.npz"
    np.savez_compressed(path, key=keys, cross_s=times + 1.0,
                        params=np.array(moves._params().replace("cross_tol", "tol")))
    fresh = Moves.__new__(Moves)
    fresh.hand, fresh.atlas, fresh._crossings = moves.hand, moves.atlas, {}
    fresh._load_crossings(path)
    assert fresh._crossings == {}
    np.savez_compressed(path, key=keys, cross_s=times, params=np.array(moves._params()))
    fresh._load_crossings(path)
    assert len(fresh._crossings) == len(keys)
