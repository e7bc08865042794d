"""The rail bounds of two hands on one rail (``play --hands 2``, ``planner.play.twohands``):
the hand planned first leaves the other room for its notes (``room_bounds``, ``room``),
the hand planned second keeps the clearance from the first one's bodies as they are at
every row (``clear_bounds``: the first hand's inner edge, ``FirstEdge``), each over its
notes' windows (``windows``), the notes no place plays within their bound taken out until
none falls out (``settle``).

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
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Callable
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from planner.music import keyboard as kb
from planner.music.midi import Song
from planner.play.costs import CostMemo, Costs
from planner.play.handclear import NoteReaches, least_reach_m, loose_bound
from planner.play.handgap import HandGap, InnerEdge
from planner.play.hands import LEFT, RIGHT, other_side
from planner.play.motion import DROP_FRACTION
from planner.play.places import Places
from planner.play.roomcost import RoomClaim, RoomCost

if TYPE_CHECKING:
    from planner.hand.model import HandModel
    from planner.play.stream import PlayPlan
    from planner.play.twohands import PairPlanner
    from planner.trajfile import Trajectory

UNBOUNDED_M = 10.0  # a bound no rail reaches (the travel is a few metres at most)
HANDED_SHARE = 0.68  # of the frames of the notes the hand planned first hands over, the
# share the second hand plays where the first leaves it room: measured on material that is
# not the two-hand corpus, 48 random two-hand songs (bench/random_songs.py's generators, a
# right part and a left part an octave lower, seeds 0-47; main a2f3801, both orders): of
# the frames handed over, 2 210 played, 1 032 left out for reasons other than the first
# hand's bodies (docs/history/2026-12-07-two-hands6.md)


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
    before: list[tuple[float, float]] | None = None
    while True:
        bounds = bounds_of(out_of)
        costs = Costs(notes, places, rate_hz, memo, bounds)
        # (the notes out already stay out: only the others are asked, and of those only
        # the ones whose bound changed: ``Costs.reason`` reads the note and its own bound
        # only, so a note some place played within the same bound still is)
        now = frozenset(k for k in range(len(notes))
                        if k not in out_of and (before is None or bounds[k] != before[k])
                        and costs.reason(k) is not None)
        if not now:
            return bounds, out_of
        out_of |= now
        before = bounds


class FirstEdge(NamedTuple):
    """The hand planned first's inner edge (towards the other hand, m) per row of its
    plan, at song times ``t_s``."""

    t_s: np.ndarray
    x_m: np.ndarray


def first_edge(plan: PlayPlan, hand: HandModel, edge: InnerEdge, side: str,
               read: Callable[[PlayPlan], Trajectory] | None = None) -> FirstEdge:
    """``side``'s inner edge per row of its plan ``plan`` (its rail less, a right hand, or
    plus, a left one, its bodies' reach towards the other hand in that row's pose);
    ``read``: a plan's rows (``planner.play.twoplan.PlanReads``; None: ``plan.trajectory``)."""
    tr = plan.trajectory if read is None else read(plan)
    inner_m = edge.inner_m(tr.q)
    rail_m = tr.q[:, hand.index["rail"]]
    return FirstEdge(tr.t_s - plan.song_start_s,
                     rail_m - inner_m if side == RIGHT else rail_m + inner_m)


def room(song: Song, pp: PairPlanner, side: str, own: tuple[int, ...],
         other: tuple[int, ...], sub: Song, rate_hz: float) -> list[tuple[float, float]]:
    """The hand planned first's bounds: per note of ``own``, its places' own reach
    (``planner.play.handclear.PlaceReach``) the clearance beyond the least the other hand
    must reach to press its notes sounding in the note's window (``least_reach_m``); never
    tighter than ``room_bounds`` (the other hand's farthest reach and the rail gap). Only
    room: the second hand keeps the clearance from the first one's rows as they are."""
    return room_settled(song, pp, side, own, other, sub, rate_hz, settled=False)[0]


def room_settled(song: Song, pp: PairPlanner, side: str, own: tuple[int, ...],
                 other: tuple[int, ...], sub: Song, rate_hz: float, settled: bool = True
                 ) -> tuple[list[tuple[float, float]], frozenset[int]]:
    """``room``'s bounds settled (``settle``: a note no place plays within its bound is no
    event of the hand's, which stands where its note before left it until its next one, so
    that note's window, and its room, runs on to it) and the notes they take out
    (positions in ``own``); ``settled`` False: ``room``'s, none taken out."""
    osd = other_side(side)
    opl, pl = pp.planners[osd], pp.planners[side]
    o_reach = NoteReaches(Costs(song.notes, opl.places, rate_hz, opl.memo), pp.place_reach[osd])
    need = {i: least_reach_m(o_reach, i, osd) for i in other}
    free = NoteReaches(Costs(sub.notes, pl.places, rate_hz, pl.memo), pp.place_reach[side])
    c = pp.gap.clearance_m

    def bounds_of(out_of: frozenset[int]) -> list[tuple[float, float]]:
        strict = room_bounds(song.notes, side, own, other, pp.gap, out_of)
        out = []
        for k, (t0, t1) in enumerate(windows(song.notes, own, out_of)):
            xs = [need[i] for i in other if song.notes[i].onset_s < t1
                  and song.notes[i].offset_s > t0]
            if not xs or any(x is None for x in xs):
                out.append(strict[k])
                continue
            lim = max(xs) + c if side == RIGHT else min(xs) - c
            out.append(loose_bound(free, k, side, lim, strict[k]))
        return out

    if not settled:
        return bounds_of(frozenset()), frozenset()
    return settle(sub.notes, pl.places, pl.memo, rate_hz, bounds_of)


def room_cost(song: Song, pp: PairPlanner, side: str, own: tuple[int, ...],
              other: tuple[int, ...], rate_hz: float,
              out_of: frozenset[int] = frozenset()) -> RoomCost:
    """What the room the hand planned first (``side``, its notes ``own``) takes costs
    (``planner.play.roomcost``): every note of the other hand's (``other``) and of its
    own part (which it hands over when it leaves it out) claims, while it sounds, the
    rail beyond the least the other hand must reach to press it (``least_reach_m``) and
    the clearance; a note the other hand presses from no place claims nothing. A state
    lasts to the hand's next event: the onset of a note of ``own`` not in ``out_of``
    (positions in ``own``: the notes no place plays within their bound, ``room_settled``,
    which the programme makes no event of: the hand stands where it was through them)."""
    osd = other_side(side)
    opl = pp.planners[osd]
    o_reach = NoteReaches(Costs(song.notes, opl.places, rate_hz, opl.memo), pp.place_reach[osd])
    c = pp.gap.clearance_m if side == RIGHT else -pp.gap.clearance_m
    pos = {i: k for k, i in enumerate(own)}
    claims = []
    for i in sorted(set(own) | set(other)):
        x = least_reach_m(o_reach, i, osd)
        if x is not None:
            n = song.notes[i]
            claims.append(RoomClaim(n.onset_s, n.offset_s, x + c, pos.get(i, -1)))
    places, reach = pp.planners[side].places, pp.place_reach[side]
    return RoomCost(claims, side, [song.notes[i].onset_s for k, i in enumerate(own)
                                   if k not in out_of],
                    [song.notes[i].pitch for i in own], reach.reach_m,
                    pp.reach(side).inner_extent_m, places.rail_m, rate_hz, HANDED_SHARE)
