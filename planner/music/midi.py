"""MIDI file -> notes (the only module on the music side that imports mido).

``load_song(path)`` / ``parse_song_bytes(data)`` turn a Standard MIDI File
(format 0 or 1) into a :class:`Song`: a sorted tuple of :class:`Note` in
seconds, the sustain-pedal intervals and the file's duration.
``write_notes_midi`` writes notes back out (used to record what a plan played).

How a file is read (the choices are deliberate; tests pin them down):

* Times. mido only tokenises the tracks; seconds are computed here from
  the tempo map, with exact integer arithmetic and one rounding at the end.
  ``set_tempo`` events may sit in any track (format 1) and apply to every
  track from their tick on; before the first one the tempo is 120 bpm.
  A tempo of 0 us/beat is refused. The 24-bit ``set_tempo`` field limits
  tempi to >= 3.58 bpm (16,777,215 us/beat); anything up to that and far
  beyond 1000 bpm works.
* Note ends. ``note_off`` and ``note_on`` with velocity 0 end a note. Notes
  are paired per (track, channel, pitch).
* A second ``note_on`` of a sounding (track, channel, pitch) ends the
  sounding note at the new onset and starts a new note (a piano key cannot
  be struck twice without being released). The next ``note_off`` ends the
  new note -- except a ``note_off`` at the very tick of such a re-strike,
  which is taken to be the (late-written) release of the old note, so that
  "on, on, off" written at one tick does not lose the second note.
  Unmatched ``note_off`` events are ignored.
* Notes still sounding at the end of the file end at the end of the file
  (the last event of any track).
* Zero-length notes (on and off at the same tick) are dropped: a key that
  is never down does not sound.
* Channel 10 (index 9, General MIDI drums) is ignored. Channels are 0-based
  (0..15) everywhere in this module.
* Sustain pedal (CC64; value >= 64 is down) of the selected part is
  reported as intervals in ``Song.sustain`` (the union over channels); it
  does not lengthen notes.
* A part is chosen with ``track=`` (index of the MTrk chunk, 0-based) and/or
  ``channel=``. Without either, a file of several parts (tracks or channels), or of
  two hands in one, gives its upper part, the right hand's (``planner.music.parts``:
  ``Song.part`` says which and why); a file of one part gives every note.
  ``every_part=True`` (two hands: ``play --hands 2``) reads every part, none chosen.
  Channel 9 (drums) is never read.
* After selection (and transposition) the notes are merged: if two notes of
  the same pitch overlap (from different tracks or channels, or moved onto
  one pitch by ``transpose``), the earlier one ends at the later one's onset;
  two notes of one pitch starting together become one note (the longer end,
  the louder velocity).
* Piano range is 21 (A0)..108 (C8). Out-of-range notes are an InputError
  unless ``transpose=True``, which moves each such note by whole octaves to
  the nearest octave inside the range.
* Notes are sorted by (onset, pitch); the order is deterministic.

Every failure is an :class:`~planner.errors.InputError` with a one-line
message that starts with the file name. Hostile inputs are bounded: files
larger than 16 MiB, more than 200,000 notes, more than 1,000,000 events or
lasting more than 24 hours are refused.
"""

from __future__ import annotations

import dataclasses
import io
import os
from bisect import bisect_right
from collections.abc import Iterable
from dataclasses import dataclass

import mido

from planner.errors import InputError
from planner.music.keyboard import pitch_name
from planner.music.parts import PartChoice, choose_part
from planner.music.smf import (
    MAX_DURATION_S,
    MAX_EVENTS,
    MAX_FILE_BYTES,
    MAX_NOTES,
    check_high_bit_runs,
    limit_text,
    one_line,
    parse_tracks,
    split_chunks,
    unwrap_riff,
)

__all__ = [
    "DRUM_CHANNEL",
    "MAX_DURATION_S",
    "MAX_EVENTS",
    "MAX_FILE_BYTES",
    "MAX_NOTES",
    "PIANO_HIGHEST",
    "PIANO_LOWEST",
    "Note",
    "Song",
    "load_song",
    "parse_song_bytes",
    "pitch_name",
    "write_notes_midi",
]

PIANO_LOWEST = 21  # A0
PIANO_HIGHEST = 108  # C8
DRUM_CHANNEL = 9  # "channel 10" in 1-based numbering


_DEFAULT_TEMPO_US = 500_000


