"""Motion: the fingering's notes -> timed segments of every finger and of the rail.

Each finger and the rail move on their own joints, one time-optimal straight move
(``planner.play.moves``) after another, holding still between them. The rules that keep
the plan safe are few and hold by construction:

* a finger not pressing is at its crossing height (``high``), or waits at ``hover`` over
  the key it presses next, or moves straight between atlas poses whose paths the atlas
  and ``Moves.across`` checked clear of the keys;
* the arm moves only while every finger is at crossing height (so nothing under a tip
  is higher than a black key's top, at any rail), or holds its key down following it
  (``planner.play.follow``: tip on the key, body holding it down and clear of every
  other key, checked along the very move; into another posture too);
* a key goes down early in the row before the note's first row and comes up late in the
  row before the first row at or after its end (``planner.play.keytimes``: the hand the
  servos drive lags its rows into a key and leaves it early), or as close to that as the
  moves allow: down later, up earlier, never the other way (a key down outside its note
  is a wrong note).

Notes are placed in onset order (a causal schedule: later notes never move what was
placed for earlier ones, except to lift a held finger before a rail move). A note whose
key cannot go down before half of it is over, or come up in time after a press, is not
pressed and is named (``TOO_LATE``, ``TOO_SHORT``).
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass, field

import numpy as np

from planner.music import keyboard as kb
from planner.play.armload import within_motors
from planner.play.armmotion import ArmMotion, up_move
from planner.play.atlas import SPAN_M, STEP_M, Atlas, AtlasEntry
from planner.play.costs import SkipReason
from planner.play.fingering import Assignment
from planner.play.keytimes import held_enough_s, key_down_s, key_up_s, struck_s
from planner.play.places import Places
from planner.play.profile import Bounce, Move, bounce_s, path_s

DROP_FRACTION = 0.5  # a note whose key cannot go down before this much of it is over is left out
WAIT_MARGIN_S = 0.005  # a finger reaches its waiting pose at least this long before it descends
BOUNCE_STRETCH = 2.0  # a repeat's bounce is played at most this much slower (its room that
# much more than its gap): past it the lift and the descent from rest fit (their gap is 1.5-1.8
# times the bounce's on the default hand) and cross the key-down depth faster
COMMIT_MARGIN_S = 0.3  # a key due up this soon after the rows written is let up when they are


def _key_x(pitch: int) -> float:
    return kb.key(pitch).center_x_m


def start_entries(atlas: Atlas, rail_m: float) -> dict[str, AtlasEntry]:
    """Each finger's atlas entry over the key nearest its natural place that it can press
    from ``rail_m``; where no key is in its reach (the rail near an end of the keyboard),
    the entry nearest its natural place of any key: its crossing height is above every
    key top wherever it is. A finger that presses no key at all (a hand whose fingers do
    not all reach the keyboard) has none: it keeps the natural hand's pose and plays
    nothing (the fingering names its notes)."""
    out = {}
    for f in atlas.hand.fingers:
        x = rail_m + atlas.natural_dx[f]
        near = sorted((p for p in kb.ALL_PITCHES if abs(kb.key(p).center_x_m - x) < 0.1),
                      key=lambda p: abs(kb.key(p).center_x_m - x))
        e = next((e for p in near if (e := atlas.entry(f, p, rail_m)) is not None), None)
        if e is None:
            n = round(SPAN_M / STEP_M)
            e = next((e for k in sorted(range(-n, n + 1), key=abs) for pc in range(12)
                      if (e := atlas.entry_at(f, pc, k)) is not None), None)
        if e is not None:
            out[f] = e
    return out


@dataclass(frozen=True)
class Segment:
    """A move of one joint group (a finger, or the rail) starting at ``t0_s``."""

    t0_s: float
    move: Move | Bounce  # (a ``Bounce``: a repeat, out and back to its start)

    @property
    def t1_s(self) -> float:
        return self.t0_s + self.move.duration_s


@dataclass
class _Track:
    """One joint group's segments, in time order, and where it is at their end."""

    q: np.ndarray
    segments: list[Segment] = field(default_factory=list)
    starts: list[float] = field(default_factory=list)  # their start times (for bisection)
    free_s: float = 0.0  # the end of its last segment

    def add(self, t0_s: float, move: Move) -> float:
        if move.duration_s <= 0.0:
            return t0_s
        t0_s = max(t0_s, self.free_s)
        self.segments.append(Segment(t0_s, move))
        self.starts.append(t0_s)
        self.q = move.q_end
        self.free_s = t0_s + move.duration_s
        return self.free_s

    def at(self, t_s: np.ndarray, q_start: np.ndarray) -> np.ndarray:
        """Positions at sorted times ``t_s`` (each segment's rows at once: a hold of an
        hour costs what a hold of a second does)."""
        t_s = np.asarray(t_s, dtype=float)
        if self.segments and len(t_s) and t_s[0] >= self.free_s:  # (all after its last
            # segment: where that one ended, ``self.q``, as below; most tracks, most rows)
            return np.tile(self.q, (len(t_s), 1))
        out = np.tile(q_start, (len(t_s), 1))
        if not self.segments or len(t_s) == 0:
            return out
        # (only the segments from the one running at the first time on: the rows asked
        # for are the next ones, and a long song's track has thousands of segments)
        i0 = max(0, bisect.bisect_right(self.starts, t_s[0]) - 1)
        idx = np.searchsorted(self.starts[i0:], t_s, side="right") - 1 + i0
        first = int(np.searchsorted(idx, 0, side="left"))  # (rows before every segment:
        # q_start)
        if first == len(idx):
            return out
        # (every row after the first segment's start at once: each row's segment, the
        # one running or the last ended, its move's profile, or its end once it is over)
        lo = int(idx[first])
        segs = self.segments[lo:int(idx[-1]) + 1]
        of = idx[first:] - lo
        # (a repeat's ``Bounce`` comes back to its start: its own profile, ``bounce_s``
        # of its ramps ``tb``, and its end at 0; its double-S phases, never read, are its
        # halves')
        t0, dur, ta, tj, bj, ba, bb, back = np.array([
            (g.t0_s, g.move.duration_s,
             *((0.5 * g.move.duration_s, 0.25 * g.move.duration_s, g.move.tj_s, g.move.ta_s,
                g.move.tb_s, 1.0) if g.move.back else
               (g.move.ta_s, g.move.tj_s, 0.0, 0.0, 0.0, 0.0)))
            for g in segs]).T[:, of]
        q_a = np.array([g.move.q_a for g in segs])[of]
        dq = np.array([g.move.dq for g in segs])[of]
        tt = t_s[first:]
        s = path_s(tt - t0, dur, ta, tj)
        if back.any():
            k = back > 0.0
            s[k] = bounce_s(tt[k] - t0[k], dur[k], bj[k], ba[k], bb[k])
            dq_end = np.where(back[:, None] > 0.0, 0.0, dq)
        else:
            dq_end = dq
        moving = (tt < t0 + dur)[:, None]  # (before its end, ``Segment.t1_s``)
        out[first:] = np.where(moving, q_a + s[:, None] * dq, q_a + dq_end)
        return out


