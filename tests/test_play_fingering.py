"""planner.play.fingering: the dynamic programme on hand-made songs."""

from __future__ import annotations

from pathlib import Path

import pytest

from planner.hand.model import load_hand
from planner.music.midi import Note
from planner.play.fingering import SkipReason, events, plan_fingering
from planner.play.places import Places

FINGERS = ("thumb", "index", "middle", "ring", "pinky")


@pytest.fixture(scope="module")
def hand_parts():
    return Places(load_hand("default"))


def plan(hand_parts, notes):
    return plan_fingering(notes, hand_parts, 100.0)


def test_events_group_notes_by_onset():
    notes = [Note(64, 0.5, 1.0, 80), Note(60, 0.0, 1.0, 80), Note(67, 0.50005, 1.0, 80)]
    assert events(notes) == [(0.0, [1]), (0.5, [0, 2])]


def test_a_slow_melody_is_played_whole_in_finger_order(hand_parts):
    """C4 D4 E4 F4 at 0.5 s: four fingers from one hand position, in the keys' order, no
    frame lost. (Adding G4 needs a move of the hand: this hand's fingers are 33 mm apart
    at rest, keys 23.5 mm; five in a row do not fit, and it costs a few frames.)"""
    notes = [Note(p, 0.5 * k, 0.5 * k + 0.45, 80) for k, p in enumerate((60, 62, 64, 65))]
    fg = plan(hand_parts, notes)
    assert fg.skipped == () and len(fg.assignments) == 4
    assert fg.expected_loss_frames < 1.0
    assert len({a.rail_m for a in fg.assignments}) == 1
    order = [FINGERS.index(a.finger) for a in sorted(fg.assignments, key=lambda a: a.note)]
    assert order == sorted(order) and len(set(order)) == 4
    notes.append(Note(67, 2.0, 2.45, 80))
    fg = plan(hand_parts, notes)
    assert fg.skipped == () and len(fg.assignments) == 5
    assert fg.expected_loss_frames < 10.0


def test_no_finger_crosses_one_that_just_played(hand_parts):
    """Pinky on F4, then G4 a frame later: not the ring (it would pass the pinky, still
    over F4); the thumb on a white key is in front of the long fingers and may pass."""
    notes = [Note(65, 0.0, 0.4, 80), Note(67, 0.41, 0.8, 80)]
    fg = plan(hand_parts, notes)
    a, b = fg.assignments
    if a.rail_m == b.rail_m and b.finger != "thumb" and a.finger != "thumb":
        assert FINGERS.index(b.finger) > FINGERS.index(a.finger), (a, b)


def test_legato_steps_take_another_finger(hand_parts):
    """C4 then E4 legato: the same finger would have to lift, cross and come down inside
    no time at all; the programme gives E4 another finger and loses nothing."""
    notes = [Note(60, 0.0, 0.5, 80), Note(64, 0.5, 1.0, 80)]
    fg = plan(hand_parts, notes)
    a, b = fg.assignments
    assert a.finger != b.finger and fg.expected_loss_frames < 1.0


def test_more_notes_than_fingers_leaves_one_out_named(hand_parts):
    notes = [Note(p, 0.0, 1.0, 80) for p in (60, 62, 64, 65, 67, 69)]
    fg = plan(hand_parts, notes)
    assert len(fg.assignments) <= 5 and fg.skipped
    assert all(s.reason is SkipReason.CHORD for s in fg.skipped)
    assert len(fg.assignments) + len(fg.skipped) == 6
    assert len({a.finger for a in fg.assignments}) == len(fg.assignments)


def test_a_chord_wider_than_the_hand_keeps_what_fits(hand_parts):
    notes = [Note(48, 0.0, 1.0, 80), Note(84, 0.0, 1.0, 80)]
    fg = plan(hand_parts, notes)
    assert len(fg.assignments) == 1 and fg.skipped[0].reason is SkipReason.CHORD


