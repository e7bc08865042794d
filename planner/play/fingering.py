"""Fingering and hand positions as one dynamic programme over atlas states.

The song is cut at its onsets (events). At each event the hand is in a state: a rail
position (on a ``RAIL_STEP_M`` grid) and a finger for every note sounding then (the new
ones and those still held). A state exists only where the atlas has every one of those
fingers over its key from that rail, pressing with the note's force within the motors'
torque (``AtlasEntry.max_force_n``), the fingers in the order of their keys (no crossing
in this version), one note per finger. A held note keeps its finger and the rail, or is
cut at the event.

A transition costs the frames of music it loses (the currency of frame F1), from the
timed moves of ``planner.play.moves``: a finger striking again needs ``repeat_gap_s``
(same key) or ``move_gap_s`` (another key) between its key up and key down; a move of
the rail needs every finger lifted, the rail's own time-optimal move, and the new
fingers' descents. Where the music gives less, the shortfall is lost (as a key let up
early or put down late). A cut loses the rest of the held note. Ties go to the smaller
rail move and the finger nearer its natural place (``TIE_*``, far below a frame).

A note no finger can press from any rail is left out before the programme
(``OUT_OF_REACH`` or ``TORQUE``); when no state holds every new note of an event (more
notes than fingers, a chord wider than the hand), the largest subset that fits is kept
and the rest are left out (``CHORD``). The ``BEAM`` best states of each event go on.
"""

from __future__ import annotations

import enum
import itertools
import math
from dataclasses import dataclass

from planner.music import keyboard as kb
from planner.play.atlas import Atlas
from planner.play.moves import Moves
from planner.targets import press_force_n

THUMB = "thumb"
RAIL_STEP_M = 0.006  # the hand positions the programme weighs, this far apart
BEAM = 60  # states kept per event
WINDOW = 48  # events the programme looks over at once ...
LOOKAHEAD = 16  # ... the last of which it decides only in the next window
PER_RAIL = 6  # ... at most this many at one rail position
RECENT_S = 0.3  # a finger's note ended longer ago than this costs its next move nothing
# (the slowest move between two keys in the default hand's atlas, the thumb's, takes 0.2 s)
ONSET_TOL_S = 1e-4  # notes starting this close together are one event
TIE_RAIL_PER_M = 5.0  # frames per metre of rail moved: a tie-break, not a cost
TIE_DX_PER_M = 0.5  # frames per metre a finger is off its natural place


class SkipReason(enum.Enum):
    OUT_OF_REACH = "out_of_reach"  # no finger presses the key from any rail position
    TORQUE = "torque"  # the fingers that reach it cannot press with the note's force
    CHORD = "chord"  # more notes at once than the hand can hold from one position


@dataclass(frozen=True)
class Assignment:
    """A note played by ``finger`` with the rail at ``rail_m``; ``release_s`` is when a
    held note is cut (a later event needs its finger or the hand), else None."""

    note: int
    finger: str
    rail_m: float
    release_s: float | None = None