@dataclass
class _Finger:
    track: _Track
    pose: str = "high"  # "high", "hover" or "press"
    entry: AtlasEntry | None = None  # the key it is over
    note: int | None = None  # the note it presses
    up_s: float = -math.inf  # when that note's key is to come up
    high_s: float = 0.0  # when it was last back at crossing height
    safe_s: float = 0.0  # ... and clear above every key on its way there (the arm may move:
    # ``planner.play.highclear``)
    black_s: float = 0.0  # ... by the black rule alone (the arm may change its posture)


@dataclass(frozen=True)
class Outcome:
    note: int
    down_s: float | None  # planned key-down moment (None: not pressed)
    up_s: float | None
    skip: SkipReason | None = None
    detail: str = ""


def _bounce(moves: Places, st: _Finger, e: AtlasEntry, want: float, floor: float,
            committed_s: float):
    """A repeat of the key finger ``st`` presses (``approach``'s answer, or None): one
    ``Bounce`` (``Moves.repeat``) that puts the key down at ``want`` and lets it up by the
    note before's key-up ``st.up_s``: earlier where their room is less than its gap
    (``repeat_gap_s``: the programme counts the frames), played slower where it is more
    (the key up at ``st.up_s`` exactly), up to ``BOUNCE_STRETCH`` times its time; with more
    room, None: the lift and descent from rest (``Moves.repeat_pair``) fit there, and
    those to the atlas's rise pose (2 mm above the key-down depth, crossing it faster:
    the physics' key goes down nearer the rows' time) where the room is more still."""
    b = moves.repeat(e)
    gap = b.duration_s - 2.0 * b.cross_s
    room = want - st.up_s
    if room >= BOUNCE_STRETCH * gap:
        return None
    sigma = max(1.0, room / gap)
    move, up_s = b.move.slowed(sigma), b.cross_s * sigma
    t0 = max(want - (move.duration_s - up_s), st.track.free_s, committed_s,
             floor - 0.5 * move.duration_s)  # (its way down no earlier than a descent's)
    if t0 + up_s > st.up_s + 1e-9:  # (the key would come up late: not this way)
        return None
    return t0 + move.duration_s - up_s, [(t0, move)], "bounce"


