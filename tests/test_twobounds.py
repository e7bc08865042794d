"""The two hands' rail bounds (``planner.play.twobounds``): the windows of a hand's notes,
the second hand's bounds from the first hand's inner edge, ``settle``, and the first
hand's room settled (a note of its own no place plays within its room: the hand stands
where it was through it, and leaves the other hand its room there)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from planner.hand.model import load_hand
from planner.music.midi import Note, Song
from planner.play.costs import SkipReason
from planner.play.handclear import collided_notes
from planner.play.hands import LEFT, RIGHT, SIDES, assign_hands
from planner.play.twobounds import (
    UNBOUNDED_M,
    clear_bounds,
    room_cost,
    room_settled,
    settle,
    windows,
)
from planner.play.twohands import PairPlanner, plan_pass, plan_two_hands
from planner.play.twoplan import one_clock

RATE_HZ = 100.0


@pytest.fixture(scope="module")
def pair() -> PairPlanner:
    return PairPlanner(load_hand("default-left"), load_hand("default"))


def test_windows_skip_the_notes_out_of_reach() -> None:
    notes = [Note(60, t, t + 0.2, 80) for t in (0.0, 1.0, 2.0, 3.0)]
    w = windows(notes, (0, 1, 2, 3))
    assert w[0] == (-math.inf, 1.1) and w[1] == (0.0, 2.1) and w[3] == (2.0, math.inf)
    # (the note at 2 s played by no place: the hand stays from the one at 1 s to 3 s)
    w = windows(notes, (0, 1, 2, 3), frozenset({2}))
    assert w[1] == (0.0, 3.1) and w[3] == (1.0, math.inf)


def test_left_bound_is_the_right_rail_less_the_gap_over_the_window(pair) -> None:
    notes = [Note(48, 1.0, 1.2, 80), Note(50, 2.0, 2.2, 80)]
    t = np.arange(0, 400) / 100.0
    rail = np.where(t < 1.5, 0.30, 0.10)  # (the right hand comes down at 1.5 s)
    gap = pair.gap  # (the right hand's bodies at their farthest reach whatever its pose)
    b = clear_bounds(notes, LEFT, (0, 1), t, rail - gap.right.inner_extent_m,
                     gap.left.inner_extent_m + gap.clearance_m, 0.01)
    # (the first note's window lasts to the second's onset and half of it: it holds the
    # rail from before the right hand came down to after)
    assert b[0][1] == pytest.approx(0.10 - pair.gap.rail_gap_m)
    assert b[1][1] == pytest.approx(0.10 - pair.gap.rail_gap_m)


def test_clear_bounds_keep_the_reach_from_the_first_hands_edge() -> None:
    notes = [Note(48, 1.0, 1.2, 80), Note(72, 1.0, 1.2, 80)]
    t = np.arange(0, 300) / 100.0
    edge = np.where(t < 1.5, 0.20, 0.25)  # (the first hand's inner edge, row by row)
    (lo, hi), = clear_bounds(notes, LEFT, (0,), t, edge, 0.1, 0.01)
    assert lo == -UNBOUNDED_M and hi == pytest.approx(0.10)  # (its least, less the reach)
    (lo, hi), = clear_bounds(notes, RIGHT, (1,), t, edge, 0.1, 0.01)
    assert hi == UNBOUNDED_M and lo == pytest.approx(0.35)  # (its most, plus the reach)


def _count_reasons(monkeypatch) -> list[int]:
    """The notes ``Costs.reason`` is asked about from now on, in order (patched)."""
    from planner.play.costs import Costs

    asked: list[int] = []
    reason = Costs.reason

    def counted(self, k):
        asked.append(k)
        return reason(self, k)

    monkeypatch.setattr(Costs, "reason", counted)
    return asked


def test_settle_asks_no_note_out_again(pair, monkeypatch) -> None:
    """``settle``: a note taken out stays out (windows only grow, bounds only tighten),
    so the next round asks only the others, and of those only the ones whose bound
    changed (here none: each note asked once); the same bounds and notes out."""
    from planner.music import keyboard as kb

    pl = pair.planners[LEFT]
    notes = [Note(p, 0.5 * i, 0.5 * i + 0.3, 80) for i, p in enumerate((48, 50, 72, 52, 53))]
    hi = kb.key(60).center_x_m - 0.05  # (the left hand's rail below middle C: C5 out)
    asked = _count_reasons(monkeypatch)
    bounds, out = settle(notes, pl.places, pl.memo, 100.0,
                         lambda out: [(-UNBOUNDED_M, hi)] * len(notes))
    assert out == frozenset({2}) and bounds == [(-UNBOUNDED_M, hi)] * len(notes)
    assert sorted(asked) == [0, 1, 2, 3, 4]


def test_settle_asks_again_only_the_notes_whose_bound_changed(pair, monkeypatch) -> None:
    """``settle`` with a bound that tightens note 3's when note 2 is out: note 3 asked
    again, no other; the same bounds and notes out as asking every note every round."""
    from planner.music import keyboard as kb
    from planner.play.costs import Costs

    pl = pair.planners[LEFT]
    notes = [Note(p, 0.5 * i, 0.5 * i + 0.3, 80) for i, p in enumerate((48, 50, 72, 52, 53))]
    hi = kb.key(60).center_x_m - 0.05  # (the left hand's rail below middle C: C5 out)
    tight = kb.key(52).center_x_m - 0.3  # (E3 out of reach from below it)

    def bounds_of(out):
        return [(-UNBOUNDED_M, tight if k == 3 and 2 in out else hi) for k in range(5)]

    def every_round():  # (the rounds asking every note not out)
        out: frozenset[int] = frozenset()
        while True:
            costs = Costs(notes, pl.places, 100.0, pl.memo, bounds_of(out))
            now = frozenset(k for k in range(5) if k not in out and costs.reason(k))
            if not now:
                return bounds_of(out), out
            out |= now

    want = every_round()
    asked = _count_reasons(monkeypatch)
    got = settle(notes, pl.places, pl.memo, 100.0, bounds_of)
    assert got == want and got[1] == frozenset({2, 3})
    assert sorted(asked) == [0, 1, 2, 3, 3, 4]


def _standing_song() -> Song:
    """The left part's F3 at 0 s, G3 at 0.5 s (under the right part's A3, 0.45-0.85 s:
    no place of the left's leaves the right its room for A3), A2 at 2.5 s; the right
    part's A3, four G3s at 1.0-1.75 s (the left plays nothing then), E4 at 2.5 s."""
    notes = [Note(53, 0.0, 0.3, 80, 1), Note(57, 0.45, 0.85, 80, 0), Note(55, 0.5, 0.8, 80, 1)]
    notes += [Note(55, 1.0 + 0.25 * j, 1.2 + 0.25 * j, 80, 0) for j in range(4)]
    notes += [Note(45, 2.5, 2.8, 80, 1), Note(64, 2.5, 2.8, 80, 0)]
    return Song(tuple(notes), 2.8)


