"""The layers of the fingering's programme: the states one event keeps, each reached by
the cheapest transition from a state of the event before.

An event's new notes are struck all, or fewer (a run of them in pitch order) or none,
each note left out costing its frames; held notes are kept (their fingers stay, the rail
too unless they can follow their keys) or cut. Every finger choice for the notes struck,
in the hand's order, and every rail worth a move (``Layers._moves_to``, and
``Layers._keeping``: the places where the notes sounding can ride along) is a transition,
costed by ``planner.play.costs``. A layer keeps, of each hand shape (the rail and the
fingers on the notes sounding), the cheapest state, and of those the ``BEAM`` cheapest
(``_prune``). A transition that cannot beat its shape's best or the beam's last state
(its state before's cost and its tie-breaks: no loss is negative) is not costed, nor
is a move of the arm whose loss's floor cannot (``ArmFloor._arm_floor``).
"""

from __future__ import annotations

import bisect
import itertools
import math
from collections.abc import Sequence

from planner.music import keyboard as kb
from planner.play.armcost import TIE_RAIL_PER_M
from planner.play.costs import (
    TIE_DX_PER_M,
    CostMemo,
    Costs,
    Prev,
    State,
)
from planner.play.places import PLACE_STRIDE, Places
from planner.play.roomcost import RoomCost

THUMB = "thumb"
BEAM = 20  # states kept per event (measured: docs/history/play-second-design.md, "Speed")
PER_RAIL = 6  # ... at most this many at one rail position
# (and one of each hand shape, rail and fingers on the notes sounding: a layer keeps the
# cheapest state of each, so that states that differ only in the notes just let go,
# ``State.recent``, do not crowd out others)
PER_NOTES = 10  # ... and at most this many holding the same notes (so that a state that
# lets a note go, or leaves one out, is not crowded out by the ways of holding it)
BOUND_EVERY = 8  # the beam's cost bound is renewed after this many states before


class _Strike:
    """The new notes of a transition and their fingers (``new``: note -> finger, by
    pitch), with what every state before asks of them, made once per event: their
    ``press_key`` (``Layers._press_key``), the (note, finger) ``items`` by pitch and
    ``by_note``, and the fingers (``busy``)."""

    __slots__ = ("busy", "by_note", "items", "new", "press_key")

    def __init__(self, new: dict[int, str], press_key: tuple) -> None:
        self.new = new
        self.press_key = press_key
        self.items = tuple(new.items())
        self.by_note = tuple(sorted(self.items))
        self.busy = frozenset(new.values())