def _struck(found, struck: float, up_s: float, timed_by: Places, e: AtlasEntry):
    """``approach``'s (key-down moment, steps, start) with the key put down at ``struck``
    (``keytimes.struck_s``: a late key after the note's first row) where that is later:
    the last step, the descent, starts that much later (a repeat's bounce only while its
    key-up stays by the note before's, ``up_s``); and when the press ends (the last step's
    end for a repeat's own moves, else the descent's from ``start``): (key-down moment,
    steps, press end)."""
    down_at, steps, start = found
    t0, last = steps[-1]
    if struck > down_at and (start != "bounce" or 2.0 * t0 + last.duration_s + struck
                             - 2.0 * down_at <= up_s + 1e-9):
        steps = steps[:-1] + [(t0 + struck - down_at, last)]
        down_at = struck
    if start in ("bounce", "repeat"):
        return down_at, steps, steps[-1][0] + steps[-1][1].duration_s
    desc = timed_by.descend(e, start)
    return down_at, steps, down_at + desc.duration_s - desc.cross_s


def approach(moves: Places, st: _Finger, e: AtlasEntry, want: float, after_s: float,
             rail_free_s: float, committed_s: float, front: bool = True):
    """The moves that bring finger ``st`` from where it is to key-down on ``e`` (no
    earlier than ``want``, no move starting before ``after_s`` nor ``committed_s`` (the
    rows written), below crossing height only once the rail is still, at
    ``rail_free_s``, or clear above every key until then by the front rule, ``front``,
    or the black rule alone, after a move that changed the play posture): (key-down
    moment, [(t0, move), ...], the pose its last descent starts from: "bounce" and
    "repeat" for a repeat's, ``Moves.repeat`` and ``repeat_pair``), or None when no
    checked path leads there."""
    floor = max(rail_free_s, committed_s, after_s)
    if st.pose == "press" and st.entry is e and moves.repeat(e) is not None:
        # (the same key again: a bounce, or up to the repeat's top and down)
        got = _bounce(moves, st, e, want, floor, committed_s)
        if got is not None:
            return got
        lift, desc = moves.repeat_pair(e)
        up, down = moves.lift(e, "rise"), moves.descend(e, "rise")
        if want - st.up_s >= (up.duration_s - up.cross_s) + down.cross_s:
            lift, desc = up, down  # (room for the whole line: its faster crossings)
        t_lift = min(want - desc.cross_s - lift.duration_s, st.up_s - lift.cross_s)
        t_lift = max(t_lift, st.track.free_s, committed_s)
        if t_lift + lift.cross_s <= st.up_s + 1e-9:  # (its key up by the note before's end)
            t_desc = max(want - desc.cross_s, t_lift + lift.duration_s, floor)
            return t_desc + desc.cross_s, [(t_lift, lift.move), (t_desc, desc.move)], "repeat"
        # (a press that ends late lifts too slowly to the rise: the short move crosses the
        # key-down depth later than the lift to crossing height, which the note's own
        # check (``Motion.place``, TOO_SHORT) holds within its end: that way, then down)
    if st.pose == "hover" and st.entry is e:  # waiting over this key already
        desc = moves.descend(e, "hover")
        t_desc = max(want - desc.cross_s, st.track.free_s, floor)
        return t_desc + desc.cross_s, [(t_desc, desc.move)], "hover"
    steps: list[tuple[float, Move]] = []
    t = max(st.track.free_s, committed_s, after_s)  # (a finger high may cross
    # while the rail moves: nothing under a tip that high is higher than it)
    if st.pose != "high":  # let its key up on time (pressing), rise to crossing height
        up = up_move(moves, st)
        t_up = max(st.up_s - up.cross_s, st.track.free_s, committed_s) \
            if st.pose == "press" else max(st.track.free_s, committed_s)
        steps.append((t_up, up.move))
        t = max(t, t_up + up.duration_s)
    across = None
    if st.entry is not e:
        across = moves.across(st.entry, e)
        if across is None:
            return None
    d_high, d_hover = moves.descend(e, "high"), moves.descend(e, "hover")
    to_hover = moves.to_hover(e)
    across_s = across.duration_s if across is not None else 0.0
    low = max(t + across_s, floor)  # below crossing height only once the rail is still
    if low + to_hover.duration_s + WAIT_MARGIN_S <= want - d_hover.cross_s:
        # time to wait at hover: get there just in time, then straight down
        t_hover = want - d_hover.cross_s - WAIT_MARGIN_S - to_hover.duration_s
        if across is not None:
            steps.append((max(t, t_hover - across_s), across))
        steps.append((t_hover, to_hover))
        steps.append((want - d_hover.cross_s, d_hover.move))
        return want, steps, "hover"
    if across is not None:
        steps.append((t, across))
    # (from crossing height it may start down while the rail moves, clear above every key
    # until the rail is still: ``planner.play.highclear``)
    low = max(t + across_s, rail_free_s - moves.high.descent_clear_s(e, d_high.move, front),
              committed_s, after_s)
    t_desc = max(want - d_high.cross_s, low)
    steps.append((t_desc, d_high.move))
    return t_desc + d_high.cross_s, steps, "high"


