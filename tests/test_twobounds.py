"""The two hands' rail bounds (``planner.play.twobounds``): the windows of a hand's notes,
the second hand's bounds from the first hand's inner edge, and ``settle``."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planner.hand.model import load_hand
from planner.music.midi import Note
from planner.play.hands import LEFT, RIGHT
from planner.play.twobounds import UNBOUNDED_M, clear_bounds, settle, windows
from planner.play.twohands import PairPlanner


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
