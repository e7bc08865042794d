"""Write the sample songs in this folder, note by note.

Run from the repository root::

    python songs/make_songs.py

Every melody is public domain (see README.md). The files are written with
``planner.music.midi.write_notes_midi`` and their bytes are deterministic:
running the script again rewrites identical files.

Timing rule: every note sounds for 90 % of its slot (the leaps: half of it,
detached), so there is always a gap before the next note; when the next
note repeats the pitch the gap is at least 60 ms (the key must come up
before it can be struck again).

``stress/`` holds songs beyond this hand (see README.md there): the planner
must still plan them, name what it cannot play and stay within every limit.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
TPB = 480  # ticks per quarter note
REPEAT_GAP_S = 0.060

# MIDI pitches: C4 = 60 (middle C)
C3, D3, E3, G3 = 48, 50, 52, 55
B3, C4, D4, E4, F4, G4, GS4, A4, B4 = 59, 60, 62, 64, 65, 67, 68, 69, 71
C5, D5, DS5, E5, F5, G5, C6 = 72, 74, 75, 76, 77, 79, 84

Q, H, E8, S16 = 1.0, 2.0, 0.5, 0.25  # beats (quarter note = 1)
DQ = 1.5


def tempo_us(bpm: float) -> int:
    return round(60_000_000 / bpm)


def melody(events: list[tuple[object, float]], bpm: float, sound: float = 0.9
           ) -> list[tuple[int, float, float]]:
    """(pitch(es) or None for a rest, beats) -> (pitch, onset_s, offset_s).

    A pitch may be a tuple for a chord. Each note sounds ``sound`` of its slot;
    if the next slot repeats one of its pitches the gap is at least 60 ms.
    Times are whole ticks of the file that main() writes, so the file holds
    exactly these times.
    """
    tick_s = tempo_us(bpm) / 1e6 / TPB
    repeat_gap = math.ceil(REPEAT_GAP_S / tick_s)
    out = []
    tick = 0
    for k, (pitches, beats) in enumerate(events):
        slot = round(beats * TPB)
        if pitches is not None:
            group = pitches if isinstance(pitches, tuple) else (pitches,)
            nxt = events[k + 1][0] if k + 1 < len(events) else None
            nxt_group = nxt if isinstance(nxt, tuple) else (nxt,)
            for p in group:
                length = math.floor(sound * slot + 1e-9)
                if p in nxt_group:
                    length = min(length, slot - repeat_gap)
                out.append((p, tick * tick_s, (tick + length) * tick_s))
        tick += slot
    return out


def scale() -> tuple[list, float]:
    up = [C4, D4, E4, F4, G4, A4, B4, C5]
    return melody([(p, Q) for p in up + up[-2::-1]], 100), 100


def twinkle() -> tuple[list, float]:
    # "Twinkle, Twinkle, Little Star" (French "Ah ! vous dirai-je, maman", 1761)
    ph1 = [(C4, Q), (C4, Q), (G4, Q), (G4, Q), (A4, Q), (A4, Q), (G4, H)]
    ph2 = [(F4, Q), (F4, Q), (E4, Q), (E4, Q), (D4, Q), (D4, Q), (C4, H)]
    return melody(ph1 + ph2, 100), 100


def ode_to_joy() -> tuple[list, float]:
    # Beethoven, Symphony No. 9, 4th movement, theme (16 bars), in C major
    a = [(E4, Q), (E4, Q), (F4, Q), (G4, Q), (G4, Q), (F4, Q), (E4, Q), (D4, Q),
         (C4, Q), (C4, Q), (D4, Q), (E4, Q)]
    end1 = [(E4, DQ), (D4, E8), (D4, H)]
    end2 = [(D4, DQ), (C4, E8), (C4, H)]
    bridge = [(D4, Q), (D4, Q), (E4, Q), (C4, Q),
              (D4, Q), (E4, E8), (F4, E8), (E4, Q), (C4, Q),
              (D4, Q), (E4, E8), (F4, E8), (E4, Q), (D4, Q),
              (C4, Q), (D4, Q), (G3, H)]
    return melody(a + end1 + a + end2 + bridge + a + end2, 120), 120


def fur_elise() -> tuple[list, float]:
    # Beethoven, Bagatelle WoO 59 "Fur Elise", right hand, pickup to the C5 of bar 4 (3/8)
    ev = [(E5, S16), (DS5, S16),
          (E5, S16), (DS5, S16), (E5, S16), (B4, S16), (D5, S16), (C5, S16),
          (A4, E8), (None, S16), (C4, S16), (E4, S16), (A4, S16),
          (B4, E8), (None, S16), (E4, S16), (GS4, S16), (B4, S16),
          (C5, E8)]
    return melody(ev, 70), 70


def chords() -> tuple[list, float]:
    # I - vi - IV - V7 - I - ii7 - V7 - I in C, close position, half notes
    prog = [(C4, E4, G4), (C4, E4, A4), (C4, F4, A4), (B3, D4, F4, G4),
            (C4, E4, G4, C5), (D4, F4, A4, C5), (B3, D4, F4, G4), (C4, E4, G4, C5)]
    return melody([(c, H) for c in prog], 100), 100


def fast() -> tuple[list, float]:
    # sixteenth-note runs at 132 bpm (8.8 notes per second), each within five keys, the
    # hand moving on to the next five (C4..G4, D4..A4, C4..G4) in an eighth-note rest
    on_c = [C4, D4, E4, F4, G4, F4, E4, D4, C4, D4, E4, F4, G4, F4]
    on_d = [D4, E4, F4, G4, A4, G4, F4, E4, D4, E4, F4, G4, A4, G4]
    back = [C4, D4, E4, F4, G4, F4, E4, D4, C4, D4, E4, F4, E4, D4]
    ev = ([(p, S16) for p in on_c] + [(None, E8)] + [(p, S16) for p in on_d] + [(None, E8)]
          + [(p, S16) for p in back] + [(C4, Q)])
    return melody(ev, 132), 132


def leaps() -> tuple[list, float]:
    # leaps of two octaves and more (C3 <-> E5 is 28 semitones), 0.6 s per note, each
    # note detached (half its slot): the hand crosses the keyboard in the other half
    seq = [C3, E5, C3, E5, D3, F5, E3, G5, C3, C6, G3, C5]
    return melody([(p, Q) for p in seq], 100, sound=0.5), 100


def fast_six_keys() -> tuple[list, float]:
    # (stress) sixteenth-note runs over six keys, C4..A4, at 132 bpm, without a rest:
    # five fingers that do not cross cannot hold six keys, and no finger of this hand
    # moves to another key in the 11 ms between two notes
    run = [C4, D4, E4, F4, G4, F4, E4, D4,
           C4, D4, E4, F4, G4, A4, G4, F4,
           E4, F4, G4, A4, G4, F4, E4, D4,
           C4, D4, E4, F4, E4, D4, C4, D4]
    return melody([(p, S16) for p in run] + [(C4, Q)], 132), 132


def leaps_legato() -> tuple[list, float]:
    # (stress) the leaps held for 90 % of their slot: 60 ms for the hand to cross up to
    # three octaves, which the rail alone cannot do
    seq = [C3, E5, C3, E5, D3, F5, E3, G5, C3, C6, G3, C5]
    return melody([(p, Q) for p in seq], 100), 100


SONGS = {
    "scale.mid": scale,
    "twinkle.mid": twinkle,
    "ode_to_joy.mid": ode_to_joy,
    "fur_elise.mid": fur_elise,
    "chords.mid": chords,
    "fast.mid": fast,
    "leaps.mid": leaps,
    "stress/fast_six_keys.mid": fast_six_keys,
    "stress/leaps_legato.mid": leaps_legato,
}


def main() -> int:
    sys.path.insert(0, str(HERE.parent))
    from planner.music.midi import Note, write_notes_midi

    for name, make in SONGS.items():
        triples, bpm = make()
        notes = [Note(p, on, off, 80) for p, on, off in triples]
        (HERE / name).parent.mkdir(exist_ok=True)
        write_notes_midi(notes, HERE / name, ticks_per_beat=TPB, tempo_us=tempo_us(bpm))
        end = max(off for _, _, off in triples)
        print(f"{name:16s} {len(notes):3d} notes  {end:6.2f} s  {bpm:g} bpm")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
