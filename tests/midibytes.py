"""MIDI files built byte by byte for the tests (no test here).

Two ways: raw chunks and events (``header``, ``mtrk``, ``smf`` of (tick, message) tracks,
``notes_track``, ``events_track``: any byte sequence, valid or not), and mido messages
written by mido (``on``, ``off``, ``tempo``, ``cc``, ``mido_smf``: a valid file); and what
``parse_song_bytes`` made of one (``times``, ``assert_input_error``).
"""

from __future__ import annotations

import io
import struct

import mido
import pytest

from planner.errors import InputError
from planner.music.midi import Song, parse_song_bytes

END = b"\x00\xff\x2f\x00"  # delta 0, end_of_track


# ---------------------------------------------------------------- raw bytes


def vlq(n: int) -> bytes:
    out = [n & 0x7F]
    n >>= 7
    while n:
        out.append(0x80 | (n & 0x7F))
        n >>= 7
    return bytes(reversed(out))


def header(fmt: int = 1, ntracks: int = 1, division: int = 480, hlen: int = 6) -> bytes:
    return b"MThd" + struct.pack(">LHHH", hlen, fmt, ntracks, division) + b"\0" * (hlen - 6)


def mtrk(body: bytes) -> bytes:
    return b"MTrk" + struct.pack(">L", len(body)) + body


def tempo_msg(us: int) -> bytes:
    return b"\xff\x51\x03" + us.to_bytes(3, "big")


def on_msg(pitch: int, vel: int, ch: int = 0) -> bytes:
    return bytes([0x90 | ch, pitch, vel])


def off_msg(pitch: int, ch: int = 0) -> bytes:
    return bytes([0x80 | ch, pitch, 0])


def track_bytes(events: list[tuple[int, bytes]]) -> bytes:
    """(absolute tick, message) -> an MTrk chunk (stable order at one tick)."""
    body, now = b"", 0
    for tick, msg in sorted(events, key=lambda e: e[0]):
        body += vlq(tick - now) + msg
        now = tick
    return mtrk(body + END)


def smf(*tracks: list[tuple[int, bytes]], fmt: int = 1, division: int = 480) -> bytes:
    return header(fmt, len(tracks), division) + b"".join(track_bytes(t) for t in tracks)


def notes_track(notes, tempos=((0, 500_000),)) -> list[tuple[int, bytes]]:
    """notes: (pitch, on_tick, off_tick, velocity[, channel]); offs sort before ons at a tick."""
    ev = [(t, tempo_msg(us)) for t, us in tempos]
    offs, ons = [], []
    for n in notes:
        p, a, b, v = n[:4]
        ch = n[4] if len(n) > 4 else 0
        ons.append((a, on_msg(p, v, ch)))
        offs.append((b, off_msg(p, ch)))
    return ev + sorted(offs, key=lambda e: e[0]) + sorted(ons, key=lambda e: e[0])


def events_track(evs) -> bytes:
    """An MTrk chunk at 120 bpm of (delta ticks, "on" | "off" | "on0", pitch, velocity,
    channel) events ("on0": a note_on of velocity 0)."""
    body = tempo_msg(500_000)
    body = b"\x00" + body
    for delta, kind, p, v, ch in evs:
        msg = on_msg(p, v, ch) if kind == "on" else on_msg(p, 0, ch) if kind == "on0" \
            else off_msg(p, ch)
        body += vlq(delta) + msg
    return mtrk(body + END)


def chunks(data: bytes) -> list[tuple[int, int]]:
    """(offset of the length field, length) of every chunk after the header."""
    out, pos = [], 8 + struct.unpack(">L", data[4:8])[0]
    while pos + 8 <= len(data):
        (n,) = struct.unpack(">L", data[pos + 4:pos + 8])
        out.append((pos + 4, n))
        pos += 8 + n
    return out


# ---------------------------------------------------------------- mido messages


def on(note, time=0, velocity=64, channel=0):
    return mido.Message("note_on", note=note, velocity=velocity, channel=channel, time=time)


def off(note, time=0, channel=0, velocity=0, kind="note_off"):
    return mido.Message(kind, note=note, velocity=velocity, channel=channel, time=time)


def tempo(us, time=0):
    return mido.MetaMessage("set_tempo", tempo=us, time=time)


def cc(control, value, time=0, channel=0):
    return mido.Message(
        "control_change", control=control, value=value, channel=channel, time=time
    )


def mido_smf(*tracks, type=1, tpb=480) -> bytes:
    """A file of mido message tracks, written by mido."""
    mf = mido.MidiFile(type=type, ticks_per_beat=tpb)
    for msgs in tracks:
        mf.tracks.append(mido.MidiTrack(msgs))
    buf = io.BytesIO()
    mf.save(file=buf)
    return buf.getvalue()


# ---------------------------------------------------------------- what the parser made of them


def times(song: Song) -> list[tuple[int, float, float]]:
    return [(n.pitch, n.onset_s, n.offset_s) for n in song.notes]


def assert_input_error(data: bytes, *words: str, **kw) -> str:
    """``parse_song_bytes(data, **kw)`` refuses the file in one line naming ``words``."""
    with pytest.raises(InputError) as info:
        parse_song_bytes(data, **kw)
    msg = str(info.value)
    assert "\n" not in msg
    for w in words:
        assert w in msg, msg
    return msg
