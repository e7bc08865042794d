"""What the room the hand planned first takes from the other hand's notes costs, in frames
of music (two hands: ``planner.play.twohands``; the fingering's currency,
``planner.play.costs``).

**Why.** The hand planned first keeps hard bounds only for the notes the other hand is
given (``planner.play.twobounds.room``). The notes it leaves out of its own part are
handed to the other hand after it is planned; the other hand plays them only where the
first hand's bodies leave it room (``clear_bounds``). Leaving a note out costs the first
hand's programme its frames, blocking it afterwards cost nothing: a long dive of the arm
that plays one more chord could stand over a run of notes it had handed over, each lost
to both hands (the two-hand corpus's ``clara_polonaise1_3``: 498 -> 155 frames of
handed notes played, ``docs/history/2026-12-07-two-hands5.md``).

**The charge.** Each note the other hand plays or may be handed (every note of the first
hand's part the other hand can press) claims, over the time it sounds, the rail beyond
the least the other hand must reach to press it (``planner.play.handclear.least_reach_m``)
and the clearance. A state of the first hand's programme whose inner edge (its rail less,
a right hand, or plus, a left one, its places' own reach: ``PlaceReach`` of the notes it
holds; the hand's farthest reach where it holds none) lies inside a claim pays the frames
of the claim that overlap the state's time (from its event to the next one): the other
hand's notes all of them, a note of its own the ``share`` of them the other hand plays of
what it is handed where it has the room (measured: ``twobounds.HANDED_SHARE``). Leaving
such a note out costs the rest of its frames (``left_out``): left out and blocked, all
its frames, as one hand pays; left out with the room left, less. (Charging the room on
top of the whole note priced a note left out twice where the hand stood over it, and
tipped the programme into notes its estimates play but the motion cannot: measured on
``schoenberg_op19_6``.) A note of its own the hand played (holds, or its fingers last
struck) is not handed over and claims nothing. One hand alone is planned with no
``RoomCost``: nothing changes.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from planner.play.costs import ONSET_TOL_S, State
from planner.play.hands import RIGHT


@dataclass(frozen=True)
class RoomClaim:
    """A note's claim on the rail (song time ``t0_s``..``t1_s``, when it sounds): the
    first hand's inner edge must stay beyond ``edge_m`` (a right hand at or above it, a
    left one at or below). ``own``: the note's position in the first hand's notes (its
    own part, handed over when it leaves it out), -1 for the other hand's note."""

    t0_s: float
    t1_s: float
    edge_m: float
    own: int = -1


class RoomCost:
    """The room charge of one hand planned first (module docstring): ``at(t_s)`` sets the
    event (its state lasts to the next of the hand's onsets, ``onsets_s``, later than
    ``ONSET_TOL_S``: the programme's next event), ``frames(place, sounding)`` is a
    state's charge at it. ``pitch``: the first hand's notes' pitches; ``reach_m(finger, pitch, place)``: a place's own reach towards
    the other hand (``PlaceReach.reach_m``; inf: not known, the farthest taken);
    ``farthest_m``: the hand's farthest reach; ``rail_m(place)``: the place's rail."""

    def __init__(self, claims: Sequence[RoomClaim], side: str, onsets_s: Sequence[float],
                 pitch: Sequence[int],
                 reach_m: Callable[[str, int, int], float], farthest_m: float,
                 rail_m: Callable[[int], float], rate_hz: float, share: float = 1.0) -> None:
        self.claims = sorted(claims, key=lambda c: (c.t0_s, c.t1_s, c.edge_m, c.own))
        self._starts = [c.t0_s for c in self.claims]
        self.onsets_s = sorted(onsets_s)
        self.right = side == RIGHT
        self.pitch, self.reach_m, self.farthest_m = pitch, reach_m, farthest_m
        self.rail_m, self.rate_hz = rail_m, rate_hz
        self._now: list[tuple[float, float, int]] = []  # (frames, edge, own) at the event
        self.share = share
        self.handed = frozenset(c.own for c in self.claims if c.own >= 0)
        self._owns: tuple[int, ...] = ()  # (the hand's own notes claiming at the event)
        self._memo: dict[tuple, float] = {}

    def at(self, t_s: float) -> None:
        """The event at ``t_s`` (its state lasts to the next event's time; inf for the
        last): the claims overlapping it, with the frames they overlap."""
        k = bisect.bisect_right(self.onsets_s, t_s + ONSET_TOL_S)
        next_s = self.onsets_s[k] if k < len(self.onsets_s) else math.inf
        end = bisect.bisect_left(self._starts, next_s)
        self._now = [((min(c.t1_s, next_s) - max(c.t0_s, t_s)) * self.rate_hz, c.edge_m, c.own)
                     for c in self.claims[:end] if c.t1_s > t_s]
        self._now = [x for x in self._now if x[0] > 0.0 and math.isfinite(x[0])]
        self._owns = tuple(sorted({own for _, _, own in self._now if own >= 0}))
        self._memo = {}

    def left_out(self, note: int, frames: float) -> float:
        """What leaving ``note`` (a position in the hand's notes, sounding ``frames``) out
        costs: a note the other hand can press is handed over, and played there (the
        share ``share``) where the hand leaves it the room: that share is paid by the room
        it takes (``frames``), the rest here; any other note all its frames."""
        return frames * (1.0 - self.share) if note in self.handed else frames

    def frames(self, place: int, sounding: Sequence[tuple[int, str]],
               before: State | None = None) -> float:
        """The frames the state at ``place`` holding ``sounding`` ((note, finger): its
        notes, positions in the first hand's notes) blocks at the event (``at``), coming
        from ``before`` (the state of the event before; None: the first): the other
        hand's notes' whole, the hand's own (handed over) their ``share``; a note of the
        hand's own that it played (``sounding`` holds it, or ``before`` holds it or its
        fingers last struck it: ``State.fingers``, ``recent``, ``older``) is not handed
        over and claims nothing."""
        if not self._now:
            return 0.0
        owns: tuple = ()
        if self._owns:
            done = {m for m, _ in sounding}
            if before is not None:
                done.update(m for m, _ in before.fingers)
                done.update(m for m, _, _ in before.recent)
                done.update(m for m, _, _ in before.older)
            owns = tuple(j for j in self._owns if j not in done)
        key = (place, tuple(sounding), owns)
        got = self._memo.get(key)
        if got is None:
            edge = self._edge(place, sounding)
            got = self._memo[key] = sum(fr if own < 0 else fr * self.share
                                        for fr, e, own in self._now
                                        if (own < 0 or own in owns) and self._blocks(edge, e))
        return got

    def _edge(self, place: int, sounding: Sequence[tuple[int, str]]) -> float:
        """The inner edge of the hand at ``place`` holding ``sounding`` (m)."""
        key = ("edge", place, tuple(sounding))
        got = self._memo.get(key)
        if got is None:
            reach = max((self.reach_m(f, self.pitch[m], place) for m, f in sounding),
                        default=self.farthest_m)
            if not math.isfinite(reach):
                reach = self.farthest_m
            rail = self.rail_m(place)
            got = self._memo[key] = rail - reach if self.right else rail + reach
        return got

    def _blocks(self, edge_m: float, claim_m: float) -> bool:
        return edge_m < claim_m if self.right else edge_m > claim_m
