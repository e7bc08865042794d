"""What the room the hand planned first takes from the other hand's notes costs
(``planner.play.roomcost``, built by ``planner.play.twobounds.room_cost``): a dive of the
right hand over a note of its own part it does not hold (handed to the left) costs the
share of that note's frames the left would play, while the dive lasts; a place clear of
the note, or a state holding the note, costs nothing; leaving a handed note out costs the
rest of its frames, so that left out and blocked it costs all of them."""

from __future__ import annotations

from dataclasses import replace

import pytest

from planner.hand.model import load_hand
from planner.music.midi import Note, Song
from planner.play.costs import Costs, State
from planner.play.hands import LEFT, RIGHT, assign_hands
from planner.play.roomcost import RoomClaim, RoomCost
from planner.play.stream import plan_song
from planner.play.twobounds import HANDED_SHARE, room, room_cost
from planner.play.twohands import PairPlanner, plan_pass

RATE_HZ = 100.0


@pytest.fixture(scope="module")
def pair() -> PairPlanner:
    return PairPlanner(load_hand("default-left"), load_hand("default"))


def _song() -> tuple[Song, tuple[int, ...], tuple[int, ...]]:
    """The left hand's C3 (0.5-1.0 s); the right part's C4 (0.5-0.8 s), E4 (0.5-1.0 s) and
    G4 at 0.7 s: the right hand's events at 0.5 and 0.7 s."""
    notes = (Note(48, 0.5, 1.0, 80, 1), Note(60, 0.5, 0.8, 80, 0), Note(64, 0.5, 1.0, 80, 0),
             Note(67, 0.7, 0.9, 80, 0))
    return Song(notes, 1.0), (1, 2, 3), (0,)


def test_a_dive_over_a_handed_note_costs_its_frames_while_it_lasts(pair) -> None:
    song, own, other = _song()
    rc = room_cost(song, pair, RIGHT, own, other, RATE_HZ)
    pl = pair.planners[RIGHT]
    costs = Costs([song.notes[i] for i in own], pl.places, RATE_HZ, pl.memo)
    c4 = next(c for c in rc.claims if c.own == 0)  # (C4's claim: the left's least reach)
    assert (c4.t0_s, c4.t1_s) == (0.5, 0.8)
    w = HANDED_SHARE  # (a handed note's frames the left would play, paid by the room)
    rc.at(0.5)  # (the state lasts to the next event, G4 at 0.7 s: 20 frames of C4)
    blocked = clear = 0
    for f in pl.places.hand.fingers:
        for place in sorted(costs.rails(f, 1)):  # (every place pressing E4)
            edge_m = pl.places.rail_m(place) - pair.place_reach[RIGHT].reach_m(f, 64, place)
            got = rc.frames(place, ((1, f),))  # (holding E4, not C4: handed over)
            if edge_m < c4.edge_m:
                assert got == pytest.approx(20.0 * w)
                blocked += 1
            else:
                assert got == 0.0
                clear += 1
    assert blocked and clear  # (the dives down to C4 and the places above it both seen)
    rc.at(0.7)  # (G4's event lasts to the song's end: C4 sounds 10 frames more, and E4,
    # not held by a state holding G4 alone, 30 more)
    low = min(q for f in pl.places.hand.fingers for q in costs.rails(f, 2))
    assert rc.frames(low, ((2, "thumb"),)) == pytest.approx(40.0 * w)


