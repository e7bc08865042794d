"""The hand planned second's clearance judged on the poses it presses each note with, then
confirmed on both hands' rows by the check's own bodies (``play --hands 2``:
``planner.play.twohands``).

**The rule it loosens.** The hand planned second keeps, at every row of a note's window,
its rail its *farthest* reach (``HandReach.inner_extent_m``: over every pose the planner
puts the hand in, the index finger abducted towards the other hand, 96.5 mm on the default
pair) plus the clearance from the first hand's bodies as they are (``clear_bounds``). It is
exact whatever the second hand's poses, and it refuses a note whose key lies a finger's
width from the first hand's bodies but whose place would need that farthest pose on the
rail's side of the key (on the two-hand corpus, notes 70-140 mm clear of the first hand's
bodies when struck were left out so).

**The place's own reach.** Each place a finger presses a key from has its own poses (the
atlas entry's press, rise, hover and high, the idle fingers tucked): ``PlaceReach`` is the
farthest its bodies reach from the rail towards the other hand over those four poses (the
check's bodies and kinematics, the rail at 0). A note's **loosened bound** is the farthest
rail (towards the other hand) of the places that press it with their own reach clear of
the first hand's inner edge over the window by the clearance (``loose_bound``); never
tighter than the farthest-reach rule's.

**Confirmed, not assumed.** The loosened bound is a bound on the rail, not on the poses:
another finger pressing from a place within it, the hand between two places, or a pose of
a chord's other note may reach further. So the plan it gives is replayed with the first
hand's rows on one clock (the rows as the file holds them, six decimals) through the
check's own judge of the hands' distance (``planner.check.handgap.GapJudge``); the notes
whose windows hold a row under the clearance go back to the farthest-reach rule and the
hand is planned again (``collided_notes``), until no row is under it; past
``MAX_ROUNDS`` the farthest-reach plan is kept (exact by construction). The plan is
exact by the check's own test either way.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from planner.check.handgap import GapJudge
from planner.play.costs import Costs
from planner.play.handgap import InnerEdge, PoseExtents, pose_extents
from planner.play.places import Places
from planner.trajfile import as_written

MAX_ROUNDS = 3  # the second hand planned again at most this often with the notes of its
# collisions back on the farthest-reach rule (each round one more one-hand plan; the
# collisions a loosened bound causes are few: the farthest-reach plan kept past them)


class PlaceReach:
    """Per place a finger presses a key from, how far the hand's bodies reach from the rail
    towards the other hand over that place's four poses (module docstring), by the atlas
    entry: ``reach_m(finger, pitch, place)``."""

    def __init__(self, places: Places, edge: InnerEdge, ext: PoseExtents | None = None
                 ) -> None:
        self.places = places
        ext = ext or pose_extents(places, edge)  # (``ext``: the hand's, shared with its
        # ``HandReach``: ``planner.play.handgap.PoseExtents``)
        # (every place that presses a key with a force, with its reach: ``NoteReaches``'
        # arrays, shared by every song and way the pair plans)
        self.presses: dict[tuple[int, float], tuple[np.ndarray, np.ndarray]] = {}
        if not ext.keys:
            self._reach: dict = {}
            return
        inner = ext.inner_m(places.hand.side)[ext.rows].max(axis=1)
        self._reach = dict(zip(ext.keys, inner.tolist()))

    def reach_m(self, finger: str, pitch: int, place: int) -> float:
        """The place's reach towards the other hand (m from its rail); ``math.inf`` for a
        place the finger presses the key from none of its entries (never clear)."""
        p = self.places.posture_of(place)
        at = self.places.atlases[p]
        k = at.grid_index(finger, pitch, self.places.rail_m(place))
        return self._reach.get((p, finger, pitch % 12, k), math.inf)


class NoteReaches:
    """Per note of a song, every place that presses it (``costs``: no bounds): its rail (m)
    and the hand's reach from there towards the other hand (``PlaceReach``), as arrays,
    gathered once per key and force (``Costs.rails``' own key: the places that press a note
    with no bounds are its key's and its force's) and kept in ``PlaceReach.presses`` for
    every song and way of the pair, read by every bound the rounds try (``loose_bound``,
    ``least_reach_m``)."""

    def __init__(self, costs: Costs, pr: PlaceReach) -> None:
        if costs.bound is not None or costs.places is not pr.places:
            raise ValueError("NoteReaches reads every place of the reach's own hand: "
                             "costs with no bounds, on the same places")
        self.costs, self.pr = costs, pr

    def of(self, note: int) -> tuple[np.ndarray, np.ndarray]:
        """``note``'s places' rails (m) and reaches (m, ``math.inf``: never clear)."""
        c = self.costs
        key = (c.pitch[note], c.force[note])
        got = self.pr.presses.get(key)
        if got is None:
            pitch = c.pitch[note]
            rail_m, reach_m = c.places.rail_m, self.pr.reach_m
            qs = [(f, q) for f in c.places.hand.fingers for q in c.rails(f, note)]
            got = self.pr.presses[key] = (
                np.array([rail_m(q) for _, q in qs], dtype=float),
                np.array([reach_m(f, pitch, q) for f, q in qs], dtype=float))
        return got


def loose_bound(nr: NoteReaches, note: int, side: str, limit_m: float,
                strict: tuple[float, float]) -> tuple[float, float]:
    """``note``'s loosened rail bound (module docstring): ``limit_m`` is the farthest x the
    hand's bodies may reach (the first hand's inner edge over the window less the
    clearance, or plus it for a right hand); ``strict``: the farthest-reach rule's bound,
    which it never tightens. ``nr``: the song's places with no bounds (every place that
    presses the note)."""
    rail, reach = nr.of(note)
    ok = rail[rail + reach <= limit_m] if side == "left" else rail[rail - reach >= limit_m]
    lo, hi = strict
    if not ok.size:
        return strict
    if side == "left":
        return lo, max(hi, float(ok.max()))
    return min(lo, float(ok.min())), hi


def collided_notes(t_s: np.ndarray, q_left: np.ndarray, q_right: np.ndarray,
                   edges: tuple[InnerEdge, InnerEdge], song_start_s: float,
                   note_windows: Sequence[tuple[float, float]], dt_s: float,
                   clearance_m: float) -> set[int] | None:
    """The positions (in ``note_windows``' order) of the notes whose windows (song time)
    hold a row where the hands' bodies are under ``clearance_m`` apart (the check's judge,
    on the rows as the file holds them; one row more each side); an empty set when no row
    is; None when some row is but no window holds it."""
    judge = GapJudge(tuple(e.kin for e in edges), tuple(e.bodies for e in edges),
                     ("left.", "right."), clearance_m, hits_only=True)
    judge.add(as_written(t_s), as_written(q_left), as_written(q_right))
    gap = judge.finish(float(t_s[-1]) + dt_s)
    if gap.ok:
        return set()
    hit = set()
    for c in gap.collisions:
        a, b = c.start_s - song_start_s - dt_s, c.end_s - song_start_s + dt_s
        hit |= {k for k, (t0, t1) in enumerate(note_windows) if t0 < b and t1 > a}
    return hit or None


def least_reach_m(nr: NoteReaches, note: int, side: str) -> float | None:
    """How far towards the other hand a hand (``side``) must reach, at the least, to
    press ``note`` (``nr``: the song's places with no bounds): over every place that
    presses it, its rail plus its reach (a left hand: the least), or less it (a right
    hand: the most); None when no place does."""
    rail, reach = nr.of(note)
    xs = rail + reach if side == "left" else rail - reach
    xs = xs[np.isfinite(xs)]
    if not xs.size:
        return None
    return float(xs.min()) if side == "left" else float(xs.max())