def test_the_hand_planned_first_leaves_room_where_it_stands_through_a_note_out(pair) -> None:
    song = _standing_song()
    places = {s: pair.planners[s].places for s in SIDES}
    a = assign_hands(song.notes, pair.gap, places, RATE_HZ)
    own, other = a.notes_of(LEFT), a.notes_of(RIGHT)
    assert own == (0, 2, 7) and other == (1, 3, 4, 5, 6, 8)
    sub = replace(song, notes=tuple(song.notes[i] for i in own), part=None)
    out = room_settled(song, pair, LEFT, own, other, sub, RATE_HZ)[1]
    # (the left's G3 is no event of the left's: it stands at F3's place until A2, so F3's
    # window, and the room it leaves, runs over the right's G3s; no place of F3's leaves
    # it, so F3 is out too: the left moves in for A2 only)
    assert out == frozenset({0, 1})
    assert windows(song.notes, own, frozenset({1}))[0][1] > 2.5
    # (and the room's charge: a state lasts to the hand's next event, A2's)
    assert room_cost(song, pair, LEFT, own, other, RATE_HZ, out).onsets_s == [2.5]
    p = plan_pass(song, pair, a, LEFT, RATE_HZ, settled=True)
    r = SIDES.index(RIGHT)
    refused = {p.planned_of[r][s.note] for s in p.plans[r].verdict.skipped
               if s.reason is SkipReason.OTHER_HAND}
    # (the right plays its four G3s: the room as the windows give it (not settled) has the
    # left stand over them from F3's place, all four refused for it: 130 frames against 210)
    assert not refused & {3, 4, 5, 6}
    assert p.played_frames == 210.0 and p.way == "left first settled"
    off = plan_pass(song, pair, a, LEFT, RATE_HZ)
    assert {off.planned_of[r][s.note] for s in off.plans[r].verdict.skipped
            if s.reason is SkipReason.OTHER_HAND} >= {3, 4, 5, 6}
    assert off.played_frames == 130.0
    # (``plan_two_hands`` plans each order with both rooms, the settled one where it takes
    # a note out: here right first 120 frames, settled 240; left first 130, settled 210)
    two = plan_two_hands(song, pair)
    assert dict(two.tried) == {"right first": 120.0, "left first": 130.0, "right alone": 240.0,
                               "right first settled": 240.0, "left first settled": 210.0}
    assert two.way == "right alone"  # (the earlier of equals: the old ways first)
    played = {i for k, i in enumerate(p.planned_of[r])
              if k not in {s.note for s in p.plans[r].verdict.skipped}}
    assert {3, 4, 5, 6} <= played
    # (and no row of the two hands' under the clearance: the check's judge)
    rows = one_clock(p.plans, RATE_HZ)
    assert collided_notes(rows.t_s, rows.q[0], rows.q[1], (pair.edges[LEFT], pair.edges[RIGHT]),
                          rows.song_start_s, [(-math.inf, math.inf)], 1.0 / RATE_HZ,
                          pair.gap.clearance_m) == set()