@dataclass(frozen=True)
class Skip:
    note: int
    reason: SkipReason
    detail: str


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
    (struck in it or before) cut at a time, and the loss the model expects so far."""

    assignments: tuple[Assignment, ...]
    skipped: tuple[Skip, ...]
    cuts: tuple[tuple[int, float], ...]
    loss_frames: float


@dataclass(frozen=True)
class _State:
    rail_i: int
    fingers: tuple[tuple[int, str], ...]  # (note, finger), by note: the notes sounding
    recent: tuple[tuple[int, str, int], ...] = ()  # (note, finger, rail index it was at):
    # the last notes of fingers not sounding, ended within RECENT_S

    def last_notes(self) -> tuple[tuple[int, str, int], ...]:
        """Every finger's note that still matters to its next move, sounding or recent,
        with the rail index it is (or was last) pressed from."""
        return self.recent + tuple((m, f, self.rail_i) for m, f in self.fingers)


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


class FingeringProblem:
    """The programme for one song on one hand (built, then ``solve``d)."""

    def __init__(self, notes, atlas: Atlas, moves: Moves, rate_hz: float) -> None:
        self.notes = notes
        self.atlas = atlas
        self.moves = moves
        self.dt = 1.0 / rate_hz
        h = atlas.hand
        r = atlas.rail
        self.rail_lo = math.ceil(h.lower[r] / RAIL_STEP_M)
        self.rail_hi = math.floor(h.upper[r] / RAIL_STEP_M)
        self._rails: dict[tuple[str, int], frozenset[int]] = {}
        self._entry: dict = {}
        self._rail_time: dict[int, float] = {}
        self._release: dict = {}
        self._cands: dict = {}
        self._t_down = [(math.ceil(n.onset_s / self.dt - 1e-9) - 0.5) * self.dt for n in notes]
        self._t_up = [(math.ceil(n.offset_s / self.dt - 1e-9) - 0.5) * self.dt for n in notes]

    # ------------------------------------------------------------------ reach
    def rails(self, finger: str, note: int) -> frozenset[int]:
        """Rail grid indices from which ``finger`` presses ``note`` with its force."""
        key = (finger, note)
        if key not in self._rails:
            n = self.notes[note]
            force = press_force_n(n.velocity)
            x = kb.key(n.pitch).center_x_m
            nat = self.atlas.natural_dx[finger]
            span = 0.05
            lo = max(self.rail_lo, math.ceil((x - nat - span) / RAIL_STEP_M))
            hi = min(self.rail_hi, math.floor((x - nat + span) / RAIL_STEP_M))
            ok = set()
            for i in range(lo, hi + 1):
                e = self.atlas.entry(finger, n.pitch, i * RAIL_STEP_M)
                if e is not None and e.max_force_n >= force:
                    ok.add(i)
            self._rails[key] = frozenset(ok)
        return self._rails[key]

    def _reason(self, note: int) -> Skip | None:
        fingers = self.atlas.hand.fingers
        if any(self.rails(f, note) for f in fingers):
            return None
        n = self.notes[note]
        reach = any(self.atlas.entry(f, n.pitch, i * RAIL_STEP_M) is not None
                    for f in fingers for i in range(self.rail_lo, self.rail_hi + 1, 2))
        if reach:
            return Skip(note, SkipReason.TORQUE, f"no finger presses {kb_name(n.pitch)} with "
                        f"{press_force_n(n.velocity):.1f} N within the motors' torque")
        return Skip(note, SkipReason.OUT_OF_REACH, f"no finger reaches {kb_name(n.pitch)} "
                    "from any rail position")

    # ------------------------------------------------------------------ timing model
    def t_down(self, note: int) -> float:
        """When the key should go down: half a frame before the note's first row."""
        return self._t_down[note]

    def t_up(self, note: int) -> float:
        """When it should come up: half a frame before the first row at or after its end."""
        return self._t_up[note]

    def entry(self, note: int, finger: str, rail_i: int):
        key = (note, finger, rail_i)
        e = self._entry.get(key, False)
        if e is False:
            e = self._entry[key] = self.atlas.entry(finger, self.notes[note].pitch,
                                                    rail_i * RAIL_STEP_M)
        return e

    def _same_rail_loss(self, prev: _State, new_notes: dict[int, str], rail_i: int) -> float:
        last = {f: (m, r) for m, f, r in prev.last_notes()}
        on_key = {self.notes[m].pitch: (m, f) for m, f, r in prev.last_notes() if r == rail_i}
        loss = 0.0
        for n, f in new_notes.items():
            other = on_key.get(self.notes[n].pitch)
            if other is not None and other[1] != f:  # another finger leaves the key first
                m2, g = other
                gap = (self.moves.before_rail_s(self.entry(m2, g, rail_i))
                       + self.moves.after_rail_s(self.entry(n, f, rail_i)))
                loss += max(0.0, gap - (self.t_down(n) - self.t_up(m2)))
            if f not in last:
                continue
            m, r = last[f]
            a, b = self.entry(m, f, r), self.entry(n, f, rail_i)
            if self.notes[m].pitch == self.notes[n].pitch and r == rail_i:
                gap = self.moves.repeat_gap_s(a)
            else:
                gap = self.moves.move_gap_s(a, b)
                if gap is None:
                    return math.inf
            loss += max(0.0, gap - (self.t_down(n) - self.t_up(m)))
        return loss / self.dt

    def _rail_loss(self, prev: _State, arrive: float, rail_i: int, kept=()) -> float:
        """Frames lost to a move of the rail to ``rail_i`` after ``prev``: a finger of
        ``prev`` holding a key it can follow (``Moves.follow``) rides along on it; every
        other lifts after its key comes up; then the rail moves (as slow as its slowest
        follower), and the new fingers descend (``arrive``: the latest of their descents'
        key-down lead minus key-down target). The worst pair decides, and it splits:
        max over the lifters (lift + key up) + the move + max over the new. A ``kept``
        note (sounding past the event) must follow, or the move is not made (inf)."""
        key = (prev, rail_i)
        got = self._release.get(key)
        if got is None:
            di = abs(rail_i - prev.rail_i)
            T = self._rail_time.get(di)
            if T is None:
                T = self._rail_time[di] = self.moves.rail_move(0.0, di * RAIL_STEP_M).duration_s
            followers = set()
            for m, f in prev.fingers:
                a, b = self.entry(m, f, prev.rail_i), self.entry(m, f, rail_i)
                mv = None if b is None else self.moves.follow(a, b)
                # (the move fits inside the note, after its press and before its lift)
                if mv is not None and (self.t_up(m) - self.t_down(m)
                                       >= mv.duration_s + self.moves.press_min_s(a)):
                    followers.add((m, f))
                    T = max(T, mv.duration_s)
            release = max((self.moves.before_rail_s(self.entry(m, f, r)) + self.t_up(m)
                           for m, f, r in prev.last_notes() if (m, f) not in followers),
                          default=-math.inf)
            got = self._release[key] = (release + T, frozenset(followers))
        release_t, followers = got
        if not set(kept) <= followers:
            return math.inf
        di = abs(rail_i - prev.rail_i)
        return max(0.0, release_t + arrive) / self.dt + TIE_RAIL_PER_M * di * RAIL_STEP_M

    def _after_follow_loss(self, prev: _State, new: dict[int, str], rail_i: int) -> float:
        """Frames lost around a move of the rail by the new notes whose finger, or whose
        key, a follower still holds (that finger strikes again, same key, or moves on,
        another key, once its note ends; another finger waits for it to leave the key),
        and by those whose finger lifted from a recent note: it crosses to its new key
        while the rail moves, then comes down."""
        followers = self._release[(prev, rail_i)][1]
        by_finger = {f: m for m, f in followers}
        by_key = {self.notes[m].pitch: (m, f) for m, f in followers}
        lifted = {f: (m, r) for m, f, r in prev.last_notes() if (m, f) not in followers}
        loss = 0.0
        for n, f in new.items():
            m = by_finger.get(f)
            if m is None and f in lifted:  # it lifts, crosses (while the rail moves), down
                m, r = lifted[f]
                across = self.moves.across(self.entry(m, f, r), self.entry(n, f, rail_i))
                if across is None:
                    return math.inf
                gap = (self.moves.before_rail_s(self.entry(m, f, r))
                       + across.duration_s + self.moves.after_rail_s(self.entry(n, f, rail_i)))
                loss += max(0.0, gap - (self.t_down(n) - self.t_up(m)))
                m = None
            if m is not None:
                a, b = self.entry(m, f, rail_i), self.entry(n, f, rail_i)
                if self.notes[m].pitch == self.notes[n].pitch:
                    gap = self.moves.repeat_gap_s(a)
                else:
                    gap = self.moves.move_gap_s(a, b)
                    if gap is None:
                        return math.inf
                loss += max(0.0, gap - (self.t_down(n) - self.t_up(m)))
            other = by_key.get(self.notes[n].pitch)
            if other is not None and other[1] != f:
                m2, g = other
                gap = (self.moves.before_rail_s(self.entry(m2, g, rail_i))
                       + self.moves.after_rail_s(self.entry(n, f, rail_i)))
                loss += max(0.0, gap - (self.t_down(n) - self.t_up(m2)))
        return loss / self.dt

    def _arrival(self, new: dict[int, str], rail_i: int) -> float:
        return max(self.moves.after_rail_s(self.entry(n, f, rail_i)) - self.t_down(n)
                   for n, f in new.items())

    # ------------------------------------------------------------------ the programme
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
        events decides its first ones (all but ``LOOKAHEAD``), which are yielded
        (``FingeringChunk``) and fixed; the next window starts from the state it reached.
        So the motion and the rows can start after the first window, not the song."""
        evs = []
        for t, new in events(self.notes):
            playable = []
            for n in new:
                why = self._reason(n)
                if why is None:
                    playable.append(n)
                else:
                    yield FingeringChunk((), (why,), (), 0.0)
            if playable:
                evs.append((t, playable))
        i = 0
        start: dict[_State, tuple[float, _State | None]] = {}
        while i < len(evs):
            layers = []
            prev = start
            for t, new in evs[i:i + WINDOW]:
                prev = self._layer(prev, t, new)
                layers.append((t, prev, new))
            final = i + len(layers) >= len(evs)
            k = len(layers) if final else max(1, len(layers) - LOOKAHEAD)
            path = self._path(layers)
            before = next(iter(start)) if start else None
            yield self._chunk(layers[:k], path[:k], before)
            last = path[k - 1]
            start = {last: (layers[k - 1][1][last][0], None)}
            i += k

    def _path(self, layers) -> list[_State]:
        """The best path through a window's layers, one state per layer."""
        state = min(layers[-1][1].items(), key=lambda kv: kv[1][0])[0]
        out = [state]
        for _, layer, _ in reversed(layers[1:]):
            state = layer[state][1]
            out.append(state)
        return out[::-1]

    def _chunk(self, layers, path: list[_State], before: _State | None) -> FingeringChunk:
        """What a committed stretch of the path says: the notes struck in it (finger, rail
        at their first state), the chord notes left out, the held notes cut (at the event
        whose state no longer holds them)."""
        assignments, skipped, cuts = [], [], []
        seen = set() if before is None else {n for n, _ in before.fingers}
        prev = before
        for (t, layer, new), state in zip(layers, path):
            here = {n for n, _ in state.fingers}
            skipped.extend(Skip(n, SkipReason.CHORD, f"{len(new)} notes at t={t:.3f} s: the "
                                f"hand holds {sum(m in here for m in new)} of them from one "
                                "position") for n in new if n not in here)
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

    def _layer(self, prev, t: float, new: list[int]):
        """The states of one event that hold the largest subset of ``new`` any state holds
        (the ``BEAM`` cheapest)."""
        for size in range(len(new), 0, -1):
            layer: dict[_State, tuple[float, _State | None]] = {}
            for keep in itertools.combinations(new, size):
                self._extend(layer, prev, t, list(keep))
            if layer:
                return self._prune(layer)
        return {}

    @staticmethod
    def _prune(layer):
        """The ``BEAM`` cheapest states, at most ``PER_RAIL`` of them at one rail position
        (so that the programme keeps other hand positions in view)."""
        out, per = {}, {}
        for s, v in sorted(layer.items(), key=lambda kv: kv[1][0]):
            if per.get(s.rail_i, 0) < PER_RAIL:
                out[s] = v
                per[s.rail_i] = per.get(s.rail_i, 0) + 1
                if len(out) == BEAM:
                    break
        return out

    def _extend(self, layer, prev, t: float, new: list[int]) -> None:
        fingers = self.atlas.hand.fingers
        new = sorted(new, key=lambda n: self.notes[n].pitch)
        starts = prev.items() if prev else [(None, (0.0, None))]
        for p, (cost, _) in starts:
            held = [] if p is None else [(m, f) for m, f in p.fingers
                                         if self.notes[m].offset_s > t + ONSET_TOL_S]
            for k in range(len(held), -1, -1):
                for kept in itertools.combinations(held, k):
                    cut = sum(self.notes[m].offset_s - t for m, _ in held
                              if (m, _) not in kept) / self.dt
                    busy = {f for _, f in kept}
                    free = [f for f in fingers if f not in busy]
                    for combo in itertools.combinations(free, len(new)):
                        self._try(layer, p, cost + cut, kept, dict(zip(new, combo)), t)

    def _try(self, layer, p: _State | None, cost: float, kept, new: dict[int, str],
             t: float) -> None:
        fingers = self.atlas.hand.fingers
        sounding = sorted([*kept, *new.items()], key=lambda mf: self.notes[mf[0]].pitch)
        order = [fingers.index(f) for _, f in sounding]
        if any(b <= a for a, b in itertools.pairwise(order)):
            return
        sounding_t = tuple(sorted(sounding))
        busy = {f for _, f in sounding}
        # fingers that left their keys within RECENT_S are still over them: the new
        # fingers keep the hand's order with them too (no finger crosses another)
        left = [] if p is None else [(m, f) for m, f, r in p.last_notes()
                                     if f not in busy and r == p.rail_i
                                     and self.t_up(m) > t - RECENT_S]
        near = sorted([*sounding, *left], key=lambda mf: self.notes[mf[0]].pitch)
        # (the thumb on a white key presses in front of the black keys, 30 mm and more
        # before the long fingers' tips: they pass behind it, it passes under them)
        near = [(m, f) for m, f in near
                if not (f == THUMB and not kb.is_black(self.notes[m].pitch))]
        order_near = [fingers.index(f) for _, f in near]
        crossing = any(b <= a for a, b in itertools.pairwise(order_near))
        recent = {}
        for rail_i, arrive, tie in self._moves_to(self._candidates(new), p):
            if crossing and rail_i == p.rail_i:
                continue
            if p is None:
                step = 0.0
            elif rail_i == p.rail_i:
                step = self._same_rail_loss(p, new, rail_i)
            else:
                step = self._rail_loss(p, arrive, rail_i, kept)
                if not math.isinf(step):
                    step += self._after_follow_loss(p, new, rail_i)
            if math.isinf(step):
                continue
            same = p is not None and rail_i == p.rail_i
            if same not in recent:
                recent[same] = self._recent(p, sounding, t, rail_i)
            s = _State(rail_i, sounding_t, recent[same])
            total = cost + step + tie
            if s not in layer or total < layer[s][0]:
                layer[s] = (total, p)

    @staticmethod
    def _moves_to(cands, p: _State | None):
        """The rails worth a transition from ``p``: staying, when the new notes can be
        played from there; else, of the moves, the shortest one each way and the one
        with the fingers nearest their natural places (a longer move to a place no
        better for the fingers is never cheaper: the arm's time grows with the distance,
        the fingers' lifts and descents do not change)."""
        if p is None or len(cands) <= 3:
            return cands
        here = [c for c in cands if c[0] == p.rail_i]
        below = [c for c in cands if c[0] < p.rail_i]
        above = [c for c in cands if c[0] > p.rail_i]
        keep = here + below[-1:] + above[:1]
        best = min(cands, key=lambda c: c[2])
        if best not in keep:
            keep.append(best)
        return keep

    def _candidates(self, new: dict[int, str]) -> list[tuple[int, float, float]]:
        """(rail index, arrival lead, tie-break) of every rail from which the fingers of
        ``new`` press their notes (memoised: it does not depend on the state before)."""
        key = tuple(sorted(new.items()))
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
                out.append((rail_i, self._arrival(new, rail_i), tie))
            self._cands[key] = out
        return out

    def _recent(self, p: _State | None, sounding, t: float,
                rail_i: int) -> tuple[tuple[int, str, int], ...]:
        """The last notes of the fingers not sounding now, ended within RECENT_S of ``t``
        (a note of the state before that is not sounding now has just ended), with the
        rail they were pressed from."""
        if p is None:
            return ()
        busy = {f for _, f in sounding}
        last: dict[str, tuple[int, int]] = {}
        for m, f, r in p.last_notes():
            if f not in busy and self.t_up(m) > t - RECENT_S:
                last[f] = (m, r)
        return tuple(sorted((m, f, r) for f, (m, r) in last.items()))

def kb_name(pitch: int) -> str:
    names = ("C", "C#", "D", "D#", "E", "F", "F#", "G", "G#", "A", "A#", "B")
    return f"{names[pitch % 12]}{pitch // 12 - 1}"


def plan_fingering(notes, atlas: Atlas, moves: Moves, rate_hz: float) -> Fingering:
    """The fingering and hand positions of ``notes`` (see the module docstring)."""
    return FingeringProblem(notes, atlas, moves, rate_hz).solve()
