"""Tests of planner.music.midi: MIDI bytes -> Song, and write_notes_midi.

The bytes a Standard MIDI File reader must refuse (chunks, headers, sizes, garbage)
are tested in test_smf.py; the files are built in tests/midibytes.py."""

from __future__ import annotations

from itertools import pairwise
from pathlib import Path

import mido
import pytest

from planner.errors import InputError
from planner.music import midi
from planner.music.midi import (
    Note,
    load_song,
    parse_song_bytes,
    pitch_name,
    write_notes_midi,
)
from tests.midibytes import (
    END,
    assert_input_error,
    cc,
    header,
    mido_smf,
    mtrk,
    off,
    on,
    tempo,
    times,
)

SONGS = Path(__file__).resolve().parent.parent / "songs"


# ---------------------------------------------------------------- tempo map


def hand_seconds(tick: int) -> float:
    """The tempo map of test_tempo_change_type1, by hand."""
    # 120 bpm for ticks 0..960, 240 bpm for 960..1920, 40 bpm after that
    if tick <= 960:
        return tick * 0.5 / 480
    if tick <= 1920:
        return 1.0 + (tick - 960) * 0.25 / 480
    return 1.5 + (tick - 1920) * 1.5 / 480


def test_tempo_change_type1():
    conductor = [tempo(500_000), tempo(250_000, time=960), tempo(1_500_000, time=960)]
    part = []
    for i in range(14):  # an eighth note every 240 ticks, 200 ticks long
        part += [on(60 + i, time=0 if i == 0 else 40), off(60 + i, time=200)]
    song = parse_song_bytes(mido_smf(conductor, part))
    assert len(song.notes) == 14
    for i, n in enumerate(song.notes):
        assert n.pitch == 60 + i
        assert n.track == 1 and n.channel == 0 and n.velocity == 64
        assert n.onset_s == pytest.approx(hand_seconds(240 * i), abs=1e-3)
        assert n.offset_s == pytest.approx(hand_seconds(240 * i + 200), abs=1e-3)
        # exact arithmetic: much better than 1 ms
        assert n.onset_s == pytest.approx(hand_seconds(240 * i), abs=1e-9)
    # note 4 starts at the first change, note 5 straddles none, note 9 the second
    assert song.notes[4].onset_s == pytest.approx(1.0)
    assert song.notes[8].onset_s == pytest.approx(1.5)
    assert song.duration_s == pytest.approx(hand_seconds(240 * 13 + 200))


def test_tempo_change_in_a_later_track_applies_to_all():
    notes = [on(60), off(60, time=1920)]
    tempos = [tempo(1_000_000, time=960)]  # tempo in track 2, after the notes' track
    song = parse_song_bytes(mido_smf([], notes, tempos))
    # 960 ticks (2 beats) at 120 bpm = 1.0 s, then 2 beats at 60 bpm = 2.0 s
    assert times(song) == [(60, 0.0, 3.0)]


def test_tempo_change_type0_mid_note():
    msgs = [on(60), tempo(1_000_000, time=480), off(60, time=480), on(62), off(62, time=240)]
    song = parse_song_bytes(mido_smf(msgs, type=0))
    assert times(song) == [(60, 0.0, 1.5), (62, 1.5, 2.0)]


@pytest.mark.parametrize("us_per_beat", [60_000, 120_000, 500_000, 15_000_000, 0xFFFFFF])
def test_tempo_extremes(us_per_beat):
    # 1000 bpm up to the slowest tempo MIDI can encode (3.58 bpm)
    song = parse_song_bytes(mido_smf([tempo(us_per_beat)], [on(60, time=480), off(60, time=480)]))
    beat = us_per_beat / 1e6
    assert times(song) == [(60, pytest.approx(beat), pytest.approx(2 * beat))]


def test_zero_tempo_is_refused():
    body = b"\x00\xff\x51\x03\x00\x00\x00" + b"\x00\x90\x3c\x40\x60\x80\x3c\x00" + END
    assert_input_error(header(0, 1) + mtrk(body), "tempo")


def test_two_tempi_at_one_tick_the_later_wins():
    song = parse_song_bytes(mido_smf([tempo(250_000), tempo(1_000_000)], [on(60), off(60, time=480)]))
    assert times(song) == [(60, 0.0, 1.0)]


# ---------------------------------------------------------------- note pairing


