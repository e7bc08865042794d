"""Hardening (the harness and its contract: tests/hardening.py), (5) the envelope:
random small songs, planned and replayed through the independent check, stay inside
the joint and motor limits and never hit a key bed."""

from __future__ import annotations

import tempfile
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from planner.check import check_trajectory
from planner.hand.model import load_hand
from planner.music.midi import Note, load_song, write_notes_midi
from tests.hardening import SETTINGS

# ====================================================================== 5. the envelope


@pytest.fixture(scope="module")
def song_planner():
    from planner.play import Planner

    return Planner(load_hand("default"))


NOTES = st.lists(st.tuples(
    st.integers(48, 84),  # pitch
    st.floats(0.0, 4.0),  # onset, s
    st.floats(0.05, 1.0),  # duration, s
    st.integers(1, 127),  # velocity
), min_size=1, max_size=12)


def plan_and_check(notes, planner=None):
    """Write the notes as a MIDI file (as a user would), plan it with plan_song, replay it
    with check_trajectory; returns the report."""
    from planner.play import plan_song

    with tempfile.TemporaryDirectory() as d:
        mid, out = Path(d, "s.mid"), Path(d, "s.csv")
        write_notes_midi([Note(p, a, a + dur, v) for p, a, dur, v in notes], mid)
        song = load_song(mid)
        hand = load_hand("default")
        plan_song(song, hand, str(out), song_name="s.mid", planner=planner)
        return check_trajectory(str(out), str(mid))


def assert_inside_envelope(rep) -> None:
    bad = [f"{lc.category}: {lc.count} (worst {lc.worst:.6g} vs {lc.limit:.6g} {lc.unit}, "
           f"{lc.name} at {lc.time_s:.3f} s)" for lc in rep.limits if lc.count]
    hits = rep.play.key_bed_hits
    assert not bad and not hits, "\n".join(bad + [str(h) for h in hits[:3]])


@SETTINGS
@given(notes=NOTES)
def test_random_songs_stay_inside_the_envelope(song_planner, notes):
    assert_inside_envelope(plan_and_check(notes, song_planner))


# minimal example found by the property above (HARDENING_EXAMPLES=300, shrunk by hypothesis):
# (pitch, onset s, duration s, velocity); the velocity does not matter
TRAVEL_DIP = [(62, 0.0, 1.0, 1), (77, 0.015625, 1.0, 1), (48, 2.0, 1.0, 1)]


def test_hand_travel_stays_above_the_keys():
    """Found by the envelope property: a straight travel once swept the pinky 14 mm
    into G#4 (key-bed hit); travel now lifts every fingertip when the straight move dips."""
    assert_inside_envelope(plan_and_check(TRAVEL_DIP, None))  # a fresh Planner
