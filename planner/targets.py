"""Notes + fingering -> press intervals: which finger holds which key, when.

A note's press interval is its [onset, offset), except:

- a key struck again within ``RELEASE_S`` of its release is released
  ``RELEASE_S`` before the new onset (a piano key must come up to sound
  again); the first press keeps at least half its length;
- a finger that must move to another key is freed ``MOVE_S`` before its
  next onset, likewise;
- a note the fingering lets go early (``Assignment.release_s``: later notes
  need its finger, or the hand where it cannot hold the key) ends then.

MIDI velocity maps to press force (N) and key speed: ``force_n = 0.5 +
2.5 (v/127)^2`` (0.5 N is a real key's weight, 3 N a forte press on this
hand) and a descent time of ``60 - 35 v/127`` ms over the 30 mm from travel
height to full dip (key speed 0.5 to 1.2 m/s); play.py scales it to the
actual descent.
"""

from __future__ import annotations

from dataclasses import dataclass

RELEASE_S = 0.040
MOVE_S = 0.060
MIN_FORCE_N = 0.5
MAX_FORCE_N = 3.0


def press_force_n(velocity: int) -> float:
    """Press force (N) for a MIDI velocity 0..127."""
    v = min(max(velocity, 0), 127) / 127.0
    return MIN_FORCE_N + (MAX_FORCE_N - MIN_FORCE_N) * v * v


def descent_time_s(velocity: int) -> float:
    """Time (s) to go from travel height to full dip for a MIDI velocity."""
    v = min(max(velocity, 0), 127) / 127.0
    return 0.060 - 0.035 * v


@dataclass(frozen=True)
class Press:
    finger: str
    pitch: int
    force_n: float
    note_index: int
    velocity: int


@dataclass(frozen=True)
class PressInterval:
    start_s: float
    end_s: float
    press: Press


def press_intervals(notes, assignments) -> list[PressInterval]:
    """Press intervals per assigned note, shortened where a key or finger must be freed."""
    by_note = {a.note_index: a for a in assignments}
    items = []
    for i, a in sorted(by_note.items()):
        n = notes[i]
        end = n.offset_s if a.release_s is None else min(n.offset_s, a.release_s)
        items.append([n.onset_s, end, Press(a.finger, n.pitch, press_force_n(n.velocity), i, n.velocity)])
    # same key struck again, same finger moving on: free it in time
    for key_fn, gap in ((lambda p: ("key", p.pitch), RELEASE_S), (lambda p: ("finger", p.finger), MOVE_S)):
        last: dict = {}
        for it in sorted(items, key=lambda x: (x[0], x[2].pitch)):
            k = key_fn(it[2])
            prev = last.get(k)
            if prev is not None and prev[1] > it[0] - gap:
                prev[1] = max(prev[0] + 0.5 * (it[0] - prev[0]), it[0] - gap)
                prev[1] = min(prev[1], it[0])
            last[k] = it
    return [PressInterval(s, e, p) for s, e, p in sorted(items, key=lambda x: (x[0], x[2].pitch))
            if e > s]
