"""Two hands on one rail (``play --hands 2``): a song's notes given to the left and the
right hand, both planned so that they never come within their clearance, one file.

**The stages.** ``planner.play.hands`` gives each note a hand (the file's parts a
strong hint, weighed in frames of music). One hand is planned first by the one-hand
planner (``plan_song``), each of its notes pressed only from rail positions that leave
the other hand room for its own notes sounding then (``room_bounds``); then the other
hand, each of its notes pressed only from rail positions that keep its bodies, at their
farthest reach (``planner.play.handgap``), the clearance from the first hand's bodies as
they *are* at every row over the note's window (``clear_bounds``: the first hand's
inner edge, ``InnerEdge``, read from its rows). A note whose every place breaks its
bound is left out (``SkipReason.OTHER_HAND``), never played into the other hand. The
notes the first hand leaves out are handed to the second (``HandAssignment.hand_over``),
planned with its own notes within the first one's rows: it plays them where it is free.
Where the farthest-reach rule leaves the second hand's notes out, the second hand is
planned again on the reach of the places that press each note, confirmed on both hands'
rows by the check's judge (``planner.play.handclear``). Which hand goes first, or whether
one hand plays alone (the other taking only what it leaves out), is decided by the
frames of music each way plays (``plan_two_hands``); the way kept is then planned once
more with the notes its second hand left out handed back to the first (``hand_back``).

**Why the rails stay apart between the notes too.** A note's window runs from its hand's
previous onset to its hand's next onset (and half of the next notes' length, the latest a
note is still struck: ``planner.play.motion.DROP_FRACTION``): the arm moves to a note's
place after the notes before it are struck and leaves it for the next ones, one straight,
monotone move, so its rail lies between two places each within the bound over the move's
time. The first note's window starts before the way in, the last note's lasts to the end
of the file. Each hand rests at its end of the rail (the left hand at the lowest rail
position of its travel, the right at the highest: ``REST_RAIL_M`` is where one hand
rests), so the way in and the way out move each carriage away from the other or towards
a place within its bound.

**One clock.** The two hands' plans are made apart; each starts its song when its way
in allows (``song_start_s``). The one that starts the song sooner waits at rest for the
difference (rows of its rest pose, every speed zero), and the shorter plan holds its last
row (rest) to the end, so both hands' rows are on one clock with one ``song_start_s``.
"""

from __future__ import annotations

import bisect
import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import NamedTuple

import numpy as np

from planner.errors import InputError
from planner.hand.model import HandModel
from planner.music import keyboard as kb
from planner.music.midi import Song
from planner.play.costs import CostMemo, Costs, SkipReason
from planner.play.handclear import (
    MAX_ROUNDS,
    NoteReaches,
    PlaceReach,
    collided_notes,
    least_reach_m,
    loose_bound,
)
from planner.play.handgap import HandGap, HandReach, InnerEdge, hand_gap
from planner.play.hands import LEFT, RIGHT, SIDES, HandAssignment, assign_hands
from planner.play.motion import DROP_FRACTION
from planner.play.places import Places
from planner.play.stream import ROW_BLOCK, Planner, PlayPlan, plan_song

UNBOUNDED_M = 10.0  # a bound no rail reaches (the travel is a few metres at most)


