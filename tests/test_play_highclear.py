"""When a finger going up or down is clear above every key (planner/play/highclear.py):
the arm may move from the lift's clear moment on and until the descent's; the moments
shipped in the move tables are those the search finds."""

from __future__ import annotations

import numpy as np
import pytest

from planner.play.highclear import BODY_CLEAR_Z_M, HighClear, params
from planner.play.places import Places
from planner.play.tendonload import slowed


@pytest.fixture(scope="module")
def places(hand) -> Places:
    return Places(hand)


def _lowest_body_z(places: Places, e, move, t_s: float) -> float:
    h, atlas = places.hand, places.atlases[e.posture]
    q = atlas.base.copy()
    q[h.joint_slice(e.finger)] = move.at(t_s)[0]
    p, r = atlas.bodies.points(h.apply_couplings(q), e.finger)
    return float(np.min(p[:, 2] - r))


def _entries(places: Places):
    for posture, atlas in enumerate(places.atlases):
        for finger in ("index", "middle", "ring", "pinky"):
            for pitch in (60, 61, 64, 66):
                e = atlas.entry(finger, pitch, 0.0)
                if e is not None:
                    yield e


def test_a_lift_is_clear_from_its_clear_moment_to_its_end(places):
    seen = 0
    for e in _entries(places):
        u = places.lift(e, "high")
        t_clear = places.high.rise_clear_s(e, u.move)
        # (the key comes up first; the last part of the lift overlaps the arm's move)
        assert u.cross_s < t_clear < u.move.duration_s
        assert places.rail_lift_s(e) < places.before_rail_s(e)
        for t in np.linspace(t_clear, u.move.duration_s, 25):
            assert _lowest_body_z(places, e, u.move, t) >= BODY_CLEAR_Z_M - 1e-9
        # (just before it, the finger is still lower: the moment is not too late by much)
        assert _lowest_body_z(places, e, u.move, t_clear - 0.002) < BODY_CLEAR_Z_M + 3e-4
        seen += 1
    assert seen >= 8


def test_a_descent_is_clear_until_its_clear_moment(places):
    for e in _entries(places):
        d = places.descend(e, "high")
        t_clear = places.high.descent_clear_s(e, d.move)
        assert 0.0 < t_clear < d.cross_s
        assert places.rail_descent_s(e) == pytest.approx(d.cross_s - t_clear)
        for t in np.linspace(0.0, t_clear, 25):
            assert _lowest_body_z(places, e, d.move, t) >= BODY_CLEAR_Z_M - 1e-9
        assert _lowest_body_z(places, e, d.move, t_clear + 0.002) < BODY_CLEAR_Z_M + 3e-4


def _searched(places: Places) -> HighClear:
    """The same hand's moments with no table: every one searched by forward kinematics."""
    return HighClear(places.hand, places.atlases)


def test_the_shipped_moments_are_those_searched(places):
    """Every posture's table ships the moments (``MoveTable.clear_s``); on 30 entries of
    each they are, bit for bit, what the search finds on the entry's own moves (the
    planner reads them there: ``HighClear._shipped``)."""
    searched = _searched(places)
    rng = np.random.default_rng(7)
    for moves in places.moves:
        assert len(moves.table.clears) == len(moves.table.crossings) > 1000
        entries = [e for e in moves.atlas._entries.values() if e is not None]
        for i in rng.choice(len(entries), 30, replace=False):
            e = entries[i]
            row = [moves.table.clear_s(e, c, params()) for c in range(3)]
            assert None not in row
            assert row == searched.clear_row(e, moves)
            assert row == places.high.clear_row(e, moves)
            assert places.high.rise_clear_s(e, moves.lift(e, "high").move) == row[0]


def test_a_move_not_the_entrys_own_is_searched(places):
    """A move the table does not hold (another pose's lift, here one slowed to twice
    its time) is searched, not read: its moment is its own."""
    searched = _searched(places)
    e = next(_entries(places))
    u = places.lift(e, "high").move
    slow = slowed(u, 2.0)
    got = places.high.rise_clear_s(e, slow)
    assert got == searched.rise_clear_s(e, slow)
    assert got != places.high.rise_clear_s(e, u)


def test_moments_of_other_parameters_are_not_read(places):
    moves = places.moves[0]
    e = next(_entries(places))
    assert moves.table.clear_s(e, 0, params()) is not None
    assert moves.table.clear_s(e, 0, params().replace("samples", "points")) is None