@dataclass(frozen=True)
class Note:
    """One note: MIDI pitch, onset and offset in seconds (onset < offset)."""

    pitch: int
    onset_s: float
    offset_s: float
    velocity: int
    channel: int = 0
    track: int = 0

    @property
    def duration_s(self) -> float:
        return self.offset_s - self.onset_s


@dataclass(frozen=True)
class Song:
    """A parsed song.

    ``notes`` sorted by (onset, pitch); ``duration_s`` the time of the last
    event in the file (>= every offset); ``sustain`` the (start, end) seconds
    of the pedal-down intervals, sorted and disjoint; ``source`` the file name
    (``"<bytes>"`` when parsed from memory).
    """

    notes: tuple[Note, ...]
    duration_s: float
    sustain: tuple[tuple[float, float], ...] = ()
    source: str = ""
    track: int | None = None  # the options it was read with (a plan's metadata names them)
    channel: int | None = None
    transpose: bool = False
    part: PartChoice | None = None  # the part chosen when neither track nor channel was
    every_part: bool = False  # read with ``every_part`` (both hands' parts, none chosen)


SHIFT_DIGITS = 12  # a shifted note's times are rounded to 1 ps (``shift_notes``)


def shift_notes(notes, shift_s: float) -> list[Note]:
    """The notes ``shift_s`` later (a plan's file time: ``song_start_s``), each time
    rounded to ``SHIFT_DIGITS`` decimals, so that a sum that is a row's time in exact
    arithmetic is that row's time as the file's decimals give it (5.4 + 0.12 is
    5.5200000000000005 in floats, after row 5.52): the planner and every reader shift
    the song by this one function and agree on the frames each note covers."""
    if shift_s == 0.0:
        return list(notes)
    return [dataclasses.replace(n, onset_s=round(n.onset_s + shift_s, SHIFT_DIGITS),
                                offset_s=round(n.offset_s + shift_s, SHIFT_DIGITS))
            for n in notes]


# --------------------------------------------------------------------------
# Reading


def load_song(
    path: str | os.PathLike[str],
    *,
    track: int | None = None,
    channel: int | None = None,
    transpose: bool = False,
    every_part: bool = False,
) -> Song:
    """Read a MIDI file into a :class:`Song` (see the module docstring; ``every_part``:
    every part of the file, none chosen, as two hands play it)."""
    name = os.fspath(path)
    try:
        size = os.path.getsize(name)
        if size > MAX_FILE_BYTES:
            raise InputError(f"{name}: file is {size} bytes; the limit is {limit_text()}")
        with open(name, "rb") as fh:
            data = fh.read(MAX_FILE_BYTES + 1)
    except InputError:
        raise
    except FileNotFoundError:
        raise InputError(f"{name}: file not found") from None
    except IsADirectoryError:
        raise InputError(f"{name}: is a directory, not a MIDI file") from None
    except PermissionError:
        raise InputError(f"{name}: permission denied") from None
    except OSError as exc:
        raise InputError(f"{name}: cannot read file ({one_line(exc)})") from None
    return parse_song_bytes(
        data, track=track, channel=channel, transpose=transpose, source=name,
        every_part=every_part,
    )


def parse_song_bytes(
    data: bytes,
    *,
    track: int | None = None,
    channel: int | None = None,
    transpose: bool = False,
    source: str = "<bytes>",
    every_part: bool = False,
) -> Song:
    """Parse the bytes of a MIDI file into a :class:`Song` (see the module docstring)."""
    data = bytes(data)
    if not data:
        raise InputError(f"{source}: empty file")
    if len(data) > MAX_FILE_BYTES:
        raise InputError(f"{source}: file is {len(data)} bytes; the limit is {limit_text()}")
    data = unwrap_riff(data, source)
    _fmt, ntracks, tpb, chunks = split_chunks(data, source)
    _check_selection(track, channel, ntracks, source)
    check_high_bit_runs(data, source)
    tracks = parse_tracks(chunks, tpb, source)
    tempo_map = _TempoMap(tracks, tpb, source)

    end_tick = max((sum(m.time for m in t) for t in tracks), default=0)
    if tempo_map.us_ticks(end_tick) > MAX_DURATION_S * 1_000_000 * tpb:
        raise InputError(
            f"{source}: the file lasts more than {MAX_DURATION_S // 3600} hours; refusing it"
        )

    raw, sustain, found = _collect(tracks, end_tick, track, channel)
    if not raw:
        raise InputError(f"{source}: {_no_notes_text(track, channel, found)}")
    part = choose_part(raw) if track is None and channel is None and not every_part else None
    if part is not None:  # several parts, or two hands in one: the upper one
        if part.track is not None:
            raw, sustain, _ = _collect(tracks, end_tick, part.track, part.channel)
        raw = [r for r in raw if part.keeps(r[0], r[4], r[5])]

    notes = sorted(
        (
            Note(p, tempo_map.seconds(on), tempo_map.seconds(off), vel, ch, ti)
            for (p, on, off, vel, ch, ti) in raw
        ),
        key=_sort_key,
    )
    notes = _fit_range(notes, transpose, source)
    notes = _merge_same_pitch(notes)
    if not notes:  # every note vanished in float rounding: pathological timing
        raise InputError(f"{source}: no notes of non-zero length")

    sustain_s = _merge_intervals(
        (tempo_map.seconds(a), tempo_map.seconds(b)) for (a, b) in sustain
    )
    return Song(
        notes=tuple(notes),
        duration_s=tempo_map.seconds(end_tick),
        sustain=tuple(sustain_s),
        source=source,
        track=track,
        channel=channel,
        transpose=bool(transpose),
        part=part,
        every_part=bool(every_part),
    )


