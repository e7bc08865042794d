"""A key taken over from another finger (planner/play/costs.py ``Costs._leave_key_s``): the
programme's estimate of its key-down is the motion's (planner/play/motion.py): the other
finger lifts, then the striking finger moves across from its last key and descends."""

from __future__ import annotations

import pytest

from planner.music.midi import Note
from planner.play.costs import Costs, State
from planner.play.fingering import Assignment
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


@pytest.mark.parametrize("gap_s", [0.004, 0.02, 0.04])
def test_a_key_taken_over_goes_down_when_the_programme_says(places, gap_s):
    notes = _notes(gap_s)
    costs = Costs(notes, places, 100.0)
    common = costs.rails("index", 0) & costs.rails("middle", 1) & costs.rails("index", 2)
    place = min((p for p in common if places.posture_of(p) == 0),
                key=lambda p: abs(places.rail_i(p)))
    # (the state before the third note: the middle sounding, the index's last note recent)
    state = State(place, ((1, "middle"),), ((0, "index", place),))
    lates: list = []
    costs._same_rail_loss(costs.prev(state, notes[2].onset_s), {2: "index"}, lates)
    assert [n for n, _ in lates] == [2]  # (late: the key is taken over, not on time)
    planned = costs.t_down(2) + lates[0][1]

    motion = Motion(notes, places, 100.0, places.rail_m(place))
    plays = [Assignment(0, "index", places.rail_m(place)),
             Assignment(1, "middle", places.rail_m(place)),
             Assignment(2, "index", places.rail_m(place))]
    motion.expect(plays)
    for a in plays:
        assert motion.place(a).down_s is not None
    assert motion.outcomes[2].down_s == pytest.approx(planned, abs=1e-6)
