"""Hardening (the harness and its contract: tests/hardening.py), (1) MIDI input: random,
truncated and mutated files, wrong chunk lengths, unsupported headers, overlapping and
zero-length notes, every tempo, pitch and velocity, 10,000 notes, dense one-tick notes,
a long silence; and the ``play`` command's arguments."""

from __future__ import annotations

import os
import struct
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import example, given
from hypothesis import strategies as st

from planner.music.midi import MAX_DURATION_S, Note, load_song, parse_song_bytes, write_notes_midi
from planner.trajfile import read_trajectory
from tests.hardening import (
    LONG,
    SCALE,
    SETTINGS,
    SONGS,
    SUMMARY,
    assert_envelope,
    assert_input_refused,
    assert_play_outcome,
    one_line,
    play_bytes,
    playable,
    run_cli,
    run_sub,
)
from tests.midibytes import chunks, events_track, header, mtrk, notes_track, smf, tempo_msg

# ====================================================================== 1. MIDI input


@SETTINGS
@given(data=st.one_of(
    st.binary(max_size=600),
    st.binary(max_size=600).map(lambda b: b"MThd" + b),
    st.tuples(st.integers(0, 3), st.integers(0, 4), st.integers(0, 0xFFFF),
              st.binary(max_size=400)).map(lambda t: header(t[0], t[1], t[2]) + b"MTrk" + t[3]),
    st.binary(max_size=400).map(lambda b: header(0, 1) + mtrk(b)),
), transpose=st.booleans())
def test_random_bytes(capsys, data, transpose):
    flags = ("--transpose",) if transpose else ()
    if playable(data, transpose):
        play_bytes(capsys, data, *flags)


@pytest.mark.parametrize("song", SONGS, ids=lambda p: p.stem)
def test_truncated_sample_song_at_every_length(capsys, song, tmp_path):
    data = song.read_bytes()
    out = tmp_path / "out.csv"
    for n in range(len(data)):
        p = tmp_path / "cut.mid"
        p.write_bytes(data[:n])
        rc, _, err = run_cli(capsys, "play", p, "-o", out)
        assert_input_refused(rc, err, out)
        assert ("empty" in err) if n == 0 else ("truncated" in err or "corrupt" in err), (n, err)


@SETTINGS
@given(song=st.sampled_from(SONGS), edits=st.lists(
    st.tuples(st.integers(0, 10_000), st.integers(0, 255)), min_size=1, max_size=4))
def test_mutated_sample_songs(capsys, song, edits):
    data = bytearray(song.read_bytes())
    for pos, b in edits:
        data[pos % len(data)] = b
    if playable(bytes(data)):
        play_bytes(capsys, bytes(data))


@SETTINGS
@given(song=st.sampled_from(SONGS), which=st.integers(0, 7), length=st.one_of(
    st.integers(-8, 8), st.integers(0, 0xFFFF_FFFF), st.sampled_from([0, 1, 3, 4, 0xFFFF_FFFF])),
    relative=st.booleans())
def test_wrong_chunk_lengths(capsys, song, which, length, relative):
    data = bytearray(song.read_bytes())
    pos, n = chunks(bytes(data))[which % len(chunks(bytes(data)))]
    new = min(max(n + length if relative else length, 0), 0xFFFF_FFFF)
    data[pos:pos + 4] = struct.pack(">L", new)
    if playable(bytes(data)):
        play_bytes(capsys, bytes(data))


def _scale_with_header(**kw) -> bytes:
    data = SCALE.read_bytes()
    hlen, fmt, ntracks, division = struct.unpack(">LHHH", data[4:14])
    vals = {"hlen": hlen, "fmt": fmt, "ntracks": ntracks, "division": division, **kw}
    return (b"MThd" + struct.pack(">LHHH", vals["hlen"], vals["fmt"], vals["ntracks"],
                                  vals["division"]) + data[14:])


@pytest.mark.parametrize("kw, words", [
    ({"fmt": 2}, "type 2"),
    ({"fmt": 3}, "format 3"),
    ({"fmt": 0xFFFF}, "format"),
    ({"division": 0xE728}, "SMPTE"),  # -25 fps, 40 ticks per frame
    ({"division": 0xE250}, "SMPTE"),  # -30 fps, 80 ticks per frame
    ({"division": 0}, "division"),
    ({"ntracks": 0}, "no tracks"),
    ({"ntracks": 3}, "truncated"),
    ({"ntracks": 0xFFFF}, "truncated"),
    ({"hlen": 0}, "header"),
    ({"hlen": 0xFFFF_FFFF}, "header"),
], ids=lambda v: str(v))
def test_unsupported_headers(capsys, tmp_path, kw, words):
    song = tmp_path / "s.mid"
    song.write_bytes(_scale_with_header(**kw))
    out = tmp_path / "o.csv"
    rc, _, err = run_cli(capsys, "play", song, "-o", out)
    assert_input_refused(rc, err, out)
    assert words in err, err


