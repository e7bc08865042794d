"""What a transition of the fingering's dynamic programme costs, in frames of music lost.

A state is a hand position (``planner.play.places``: an arm posture and a rail position
on the ``RAIL_STEP_M`` grid, one int) and a finger for every note
sounding then (``State``). A transition costs the frames of music it loses (the currency
of frame F1), from the timed moves of ``planner.play.moves``: a finger striking again
needs ``repeat_gap_s`` (same key) or ``move_gap_s`` (another key) between its key up and
key down; another finger on a key a finger just left waits for its lift; a move of the
rail needs every finger lifted but those that follow their keys, the rail's own
time-optimal move, and the new fingers' descents. Where the music gives less, the
shortfall is lost (as a key let up early or put down late). Ties go to the smaller rail
move and the finger nearer its natural place (``TIE_*``, far below a frame). A note no
finger can press from any rail is named (``OUT_OF_REACH`` or ``TORQUE``).
"""

from __future__ import annotations

import enum
import math
from collections.abc import Sequence
from dataclasses import dataclass

from planner.music import keyboard as kb
from planner.music.keyboard import pitch_name
from planner.play.armcost import ArmCosts
from planner.play.force import press_force_n, pressed_force_n
from planner.play.keytimes import (
    LATE_MIN_S,
    key_down_s,
    key_up_s,
    late_frames,
    sounding_frames,
    struck_s,
)
from planner.play.places import RAIL_STEP_M, Places

RECENT_S = 0.3  # a finger's note ended longer ago than this costs its next move nothing
# (the slowest move between two keys in the default hand's atlas, the thumb's, takes 0.2 s)
ONSET_TOL_S = 1e-4  # notes starting this close together are one event
TIE_DX_PER_M = 0.5  # frames per metre a finger is off its natural place


class SkipReason(enum.Enum):
    """Why a note is not played: the fingering's reasons (no state holds it), the
    motion's (the state chosen cannot strike it in time), and the self-check's (meant
    to be played, found by the replay with its key down too little: ``MISSED``)."""

    OUT_OF_REACH = "out_of_reach"  # no finger presses the key from any rail position
    BODY = "body"  # a finger would press it but for its body, which touches another key or
    # the key bed (spec section 2): never pressed wrongly
    TORQUE = "torque"  # the fingers that reach it cannot drive its key down (``force.py``)
    CHORD = "chord"  # more notes at once than the hand can hold from one position
    HELD = "held"  # the fingers that could strike it hold longer notes through it (each
    # left-out note costs its frames: the programme gives up the fewer)
    TOO_SHORT = "too_short"  # a press cannot go down and up again inside it (the fingering
    # names the notes shorter than every press of every finger and rail that reach them)
    TOO_LATE = "too_late"  # its key cannot go down before half of it is over
    NO_PATH = "no_path"  # no move checked clear of the keys takes the finger there
    MISSED = "missed"  # (``planner.selfcheck``) meant to be played, the replay finds it missed
    OTHER_HAND = "other_hand"  # (two hands) every place that presses it leaves the other
    # hand less than its clearance (``rail_bounds``: ``planner.play.twohands``)




@dataclass(frozen=True)
class Skip:
    note: int
    reason: SkipReason
    detail: str