class PairPlanner:
    """The per-pair part of the two-hand planner, built once: each hand's ``Planner``
    (resting at its end of the rail) and the pair's ``HandGap``."""

    def __init__(self, left: HandModel, right: HandModel) -> None:
        if left.side != LEFT or right.side != RIGHT:
            raise InputError(f"two hands are a left hand then a right one; got {left.name} "
                             f"({left.side}), {right.name} ({right.side})")
        self.hands = {LEFT: left, RIGHT: right}
        rl, rr = left.index.get("rail"), right.index.get("rail")
        if rl is None or rr is None:
            raise InputError("two hands share one rail: each hand needs a rail axis "
                             f"({left.name}, {right.name})")
        self.planners = {LEFT: Planner(left, rest_rail_m=float(left.plan_lower[rl])),
                         RIGHT: Planner(right, rest_rail_m=float(right.plan_upper[rr]))}
        for pl in self.planners.values():  # (the idle fingers tucked in: the hands nearer)
            pl.places.idle.narrow()
        self.gap: HandGap = hand_gap(self.planners[LEFT].places, self.planners[RIGHT].places)
        self.edges = {s: InnerEdge(h) for s, h in self.hands.items()}
        # (each place's own reach towards the other hand: the second hand's loosened rule)
        self.place_reach = {s: PlaceReach(self.planners[s].places, self.edges[s])
                            for s in SIDES}

    def reach(self, side: str) -> HandReach:
        """``side``'s ``HandReach`` (of the pair's ``HandGap``)."""
        return self.gap.left if side == LEFT else self.gap.right


@dataclass(frozen=True)
class PairRows:
    """Both hands' rows on one clock: times ``t_s`` (from 0 at the rate), each hand's
    joints (``q``: left, right) and the common ``song_start_s``."""

    t_s: np.ndarray
    q: tuple[np.ndarray, np.ndarray]
    song_start_s: float


@dataclass(frozen=True)
class TwoHandPlan:
    """What ``plan_two_hands`` did: the assignment, each hand's one-hand plan (in memory,
    ``plans``, left then right), each hand's notes as indices of the song (``notes_of``:
    the hand each note was last planned on), the rows on one clock, and the clock after
    set-up. ``planned_of``: each plan's song as indices of the song (None: ``notes_of``);
    the hand planned first's holds the notes it left out and handed over too."""

    assignment: HandAssignment
    gap: HandGap
    plans: tuple[PlayPlan, PlayPlan]
    notes_of: tuple[tuple[int, ...], tuple[int, ...]]
    rows: PairRows
    planning_s: float
    least_rail_gap_m: float  # the rails' least distance apart over the rows
    text: str | None = None  # the file, planned in memory (no path)
    first: str = RIGHT  # the hand planned first
    # (every way planned, ``PairPass.way``, and the frames of music it played)
    tried: tuple[tuple[str, float], ...] = ()
    planned_of: tuple[tuple[int, ...], tuple[int, ...]] | None = None
    way: str = ""  # the way kept (``PairPass.way``)

    def left_out(self) -> list[tuple[int, object]]:
        """Every note not played, as (song index, ``Skip`` of its hand's plan), by note."""
        return left_out_of(self.plans, self.planned_of or self.notes_of, self.notes_of)

    def played_of(self, side: str) -> list[int]:
        """The song indices of the notes ``side`` plays (its notes but those left out)."""
        i = SIDES.index(side)
        out = {s.note for s in self.plans[i].verdict.skipped}
        return [n for k, n in enumerate((self.planned_of or self.notes_of)[i]) if k not in out]


def left_out_of(plans, planned_of, notes_of) -> list[tuple[int, object]]:
    """(song index, ``Skip``) of every note its hand (``notes_of``) left out, by note: a
    note the hand planned first left out and handed over is the other hand's. A handed
    note the other hand refused for the first one's bodies (``SkipReason.OTHER_HAND``:
    the first hand over its key, as it was when it left the note out) is named by why the
    first hand left it out, the refusal added to the detail: the loss is the first hand's."""
    mine = [set(idx) for idx in notes_of]
    skips = [{idx[s.note]: s for s in p.verdict.skipped} for idx, p in zip(planned_of, plans)]
    out = []
    for k in range(len(plans)):
        for i, s in skips[k].items():
            if i not in mine[k]:
                continue
            before = skips[1 - k].get(i)
            if s.reason is SkipReason.OTHER_HAND and before is not None:
                s = replace(before, detail=f"{before.detail}; handed to the other hand, "
                                           f"which could not take it: {s.detail}")
            out.append((i, s))
    return sorted(out, key=lambda x: x[0])