def test_a_claim_counts_only_the_frames_within_the_event() -> None:
    # (a right hand on a rail of its place index in cm, reaching 1 cm: events at 0, 1, 2 s;
    # a note of the other hand's sounding 0.5-1.5 s needs the edge at or above 0.10 m)
    rc = RoomCost([RoomClaim(0.5, 1.5, 0.10)], RIGHT, [0.0, 1.0, 2.0], [60, 62, 64],
                  lambda f, p, q: 0.01, 0.05, lambda q: q / 100.0, RATE_HZ)
    rc.at(0.0)
    assert rc.frames(5, ((0, "index"),)) == pytest.approx(50.0)  # (0.5-1.0 s blocked)
    assert rc.frames(11, ((0, "index"),)) == 0.0  # (the edge at 0.10 m: clear)
    assert rc.frames(11, ()) == pytest.approx(50.0)  # (no note held: the farthest reach)
    rc.at(1.0)
    assert rc.frames(5, ((1, "index"),)) == pytest.approx(50.0)  # (1.0-1.5 s)
    rc.at(2.0)
    assert rc.frames(5, ((2, "index"),)) == 0.0  # (the note is over)
    # (a note of the hand's own part held by the state claims nothing)
    own = RoomCost([RoomClaim(0.0, 1.0, 0.10, own=0)], RIGHT, [0.0, 1.0], [60, 62],
                   lambda f, p, q: 0.01, 0.05, lambda q: q / 100.0, RATE_HZ)
    own.at(0.0)
    assert own.frames(5, ((0, "index"),)) == 0.0
    assert own.frames(5, ((1, "index"),)) == pytest.approx(100.0)


def test_a_note_the_hand_struck_claims_nothing_after_it_lets_it_go() -> None:
    # (the hand's own note, 0-2 s, needs the edge at or above 0.10 m: events at 0, 1 s)
    rc = RoomCost([RoomClaim(0.0, 2.0, 0.10, own=0)], RIGHT, [0.0, 1.0], [60, 62],
                  lambda f, p, q: 0.01, 0.05, lambda q: q / 100.0, RATE_HZ)
    rc.at(1.0)
    struck = State(20, ((0, "index"),))  # (the state before held it: struck, let go now)
    left_out = State(20, ((1, "index"),))  # (never struck it, its room left free)
    assert rc.frames(5, ((1, "middle"),), struck) == 0.0
    assert rc.frames(5, ((1, "middle"),), left_out) == pytest.approx(100.0)
    gone = State(20, (), recent=((0, "index", 20),))  # (its finger's last note, let go)
    assert rc.frames(5, ((1, "middle"),), gone) == 0.0


def test_a_handed_note_left_out_costs_its_frames_where_blocked_and_less_where_free() -> None:
    # (the hand's own note, 0-1 s (100 frames), needs the edge at or above 0.10 m; the
    # other hand plays, say, 0.4 of what it is handed where it has the room)
    rc = RoomCost([RoomClaim(0.0, 1.0, 0.10, own=0)], RIGHT, [0.0, 1.0], [60, 62],
                  lambda f, p, q: 0.01, 0.05, lambda q: q / 100.0, RATE_HZ, share=0.4)
    rc.at(0.0)
    left_out = rc.left_out(0, 100.0)
    assert left_out == pytest.approx(60.0)
    # (left out and blocked for its whole sounding: all its frames, as one hand pays)
    assert left_out + rc.frames(5, ((1, "index"),)) == pytest.approx(100.0)
    assert left_out + rc.frames(20, ((1, "index"),)) == pytest.approx(60.0)  # (room left)
    assert rc.left_out(1, 80.0) == 80.0  # (a note with no claim: the other hand cannot
    # press it, nothing handed)


def test_a_hand_planned_alone_pays_no_room(pair) -> None:
    # (the right hand alone, every note its own: planned as one hand plays the file, the
    # left given only what it leaves out; a room cost would make it differ)
    notes = tuple(Note(p, 0.25 * i, 0.25 * i + 0.2, 80, 0) for i, p in
                  enumerate([60, 64, 67, 72, 48, 52, 55, 60]))
    song = Song(notes, 2.5)
    places = {s: pair.planners[s].places for s in (LEFT, RIGHT)}
    a = assign_hands(song.notes, pair.gap, places, RATE_HZ).one_hand(RIGHT)
    way = plan_pass(song, pair, a, RIGHT, RATE_HZ)
    idx = a.notes_of(RIGHT)
    sub = replace(song, notes=tuple(notes[i] for i in idx), part=None)
    bounds = room(song, pair, RIGHT, idx, (), sub, RATE_HZ)
    one = plan_song(sub, pair.hands[RIGHT], None, RATE_HZ, planner=pair.planners[RIGHT],
                    rail_bounds=bounds)
    assert way.alone and way.plans[1].text == one.text