EVENT = st.tuples(
    st.integers(0, 240),  # delta ticks (480 per beat at 120 bpm: 0.25 s)
    st.sampled_from(["on", "off", "on0"]),  # note_on, note_off, note_on velocity 0
    st.sampled_from([60, 62, 64]),  # few pitches: overlaps, re-strikes, zero lengths
    st.integers(1, 127),
    st.sampled_from([0, 0, 1, 9]),  # 9 is the (ignored) drum channel
)


@SETTINGS
@given(tracks=st.lists(st.lists(EVENT, max_size=16), min_size=1, max_size=2),
       strict=st.booleans())
def test_zero_length_and_overlapping_notes(capsys, tracks, strict):
    data = header(1, len(tracks)) + b"".join(events_track(t) for t in tracks)
    rc = play_bytes(capsys, data, *(["--strict"] if strict else []), check_limits=True)
    try:
        song = parse_song_bytes(data)
    except Exception:  # noqa: BLE001
        song = None
    # refused exactly when there is nothing to play
    assert (rc == 2) == (song is None)
    if song is not None:  # notes of one key never overlap, none is empty
        for a in song.notes:
            assert a.offset_s > a.onset_s
            for b in song.notes:
                if a is not b and a.pitch == b.pitch:
                    assert a.offset_s <= b.onset_s or b.offset_s <= a.onset_s


SLOWEST_US = 0xFFFFFF  # the 24-bit set_tempo field: 3.576 bpm is the slowest tempo
BPM = st.floats(60e6 / SLOWEST_US, 1000.0)


@SETTINGS
@given(bpms=st.lists(BPM, min_size=1, max_size=3),
       notes=st.lists(st.tuples(st.sampled_from([55, 60, 64, 67, 72]), st.integers(0, 360),
                                st.integers(1, 120), st.integers(1, 127)),
                      min_size=1, max_size=4))
def test_tempos_from_3_58_to_1000_bpm(capsys, bpms, notes):
    tempos = [(i * 160, min(SLOWEST_US, round(60e6 / b))) for i, b in enumerate(bpms)]
    ns = [(p, a, a + d, v) for p, a, d, v in notes]
    data = smf(notes_track(ns, tempos))
    assert play_bytes(capsys, data, check_limits=True) != 2


@pytest.mark.parametrize("us", [SLOWEST_US, 60_000, 1, 0], ids=lambda u: f"{u}us")
def test_extreme_tempo_values(capsys, us):
    data = smf(notes_track([(60, 0, 240, 80), (64, 480, 720, 80)], [(0, us)]))
    rc = play_bytes(capsys, data, check_limits=True)
    assert rc == (2 if us == 0 else 0)


def test_slower_than_the_field_allows_is_not_representable():
    with pytest.raises(OverflowError):
        round(60e6 / 3.5).to_bytes(3, "big")  # 3.5 bpm needs 17,142,857 us per beat


@SETTINGS
@given(pitches=st.lists(st.integers(0, 127), min_size=1, max_size=6), transpose=st.booleans(),
       strict=st.booleans())
# found by this test: the hand travelling while a key was still down, and a finger pressing
# its key while the rail (after a rail-only travel) was still moving: key-bed hits
@example(pitches=[30, 54, 74], transpose=False, strict=False)
@example(pitches=[21, 30, 98, 89, 34], transpose=False, strict=False)
def test_pitches_0_to_127(capsys, pitches, transpose, strict):
    ns = [(p, 240 * i, 240 * i + 200, 80) for i, p in enumerate(pitches)]
    flags = (["--transpose"] if transpose else []) + (["--strict"] if strict else [])
    rc = play_bytes(capsys, smf(notes_track(ns)), *flags, check_limits=True)
    outside = any(not 21 <= p <= 108 for p in pitches)
    assert (rc == 2) == (outside and not transpose)


