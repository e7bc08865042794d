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
