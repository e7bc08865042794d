"""A key taken over from another finger (planner/play/costs.py ``Costs._leave_key_s``): the
programme's estimate of its key-down is the motion's (planner/play/motion.py): the other
finger lifts, then the striking finger moves across from its last key and descends."""

from __future__ import annotations

import pytest

from planner.music.midi import Note
from planner.play.costs import RECENT_S, Costs, State
from planner.play.fingering import Assignment
from planner.play.layers import Layers
from planner.play.motion import Motion
from planner.play.places import Places


@pytest.fixture(scope="module")
def places(hand) -> Places:
    return Places(hand)


def _notes(gap_s: float) -> tuple[Note, ...]:
    """The index on C4, then the middle on E4 (the index lifted), then the index on E4
    ``gap_s`` after the middle's note ends."""
    return (Note(60, 0.40, 0.45, 80), Note(64, 0.45, 0.60, 80),
            Note(64, 0.60 + gap_s, 1.20, 80))


def _index_place(costs: Costs, places: Places) -> int:
    """The posture-0 place nearest the rail's middle from which the index plays notes 0
    and 2 and the middle note 1."""
    common = costs.rails("index", 0) & costs.rails("middle", 1) & costs.rails("index", 2)
    return min((p for p in common if places.posture_of(p) == 0),
               key=lambda p: abs(places.rail_i(p)))


def _motion_down_s(notes, places: Places, place: int) -> float:
    """The motion's key-down of note 2 with the index, the middle, the index at ``place``."""
    rail_m = places.rail_m(place)
    motion = Motion(notes, places, 100.0, rail_m)
    plays = [Assignment(0, "index", rail_m), Assignment(1, "middle", rail_m),
             Assignment(2, "index", rail_m)]
    motion.expect(plays)
    for a in plays:
        assert motion.place(a).down_s is not None
    return motion.outcomes[2].down_s


@pytest.mark.parametrize("gap_s", [0.004, 0.02, 0.04])
def test_a_key_taken_over_goes_down_when_the_programme_says(places, gap_s):
    notes = _notes(gap_s)
    costs = Costs(notes, places, 100.0)
    place = _index_place(costs, places)
    # (the state before the third note: the middle sounding, the index's last note recent)
    state = State(place, ((1, "middle"),), ((0, "index", place),))
    lates: list = []
    costs._same_rail_loss(costs.prev(state, notes[2].onset_s), {2: "index"}, lates)
    assert [n for n, _ in lates] == [2]  # (late: the key is taken over, not on time)
    planned = costs.t_down(2) + lates[0][1]

    assert _motion_down_s(notes, places, place) == pytest.approx(planned, abs=1e-6)


@pytest.mark.parametrize("gap_s", [0.004, 0.04])
def test_a_key_taken_over_by_a_finger_idle_longer_than_recent(places, gap_s):
    """The index's last note (C4) ended 0.4 s before the middle's E4 and longer than
    RECENT_S before it takes E4 over: not in ``State.recent`` but in ``State.older`` (where
    it waits over C4's entry); it moves across from there once the key is free, as the
    motion plays it (before: no move across counted, 85 ms early on the default hand)."""
    notes = (Note(60, 0.4, 0.5, 80), Note(64, 0.9, 1.4, 80), Note(64, 1.4 + gap_s, 1.9, 80))
    assert notes[1].onset_s - notes[0].offset_s > RECENT_S
    costs = Costs(notes, places, 100.0)
    place = _index_place(costs, places)
    # (the programme's state after the middle's note: the index's note older than recent)
    before = costs.prev(State(place, ((0, "index"),)), notes[1].onset_s)
    recent, older = Layers._recent(before, frozenset({"middle"}))
    assert (recent, older) == ((), ((0, "index", place),))
    state = State(place, ((1, "middle"),), recent, older=older)
    lates: list = []
    costs._same_rail_loss(costs.prev(state, notes[2].onset_s), {2: "index"}, lates)
    assert [n for n, _ in lates] == [2]
    planned = costs.t_down(2) + lates[0][1]
    unmoved: list = []  # (the same without the index's older note: no move across)
    costs._same_rail_loss(costs.prev(State(place, ((1, "middle"),)), notes[2].onset_s),
                          {2: "index"}, unmoved)
    assert planned > costs.t_down(2) + dict(unmoved).get(2, 0.0) + 0.005

    assert _motion_down_s(notes, places, place) == pytest.approx(planned, abs=1e-6)