class State:
    """A state of the programme: the hand's place (``planner.play.places``), the notes
    sounding with their fingers (``fingers``: (note, finger), by note) and ``recent``:
    (note, finger, rail index it was at), the last notes of fingers not sounding, ended
    within RECENT_S; ``late``: (note, seconds) of the notes it struck late (their keys
    down that much after their time: a rider's press is done that much later, its key's
    window that much shorter, ``Prev.follows``); ``rode``: (note, seconds) of the notes
    that rode along on the arm's move into this state and when that move ended (their
    fingers are busy until then: ``ArmCosts._cut_up_s``); ``older``: (note, finger, rail
    index) the last notes of the fingers neither sounding nor recent, ended longer ago
    (such a finger waits at crossing height over that key's entry, carried with the hand:
    the motion moves it across from there to a key it takes over from another finger,
    ``Costs._leave_key_s``). Immutable (its slots are set once; it is
    hashed many times, its hash kept). ``notes`` are the notes sounding; ``last_notes`` every finger's note that
    still matters to its next move, sounding or recent, with the rail index it is (or
    was last) pressed from."""

    __slots__ = ("_hash", "fingers", "last_notes", "late", "notes", "older", "place", "recent",
                 "rode")

    def __init__(self, place: int, fingers: tuple[tuple[int, str], ...],
                 recent: tuple[tuple[int, str, int], ...] = (),
                 late: tuple[tuple[int, float], ...] = (),
                 rode: tuple[tuple[int, float], ...] = (),
                 older: tuple[tuple[int, str, int], ...] = ()) -> None:
        object.__setattr__(self, "place", place)
        object.__setattr__(self, "fingers", fingers)
        object.__setattr__(self, "recent", recent)
        object.__setattr__(self, "late", late)
        object.__setattr__(self, "rode", rode)
        object.__setattr__(self, "older", older)
        object.__setattr__(self, "_hash", hash((place, fingers, recent, late, rode, older)))

    def __setattr__(self, name, value):
        raise AttributeError("State is immutable")

    def __getattr__(self, name: str):  # (the derived fields, made when first read)
        if name == "notes":
            value = tuple(n for n, _ in self.fingers)
        elif name == "last_notes":
            value = self.recent + tuple((m, f, self.place) for m, f in self.fingers)
        else:
            raise AttributeError(name)
        object.__setattr__(self, name, value)
        return value

    def __eq__(self, other) -> bool:
        return (self is other or isinstance(other, State) and self._hash == other._hash
                and self.place == other.place and self.fingers == other.fingers
                and self.recent == other.recent and self.late == other.late
                and self.rode == other.rode and self.older == other.older)

    def __hash__(self) -> int:
        return self._hash

    def __repr__(self) -> str:
        return (f"State(place={self.place}, fingers={self.fingers}, recent={self.recent}, "
                f"late={self.late}, rode={self.rode}, older={self.older})")


class Prev:
    """What a state of the event before tells every transition from it, worked out once
    (the programme weighs hundreds of transitions from each state)."""

    __slots__ = ("around", "cut_up", "follow_of", "follows", "fresh", "held", "last",
                 "late_of", "lift_end", "lift_end_black", "lift_parts", "lifts", "lifts_black",
                 "lifts_same", "lifts_to", "older", "on_key", "posture", "recent", "rode_of",
                 "state", "steps", "up_parts")

    def __init__(self, costs: Costs, state: State, t: float) -> None:
        self.state = state
        self.posture = costs.places.posture_of(state.place)
        # (a held note let go at this event: its key comes up when the new notes' go down)
        self.cut_up = cut_up = key_up_s(t, costs.dt)
        pitch, t_up, t_down = costs.pitch, costs._t_up, costs._t_down
        self.held = [(m, f) for m, f in state.fingers if costs.offset[m] > t + ONSET_TOL_S]
        self.last = {f: (m, r) for m, f, r in state.last_notes}
        self.older = {f: (m, r) for m, f, r in state.older}  # (the fingers' older notes)
        self.on_key = {pitch[m]: (m, f) for m, f, r in state.last_notes if r == state.place}
        self.fresh = [(m, f, r) for m, f, r in state.last_notes if t_up[m] > t - RECENT_S]
        # (before a move of the rail: when each finger is clear above every key, latest
        # first; by the front rule for a move that keeps the play posture, by the black
        # rule for one that changes it: ``planner.play.highclear``)
        timing = costs._timing  # (``Costs._times``' memo, read here: most find it)
        times = [((timing.get((pitch[m], f, r)) or costs._times(m, f, r)),
                  min(t_up[m], cut_up), m, f) for m, f, r in state.last_notes]
        self.lifts = sorted(((ts[0] + up, m, f) for ts, up, m, f in times),
                            key=lambda x: -x[0])
        self.lifts_black = sorted(((ts[2] + up, m, f) for ts, up, m, f in times),
                                  key=lambda x: -x[0])
        self.lift_end = self.lifts[0][0] if self.lifts else -math.inf  # (the latest)
        self.lift_end_black = self.lifts_black[0][0] if self.lifts_black else -math.inf
        self.lifts_same = (self.lifts, self.lift_end, None)  # (``ArmCosts._lifts``' answer
        # for a move that keeps the posture)
        self.lifts_to: dict[int, tuple] = {}  # (each finger's rule, by posture moved to:
        # ``ArmCosts._lifts``)
        # (the notes sounding that might ride along: their entry, the time their key is
        # down (from when it went down: a note struck late, ``State.late``, has less),
        # their press and when their key went down)
        # (the notes struck late and those that rode along, by note: ``State.late``,
        # ``State.rode``)
        self.late_of = late = dict(state.late)
        self.rode_of = dict(state.rode)
        self.follows = [] if costs.places.rail is None else [
            (m, f, a, t_up[m] - down, costs.places.press_min_s(a), down)
            for m, f in state.fingers if (a := costs.entry(m, f, state.place)) is not None
            for down in (t_down[m] + late.get(m, 0.0),)]
        self.follow_of = {(x[0], x[1]): x for x in self.follows}  # (by note and finger:
        # ``ArmFloor._first_clear``)
        self.up_parts: dict[int, tuple] = {}  # by note: what its key's up cut for a move
        # of the arm works out whatever the cut (``ArmCosts._cut_up_s``)
        self.lift_parts: dict[tuple, tuple] = {}  # by (note, finger, ``Costs._times``
        # column): its lift's time, its entry, the key-up no cut goes before
        # (``ArmCosts._cut_lifts``)
        self.around: dict[frozenset, tuple] = {}  # by the notes riding along
        self.steps: dict[tuple, tuple] = {}  # a transition's loss and its late notes, by
        # (notes, rail, kept)
        self.recent: dict[frozenset, tuple] = {}  # ``State.recent`` after, by fingers sounding