def windows(notes, idx: tuple[int, ...], out_of: frozenset[int] = frozenset()
            ) -> list[tuple[float, float]]:
    """Per note of ``idx`` (indices into ``notes``, in onset order), its window (module
    docstring): from its hand's previous onset (-inf for the first) to its hand's next
    onset plus half of that event's longest note (+inf for the last); the onsets of the
    notes ``out_of`` (positions in ``idx`` no place within their bound plays) are none:
    the hand does not move for them."""
    struck = sorted({notes[i].onset_s for k, i in enumerate(idx) if k not in out_of})
    longest: dict[float, float] = {}
    for k, i in enumerate(idx):
        if k not in out_of:
            t = notes[i].onset_s
            longest[t] = max(longest.get(t, 0.0), notes[i].duration_s)
    out = []
    for i in idx:
        t = notes[i].onset_s
        a, b = bisect.bisect_left(struck, t), bisect.bisect_right(struck, t)
        t0 = struck[a - 1] if a > 0 else -math.inf
        t1 = struck[b] + DROP_FRACTION * longest[struck[b]] if b < len(struck) else math.inf
        out.append((t0, t1))
    return out


def room_bounds(notes, side: str, own: tuple[int, ...], other: tuple[int, ...], gap: HandGap,
                out_of: frozenset[int] = frozenset()) -> list[tuple[float, float]]:
    """The bounds of the hand planned first (``side``): per note of ``own``, its rail no
    nearer the other hand than leaves that hand room for its notes (``other``) sounding
    in the note's window, their keys at the other hand's farthest reach towards it, plus
    the rail gap (the right hand above, the left below)."""
    reach = gap.left if side == RIGHT else gap.right
    xs = [(notes[i].onset_s, notes[i].offset_s, kb.key(notes[i].pitch).center_x_m)
          for i in other]
    out = []
    for t0, t1 in windows(notes, own, out_of):
        need = [x for a, b, x in xs if a < t1 and b > t0]
        if side == RIGHT:
            lo = (max(need) - reach.key_hi_m + gap.rail_gap_m) if need else -UNBOUNDED_M
            out.append((lo, UNBOUNDED_M))
        else:
            hi = (min(need) - reach.key_lo_m - gap.rail_gap_m) if need else UNBOUNDED_M
            out.append((-UNBOUNDED_M, hi))
    return out


def clear_limits(notes, side: str, own: tuple[int, ...], edge_t_s: np.ndarray,
                 edge_m: np.ndarray, dt_s: float, out_of: frozenset[int] = frozenset()
                 ) -> list[float]:
    """Per note of ``own`` (the hand planned second, ``side``), the other hand's inner edge
    nearest this hand over the note's window (``edge_m`` at song times ``edge_t_s``: per
    row of the other hand, its rail less (a right hand) or plus (a left one) its bodies'
    reach towards this hand in that row's pose, ``InnerEdge``; one row more each side:
    the rows' clock samples the other hand's moves): the least for a left hand, the most
    for a right one."""
    out = []
    for t0, t1 in windows(notes, own, out_of):
        a = 0 if t0 == -math.inf else int(np.searchsorted(edge_t_s, t0 - dt_s, side="left"))
        b = (len(edge_t_s) if t1 == math.inf
             else int(np.searchsorted(edge_t_s, t1 + dt_s, side="right")))
        seg = edge_m[max(0, a - 1):b + 1]
        out.append(float(seg.min()) if side == LEFT else float(seg.max()))
    return out


def clear_bounds(notes, side: str, own: tuple[int, ...], edge_t_s: np.ndarray,
                 edge_m: np.ndarray, reach_m: float, dt_s: float,
                 out_of: frozenset[int] = frozenset()) -> list[tuple[float, float]]:
    """The bounds of the hand planned second (``side``) by the farthest-reach rule: per
    note of ``own``, its rail ``reach_m`` (its own bodies' farthest reach towards the
    other hand, plus the clearance) from the other hand's inner edge at every row of the
    note's window (``clear_limits``); the left hand below, the right above."""
    return [(-UNBOUNDED_M, e - reach_m) if side == LEFT else (e + reach_m, UNBOUNDED_M)
            for e in clear_limits(notes, side, own, edge_t_s, edge_m, dt_s, out_of)]