class Layers(Costs):
    """The layers of one song's programme (``_layer``: one event's states from the
    layer before); the windows over them are ``planner.play.fingering``'s."""

    def __init__(self, notes, places: Places, rate_hz: float,
                 memo: CostMemo | None = None,
                 rail_bounds: Sequence[tuple[float, float]] | None = None,
                 room: RoomCost | None = None) -> None:
        super().__init__(notes, places, rate_hz, memo, rail_bounds)
        self.room = room  # (two hands, the hand planned first: the room it takes costs)
        # (the fingers in the order of their keys: a left hand's thumb is its highest)
        self._order = {f: i for i, f in enumerate(places.hand.fingers_low_to_high)}
        self._bound_at: tuple = (None, 0, math.inf)  # (layer, its size, its bound)
        self._stay_bound: tuple[int, int] = (0, 0)  # (two hands: ``_layer``'s event's)

    def _layer(self, prev, t: float, new: list[int]):
        """The ``BEAM`` cheapest states of one event: striking every note of ``new`` the
        hand can hold at once, or fewer (a run of them in pitch order: one hand's span),
        or none, each note left out costing its frames (a short note given up for a long
        one held through it is the better music, in the frame currency)."""
        new = sorted(new, key=lambda n: self.notes[n].pitch)
        if self.bound is not None:  # (two hands: the event's rail bound, its notes' one,
            # which a hand that strikes none of them must keep too)
            self._stay_bound = self.bound[new[0]]  # (uncut: the hand's rail, any key)
        if self.room is not None:
            self.room.at(t)
        # (by hand shape, the rail and the fingers on the notes sounding: the cheapest
        # state of each, the only one the pruning can keep; (cost, state before, state))
        layer: dict[tuple, tuple[float, State | None, State]] = {}
        for size in range(min(len(new), len(self.places.hand.fingers)), -1, -1):
            for i in range(len(new) - size + 1):
                sub = new[i:i + size]
                left_out = sum(self.frames(n) if self.room is None
                               else self.room.left_out(n, self.frames(n))
                               for n in new if n not in sub)
                self._extend(layer, prev, t, sub, left_out)
        if not layer and self.bound is not None and prev:  # (no state keeps the bound:
            # the hand stays where it is rather than the programme lose its path)
            self._stay_bound = (-PLACE_STRIDE, PLACE_STRIDE)
            self._extend(layer, prev, t, [], sum(self.frames(n) for n in new))
        return _prune(layer)

    def _extend(self, layer, prev, t: float, new: list[int], left_out: float = 0.0) -> None:
        fingers = self.places.hand.fingers_low_to_high
        new = sorted(new, key=lambda n: self.pitch[n])
        offset = self.offset
        starts = prev.items() if prev else [(None, (0.0, None))]
        bound = math.inf  # the beam's cost bound of the layer being made
        assign: dict[frozenset, list] = {}  # by the fingers holding kept notes
        for i, (p, (cost, _)) in enumerate(starts):
            cost += left_out
            # (the states before come cheapest first, and no step costs less than
            # nothing: once ``BEAM`` states are cheaper than this one's cost, no state
            # it leads to is kept, nor are those of the states after it)
            if i % BOUND_EVERY == 0:
                bound = self._beam_bound(layer)
            if cost > bound:
                break
            ctx = None if p is None else self.prev(p, t)
            held = [] if p is None else ctx.held
            for k in range(len(held), -1, -1):
                for kept in itertools.combinations(held, k):
                    cut = sum(offset[m] - t for m, _ in held
                              if (m, _) not in kept) / self.dt
                    busy = frozenset(f for _, f in kept)
                    got = assign.get(busy)
                    if got is None:  # (the new notes' fingers, once per event and kept
                        # fingers: their press keys, as items by pitch and by note, and the
                        # fingers)
                        free = [f for f in fingers if f not in busy]
                        got = assign[busy] = [_Strike(d, self._press_key(d)) for d in (
                            dict(zip(new, combo))
                            for combo in itertools.combinations(free, len(new)))]
                    for d in got:
                        self._try(layer, ctx, cost + cut, bound, kept, d)

    def _beam_bound(self, layer) -> float:
        """The cost of the last state ``_prune`` keeps of ``layer`` (inf when it keeps
        fewer than ``BEAM``), worked out again only when the layer has grown since (a
        state made cheaper in place only lowers it: the bound kept is safe)."""
        if len(layer) < BEAM:
            return math.inf
        if self._bound_at[0] is not layer or self._bound_at[1] != len(layer):
            kept = _prune(layer)
            bound = max(v[0] for v in kept.values()) if len(kept) == BEAM else math.inf
            self._bound_at = (layer, len(layer), bound)
        return self._bound_at[2]

    def _try(self, layer, ctx: Prev | None, cost: float, bound: float, kept,
             strike: _Strike) -> None:
        """Every transition from ``ctx`` (its cost so far ``cost``) that strikes
        ``strike.new`` (note -> finger) and keeps ``kept`` held, into ``layer``; none
        costing more than ``bound``, the beam's (no such state is kept)."""
        new = strike.new
        if kept:
            order_of, pitch = self._order, self.pitch
            sounding = sorted([*kept, *strike.items], key=lambda mf: pitch[mf[0]])
            order = [order_of[f] for _, f in sounding]
            if any(b <= a for a, b in itertools.pairwise(order)):
                return
            sounding_t = tuple(sorted(sounding))
            busy = None
        else:  # (the new notes' fingers are in the hand's order, as their pitches)
            sounding, sounding_t, busy = strike.items, strike.by_note, strike.busy
        p = None if ctx is None else ctx.state
        if not new:  # (every new note left out: the hand stays)
            if p is None or self.bound is not None and not (
                    self._stay_bound[0] <= self.places.rail_i(p.place) <= self._stay_bound[1]):
                return
            rails = [(p.place, 0.0)]
        else:  # (``_moves_to``'s memo read here: most calls find it)
            rails = self._rails_to.get((strike.press_key, None if p is None else p.place))
            if rails is None:
                rails = self._moves_to(new, strike.press_key, p)
            if p is not None and p.fingers:  # (and the places the notes sounding can
                # ride to)
                rails = self._keeping(new, strike, p, rails)
        if p is None:  # (the song's first notes: from anywhere, no move lost)
            for place, tie in rails:
                total, shape = cost + tie, (place, sounding_t)
                if self.room is not None:
                    total += self.room.frames(place, sounding_t)
                old = layer.get(shape)
                if total <= bound and (old is None or total < old[0]):
                    layer[shape] = (total, None, State(place, sounding_t))
            return
        here, steps = p.place, ctx.steps
        crossing = recent = None
        for place, tie in rails:
            # (the pruning keeps one state per shape, the cheapest: a transition that
            # cannot cost less than the cheapest state of its shape so far is not weighed,
            # nor one that cannot cost less than the beam's last state)
            tie_rail = TIE_RAIL_PER_M * self.places.distance_m(place, here)
            low = cost + tie + tie_rail
            shape = (place, sounding_t)
            old = layer.get(shape)
            if low > bound or old is not None and low > old[0]:
                continue
            if busy is None:
                busy = frozenset(f for _, f in sounding)
            if place == here:
                if crossing is None:
                    crossing = self._crosses(ctx, sounding, busy)
                if crossing:
                    continue
            key = (sounding_t, place, kept)
            got = steps.get(key)
            if got is None:  # (``ArmCosts._step``; None: ruled out, ``ArmFloor._arm_floor``)
                got = self._step(ctx, new, place, kept, (
                    bound if old is None else min(bound, old[0])) - (cost + tie), tie_rail)
                if got is None:
                    continue
                steps[key] = got
            step = got[0]
            total = cost + step + tie
            if self.room is not None:
                total += self.room.frames(place, sounding_t, p)
            if step == math.inf or total > bound:  # (inf: no move gets there)
                continue
            if old is None or total < old[0]:
                if recent is None:
                    recent = self._recent(ctx, busy)
                s = State(place, sounding_t, rode_to(recent[0], got[2], place), got[1],
                          tuple((m, end_s) for m, _, end_s in got[2]),
                          rode_to(recent[1], got[2], place))
                if old is not None and old[2] != s:
                    del layer[shape]  # (another state of the shape: it comes after)
                layer[shape] = (total, p, s)

    def _crosses(self, ctx: Prev, sounding, busy: set[str]) -> bool:
        """Whether the fingers sounding, with those that left their keys within
        RECENT_S (still over them), are out of the hand's order: a finger would cross
        another without moving the rail."""
        order_of, pitch, place = self._order, self.pitch, ctx.state.place
        left = [(m, f) for m, f, r in ctx.fresh if f not in busy and r == place]
        near = sorted([*sounding, *left], key=lambda mf: pitch[mf[0]])
        # (the thumb on a white key presses in front of the black keys, 30 mm and more
        # before the long fingers' tips: they pass behind it, it passes under them)
        order_near = [order_of[f] for m, f in near
                      if not (f == THUMB and not kb.is_black(pitch[m]))]
        return any(b <= a for a, b in itertools.pairwise(order_near))

    def _moves_to(self, new: dict[int, str], press_key: tuple,
                  p: State | None) -> list[tuple[int, float]]:
        """The places worth a transition from ``p`` (memoised per place before): staying,
        when the new notes can be played from there; else, of the moves in each posture,
        the shortest one each way and the one with the fingers nearest their natural places (a longer move
        to a place no better for the fingers is never cheaper: the arm's time grows with
        the distance, the fingers' lifts and descents do not change)."""
        key = (press_key, None if p is None else p.place)
        keep = self._rails_to.get(key)
        if keep is None:
            cands = self._candidates(new, press_key)
            if p is None or len(cands) <= 3:
                keep = cands
            else:
                keep = _nearest_and_best(self.places, cands, p.place,
                                         self._cand_rails[press_key])
            self._rails_to[key] = keep
        return keep

    def _keeping(self, new: dict[int, str], strike: _Strike, p: State,
                 rails: list[tuple[int, float]]) -> list[tuple[int, float]]:
        """``rails`` (``_moves_to``'s places) and the places to which the notes sounding
        in ``p`` whose fingers strike none of ``new`` can ride along on the arm's move
        (their fingers have their keys there too): for each such note and for all of them,
        in each posture, the nearest places each way and the best for the fingers, as
        ``_moves_to`` chooses (memoised per keys, fingers and place before).
        ``_moves_to`` picks its moves by the new notes alone, for which a longer move is
        never cheaper; it is where it lets a key sounding stay down to its end (or past
        the event, held) instead of coming up before the move."""
        pitch, force = self.pitch, self.force
        riders = tuple([(m, f) for m, f in p.fingers if f not in strike.busy])
        if not riders:
            return rails
        sig = tuple([(pitch[m], force[m], f) for m, f in riders])
        key = (strike.press_key, p.place, sig)
        got = self._keep_to.get(key)
        if got is None:
            got = list(rails)
            groups = [(riders, sig)] + ([((r,), (s,)) for r, s in zip(riders, sig)]
                                        if len(riders) > 1 else [])
            for group, group_sig in groups:
                # (the candidates where the group's notes have their keys too, and their
                # index: by the new notes' and the group's keys, forces and fingers)
                gkey = (strike.press_key, group_sig)
                sub = self._keep_cands.get(gkey)
                if sub is None:
                    ok = None
                    for m, f in group:
                        r = self.rails(f, m)
                        ok = r if ok is None else ok & r
                    sub = [c for c in self._candidates(new, strike.press_key) if c[0] in ok]
                    sub = self._keep_cands[gkey] = (sub, _index(self.places, sub))
                got += [c for c in _nearest_and_best(self.places, sub[0], p.place, sub[1])
                        if c not in got]
            self._keep_to[key] = got
        return got

    def _candidates(self, new: dict[int, str], key: tuple) -> list[tuple[int, float]]:
        """(place, tie-break) of every place from which the fingers of
        ``new`` press their notes (memoised by ``key``, their keys, forces and fingers:
        it does not depend on the state before)."""
        out = self._cands.get(key)
        if out is None:
            rails = None
            for n, f in new.items():
                r = self.rails(f, n)
                rails = r if rails is None else rails & r
            out = []
            for place in sorted(rails):
                tie = sum(abs(self.entry(n, f, place).dx_m - self.places.natural_dx[f])
                          for n, f in new.items()) * TIE_DX_PER_M
                out.append((place, tie))
            self._cands[key] = out
            self._cand_rails[key] = _index(self.places, out)
        return out

    def _press_key(self, new: dict[int, str]) -> tuple:
        """What the rails that press ``new`` depend on: each note's key and force, and its
        finger."""
        pitch, force = self.pitch, self.force
        if self.bound is not None:  # (two hands: and each note's rail bound, if it cuts)
            nb = self.note_bound
            return tuple((pitch[n], force[n], f) if nb(n) is None else
                         (pitch[n], force[n], f, nb(n)) for n, f in new.items())
        return tuple((pitch[n], force[n], f) for n, f in new.items())

    @staticmethod
    def _recent(ctx: Prev, busy: frozenset[str]) -> tuple[tuple, tuple]:
        """``State.recent`` and ``State.older`` after: the last notes of the fingers not
        sounding now (``busy``: those sounding), ended within RECENT_S of the event (a
        note of the state before that is not sounding now has just ended), and those
        ended before, with the rail they were pressed from (memoised per state before
        and fingers sounding)."""
        got = ctx.recent.get(busy)
        if got is None:
            last: dict[str, tuple[int, int]] = {}
            for m, f, r in ctx.fresh:
                if f not in busy:
                    last[f] = (m, r)
            older = {f: mr for f, mr in (*ctx.older.items(), *ctx.last.items())
                     if f not in busy and f not in last}
            got = ctx.recent[busy] = (
                tuple(sorted((m, f, r) for f, (m, r) in last.items())),
                tuple(sorted((m, f, r) for f, (m, r) in older.items())))
        return got