def test_velocity_zero_note_on_ends_a_note():
    song = parse_song_bytes(mido_smf([on(60), on(60, time=480, velocity=0), on(64), off(64, time=480)]))
    assert times(song) == [(60, 0.0, 0.5), (64, 0.5, 1.0)]


def test_note_off_velocity_is_ignored():
    song = parse_song_bytes(mido_smf([on(60, velocity=100), off(60, time=480, velocity=64)]))
    assert song.notes[0].velocity == 100
    assert times(song) == [(60, 0.0, 0.5)]


def test_overlapping_same_pitch_restrike():
    # on, on (before any off), off, off: the second note_on ends the first
    msgs = [on(60, velocity=50), on(60, time=480, velocity=90), off(60, time=480),
            off(60, time=240)]
    song = parse_song_bytes(mido_smf(msgs))
    assert times(song) == [(60, 0.0, 0.5), (60, 0.5, 1.0)]
    assert [n.velocity for n in song.notes] == [50, 90]


def test_restrike_with_release_written_late_at_the_same_tick():
    # a writer that emits the next note_on before the old note_off at one tick
    msgs = [on(60), on(60, time=480), off(60), off(60, time=480)]
    song = parse_song_bytes(mido_smf(msgs))
    assert times(song) == [(60, 0.0, 0.5), (60, 0.5, 1.0)]


def test_off_then_on_at_the_same_tick():
    msgs = [on(60), off(60, time=480), on(60), off(60, time=480)]
    song = parse_song_bytes(mido_smf(msgs))
    assert times(song) == [(60, 0.0, 0.5), (60, 0.5, 1.0)]


def test_unclosed_note_ends_at_end_of_file():
    notes = [on(60), on(64, time=240), off(64, time=240)]
    other = [mido.MetaMessage("end_of_track", time=1920)]  # the longest track
    song = parse_song_bytes(mido_smf(notes, other))
    assert times(song) == [(60, 0.0, 2.0), (64, 0.25, 0.5)]
    assert song.duration_s == pytest.approx(2.0)


def test_zero_length_notes_are_dropped():
    msgs = [on(60), off(60), on(62), off(62, time=480)]
    song = parse_song_bytes(mido_smf(msgs))
    assert times(song) == [(62, 0.0, 0.5)]


def test_unmatched_note_off_is_ignored():
    song = parse_song_bytes(mido_smf([off(61), on(60, time=10), off(60, time=470), off(60)]))
    assert [n.pitch for n in song.notes] == [60]


def test_same_pitch_on_two_channels_is_merged_into_one_key():
    msgs = [on(60, channel=0), on(60, time=240, channel=1), off(60, time=240, channel=0),
            off(60, time=240, channel=1)]
    song = parse_song_bytes(mido_smf(msgs))
    assert times(song) == [(60, 0.0, 0.25), (60, 0.25, 0.75)]


def test_notes_sorted_by_onset_then_pitch():
    msgs = [on(67), on(60), on(64), off(60, time=480), off(64), off(67), on(59), on(48),
            off(59, time=480), off(48)]
    song = parse_song_bytes(mido_smf(msgs))
    assert [(n.onset_s, n.pitch) for n in song.notes] == [
        (0.0, 60), (0.0, 64), (0.0, 67), (0.5, 48), (0.5, 59)]
    assert all(n.onset_s < n.offset_s for n in song.notes)


# ---------------------------------------------------------------- channels, tracks, pedal


def test_drums_are_ignored():
    msgs = [on(36, channel=9), on(60), off(36, time=480, channel=9), off(60)]
    song = parse_song_bytes(mido_smf(msgs))
    assert [(n.pitch, n.channel) for n in song.notes] == [(60, 0)]


def test_drums_only_file_has_no_notes():
    msgs = [on(36, channel=9), off(36, time=480, channel=9)]
    assert_input_error(mido_smf(msgs), "no notes", "drums")


def two_parts() -> bytes:
    conductor = [tempo(500_000)]
    right = [on(72, channel=0), off(72, time=480, channel=0), on(74, channel=1),
             off(74, time=480, channel=1)]
    left = [on(48, channel=2), off(48, time=960, channel=2)]
    return mido_smf(conductor, right, left)


