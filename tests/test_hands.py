"""Which hand plays each note (``planner.play.hands``): the file's parts as the hint, and the
three reasons a note changes hands (span, crossing, time), weighed in frames."""

from __future__ import annotations

import pytest

from planner.hand.model import load_hand
from planner.music.midi import Note
from planner.play.handgap import HandGap, HandReach
from planner.play.hands import (
    LEFT,
    RIGHT,
    HintSource,
    MoveReason,
    assign_hands,
    hint_hands,
)
from planner.play.places import Places

# (the default pair's numbers as measured, ``hand_gap``; fixed here: the rules are tested,
# not the hands)
GAP = HandGap(HandReach(LEFT, 0.1057, -0.0825, 0.0845), HandReach(RIGHT, 0.1057, -0.0845, 0.0825))


@pytest.fixture(scope="module")
def places() -> dict[str, Places]:
    return {LEFT: Places(load_hand("default-left")), RIGHT: Places(load_hand("default"))}


def note(pitch: int, on: float, off: float, channel: int = 0, track: int = 0) -> Note:
    return Note(pitch, on, off, 80, channel, track)


def ordered(notes):
    return sorted(notes, key=lambda n: (n.onset_s, n.pitch))


def test_hint_two_parts_lower_is_left() -> None:
    notes = ordered([note(72 + i % 3, 0.5 * i, 0.5 * i + 0.4, 0, 0) for i in range(6)]
                    + [note(48 + i % 3, 0.5 * i, 0.5 * i + 0.4, 1, 1) for i in range(6)])
    hint, source, split = hint_hands(notes)
    assert source is HintSource.PARTS and split is None
    assert all(h == (LEFT if n.track == 1 else RIGHT) for h, n in zip(hint, notes))


def test_hint_parts_cut_at_widest_gap() -> None:
    # (three parts: a melody, its doubling a third below, a bass: the bass alone is left)
    parts = [(76, 0), (72, 1), (43, 2)]
    notes = ordered([note(p + i % 2, 0.5 * i, 0.5 * i + 0.4, c, 0) for p, c in parts
                     for i in range(4)])
    hint, _, _ = hint_hands(notes)
    assert [h for h, n in zip(hint, notes) if n.channel == 2] == [LEFT] * 4
    assert {h for h, n in zip(hint, notes) if n.channel != 2} == {RIGHT}


def test_hint_one_part_of_two_hands_is_split() -> None:
    notes = ordered([note(p, 0.5 * i, 0.5 * i + 0.45) for i in range(8) for p in (40 + i % 2,
                                                                                    76 + i % 3)])
    hint, source, split = hint_hands(notes)
    assert source is HintSource.SPLIT and 41 < split <= 76
    assert all(h == (LEFT if n.pitch < split else RIGHT) for h, n in zip(hint, notes))


def test_hint_melody_is_the_right_hands() -> None:
    notes = [note(60 + i, 0.3 * i, 0.3 * i + 0.25) for i in range(8)]
    hint, source, _ = hint_hands(notes)
    assert source is HintSource.MELODY and set(hint) == {RIGHT}


def test_no_reason_no_move(places) -> None:
    notes = ordered([note(72, 0.5 * i, 0.5 * i + 0.4, 0, 0) for i in range(4)]
                    + [note(48, 0.5 * i, 0.5 * i + 0.4, 1, 1) for i in range(4)])
    a = assign_hands(notes, GAP, places)
    assert a.hand == a.hint and a.moved == ()
    assert set(a.notes_of(LEFT)) | set(a.notes_of(RIGHT)) == set(range(len(notes)))


def test_crossing_goes_to_the_other_hand(places) -> None:
    # (the right part dips below a note the left hand holds: it cannot be played by the
    # right hand, which would cross; the left hand, holding the note a third above, can)
    notes = ordered([note(64, 0.0, 2.0, 1, 1), note(72, 0.0, 0.5, 0, 0),
                     note(60, 0.5, 1.0, 0, 0), note(74, 1.5, 2.0, 0, 0)])
    a = assign_hands(notes, GAP, places)
    i = next(k for k, n in enumerate(notes) if n.pitch == 60)
    assert a.hint[i] == RIGHT and a.hand[i] == LEFT
    (m,) = a.moved
    assert m.note == i and m.reason is MoveReason.CROSSING
    assert m.cost_frames[1] == pytest.approx(50.0)  # (the whole note: 0.5 s at 100 Hz)


