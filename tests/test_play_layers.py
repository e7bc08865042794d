"""The programme's states after a move of the arm (planner/play/layers.py ``rode_to``,
planner/play/costs.py ``State.rode``): a note that rode along is where it rode to."""

from __future__ import annotations

from planner.play.costs import State
from planner.play.layers import rode_to


def test_a_rider_is_where_it_rode_to():
    recent = ((3, "pinky", 8), (2, "middle", 8))
    assert rode_to(recent, (), 7) is recent
    assert rode_to(recent, ((3, "pinky", 0.41),), 7) == ((2, "middle", 8), (3, "pinky", 7))
    # (a finger's other note is not moved: by note and finger)
    assert rode_to(recent, ((4, "pinky", 0.41),), 7) == ((2, "middle", 8), (3, "pinky", 8))


def test_states_differ_by_when_their_riders_are_free():
    a = State(7, ((4, "ring"),), ((3, "pinky", 7),), (), ((3, 0.41),))
    b = State(7, ((4, "ring"),), ((3, "pinky", 7),), (), ((3, 0.42),))
    assert a != b and a == State(7, ((4, "ring"),), ((3, "pinky", 7),), (), ((3, 0.41),))
    assert hash(a) == hash(State(7, ((4, "ring"),), ((3, "pinky", 7),), (), ((3, 0.41),)))
