"""A file of several parts played by one hand: the upper part by default, said in the
summary and ``--json``; ``track=``/``channel=`` choose another (planner/music/parts.py)."""

from __future__ import annotations

import glob
from pathlib import Path

import pytest

from planner.music.midi import load_song, parse_song_bytes
from tests.midibytes import notes_track, smf

ROOT = Path(__file__).resolve().parents[1]
Q = 480  # ticks a quarter note (0.5 s at the default 120 bpm)
E4, D4, C4, G4 = 64, 62, 60, 67
MELODY = [(E4, 1), (D4, 1), (C4, 1), (D4, 1), (E4, 1), (E4, 1), (E4, 2), (D4, 1), (D4, 1),
          (D4, 2), (E4, 1), (G4, 1), (G4, 2), (E4, 1), (D4, 1), (C4, 1), (D4, 1), (E4, 1),
          (E4, 1), (E4, 1), (E4, 1), (D4, 1), (D4, 1), (E4, 1), (D4, 1), (C4, 4)]
BASS = [(48, 8), (43, 4), (48, 4), (48, 4), (48, 4), (43, 4), (48, 4)]  # C3, G2: 7 notes


def _line(notes, channel=0):
    out, tick = [], 0
    for pitch, beats in notes:
        out.append((pitch, tick, tick + beats * Q - 24, 80, channel))
        tick += beats * Q
    return out


def _mary(tmp_path, one_track=False) -> Path:
    """"Mary had a little lamb": the melody (26 notes) and a bass line (7), in tracks 1
    and 2 after a tempo track, or both in track 0."""
    if one_track:
        data = smf(notes_track(_line(MELODY) + _line(BASS)), fmt=0)
    else:
        data = smf(notes_track([]), notes_track(_line(MELODY)), notes_track(_line(BASS, 1)))
    path = tmp_path / ("mary1.mid" if one_track else "mary.mid")
    path.write_bytes(data)
    return path


def test_the_upper_track_is_played_and_the_reason_given(tmp_path):
    song = load_song(_mary(tmp_path))
    assert [n.pitch for n in song.notes] == [p for p, _ in MELODY]
    assert (song.track, song.channel) == (None, None)  # (the options: check reads it so)
    part = song.part
    assert (part.played, part.track, part.channel, part.split_pitch) == (((1, 0),), 1, 0, None)
    assert [(p.track, p.notes, p.median_pitch) for p in part.parts] == [(1, 26, 63.0),
                                                                        (2, 7, 48.0)]
    assert part.reason == ("the upper part, track 1 channel 0 (26 notes, median MIDI 63), its "
                           "notes highest; left out, an octave or more lower: track 2 "
                           "channel 1 (7 notes, median MIDI 48); --track/--channel choose "
                           "another part")


def test_track_and_channel_choose_otherwise(tmp_path):
    path = _mary(tmp_path)
    bass = load_song(path, track=2)
    assert [n.pitch for n in bass.notes] == [p for p, _ in BASS] and bass.part is None
    assert len(load_song(path, channel=1).notes) == 7
    assert len(load_song(path, track=1).notes) == 26


def test_one_track_with_both_hands_is_split_by_pitch(tmp_path):
    song = load_song(_mary(tmp_path, one_track=True))
    assert [n.pitch for n in song.notes] == [p for p, _ in MELODY]
    assert song.part.split_pitch == C4 and song.part.played == ((0, 0),)
    assert "7 below left out" in song.part.reason


def test_a_single_part_is_read_whole():
    """Every sample song is one part: no choice, every note (their plans unchanged)."""
    for f in glob.glob(str(ROOT / "songs" / "**" / "*.mid"), recursive=True):
        assert load_song(f).part is None, f
    wide = smf(notes_track([(p, 0, Q, 80) for p in (36, 48, 60, 72, 84)]))
    assert len(parse_song_bytes(wide).notes) == 5  # (one wide chord: one hand's problem)


def test_parts_within_an_octave_are_one_hands_line():
    """A line spread over channels (a doubling, a file written channel by channel) is
    read whole; a part an octave lower is left out."""
    line = [(60 + i % 5, i * Q, (i + 1) * Q, 80, i % 3) for i in range(12)]  # 3 channels
    assert len(parse_song_bytes(smf(notes_track(line))).notes) == 12
    bass = [(45, i * 4 * Q, (i + 1) * 4 * Q, 80, 5) for i in range(3)]  # A2, 21 lower
    song = parse_song_bytes(smf(notes_track(line + bass)))
    assert len(song.notes) == 12 and song.part.played == ((0, 0), (0, 1), (0, 2))
    assert (song.part.track, song.part.channel) == (0, None)


@pytest.mark.parametrize("one_track", [False, True])
def test_the_hand_plays_the_melody_and_says_which_part(tmp_path, one_track):
    import planner
    from planner.play.summary import format_summary, plan_dict

    path = _mary(tmp_path, one_track)
    song = planner.load_song(path)
    hand = planner.load_hand("default")
    out = str(tmp_path / "mary.csv")
    plan = planner.plan_song(song, hand, out)
    assert (plan.verdict.notes, plan.verdict.played) == (26, 26)
    text = format_summary(path.name, song.notes, plan, out)
    assert text.splitlines()[2] == f"part: {song.part.reason}"
    d = plan_dict(path.name, song.notes, plan, out, 0.0)
    assert d["part"]["split_pitch"] == (C4 if one_track else None)
    tr = planner.read_trajectory(out)
    assert tr.metadata["song"] == path.name and tr.metadata["part"]["reason"] == song.part.reason
    report = planner.check_trajectory(out, str(path))  # (check reads the same part)
    assert report.ok and report.play.notes_hit == 26