def test_span_goes_to_the_other_hand(places) -> None:
    # (a right-hand chord wider than the hand's span: its lowest note, an octave and a half
    # below, goes to the idle left hand)
    notes = ordered([note(84, 0.0, 1.0, 0, 0), note(79, 0.0, 1.0, 0, 0),
                     note(60, 0.0, 1.0, 0, 0), note(36, 2.0, 2.5, 1, 1)])
    a = assign_hands(notes, GAP, places)
    i = next(k for k, n in enumerate(notes) if n.pitch == 60)
    assert a.hand[i] == LEFT and a.moved[0].reason is MoveReason.SPAN


def test_time_goes_to_the_nearer_hand_only_when_it_saves_frames(places) -> None:
    # (the right hand plays high, then a note three octaves down 0.15 s later: its rail
    # cannot get there; the left hand, an octave below it, can; 2 s later it can)
    def song(gap_s: float):
        return ordered([note(96, 0.0, 0.1, 0, 0), note(60, 0.1 + gap_s, 0.6 + gap_s, 0, 0),
                        note(48, 0.0, 0.1, 1, 1)])

    soon = assign_hands(song(0.05), GAP, places)
    late = assign_hands(song(2.0), GAP, places)
    i = 2  # (the C4: onsets 0, 0, then it)
    assert soon.hand[i] == LEFT and soon.moved[0].reason is MoveReason.TIME
    assert late.hand[i] == RIGHT and late.moved == ()


def test_same_notes_same_assignment(places) -> None:
    notes = ordered([note(60 + (7 * i) % 25, 0.2 * i, 0.2 * i + 0.3, i % 2, i % 2)
                     for i in range(40)])
    assert assign_hands(notes, GAP, places) == assign_hands(notes, GAP, places)


def test_one_hand_gives_every_note_to_it(places) -> None:
    notes = ordered([note(72 + i % 3, 0.5 * i, 0.5 * i + 0.4, 0, 0) for i in range(6)]
                    + [note(48 + i % 3, 0.5 * i, 0.5 * i + 0.4, 1, 1) for i in range(6)])
    a = assign_hands(notes, GAP, places)
    one = a.one_hand(RIGHT)
    assert one.hand == tuple(RIGHT for _ in notes) and one.hint == a.hint
    assert [m.note for m in one.moved] == [i for i, h in enumerate(a.hint) if h == LEFT]
    assert {m.reason for m in one.moved} == {MoveReason.ONE_HAND}
    assert one.notes_of(LEFT) == ()


def test_hand_over_gives_left_out_notes_to_the_other_hand(places) -> None:
    notes = ordered([note(72 + i % 3, 0.5 * i, 0.5 * i + 0.4, 0, 0) for i in range(6)]
                    + [note(48 + i % 3, 0.5 * i, 0.5 * i + 0.4, 1, 1) for i in range(6)])
    one = assign_hands(notes, GAP, places).one_hand(RIGHT)
    right = [i for i, h in enumerate(one.hint) if h == RIGHT]
    left = [i for i, h in enumerate(one.hint) if h == LEFT]
    # (a note of the right part the right hand left out: moved for that reason; a note
    # of the left part, moved to the right hand for one hand, given back: moved no more)
    got = one.hand_over({right[0]: "too_late: x", left[0]: "chord: y"}, LEFT)
    assert got.hand[right[0]] == LEFT and got.hand[left[0]] == LEFT
    why = {m.note: m for m in got.moved}
    assert why[right[0]].reason is MoveReason.LEFT_OUT and "too_late: x" in why[right[0]].detail
    assert left[0] not in why
    assert set(why) == set(left[1:]) | {right[0]}
    assert got.notes_of(LEFT) == tuple(sorted([right[0], left[0]]))
