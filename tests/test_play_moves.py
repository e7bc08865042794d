"""planner.play.moves and its shipped table (planner.play.movetable): what the table
says is what the forward kinematics finds, and a table made otherwise is not used."""

from __future__ import annotations

from dataclasses import fields, replace

import numpy as np
import pytest

from planner.hand.chain import FrameChain
from planner.hand.model import load_hand
from planner.play.atlas import Atlas
from planner.play.moves import REPEAT_PARAMS, Moves
from planner.play.movetable import MoveTable, add_proofs, add_repeats, make_table, table_path


@pytest.fixture(scope="module")
def moves():
    hand = load_hand("default")
    return Moves(hand, Atlas(hand))


@pytest.fixture(scope="module")
def by_fk(moves):
    """The same hand's moves with no table: everything found by forward kinematics."""
    m = Moves(moves.hand, moves.atlas)
    m.table = MoveTable(moves.hand.fingers, moves.atlas.natural_dx)
    return m


def _entries(moves):
    return [e for e in moves.atlas._entries.values() if e is not None]


def _same_finger_pairs(E, rng, n):
    """``n`` random pairs (a, b, a's finger's entries) of entries of one finger."""
    for _ in range(n):
        a = E[rng.integers(len(E))]
        mine = [e for e in E if e.finger == a.finger]
        yield a, mine[rng.integers(len(mine))], mine


def test_the_default_hand_ships_its_move_table(moves):
    assert table_path(moves.hand.urdf_sha256).exists()
    assert len(moves.table.crossings) == len(_entries(moves)) > 1000


def test_frame_chain_is_pinocchio_forward_kinematics(moves):
    h = moves.hand
    rng = np.random.default_rng(1)
    Q = h.apply_couplings(h.lower + (h.upper - h.lower) * rng.random((40, h.n)))
    for i, f in enumerate(h.fingers):
        ref = np.array([h.tip_position(q, i) for q in Q])
        np.testing.assert_allclose(FrameChain(h, f"{f}_tip").positions(Q), ref, atol=1e-14)


def test_shipped_crossings_equal_the_forward_kinematics(moves, by_fk):
    rng = np.random.default_rng(3)
    E = _entries(moves)
    for i in rng.choice(len(E), 25, replace=False):
        e = E[i]
        for p in ("high", "hover", "rise"):
            assert moves.descend(e, p).cross_s == by_fk.descend(e, p).cross_s
            assert moves.lift(e, p).cross_s == by_fk.lift(e, p).cross_s
        d = moves.descend(e, "high")
        assert 0.0 < d.cross_s <= d.duration_s


def test_shipped_paths_across_equal_the_forward_kinematics(moves, by_fk):
    rng = np.random.default_rng(4)
    E = _entries(moves)
    seen = {True: 0, False: 0}
    for a, b, mine in _same_finger_pairs(E, rng, 300):
        fk = by_fk.across(a, b) is not None
        assert moves.table.across_clear(a, b) is fk
        seen[fk] += 1
    # (the default hand's fingers, nearly straight in its play postures, cross clear
    # between every pair of entries; the forward kinematics does refuse a move that
    # ends low: the test can fail)
    assert seen[True] and by_fk.across(a, replace(b, high=b.press)) is None


def test_shipped_follows_equal_the_forward_kinematics(moves, by_fk):
    rng = np.random.default_rng(5)
    E = _entries(moves)
    seen = {True: 0, False: 0}
    pairs = []
    for _ in range(3000):  # (300 random pairs, and the first 20 the table finds not clear:
        # 0.1 % of them, the stop margins keeping the fingers from their widest reach)
        a = E[rng.integers(len(E))]
        same_key = [e for e in E if e.finger == a.finger and e.pitch_class == a.pitch_class]
        b = same_key[rng.integers(len(same_key))]
        if len(pairs) < 300 or (not moves.table.follow_clear(a, b) and seen[False] < 20):
            seen[False] += len(pairs) >= 300
            pairs.append((a, b))
    seen[False] = 0
    for a, b in pairs:
        fk = by_fk._follow(a, b) is not None
        assert moves.table.follow_clear(a, b) is fk
        seen[fk] += 1
    assert seen[True] and seen[False]


