"""The follow test's shipped answers (planner.play.followtable) and the batched follow
test they are made with (follow.paths_clear_each): the answers the code gives, move by
move, on real moves of the default hand."""

from __future__ import annotations

import numpy as np
import pytest

from planner.hand.model import load_hand
from planner.play import follow
from planner.play.followtable import (
    FollowTable,
    answer_pairs,
    cross_pairs,
    domain,
    ends,
    params,
    table_path,
)
from planner.play.places import RAIL_STEP_M, Places


@pytest.fixture(scope="module")
def places():
    return Places(load_hand("default"))


def _one_by_one(places, finger: str, pitch: int, pairs: list) -> list[bool]:
    """``paths_clear`` asked move by move, its memo emptied first (found, not read)."""
    follow._ANSWERS.clear()
    out = []
    for qa, a, qb, b in pairs:
        QA, QB = places.follow_ends_on_rail(a, b, places.rail_m(qa), places.rail_m(qb))
        out.append(bool(follow.paths_clear(places.atlas, finger, pitch, QA[None], QB[None],
                                           places.arm)[0]))
    follow._ANSWERS.clear()
    return out


def test_the_batch_answers_as_each_move_alone(places):
    """``paths_clear_each`` of every pair of places of three fingers on four keys (white
    and black, moves of 12 to more than 30 samples in one array) is ``paths_clear`` of
    each move asked alone; both answers occur."""
    seen = set()
    counts = set()
    for fi, pitch, pairs in domain(places, ("thumb", "index", "ring"), (47, 53, 61, 64)):
        f = places.hand.fingers[fi]
        follow._ANSWERS.clear()
        got = answer_pairs(places, fi, pitch, pairs).tolist()
        assert got == _one_by_one(places, f, pitch, pairs), (f, pitch)
        seen |= set(got)
        counts |= {follow.samples(abs(places.rail_m(qb) - places.rail_m(qa)))
                   for qa, _, qb, _ in pairs}
    assert seen == {True, False}
    assert min(counts) == follow.samples(0.0) and max(counts) > 30


def test_the_shipped_table_is_what_the_code_computes(places):
    """The default hand's table is loaded (made with its entries and parameters) and
    every row of two fingers on six keys across the keyboard, and 12 rows drawn at
    random of three fingers on every seventh key, is the answer found by forward
    kinematics, and ``follow_path_clear``'s; both answers occur."""
    assert len(places.follows) > 50_000
    rng = np.random.default_rng(11)
    rows = domain(places, ("index", "pinky"), (21, 47, 58, 64, 95, 108))
    fixed = len(rows)
    rows += domain(places, ("thumb", "middle", "ring"), range(21, 109, 7))
    seen = set()
    for i, (fi, pitch, pairs) in enumerate(rows):
        if i >= fixed:  # (the drawn ones)
            pairs = [pairs[j] for j in rng.choice(len(pairs), min(len(pairs), 12), replace=False)]
        f = places.hand.fingers[fi]
        want = _one_by_one(places, f, pitch, pairs)
        got = [places.follows.get(fi, pitch, qa, qb) for qa, _, qb, _ in pairs]
        assert got == want, (f, pitch)
        assert [places.follow_path_clear(a, b, pitch, places.rail_m(qa), places.rail_m(qb))
                for qa, a, qb, b in pairs] == want
        seen |= set(want)
    assert seen == {True, False}