def test_a_held_note_keeps_its_finger(hand_parts):
    """A bass held for 2 s under four melody notes: one finger holds it to its end (the
    hand may move under it only where that finger can follow its key), no melody note
    takes that finger, nothing is lost. (C4 under E4-G4: within the four long fingers'
    reach; the default hand's thumb presses nothing, ``test_play_atlas``.)"""
    notes = [Note(60, 0.0, 2.0, 80)] + [Note(p, 0.5 * k, 0.5 * k + 0.45, 80)
                                        for k, p in enumerate((64, 65, 67, 65))]
    fg = plan(hand_parts, notes)
    by = {a.note: a for a in fg.assignments}
    bass = by[0]
    assert len(by) == 5 and bass.release_s is None
    assert all(by[i].finger != bass.finger for i in range(1, 5))
    assert fg.expected_loss_frames < 1.0


def test_fast_repeated_notes_are_all_fingered(hand_parts):
    notes = [Note(62, 0.12 * k, 0.12 * k + 0.1, 80) for k in range(12)]
    fg = plan(hand_parts, notes)
    assert fg.skipped == () and len(fg.assignments) == 12


def test_the_programme_runs_over_a_receding_window(hand_parts):
    """A 150-note song: the chunks cover every note once (struck or left out), the first
    chunk decides only the window less its look-ahead, and a note cut later is one struck
    before."""
    from planner.play.fingering import FIRST_LOOKAHEAD, FIRST_WINDOW, FingeringProblem

    notes = [Note(60 + (k * 5) % 12, 0.3 * k, 0.3 * k + 0.28, 80) for k in range(150)]
    chunks = list(FingeringProblem(notes, hand_parts, 100.0).chunks())
    assert len(chunks) >= 3
    struck = [a.note for c in chunks for a in c.assignments]
    left = [s.note for c in chunks for s in c.skipped]
    assert sorted(struck + left) == list(range(150))
    # (the first chunk decides the window less its look-ahead, or fewer events once
    # their path is certain: ``_certain``)
    assert 1 <= len(chunks[0].assignments) + len(chunks[0].skipped) <= \
        FIRST_WINDOW - FIRST_LOOKAHEAD
    seen: set[int] = set()
    for c in chunks:
        seen |= {a.note for a in c.assignments}
        assert all(n in seen for n, _ in c.cuts)


def test_a_short_note_is_given_up_for_a_long_one_held_through_it(hand_parts):
    """C5 tied over 8 s (held by the index, the thumb on B4 beside it) under a melody that
    climbs to C6, out of the pinky's reach while C5 is held: striking C6 would cut C5
    (500 frames lost), leaving C6 out loses its 30. The programme leaves out C6, named
    HELD, and holds C5 to its end (before it always struck every note it could)."""
    notes = [Note(72, 0.0, 8.0, 80), Note(71, 0.0, 0.3, 80)] + [
        Note(p, 1.0 + i, 1.3 + i, 80) for i, p in enumerate((76, 79, 84, 79, 76))]
    fg = plan(hand_parts, notes)
    c5 = next(a for a in fg.assignments if a.note == 0)
    assert c5.release_s is None  # held to its end
    assert [(s.note, s.reason) for s in fg.skipped] == [(4, SkipReason.HELD)]
    assert "holds C5 through it" in fg.skipped[0].detail
    assert fg.expected_loss_frames <= 30.0 + 0.5  # (C6's 30 frames, tie-breaks)


def test_a_state_is_immutable_and_equal_by_value():
    from planner.play.costs import State

    a = State(3, ((0, "index"),), ((1, "thumb", 2),))
    b = State(3, ((0, "index"),), ((1, "thumb", 2),))
    assert a == b and hash(a) == hash(b) and len({a, b}) == 1
    assert a != State(3, ((0, "index"),)) and a != State(4, ((0, "index"),), a.recent)
    assert a.notes == (0,) and a.last_notes == ((1, "thumb", 2), (0, "index", 3))
    with pytest.raises(AttributeError):
        a.place = 4