@SETTINGS
@given(vels=st.lists(st.integers(0, 127), min_size=1, max_size=8))
def test_velocities_0_to_127(capsys, vels):
    pitches = [60, 62, 64, 65, 67, 69, 71, 72]
    ns = [(pitches[i], 120 * i, 120 * i + 100, v) for i, v in enumerate(vels)]
    with tempfile.TemporaryDirectory() as d:
        song, out = Path(d, "s.mid"), Path(d, "o.csv")
        song.write_bytes(smf(notes_track(ns)))
        rc, o, err = run_cli(capsys, "play", song, "-o", out)
        rc, summary = assert_play_outcome(rc, err, out, out=o)
        sounding = sum(v > 0 for v in vels)  # a note_on of velocity 0 is a note_off
        if sounding == 0:
            assert rc == 2 and "no notes" in err
        else:
            assert rc == 0 and int(summary["notes"]) == sounding
            assert_envelope(out)


def test_ten_thousand_notes_parse_and_a_selected_part_plays(capsys, tmp_path):
    big = [(48 + i % 37, 60 * i, 60 * i + 50, 1 + i % 127) for i in range(10_000)]
    small = [(60, 0, 240, 80), (64, 480, 720, 80)]
    song = tmp_path / "big.mid"
    song.write_bytes(smf(notes_track(big), notes_track(small)))
    assert len(load_song(song).notes) == 10_002
    out = tmp_path / "o.csv"
    rc, o, err = run_cli(capsys, "play", song, "--track", "1", "-o", out)
    assert assert_play_outcome(rc, err, out, out=o)[1]["notes"] == "2"


