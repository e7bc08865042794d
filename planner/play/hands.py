"""Which hand plays each note of a song played by two hands (``play --hands 2``).

**The hint.** The file's parts say which hand a note is written for: with two parts or
more (``(track, channel)`` pairs), the parts sorted by their median pitch and cut at the
widest gap between neighbours, the lower ones the left hand's; one part that holds two
hands' notes (``planner.music.parts.two_hands_split``) is cut at its split pitch; one
part that does not (a melody) is the right hand's, as one hand plays it.

**Not a law.** The notes are weighed one by one in onset order (of one onset, the left
part's from the lowest up, then the right part's from the highest down), each hand's cost in frames of music (the currency of frame F1 and of the one-hand
planner's programme, ``planner.play.costs``), and the note goes to the cheaper hand:

* a hand whose notes sounding with it would not fit its span (the lowest and highest key
  its fingers press from one rail position, ``HandGap``'s ``HandReach``) loses the note:
  all its frames;
* so does a hand that would cross the other: two notes sounding at once are played by
  two hands only with the left one at least ``HandGap.key_gap_m`` below the right one
  (the carriages' clearance, ``planner.play.handgap``);
* a hand that must move its rail to reach the note loses the frames its move takes
  beyond the time since its last note struck (the arm's time-optimal move,
  ``Places.arm_time_s``; the hand's notes so far placed at its span's middle);
* the hand the note is not written for pays ``hint_frames``: the frames of the rail's
  move by one white key (the hand's smallest move), so that a note changes hands only
  when its own hand would lose more than its smallest move takes.

Ties go to the written hand. The result is a ``HandAssignment`` (frozen): the hand of
every note, the hand it was written for, and each note moved, with its reason.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

from planner.music import keyboard as kb
from planner.music.parts import two_hands_split
from planner.play.costs import RECENT_S
from planner.play.handgap import HandGap
from planner.play.places import RAIL_STEP_M, Places

LEFT, RIGHT = "left", "right"
SIDES = (LEFT, RIGHT)


def other_side(side: str) -> str:
    """The other hand's side."""
    return RIGHT if side == LEFT else LEFT


class HintSource(enum.Enum):
    """How the file's parts gave the hint."""

    PARTS = "parts"  # two parts or more: the lower ones the left hand's
    SPLIT = "split"  # one part holding two hands' notes, cut at its split pitch
    MELODY = "melody"  # one part of one hand: the right hand's


class MoveReason(enum.Enum):
    """Why a note is played by the hand it is not written for."""

    SPAN = "span"  # its hand's notes sounding with it would not fit the hand's span
    CROSSING = "crossing"  # its hand would come within the clearance of the other
    TIME = "time"  # its hand cannot move there in time; the other loses fewer frames
    ONE_HAND = "one_hand"  # one hand playing every note played more frames than two
    LEFT_OUT = "left_out"  # the hand planned first left it out; the other, planned after
    # within the first one's rows, is given it; or the hand planned second left it out and
    # the first, planned again within the second one's rows, is (``planner.play.twohands``)


@dataclass(frozen=True)
class Moved:
    """A note given to the other hand: its index, the reason, the frames each hand would
    lose (``cost_frames``: left, right) and a sentence."""

    note: int
    reason: MoveReason
    cost_frames: tuple[float, float]
    detail: str


@dataclass(frozen=True)
class HandAssignment:
    """Per note of the song (its order), the hand that plays it (``hand``) and the one its
    part gives (``hint``); ``moved``: the notes whose hand differs; ``source``: how the
    hint was read; ``split_pitch``: the pitch a one-part file was cut at (None)."""

    hand: tuple[str, ...]
    hint: tuple[str, ...]
    moved: tuple[Moved, ...]
    source: HintSource
    split_pitch: int | None = None

    def notes_of(self, side: str) -> tuple[int, ...]:
        """The indices of the notes ``side`` plays, in the song's order."""
        return tuple(i for i, h in enumerate(self.hand) if h == side)

    def one_hand(self, side: str = RIGHT) -> HandAssignment:
        """Every note ``side``'s (the other hand rests): a note its part gives the other
        hand is moved (``MoveReason.ONE_HAND``)."""
        return HandAssignment(
            tuple(side for _ in self.hand), self.hint,
            tuple(Moved(i, MoveReason.ONE_HAND, (0.0, 0.0), f"the {side} hand plays every "
                        "note: one hand played more frames of music than two")
                  for i, h in enumerate(self.hint) if h != side),
            self.source, self.split_pitch)

    def hand_over(self, notes: dict[int, str], to: str) -> HandAssignment:
        """These notes (song index: a sentence why their hand left them out) given to
        ``to`` (``MoveReason.LEFT_OUT``); a note moved before keeps its first reason, one
        given back to its part's hand is moved no more."""
        hand = list(self.hand)
        moved = {m.note: m for m in self.moved}
        for i, why in notes.items():
            hand[i] = to
            if to == self.hint[i]:
                moved.pop(i, None)
            elif i not in moved:
                moved[i] = Moved(i, MoveReason.LEFT_OUT, (0.0, 0.0),
                                 f"the {self.hand[i]} hand left it out: {why}")
        return HandAssignment(tuple(hand), self.hint, tuple(moved[i] for i in sorted(moved)),
                              self.source, self.split_pitch)