def settled_bounds(notes, places: Places, memo: CostMemo, rate_hz: float,
                   bounds_of: Callable[[frozenset[int]], list[tuple[float, float]]]
                   ) -> list[tuple[float, float]]:
    """A hand's bounds (``bounds_of(out_of)``) with the windows of its notes that no place
    plays within their bound (``Costs.reason``: out of reach, too short, the other hand's)
    taken out, again until no more notes fall out (windows only grow, so bounds only
    tighten: it ends)."""
    return settle(notes, places, memo, rate_hz, bounds_of)[0]


def settle(notes, places: Places, memo: CostMemo, rate_hz: float,
           bounds_of: Callable[[frozenset[int]], list[tuple[float, float]]]
           ) -> tuple[list[tuple[float, float]], frozenset[int]]:
    """``settled_bounds`` and the notes taken out (positions in ``notes``)."""
    out_of: frozenset[int] = frozenset()
    while True:
        bounds = bounds_of(out_of)
        costs = Costs(notes, places, rate_hz, memo, bounds)
        # (the notes out already stay out: only the others are asked)
        now = frozenset(k for k in range(len(notes))
                        if k not in out_of and costs.reason(k) is not None)
        if not now:
            return bounds, out_of
        out_of |= now


def _sub_song(song: Song, idx: tuple[int, ...]) -> Song:
    return replace(song, notes=tuple(song.notes[i] for i in idx), part=None)


def _other(side: str) -> str:
    return RIGHT if side == LEFT else LEFT


@dataclass(frozen=True)
class PairPass:
    """One way of planning the pair: an assignment (the notes the hand planned first left
    out handed over: ``HandAssignment.hand_over``), the hand planned first (``first``),
    each hand's plan (left, right), each hand's notes as song indices (``notes_of``) and
    each plan's (``planned_of``), the frames of music the two plans play
    (``played_frames``: the played notes' lengths in whole frames at the rate, the
    currency the weighing and the frame F1 count in), and ``alone``: the assignment
    planned gave every note to the hand planned first."""

    assignment: HandAssignment
    first: str
    plans: tuple[PlayPlan, PlayPlan]
    notes_of: tuple[tuple[int, ...], tuple[int, ...]]
    played_frames: float
    planned_of: tuple[tuple[int, ...], tuple[int, ...]]
    alone: bool = False
    back: bool = False  # the first hand planned again with what the second left out

    @property
    def way(self) -> str:
        """How it was planned: ``right first``, ``left first``, or ``right alone`` (the
        other hand given only the notes the first one left out); `` back``: then the
        first hand planned again with the notes the second left out (``hand_back``)."""
        return f"{self.first} {'alone' if self.alone else 'first'}{' back' if self.back else ''}"

    def skipped_for(self, reason: SkipReason) -> list[tuple[int, object]]:
        """(song index, ``Skip``) of every note a plan left out for ``reason`` (the notes
        handed over too)."""
        return [(idx[s.note], s) for idx, p in zip(self.planned_of, self.plans)
                for s in p.verdict.skipped if s.reason is reason]


class FirstEdge(NamedTuple):
    """The hand planned first's inner edge (towards the other hand, m) per row of its
    plan, at song times ``t_s``."""

    t_s: np.ndarray
    x_m: np.ndarray


