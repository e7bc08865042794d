"""A finger's moves across bounded by a box of moves at once (planner.play.acrossproof):
the move ``Moves.across`` makes is the one the per-move bound times, from an entry of the
box and from one that is not."""

from __future__ import annotations

import dataclasses

import numpy as np

from planner.hand.model import load_hand
from planner.play.atlas import Atlas
from planner.play.moves import Moves


def test_a_move_across_is_timed_as_the_full_bound_times_it():
    """``Moves.across`` (the box's proof first) against ``finger_scale`` on each of
    sixty random moves across, and on the same moves from a copy of the entry (not one
    of the box's: the box stretched to it): the same scale, the same move; the box
    proves most of them."""
    hand = load_hand("default")
    atlas = Atlas(hand)
    moves = Moves(hand, atlas)
    rng = np.random.default_rng(23)
    entries = [e for e in atlas.solved().values() if e.finger in ("index", "ring")]
    proved = tried = 0
    for _ in range(60):
        a, b = (entries[i] for i in rng.integers(len(entries), size=2))
        if a.finger != b.finger:
            continue
        for start in (a, dataclasses.replace(a)):
            move = moves._move(a.finger, start.high, b.high)
            full = moves.finger_scale(a.finger, start.high, b.high, move)
            assert moves._across_scale(start, b, move) == full
            tried += 1
            proved += moves.across_proof.proves(start, b, move)
            got = moves.across(start, b)
            assert got is not None and got.duration_s == move.duration_s * full
    assert proved > 0.8 * tried