class Motion(ArmMotion):
    """Builds the segments note by note (``place``); ``rows`` samples them (the arm's
    moves and the fingers riding along on them: ``ArmMotion``)."""

    def __init__(self, notes, places: Places, rate_hz: float, rail0_m: float,
                 posture: int = 0, park: bool = False) -> None:
        """``park``: the hand has nothing to play (asked, or none of its fingers presses
        any key); it waits with every tip at crossing height (``Atlas.park``) and never
        moves. The arm starts at ``rail0_m`` in play posture ``posture``."""
        atlas = places.atlases[posture]
        self.notes, self.places, self.moves = notes, places, places
        self.hand = places.hand
        self.dt = 1.0 / rate_hz
        self.q0 = atlas.base.copy()
        self.arm = places.arm  # (the rail, and the reach axis if the rig has one)
        if places.rail is not None:
            self.q0[places.rail] = rail0_m
        self.posture = posture
        reach = places.reach_m(posture)  # (the reach axis before and after the arm's last
        self.arm_reaches = (reach, reach)  # move: its descents' rule, ``descent_front``)
        # (the arm's joints, ``arm``, as one track: the rail alone on a hand without a reach axis)
        self.arm_track = _Track(np.array([rail0_m, places.reach_m(posture)][:max(1, len(self.arm))]))
        self.fingers = {f: _Finger(_Track(self.q0[self.hand.joint_slice(f)].copy()))
                        for f in self.hand.fingers}
        entries = {} if park else start_entries(atlas, rail0_m)
        if not entries:
            self.q0 = places.atlas.park()
            if places.rail is not None:
                self.q0[places.rail] = rail0_m
            for f, st in self.fingers.items():
                st.track.q = self.q0[self.hand.joint_slice(f)].copy()
        else:
            self._start_high(entries)
        self._tuck()
        self.committed_s = 0.0  # nothing may start before this (rows written up to it)
        self._strikers: dict[float, set[str]] = {}  # (``expect``: by key-down time)
        self._next: dict[str, tuple[list[float], list[Assignment]]] = {}  # (``expect``:
        # each finger's notes to strike, by key-down time)
        self.outcomes: dict[int, Outcome] = {}

    def entry(self, a: Assignment) -> AtlasEntry | None:
        """The entry of an assignment: its finger over its key from its place."""
        return self.places.atlases[a.posture].entry(a.finger, self.notes[a.note].pitch, a.rail_m)

    def _start_high(self, entries: dict[str, AtlasEntry]) -> None:
        """The hand starts with every finger at crossing height over the key nearest its
        natural place (``entries``, ``start_entries``; the first row: no tip near a key)."""
        for f, e in entries.items():
            st = self.fingers[f]
            st.entry = e
            st.track.q = e.high.copy()
            self.q0[self.hand.joint_slice(f)] = e.high
        self.q0 = self.hand.apply_couplings(self.q0)

    def _tuck(self) -> None:
        """The fingers that press no key (``planner.play.idle``) hold, all song long,
        the pose nearest their natural one whose body enters no key's column in any
        posture (``IdleFingers.pose``, ``IdleFingers.tuck``; the rest pose has them there too:
        the default hand's thumb hangs 52 mm below the keys' tops in its third posture's
        natural hand, inside a white key's column)."""
        q0 = self.places.idle.tuck(self.q0)
        if q0 is not self.q0:
            self.q0 = q0
            for f in self.places.idle.fingers:
                self.fingers[f].track.q = q0[self.hand.joint_slice(f)].copy()

    def prepared(self, assignments) -> list:
        """The first assignment of each finger, of those at the start rail (in onset
        order): the fingers that wait over their first key from the start."""
        seen, out = set(), []
        for a in sorted(assignments, key=lambda a: self.notes[a.note].onset_s):
            if a.finger in seen:
                continue
            seen.add(a.finger)
            if abs(a.rail_m - self.arm_track.q[0]) <= 1e-9 and a.posture == self.posture:
                out.append(a)
        return out

    def prepare(self, assignments) -> None:
        """Before the first row: each finger whose first note is at the start rail waits
        at crossing height over its key (``prepared``); the hand comes there from rest
        (``planner.play.rest``), so no key is down when the motion starts."""
        for a in self.prepared(assignments):
            st = self.fingers[a.finger]
            e = self.entry(a)
            st.entry = e
            st.track.q = e.high.copy()
            self.q0[self.hand.joint_slice(a.finger)] = st.track.q
        self.q0 = self.hand.apply_couplings(self.q0)

    def start_after(self, t_s: float, notes) -> None:
        """The hand reaches ``q0`` at ``t_s`` (its way in from rest): no move starts
        before then; ``notes`` are the song's notes in the file's time, which the
        motion times from now on."""
        self.notes = notes
        for track in [self.arm_track] + [st.track for st in self.fingers.values()]:
            track.free_s = max(track.free_s, t_s)
        for st in self.fingers.values():
            st.high_s = max(st.high_s, t_s)
            st.safe_s = max(st.safe_s, t_s)
            st.black_s = max(st.black_s, t_s)
        self.committed_s = max(self.committed_s, t_s)

    # ------------------------------------------------------------------ timing targets
    def t_down(self, note: int) -> float:
        return key_down_s(self.notes[note].onset_s, self.dt)

    def t_up(self, note: int, release_s: float | None = None) -> float:
        end = self.notes[note].offset_s if release_s is None else min(release_s,
                                                                       self.notes[note].offset_s)
        return key_up_s(end, self.dt)

    # ------------------------------------------------------------------ placing
    def place(self, a: Assignment) -> Outcome:
        """Schedule note ``a.note`` (after every note of earlier onset)."""
        n = self.notes[a.note]
        e = self.entry(a)
        if abs(self.arm_track.q[0] - a.rail_m) > 1e-9 or a.posture != self.posture:
            strikers = self._strikers.get(self.t_down(a.note), set()) | {a.finger}
            reaches = (self.places.reach_m(self.posture), self.places.reach_m(a.posture))
            self._move_rail(a.rail_m, a.posture, self._arrive_by_s(a, e, reaches), strikers)
        st = self.fingers[a.finger]
        want = self.t_down(a.note)
        after = self._release_others_on(n.pitch, a.finger)
        front = self.descent_front(e)
        found = approach(self.moves, st, e, want, after, self.arm_track.free_s,
                         self.committed_s, front)
        if found is None:
            out = Outcome(a.note, None, None, SkipReason.NO_PATH,
                          f"no checked path of the {a.finger} to it")
            self.outcomes[a.note] = out
            return out
        found, timed_by = within_motors(self, a.finger, found, lambda places: approach(
            places, st, e, want, after, self.arm_track.free_s, self.committed_s, front))
        down_at, steps, press_end = _struck(found, struck_s(n.onset_s, found[0], self.dt),
                                            st.up_s, timed_by, e)
        up = self._held_enough_s(a.note, down_at, self.t_up(a.note, a.release_s),
                                 self.t_up(a.note))
        lift = self.moves.lift(e, "high")
        shortest = self.moves.press_min_s(e)
        if up - want < shortest:
            out = Outcome(a.note, None, None, SkipReason.TOO_SHORT,
                          f"{1000 * n.duration_s:.0f} ms long; the {a.finger}'s shortest "
                          f"press down and up takes {1000 * shortest:.0f} ms")
        elif down_at > n.onset_s + DROP_FRACTION * n.duration_s:
            out = Outcome(a.note, None, None, SkipReason.TOO_LATE,
                          f"its key could go down {1000 * (down_at - want):.0f} ms late, "
                          "after half of it")
        elif press_end + lift.cross_s > up:
            out = Outcome(a.note, None, None, SkipReason.TOO_SHORT,
                          f"{1000 * n.duration_s:.0f} ms long; a press down and up takes "
                          f"{1000 * (press_end + lift.cross_s - down_at):.0f} ms")
        else:
            for t0, move in steps:
                st.track.add(t0, move)
            st.pose, st.entry, st.note, st.up_s = "press", e, a.note, up
            out = Outcome(a.note, down_at, up)
        self.outcomes[a.note] = out
        return out

    def _to_high(self, st: _Finger, latest_s: float = math.inf) -> float:
        """The finger rises to crossing height: a pressing one lets its key up at its
        planned time or by ``latest_s``, whichever is first (never before its press is
        done). Returns when it is up."""
        if st.pose == "high":
            return st.high_s
        up = up_move(self.moves, st)
        if st.pose == "press":
            o = self.outcomes.get(st.note) if st.note is not None else None
            if o is not None and o.down_s is not None:
                latest_s = self._held_enough_s(st.note, o.down_s, latest_s, st.up_s)
            t0 = min(st.up_s, latest_s) - up.cross_s
            t0 = max(t0, st.track.free_s, self.committed_s)
            self._shorten(st, t0 + up.cross_s)
        else:
            t0 = max(st.track.free_s, self.committed_s)
        end = st.track.add(t0, up.move)
        st.safe_s = end - up.move.duration_s + self.moves.high.rise_clear_s(st.entry, up.move)
        st.black_s = end - up.move.duration_s + self.moves.high.rise_clear_s(
            st.entry, up.move, front=False)
        st.pose, st.note, st.high_s = "high", None, end
        return end

    def _held_enough_s(self, note: int, down_s: float, cut_s: float, up_s: float) -> float:
        """``keytimes.held_enough_s`` of ``note`` (the programme reads the same)."""
        n = self.notes[note]
        return held_enough_s(n.onset_s, n.offset_s, down_s, cut_s, up_s, self.dt)

    def _release_others_on(self, pitch: int, finger: str) -> float:
        """Another finger on key ``pitch`` (pressing or waiting) leaves it, on time, for
        crossing height; returns when the key is free of it."""
        clear = -math.inf
        for g, st in self.fingers.items():
            if g != finger and st.pose != "high" and st.entry is not None \
                    and (st.entry.pitch_class == pitch % 12) \
                    and abs(st.entry.dx_m + self.arm_track.q[0] - _key_x(pitch)) < 0.005:
                clear = max(clear, self._to_high(st))
        return clear

    def expect(self, assignments) -> None:
        """The fingers that strike at each onset (``assignments``, a chunk of the
        fingering's, before they are placed): a finger about to strike does not ride
        along on a move of the arm (``_holds``)."""
        for a in assignments:
            self._strikers.setdefault(self.t_down(a.note), set()).add(a.finger)
            times, notes = self._next.setdefault(a.finger, ([], []))
            i = bisect.bisect_right(times, self.t_down(a.note))
            times.insert(i, self.t_down(a.note))
            notes.insert(i, a)

    def lift_by_s(self, st: _Finger, arm_s: float, after_s: float, front: bool = True) -> float:
        """The latest key-up of pressing (or waiting) finger ``st`` for a move of the arm
        starting at ``arm_s``: clear above every key by then (``planner.play.highclear``,
        by the front rule or, ``front`` False, a move that changes the posture, the black),
        and, where it strikes again after ``after_s`` (``expect``), at crossing height in
        time to move across and down onto that key on time (its lift's end is where its
        move across starts: a finger striking the move's note lifts that early even where
        the arm starts later); where no checked path takes it there, by the lift that
        ends at ``arm_s``."""
        up = up_move(self.moves, st)
        by_end = arm_s - up.duration_s + up.cross_s
        latest = arm_s - self.moves.high.rise_clear_s(st.entry, up.move, front) + up.cross_s
        times, notes = self._next.get(st.entry.finger, ((), ()))
        i = bisect.bisect_right(times, after_s)
        if i < len(times):
            e = self.entry(notes[i])
            if e is None:
                return by_end
            across = None if e is st.entry else self.moves.across(st.entry, e)
            if across is None and e is not st.entry:
                return by_end
            across_s = 0.0 if across is None else across.duration_s
            high_by = times[i] - self.moves.descend(e, "high").cross_s - across_s
            latest = min(latest, high_by - up.duration_s + up.cross_s)
        return latest

    def cut(self, note: int, release_s: float) -> None:
        """The programme cut ``note`` (held) at ``release_s``: its key comes up by then."""
        for st in self.fingers.values():
            if st.pose == "press" and st.note == note:
                st.up_s = min(st.up_s, self.t_up(note, release_s))
                self._shorten(st, st.up_s)

    def _shorten(self, st: _Finger, up_s: float) -> None:
        if st.note is not None and st.note in self.outcomes:
            o = self.outcomes[st.note]
            if o.up_s is not None and up_s < o.up_s:
                self.outcomes[st.note] = Outcome(o.note, o.down_s, up_s, o.skip, o.detail)

    def commit(self, t_s: float) -> None:
        """Rows up to ``t_s`` are to be written: every key due up before then (and the
        lag after) is let up now, and nothing new starts before ``t_s``."""
        for st in self.fingers.values():
            if st.pose == "press" and st.up_s <= t_s + COMMIT_MARGIN_S:
                self._to_high(st)
        self.committed_s = max(self.committed_s, t_s)

    def finish(self, end_s: float) -> float:
        """Every key still down comes up on time, every finger rises; returns when the
        hand is still."""
        for st in self.fingers.values():
            self._to_high(st)
        return max([end_s, self.arm_track.free_s] + [s.track.free_s for s in self.fingers.values()])

    # ------------------------------------------------------------------ rows
    def rows(self, t_s: np.ndarray) -> np.ndarray:
        """Whole-hand configurations at times ``t_s`` (sorted)."""
        q = np.tile(self.q0, (len(t_s), 1))
        if self.arm:
            n = len(self.arm_track.q)
            q[:, self.arm[:n]] = self.arm_track.at(t_s, self.q0[self.arm[:n]])
        for f, st in self.fingers.items():
            js = self.hand.joint_slice(f)
            q[:, js] = st.track.at(t_s, self.q0[js])
        return self.hand.apply_couplings(q)