def test_ten_thousand_notes_struck_together(capsys, tmp_path):
    """10,000 note_on events of 4 keys at 4 ticks: merged into 4 notes per tick."""
    ns = [(60 + 4 * (i % 4), 480 * (i // 2500), 480 * (i // 2500) + 240, 1 + i % 127)
          for i in range(10_000)]
    song = tmp_path / "big.mid"
    song.write_bytes(smf(notes_track(ns)))
    out = tmp_path / "o.csv"
    rc, o, err = run_cli(capsys, "play", song, "-o", out)
    assert assert_play_outcome(rc, err, out, out=o)[1]["notes"] == "16"


def test_ten_thousand_notes_planned_end_to_end(tmp_path):
    """One case (a subprocess, 1-2 min): 10,000 notes at 8 per second, 1250 s of music;
    in long mode 20,000 notes (2500 s), and the rows are also replayed through the
    independent check."""
    n = 20_000 if LONG else 10_000
    notes = [Note((60, 62, 64, 65, 67)[i % 5], 0.125 * i, 0.125 * i + 0.1, 64)
             for i in range(n)]
    write_notes_midi(notes, tmp_path / "big.mid")
    r = run_sub("play", tmp_path / "big.mid", "-o", tmp_path / "big.csv", cwd=tmp_path,
                timeout=1800)
    assert r.returncode == 0, r.stderr[-2000:]
    tr = read_trajectory(str(tmp_path / "big.csv"))
    assert tr.metadata["notes"] == n
    assert int(SUMMARY.search(r.stderr)["rows"]) == len(tr.t_s)
    if LONG:
        assert_envelope(tmp_path / "big.csv")


# the inputs issue 14 found slow (2 cores): one-tick notes (1/960 s at 480 per beat and
# 120 bpm), 48 ms each to plan, 20,000 killed at 600 s; a trill of 1 ms notes 78 s; one
# note after 20 hours of silence killed at 300 s. Long mode: 20,000 notes, an hour of music.
N_DENSE = 20_000 if LONG else 2_000
SILENCE_S = 3600 if LONG else 600


@pytest.mark.parametrize("kind", ["same_key", "many_keys", "trill_1ms"])
def test_notes_no_finger_can_strike_are_named_and_cost_nothing(capsys, tmp_path, kind):
    """Notes shorter than every press a finger can make are named too short before the
    fingering weighs them: planned at once, every one named, the file complete."""
    if kind == "trill_1ms":  # 1 ms notes, C4-D4 back to back (at 480 ticks per second)
        ns = [(60 + 2 * (i % 2), i, i + 1) for i in range(N_DENSE)]
        data = smf(notes_track([(p, a, b, 80) for p, a, b in ns], tempos=((0, 480_000),)),
                   division=480)
    else:  # one tick every 24 ticks: 20 per second
        ns = [(60 if kind == "same_key" else 48 + (7 * i) % 36, 24 * i, 24 * i + 1, 80)
              for i in range(N_DENSE)]
        data = smf(notes_track(ns))
    song = tmp_path / "dense.mid"
    song.write_bytes(data)
    out = tmp_path / "o.csv"
    rc, o, err = run_cli(capsys, "play", song, "-o", out)
    _, m = assert_play_outcome(rc, err, out, out=o)
    assert m["notes"] == str(N_DENSE) and m["played"] == "0" and m["bad"] == str(N_DENSE)
    assert err.count(": too_short: ") == N_DENSE
    assert read_trajectory(str(out)).end["left_out"][0]["reason"] == "too_short"


def test_one_note_after_a_long_silence(capsys, tmp_path):
    """Silence costs rows, not planning: a note, ``SILENCE_S`` of nothing, a note; both
    played, every row in the file, the hand still in between."""
    song = tmp_path / "silence.mid"
    ticks = SILENCE_S * 960  # at 120 bpm
    song.write_bytes(smf(notes_track([(60, 0, 480, 80), (62, ticks, ticks + 480, 80)])))
    out = tmp_path / "o.csv"
    rc, o, err = run_cli(capsys, "play", song, "-o", out)
    _, m = assert_play_outcome(rc, err, out, out=o)
    assert m["played"] == "2"
    tr = read_trajectory(str(out))
    assert len(tr.t_s) >= SILENCE_S * 100
    mid = (tr.t_s > 5.0) & (tr.t_s < SILENCE_S - 5.0)
    assert np.ptp(tr.q[mid], axis=0).max() == 0.0


def test_a_song_longer_than_24_hours_is_refused(capsys, tmp_path):
    ticks = (MAX_DURATION_S + 3600) * 2 * 480  # at 120 bpm
    song = tmp_path / "long.mid"
    song.write_bytes(smf(notes_track([(60, 0, ticks, 80)])))
    out = tmp_path / "o.csv"
    rc, _, err = run_cli(capsys, "play", song, "-o", out)
    assert_input_refused(rc, err, out)
    assert "hours" in err


@pytest.mark.parametrize("argv", [
    ["--rate", "nan"], ["--rate", "inf"], ["--rate", "0"], ["--rate", "-5"], ["--rate", "1e9"],
    ["--rate", "abc"], ["--track", "7"], ["--track", "-1"], ["--track", "x"],
    ["--channel", "16"], ["--channel", "9"], ["--channel", "-1"], ["--hand", "nosuchhand"],
    ["--hand", "/nonexistent/hand.toml"], ["--bogus"],
], ids=" ".join)
def test_bad_play_arguments(capsys, tmp_path, argv):
    out = tmp_path / "o.csv"
    rc, _, err = run_cli(capsys, "play", SCALE, "-o", out, *argv)
    assert_input_refused(rc, err, out)


def test_missing_and_unreadable_songs(capsys, tmp_path):
    out = tmp_path / "o.csv"
    for song in (tmp_path / "nope.mid", tmp_path, Path("/dev/null")):
        rc, _, err = run_cli(capsys, "play", song, "-o", out)
        assert_input_refused(rc, err, out)


def _hands() -> list[str]:
    from planner.hand.spec import list_hands

    return list(list_hands())


@pytest.mark.parametrize("hand", _hands())
def test_play_with_every_shipped_hand(capsys, tmp_path, hand):
    out = tmp_path / "o.csv"
    rc, o, err = run_cli(capsys, "play", SCALE, "--hand", hand, "-o", out)
    assert_play_outcome(rc, err, out, out=o)
    assert_envelope(out, SCALE)


@pytest.mark.parametrize("argv", [
    ["play", "no\nsuch.mid"], ["play", str(SCALE), "stray\nargument"],
    ["play", str(SCALE), "--hand", "x\ny"], ["play", str(SCALE), "--rate", "1\n2"],
    ["check", "no\nsuch.csv"], ["hand", "--hand", "a\r\nb"],
], ids=["song", "argument", "hand", "rate", "check", "crlf"])
def test_line_breaks_in_user_input_stay_on_one_line(capsys, tmp_path, argv):
    rc, out, err = run_cli(capsys, *argv)
    assert rc == 2 and out == ""
    one_line(err)


BAD_MIDI = {
    "garbage": b"\x00\xffgarbage" * 30,
    "truncated": SCALE.read_bytes()[:60],
    "type2": _scale_with_header(fmt=2),
    "smpte": _scale_with_header(division=0xE728),
    "pitch_out_of_range": smf(notes_track([(120, 0, 240, 80)])),
    "no_notes": smf([(0, tempo_msg(500_000))]),
}


@pytest.mark.parametrize("name", sorted(BAD_MIDI))
def test_subprocess_bad_midi_prints_one_line(tmp_path, name):
    song = tmp_path / "in.mid"
    song.write_bytes(BAD_MIDI[name])
    r = run_sub("play", song, "-o", tmp_path / "o.csv", cwd=tmp_path, timeout=60)
    assert_input_refused(r.returncode, r.stderr, tmp_path / "o.csv")
    assert r.stdout == ""
    assert sorted(os.listdir(tmp_path)) == ["in.mid"]