def _room(song: Song, pp: PairPlanner, side: str, own: tuple[int, ...],
          other: tuple[int, ...], sub: Song, rate_hz: float) -> list[tuple[float, float]]:
    """The hand planned first's bounds: per note of ``own``, its places' own reach
    (``planner.play.handclear.PlaceReach``) the clearance beyond the least the other hand
    must reach to press its notes sounding in the note's window (``least_reach_m``); never
    tighter than ``room_bounds`` (the other hand's farthest reach and the rail gap). Only
    room: the second hand keeps the clearance from the first one's rows as they are."""
    strict = room_bounds(song.notes, side, own, other, pp.gap)
    osd = _other(side)
    opl, pl = pp.planners[osd], pp.planners[side]
    o_reach = NoteReaches(Costs(song.notes, opl.places, rate_hz, opl.memo), pp.place_reach[osd])
    need = {i: least_reach_m(o_reach, i, osd) for i in other}
    free = NoteReaches(Costs(sub.notes, pl.places, rate_hz, pl.memo), pp.place_reach[side])
    c = pp.gap.clearance_m
    out = []
    for k, (t0, t1) in enumerate(windows(song.notes, own)):
        xs = [need[i] for i in other if song.notes[i].onset_s < t1
              and song.notes[i].offset_s > t0]
        if not xs or any(x is None for x in xs):
            out.append(strict[k])
            continue
        lim = max(xs) + c if side == RIGHT else min(xs) - c
        out.append(loose_bound(free, k, side, lim, strict[k]))
    return out


def _played_frames(plan: PlayPlan, idx: tuple[int, ...], notes, rate_hz: float) -> int:
    """The frames of music ``plan`` (of the notes ``idx``) plays, in whole frames (ways
    playing the same music tie exactly; a sum of seconds differs in its last bits with
    the notes' order)."""
    out = {k.note for k in plan.verdict.skipped}
    return sum(round(notes[i].duration_s * rate_hz) for k, i in enumerate(idx) if k not in out)


def _plan_second(song: Song, pp: PairPlanner, side: str, idx: tuple[int, ...], sub: Song,
                 first: PlayPlan, edge: FirstEdge, rate_hz: float, song_name: str) -> PlayPlan:
    """The hand planned second (``side``, its notes ``idx`` as ``sub``) within the first
    one's rows: by the farthest-reach rule (``clear_bounds``, settled); where that leaves
    a note out for the other hand, again with each note's bound loosened to the reach of
    the places that press it, confirmed on both hands' rows by the check's judge
    (``planner.play.handclear``); the plan playing more frames kept (the first of equals)."""
    notes, pl, dt = song.notes, pp.planners[side], 1.0 / rate_hz
    reach_m = pp.reach(side).inner_extent_m + pp.gap.clearance_m
    bounds = settled_bounds(
        sub.notes, pl.places, pl.memo, rate_hz,
        lambda out: clear_bounds(notes, side, idx, edge.t_s, edge.x_m, reach_m, dt, out))
    strict = plan_song(sub, pp.hands[side], None, rate_hz, song_name=song_name, planner=pl,
                       rail_bounds=bounds)
    refused = [s.note for s in strict.verdict.skipped if s.reason is SkipReason.OTHER_HAND]
    if not refused:
        return strict
    loose = _plan_loose(song, pp, side, idx, sub, first, edge, rate_hz, song_name, refused)
    if loose is not None and (_played_frames(loose, idx, notes, rate_hz)
                              > _played_frames(strict, idx, notes, rate_hz)):
        return loose
    return strict