def test_a_table_of_other_parameters_is_not_used(moves, tmp_path):
    hand = load_hand("default")
    small = Moves(hand, Atlas(hand))
    keep = {k: e for k, e in small.atlas._entries.items()
            if e is not None and k[0] == "index" and k[1] in (0, 1)}
    small.atlas._entries = keep
    small.table = MoveTable(hand.fingers, small.atlas.natural_dx)
    path = tmp_path / "moves.npz"
    assert make_table(small, path, small.params()) == len(keep)
    # (the tendon proof's gains and the repeats go in after, as make_atlas adds them)
    assert add_proofs(small, path) and add_repeats(small, path) == len(keep)
    other = MoveTable(hand.fingers, small.atlas.natural_dx)
    other.load(path, small.params().replace("cross_tol", "tol"))
    assert other.crossings == {}
    same = MoveTable(hand.fingers, small.atlas.natural_dx)
    same.load(path, small.params())
    assert len(same.crossings) == len(keep)
    e = next(iter(keep.values()))
    assert same.crossing(e, 0) == moves.descend(e, "high").cross_s
    # (the tendon proof's bound of the finger's box written into it, read by the
    # table made with the same parameters only)
    lo, hi = small.high_boxes()["index"]
    proof = small.tendons.proof
    assert same.proof_gain("index", lo, hi, proof.params()) is not None
    assert other.proof_gain("index", lo, hi, proof.params()) is None
    # (each entry's repeat likewise, and not for a table of another repeat: another
    # re-arm height, or other columns)
    assert same.repeat_row(e, REPEAT_PARAMS) == small.repeat_found(e)
    assert other.repeat_row(e, REPEAT_PARAMS) is None
    assert same.repeat_row(e, REPEAT_PARAMS.replace("rearm_m", "rearm_mm")) is None
    assert same.repeat_row(e, REPEAT_PARAMS.replace("gap_s", "gap")) is None


def test_the_programmes_durations_are_the_moves_own(moves, by_fk):
    """``across_s`` and ``follow_s`` (no Move made) are, bit for bit, the durations of the
    moves ``across`` and ``follow`` make (the motion plays those: the programme's costs
    are their times); ``follow_clear`` is whether ``follow`` makes one."""
    rng = np.random.default_rng(6)
    E = _entries(moves)
    seen = {"across": 0, "across None": 0, "follow": 0, "follow None": 0}
    for a, b, mine in _same_finger_pairs(E, rng, 400):
        lat = moves.across(a, b)
        assert moves.across_s(a, b) == (None if lat is None else lat.duration_s)
        seen["across" if lat is not None else "across None"] += 1
        same_key = [e for e in mine if e.pitch_class == a.pitch_class]
        c = same_key[rng.integers(len(same_key))]
        fol = moves.follow(a, c)
        assert moves.follow_s(a, c) == moves._follow_ends(a, c)[2].duration_s
        assert moves.follow_clear(a, c) is (fol is not None)
        if fol is not None:
            assert moves.follow_s(a, c) == fol.duration_s
        seen["follow" if fol is not None else "follow None"] += 1
    # (a move across that is not clear: to an entry whose crossing height were its press,
    # found by forward kinematics; the default hand's shipped pairs are all clear)
    low = replace(b, high=b.press)
    assert by_fk.across_s(a, low) is None and by_fk.across(a, low) is None
    seen["across None"] += 1
    assert all(seen.values()), seen


def test_entry_times_made_at_once_are_those_made_one_by_one(moves):
    """The set-up's ``entry_times`` of every entry (``move_times_s`` over arrays) are, bit
    for bit, what the entry's own lifts and descents give (``entry_times`` when first
    asked)."""
    E = _entries(moves)
    assert len(moves._times) == len(E)
    for e in E[::7]:
        made = moves.entry_times(e)
        del moves._times[id(e)]
        assert moves.entry_times(e) == made
        d, u = moves.descend(e, "high"), moves.lift(e, "high")
        assert made[2] == (d.duration_s - d.cross_s) + u.cross_s and made[1] == d.cross_s


def test_the_records_read_the_table_as_it_is(moves):
    """The programme's questions read each entry's record (its poses as floats, its
    places in the move table) and the tables as bytes: the same answers as the table's
    arrays, the same poses as the entry's (after a record made when first asked too)."""
    rng = np.random.default_rng(7)
    E = _entries(moves)
    seen = {True: 0, False: 0}
    for a, b, mine in _same_finger_pairs(E, rng, 400):
        ra, rb = moves._record(a), moves._record(b)
        ok = moves._across_clear(a, b, ra.places, rb.places)
        assert ok is moves.table.across_clear(a, b)
        seen[ok] += 1
        c = next(e for e in mine[rng.integers(len(mine)):] + mine
                 if e.pitch_class == a.pitch_class)
        assert moves.follow_clear(a, c) is moves.table.follow_clear(a, c)
    assert seen[True]  # (every pair of the default hand's crosses clear: above)
    e = E[11]
    made = moves._record(e)
    del moves._times[id(e)]
    assert moves._record(e) == made and made.places == moves.table.index(e)
    assert made.high == e.high.tolist() and made.press == e.press.tolist()


