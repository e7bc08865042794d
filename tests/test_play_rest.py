"""Rows a controller can run (issue "Play on the real keyboard", item 4): every plan
starts at the hand's rest pose, still, and ends there; a song whose first note comes too
soon to reach from rest starts later in the file (``song_start_s``, format version 2),
which ``check`` honours; never a key down in the first row."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from planner.check import check_trajectory
from planner.hand.model import load_hand
from planner.music import keyboard as kb
from planner.music.midi import Note, Song, load_song, shift_notes
from planner.play import Planner, plan_song
from planner.play.atlas import CLEARANCE_M, HIGH_Z_M
from planner.play.rest import Legs, rest_pose, whole_hand_move
from planner.trajfile import parse_trajectory, read_trajectory

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module", params=["default", "mk5", "agh"])
def planner(request):
    return Planner(load_hand(request.param))


def _song(notes) -> Song:
    return Song(tuple(notes), max(n.offset_s for n in notes), source="made.mid")


def test_rest_pose_is_clear_of_every_key_and_within_limits(planner):
    q = rest_pose(planner.atlas)
    h = planner.hand
    assert h.within_limits(q)
    tips = h.tip_positions(q)
    # every tip clear of every key top (the rail runs in this posture); the fitted
    # fingers at crossing height (the Mk5's one-joint thumb cannot rise past 13.7 mm on
    # its arc from the fitted wrist)
    assert tips[:, 2].min() >= kb.BLACK_TOP_Z_M + CLEARANCE_M
    if h.name == "default":
        assert tips[:, 2].min() >= HIGH_Z_M - 1e-4


@pytest.mark.parametrize("name", ["twinkle", "leaps", "chords"])
def test_rows_start_and_end_at_rest_still(planner, tmp_path, name):
    path = tmp_path / f"{name}.csv"
    plan_song(load_song(ROOT / "songs" / f"{name}.mid"), planner.hand, str(path),
              planner=planner)
    tr = read_trajectory(str(path))
    rest = rest_pose(planner.atlas)
    assert np.allclose(tr.q[0], rest, atol=2e-6)
    assert np.allclose(tr.q[-1], rest, atol=2e-6)
    # still at the end: the last rows equal (SETTLE_S of rows after the way back)
    assert np.ptp(tr.q[-5:], axis=0).max() < 2e-6
    # the first step is the start of an acceleration from rest: far below the speed caps
    v0 = np.abs(tr.q[1] - tr.q[0]) / 0.01
    assert np.all(v0 <= 0.5 * planner.hand.velocity + 1e-9)


def test_a_first_note_after_two_ms_starts_the_song_later(tmp_path):
    """`onset_2ticks.mid` of the round-3 reproducers (a C4 2 ms after t = 0): row 0 had
    the key down before its note. Now the song starts ``song_start_s`` into the file
    (whole rows), the first row is at rest and the note is played."""
    pl = Planner(load_hand("default"))
    song = _song([Note(60, 0.002, 0.5, 80), Note(62, 0.6, 1.0, 80)])
    path = tmp_path / "o.csv"
    res = plan_song(song, pl.hand, str(path), planner=pl, song_name="made.mid")
    tr = read_trajectory(str(path))
    start = tr.metadata["song_start_s"]
    assert tr.metadata["version"] == 2
    assert start > 0 and res.song_start_s == start
    assert abs(start * 100 - round(start * 100)) < 1e-9  # a whole number of rows
    rep = check_trajectory(str(path), song)
    assert rep.ok and rep.play.notes_hit == 2 and not rep.play.wrong_presses, rep.summary()
    assert rep.song_start_s == start
    assert not rep.replay.down[0].any()  # no key down in the first row


def test_a_song_late_enough_is_not_shifted():
    pl = Planner(load_hand("default"))
    res = plan_song(_song([Note(60, 2.0, 2.5, 80)]), pl.hand, None, planner=pl)
    assert res.song_start_s == 0.0
    assert res.trajectory.metadata["song_start_s"] == 0.0
    assert res.verdict.played == 1


def test_check_reads_the_song_in_the_files_time():
    """The same rows judged with the song unshifted (the shift removed from the file)
    lose the notes: `check` honours `song_start_s`."""
    pl = Planner(load_hand("default"))
    song = _song([Note(60, 0.0, 0.4, 80), Note(64, 0.5, 0.9, 80)])
    res = plan_song(song, pl.hand, None, planner=pl)
    assert res.song_start_s > 0
    good = check_trajectory(res.trajectory, song)
    assert good.ok and good.play.notes_hit == 2
    start = res.song_start_s
    text = res.text.replace(f'"song_start_s": {start}', '"song_start_s": 0.0')
    bad = check_trajectory(parse_trajectory(text), song)
    assert bad.play.notes_hit < 2 or bad.play.wrong_presses


def test_shift_notes_lands_on_the_rows_clock():
    """5.4 + 0.12 is 5.5200000000000005 in floats: shifted notes are rounded so that a
    sum that is a row's time is that row's time."""
    (n,) = shift_notes([Note(65, 5.4, 5.94, 80)], 0.12)
    assert n.onset_s == 5.52 and n.offset_s == 6.06


def test_whole_hand_move_keeps_every_motor_within_its_share(planner):
    """The way in turns the wrist and runs the rail: its acceleration is capped by what
    the motors hold with the hand's inertia (``path_acceleration_cap``), so its duration
    is at least that of the joints' own limits."""
    from planner.play.railcap import RAIL_TORQUE_SHARE, path_acceleration_cap

    rest = rest_pose(planner.atlas)
    q = planner.atlas.base.copy()
    m = whole_hand_move(planner.moves, rest, q)
    line = [planner.hand.apply_couplings(rest + s * m.dq) for s in np.linspace(0, 1, 12)]
    assert m.peak_acceleration <= path_acceleration_cap(planner.hand, line, m.dq) * (1 + 1e-12)
    assert 0.0 < RAIL_TORQUE_SHARE < 1.0
    legs = Legs(0.0, (m,))
    assert np.allclose(legs.at(np.array([0.0]))[0], rest)
    assert np.allclose(legs.at(np.array([legs.end_s + 1.0]))[0], rest + m.dq)