def test_a_state_carries_the_notes_it_strikes_late(hand_parts):
    """``State.late``: a note struck late is part of the state (two states that differ in
    it are two), and the state's ``Prev`` times that note's key from when it went down:
    a rider's press is done that much later, its key's window that much shorter."""
    from planner.play.costs import State
    from planner.play.fingering import FingeringProblem

    notes = [Note(60, 0.0, 0.4, 80), Note(62, 0.4, 0.8, 80)]
    fp = FingeringProblem(notes, hand_parts, 100.0)
    place = min(fp.rails("index", 0))
    on_time = State(place, ((0, "index"),))
    late = State(place, ((0, "index"),), (), ((0, 0.03),))
    assert on_time != late and len({on_time, late}) == 2
    (_, _, _, w0, _, d0), = fp.prev(on_time, 0.1).follows
    (_, _, _, w1, _, d1), = fp.prev(late, 0.1).follows
    assert d0 == pytest.approx(fp.t_down(0)) and d1 == pytest.approx(fp.t_down(0) + 0.03)
    assert w1 == pytest.approx(w0 - 0.03)


def test_the_lateness_a_state_carries_is_what_its_step_priced(hand_parts):
    """A quick stepwise run (7.5 notes per second, up and down an octave and a half: the
    hand moves at nearly every note): every state the programme keeps carries as late
    only notes it strikes at its event, and no more late than its step's loss."""
    from planner.play.costs import ONSET_TOL_S
    from planner.play.fingering import FingeringProblem

    line = [60, 62, 64, 65, 67, 69, 71, 72, 74, 76, 77, 79, 77, 76, 74, 72, 71, 69, 67]
    notes = [Note(p, 0.134 * k, 0.134 * (k + 1), 80) for k, p in enumerate(line)]
    fp = FingeringProblem(notes, hand_parts, 100.0)
    prev, seen_late = {}, 0
    for t, new in events(notes):
        layer = fp._layer(prev, t, new)
        for s, (cost, before) in layer.items():
            assert {n for n, _ in s.late} <= set(new)
            assert all(late_s > 0 for _, late_s in s.late)
            if before is not None:
                step = cost - prev[before][0]
                assert sum(late_s for _, late_s in s.late) / fp.dt <= step + ONSET_TOL_S
            seen_late += bool(s.late)
        prev = layer
    assert seen_late  # (the run is quick enough that some states strike late)


def test_a_layer_holds_one_state_per_hand_shape_cheapest_first(hand_parts):
    """The programme's layers (what each event keeps): at most BEAM states, one of each
    hand shape (rail and fingers on the notes sounding), at most PER_RAIL at one rail,
    in cost order, each reached from a state of the layer before."""
    from planner.play.fingering import FingeringProblem, events
    from planner.play.layers import BEAM, PER_RAIL

    notes = [Note(60 + (k * 7) % 15, 0.2 * k, 0.2 * k + 0.3, 80) for k in range(30)]
    fp = FingeringProblem(notes, hand_parts, 100.0)
    prev = {}
    for t, new in events(notes)[:12]:
        layer = fp._layer(prev, t, new)
        costs = [v[0] for v in layer.values()]
        shapes = [(s.place, s.fingers) for s in layer]
        assert 0 < len(layer) <= BEAM and costs == sorted(costs)
        assert len(set(shapes)) == len(shapes)
        assert max(sum(s.place == r for s in layer) for r, _ in shapes) <= PER_RAIL
        assert all((p is None) == (not prev) and (p is None or p in prev)
                   for _, p in layer.values())
        prev = layer