def test_a_repeat_bounces_to_the_rearm_height_and_back(moves):
    """The repeat (``Moves.repeat``): one bounce up the entry's press -> rise line, its
    finger's lowest point ``REARM_M`` above the key-down depth at its turn, its key down
    until ``cross_s`` and again from as long before its end, up between (forward
    kinematics of the rows' joints); ``repeat_gap_s`` is that time up, shorter than the
    lift and descent from rest to the same top (``repeat_pair``), which are shorter than
    those to the atlas's rise pose (the repeat before); on the default hand the key is up
    11.3 ms (median of 40 entries; the jerk-only bounce before: 12.1; from rest to the
    rise and back: 30 ms), under 0.6 of that in every entry."""
    from planner.music import keyboard as kb
    from planner.play.moves import REARM_M

    rng = np.random.default_rng(8)
    E = _entries(moves)
    gaps = []
    for e in (E[i] for i in rng.choice(len(E), 40, replace=False)):
        b = moves.repeat(e)
        if b is None:  # (the rise keeps a body of its finger at the key-down depth)
            continue
        depth = moves._depth_fn(e)
        turn = depth(b.move.at(0.5 * b.move.duration_s)[0])
        sigma, _ = moves.repeat_apex(e)
        assert turn == pytest.approx(kb.DOWN_DEPTH_M - REARM_M, abs=2e-5) or sigma == 1.0
        T, up = b.move.duration_s, b.cross_s
        for t, down in ((up - 1e-4, True), (up + 1e-4, False), (T - up - 1e-4, False),
                        (T - up + 1e-4, True), (0.0, True), (T, True)):
            assert (depth(b.move.at(t)[0]) >= kb.DOWN_DEPTH_M) == down, (t, T, up)
        gap = moves.repeat_gap_s(e)
        assert gap == T - 2.0 * up
        lift, desc = moves.repeat_pair(e)
        ur, dr = moves.lift(e, "rise"), moves.descend(e, "rise")
        assert gap < (lift.duration_s - lift.cross_s) + desc.cross_s \
            < (ur.duration_s - ur.cross_s) + dr.cross_s
        gaps.append((gap, (ur.duration_s - ur.cross_s) + dr.cross_s))
    assert len(gaps) >= 30
    new, old = np.array(gaps).T  # (seed 8: 10.2-18.6 ms, median 11.3; the jerk-only bounce
    # 10.8-19.8, 12.1; from rest to the rise and back 28-35, 30.4)
    assert 0.010 < float(np.median(new)) < 0.0118 and np.all(new < 0.6 * old)


def _same_timed(a, b) -> None:
    """Two ``Timed`` (or None) equal to the bit: their moves' every field, their crossing."""
    assert (a is None) == (b is None)
    if a is None:
        return
    assert type(a.move) is type(b.move) and a.cross_s == b.cross_s
    for f in fields(a.move):
        x, y = getattr(a.move, f.name), getattr(b.move, f.name)
        assert np.array_equal(x, y) if isinstance(x, np.ndarray) else x == y, f.name


def _same_repeats(shipped: Moves, found: Moves, E) -> int:
    """Every entry of ``E``: the repeat ``shipped`` reads from its move table is the one
    ``found`` (no table) works out, bit for bit (its row, ``repeat``, ``repeat_pair``,
    ``repeat_gap_s``); the number of entries without a repeat."""
    none = 0
    for e in E:
        row = shipped.table.repeat_row(e, REPEAT_PARAMS)
        assert row is not None
        np.testing.assert_array_equal(np.array(row), np.array(found.repeat_found(e)))
        assert row == shipped.repeat_row(e) and found.table.repeat_row(e, REPEAT_PARAMS) is None
        _same_timed(shipped.repeat(e), found.repeat(e))
        pair, pair_found = shipped.repeat_pair(e), found.repeat_pair(e)
        assert (pair is None) == (pair_found is None)
        for a, b in zip(pair or (), pair_found or ()):
            _same_timed(a, b)
        assert shipped.repeat_gap_s(e) == found.repeat_gap_s(e)
        none += shipped.repeat(e) is None
    return none


def test_shipped_repeats_equal_the_ones_worked_out(moves, by_fk):
    """The repeat the move table ships (``REPEAT_COLUMNS``: ``Moves.repeat_found`` when
    the table was made) is the one a hand without the table works out, to the bit, on 60
    random entries of the default hand."""
    rng = np.random.default_rng(9)
    E = _entries(moves)
    assert _same_repeats(moves, by_fk, [E[i] for i in rng.choice(len(E), 60, replace=False)]) == 0


def test_shipped_repeats_without_a_repeat_equal_the_ones_worked_out():
    """The same on every entry of the mk5 hand, 24 of whose 159 lines never let the key up
    (no repeat: NaN in the table, the gap up to crossing height and down)."""
    hand = load_hand("mk5")
    shipped = Moves(hand, Atlas(hand))
    found = Moves(hand, shipped.atlas)
    found.table = MoveTable(hand.fingers, shipped.atlas.natural_dx)
    E = _entries(shipped)
    assert len(E) == len(shipped.table.repeats)
    assert _same_repeats(shipped, found, E) > 0