def _plan_loose(song: Song, pp: PairPlanner, side: str, idx: tuple[int, ...], sub: Song,
                first: PlayPlan, edge: FirstEdge, rate_hz: float, song_name: str,
                refused: list[int]) -> PlayPlan | None:
    """``_plan_second``'s loosened plan (``planner.play.handclear``), or None when the
    check's judge still finds the hands too near after ``MAX_ROUNDS`` plans, or when no
    note the farthest-reach rule refused (``refused``, positions in ``sub``) has a place
    within its loosened bound (then the plan would be the same)."""
    notes, pl, dt = song.notes, pp.planners[side], 1.0 / rate_hz
    c = pp.gap.clearance_m
    reach_m = pp.reach(side).inner_extent_m + c
    # (every place: no bound)
    free = NoteReaches(Costs(sub.notes, pl.places, rate_hz, pl.memo), pp.place_reach[side])
    back: set[int] = set()  # (the notes held to the farthest-reach rule)
    got: dict[str, frozenset[int]] = {}

    def bounds_of(out: frozenset[int]) -> list[tuple[float, float]]:
        got["out"] = out
        lims = clear_limits(notes, side, idx, edge.t_s, edge.x_m, dt, out)
        res = []
        for k, e in enumerate(lims):
            strict = (-UNBOUNDED_M, e - reach_m) if side == LEFT else (e + reach_m, UNBOUNDED_M)
            res.append(strict if k in back else loose_bound(
                free, k, side, e - c if side == LEFT else e + c, strict))
        return res

    for _ in range(MAX_ROUNDS):
        bounds = settled_bounds(sub.notes, pl.places, pl.memo, rate_hz, bounds_of)
        placed = Costs(sub.notes, pl.places, rate_hz, pl.memo, bounds)
        if all(placed.reason(k) is not None for k in refused):
            return None
        plan = plan_song(sub, pp.hands[side], None, rate_hz, song_name=song_name, planner=pl,
                         rail_bounds=bounds)
        rows = _one_clock((plan, first) if side == LEFT else (first, plan), rate_hz)
        hit = collided_notes(rows.t_s, rows.q[0], rows.q[1],
                             (pp.edges[LEFT], pp.edges[RIGHT]), rows.song_start_s,
                             windows(notes, idx, got["out"]), dt, c)
        if hit is not None and not hit:
            return plan
        if hit is None or hit <= back:
            return None
        back |= hit
    return None


def plan_pass(song: Song, pp: PairPlanner, a: HandAssignment, first: str, rate_hz: float,
              song_name: str = "") -> PairPass:
    """Plan both hands by ``a``: the hand ``first`` leaving the other room for its notes
    (``room_bounds``), then the other within the first one's rows (``clear_bounds``,
    settled: ``settled_bounds``), its notes and every note the first one left out (the
    second hand's programme weighs them in the same frames as its own: a note it cannot
    play is left out again, one it plays instead of its own costs it fewer frames)."""
    notes = song.notes
    idx = {s: a.notes_of(s) for s in SIDES}
    subs = {s: _sub_song(song, idx[s]) for s in SIDES}
    second = _other(first)
    plans: dict[str, PlayPlan] = {}
    # (the first hand's bound leaves the other room; it keeps no clearance itself, the
    # second hand's bound does: its windows are its notes' own, none taken out)
    bounds = _room(song, pp, first, idx[first], idx[second], subs[first], rate_hz)
    plans[first] = plan_song(subs[first], pp.hands[first], None, rate_hz, song_name=song_name,
                             planner=pp.planners[first], rail_bounds=bounds)
    given = {idx[first][s.note]: f"{s.reason.value}: {s.detail}"
             for s in plans[first].verdict.skipped}
    planned = {first: idx[first], second: tuple(sorted(set(idx[second]) | set(given)))}
    subs[second] = _sub_song(song, planned[second])
    tr = plans[first].trajectory
    edge_t_s = tr.t_s - plans[first].song_start_s
    inner_m = pp.edges[first].inner_m(tr.q)
    rail_m = tr.q[:, pp.hands[first].index["rail"]]
    edge_m = rail_m - inner_m if first == RIGHT else rail_m + inner_m
    edge = FirstEdge(edge_t_s, edge_m)
    plans[second] = _plan_second(song, pp, second, planned[second], subs[second], plans[first],
                                 edge, rate_hz, song_name)
    played = sum(_played_frames(plans[s], planned[s], notes, rate_hz) for s in SIDES)
    a = a.hand_over(given, second)
    return PairPass(a, first, (plans[LEFT], plans[RIGHT]), (a.notes_of(LEFT), a.notes_of(RIGHT)),
                    float(played), (planned[LEFT], planned[RIGHT]), not idx[second])