def rode_to(recent: tuple, rode: tuple, place: int) -> tuple:
    """``State.recent`` after a move to ``place`` on which the notes ``rode`` ((note,
    finger, the move's end)) rode along: their fingers are over their keys from there
    now, as the motion carried them (``ArmMotion._move_rail``), not where they were
    struck."""
    if not rode:
        return recent
    moved = {(m, f) for m, f, _ in rode}
    return tuple(sorted((m, f, place if (m, f) in moved else r) for m, f, r in recent))


def _nearest_and_best(places: Places, cands: list[tuple[int, float]], here: int,
                      index: tuple | None = None) -> list[tuple[int, float]]:
    """Of ``cands`` ((place, tie-break), by place), in each posture: the place at
    ``here``'s rail index, the nearest below and above it (found by bisection), and the
    one of least tie-break (the fingers nearest their natural places). ``index``: the
    candidates' places and each posture's best, when made already (``_candidates``)."""
    rails, bests = _index(places, cands) if index is None else index
    out: list[tuple[int, float]] = []
    for q in sorted(bests, key=lambda q: q != places.posture_of(here)):
        at = places.place(q, places.rail_i(here))
        i = bisect.bisect_left(rails, at)
        j = i + 1 if i < len(rails) and rails[i] == at else i
        out += [c for c in cands[i:j] + cands[max(0, i - 1):i] + cands[j:j + 1]
                if places.posture_of(c[0]) == q and c not in out]
        if bests[q] not in out:
            out.append(bests[q])
    return out


