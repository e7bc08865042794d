"""Fingering and hand positions as one dynamic programme over atlas states.

The song is cut at its onsets (events). At each event the hand is in a state
(``planner.play.costs.State``): a rail position and a finger for every note sounding
then (the new ones and those still held). A state exists only where the atlas has every
one of those fingers over its key from that rail, pressing with the note's force or
softer (``planner.play.force.pressed_force_n``), the fingers in the order of their keys,
one note per finger; no finger passes one that has just played (the thumb on a white key
excepted: it presses in front of the black keys). A held note keeps its finger, and the
rail unless its finger can follow its key, or is cut at the event. Transitions cost what
``planner.play.costs`` says.

A state may also strike fewer of an event's new notes (a run of them in pitch order) or
none, each note left out costing its frames: more notes than fingers or a chord wider
than the hand (``CHORD``), a short note whose finger would have to let go of a long note
held through it (``HELD``: a tie held under a melody), a note the moves reach too late
to be worth its frames (``TOO_LATE``). The ``BEAM`` best states of each event go on (at
most ``PER_RAIL`` at one rail position, one of each hand shape: ``planner.play.layers``),
over a receding window (``chunks``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from planner.music.keyboard import pitch_name
from planner.play.costs import ONSET_TOL_S, Skip, SkipReason, State
from planner.play.layers import Layers
from planner.play.places import Places

WINDOW = 48  # events the programme looks over at once ...
LOOKAHEAD = 16  # ... the last of which it decides only in the next window
FIRST_WINDOW, FIRST_LOOKAHEAD = 16, 8  # the first window is short: the rows start sooner
# (shorter ones were tried: docs/history/play-second-design.md, "Speed ... session 21", item 3)


@dataclass(frozen=True)
class Assignment:
    """A note played by ``finger`` with the rail at ``rail_m`` and the arm in play posture
    ``posture`` (``planner.play.places``); ``release_s`` is when a held note is cut (a
    later event needs its finger or the hand), else None."""

    note: int
    finger: str
    rail_m: float
    release_s: float | None = None
    posture: int = 0




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


class FingeringProblem(Layers):
    """The programme for one song on one hand (built, then ``solve``d or streamed in
    ``chunks``); its layers are ``Layers``', its costs ``Costs``'."""

    def solve(self) -> Fingering:
        """The whole song's answer (the chunks of ``chunks`` put together)."""
        out: dict[int, Assignment] = {}
        skipped: list[Skip] = []
        loss = 0.0
        for ch in self.chunks():
            out.update({x.note: x for x in ch.assignments})
            for n, t in ch.cuts:
                out[n] = replace(out[n], release_s=t)
            skipped.extend(ch.skipped)
            loss = ch.loss_frames
        return Fingering(tuple(out[n] for n in sorted(out)),
                         tuple(sorted(skipped, key=lambda s: s.note)), loss)

    def chunks(self):
        """The programme over a receding window: the best path over the next ``WINDOW``
        events (``FIRST_WINDOW`` at the start) decides its first ones (all but
        ``LOOKAHEAD``; the first window fewer as soon as their path is certain:
        ``_certain``), which are yielded (``FingeringChunk``, with the notes no state can
        play that start before the next event) and fixed; the next window goes on from the
        look-ahead's states that lead back to the last state decided (``_descendants``:
        every event is weighed once). Events are read as the windows need them, so the motion and the
        rows can start after the first window, not the song."""
        source = self._events()
        ahead_evs: list[tuple[float, list[int]]] = []  # playable events not decided yet
        skips: list[tuple[float, Skip]] = []  # notes no state plays, not yet yielded
        done, first, loss = False, True, 0.0
        # (the window's layers not decided yet, each {state: (cost, state before)}, and
        # the last state decided)
        layers: list[tuple[float, dict, list[int]]] = []
        before: State | None = None
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
            if layers:  # (the look-ahead kept from the window before)
                prev = layers[-1][1]
            else:  # (the song's start: from anywhere; else from the state decided)
                prev = {} if before is None else {before: (loss, None)}
            n = min(window, len(ahead_evs))  # (the window's layers, and the ``k`` it decides)
            k = n if done and len(ahead_evs) <= window else max(1, n - ahead)
            for t, new in ahead_evs[len(layers):window]:
                prev = self._layer(prev, t, new)
                layers.append((t, prev, new))
                if first and len(layers) < n and (sure := _certain(layers, k)):
                    k = sure  # (the first events' path is certain: decided now, as the
                    # whole window would; the rest is weighed again from the state
                    # decided, with the longer window; the rows start sooner)
                    break
            path = self._path(layers)
            until = ahead_evs[k][0] if k < len(ahead_evs) else math.inf
            mine = tuple(s for t, s in skips if t < until)
            skips = [(t, s) for t, s in skips if t >= until]
            ch = self._chunk(layers[:k], path[:k], before)
            loss = ch.loss_frames
            yield FingeringChunk(ch.assignments, mine + ch.skipped, ch.cuts, loss, until)
            before = path[k - 1]
            # (the first window's look-ahead, pruned with 8 events in view, is weighed
            # again from the state decided: kept, it lost on trills, trill_3 0.998 -> 0.971)
            layers = [] if first else _descendants(layers[k:], before)
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

    @staticmethod
    def _path(layers) -> list[State]:
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
                    assignments.append(Assignment(n, f, self.places.rail_m(state.place),
                                                  posture=self.places.posture_of(state.place)))
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

def _certain(layers, most: int) -> int:
    """How many of the first layers (at most ``most``, fewer than all) have a certain
    path: the largest ``k`` such that every state of the last layer descends from one
    state of layer ``k - 1``. The best path through any later layers goes through that
    state too (a later layer is built from the last one's states alone), so the first
    ``k`` layers' path is the one the whole window would choose (exact). 0: none yet."""
    states = layers[-1][1].keys()
    for i in range(len(layers) - 1, 0, -1):  # (then ``states``: layer ``i - 1``'s ancestors)
        states = {layers[i][1][s][1] for s in states}
        if len(states) == 1 and i <= most:
            return i
    return 0


def _descendants(layers, before: State):
    """``layers`` (those after a decided state ``before``) with only the states whose
    path leads back to ``before``: the next window goes on from them, its events weighed
    once (a window restarted from ``before`` alone weighed its look-ahead again)."""
    out, allowed = [], {before}
    for t, layer, new in layers:
        kept = {s: v for s, v in layer.items() if v[1] in allowed}
        out.append((t, kept, new))
        allowed = kept.keys()
    return out


def plan_fingering(notes, places: Places, rate_hz: float) -> Fingering:
    """The fingering and hand positions of ``notes`` (see the module docstring)."""
    return FingeringProblem(notes, places, rate_hz).solve()