def hand_back(song: Song, pp: PairPlanner, p: PairPass, rate_hz: float,
              song_name: str = "") -> PairPass | None:
    """``p`` with the notes its second hand left out handed back to the first: the first
    hand planned again, its notes but those the second plays and with those, within the
    second one's rows as they are (``_plan_second``: the same rule the second kept from
    the first one's rows, so the pair keeps its clearance; the second's plan is
    unchanged). None when the second hand left nothing out."""
    first, second = p.first, _other(p.first)
    f, s = SIDES.index(first), SIDES.index(second)
    gone = {p.planned_of[s][k.note] for k in p.plans[s].verdict.skipped}
    if not gone:
        return None
    plays = set(p.planned_of[s]) - gone
    idx = tuple(sorted((set(p.planned_of[f]) - plays) | gone))
    sub = _sub_song(song, idx)
    tr = p.plans[s].trajectory
    inner_m = pp.edges[second].inner_m(tr.q)
    rail_m = tr.q[:, pp.hands[second].index["rail"]]
    edge = FirstEdge(tr.t_s - p.plans[s].song_start_s,
                     rail_m - inner_m if second == RIGHT else rail_m + inner_m)
    again = _plan_second(song, pp, first, idx, sub, p.plans[s], edge, rate_hz, song_name)
    plans = {first: again, second: p.plans[s]}
    planned = {first: idx, second: p.planned_of[s]}
    a = p.assignment.hand_over({i: _why(p, i) for i in idx if p.assignment.hand[i] != first},
                               first)
    played = sum(_played_frames(plans[x], planned[x], song.notes, rate_hz) for x in SIDES)
    return PairPass(a, first, (plans[LEFT], plans[RIGHT]), (a.notes_of(LEFT), a.notes_of(RIGHT)),
                    float(played), (planned[LEFT], planned[RIGHT]), p.alone, True)


def _why(p: PairPass, i: int) -> str:
    """Why ``p``'s hand of note ``i`` (song index) left it out (its plan's ``Skip``)."""
    k = SIDES.index(p.assignment.hand[i])
    for s in p.plans[k].verdict.skipped:
        if p.planned_of[k][s.note] == i:
            return f"{s.reason.value}: {s.detail}"
    return "left out"


def plan_two_hands(song: Song, pp: PairPlanner, out_path: str | None = None,
                   rate_hz: float = 100.0, song_name: str = "") -> TwoHandPlan:
    """Plan ``song`` (every part: ``load_song(..., every_part=True)``) on both hands (the
    module docstring) and write the two-hand file to ``out_path`` ('-': stdout; None:
    in memory, ``TwoHandPlan.text``). The clock starts after the pair's set-up.

    The right hand is planned first; when that leaves a note out for the other hand's
    clearance (``SkipReason.OTHER_HAND``: the hands want the same keys), the left hand
    first too (the hand planned first takes the keys both want); and the right hand
    alone, every note its own, as one hand plays the file (where the parts lie within
    one hand's reach, two hands only get in each other's way), the left one given what
    it leaves out. Every way hands the notes its first hand leaves out to the other. The way playing the most frames of music is kept (the earlier of
    equals). (A hand with no notes plans nothing the order could change.)"""
    if not (math.isfinite(rate_hz) and 1.0 <= rate_hz <= 10000.0):
        raise InputError(f"--rate must be between 1 and 10000 Hz, got {rate_hz}")
    t_start = time.perf_counter()
    places = {s: pp.planners[s].places for s in SIDES}
    a = assign_hands(song.notes, pp.gap, places, rate_hz)
    tried = [plan_pass(song, pp, a, RIGHT, rate_hz, song_name)]
    if all(a.notes_of(s) for s in SIDES):
        if tried[0].skipped_for(SkipReason.OTHER_HAND):
            tried.append(plan_pass(song, pp, a, LEFT, rate_hz, song_name))
        tried.append(plan_pass(song, pp, a.one_hand(RIGHT), RIGHT, rate_hz, song_name))
    best = max(tried, key=lambda p: p.played_frames)  # (max keeps the first of equals)
    back = hand_back(song, pp, best, rate_hz, song_name)
    if back is not None:
        tried.append(back)
        best = max((best, back), key=lambda p: p.played_frames)
    rows = _one_clock(best.plans, rate_hz)
    least = float((rows.q[1][:, pp.hands[RIGHT].index["rail"]]
                   - rows.q[0][:, pp.hands[LEFT].index["rail"]]).min())
    plan = TwoHandPlan(best.assignment, pp.gap, best.plans, best.notes_of, rows, 0.0, least,
                       first=best.first,
                       tried=tuple((p.way, p.played_frames) for p in tried),
                       planned_of=best.planned_of, way=best.way)
    text = write_two_hands(plan, song, pp, out_path, rate_hz, song_name)
    return replace(plan, planning_s=time.perf_counter() - t_start, text=text)


