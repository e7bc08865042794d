"""Tests of planner.music.smf: a MIDI file's bytes read without trusting them (the
header, the chunks, the RIFF wrapper, the size and event budgets, garbage), through
parse_song_bytes; the files are built in tests/midibytes.py."""

from __future__ import annotations

import struct
from itertools import pairwise

import mido
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from planner.errors import InputError
from planner.music import midi
from planner.music import smf as smf_module
from planner.music.midi import parse_song_bytes
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

# ---------------------------------------------------------------- bad files


def test_not_a_midi_file():
    assert_input_error(b"hello world, this is text\n", "not a MIDI file")


def test_no_tracks():
    assert_input_error(header(1, 0), "no tracks")


def test_type2_refused():
    data = header(2, 1) + mtrk(b"\x00\x90\x3c\x40\x60\x80\x3c\x00" + END)
    assert_input_error(data, "type 2 (asynchronous) MIDI files are not supported")


def test_unknown_format_refused():
    assert_input_error(header(7, 1) + mtrk(END), "format 7")


def test_smpte_division_refused():
    # -25 frames per second, 40 ticks per frame: top bit of the division set
    division = ((256 - 25) << 8) | 40
    data = header(0, 1, division) + mtrk(b"\x00\x90\x3c\x40\x60\x80\x3c\x00" + END)
    assert_input_error(data, "SMPTE")


def test_zero_division_refused():
    assert_input_error(header(0, 1, 0) + mtrk(END), "0 ticks per beat")


def test_truncated_files():
    data = mido_smf([tempo(400_000)], [on(60), off(60, time=480), on(64), off(64, time=480)])
    parse_song_bytes(data)  # the whole file is fine
    for n in range(1, len(data)):
        with pytest.raises(InputError) as info:
            parse_song_bytes(data[:n])
        assert "\n" not in str(info.value)


def test_missing_track():
    assert_input_error(header(1, 2) + mtrk(b"\x00\x90\x3c\x40\x60\x80\x3c\x00" + END),
                       "declares 2 track(s)")


def test_unknown_chunk_is_skipped():
    body = b"\x00\x90\x3c\x40\x60\x80\x3c\x00" + END
    data = header(1, 1) + b"XFIH" + struct.pack(">L", 3) + b"abc" + mtrk(body)
    song = parse_song_bytes(data)
    assert [n.pitch for n in song.notes] == [60]


def test_garbage_where_a_chunk_should_be():
    assert_input_error(header(1, 1) + b"\x00\x01\xfe\x99" + b"\0" * 20, "no track chunk")


def test_bad_data_byte_in_track():
    body = b"\x00\x90\x3c\xc0" + END  # velocity byte with the high bit set
    assert_input_error(header(0, 1) + mtrk(body), "corrupt MIDI data in track 0")


def test_riff_wrapped_midi():
    inner = mido_smf([on(60), off(60, time=480)])
    data_chunk = b"data" + struct.pack("<L", len(inner)) + inner
    riff = b"RIFF" + struct.pack("<L", 4 + len(data_chunk)) + b"RMID" + data_chunk
    assert times(parse_song_bytes(riff)) == [(60, 0.0, 0.5)]


# ---------------------------------------------------------------- hostile sizes


def test_too_many_notes(monkeypatch):
    monkeypatch.setattr(smf_module, "MAX_NOTES", 10)
    msgs = []
    for i in range(11):
        msgs += [on(60 + i), off(60 + i, time=10)]
    assert_input_error(mido_smf(msgs), "more than 10 notes")
    parse_song_bytes(mido_smf(msgs[:20]))  # 10 notes are fine


def test_too_many_events(monkeypatch):
    monkeypatch.setattr(smf_module, "MAX_EVENTS", 100)
    msgs = [cc(7, i % 128, time=1) for i in range(150)] + [on(60), off(60, time=10)]
    assert_input_error(mido_smf(msgs), "more than 100 MIDI events")


def test_endless_variable_length_quantity():
    body = b"\xff" * 20_000 + b"\x00"
    assert_input_error(header(0, 1) + mtrk(body), "high bit")


def test_absurd_duration():
    # four maximal deltas at 1 tick per beat and the slowest tempo: years of silence
    body = b"\x00\xff\x51\x03\xff\xff\xff" + b"\x00\x90\x3c\x40"
    body += b"\xff\xff\xff\x7f\x80\x3c\x00" * 4 + END
    assert_input_error(header(0, 1, 1) + mtrk(body), "24 hours")


# ---------------------------------------------------------------- garbage in, InputError out


VALID = mido_smf(
    [tempo(500_000), mido.MetaMessage("key_signature", key="C"), tempo(300_000, time=480)],
    [on(60), cc(64, 127), off(60, time=240), on(64, time=10), off(64, time=400), cc(64, 0)],
)


def _mutate(data: bytes, edits: list[tuple[int, int]]) -> bytes:
    b = bytearray(data)
    for pos, val in edits:
        b[pos % len(b)] = val
    return bytes(b)


garbage = st.one_of(
    st.binary(max_size=300),
    st.binary(max_size=200).map(lambda body: header(1, 1) + mtrk(body)),
    st.binary(max_size=200).map(lambda body: header(0, 1) + body),
    st.lists(st.tuples(st.integers(0, 10_000), st.integers(0, 255)), min_size=1, max_size=6)
    .map(lambda edits: _mutate(VALID, edits)),
    st.integers(0, len(VALID)).map(lambda n: VALID[:n]),
)


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(garbage, st.booleans())
def test_garbage_parses_or_raises_input_error(data, transpose):
    try:
        song = parse_song_bytes(data, transpose=transpose)
    except InputError as exc:
        assert "\n" not in str(exc)
        return
    assert song.notes
    for a, b in pairwise(song.notes):
        assert (a.onset_s, a.pitch) < (b.onset_s, b.pitch)
    for n in song.notes:
        assert n.onset_s < n.offset_s <= song.duration_s
        assert midi.PIANO_LOWEST <= n.pitch <= midi.PIANO_HIGHEST
