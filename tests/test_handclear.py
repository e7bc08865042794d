"""The second hand's clearance on the poses that press each note (``planner.play.handclear``):
each place's own reach within the hand's farthest, the loosened bound never tighter than
the farthest-reach rule's, the least reach a note needs, and the check's judge finding the
notes whose windows hold a collision."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planner.music import keyboard as kb
from planner.music.midi import Note
from planner.play.costs import Costs
from planner.play.handclear import NoteReaches, collided_notes, least_reach_m, loose_bound
from planner.play.hands import LEFT, RIGHT
from planner.play.places import RAIL_STEP_M
from planner.play.twobounds import UNBOUNDED_M
from planner.play.twohands import PairPlanner


@pytest.fixture(scope="module")
def pair() -> PairPlanner:
    from planner.hand.model import load_hand

    return PairPlanner(load_hand("default-left"), load_hand("default"))


def _costs(pair, side, notes):
    pl = pair.planners[side]
    return Costs(notes, pl.places, 100.0, pl.memo)


@pytest.mark.parametrize("side", [LEFT, RIGHT])
def test_place_reach_within_the_farthest_and_mostly_less(pair, side) -> None:
    # (every place's reach over its four poses is one of the poses the farthest reach is
    # the most of; most places reach less: what the loosened bound gains)
    costs = _costs(pair, side, [Note(p, 0.0, 0.5, 80) for p in range(55, 80)])
    pr = pair.place_reach[side]
    got = [pr.reach_m(f, costs.notes[k].pitch, q) for k in range(len(costs.notes))
           for f in costs.places.hand.fingers for q in costs.rails(f, k)]
    most = pair.reach(side).inner_extent_m
    assert got and max(got) <= most + 1e-9
    assert float(np.median(got)) < most - 0.01
    # (a place no entry presses from, the key half a metre away: never clear)
    far = costs.places.place(0, round((kb.key(60).center_x_m - 0.5) / RAIL_STEP_M))
    assert pr.reach_m("index", 60, far) == math.inf


@pytest.mark.parametrize("side", [LEFT, RIGHT])
def test_least_reach_is_beyond_the_key_and_within_the_farthest(pair, side) -> None:
    costs = _costs(pair, side, [Note(64, 0.0, 0.5, 80)])
    x = kb.key(64).center_x_m
    need = least_reach_m(NoteReaches(costs, pair.place_reach[side]), 0, side)
    assert need is not None
    # (the finger on the key reaches past its centre towards the other hand, and no
    # further than a place at the farthest reach)
    if side == LEFT:
        assert x < need < x + pair.reach(LEFT).inner_extent_m
    else:
        assert x - pair.reach(RIGHT).inner_extent_m < need < x


@pytest.mark.parametrize("side", [LEFT, RIGHT])
def test_loose_bound_never_tighter_than_the_farthest_reach_rule(pair, side) -> None:
    costs = _costs(pair, side, [Note(64, 0.0, 0.5, 80)])
    pr = pair.place_reach[side]
    nr = NoteReaches(costs, pr)
    x = kb.key(64).center_x_m
    reach = pair.reach(side).inner_extent_m
    for d in (0.0, 0.02, 0.04, 0.06, 0.1, 0.2):
        lim = x + d if side == LEFT else x - d  # (the bodies may reach this far)
        strict = (-UNBOUNDED_M, lim - reach) if side == LEFT else (lim + reach, UNBOUNDED_M)
        lo, hi = loose_bound(nr, 0, side, lim, strict)
        assert (hi >= strict[1] and lo == strict[0]) if side == LEFT else (
            lo <= strict[0] and hi == strict[1])
        # (every place the loosened bound was made of keeps its bodies within the limit)
        ok = [costs.places.rail_m(q) for f in costs.places.hand.fingers
              for q in costs.rails(f, 0)
              if (costs.places.rail_m(q) + pr.reach_m(f, 64, q) <= lim if side == LEFT
                  else costs.places.rail_m(q) - pr.reach_m(f, 64, q) >= lim)]
        if ok:
            assert (hi == max(max(ok), strict[1])) if side == LEFT else (
                lo == min(min(ok), strict[0]))
        else:
            assert (lo, hi) == strict
    # (the other hand's bodies just as far as the least this note needs: the farthest-reach
    # rule refuses every place, the places' own reach keeps the one that needs least)
    lim = least_reach_m(nr, 0, side)
    strict = (-UNBOUNDED_M, lim - reach) if side == LEFT else (lim + reach, UNBOUNDED_M)
    rails = [costs.places.rail_m(q) for f in costs.places.hand.fingers for q in costs.rails(f, 0)]
    lo, hi = loose_bound(nr, 0, side, lim, strict)
    inside = [r for r in rails if lo - 1e-9 <= r <= hi + 1e-9]
    strict_in = [r for r in rails if strict[0] - 1e-9 <= r <= strict[1] + 1e-9]
    assert not strict_in and inside


def test_collided_notes_finds_the_windows_of_the_rows_too_near(pair) -> None:
    pl, pr = pair.planners[LEFT], pair.planners[RIGHT]
    rl, rr = pair.hands[LEFT].index["rail"], pair.hands[RIGHT].index["rail"]
    n = 300
    t = np.arange(n) / 100.0
    ql = np.repeat(pl.rest_q[None], n, axis=0)
    qr = np.repeat(pr.rest_q[None], n, axis=0)
    ql[:, rl], qr[:, rr] = 0.0, 0.5  # (half a metre apart: clear)
    edges = (pair.edges[LEFT], pair.edges[RIGHT])
    wins = [(-math.inf, 1.0), (0.5, 2.0), (2.0, math.inf)]
    assert collided_notes(t, ql, qr, edges, 0.0, wins, 0.01, pair.gap.clearance_m) == set()
    qr[100:150, rr] = 0.05  # (the right hand over the left one from 1.0 s to 1.5 s)
    assert collided_notes(t, ql, qr, edges, 0.0, wins, 0.01, pair.gap.clearance_m) == {0, 1}
    # (a collision no window holds: None)
    assert collided_notes(t, ql, qr, edges, 0.0, [(2.5, 3.0)], 0.01,
                          pair.gap.clearance_m) is None


def test_a_handed_note_refused_for_the_first_hands_bodies_is_named_by_the_first_hands_reason(
) -> None:
    from types import SimpleNamespace

    from planner.play.costs import Skip, SkipReason
    from planner.play.twoplan import left_out_of

    def plan(*skips):
        return SimpleNamespace(verdict=SimpleNamespace(skipped=list(skips)))

    # (song notes 0..3: the right hand, planned first, has 0, 1, 2 and leaves 1 (late) and
    # 2 (held) out; the left hand has its own 3 and both handed notes: it refuses 1 for
    # the right hand's bodies, 2 for being late, and its own 3 for the right hand's bodies)
    right = plan(Skip(1, SkipReason.TOO_LATE, "late"), Skip(2, SkipReason.HELD, "held"))
    left = plan(Skip(0, SkipReason.OTHER_HAND, "bodies"), Skip(1, SkipReason.TOO_LATE, "late2"),
                Skip(2, SkipReason.OTHER_HAND, "bodies2"))
    planned_of = ((1, 2, 3), (0, 1, 2))
    notes_of = ((1, 2, 3), (0,))
    got = dict(left_out_of((left, right), planned_of, notes_of))
    assert sorted(got) == [1, 2, 3]
    # (the loss is the right hand's: its reason, the refusal in the detail)
    assert got[1].reason is SkipReason.TOO_LATE
    assert got[1].detail.startswith("late;") and got[1].detail.endswith("bodies")
    assert got[2].reason is SkipReason.TOO_LATE and got[2].detail == "late2"
    assert got[3].reason is SkipReason.OTHER_HAND and got[3].detail == "bodies2"


def _gathered(costs, pr, note):
    """``note``'s places' rails and reaches gathered afresh (no ``PlaceReach.presses``)."""
    qs = [(f, q) for f in costs.places.hand.fingers for q in costs.rails(f, note)]
    return (np.array([costs.places.rail_m(q) for _, q in qs]),
            np.array([pr.reach_m(f, costs.notes[note].pitch, q) for f, q in qs]))


@pytest.mark.parametrize("side", [LEFT, RIGHT])
def test_note_reaches_shared_by_key_and_force_equal_a_fresh_gathering(pair, side) -> None:
    pr = pair.place_reach[side]
    a = _costs(pair, side, [Note(64, 0.0, 0.5, 80)])
    # (the same key and velocity at another position, among other notes; and softer)
    b = _costs(pair, side, [Note(60, 0.0, 0.2, 80), Note(64, 1.0, 1.3, 80),
                            Note(64, 2.0, 2.5, 20)])
    got_a = NoteReaches(a, pr).of(0)
    nr_b = NoteReaches(b, pr)
    assert nr_b.of(1) is got_a  # (gathered once for the key and force)
    for costs, nr, k in ((a, NoteReaches(a, pr), 0), (b, nr_b, 0), (b, nr_b, 1), (b, nr_b, 2)):
        rail, reach = nr.of(k)
        fresh_rail, fresh_reach = _gathered(costs, pr, k)
        assert rail.size and np.array_equal(rail, fresh_rail)
        assert np.array_equal(reach, fresh_reach)


def test_note_reaches_refuse_bounded_costs_and_other_places(pair) -> None:
    pl = pair.planners[LEFT]
    bounded = Costs([Note(64, 0.0, 0.5, 80)], pl.places, 100.0, pl.memo, [(-1.0, 1.0)])
    with pytest.raises(ValueError):
        NoteReaches(bounded, pair.place_reach[LEFT])
    with pytest.raises(ValueError):
        NoteReaches(_costs(pair, LEFT, [Note(64, 0.0, 0.5, 80)]), pair.place_reach[RIGHT])