def _check_selection(track: int | None, channel: int | None, ntracks: int, source: str) -> None:
    if track is not None and not (0 <= track < ntracks):
        raise InputError(
            f"{source}: track {track} does not exist; valid tracks are 0..{ntracks - 1}"
        )
    if channel is not None:
        if not (0 <= channel <= 15):
            raise InputError(
                f"{source}: channel {channel} is invalid; valid channels are 0..15 (0-based)"
            )
        if channel == DRUM_CHANNEL:
            raise InputError(
                f"{source}: channel 9 (MIDI channel 10) is the drum channel and is ignored; "
                "valid channels are 0..8 and 10..15"
            )


class _TempoMap:
    """Ticks -> seconds through every set_tempo of every track."""

    def __init__(self, tracks: list[list], tpb: int, source: str) -> None:
        changes: list[tuple[int, int, int, int]] = []  # (tick, track, index, tempo)
        for ti, msgs in enumerate(tracks):
            tick = 0
            for k, m in enumerate(msgs):
                tick += m.time
                if m.type == "set_tempo":
                    if m.tempo <= 0:
                        raise InputError(
                            f"{source}: invalid tempo of {m.tempo} us per beat "
                            f"in track {ti} at tick {tick}"
                        )
                    changes.append((tick, ti, k, m.tempo))
        changes.sort()
        self._tpb = tpb
        self._ticks: list[int] = [0]
        self._tempo: list[int] = [_DEFAULT_TEMPO_US]
        self._acc: list[int] = [0]  # us * tpb elapsed at self._ticks[i]
        for tick, _, _, tempo in changes:
            if tick == self._ticks[-1]:
                self._tempo[-1] = tempo  # the later event at one tick wins
                continue
            self._acc.append(self._acc[-1] + (tick - self._ticks[-1]) * self._tempo[-1])
            self._ticks.append(tick)
            self._tempo.append(tempo)

    def us_ticks(self, tick: int) -> int:
        """Elapsed time at ``tick`` in microseconds times ticks-per-beat (exact)."""
        i = bisect_right(self._ticks, tick) - 1
        return self._acc[i] + (tick - self._ticks[i]) * self._tempo[i]

    def seconds(self, tick: int) -> float:
        return self.us_ticks(tick) / (self._tpb * 1_000_000)