class CostMemo:
    """What the cost model works out that depends on the hand alone, not on the song:
    by keys, forces, fingers and rail positions (bounded), kept across the songs of one
    hand (``planner.play.Planner`` holds one)."""

    __slots__ = ("afters", "cand_rails", "cands", "entry", "follows", "gaps", "keep_cands",
                 "keep_to", "lift_cols", "paths", "rails", "rails_to", "shortest", "timing")

    def __init__(self) -> None:
        for name in self.__slots__:
            setattr(self, name, {})


class Costs(ArmCosts):
    """The cost model of one song on one hand (memoised: what depends on the hand alone
    in ``memo``, kept across songs when one is given); a move of the arm is costed by
    ``ArmCosts``."""

    def __init__(self, notes, places: Places, rate_hz: float,
                 memo: CostMemo | None = None,
                 rail_bounds: Sequence[tuple[float, float]] | None = None) -> None:
        self.notes = notes
        self.places = places
        self.dt = 1.0 / rate_hz
        h = places.hand
        r = places.rail
        self.rail_lo = 0 if r is None else math.ceil(h.plan_lower[r] / RAIL_STEP_M)
        self.rail_hi = 0 if r is None else math.floor(h.plan_upper[r] / RAIL_STEP_M)
        m = memo or CostMemo()
        self._rails: dict[tuple[str, int, float], frozenset[int]] = m.rails
        self._entry: dict = m.entry
        self._timing: dict = m.timing
        self._afters: dict = m.afters  # (``ArmCosts._afters_of``' answers, by the posture
        # moved from and the place moved to)
        self._gaps: dict = m.gaps
        self._follows: dict = m.follows
        self._paths: dict = m.paths  # (``_follow_path``'s answers)
        self._cands: dict = m.cands
        self._cand_rails: dict = m.cand_rails  # (``_cands``' rails, and its best, by key)
        self._rails_to: dict = m.rails_to
        self._keep_to: dict = m.keep_to  # (``Layers._keeping``'s answers)
        self._lift_cols: dict = m.lift_cols  # (``ArmCosts._lift_col``'s answers)
        self._keep_cands: dict = m.keep_cands  # (``Layers._keeping``'s candidates and
        # their index, by the new notes' and the riders' keys, forces and fingers)
        self._shortest: dict[tuple[int, float], float] = m.shortest
        self._ctx: dict[float, dict[State, Prev]] = {}  # (the song's: by event time)
        self.pitch = [n.pitch for n in notes]
        self.force = [press_force_n(n.velocity) for n in notes]
        self.offset = [n.offset_s for n in notes]
        self._t_down = [key_down_s(n.onset_s, self.dt) for n in notes]
        self._t_up = [key_up_s(n.offset_s, self.dt) for n in notes]
        # (two hands: per note, the rail's grid indices it may be pressed from, the other
        # hand's clearance kept; None: the whole travel, as one hand plays)
        self.bound: list[tuple[int, int]] | None = None if rail_bounds is None else [
            (math.ceil(lo / RAIL_STEP_M - 1e-9), math.floor(hi / RAIL_STEP_M + 1e-9))
            for lo, hi in rail_bounds]
        self._note_bound: list = [False] * len(notes)  # (``note_bound``'s, made when asked)

    # ------------------------------------------------------------------ reach
    def rails(self, finger: str, note: int) -> frozenset[int]:
        """Places (every posture's rail grid indices) from which ``finger`` presses
        ``note`` (with its force, or softer where the pose holds less: ``pressed_force_n``)."""
        n = self.notes[note]
        force = press_force_n(n.velocity)
        key = (finger, n.pitch, force)  # (bounded: keys and forces, not notes)
        if key not in self._rails:
            x = kb.key(n.pitch).center_x_m
            nat = self.places.natural_dx[finger]
            span = 0.05
            lo = max(self.rail_lo, math.ceil((x - nat - span) / RAIL_STEP_M))
            hi = min(self.rail_hi, math.floor((x - nat + span) / RAIL_STEP_M))
            ok = []
            for p in range(self.places.postures):
                for i in range(lo, hi + 1):
                    place = self.places.place(p, i)
                    e = self.places.entry(finger, n.pitch, place)
                    if e is not None and pressed_force_n(force, e.max_force_n) > 0.0:
                        ok.append(place)
            # (the press clear of the other keys with the rail where the place puts it)
            clear = self.places.presses_clear(finger, n.pitch, ok)
            self._rails[key] = frozenset(q for q, c in zip(ok, clear) if c)
            self._rails[("refused", *key)] = frozenset(q for q, c in zip(ok, clear) if not c)
        b = None if self.bound is None else self.note_bound(note)
        if b is None:
            return self._rails[key]
        lo, hi = b
        bounded = (*key, lo, hi)
        got = self._rails.get(bounded)
        if got is None:
            rail_i = self.places.rail_i
            got = self._rails[bounded] = frozenset(
                q for q in self._rails[key] if lo <= rail_i(q) <= hi)
        return got

    def note_bound(self, note: int) -> tuple[int, int] | None:
        """Two hands: ``note``'s rail bound (grid indices) cut to the rails any finger
        presses it from, None when it cuts none of them (then the note is weighed as one
        hand weighs it, and the memos keyed by keys and forces serve it)."""
        got = self._note_bound[note]
        if got is False:
            n = self.notes[note]
            force = press_force_n(n.velocity)
            rail_i = self.places.rail_i
            idx = [rail_i(q) for f in self.places.hand.fingers
                   for q in self._unbounded(f, n.pitch, force, note)]
            lo, hi = self.bound[note]
            if not idx or (lo <= min(idx) and hi >= max(idx)):
                got = None
            else:
                got = (max(lo, min(idx) - 1), min(hi, max(idx) + 1))
            self._note_bound[note] = got
        return got

    def _unbounded(self, finger: str, pitch: int, force: float, note: int) -> frozenset[int]:
        key = (finger, pitch, force)
        if key not in self._rails:
            bound, self.bound = self.bound, None
            try:
                self.rails(finger, note)
            finally:
                self.bound = bound
        return self._rails[key]

    def reason(self, note: int) -> Skip | None:
        """Why no state can play ``note`` (None: some can): no finger reaches its key with
        its force, or every press that could is longer than the note (so that the
        programme never weighs a note the motion cannot strike: a dense run of one-tick
        notes costs nothing to plan)."""
        fingers = self.places.hand.fingers
        n = self.notes[note]
        if any(self.rails(f, note) for f in fingers):
            window_s = self._t_up[note] - self._t_down[note]
            fits, shortest_s = self._press_fits(note, window_s)
            if fits:
                return None
            return Skip(note, SkipReason.TOO_SHORT, f"{1000 * n.duration_s:.0f} ms long; the "
                        f"shortest press down and up of any finger on {pitch_name(n.pitch)} "
                        f"takes {1000 * shortest_s:.0f} ms")
        if self.bound is not None and self.note_bound(note) is not None:
            lo, hi = self.note_bound(note)
            return Skip(note, SkipReason.OTHER_HAND, f"every place that presses "
                        f"{pitch_name(n.pitch)} puts the rail outside "
                        f"{lo * RAIL_STEP_M:+.3f}..{hi * RAIL_STEP_M:+.3f} m, where the other "
                        "hand leaves it its clearance")
        if any(self._rails[("refused", f, n.pitch, press_force_n(n.velocity))]
               for f in fingers):
            return Skip(note, SkipReason.BODY, f"no finger presses {pitch_name(n.pitch)} with "
                        "its body clear of the other keys from the rail's places")
        reach = any(self.places.entry(f, n.pitch, self.places.place(p, i)) is not None
                    for f in fingers for p in range(self.places.postures)
                    for i in range(self.rail_lo, self.rail_hi + 1, 2))
        if reach:
            return Skip(note, SkipReason.TORQUE, f"no finger presses {pitch_name(n.pitch)} with "
                        f"{press_force_n(n.velocity):.1f} N within the motors' torque")
        if any(self.places.body_refused(f, n.pitch, self.places.place(p, i))
               for f in fingers for p in range(self.places.postures)
               for i in range(self.rail_lo, self.rail_hi + 1, 2)):
            return Skip(note, SkipReason.BODY, f"no finger presses {pitch_name(n.pitch)} with "
                        "its body clear of the other keys and the key bed")
        return Skip(note, SkipReason.OUT_OF_REACH, f"no finger reaches {pitch_name(n.pitch)} "
                    "from any rail position")

    def _press_fits(self, note: int, window_s: float) -> tuple[bool, float]:
        """Whether some finger, from some rail, presses ``note``'s key down and up within
        ``window_s`` (``Moves.press_min_s``, the motion's bound), and that press's time,
        or the shortest of all when none fits (memoised per key and force)."""
        n = self.notes[note]
        key = (n.pitch, press_force_n(n.velocity))
        if self.bound is not None and self.note_bound(note) is not None:  # (the fingers
            key = (*key, *self.note_bound(note))  # that reach it depend on its bound)
        shortest = self._shortest.get(key)
        if shortest is not None:
            return window_s >= shortest, shortest
        shortest = math.inf
        for f in self.places.hand.fingers:
            for i in sorted(self.rails(f, note)):
                s = self.places.press_min_s(self.entry(note, f, i))
                if s <= window_s:
                    return True, s
                shortest = min(shortest, s)
        self._shortest[key] = shortest
        return False, shortest

    # ------------------------------------------------------------------ timing model
    def t_down(self, note: int) -> float:
        """When the key should go down: early in the row before the note's first row
        (``keytimes.key_down_s``)."""
        return self._t_down[note]

    def frames(self, note: int) -> float:
        """The frames ``note`` sounds (what leaving it out costs)."""
        return sounding_frames(self._t_down[note], self._t_up[note], self.dt)

    def t_up(self, note: int) -> float:
        """When it should come up: late in the row before the first row at or after its
        end (``keytimes.key_up_s``)."""
        return self._t_up[note]

    def entry(self, note: int, finger: str, place: int):
        key = (self.pitch[note], finger, place)  # (bounded: keys, not notes)
        e = self._entry.get(key, False)
        if e is False:
            e = self._entry[key] = self.places.entry(finger, key[0], place)
        return e

    def before_rail_s(self, note: int, finger: str, place: int) -> float:
        """Key up to the end of the lift to crossing height (``Moves.before_rail_s``)."""
        return self.places.before_rail_s(self.entry(note, finger, place))

    def after_rail_s(self, note: int, finger: str, place: int) -> float:
        """A descent from crossing height to key down (``Moves.after_rail_s``)."""
        return self.places.after_rail_s(self.entry(note, finger, place))

    def forget(self, until_s: float = math.inf) -> None:
        """Drop what only the events before ``until_s``, decided, can use (memory stays
        bounded on a long song; the next window, which starts there, keeps the rest)."""
        self._ctx = {t: v for t, v in self._ctx.items() if t >= until_s}

    def prev(self, state: State, t: float) -> Prev:
        """The ``Prev`` of ``state`` before the event at ``t`` (memoised: the subsets of an
        event's notes, and the next window over the same events, weigh it again)."""
        at = self._ctx.get(t)
        if at is None:
            at = self._ctx[t] = {}
        got = at.get(state)
        if got is None:
            got = at[state] = Prev(self, state, t)
        return got

    def _same_rail_loss(self, prev: Prev, new_notes: dict[int, str],
                        lates: list | None = None) -> float:
        """Frames lost by the new notes struck with the rail where it is: each key down
        as late as the latest of what it waits for (another finger leaving the key, its
        own finger's move from its last key), a repeated key let up early. ``lates``:
        gets (note, seconds) of each note struck late (``State.late``)."""
        place, last, on_key = prev.state.place, prev.last, prev.on_key
        loss = 0.0
        for n, f in new_notes.items():
            late = 0.0
            other = on_key.get(self.pitch[n])
            if other is not None and other[1] != f:  # another finger leaves the key first
                late = self._leave_key_s(other, n, f, place, last.get(f) or prev.older.get(f))
            if f in last:
                m, r = last[f]
                early, again = self._strike_again(m, r, n, f, place)
                if math.isinf(again):
                    return math.inf
                loss += early / self.dt
                late = max(late, again)
            loss += late_frames(late, self.dt)
            if lates is not None and late > LATE_MIN_S:
                lates.append((n, struck_s(self.notes[n].onset_s, self._t_down[n] + late,
                                          self.dt) - self._t_down[n]))
        return loss

    def _strike_again(self, m: int, r: int, n: int, f: str, place: int) -> tuple[float, float]:
        """(seconds ``m``'s key comes up early, seconds ``n``'s goes down late) when finger
        ``f``, last on note ``m`` from rail ``r``, strikes ``n`` from ``place``: the same
        key again from the same place is a repeat (the motion lets the key up in time for
        it), another key a lift, a move across and a descent (the key down late); late
        inf when no checked move gets there."""
        room = self._t_down[n] - self._t_up[m]
        if self.pitch[m] == self.pitch[n] and r == place:
            return max(0.0, self.places.repeat_gap_s(self.entry(m, f, r)) - room), 0.0
        gap = self._move_gap_s(m, f, r, n, place)
        if gap is None:
            return 0.0, math.inf
        return 0.0, max(0.0, gap - room)

    def _move_gap_s(self, m: int, f: str, r: int, n: int, place: int) -> float | None:
        """``Moves.move_gap_s`` from finger ``f``'s entry on ``m`` at rail ``r`` to its
        entry on ``n`` at ``place`` (memoised by keys and rails)."""
        key = (self.pitch[m], f, r, self.pitch[n], place)
        got = self._gaps.get(key, False)
        if got is False:
            got = self._gaps[key] = self.places.move_gap_s(self.entry(m, f, r),
                                                          self.entry(n, f, place))
        return got

    def _leave_key_s(self, other: tuple[int, str], n: int, f: str, place: int,
                     came: tuple[int, int] | None = None) -> float:
        """Seconds late when finger ``f`` strikes ``n`` on the key another finger has
        (``other``: its note and finger): that one lifts first, then this one moves
        across from its last key (``came``: its note and place; None: it has none) and
        descends, as the motion plays it (``Motion._release_others_on``: the striker's
        move across starts once the key is free)."""
        m2, g = other
        across = 0.0 if came is None else (self._across_s(came[0], f, came[1], n, place) or 0.0)
        gap = self.before_rail_s(m2, g, place) + across + self.after_rail_s(n, f, place)
        return max(0.0, gap - (self.t_down(n) - self.t_up(m2)))

    def _across_s(self, m: int, f: str, r: int, n: int, place: int) -> float | None:
        """Finger ``f``'s move across from its entry on ``m`` at place ``r`` to its entry
        on ``n`` at ``place``: the motion's very move (``Places.across``; 0 for the same
        entry, None where none is clear; memoised by keys and places)."""
        key = ("across", self.pitch[m], f, r, self.pitch[n], place)
        got = self._gaps.get(key, False)
        if got is False:
            a, b = self.entry(m, f, r), self.entry(n, f, place)
            move = None if a is None or b is None or a is b else self.places.across(a, b)
            got = self._gaps[key] = 0.0 if a is b else (None if move is None
                                                         else move.duration_s)
        return got