def test_track_and_channel_selection():
    data = two_parts()
    upper = parse_song_bytes(data)  # (the default: the upper part, planner/music/parts.py)
    assert [(n.pitch, n.track, n.channel) for n in upper.notes] == [(72, 1, 0), (74, 1, 1)]
    assert upper.part.played == ((1, 0), (1, 1)) and "track 2 channel 2" in upper.part.reason
    assert [n.pitch for n in parse_song_bytes(data, track=1).notes] == [72, 74]
    assert [n.pitch for n in parse_song_bytes(data, track=2).notes] == [48]
    assert [n.pitch for n in parse_song_bytes(data, channel=1).notes] == [74]
    assert [n.pitch for n in parse_song_bytes(data, track=1, channel=0).notes] == [72]
    # selection never changes the timing or the file's duration
    assert parse_song_bytes(data, track=2).duration_s == upper.duration_s == 1.0


def test_bad_track_index_names_the_range():
    assert_input_error(two_parts(), "track 3", "0..2", track=3)
    assert_input_error(two_parts(), "0..2", track=-1)


def test_bad_channel_index_names_the_range():
    assert_input_error(two_parts(), "channel 16", "0..15", channel=16)
    assert_input_error(two_parts(), "drum", channel=9)


def test_empty_selection_says_where_the_notes_are():
    msg = assert_input_error(two_parts(), "no notes", "track 0", track=0)
    assert "track 1 channel 0" in msg
    assert_input_error(two_parts(), "no notes on channel 5", channel=5)
    assert_input_error(two_parts(), "no notes in track 2 on channel 0", track=2, channel=0)


def test_sustain_intervals():
    msgs = [cc(64, 127), on(60), cc(64, 0, time=480), off(60, time=480), cc(64, 100, time=480),
            cc(64, 90, time=240), cc(7, 10), on(62), off(62, time=240)]
    song = parse_song_bytes(mido_smf(msgs))
    # pedal down 0..0.5 s; down again at 1.5 s and never up -> to end of file (2.0 s)
    assert song.sustain == ((0.0, 0.5), (1.5, 2.0))
    # the pedal does not lengthen notes
    assert times(song) == [(60, 0.0, 1.0), (62, 1.75, 2.0)]


def test_sustain_is_a_union_over_channels():
    msgs = [cc(64, 127, channel=0), cc(64, 127, time=240, channel=1), on(60),
            cc(64, 0, time=240, channel=0), cc(64, 0, time=480, channel=1), off(60)]
    song = parse_song_bytes(mido_smf(msgs))
    assert song.sustain == ((0.0, 1.0),)
    assert parse_song_bytes(mido_smf(msgs), channel=0).sustain == ((0.0, 0.5),)


# ---------------------------------------------------------------- piano range


def test_out_of_range_pitch_is_an_input_error():
    msgs = [on(60), off(60, time=480), on(110), off(110, time=480), on(10), off(10, time=480)]
    msg = assert_input_error(mido_smf(msgs), "110", "0.500 s", "--transpose", "21", "108")
    assert "1.000 s" not in msg  # the first offender is named, not a later one


def test_transpose_moves_by_octaves_into_range():
    msgs = [on(0), on(20), on(21), on(108), on(109), on(127),
            off(0, time=480), off(20), off(21), off(108), off(109), off(127)]
    song = parse_song_bytes(mido_smf(msgs), transpose=True)
    # 0 -> 24, 20 -> 32, 109 -> 97, 127 -> 103; 21 and 108 are in range and stay
    assert [n.pitch for n in song.notes] == [21, 24, 32, 97, 103, 108]
    assert all((n.onset_s, n.offset_s) == (0.0, 0.5) for n in song.notes)


def test_transpose_keeps_in_range_notes_and_merges_collisions():
    msgs = [on(21), on(108), on(9), on(120), off(21, time=480), off(108), off(9), off(120)]
    song = parse_song_bytes(mido_smf(msgs), transpose=True)
    # 9 -> 21 and 120 -> 108 land on sounding keys: struck together, so one note each
    assert times(song) == [(21, 0.0, 0.5), (108, 0.0, 0.5)]
    msgs = [on(9), on(21, time=240), off(9, time=240), off(21, time=240)]
    song = parse_song_bytes(mido_smf(msgs), transpose=True)
    # 9 -> 21 is cut where the real 21 starts
    assert times(song) == [(21, 0.0, 0.25), (21, 0.25, 0.75)]

# ---------------------------------------------------------------- files load_song refuses


def test_empty_bytes_and_empty_file(tmp_path):
    assert_input_error(b"", "empty file")
    p = tmp_path / "empty.mid"
    p.write_bytes(b"")
    with pytest.raises(InputError, match="empty file"):
        load_song(p)