def test_a_question_off_the_table_is_found(places):
    """A rail off the grid, or entries that are not the finger's at those places, are
    not the table's moves: ``follow_path_clear`` finds them by forward kinematics."""
    _, pitch, pairs = domain(places, ("middle",), (64,))[0]
    qa, a, qb, b = next(p for p in pairs if p[0] != p[2])
    ra, rb = places.rail_m(qa), places.rail_m(qb)
    assert places._follow_row(a, b, pitch, ra, rb) is not None
    assert places._follow_row(a, b, pitch, ra + RAIL_STEP_M / 3, rb) is None
    assert places._follow_row(b, a, pitch, ra, rb) is None
    QA, QB = places.follow_ends_on_rail(a, b, ra + RAIL_STEP_M / 3, rb)
    follow._ANSWERS.clear()
    want = bool(follow.paths_clear(places.atlas, "middle", pitch, QA[None], QB[None],
                                   places.arm)[0])
    assert places.follow_path_clear(a, b, pitch, ra + RAIL_STEP_M / 3, rb) == want


def test_a_table_of_other_entries_is_not_used(places, tmp_path):
    """The parameters name every entry's press pose: one entry moved by one ulp in one
    joint gives other parameters, and a table made with other parameters is not read."""
    want = params(places)
    atlas = places.atlases[1]
    key = next(k for k, e in atlas.solved().items())
    e = atlas.solved()[key]
    old = e.press[0]
    e.press[0] = np.nextafter(old, np.inf)
    try:
        assert params(places) != want
    finally:
        e.press[0] = old
    assert params(places) == want
    t = FollowTable()
    assert t.load(table_path(places.hand.urdf_sha256), want) and len(t) == len(places.follows)
    with np.load(table_path(places.hand.urdf_sha256)) as z:
        np.savez(tmp_path / "t.npz", params=np.array(want + " "), code=z["code"],
                 answer=z["answer"])
    t = FollowTable()
    assert not t.load(tmp_path / "t.npz", want) and len(t) == 0
    assert t.get(0, 60, 0, 0) is None


def test_the_pairs_across_postures_are_what_the_code_finds(places):
    """300 of the table's pairs across postures, drawn at random, and every pair of the
    thumb on one key: ``Places.follow_clear`` and ``Places.follow_s`` read from the
    table are those a hand's ``Places`` without the table finds (the same float); both
    answers occur."""
    bare = Places(places.hand)
    bare.follows = FollowTable()
    cross = cross_pairs(places)
    codes = sorted(cross)
    rng = np.random.default_rng(5)
    pick = [codes[i] for i in rng.choice(len(codes), 300, replace=False)]
    thumb = [c for c, (a, _) in cross.items() if a.finger == "thumb" and a.pitch_class == 4]
    seen = set()
    for c in pick + thumb:
        a, b = cross[c]
        assert places._cross_row(a, b) is not None
        # (the same atlases' entries in both: the same keys and poses, other objects)
        ea = bare.atlases[a.posture].entry_at(a.finger, a.pitch_class, places.sample_of(a))
        eb = bare.atlases[b.posture].entry_at(b.finger, b.pitch_class, places.sample_of(b))
        assert places.follow_clear(a, b) == bare.follow_clear(ea, eb)
        assert places.follow_s(a, b) == bare.follow_s(ea, eb)
        seen.add(places.follow_clear(a, b))
    assert seen == {True, False}


def test_the_press_poses_are_what_the_code_finds(places):
    """Every finger on eight keys across the keyboard: the table's press answers are
    those ``Places.presses_clear`` finds without it, place by place and for the places
    of each press force (``Costs.rails``' lists: the entries strong enough); both
    answers occur."""
    bare = Places(places.hand)
    bare.follows = FollowTable()
    seen = set()
    for fi, f in enumerate(places.hand.fingers):
        for pitch in (21, 35, 44, 60, 61, 78, 97, 108):
            on = ends(places, f, pitch)
            got = [places.follows.press(fi, pitch, q) for q, _ in on]
            assert None not in got
            assert got == [bare.presses_clear(f, pitch, [q])[0] for q, _ in on]
            for force in (2.0, 6.0, 12.0):
                strong = [q for q, e in on if e.max_force_n >= force]
                assert places.presses_clear(f, pitch, strong) \
                    == bare.presses_clear(f, pitch, strong)
            seen |= set(got)
    assert seen == {True, False}
