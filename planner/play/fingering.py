"""Fingering and hand positions as one dynamic programme over atlas states.

The song is cut at its onsets (events). At each event the hand is in a state
(``planner.play.costs.State``): a rail position and a finger for every note sounding
then (the new ones and those still held). A state exists only where the atlas has every
one of those fingers over its key from that rail, pressing with the note's force within
the motors' torque (``AtlasEntry.max_force_n``), the fingers in the order of their keys,
one note per finger; no finger passes one that has just played (the thumb on a white key
excepted: it presses in front of the black keys). A held note keeps its finger, and the
rail unless its finger can follow its key, or is cut at the event. Transitions cost what
``planner.play.costs`` says.

A state may also strike fewer of an event's new notes (a run of them in pitch order) or
none, each note left out costing its frames: more notes than fingers or a chord wider
than the hand (``CHORD``), a short note whose finger would have to let go of a long note
held through it (``HELD``: a tie held under a melody), a note the moves reach too late
to be worth its frames (``TOO_LATE``). The ``BEAM`` best states of each event go on (at most ``PER_RAIL`` at one
rail position, one of each hand shape), over a receding window (``chunks``).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

from planner.music import keyboard as kb
from planner.music.midi import pitch_name
from planner.play.atlas import Atlas
from planner.play.costs import (
    ONSET_TOL_S,
    RAIL_STEP_M,
    TIE_DX_PER_M,
    TIE_RAIL_PER_M,
    CostMemo,
    Costs,
    Prev,
    Skip,
    SkipReason,
    State,
)
from planner.play.moves import Moves

THUMB = "thumb"
BEAM = 20  # states kept per event (measured: docs/play-second-design.md, "Speed")
WINDOW = 48  # events the programme looks over at once ...
LOOKAHEAD = 16  # ... the last of which it decides only in the next window
FIRST_WINDOW, FIRST_LOOKAHEAD = 16, 8  # the first window is short: the rows start sooner
# (shorter ones were tried: docs/play-second-design.md, "Speed ... session 21", item 3)
PER_RAIL = 6  # ... at most this many at one rail position
# (and one of each hand shape, rail and fingers on the notes sounding: a layer keeps the
# cheapest state of each, so that states that differ only in the notes just let go,
# ``State.recent``, do not crowd out others)
PER_NOTES = 10  # ... and at most this many holding the same notes (so that a state that
# lets a note go, or leaves one out, is not crowded out by the ways of holding it)
BOUND_EVERY = 8  # the beam's cost bound is renewed after this many states before
_PER_STEP = TIE_RAIL_PER_M * RAIL_STEP_M  # a move's tie-break, per step of the rail grid


@dataclass(frozen=True)
class Assignment:
    """A note played by ``finger`` with the rail at ``rail_m``; ``release_s`` is when a
    held note is cut (a later event needs its finger or the hand), else None."""

    note: int
    finger: str
    rail_m: float
    release_s: float | None = None




@dataclass(frozen=True)
class Fingering:
    """The programme's answer: a finger and a rail position for every note played, the
    notes left out, and the frames its model expects to lose."""

    assignments: tuple[Assignment, ...]
    skipped: tuple[Skip, ...]
    expected_loss_frames: float


@dataclass(frozen=True)
class FingeringChunk:
    """A stretch of the answer, fixed: notes struck in it, notes left out, held notes
    (struck in it or before) cut at a time, and the loss the model expects so far. Every
    note starting before ``until_s`` is decided (inf: the song's last chunk)."""

    assignments: tuple[Assignment, ...]
    skipped: tuple[Skip, ...]
    cuts: tuple[tuple[int, float], ...]
    loss_frames: float
    until_s: float = math.inf



def events(notes) -> list[tuple[float, list[int]]]:
    """(time, indices of the notes starting then), in time order."""
    order = sorted(range(len(notes)), key=lambda i: (notes[i].onset_s, notes[i].pitch))
    out: list[tuple[float, list[int]]] = []
    for i in order:
        if out and notes[i].onset_s - out[-1][0] <= ONSET_TOL_S:
            out[-1][1].append(i)
        else:
            out.append((notes[i].onset_s, [i]))
    return out


class FingeringProblem(Costs):
    """The programme for one song on one hand (built, then ``solve``d or streamed in
    ``chunks``); its costs are ``Costs``'."""

    def __init__(self, notes, atlas: Atlas, moves: Moves, rate_hz: float,
                 memo: CostMemo | None = None) -> None:
        super().__init__(notes, atlas, moves, rate_hz, memo)
        self._order = {f: i for i, f in enumerate(atlas.hand.fingers)}
        self._bound = math.inf  # the beam's cost bound of the layer being made
        self._bound_at: tuple = (None, 0, math.inf)  # (layer, its size, its bound)

    def solve(self) -> Fingering:
        """The whole song's answer (the chunks of ``chunks`` put together)."""
        out: dict[int, Assignment] = {}
        skipped: list[Skip] = []
        loss = 0.0
        for ch in self.chunks():
            out.update({x.note: x for x in ch.assignments})
            for n, t in ch.cuts:
                a = out[n]
                out[n] = Assignment(a.note, a.finger, a.rail_m, t)
            skipped.extend(ch.skipped)
            loss = ch.loss_frames
        return Fingering(tuple(out[n] for n in sorted(out)),
                         tuple(sorted(skipped, key=lambda s: s.note)), loss)

    def chunks(self):
        """The programme over a receding window: the best path over the next ``WINDOW``
        events (``FIRST_WINDOW`` at the start) decides its first ones (all but
        ``LOOKAHEAD``), which are yielded (``FingeringChunk``, with the notes no state can
        play that start before the next event) and fixed; the next window starts from the
        state it reached. Events are read as the windows need them, so the motion and the
        rows can start after the first window, not the song."""
        source = self._events()
        ahead_evs: list[tuple[float, list[int]]] = []  # playable events not decided yet
        skips: list[tuple[float, Skip]] = []  # notes no state plays, not yet yielded
        done, first, loss = False, True, 0.0
        start: dict[State, tuple[float, State | None]] = {}
        while True:
            window, ahead = (FIRST_WINDOW, FIRST_LOOKAHEAD) if first else (WINDOW, LOOKAHEAD)
            while not done and len(ahead_evs) <= window:  # (one more: the next event's time)
                got = next(source, None)
                if got is None:
                    done = True
                else:
                    skips.extend((got[0], s) for s in got[2])
                    if got[1]:
                        ahead_evs.append(got[:2])
                    elif not ahead_evs and len(skips) >= WINDOW:  # (a long stretch no state
                        # plays: it is decided up to its last onset, the rows can go on)
                        yield FingeringChunk((), tuple(s for _, s in skips), (), loss, got[0])
                        skips = []
            if not ahead_evs:
                break
            layers, prev = [], start
            for t, new in ahead_evs[:window]:
                prev = self._layer(prev, t, new)
                layers.append((t, prev, new))
            k = len(layers) if done and len(ahead_evs) <= window else max(1, len(layers) - ahead)
            path = self._path(layers)
            until = ahead_evs[k][0] if k < len(ahead_evs) else math.inf
            mine = tuple(s for t, s in skips if t < until)
            skips = [(t, s) for t, s in skips if t >= until]
            ch = self._chunk(layers[:k], path[:k], next(iter(start)) if start else None)
            loss = ch.loss_frames
            yield FingeringChunk(ch.assignments, mine + ch.skipped, ch.cuts, loss, until)
            last = path[k - 1]
            start = {last: (layers[k - 1][1][last][0], None)}
            del ahead_evs[:k]
            first = False
            self.forget(ahead_evs[0][0] if ahead_evs else math.inf)
        if skips:
            yield FingeringChunk((), tuple(s for _, s in skips), (), loss)

    def _events(self):
        """(time, playable notes, ``Skip`` of the others) of every onset, in time order."""
        for t, new in events(self.notes):
            playable, skipped = [], []
            for n in new:
                why = self.reason(n)
                if why is None:
                    playable.append(n)
                else:
                    skipped.append(why)
            yield t, playable, skipped

    def _path(self, layers) -> list[State]:
        """The best path through a window's layers, one state per layer."""
        state = min(layers[-1][1].items(), key=lambda kv: kv[1][0])[0]
        out = [state]
        for _, layer, _ in reversed(layers[1:]):
            state = layer[state][1]
            out.append(state)
        return out[::-1]

    def _chunk(self, layers, path: list[State], before: State | None) -> FingeringChunk:
        """What a committed stretch of the path says: the notes struck in it (finger, rail
        at their first state), the chord notes left out, the held notes cut (at the event
        whose state no longer holds them)."""
        assignments, skipped, cuts = [], [], []
        seen = set() if before is None else {n for n, _ in before.fingers}
        prev = before
        for (t, layer, new), state in zip(layers, path):
            here = {n for n, _ in state.fingers}
            skipped.extend(self._left_out(n, t, new, here, layer) for n in new
                           if n not in here)
            if prev is not None:
                cuts.extend((n, t) for n, _ in prev.fingers
                            if n not in here and self.notes[n].offset_s > t + ONSET_TOL_S)
            for n, f in state.fingers:
                if n not in seen:
                    seen.add(n)
                    assignments.append(Assignment(n, f, state.rail_i * RAIL_STEP_M))
            prev = state
        loss = layers[-1][1][path[-1]][0]
        return FingeringChunk(tuple(assignments), tuple(skipped), tuple(cuts), float(loss))

    def _left_out(self, n: int, t: float, new: list[int], here: set[int], layer) -> Skip:
        """Why the state chosen at ``t`` does not strike ``n``: longer notes held through
        it (``HELD``); striking it loses more frames than it has, the moves there taking
        too long (``TOO_LATE``: another state of the event strikes it with the notes struck
        here); or a chord the hand does not hold from one position (``CHORD``)."""
        frames = self.frames(n)
        longer = sorted(m for m in here if (self._t_up[m] - t) / self.dt > frames)
        if longer:
            names = ", ".join(pitch_name(self.pitch[m]) for m in longer)
            return Skip(n, SkipReason.HELD, f"at t={t:.3f} s the hand holds {names} through "
                        f"it: its finger would have to let go of more than its {frames:.0f} "
                        "frames")
        struck = {m for m in here if m in new} | {n}
        if any(struck <= {m for m, _ in s.fingers} for s in layer):
            return Skip(n, SkipReason.TOO_LATE, f"striking it at t={t:.3f} s would lose more "
                        f"than its {frames:.0f} frames: the moves there take longer")
        return Skip(n, SkipReason.CHORD, f"{len(new)} notes at t={t:.3f} s: the hand holds "
                    f"{sum(m in here for m in new)} of them from one position")

    def _layer(self, prev, t: float, new: list[int]):
        """The ``BEAM`` cheapest states of one event: striking every note of ``new`` the
        hand can hold at once, or fewer (a run of them in pitch order: one hand's span),
        or none, each note left out costing its frames (a short note given up for a long
        one held through it is the better music, in the frame currency)."""
        new = sorted(new, key=lambda n: self.notes[n].pitch)
        # (by hand shape, the rail and the fingers on the notes sounding: the cheapest
        # state of each, the only one the pruning can keep; (cost, state before, state))
        layer: dict[tuple, tuple[float, State | None, State]] = {}
        for size in range(min(len(new), len(self.atlas.hand.fingers)), -1, -1):
            for i in range(len(new) - size + 1):
                sub = new[i:i + size]
                left_out = sum(self.frames(n) for n in new if n not in sub)
                self._extend(layer, prev, t, sub, left_out)
        return _prune(layer)

    def _extend(self, layer, prev, t: float, new: list[int], left_out: float = 0.0) -> None:
        fingers = self.atlas.hand.fingers
        new = sorted(new, key=lambda n: self.pitch[n])
        offset = self.offset
        starts = prev.items() if prev else [(None, (0.0, None))]
        self._bound = math.inf
        assign: dict[frozenset, list] = {}  # by the fingers holding kept notes
        for i, (p, (cost, _)) in enumerate(starts):
            cost += left_out
            # (the states before come cheapest first, and no step costs less than
            # nothing: once ``BEAM`` states are cheaper than this one's cost, no state
            # it leads to is kept, nor are those of the states after it)
            if i % BOUND_EVERY == 0:
                self._bound = self._beam_bound(layer)
            if cost > self._bound:
                break
            ctx = None if p is None else self.prev(p, t)
            held = [] if p is None else ctx.held
            for k in range(len(held), -1, -1):
                for kept in itertools.combinations(held, k):
                    cut = sum(offset[m] - t for m, _ in held
                              if (m, _) not in kept) / self.dt
                    busy = frozenset(f for _, f in kept)
                    got = assign.get(busy)
                    if got is None:  # (the new notes' fingers, and their press keys)
                        free = [f for f in fingers if f not in busy]
                        got = assign[busy] = [(d, self._press_key(d)) for d in (
                            dict(zip(new, combo))
                            for combo in itertools.combinations(free, len(new)))]
                    for d, key in got:
                        self._try(layer, ctx, cost + cut, kept, d, key, t)

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

    def _try(self, layer, ctx: Prev | None, cost: float, kept, new: dict[int, str],
             press_key: tuple, t: float) -> None:
        """Every transition from ``ctx`` that strikes ``new`` (note -> finger: its
        ``_press_key``) and keeps ``kept`` held, into ``layer``."""
        if kept or len(new) > 1:
            order_of, pitch = self._order, self.pitch
            sounding = sorted([*kept, *new.items()], key=lambda mf: pitch[mf[0]])
            order = [order_of[f] for _, f in sounding]
            if any(b <= a for a, b in itertools.pairwise(order)):
                return
            sounding_t = tuple(sorted(sounding))
        else:
            sounding = sounding_t = tuple(new.items())
        p = None if ctx is None else ctx.state
        if not new:  # (every new note left out: the hand stays)
            if p is None:
                return
            rails = [(p.rail_i, 0.0)]
        else:
            rails = self._moves_to(new, press_key, p)
        if p is None:  # (the song's first notes: from anywhere, no move lost)
            for rail_i, tie in rails:
                total, shape = cost + 0.0 + tie, (rail_i, sounding_t)
                old = layer.get(shape)
                if total <= self._bound and (old is None or total < old[0]):
                    layer[shape] = (total, None, State(rail_i, sounding_t))
            return
        bound, here, steps = self._bound, p.rail_i, ctx.steps
        busy = crossing = recent = None
        for rail_i, tie in rails:
            # (the pruning keeps one state per shape, the cheapest: a transition that
            # cannot cost less than the cheapest state of its shape so far is not weighed,
            # nor one that cannot cost less than the beam's last state)
            low = cost + tie + _PER_STEP * abs(rail_i - here)
            shape = (rail_i, sounding_t)
            old = layer.get(shape)
            if low > bound or old is not None and low > old[0]:
                continue
            if busy is None:
                busy = frozenset(f for _, f in sounding)
            if rail_i == here:
                if crossing is None:
                    crossing = self._crosses(ctx, sounding, busy)
                if crossing:
                    continue
            key = (sounding_t, rail_i, kept)
            step = steps.get(key)
            if step is None:
                step = steps[key] = self._same_rail_loss(ctx, new) if rail_i == here \
                    else self._rail_loss(ctx, new, rail_i, kept)
            total = cost + step + tie
            if step == math.inf or total > bound:  # (inf: no move gets there)
                continue
            if old is None or total < old[0]:
                if recent is None:
                    recent = self._recent(ctx, busy)
                s = State(rail_i, sounding_t, recent)
                if old is not None and old[2] != s:
                    del layer[shape]  # (another state of the shape: it comes after)
                layer[shape] = (total, p, s)

    def _crosses(self, ctx: Prev, sounding, busy: set[str]) -> bool:
        """Whether the fingers sounding, with those that left their keys within
        RECENT_S (still over them), are out of the hand's order: a finger would cross
        another without moving the rail."""
        order_of, pitch, rail_i = self._order, self.pitch, ctx.state.rail_i
        left = [(m, f) for m, f, r in ctx.fresh if f not in busy and r == rail_i]
        near = sorted([*sounding, *left], key=lambda mf: pitch[mf[0]])
        # (the thumb on a white key presses in front of the black keys, 30 mm and more
        # before the long fingers' tips: they pass behind it, it passes under them)
        order_near = [order_of[f] for m, f in near
                      if not (f == THUMB and not kb.is_black(pitch[m]))]
        return any(b <= a for a, b in itertools.pairwise(order_near))

    def _moves_to(self, new: dict[int, str], press_key: tuple,
                  p: State | None) -> list[tuple[int, float]]:
        """The rails worth a transition from ``p`` (memoised per rail before): staying,
        when the new notes can be played from there; else, of the moves, the shortest one
        each way and the one with the fingers nearest their natural places (a longer move
        to a place no better for the fingers is never cheaper: the arm's time grows with
        the distance, the fingers' lifts and descents do not change)."""
        key = (press_key, None if p is None else p.rail_i)
        keep = self._rails_to.get(key)
        if keep is None:
            cands = self._candidates(new, press_key)
            if p is None or len(cands) <= 3:
                keep = cands
            else:
                here = [c for c in cands if c[0] == p.rail_i]
                below = [c for c in cands if c[0] < p.rail_i]
                above = [c for c in cands if c[0] > p.rail_i]
                keep = here + below[-1:] + above[:1]
                best = min(cands, key=lambda c: c[1])
                if best not in keep:
                    keep.append(best)
            self._rails_to[key] = keep
        return keep

    def _candidates(self, new: dict[int, str], key: tuple) -> list[tuple[int, float]]:
        """(rail index, tie-break) of every rail from which the fingers of
        ``new`` press their notes (memoised by ``key``, their keys, forces and fingers:
        it does not depend on the state before)."""
        out = self._cands.get(key)
        if out is None:
            rails = None
            for n, f in new.items():
                r = self.rails(f, n)
                rails = r if rails is None else rails & r
            out = []
            for rail_i in sorted(rails):
                tie = sum(abs(self.entry(n, f, rail_i).dx_m - self.atlas.natural_dx[f])
                          for n, f in new.items()) * TIE_DX_PER_M
                out.append((rail_i, tie))
            self._cands[key] = out
        return out

    def _press_key(self, new: dict[int, str]) -> tuple:
        """What the rails that press ``new`` depend on: each note's key and force, and its
        finger."""
        pitch, force = self.pitch, self.force
        return tuple((pitch[n], force[n], f) for n, f in new.items())

    @staticmethod
    def _recent(ctx: Prev, busy: frozenset[str]) -> tuple[tuple[int, str, int], ...]:
        """The last notes of the fingers not sounding now (``busy``: those sounding),
        ended within RECENT_S of the event (a note of the state before that is not
        sounding now has just ended), with the rail they were pressed from (memoised
        per state before and fingers sounding)."""
        got = ctx.recent.get(busy)
        if got is None:
            last: dict[str, tuple[int, int]] = {}
            for m, f, r in ctx.fresh:
                if f not in busy:
                    last[f] = (m, r)
            got = ctx.recent[busy] = tuple(sorted((m, f, r) for f, (m, r) in last.items()))
        return got


def _prune(layer):
    """The ``BEAM`` cheapest states of ``layer`` (the cheapest of each hand shape), at
    most ``PER_RAIL`` of them at one rail position (so that the programme keeps other
    hand positions in view); of those holding the same notes at most ``PER_NOTES`` while
    states holding other notes (a held note let go, a note left out) are there to fill
    the beam. As {state: (cost, state before)}, cheapest first."""
    ranked = sorted(layer.values(), key=lambda v: v[0])
    out, per, sets = {}, {}, {}
    for capped in (True, False):
        for v in ranked:
            s = v[2]
            if s in out:
                continue
            notes = s.notes
            if per.get(s.rail_i, 0) < PER_RAIL and (not capped or sets.get(notes, 0) < PER_NOTES):
                out[s] = (v[0], v[1])
                per[s.rail_i] = per.get(s.rail_i, 0) + 1
                sets[notes] = sets.get(notes, 0) + 1
                if len(out) == BEAM:  # (the first pass adds in cost order: sorted)
                    return out if capped else dict(sorted(out.items(), key=lambda kv: kv[1][0]))
    return dict(sorted(out.items(), key=lambda kv: kv[1][0]))


def plan_fingering(notes, atlas: Atlas, moves: Moves, rate_hz: float) -> Fingering:
    """The fingering and hand positions of ``notes`` (see the module docstring)."""
    return FingeringProblem(notes, atlas, moves, rate_hz).solve()