def test_missing_file_and_directory(tmp_path):
    with pytest.raises(InputError, match="not found"):
        load_song(tmp_path / "nope.mid")
    with pytest.raises(InputError, match="directory"):
        load_song(tmp_path)


def test_file_too_big(tmp_path):
    p = tmp_path / "huge.mid"
    with open(p, "wb") as fh:
        fh.truncate(midi.MAX_FILE_BYTES + 1)  # sparse: costs no disk
    with pytest.raises(InputError, match="16 MiB"):
        load_song(p)
    assert_input_error(b"\0" * (midi.MAX_FILE_BYTES + 1), "16 MiB")


def test_no_notes():
    assert_input_error(mido_smf([tempo(500_000)], [cc(64, 127)]), "no notes on channel(s)")


# ---------------------------------------------------------------- writing


def test_round_trip(tmp_path):
    notes = [
        Note(60, 0.0, 0.4, 80),
        Note(64, 0.0, 0.4, 70),
        Note(67, 0.0123, 0.4567, 90, channel=3),
        Note(60, 0.5, 0.75, 64),
        Note(72, 1.2345, 3.3333, 100),
        Note(21, 2.0, 2.001, 1),
        Note(108, 2.5, 2.6, 127),
    ]
    path = tmp_path / "rt.mid"
    write_notes_midi(notes, path)
    song = load_song(path)
    assert song.source == str(path)
    got = sorted(song.notes, key=lambda n: (n.onset_s, n.pitch))
    want = sorted(notes, key=lambda n: (n.onset_s, n.pitch))
    assert len(got) == len(want)
    for g, w in zip(got, want):
        assert (g.pitch, g.velocity, g.channel, g.track) == (w.pitch, w.velocity, w.channel, 1)
        assert abs(g.onset_s - w.onset_s) <= 1e-3
        assert abs(g.offset_s - w.offset_s) <= 1e-3
    assert song.duration_s == pytest.approx(3.3333, abs=1e-3)


@pytest.mark.parametrize(("tpb", "us"), [(480, 500_000), (960, 1_000_000), (96, 60_000)])
def test_round_trip_other_resolutions(tmp_path, tpb, us):
    notes = [Note(60 + (i % 12), 0.37 * i, 0.37 * i + 0.3, 64) for i in range(40)]
    write_notes_midi(notes, tmp_path / "x.mid", ticks_per_beat=tpb, tempo_us=us)
    song = load_song(tmp_path / "x.mid")
    tick_s = us / 1e6 / tpb
    for g, w in zip(song.notes, notes):
        assert abs(g.onset_s - w.onset_s) <= tick_s / 2 + 1e-9
        assert abs(g.offset_s - w.offset_s) <= tick_s / 2 + 1e-9


def test_round_trip_repeated_pitch_back_to_back(tmp_path):
    notes = [Note(60, 0.0, 0.5, 64), Note(60, 0.5, 1.0, 64), Note(60, 0.8, 1.2, 64)]
    write_notes_midi(notes, tmp_path / "r.mid")
    song = load_song(tmp_path / "r.mid")
    # the overlap (0.8 < 1.0) is cut at the later onset
    assert [(n.onset_s, n.offset_s) for n in song.notes] == [
        (0.0, 0.5), (0.5, pytest.approx(0.8, abs=1e-3)), (pytest.approx(0.8, abs=1e-3), 1.2)]


def test_write_is_deterministic(tmp_path):
    notes = [Note(60 + i, i * 0.25, i * 0.25 + 0.2, 64) for i in range(8)]
    write_notes_midi(notes, tmp_path / "a.mid")
    write_notes_midi(reversed(notes), tmp_path / "b.mid")
    assert (tmp_path / "a.mid").read_bytes() == (tmp_path / "b.mid").read_bytes()


@pytest.mark.parametrize(
    "note",
    [Note(128, 0, 1, 64), Note(60, 0, 1, 0), Note(60, 0, 1, 128), Note(60, 1, 1, 64),
     Note(60, -1, 1, 64), Note(60, 0, float("nan"), 64), Note(60, 0, 1, 64, channel=16)],
)
def test_write_rejects_bad_notes(tmp_path, note):
    with pytest.raises(InputError):
        write_notes_midi([note], tmp_path / "bad.mid")


def test_write_rejects_bad_parameters(tmp_path):
    with pytest.raises(InputError):
        write_notes_midi([], tmp_path / "a.mid", tempo_us=60_000_000)  # 1 bpm: no 24-bit fit
    with pytest.raises(InputError):
        write_notes_midi([], tmp_path / "a.mid", ticks_per_beat=0)