def test_the_first_window_stops_once_its_decision_is_made(hand_parts):
    """The first window stops weighing its look-ahead once every state of a layer
    descends from one state of an event (``_certain``): its first chunk decides the
    events up to that one (at most the window less its look-ahead) and is the path the
    whole window gives for them (the window's own layers and path, worked out here); on
    these songs some first windows stop early, and some first chunks are shorter."""
    from planner.music.midi import load_song
    from planner.play.fingering import FIRST_LOOKAHEAD, FIRST_WINDOW, FingeringProblem

    songs = Path(__file__).resolve().parents[1] / "songs"
    early = shorter = 0
    for name in ("fast.mid", "fur_elise.mid", "ode_to_joy.mid"):
        notes = list(load_song(songs / name).notes)

        class Counted(FingeringProblem):
            layers = 0

            def _layer(self, prev, t, new):
                Counted.layers += 1
                return super()._layer(prev, t, new)

        p = Counted(notes, hand_parts, 100.0)
        first = next(p.chunks())
        early += Counted.layers < FIRST_WINDOW
        whole = FingeringProblem(notes, hand_parts, 100.0)
        evs = [(t, new) for t, new, _ in whole._events() if new][:FIRST_WINDOW]
        k = sum(t < first.until_s for t, _ in evs)  # (the events the first chunk decides)
        assert 1 <= k <= FIRST_WINDOW - FIRST_LOOKAHEAD
        shorter += k < FIRST_WINDOW - FIRST_LOOKAHEAD
        layers, prev = [], {}
        for t, new in evs:
            prev = whole._layer(prev, t, new)
            layers.append((t, prev, new))
        ch = whole._chunk(layers[:k], whole._path(layers)[:k], None)
        assert (first.assignments, first.cuts, first.loss_frames) == \
            (ch.assignments, ch.cuts, ch.loss_frames)
        assert first.skipped == ch.skipped
    assert early >= 1 and shorter >= 1


def test_a_certain_path_is_found_in_made_up_layers():
    """``_certain`` on layers made up by hand (each {state: (cost, state before)}): the
    events whose path every state of the last layer goes back through, at most ``most``,
    never the whole window; 0 while two paths stay open from the first event."""
    from planner.play.fingering import _certain

    a0, b0 = "a0", "b0"
    l0 = (0.0, {a0: (1.0, None), b0: (2.0, None)}, [0])
    l1 = (1.0, {"a1": (2.0, a0), "b1": (3.0, b0)}, [1])  # (two paths open)
    l2 = (2.0, {"a2": (3.0, "a1"), "b2": (4.0, "a1")}, [2])  # (both back through a1)
    l3 = (3.0, {"a3": (5.0, "a2"), "b3": (4.5, "b2")}, [3])
    assert _certain([l0, l1], 8) == 0
    assert _certain([l0, l1, l2], 8) == 2  # (events 0 and 1: a0, a1)
    assert _certain([l0, l1, l2, l3], 8) == 2
    assert _certain([l0, l1, l2, l3], 1) == 1
    assert _certain([l0, l1, l2], 1) == 1
    assert _certain([l0], 8) == 0


def test_a_note_only_a_body_refused_pose_could_press_is_left_out_for_its_body(hand_parts,
                                                                            monkeypatch):
    """The default hand's thumb would press D4 but for its body (the atlas's body rule
    refuses every pose of it); with the long fingers taken away, D4 is left out, named
    ``body``, never pressed wrongly."""
    from planner.play.costs import Costs

    place = next(hand_parts.place(p, i) for p in range(hand_parts.postures)
                 for i in range(-60, 60) if hand_parts.body_refused("thumb", 62, hand_parts.place(p, i)))
    assert hand_parts.entry("thumb", 62, place) is None
    monkeypatch.setattr(hand_parts, "entry", lambda f, pitch, pl: None)
    skip = Costs([Note(62, 0.0, 0.5, 80)], hand_parts, 100.0).reason(0)
    assert skip.reason is SkipReason.BODY and "body clear" in skip.detail
