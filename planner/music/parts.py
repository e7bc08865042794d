"""Which part of a MIDI file one right hand plays, when the caller names none.

A file often holds several parts: a melody track and a bass track, a right hand on one
channel and a left hand on another, or both hands in one track. One hand cannot play
them all, and the notes it cannot play are better the lower ones: the right hand of a
pianist plays the upper part. So, with neither ``track`` nor ``channel`` given:

* Parts are the (track, channel) pairs that hold notes (drums excluded). The part whose
  notes lie highest (the largest median pitch) is played, with every part whose median
  is less than ``SPLIT_MIN_SEMITONES`` below it (one hand's line spread over channels or
  tracks, a doubling); the parts an octave or more lower (a bass, a left hand) are left
  out.
* The notes kept are then tested for two hands in one part: their pitches fall into two
  clusters (the best split of the sorted pitches into a lower and an upper group, 1-D
  two-means), each struck at ``SPLIT_MIN_ONSETS`` times or more, whose medians are at
  least ``SPLIT_MIN_SEMITONES`` apart, and at least ``SPLIT_MIN_TOGETHER`` of the lower
  group's notes sound while an upper note sounds (two hands play at once; one hand's
  leaps do not). Then only the notes at or above the split pitch are played.

``choose_part`` says what it chose and why (``PartChoice.reason``), which the play
summary, ``play --json`` and the plan's metadata give. A caller that names ``track`` or
``channel`` gets exactly that part: this module is not asked. The choice is a function
of the file alone, so every reader of a plan (``check``, ``simulate``) reads the same
notes.
"""

from __future__ import annotations

from bisect import bisect_left
from dataclasses import dataclass
from itertools import accumulate
from statistics import median

from planner.music.keyboard import pitch_name

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
    """The part played: the (track, channel) pairs kept (``played``), ``split_pitch``
    (only notes at or above it; None: no split), ``reason`` (a sentence), and every part
    of the file (``parts``). ``track``/``channel``: the one track (channel) of every part
    kept, or None when they are several."""

    played: tuple[tuple[int, int], ...]
    split_pitch: int | None
    reason: str
    parts: tuple[PartInfo, ...]

    @property
    def track(self) -> int | None:
        tracks = {t for t, _ in self.played}
        return next(iter(tracks)) if len(tracks) == 1 else None

    @property
    def channel(self) -> int | None:
        channels = {c for _, c in self.played}
        return next(iter(channels)) if len(channels) == 1 else None

    def keeps(self, pitch: int, channel: int, track: int) -> bool:
        """Whether a note of this pitch, channel and track is played."""
        return ((track, channel) in self.played
                and (self.split_pitch is None or pitch >= self.split_pitch))

    def to_dict(self) -> dict:
        return {"track": self.track, "channel": self.channel,
                "played": [list(p) for p in self.played], "split_pitch": self.split_pitch,
                "reason": self.reason, "parts": [p.to_dict() for p in self.parts]}


def choose_part(raw) -> PartChoice | None:
    """The upper part of ``raw`` notes, tuples ``(pitch, on_tick, off_tick, velocity,
    channel, track)`` (drums already out); None when the whole is one hand's part."""
    groups: dict[tuple[int, int], list] = {}
    for note in raw:
        groups.setdefault((note[5], note[4]), []).append(note)
    parts = tuple(sorted((_info(t, c, ns) for (t, c), ns in groups.items()),
                         key=lambda p: (p.track, p.channel)))
    if not parts:
        return None
    top = max(p.median_pitch for p in parts)
    kept = [p for p in parts if p.median_pitch > top - SPLIT_MIN_SEMITONES]
    notes = [n for p in kept for n in groups[(p.track, p.channel)]]
    split = two_hands_split(notes)
    if len(kept) == len(parts) and split is None:
        return None
    reasons = []
    if len(kept) < len(parts):
        reasons.append(
            f"the upper part, {_listed(kept)}, its notes highest; left out, an octave or "
            f"more lower: {_listed([p for p in parts if p not in kept])}")
    if split is not None:
        upper = sum(1 for n in notes if n[0] >= split)
        reasons.append(
            f"{'it' if reasons else _listed(kept)} holds two hands' notes (two pitch groups "
            f"sounding together): the {upper} notes from {pitch_name(split)} (MIDI {split}) up "
            f"are played, the {len(notes) - upper} below left out")
    reason = "; ".join(reasons) + "; --track/--channel choose another part"
    return PartChoice(tuple((p.track, p.channel) for p in kept), split, reason, parts)


def _listed(parts) -> str:
    return ", ".join(f"track {p.track} channel {p.channel} ({p.notes} notes, median MIDI "
                     f"{p.median_pitch:g})" for p in parts)


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
