"""Fingering (Viterbi over finger assignments), on a hand reach table made up for the
test (so that the numbers are known), and on the default hand's own."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from planner.fingering import FINGER_ORDER, HandReach, assign_fingers, fit_rail
from planner.music import keyboard as kb
from planner.music.midi import Note

# natural places one white key apart, 15 mm of stretch each way
REACH = HandReach(
    offset_m={f: (i - 2) * kb.WHITE_PITCH_M for i, f in enumerate(FINGER_ORDER)},
    reach_m={"thumb": 0.015, "index": 0.015, "middle": 0.010, "ring": 0.015, "pinky": 0.020},
    rail_speed_m_s=3.0, rail_range_m=(-0.6, 0.7), rail_accel_m_s2=40.0)


def test_fit_rail_is_the_least_squares_stretch():
    fingers = ("thumb", "middle", "pinky")
    xs = np.array([kb.key(p).center_x_m for p in (60, 65, 71)])
    rail, dev = fit_rail(fingers, xs, REACH)
    lim = np.array([REACH.reach_m[f] for f in fingers])
    # the stretches are what is left of the keys beyond the natural places ...
    offs = np.array([REACH.offset_m[f] for f in fingers])
    assert np.allclose(dev, xs - offs - rail)
    # ... and the rail makes their reach-weighted squares least: zero derivative, and any
    # other rail is worse

    def cost(r):
        return float(np.sum(((xs - offs - r) / lim) ** 2))
    assert abs(np.sum((xs - offs - rail) / lim**2)) < 1e-9
    assert cost(rail) < min(cost(rail - 1e-3), cost(rail + 1e-3))


def test_fit_rail_stays_on_the_rail():
    short = dataclasses.replace(REACH, rail_range_m=(-0.4, 0.5))
    xs = np.array([kb.key(21).center_x_m])  # A0 with the pinky: beyond the rail's left end
    rail, dev = fit_rail(("pinky",), xs, short)
    assert rail == -0.4
    assert dev[0] == pytest.approx(xs[0] - REACH.offset_m["pinky"] + 0.4)
    assert dev[0] < -REACH.reach_m["pinky"]  # (so the fingering finds A0 out of reach)
    _, bad = assign_fingers([Note(21, 0.0, 0.5, 80)], short)
    assert [b.reason for b in bad] == ["out of the rail's reach"]


def test_a_scale_uses_the_fingers_in_order():
    notes = [Note(p, 0.5 * i, 0.5 * i + 0.45, 80) for i, p in enumerate((60, 62, 64, 65, 67))]
    out, bad = assign_fingers(notes, REACH)
    assert bad == []
    assert [a.finger for a in out] == list(FINGER_ORDER)
    assert len({a.rail_m for a in out}) == 1  # one hand position serves all five


def test_pair_check_rules_out_a_chord_shape():
    """The lateral model lets thumb and middle hold C4-E4; a pair check saying they
    cannot makes the fingering take another pair of fingers, and it is asked about the
    two keys (each pair of fingers of each candidate once at least)."""
    notes = [Note(60, 0.0, 0.5, 80), Note(64, 0.0, 0.5, 80)]
    plain, _ = assign_fingers(notes, REACH)
    assert [a.finger for a in plain] == ["thumb", "middle"]
    asked = []

    def no_thumb_middle(f1, p1, f2, p2):
        asked.append((f1, p1, f2, p2))
        return {f1, f2} != {"thumb", "middle"}

    checked, bad = assign_fingers(notes, REACH, no_thumb_middle)
    assert bad == []
    assert [a.finger for a in checked] != ["thumb", "middle"]
    assert len({a.finger for a in checked}) == 2
    assert ("thumb", 60, "middle", 64) in asked
    assert all(p1 == 60 and p2 == 64 for _, p1, _, p2 in asked)


def test_a_chord_no_pair_of_fingers_holds_is_played_in_part():
    notes = [Note(60, 0.0, 0.5, 80), Note(64, 0.0, 0.5, 80)]
    out, bad = assign_fingers(notes, REACH, lambda f1, p1, f2, p2: False)
    assert len(out) == 1 and len(bad) == 1
    assert out[0].note_index == 1  # the top note is kept (often the melody)
    assert "chord wider than the hand" in bad[0].reason and "left out" in bad[0].reason


def test_a_key_held_over_later_notes_keeps_its_finger():
    """A bass note held under three melody notes: its finger is not given any of them
    (the fingering follows the keys still down over several groups, not only the last)."""
    notes = [Note(48, 0.0, 2.0, 80), Note(60, 0.0, 0.45, 80)] + [
        Note(p, 0.5 * k, 0.5 * k + 0.45, 80) for k, p in ((1, 59), (2, 57), (3, 55))]
    out, bad = assign_fingers(notes, REACH)
    fingers = {a.note_index: a.finger for a in out}
    assert bad == [] or all(b.note_index != 0 for b in bad)
    bass = fingers[0]
    for i in range(1, len(notes)):
        if i in fingers and notes[i].onset_s < notes[0].offset_s:
            assert fingers[i] != bass, (i, fingers)
    assert all(a.release_s is None for a in out)


def test_a_held_key_is_let_go_early_when_later_notes_need_the_hand_elsewhere():
    """C3 held for 3 s; from 0.5 s on, thirds two octaves up (out of reach while C3 is
    down), 4.5 s of notes while it would sound. Leaving them out costs more music than
    cutting C3 short (2.56 s): C3 is let go CUT_LEAD_S before them (release_s), and its
    press interval ends then."""
    from planner.fingering import CUT_LEAD_S
    from planner.targets import press_intervals

    thirds = ((72, 76), (74, 77), (76, 79), (77, 81), (79, 83))
    notes = [Note(48, 0.0, 3.0, 80)] + [Note(p, 0.5 + 0.5 * k, 0.95 + 0.5 * k, 80)
                                        for k, pair in enumerate(thirds) for p in pair]
    out, bad = assign_fingers(notes, REACH)
    assert bad == []
    bass = next(a for a in out if a.note_index == 0)
    assert bass.release_s == pytest.approx(0.5 - CUT_LEAD_S)
    ends = {iv.press.note_index: iv.end_s for iv in press_intervals(notes, out)}
    assert ends[0] == pytest.approx(0.5 - CUT_LEAD_S)
    assert all(ends[i] == pytest.approx(notes[i].offset_s) for i in range(1, len(notes)))


def test_a_short_note_that_would_cut_a_long_held_chord_is_left_out():
    """A C3-E3-G3 chord held 3 s and one short note two octaves up at 1 s: cutting the
    chord short would lose 6 s of music for 0.2 s, so the short note is left out, with
    the reason, and the chord keeps its length."""
    notes = [Note(p, 0.0, 3.0, 80) for p in (48, 52, 55)] + [Note(79, 1.0, 1.2, 80)]
    out, bad = assign_fingers(notes, REACH)
    assert [b.note_index for b in bad] == [3]
    assert bad[0].reason.startswith("left out: playing it would cost more music")
    assert sorted(a.note_index for a in out) == [0, 1, 2]
    assert all(a.release_s is None for a in out)


def test_reposition_time_is_the_rails_own_time_and_an_overhead():
    """The rail's minimum-jerk time and REPOSITION_OVERHEAD_S for a short move, but no
    more than REPOSITION_CAP_S in all unless the rail alone takes longer, then its time
    and REPOSITION_OVERHEAD_MIN_S (the fingers overlap most of a long move); never less
    for a longer move."""
    from planner.fingering import (
        REPOSITION_CAP_S,
        REPOSITION_OVERHEAD_MIN_S,
        REPOSITION_OVERHEAD_S,
        reposition_s,
    )

    assert reposition_s(0.0, REACH) == 0.0
    d = np.linspace(0.001, 1.0, 400)
    t = np.array([reposition_s(x, REACH) for x in d])
    t_rail = np.maximum(1.875 * d / REACH.rail_speed_m_s, np.sqrt(5.7735 * d / REACH.rail_accel_m_s2))
    over = t - t_rail
    assert np.all(np.diff(t) >= 0.0)
    assert np.all(over >= REPOSITION_OVERHEAD_MIN_S - 1e-12) and np.all(over <= REPOSITION_OVERHEAD_S + 1e-12)
    short = t_rail + REPOSITION_OVERHEAD_S <= REPOSITION_CAP_S
    assert short[0] and np.allclose(over[short], REPOSITION_OVERHEAD_S)
    assert np.allclose(over[-1], REPOSITION_OVERHEAD_MIN_S)
    assert np.all(t[~short] <= np.maximum(REPOSITION_CAP_S, t_rail[~short] + REPOSITION_OVERHEAD_MIN_S) + 1e-12)


def test_two_keys_no_hand_shape_reaches_are_costed_as_a_move():
    """C4 with the index, then G4 with the ring, 0.5 s later: the lateral model finds
    one rail position for both (no move). If the whole-hand IK says no shape holds the
    two (``pair_ok``), the step costs a change of hand position like any other."""
    from planner.fingering import MOVE_COST, _transition

    notes = [Note(60, 0.0, 0.45, 80), Note(67, 0.5, 0.95, 80)]
    span = (-1.0, 1.0)  # (the rail positions each reaches: they overlap)

    def step(pair_ok):
        return _transition(notes, [0], ("index",), 0.0, span, [1], ("ring",), 0.0, span, 0.5, 0.05, (),
                           REACH, pair_ok)

    free, _, moved = step(None)
    assert not moved
    assert step(lambda *a: True)[0] == free
    apart, cut, moved = step(lambda *a: False)
    assert cut == () and moved and apart >= free + MOVE_COST


def test_after_a_note_left_out_the_hand_is_free_from_the_last_key_up(monkeypatch):
    """C4, then C7 for 50 ms (two long changes of hand position: left out), then D4: the
    step to D4 from the state that left C7 out is costed with the time since C4's key
    came up (0.2 s), not as if no key had ever been down (free time infinite: a change
    of hand position there would have looked free)."""
    import planner.fingering as fg

    notes = [Note(60, 0.0, 0.4, 80), Note(96, 0.45, 0.5, 80), Note(62, 0.6, 1.0, 80)]
    seen = []
    orig = fg._transition

    def spy(notes_, prev_g, fa, ra, span_a, g, fb, rb, span_b, dt, free_s, held, reach, pair_ok=None,
            spans=None):
        if g == [2]:
            seen.append((tuple(prev_g), free_s))
        return orig(notes_, prev_g, fa, ra, span_a, g, fb, rb, span_b, dt, free_s, held, reach, pair_ok,
                    spans)

    monkeypatch.setattr(fg, "_transition", spy)
    _, bad = assign_fingers(notes, REACH)
    assert [b.note_index for b in bad] == [1]
    from_c4 = [f for prev, f in seen if prev == (0,)]
    assert from_c4 and all(f == pytest.approx(0.2) for f in from_c4)


def test_a_finger_sent_beyond_its_range_moves_the_hand():
    """The middle finger on C4, then on F4 0.5 s later: within its reach (the rail stays),
    but beyond its range at one hand position (``HandReach.range_m``), so the step is a
    change of hand position, costed as one; within range it is not."""
    import dataclasses as dc

    from planner.fingering import MOVE_COST, _key_spans, _transition

    notes = [Note(60, 0.0, 0.45, 80), Note(65, 0.5, 0.95, 80)]
    span = (-1.0, 1.0)
    spans = _key_spans(notes, [0], ("middle",), {})
    assert spans == {"middle": (kb.key(60).center_x_m, kb.key(60).center_x_m)}

    def step(range_m):
        reach = dc.replace(REACH, range_m={f: range_m for f in FINGER_ORDER})
        return _transition(notes, [0], ("middle",), 0.0, span, [1], ("middle",), 0.0, span, 0.5, 0.05, (),
                           reach, None, spans)

    wide, _, moved_wide = step(0.08)  # F4 is 70.5 mm from C4
    narrow, _, moved_narrow = step(0.05)
    assert not moved_wide and moved_narrow
    assert narrow >= wide + MOVE_COST