def two_hand_metadata(song: Song, plan: TwoHandPlan, rate_hz: float, song_name: str) -> dict:
    """The two-hand file's own metadata (the pair's keys are the writer's,
    ``planner.pairfile``): the song read with every part, the common ``song_start_s``,
    the pair's rail gap and how the hint was read."""
    return {"task": "play", "rate_hz": rate_hz,
            "song": song_name or os.path.basename(song.source), "notes": len(song.notes),
            "track": None, "channel": None, "transpose": song.transpose, "every_part": True,
            "song_start_s": plan.rows.song_start_s, "rail_gap_m": plan.gap.rail_gap_m,
            "hint": plan.assignment.source.value, "first_hand": plan.first}


def end_claims(plan: TwoHandPlan, notes) -> tuple[dict, dict[str, list[int]]]:
    """The end marker's claims for the whole song (``notes``, ``played``, ``left_out``,
    each hand's limit violations should one reach the end) and ``by_hand`` (per prefix,
    the notes that hand plays)."""
    left_out = plan.left_out()
    info: dict = {"notes": len(notes), "played": len(notes) - len(left_out),
                  "left_out": [{"note": i, "reason": s.reason.value, "detail": s.detail}
                               for i, s in left_out]}
    for side, p in zip(SIDES, plan.plans):
        bad = p.verdict.end_info().get("limit_violations")
        if bad:
            info.setdefault("limit_violations", []).extend(
                {**v, "name": f"{side}.{v['name']}"} for v in bad)
    return info, {f"{side}.": plan.played_of(side) for side in SIDES}


def write_two_hands(plan: TwoHandPlan, song: Song, pp: PairPlanner, out_path: str | None,
                    rate_hz: float, song_name: str = "") -> str | None:
    """The two-hand file (version 3, ``planner.pairfile.PairWriter``: the one writer and
    its guard) of ``plan``'s rows, into ``out_path`` ('-': stdout; None: returned)."""
    from planner.pairfile import PairWriter

    w = PairWriter(out_path, (pp.hands[LEFT], pp.hands[RIGHT]),
                   two_hand_metadata(song, plan, rate_hz, song_name))
    try:
        t, (ql, qr) = plan.rows.t_s, plan.rows.q
        for a in range(0, len(t), ROW_BLOCK):
            w.write_rows(t[a:a + ROW_BLOCK], ql[a:a + ROW_BLOCK], qr[a:a + ROW_BLOCK])
        info, by_hand = end_claims(plan, song.notes)
        w.close(info, by_hand)
    except BaseException as e:
        w.abort(discard=isinstance(e, InputError))
        raise
    return w.text


def _one_clock(plans: tuple[PlayPlan, PlayPlan], rate_hz: float) -> PairRows:
    """Both plans' rows on one clock (module docstring)."""
    trs = tuple(p.trajectory for p in plans)
    start = max(p.song_start_s for p in plans)
    lead = [round((start - p.song_start_s) * rate_hz) for p in plans]
    n = max(len(tr.t_s) + k for tr, k in zip(trs, lead))
    qs = []
    for tr, k in zip(trs, lead):
        q = np.concatenate([np.repeat(tr.q[:1], k, axis=0), tr.q])
        qs.append(np.concatenate([q, np.repeat(q[-1:], n - len(q), axis=0)]))
    return PairRows(np.arange(n) / rate_hz, (qs[0], qs[1]), start)