def hint_hands(notes) -> tuple[tuple[str, ...], HintSource, int | None]:
    """The hand each note is written for (module docstring), how, and a split pitch."""
    parts: dict[tuple[int, int], list[int]] = {}
    for n in notes:
        parts.setdefault((n.track, n.channel), []).append(n.pitch)
    if len(parts) >= 2:
        med = sorted((sorted(p)[len(p) // 2], key) for key, p in parts.items())
        cut = max(range(1, len(med)), key=lambda i: (med[i][0] - med[i - 1][0], -i))
        lower = {key for _, key in med[:cut]}
        return (tuple(LEFT if (n.track, n.channel) in lower else RIGHT for n in notes),
                HintSource.PARTS, None)
    split = two_hands_split([(n.pitch, n.onset_s, n.offset_s) for n in notes])
    if split is not None:
        return tuple(LEFT if n.pitch < split else RIGHT for n in notes), HintSource.SPLIT, split
    return tuple(RIGHT for _ in notes), HintSource.MELODY, None


@dataclass
class _HandState:
    """What the weighing knows of one hand: its notes (index, x, offset) still sounding,
    where it last played (the middle of its span then, m) and when."""

    sounding: list[tuple[int, float, float]]
    centre_m: float | None = None
    last_onset_s: float = -math.inf


class _Weigher:
    """The frames each hand would lose on a note (module docstring)."""

    def __init__(self, gap: HandGap, places: dict[str, Places], rate_hz: float) -> None:
        self.gap, self.places, self.dt = gap, places, 1.0 / rate_hz
        self.reach = {LEFT: gap.left, RIGHT: gap.right}
        self.span = {s: r.key_hi_m - r.key_lo_m for s, r in self.reach.items()}
        steps = max(1, round(kb.WHITE_PITCH_M / RAIL_STEP_M))
        self.hint_frames = places[RIGHT].arm_time_s(0, steps) / self.dt

    def move_s(self, side: str, distance_m: float) -> float:
        steps = math.ceil(distance_m / RAIL_STEP_M - 1e-9)
        return self.places[side].arm_time_s(0, steps) if steps > 0 else 0.0

    def cost(self, side: str, x: float, n, frames: float, states: dict[str, _HandState]
             ) -> tuple[float, MoveReason | None, str]:
        """(frames lost, the reason when it is all the note's, a sentence)."""
        st, other = states[side], states[RIGHT if side == LEFT else LEFT]
        xs = [x] + [sx for _, sx, end in st.sounding if end > n.onset_s + 1e-9]
        if max(xs) - min(xs) > self.span[side]:
            return frames, MoveReason.SPAN, (f"with the {side} hand's notes sounding it spans "
                                             f"{max(xs) - min(xs):.3f} m, more than its "
                                             f"{self.span[side]:.3f} m")
        g = self.gap.key_gap_m
        for _, ox, _ in other.sounding:
            if (side == LEFT and ox - x < g) or (side == RIGHT and x - ox < g):
                return frames, MoveReason.CROSSING, (
                    f"a note of the other hand sounds {abs(ox - x):.3f} m away; two hands "
                    f"need {g:.3f} m between their keys")
        if st.centre_m is None:
            return 0.0, None, ""
        far = max(0.0, abs(x - st.centre_m) - self.span[side] / 2)
        late = max(0.0, self.move_s(side, far) - (n.onset_s - st.last_onset_s)) / self.dt
        return min(frames, late), MoveReason.TIME, (f"its hand is {far:.3f} m from it, "
                                                   f"{late:.1f} frames late")


def assign_hands(notes, gap: HandGap, places: dict[str, Places],
                 rate_hz: float = 100.0) -> HandAssignment:
    """Each note's hand (module docstring): ``notes`` in the song's order (onset, pitch);
    ``places``: each side's hand positions (``Places``), for the times of its moves."""
    hint, source, split = hint_hands(notes)
    w = _Weigher(gap, places, rate_hz)
    states = {s: _HandState([]) for s in SIDES}
    out: list[str] = [RIGHT] * len(notes)
    moved: list[Moved] = []
    for i in _weighing_order(notes, hint):
        n = notes[i]
        for st in states.values():  # (the notes over by this onset, and RECENT_S
            # before it, leave: the hand is still where they were)
            st.sounding = [s for s in st.sounding if s[2] + RECENT_S > n.onset_s + 1e-9]
        x = kb.key(n.pitch).center_x_m
        frames = max(1.0, n.duration_s / w.dt)
        got = {s: w.cost(s, x, n, frames, states) for s in SIDES}
        own, alt = hint[i], RIGHT if hint[i] == LEFT else LEFT
        side = alt if got[alt][0] + w.hint_frames < got[own][0] else own
        if side != own:
            moved.append(Moved(i, got[own][1] or MoveReason.TIME,
                               (got[LEFT][0], got[RIGHT][0]),
                               f"the {own} hand: {got[own][2]}"))
        st = states[side]
        st.sounding.append((i, x, n.offset_s))
        xs = [sx for _, sx, end in st.sounding if end > n.onset_s + 1e-9]
        st.centre_m = (max(xs) + min(xs)) / 2
        st.last_onset_s = n.onset_s
        out[i] = side
    return HandAssignment(tuple(out), hint, tuple(sorted(moved, key=lambda m: m.note)),
                          source, split)


def _weighing_order(notes, hint: tuple[str, ...]) -> list[int]:
    """The notes in onset order; of one onset, the left part's from the lowest up, then
    the right part's from the highest down (each hand's chord from its outer side in)."""
    return sorted(range(len(notes)), key=lambda i: (
        notes[i].onset_s, hint[i] == RIGHT, -notes[i].pitch if hint[i] == RIGHT
        else notes[i].pitch))