def _collect(
    tracks: list[list],
    end_tick: int,
    want_track: int | None,
    want_channel: int | None,
) -> tuple[list[tuple[int, int, int, int, int, int]], list[tuple[int, int]], dict]:
    """Pair note events into (pitch, on_tick, off_tick, velocity, channel, track).

    Also returns the pedal-down intervals in ticks of the selected part and
    ``found``: (track, channel) -> number of notes, over the whole file, for
    error messages.
    """
    raw: list[tuple[int, int, int, int, int, int]] = []
    pedal: list[tuple[int, int]] = []
    found: dict[tuple[int, int], int] = {}
    for ti, msgs in enumerate(tracks):
        selected_track = want_track is None or want_track == ti
        sounding: dict[tuple[int, int], tuple[int, int]] = {}  # key -> (on_tick, velocity)
        restruck: dict[tuple[int, int], tuple[int, int]] = {}  # key -> (tick, owed offs)
        pedal_down: dict[int, int] = {}  # channel -> tick pressed
        tick = 0
        for m in msgs:
            tick += m.time
            mtype = m.type
            if mtype not in ("note_on", "note_off", "control_change"):
                continue
            ch = m.channel
            if ch == DRUM_CHANNEL:
                if mtype == "note_on" and m.velocity > 0:
                    found[(ti, ch)] = found.get((ti, ch), 0) + 1
                continue
            selected = selected_track and (want_channel is None or want_channel == ch)
            if mtype == "control_change":
                if m.control != 64 or not selected:
                    continue
                if m.value >= 64:
                    pedal_down.setdefault(ch, tick)
                elif ch in pedal_down:
                    start = pedal_down.pop(ch)
                    if tick > start:
                        pedal.append((start, tick))
                continue
            key = (ch, m.note)
            if mtype == "note_on" and m.velocity > 0:
                found[(ti, ch)] = found.get((ti, ch), 0) + 1
                if key in sounding:  # re-strike: end the sounding note here
                    on, vel = sounding[key]
                    if selected and tick > on:
                        raw.append((m.note, on, tick, vel, ch, ti))
                    owed = restruck.get(key)
                    count = owed[1] + 1 if owed is not None and owed[0] == tick else 1
                    restruck[key] = (tick, count)
                sounding[key] = (tick, m.velocity)
                continue
            # note_off, or note_on with velocity 0
            owed = restruck.get(key)
            if owed is not None:
                if owed[0] == tick and owed[1] > 0:
                    # the late release of the note that was re-struck at this tick
                    restruck[key] = (tick, owed[1] - 1)
                    continue
                del restruck[key]
            if key in sounding:
                on, vel = sounding.pop(key)
                if selected and tick > on:
                    raw.append((m.note, on, tick, vel, ch, ti))
        if selected_track:
            for (ch, pitch), (on, vel) in sounding.items():
                if (want_channel is None or want_channel == ch) and end_tick > on:
                    raw.append((pitch, on, end_tick, vel, ch, ti))
            for start in pedal_down.values():
                if end_tick > start:
                    pedal.append((start, end_tick))
    return raw, pedal, found


def _no_notes_text(track: int | None, channel: int | None, found: dict) -> str:
    where = []
    if track is not None:
        where.append(f"in track {track}")
    if channel is not None:
        where.append(f"on channel {channel}")
    else:
        where.append("on channel(s) 0..15 except drum channel 9")
    chosen = sum(n for (t, c), n in found.items()
                 if (track is None or t == track)
                 and (c == channel if channel is not None else c != DRUM_CHANNEL))
    if chosen:  # (notes there, every one of them ends on the tick it starts)
        return (f"all {chosen} notes " + " ".join(where) + " are of zero length (note on and "
                "off at the same tick): nothing to play")
    text = "no notes " + " ".join(where)
    if found:
        parts = sorted(found)
        listed = ", ".join(
            f"track {t} channel {c}" + (" (drums, ignored)" if c == DRUM_CHANNEL else "")
            for t, c in parts[:8]
        )
        if len(parts) > 8:
            listed += ", ..."
        text += f"; notes exist in: {listed}"
    return text


def _sort_key(n: Note) -> tuple:
    return (n.onset_s, n.pitch, n.offset_s, n.channel, n.track, n.velocity)