def test_pitch_name():
    assert pitch_name(60) == "C4"
    assert pitch_name(21) == "A0"
    assert pitch_name(108) == "C8"
    assert pitch_name(61) == "C#4"


# ---------------------------------------------------------------- sample songs


EXPECTED = {  # name: (notes, lowest, highest)
    "scale.mid": (15, 60, 72),
    "twinkle.mid": (14, 60, 69),
    "ode_to_joy.mid": (62, 55, 67),
    "fur_elise.mid": (17, 60, 76),
    "chords.mid": (29, 59, 72),
    "fast.mid": (43, 60, 69),
    "leaps.mid": (12, 48, 84),
    "stress/fast_six_keys.mid": (33, 60, 69),
    "stress/leaps_legato.mid": (12, 48, 84),
}


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_sample_song_loads(name):
    song = load_song(SONGS / name)
    count, low, high = EXPECTED[name]
    assert len(song.notes) == count
    assert min(n.pitch for n in song.notes) == low
    assert max(n.pitch for n in song.notes) == high
    assert 48 <= low and high <= 84  # right hand, C3..C6
    assert not song.sustain
    for n in song.notes:
        later = [m.onset_s for m in song.notes if m.onset_s > n.onset_s]
        if later:  # a gap before the next onset, always
            assert n.offset_s < min(later)
        same = [m.onset_s for m in song.notes if m.pitch == n.pitch and m.onset_s > n.onset_s]
        if same:  # the key comes up at least 60 ms before it is struck again
            assert min(same) - n.offset_s >= 0.060 - 1e-9


def test_sample_scale():
    song = load_song(SONGS / "scale.mid")
    assert [n.pitch for n in song.notes] == [60, 62, 64, 65, 67, 69, 71, 72, 71, 69, 67, 65, 64,
                                             62, 60]
    assert song.notes[1].onset_s == pytest.approx(0.6)  # quarter notes at 100 bpm


def test_sample_fast_has_eight_notes_per_second():
    onsets = sorted(n.onset_s for n in load_song(SONGS / "fast.mid").notes)
    best = max(sum(1 for t in onsets if t0 <= t < t0 + 1.0) for t0 in onsets)
    assert best >= 8
    pitches = {n.pitch for n in load_song(SONGS / "fast.mid").notes}
    assert 5 <= len(pitches) <= 8


def test_sample_fast_runs_stay_within_five_keys_between_rests():
    """Each legato run of fast.mid (notes less than a sixteenth apart) spans five keys at
    most; the stress song's runs span six."""
    def runs(name):
        notes = sorted(load_song(SONGS / name).notes, key=lambda n: n.onset_s)
        out = [[notes[0]]]
        for a, b in pairwise(notes):
            (out[-1] if b.onset_s - a.offset_s < 0.05 else out.append([]) or out[-1]).append(b)
        return [{n.pitch for n in r} for r in out]

    assert [len(r) for r in runs("fast.mid")] == [5, 5, 5]
    assert max(len(r) for r in runs("stress/fast_six_keys.mid")) == 6


def test_sample_leaps_has_a_leap_over_two_octaves():
    notes = load_song(SONGS / "leaps.mid").notes
    leaps = [abs(b.pitch - a.pitch) for a, b in pairwise(notes)]
    assert max(leaps) > 24
    assert min(b.onset_s - a.onset_s for a, b in pairwise(notes)) >= 0.6 - 1e-9
    # detached: half of every slot is the hand's to cross the keyboard in
    assert min(b.onset_s - a.offset_s for a, b in pairwise(notes)) == pytest.approx(0.3)


def test_sample_chords_has_three_and_four_note_chords():
    notes = load_song(SONGS / "chords.mid").notes
    chords: dict[float, list[int]] = {}
    for n in notes:
        chords.setdefault(n.onset_s, []).append(n.pitch)
    sizes = {len(c) for c in chords.values()}
    assert {3, 4} <= sizes
    assert all(max(c) - min(c) <= 12 for c in chords.values())


def test_sample_songs_are_regenerated_identically(tmp_path, monkeypatch):
    import importlib.util

    spec = importlib.util.spec_from_file_location("make_songs", SONGS / "make_songs.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    monkeypatch.setattr(mod, "HERE", tmp_path)
    mod.main()
    for name in EXPECTED:
        assert (tmp_path / name).read_bytes() == (SONGS / name).read_bytes(), name
