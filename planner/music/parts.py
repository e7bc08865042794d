"""Which part of a MIDI file one right hand plays, when the caller names none.

A file often holds several parts: a melody track and a bass track, a right hand on one
channel and a left hand on another, or both hands in one track. One hand cannot play
them all, and the notes it cannot play are better the lower ones: the right hand of a
pianist plays the upper part. So, with neither ``track`` nor ``channel`` given:

* Parts are the (track, channel) pairs that hold notes (drums excluded). With more than
  one, the part whose notes lie highest (the largest median pitch; then more notes; then
  the lower track and channel) is played, the others left out.
* The chosen part (or the only one) is then tested for two hands in one part: its
  pitches fall into two clusters (the best split of the sorted pitches into a lower and
  an upper group, 1-D two-means), each struck at ``SPLIT_MIN_ONSETS`` times or more,
  whose medians are at least ``SPLIT_MIN_SEMITONES`` apart, and at least ``SPLIT_MIN_TOGETHER`` of the lower group's notes sound while an
  upper note sounds (two hands play at once; one hand's leaps do not). Then only the
  notes at or above the split pitch are played.

``choose_part`` says what it chose and why (``PartChoice.reason``), which the play
summary and ``play --json`` print. A caller that names ``track`` or ``channel`` gets
exactly that part: this module is not asked.
"""

from __future__ import annotations

from bisect import bisect_left
from collections.abc import Callable
from dataclasses import dataclass
from itertools import accumulate
from statistics import median

SPLIT_MIN_SEMITONES = 12  # two clusters' medians at least an octave apart
SPLIT_MIN_TOGETHER = 0.5  # and half of the lower notes sounding with an upper one
SPLIT_MIN_ONSETS = 4  # times struck, each group (a wide chord is one hand's problem, not two)


@dataclass(frozen=True)
class PartInfo:
    """One (track, channel) part of a file: its note count and pitches (MIDI numbers)."""

    track: int
    channel: int
    notes: int
    median_pitch: float
    lowest_pitch: int
    highest_pitch: int

    def to_dict(self) -> dict:
        return {"track": self.track, "channel": self.channel, "notes": self.notes,
                "median_pitch": self.median_pitch, "lowest_pitch": self.lowest_pitch,
                "highest_pitch": self.highest_pitch}


@dataclass(frozen=True)
class PartChoice:
    """The part played: ``track`` and ``channel`` (None: every one), ``split_pitch``
    (only notes at or above it; None: no split), ``reason`` (a sentence), and every part
    of the file (``parts``)."""

    track: int | None
    channel: int | None
    split_pitch: int | None
    reason: str
    parts: tuple[PartInfo, ...]

    def keeps(self, pitch: int, channel: int, track: int) -> bool:
        """Whether a note of this pitch, channel and track is played."""
        return ((self.track is None or track == self.track)
                and (self.channel is None or channel == self.channel)
                and (self.split_pitch is None or pitch >= self.split_pitch))

    def to_dict(self) -> dict:
        return {"track": self.track, "channel": self.channel, "split_pitch": self.split_pitch,
                "reason": self.reason, "parts": [p.to_dict() for p in self.parts]}


def choose_part(raw, name: Callable[[int], str] = str) -> PartChoice | None:
    """The upper part of ``raw`` notes, tuples ``(pitch, on_tick, off_tick, velocity,
    channel, track)`` (drums already out); None when the whole is one hand's part.
    ``name(pitch)`` names a pitch in the reason (``planner.music.midi.pitch_name``)."""
    groups: dict[tuple[int, int], list] = {}
    for note in raw:
        groups.setdefault((note[5], note[4]), []).append(note)
    parts = tuple(sorted((_info(t, c, ns) for (t, c), ns in groups.items()),
                         key=lambda p: (p.track, p.channel)))
    if not parts:
        return None
    best = max(parts, key=lambda p: (p.median_pitch, p.notes, -p.track, -p.channel))
    chosen = groups[(best.track, best.channel)]
    split = two_hands_split(chosen)
    where = f"track {best.track}, channel {best.channel}"
    if len(parts) > 1:
        others = ", ".join(f"track {p.track} channel {p.channel} (median {p.median_pitch:g})"
                           for p in parts if p is not best)
        reason = (f"{where} of {len(parts)} parts: its notes lie highest (median MIDI "
                  f"{best.median_pitch:g}, against {others}); the right hand plays the "
                  "upper part")
        track, channel = best.track, best.channel
    elif split is None:
        return None
    else:
        reason, track, channel = f"{where}, the only part", None, None
    if split is not None:
        upper = sum(1 for n in chosen if n[0] >= split)
        reason += (f"; it holds two hands' notes (two pitch groups sounding together): "
                   f"the {upper} notes from {name(split)} (MIDI {split}) up are played, the "
                   f"{len(chosen) - upper} below left out")
    reason += "; --track/--channel choose another part"
    return PartChoice(track, channel, split, reason, parts)


def _info(track: int, channel: int, notes: list) -> PartInfo:
    pitches = [n[0] for n in notes]
    return PartInfo(track, channel, len(notes), float(median(pitches)), min(pitches),
                    max(pitches))


def two_hands_split(notes) -> int | None:
    """The split pitch of a part (tuples as ``choose_part``'s) that holds two hands'
    notes, or None (module docstring). O(n log n)."""
    pitches = sorted(n[0] for n in notes)
    if len(pitches) < 4 or pitches[-1] - pitches[0] < SPLIT_MIN_SEMITONES:
        return None
    cut = _two_means_cut(pitches)
    if cut is None or median(pitches[cut:]) - median(pitches[:cut]) < SPLIT_MIN_SEMITONES:
        return None
    split = pitches[cut]
    if min(len({n[1] for n in notes if n[0] < split}),
           len({n[1] for n in notes if n[0] >= split})) < SPLIT_MIN_ONSETS:
        return None
    upper = sorted((n[1], n[2]) for n in notes if n[0] >= split)
    onsets = [u[0] for u in upper]
    reach = list(accumulate((u[1] for u in upper), max))  # latest end among the first k
    lower = [n for n in notes if n[0] < split]
    together = 0
    for n in lower:  # an upper note sounds with it: one starts before its end, ends after
        k = bisect_left(onsets, n[2])
        together += k > 0 and reach[k - 1] > n[1]
    return split if together >= SPLIT_MIN_TOGETHER * len(lower) else None


def _two_means_cut(pitches: list[int]) -> int | None:
    """The index that splits sorted ``pitches`` into two groups of least summed squared
    spread (prefix sums), at a change of pitch; None when every pitch is one."""
    s1 = [0, *accumulate(pitches)]
    s2 = [0, *accumulate(p * p for p in pitches)]
    n = len(pitches)

    def spread(a: int, b: int) -> float:
        return s2[b] - s2[a] - (s1[b] - s1[a]) ** 2 / (b - a)

    cuts = [i for i in range(1, n) if pitches[i] != pitches[i - 1]]
    return min(cuts, key=lambda i: spread(0, i) + spread(i, n)) if cuts else None