def _fit_range(notes: list[Note], transpose: bool, source: str) -> list[Note]:
    out = []
    for n in notes:
        p = n.pitch
        if PIANO_LOWEST <= p <= PIANO_HIGHEST:
            out.append(n)
            continue
        if not transpose:
            raise InputError(
                f"{source}: note {p} ({pitch_name(p)}) at {n.onset_s:.3f} s is outside the "
                f"piano range {PIANO_LOWEST} (A0)..{PIANO_HIGHEST} (C8); "
                "use --transpose to move such notes by octaves"
            )
        if p < PIANO_LOWEST:
            p += 12 * -((p - PIANO_LOWEST) // 12)
        else:
            p -= 12 * -((PIANO_HIGHEST - p) // 12)
        out.append(Note(p, n.onset_s, n.offset_s, n.velocity, n.channel, n.track))
    if transpose:
        out.sort(key=_sort_key)
    return out


def _merge_same_pitch(notes: list[Note]) -> list[Note]:
    """Make notes of one pitch disjoint (input sorted by _sort_key)."""
    out: list[Note | None] = []
    last: dict[int, int] = {}  # pitch -> index in out
    for n in notes:
        i = last.get(n.pitch)
        prev = out[i] if i is not None else None
        if prev is not None and n.onset_s < prev.offset_s:
            if n.onset_s == prev.onset_s:  # struck together: one note
                out[i] = Note(
                    prev.pitch,
                    prev.onset_s,
                    max(prev.offset_s, n.offset_s),
                    max(prev.velocity, n.velocity),
                    prev.channel,
                    prev.track,
                )
                continue
            out[i] = Note(prev.pitch, prev.onset_s, n.onset_s, prev.velocity, prev.channel,
                          prev.track)
        if n.offset_s > n.onset_s:
            last[n.pitch] = len(out)
            out.append(n)
    return [n for n in out if n is not None]


def _merge_intervals(intervals: Iterable[tuple[float, float]]) -> list[tuple[float, float]]:
    merged: list[tuple[float, float]] = []
    for a, b in sorted(intervals):
        if merged and a <= merged[-1][1]:
            merged[-1] = (merged[-1][0], max(merged[-1][1], b))
        else:
            merged.append((a, b))
    return merged


# --------------------------------------------------------------------------
# Writing


def write_notes_midi(
    notes: Iterable[Note],
    path: str | os.PathLike[str],
    ticks_per_beat: int = 480,
    tempo_us: int = 500000,
) -> None:
    """Write ``notes`` to a type-1 MIDI file at one constant tempo.

    Track 0 holds the tempo, track 1 every note on its own channel (so the
    notes read back with ``track == 1``). Times are rounded to the nearest
    tick (tempo_us / ticks_per_beat microseconds; 1.04 ms at the defaults,
    so a round trip through :func:`load_song` is exact to 0.53 ms). A note
    shorter than one tick is written one tick long; a note that overlaps the
    next note of the same pitch and channel is ended at that note's onset.
    Invalid notes or parameters raise InputError.
    """
    if not (1 <= ticks_per_beat <= 0x7FFF):
        raise InputError(f"ticks_per_beat must be 1..32767, not {ticks_per_beat}")
    if not (1 <= tempo_us <= 0xFFFFFF):
        raise InputError(f"tempo_us must be 1..16777215, not {tempo_us}")
    notes = list(notes)
    scale = ticks_per_beat * 1_000_000 / tempo_us  # ticks per second
    timed: list[tuple[int, int, int, int, int]] = []  # (on, off, channel, pitch, velocity)
    for n in notes:
        if not (0 <= n.pitch <= 127):
            raise InputError(f"cannot write note pitch {n.pitch} (MIDI pitches are 0..127)")
        if not (1 <= n.velocity <= 127):
            raise InputError(f"cannot write note velocity {n.velocity} (must be 1..127)")
        if not (0 <= n.channel <= 15):
            raise InputError(f"cannot write note channel {n.channel} (must be 0..15)")
        if not (0 <= n.onset_s < n.offset_s) or n.offset_s == float("inf"):
            raise InputError(
                f"cannot write note {n.pitch} with onset {n.onset_s} s and offset {n.offset_s} s"
            )
        on = round(n.onset_s * scale)
        off = max(round(n.offset_s * scale), on + 1)
        timed.append((on, off, n.channel, n.pitch, n.velocity))
    timed.sort()

    # same pitch and channel must not overlap: end the earlier at the later onset
    by_key: dict[tuple[int, int], int] = {}
    for i, (on, off, ch, p, vel) in enumerate(timed):
        j = by_key.get((ch, p))
        if j is not None and timed[j][1] > on:
            pon, _, pch, pp, pvel = timed[j]
            timed[j] = (pon, on, pch, pp, pvel)
        by_key[(ch, p)] = i

    events: list[tuple[int, int, int, int, int]] = []  # (tick, kind 0=off 1=on, ch, pitch, vel)
    for on, off, ch, p, vel in timed:
        if off <= on:  # two notes struck together on one key: keep the first
            continue
        events.append((on, 1, ch, p, vel))
        events.append((off, 0, ch, p, 0))
    events.sort()

    mf = mido.MidiFile(type=1, ticks_per_beat=ticks_per_beat)
    conductor = mido.MidiTrack()
    conductor.append(mido.MetaMessage("set_tempo", tempo=tempo_us, time=0))
    conductor.append(mido.MetaMessage("end_of_track", time=0))
    part = mido.MidiTrack()
    now = 0
    for tick, kind, ch, p, vel in events:
        msg_type = "note_on" if kind else "note_off"
        part.append(mido.Message(msg_type, channel=ch, note=p, velocity=vel, time=tick - now))
        now = tick
    part.append(mido.MetaMessage("end_of_track", time=0))
    mf.tracks.append(conductor)
    mf.tracks.append(part)
    buf = io.BytesIO()
    mf.save(file=buf)
    from planner.output import write_file

    write_file(path, buf.getvalue())
