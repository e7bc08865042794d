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
frames of music each way plays (``plan_two_hands``; each order also with the first
hand's room settled: ``plan_pass``); the best ways are then planned once more with the
notes their second hand left out handed back to the first (``hand_back``).

The bounds: ``planner.play.twobounds``; the rows on one clock and the file:
``planner.play.twoplan``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace

from planner.errors import InputError
from planner.hand.model import HandModel
from planner.music.midi import Song
from planner.play.costs import Costs, SkipReason
from planner.play.handclear import MAX_ROUNDS, NoteReaches, PlaceReach, collided_notes, loose_bound
from planner.play.handgap import HandGap, HandReach, InnerEdge, hand_gap, pose_extents
from planner.play.hands import LEFT, RIGHT, SIDES, HandAssignment, assign_hands, other_side
from planner.play.stream import Planner, PlayPlan, plan_song
from planner.play.twobounds import (
    UNBOUNDED_M,
    FirstEdge,
    clear_bounds,
    clear_limits,
    first_edge,
    room_cost,
    room_settled,
    settled_bounds,
    windows,
)
from planner.play.twoplan import (
    PairRows,
    PlanReads,
    SecondPlans,
    TwoHandPlan,
    one_clock,
    write_two_hands,
)
from planner.play.twoscore import PairScorer


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
        self.edges = {s: InnerEdge(h) for s, h in self.hands.items()}
        # (every pose each hand plays in, measured once: the pair's gap and each place's
        # own reach towards the other hand, the second hand's loosened rule)
        ext = {s: pose_extents(self.planners[s].places, self.edges[s]) for s in SIDES}
        self.gap: HandGap = hand_gap(self.planners[LEFT].places, self.planners[RIGHT].places,
                                     extents=(ext[LEFT], ext[RIGHT]))
        self.place_reach = {s: PlaceReach(self.planners[s].places, self.edges[s], ext[s])
                            for s in SIDES}
        # (each plan's rows read once while a pair is planned: ``plan_two_hands`` lets
        # them go when it is done)
        self.reads = PlanReads()
        self.seconds = SecondPlans()  # (the second hands' plans, by what they are planned from)
        self.scorer = PairScorer(left, right)  # (the check's frame F1 of a way's rows)

    def reach(self, side: str) -> HandReach:
        """``side``'s ``HandReach`` (of the pair's ``HandGap``)."""
        return self.gap.left if side == LEFT else self.gap.right


def _sub_song(song: Song, idx: tuple[int, ...]) -> Song:
    return replace(song, notes=tuple(song.notes[i] for i in idx), part=None)


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
    settled: bool = False  # the first hand's room settled (``plan_pass``)

    @property
    def way(self) -> str:
        """How it was planned: ``right first``, ``left first``, or ``right alone`` (the
        other hand given only the notes the first one left out); `` settled``: the first
        hand's room settled (``plan_pass``); `` back``: then the first hand planned again
        with the notes the second left out (``hand_back``)."""
        return (f"{self.first} {'alone' if self.alone else 'first'}"
                f"{' settled' if self.settled else ''}{' back' if self.back else ''}")

    def skipped_for(self, reason: SkipReason) -> list[tuple[int, object]]:
        """(song index, ``Skip``) of every note a plan left out for ``reason`` (the notes
        handed over too)."""
        return [(idx[s.note], s) for idx, p in zip(self.planned_of, self.plans)
                for s in p.verdict.skipped if s.reason is reason]


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
    (``planner.play.handclear``); the plan playing more frames kept (the first of equals).
    Planned once for the same inputs while a pair is planned (``PairPlanner.seconds``:
    ``SecondPlans``; ``edge`` is ``first``'s rows')."""
    key = (side, idx, rate_hz, song_name, song.notes)
    made = pp.seconds.get(key, first)
    if made is None:
        made = _plan_second_anew(song, pp, side, idx, sub, first, edge, rate_hz, song_name)
        pp.seconds.put(key, first, made)
    return made


def _plan_second_anew(song: Song, pp: PairPlanner, side: str, idx: tuple[int, ...], sub: Song,
                      first: PlayPlan, edge: FirstEdge, rate_hz: float, song_name: str
                      ) -> PlayPlan:
    """``_plan_second``'s plan, planned."""
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
        rows = one_clock((plan, first) if side == LEFT else (first, plan), rate_hz, pp.reads)
        hit = collided_notes(rows.t_s, rows.q[0], rows.q[1],
                             (pp.edges[LEFT], pp.edges[RIGHT]), rows.song_start_s,
                             windows(notes, idx, got["out"]), dt, c)
        if hit is not None and not hit:
            return plan
        if hit is None or hit <= back:
            return None
        back |= hit
    return None


def settled_room(song: Song, pp: PairPlanner, a: HandAssignment, first: str, rate_hz: float
                 ) -> tuple[list[tuple[float, float]], frozenset[int]]:
    """The room bounds of the hand ``first`` by ``a``, settled, and the notes they take
    out (positions in its notes: ``twobounds.room_settled``)."""
    second = other_side(first)
    own = a.notes_of(first)
    return room_settled(song, pp, first, own, a.notes_of(second), _sub_song(song, own),
                        rate_hz)


def plan_pass(song: Song, pp: PairPlanner, a: HandAssignment, first: str, rate_hz: float,
              song_name: str = "", settled: bool = False,
              room: tuple[list[tuple[float, float]], frozenset[int]] | None = None
              ) -> PairPass:
    """Plan both hands by ``a``: the hand ``first`` leaving the other room for its notes
    (``room_bounds``), then the other within the first one's rows (``clear_bounds``,
    settled: ``settled_bounds``), its notes and every note the first one left out (the
    second hand's programme weighs them in the same frames as its own: a note it cannot
    play is left out again, one it plays instead of its own costs it fewer frames).
    ``settled``: the first hand's room settled too (``twobounds.room_settled``: where a
    note of its own has no place within its room, it stands where it was until its next
    note, and leaves the other hand its room, and is charged for it, all that time).
    ``room``: that room (``settled_room``'s bounds and notes out) when found already."""
    notes = song.notes
    idx = {s: a.notes_of(s) for s in SIDES}
    subs = {s: _sub_song(song, idx[s]) for s in SIDES}
    second = other_side(first)
    plans: dict[str, PlayPlan] = {}
    # (the first hand's bound leaves the other room; it keeps no clearance itself, the
    # second hand's bound does: its windows are its notes' own, none taken out)
    bounds, out = room or room_settled(song, pp, first, idx[first], idx[second], subs[first],
                                       rate_hz, settled)
    # (and pays, in frames, for the room it takes from the other hand's notes and from
    # those it hands over: ``planner.play.roomcost``; a hand planned alone is planned as
    # one hand plays the file, the way that bounds a pair's loss against one hand)
    cost = (room_cost(song, pp, first, idx[first], idx[second], rate_hz, out)
            if idx[second] else None)
    plans[first] = plan_song(subs[first], pp.hands[first], None, rate_hz, song_name=song_name,
                             planner=pp.planners[first], rail_bounds=bounds, room=cost)
    given = {idx[first][s.note]: f"{s.reason.value}: {s.detail}"
             for s in plans[first].verdict.skipped}
    planned = {first: idx[first], second: tuple(sorted(set(idx[second]) | set(given)))}
    subs[second] = _sub_song(song, planned[second])
    edge = first_edge(plans[first], pp.hands[first], pp.edges[first], first, pp.reads)
    plans[second] = _plan_second(song, pp, second, planned[second], subs[second], plans[first],
                                 edge, rate_hz, song_name)
    played = sum(_played_frames(plans[s], planned[s], notes, rate_hz) for s in SIDES)
    a = a.hand_over(given, second)
    return PairPass(a, first, (plans[LEFT], plans[RIGHT]), (a.notes_of(LEFT), a.notes_of(RIGHT)),
                    float(played), (planned[LEFT], planned[RIGHT]), not idx[second],
                    settled=settled)


def hand_back(song: Song, pp: PairPlanner, p: PairPass, rate_hz: float,
              song_name: str = "") -> PairPass | None:
    """``p`` with the notes its second hand left out handed back to the first: the first
    hand planned again, its notes but those the second plays and with those, within the
    second one's rows as they are (``_plan_second``: the same rule the second kept from
    the first one's rows, so the pair keeps its clearance; the second's plan is
    unchanged). None when the second hand left nothing out."""
    first, second = p.first, other_side(p.first)
    f, s = SIDES.index(first), SIDES.index(second)
    gone = {p.planned_of[s][k.note] for k in p.plans[s].verdict.skipped}
    if not gone:
        return None
    plays = set(p.planned_of[s]) - gone
    idx = tuple(sorted((set(p.planned_of[f]) - plays) | gone))
    sub = _sub_song(song, idx)
    edge = first_edge(p.plans[s], pp.hands[second], pp.edges[second], second, pp.reads)
    again = _plan_second(song, pp, first, idx, sub, p.plans[s], edge, rate_hz, song_name)
    plans = {first: again, second: p.plans[s]}
    planned = {first: idx, second: p.planned_of[s]}
    a = p.assignment.hand_over({i: _why(p, i) for i in idx if p.assignment.hand[i] != first},
                               first)
    played = sum(_played_frames(plans[x], planned[x], song.notes, rate_hz) for x in SIDES)
    return PairPass(a, first, (plans[LEFT], plans[RIGHT]), (a.notes_of(LEFT), a.notes_of(RIGHT)),
                    float(played), (planned[LEFT], planned[RIGHT]), p.alone, True, p.settled)


def back_ceiling(song: Song, p: PairPass, rate_hz: float) -> float:
    """The most frames ``hand_back`` of ``p`` could play: the second hand's played notes
    (its plan unchanged) and every note the first is planned with again, all played."""
    f, s = SIDES.index(p.first), 1 - SIDES.index(p.first)
    gone = {p.planned_of[s][k.note] for k in p.plans[s].verdict.skipped}
    plays = set(p.planned_of[s]) - gone
    again = (set(p.planned_of[f]) - plays) | gone
    return float(_played_frames(p.plans[s], p.planned_of[s], song.notes, rate_hz)
                 + sum(round(song.notes[i].duration_s * rate_hz) for i in again))


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
    it leaves out. Every way hands the notes its first hand leaves out to the other.
    Each order is planned with its first hand's room settled too, where that takes a
    note out (``_both_rooms``). The best of the three ways and the best of all are each
    handed back (``hand_back``); the pass playing the most frames of music is kept (the
    earlier of equals, the three ways first). (A hand with no notes plans nothing the
    order could change.)"""
    if not (math.isfinite(rate_hz) and 1.0 <= rate_hz <= 10000.0):
        raise InputError(f"--rate must be between 1 and 10000 Hz, got {rate_hz}")
    t_start = time.perf_counter()
    pp.reads.clear()
    pp.seconds.clear()
    pp.scorer.clear()
    try:
        return _plan_two_hands(song, pp, out_path, rate_hz, song_name, t_start)
    finally:
        pp.reads.clear()
        pp.seconds.clear()
        pp.scorer.clear()


def _both_rooms(song: Song, pp: PairPlanner, a: HandAssignment, first: str, rate_hz: float,
                song_name: str) -> list[PairPass]:
    """The passes with ``first`` planned first: its room as the windows of its notes give
    it, and, where that differs (a note of its own no place plays within its room: the
    hand stands through it), its room settled (``plan_pass``). Neither is always better:
    the settled room leaves the other hand the keys the first one stands over, at the
    cost of the first hand's notes near them (random two-hand songs and the two-hand
    corpus: ``docs/history/2026-12-07-two-hands9.md``)."""
    got = [plan_pass(song, pp, a, first, rate_hz, song_name)]
    if a.notes_of(other_side(first)):
        room = settled_room(song, pp, a, first, rate_hz)
        if room[1]:
            got.append(plan_pass(song, pp, a, first, rate_hz, song_name, settled=True,
                                 room=room))
    return got


def by_check(song: Song, pp: PairPlanner, finals: list[PairPass], rate_hz: float
              ) -> tuple[PairPass, PairRows]:
    """Of the final ways (the best ways and their hand-backs), the one whose pair of rows
    the check scores highest (``PairScorer.frame_f1``: both hands' keys as one, against
    the whole song), and its rows; equals by the frames of music played, then the
    earlier. One way: no replay."""
    if len(finals) == 1:
        return finals[0], one_clock(finals[0].plans, rate_hz, pp.reads)
    got = [((pp.scorer.plans_f1(p.plans, song, rate_hz, pp.reads), p.played_frames, -k), p)
           for k, p in enumerate(finals)]
    best = max(got, key=lambda g: g[0])[1]
    return best, one_clock(best.plans, rate_hz, pp.reads)


def _plan_two_hands(song: Song, pp: PairPlanner, out_path: str | None, rate_hz: float,
                    song_name: str, t_start: float) -> TwoHandPlan:
    """``plan_two_hands`` after its input's check (``t_start``: its clock's start)."""
    places = {s: pp.planners[s].places for s in SIDES}
    a = assign_hands(song.notes, pp.gap, places, rate_hz)
    rf = _both_rooms(song, pp, a, RIGHT, rate_hz, song_name)
    plain, settled = [rf[0]], rf[1:]
    if all(a.notes_of(s) for s in SIDES):
        if any(p.skipped_for(SkipReason.OTHER_HAND) for p in rf):
            lf = _both_rooms(song, pp, a, LEFT, rate_hz, song_name)
            plain.append(lf[0])
            settled += lf[1:]
        plain.append(plan_pass(song, pp, a.one_hand(RIGHT), RIGHT, rate_hz, song_name))
    tried = plain + settled
    # (the best way of the windows' room and the best of all, each then handed back: a
    # way is judged after its hand-back, and the settled ways never push out the way
    # the windows' room keeps; max keeps the first of equals)
    tops = [max(plain, key=lambda p: p.played_frames)]
    if settled:
        top = max(tried, key=lambda p: p.played_frames)
        tops += [top] if top is not tops[0] else []
    # (then every other way whose hand-back could play more than the most frames yet:
    # ways a few frames apart before their hand-backs can be hundreds apart after)
    finals = list(tops)
    bar = max(p.played_frames for p in tried)
    rest = sorted((p for p in tried if all(p is not t for t in tops)),
                  key=lambda p: -p.played_frames)
    for top in tops + rest:
        if all(top is not t for t in tops) and back_ceiling(song, top, rate_hz) <= bar:
            continue
        back = hand_back(song, pp, top, rate_hz, song_name)
        if back is not None:
            tried.append(back)
            finals += [back] + ([] if any(top is f for f in finals) else [top])
            bar = max(bar, back.played_frames)
    best, rows = by_check(song, pp, finals, rate_hz)
    least = float((rows.q[1][:, pp.hands[RIGHT].index["rail"]]
                   - rows.q[0][:, pp.hands[LEFT].index["rail"]]).min())
    plan = TwoHandPlan(best.assignment, pp.gap, best.plans, best.notes_of, rows, 0.0, least,
                       first=best.first,
                       tried=tuple((p.way, p.played_frames) for p in tried),
                       planned_of=best.planned_of, way=best.way)
    text = write_two_hands(plan, song, pp, out_path, rate_hz, song_name)
    return replace(plan, planning_s=time.perf_counter() - t_start, text=text)