def _index(places: Places, cands: list[tuple[int, float]]) -> tuple[list[int], dict]:
    """``_nearest_and_best``'s index of ``cands`` ((place, tie-break), by place): their
    places, and each posture's best (least tie-break, the first of equals), by posture."""
    bests: dict[int, tuple[int, float]] = {}
    for c in cands:
        q = places.posture_of(c[0])
        if q not in bests or c[1] < bests[q][1]:
            bests[q] = c
    return [c[0] for c in cands], bests


def _prune(layer):
    """The ``BEAM`` cheapest states of ``layer`` (the cheapest of each hand shape), at
    most ``PER_RAIL`` of them at one rail position (so that the programme keeps other
    hand positions in view); of those holding the same notes at most ``PER_NOTES`` while
    states holding other notes (a held note let go, a note left out) are there to fill
    the beam. As {state: (cost, state before)}, cheapest first."""
    ranked = sorted(layer.values(), key=_cost)
    out, per, sets = {}, {}, {}
    capped = []  # (skipped for their notes only: the second pass's candidates, in order)
    for v in ranked:  # (one state per shape: every state is new to ``out``)
        s = v[2]
        place = s.place
        if per.get(place, 0) >= PER_RAIL:  # (a rail's count only grows: out for good)
            continue
        notes = s.notes
        if sets.get(notes, 0) >= PER_NOTES:
            capped.append(v)
            continue
        out[s] = (v[0], v[1])
        per[place] = per.get(place, 0) + 1
        sets[notes] = sets.get(notes, 0) + 1
        if len(out) == BEAM:  # (added in cost order: sorted)
            return out
    for v in capped:
        s = v[2]
        if per.get(s.place, 0) < PER_RAIL:
            out[s] = (v[0], v[1])
            per[s.place] = per.get(s.place, 0) + 1
            if len(out) == BEAM:
                break
    return dict(sorted(out.items(), key=lambda kv: kv[1][0]))


def _cost(v) -> float:
    return v[0]
