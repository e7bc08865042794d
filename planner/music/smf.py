"""Reading a Standard MIDI File's bytes without trusting them: the RIFF wrapper, the
chunks, the size and event budgets, runs of bytes no MIDI event holds, each track parsed
by mido within the budget (``planner.music.midi`` turns the events into notes). Its
steps, in the order the reader takes them: ``unwrap_riff``, ``split_chunks``,
``check_high_bit_runs``, ``parse_tracks``; ``limit_text`` and ``one_line`` word the
errors."""

from __future__ import annotations

import io
import struct

import mido

from planner.errors import InputError

MAX_FILE_BYTES = 16 * 1024 * 1024
MAX_NOTES = 200_000
MAX_EVENTS = 1_000_000
MAX_DURATION_S = 24 * 3600
# A variable-length quantity is at most 4 bytes; a long run of bytes with the
# high bit set can only be garbage, and mido would spend quadratic time on it.
_MAX_HIGH_BIT_RUN = 16_384


def limit_text() -> str:
    """The file size limit, as a message says it."""
    return f"{MAX_FILE_BYTES // (1024 * 1024)} MiB"


def one_line(exc: BaseException) -> str:
    """An exception's text on one line of at most 200 characters (its type without text)."""
    text = " ".join(str(exc).split())
    if not text:
        text = type(exc).__name__
    return text[:200]


def unwrap_riff(data: bytes, source: str) -> bytes:
    """RIFF-wrapped MIDI (.rmi): return the SMF inside the 'data' chunk."""
    if data[:4] != b"RIFF":
        return data
    if data[8:12] != b"RMID":
        raise InputError(f"{source}: RIFF file that is not RIFF MIDI (RMID)")
    pos = 12
    while pos + 8 <= len(data):
        cid = data[pos : pos + 4]
        (clen,) = struct.unpack("<L", data[pos + 4 : pos + 8])
        if cid == b"data":
            return data[pos + 8 : pos + 8 + clen]
        pos += 8 + clen + (clen & 1)
    raise InputError(f"{source}: RIFF MIDI file without a 'data' chunk")


def split_chunks(data: bytes, source: str) -> tuple[int, int, int, list[bytes]]:
    """Check the header and cut the MTrk chunks out of ``data``."""
    if data[:4] != b"MThd":
        raise InputError(f"{source}: not a MIDI file (no 'MThd' header)")
    if len(data) < 14:
        raise InputError(f"{source}: truncated MIDI header")
    hlen, fmt, ntracks, division = struct.unpack(">LHHH", data[4:14])
    if hlen < 6 or 8 + hlen > len(data):
        raise InputError(f"{source}: corrupt MIDI header (header length {hlen})")
    if fmt == 2:
        raise InputError(f"{source}: type 2 (asynchronous) MIDI files are not supported")
    if fmt not in (0, 1):
        raise InputError(f"{source}: unknown MIDI file format {fmt} (expected 0 or 1)")
    if division & 0x8000:
        raise InputError(
            f"{source}: SMPTE time division (frames per second) is not supported; "
            "save the file with a ticks-per-beat (PPQ) division"
        )
    if division == 0:
        raise InputError(f"{source}: invalid time division of 0 ticks per beat")
    if ntracks == 0:
        raise InputError(f"{source}: the file contains no tracks")

    chunks: list[bytes] = []
    pos = 8 + hlen
    while len(chunks) < ntracks:
        if len(data) - pos < 8:
            raise InputError(
                f"{source}: the header declares {ntracks} track(s) but only "
                f"{len(chunks)} are present (truncated file?)"
            )
        cid = data[pos : pos + 4]
        (clen,) = struct.unpack(">L", data[pos + 4 : pos + 8])
        if cid == b"MTrk":
            if pos + 8 + clen > len(data):
                raise InputError(
                    f"{source}: track {len(chunks)} claims {clen} bytes but only "
                    f"{len(data) - pos - 8} remain (truncated file?)"
                )
            chunks.append(data[pos : pos + 8 + clen])
        elif not all(32 <= b < 127 for b in cid):
            raise InputError(
                f"{source}: corrupt MIDI file: no track chunk at byte offset {pos}"
            )
        # else: an unknown chunk type, which the standard says to skip
        pos += 8 + clen
    return fmt, ntracks, division, chunks


def check_high_bit_runs(data: bytes, source: str) -> None:
    if len(data) <= _MAX_HIGH_BIT_RUN:
        return
    run = max(map(len, data.translate(_HIGH_BIT_TABLE).split(b"\x00")))
    if run > _MAX_HIGH_BIT_RUN:
        raise InputError(
            f"{source}: corrupt MIDI data ({run} consecutive bytes with the high bit set)"
        )


# maps bytes < 0x80 to 0 and bytes >= 0x80 to 1, so split(b"\0") gives the runs
_HIGH_BIT_TABLE = bytes(0 if b < 0x80 else 1 for b in range(256))


class _EventBudgetExceeded(Exception):
    pass


class _BudgetReader(io.BytesIO):
    """BytesIO that stops mido after ``budget`` events.

    mido's track reader calls ``tell()`` once per event; counting those calls
    bounds the work (and memory) spent on a hostile file. If a mido version
    stops doing that, the guard simply never fires.
    """

    def __init__(self, data: bytes, budget: int) -> None:
        super().__init__(data)
        self._budget = budget

    def tell(self) -> int:
        self._budget -= 1
        if self._budget < 0:
            raise _EventBudgetExceeded
        return super().tell()


def parse_tracks(chunks: list[bytes], tpb: int, source: str) -> list[list]:
    """Tokenise each MTrk chunk with mido; return lists of messages (delta ticks)."""
    tracks: list[list] = []
    events = 0
    notes = 0
    for i, chunk in enumerate(chunks):
        mini = b"MThd" + struct.pack(">LHHH", 6, 0, 1, tpb) + chunk
        reader = _BudgetReader(mini, MAX_EVENTS - events + 2)
        try:
            mf = mido.MidiFile(file=reader)
        except _EventBudgetExceeded:
            raise InputError(
                f"{source}: more than {MAX_EVENTS:,} MIDI events; refusing the file"
            ) from None
        except EOFError:
            raise InputError(
                f"{source}: track {i} ends in the middle of an event (truncated or corrupt file)"
            ) from None
        except Exception as exc:  # noqa: BLE001 -- mido raises many types on garbage
            raise InputError(
                f"{source}: corrupt MIDI data in track {i} ({one_line(exc)})"
            ) from None
        msgs = list(mf.tracks[0]) if mf.tracks else []
        events += len(msgs)
        notes += sum(1 for m in msgs if m.type == "note_on" and m.velocity > 0)
        if notes > MAX_NOTES:
            raise InputError(f"{source}: more than {MAX_NOTES:,} notes; refusing the file")
        tracks.append(msgs)
    return tracks
