"""When a finger going up or down is high enough for the arm to move under it.

The arm moves (the rail, the reach axis) only while every finger that does not follow its
key is clear above every key top wherever the rail is: with the body rule, every body of
the finger ``CLEARANCE_M`` above the black keys' tops (the clearance a tip keeps over a
key it passes, ``planner.play.atlassolve``); without it, the tip above ``HIGH_SAFE_Z_M``
(``planner.play.movetable``: the rule a finger's own move across at crossing height
keeps while the arm moves). A lift to crossing height (the tip at ``HIGH_Z_M``, 7.5 mm
above the black tops) passes that height before its end, and a descent from crossing
height leaves it after its start: the arm may start once every lifting finger is above
it for good, and a descent may start while the arm still moves, as long as the finger
stays above it until the arm is still. The lift's slow last millimetres (the profile's
braking) and the descent's first overlap the arm's move instead of adding to it (a
pose at crossing height whose body is not that high: the whole lift, as before).

**The front rule.** A body in front of the black keys (a press on a white key's wide
front: the default hand's long fingers in its first postures) passes over nothing but
the white keys' tops while the rail moves along x: there it is clear ``CLEARANCE_M``
above the white tops (``FRONT_CLEAR_Z_M``), where it lies in front of the black keys'
front less the body rule's tolerance (``FRONT_Y_M``). A point of the path is clear when
each body of the finger is clear by the black rule or by this one; the path is tested at
``FRONT_SAMPLES`` points (the two rules together need not be monotone along it: a
finger lifting from a front press may pass behind ``FRONT_Y_M`` before it is above the
black tops). A move of the arm that changes the play posture moves the hand along y
(the reach axis, + into the keyboard: a translation, the heights unchanged). Before a
move out of the keyboard the lifts keep the front rule (``front_rules``): a body in front
of the black keys at the lift's moment only goes further out while the arm moves. Before
a move in, which carries the bodies towards the black keys, a lift keeps the front rule
where every body the rule finds clear below the black tops lies further in front of the
black keys than the arm can carry it until it is above them (``HighClear.front_room_m``
against the move's length or ``reach_bound_m`` of the lift's time from its front moment
to its black one; ``lift_front``), else the black rule's. A descent after a move out of
the keyboard, which the arm ends still further in, keeps the front rule where its room
holds the move's length or the arm's travel to rest over the descent's time from its
black moment to its front one (``descent_front``: the descent is the lift backwards,
the bound holds backwards from rest), else the black rule's. The descents after a move
in keep the black rule. (A body in front at the descent's moment was further out before:
the front rule would hold there too, but the arm, moving as late as the descents allow,
then ends later, and the programme's choices around it lose more: 4 chorales' frame F1
down by up to 0.010, ``docs/history/2026-12-07-play-notes.md``; the corpus 0.9659 ->
0.9656, ``docs/history/2026-12-07-play-post.md``.) Both rules' moments are shipped in
the move tables (``CLEAR_COLUMNS``).

``HighClear`` finds, for a straight move of one finger's joints (``profile.Move``), the
time from which (a rise) or until which (a descent) the finger stays above that height: the
point of the path where it crosses it, by forward kinematics at ``SAMPLES`` points and
bisection between the two around the crossing (the height along a straight
joint-space move between poses straight above the key is monotone there), then the
time at which the move's profile reaches that point. The path's point is memoised per
entry and poses; the time is the move's own (a move slowed for the motors reaches it
later).
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence

import numpy as np

from planner.hand.model import HandModel
from planner.music import keyboard as kb
from planner.play.atlas import Atlas, AtlasEntry
from planner.play.atlassolve import CLEARANCE_M
from planner.play.fingerbody import OTHER_KEY_TOLERANCE_M
from planner.play.movetable import HIGH_SAFE_Z_M, MoveTable
from planner.play.profile import Move
from planner.play.tendonload import MAX_SCALE

SAMPLES = 5  # points of the path tested by forward kinematics (ends included)
BISECTIONS = 5  # then halvings between the two samples around the crossing: 1/128 of
# the path (about 0.25 mm of a 30 mm lift), the answer on the safe side
BODY_CLEAR_Z_M = kb.BLACK_TOP_Z_M + CLEARANCE_M  # every body this high clears every key
WHITE_TOP_Z_M = 0.0  # the white keys' tops (``planner.music.keyboard.key``)
FRONT_CLEAR_Z_M = WHITE_TOP_Z_M + CLEARANCE_M  # a body in front of the black keys this
# high clears every key under it (the same clearance over the white tops)
FRONT_Y_M = kb.BLACK_Y0_M - OTHER_KEY_TOLERANCE_M  # ... in front of this: the black keys'
# front less the body rule's tolerance (``planner.play.fingerbody``: a body touching a key
# by that much does not press it; the rail lands up to that far off its sample)
FRONT_SAMPLES = 33  # the front rule's points of the path (ends included), then
FRONT_BISECTIONS = 2  # halvings: the same 1/128 of the path as the black rule's search
TIME_STEPS = 400  # the time is read from the profile at this many steps (the later/
# earlier one, on the safe side: 0.15 ms of a 60 ms lift)
CLEAR_MOVES = ("lift", "rise", "descent")  # an entry's moves whose moments are shipped:
# ``Moves.lift(e, "high")``, ``Moves.rise(e)``, ``Moves.descend(e, "high")``
CLEAR_RULES = ("front", "black")  # the table's columns: each move by the front rule, then
# each by the black rule alone (``column``)
ROOM_COLUMN = len(CLEAR_MOVES) * len(CLEAR_RULES)  # the table's column after the moments:
# the entry's front room (``HighClear.front_room_m``, a function of the entry alone)


def front_rules(reach_from_m: float, reach_to_m: float) -> tuple[bool, bool]:
    """Whether the lifts before a move of the arm from reach ``reach_from_m`` to
    ``reach_to_m`` (the reach axis: + into the keyboard), and the descents after it, are
    timed by the front rule (True) or the black rule alone (False): both by the front
    rule where the reach stays; the lifts where the move takes the hand out of the
    keyboard (a body in front of the black keys only goes further out); the descents of
    a change of posture by the black rule (the module's docstring; after a move out, an
    entry's own room may keep the front rule: ``HighClear.descent_front``)."""
    if reach_to_m == reach_from_m:
        return True, True
    return reach_to_m < reach_from_m, False


def column(move: int, front: bool) -> int:
    """The move table's column of ``CLEAR_MOVES[move]``'s moment by the front rule (or
    the black rule alone)."""
    return move + (0 if front else len(CLEAR_MOVES))


def params() -> str:
    """What the shipped moments depend on besides the move table's own parameters (a
    table made with others is not read: ``MoveTable.clear_s``)."""
    return json.dumps({"samples": SAMPLES, "bisections": BISECTIONS,
                       "body_clear_z_m": BODY_CLEAR_Z_M, "high_safe_z_m": HIGH_SAFE_Z_M,
                       "time_steps": TIME_STEPS, "moves": CLEAR_MOVES,
                       "front_clear_z_m": FRONT_CLEAR_Z_M, "front_y_m": FRONT_Y_M,
                       "front_samples": FRONT_SAMPLES, "front_bisections": FRONT_BISECTIONS,
                       "rules": CLEAR_RULES, "room_column": ROOM_COLUMN}, sort_keys=True)


class HighClear:
    """The moments a finger passes the height that clears every key, on its way up or
    down."""

    def __init__(self, hand: HandModel, atlases: Sequence[Atlas] | Mapping[int, Atlas],
                 moves: Sequence | None = None) -> None:
        """``atlases``: by play posture; ``moves``: each posture's ``Moves`` (its move
        table's shipped moments, read when its moves are the entry's own; None: every
        moment searched)."""
        self.hand = hand
        self.atlases = atlases
        self.moves = moves
        self._path: dict[tuple, float] = {}
        self._room: dict[int, tuple[AtlasEntry, float]] = {}  # (``front_room_m``)
        # (``lift_front`` and ``descent_front``, by entry, move and which: ``_front``)
        self._fronts: dict[tuple, tuple[AtlasEntry, bool]] = {}
        self._params = params()

    def rise_clear_s(self, e: AtlasEntry, move: Move, front: bool = True) -> float:
        """Seconds into ``move`` (``e``'s finger rising) from which it stays clear above
        every key to the move's end (its duration if it never is, or only at
        the end); ``front``: by the front rule too (False: the black rule alone, a
        move of the arm that changes the play posture)."""
        got = self._shipped(e, move, True, front)
        if got is not None:
            return got
        return _time_at(move, self._point(e, move, True, front), rising=True)

    def descent_clear_s(self, e: AtlasEntry, move: Move, front: bool = True) -> float:
        """Seconds into ``move`` (``e``'s finger descending from crossing height) until
        which it stays clear above every key (0 if it starts below that); ``front`` as
        in ``rise_clear_s``."""
        got = self._shipped(e, move, False, front)
        if got is not None:
            return got
        return _time_at(move, self._point(e, move, False, front), rising=False)

    def clear_row(self, e: AtlasEntry, moves) -> list[float]:
        """The moments of ``e``'s ``CLEAR_MOVES`` (``moves``: its posture's ``Moves``) by
        each of ``CLEAR_RULES``, searched, then its front room (``room_of``, column
        ``ROOM_COLUMN``): the move table's row."""
        return [m for front in (True, False) for m in (
            self.rise_clear_s(e, moves.lift(e, "high").move, front),
            self.rise_clear_s(e, moves.rise(e).move, front),
            self.descent_clear_s(e, moves.descend(e, "high").move, front))
            ] + [self.room_of(e, moves)]

    def front_room_m(self, e: AtlasEntry) -> float:
        """How far the arm may carry entry ``e``'s finger into the keyboard (+y) while it
        goes up with its front rule's moments still true: the least distance, over the
        points of its ways up (``Moves.lift(e, "high")`` from the press, ``Moves.rise(e)``
        from hover; ``FRONT_SAMPLES`` points each) where it is clear by the front rule,
        from ``FRONT_Y_M`` to the furthest-in body lower than the black rule's height,
        each sample's y grown by its step to the next along the path (inf: none lower; 0
        without the body rule or the move tables). Read from the posture's move table where
        it holds the entry (``ROOM_COLUMN``), else found (``room_of``); memoised per entry."""
        got = self._room.get(id(e))
        if got is not None:
            return got[1]
        room = 0.0
        if self.moves is not None:
            m = self.moves[e.posture]
            room = m.table.clear_s(e, ROOM_COLUMN, self._params)
            if room is None:
                room = self.room_of(e, m)
        self._room[id(e)] = (e, room)  # (the entry kept: its id stays its own)
        return room

    def room_of(self, e: AtlasEntry, m) -> float:
        """``front_room_m`` of entry ``e`` found by forward kinematics on its posture's
        moves ``m`` (its ``Moves``): 0 without the body rule."""
        room = 0.0
        bodies = self.atlases[e.posture].bodies
        if bodies is not None:
            h = self.hand
            ss = np.linspace(0.0, 1.0, FRONT_SAMPLES)[:, None]
            Q = np.repeat(self.atlases[e.posture].base[None], 2 * FRONT_SAMPLES, axis=0)
            Q[:, h.joint_slice(e.finger)] = np.concatenate(
                [up.q_a + ss * up.dq for up in (m.lift(e, "high").move, m.rise(e).move)])
            Q = h.apply_couplings(Q)  # (row by row: its laws act on the last axis)
            p, r = bodies.points_many(Q, e.finger), bodies.radii(e.finger)
            low, y = p[:, :, 2] - r, p[:, :, 1] + r
            black = low >= BODY_CLEAR_Z_M
            clear = np.all(black | ((y <= FRONT_Y_M) & (low >= FRONT_CLEAR_Z_M)), axis=1)
            lows = ~black & clear[:, None]  # (the bodies the front rule alone counts clear)
            # (between two samples a body lies within its change between them of either:
            # each sample's y is taken with the larger step to its neighbours on its path)
            step = np.abs(np.diff(y.reshape(2, FRONT_SAMPLES, -1), axis=1))
            pad = np.zeros((2, 1, step.shape[2]))
            step = np.maximum(np.concatenate([pad, step], 1), np.concatenate([step, pad], 1))
            y = y + step.reshape(y.shape)
            room = float(FRONT_Y_M - np.max(y[lows])) if lows.any() else math.inf
        return room

    def reach_bound_m(self, t_s: float) -> float:
        """The furthest the arm's reach axis can move in ``t_s`` from rest: its acceleration within its bound ``A`` and changing no
        faster than its jerk bound ``J`` (the posture's moves', ``Moves.acceleration``,
        ``jerk``: every move of the arm keeps them), so ``J t^3 / 6`` up to ``A / J`` and
        at ``A`` after (inf on a hand without the reach axis or the move tables)."""
        j = self.hand.index.get("reach")
        if j is None or self.moves is None:
            return math.inf
        a, jerk = float(self.moves[0].acceleration[j]), float(self.moves[0].jerk[j])
        t1 = a / jerk
        if t_s <= t1:
            return jerk * t_s ** 3 / 6.0
        u = t_s - t1
        return jerk * t1 ** 3 / 6.0 + 0.5 * a * t1 * u + 0.5 * a * u * u

    def lift_front(self, e: AtlasEntry | None, reach_from_m: float, reach_to_m: float) -> bool:
        """Whether entry ``e``'s lift before a move of the arm from reach ``reach_from_m``
        to ``reach_to_m`` is timed by the front rule: ``front_rules``' lifts, and on a
        move into the keyboard where every body the rule finds clear in front of the black
        keys stays in front while the arm carries it in (``front_room_m``) as far as the
        move goes, or as far as the arm can move (``reach_bound_m``) from the lift's front
        moment, the earliest it starts, to its black moment, from which every body is
        above the black tops (the later of its ways up: from the press, from hover)."""
        if front_rules(reach_from_m, reach_to_m)[0]:
            return True
        return e is not None and self._front(e, reach_to_m - reach_from_m, True)

    def descent_front(self, e: AtlasEntry | None, reach_from_m: float,
                      reach_to_m: float) -> bool:
        """Whether entry ``e``'s descent from crossing height after a move of the arm from
        reach ``reach_from_m`` to ``reach_to_m`` is timed by the front rule: ``front_rules``'
        descents (the same posture), and after a move out of the keyboard where every body
        the rule finds clear in front of the black keys stayed in front while the arm was
        still coming out (its ``front_room_m``: the descent is the lift backwards) by as
        much as the move's length, or as the arm's travel to rest over the descent's time
        from its black moment to its front one (``reach_bound_m``: the bound holds
        backwards from rest, an arm at rest with no acceleration; the time at the motors'
        slowest, ``tendonload.MAX_SCALE``: ``armload.within_motors`` may slow a descent so
        much). After a move into the keyboard the black rule (the front rule holds there
        too, but a later arrival of the arm keeps riders down longer: measured worse,
        ``docs/history/2026-12-07-play-post.md``)."""
        if front_rules(reach_from_m, reach_to_m)[1]:
            return True
        if e is None or reach_to_m > reach_from_m:
            return False
        return self._front(e, reach_to_m - reach_from_m, False)

    def _front(self, e: AtlasEntry, move_m: float, lifting: bool) -> bool:
        """``lift_front`` (``lifting``) or ``descent_front`` of entry ``e`` past the rules
        that need no search, the arm's move ``move_m`` long (into the keyboard > 0):
        memoised by entry, move and which (the entry kept)."""
        key = (id(e), move_m, lifting)
        got = self._fronts.get(key)
        if got is None:
            found = self._lift_found if lifting else self._descent_found
            got = self._fronts[key] = (e, found(e, move_m))
        return got[1]

    def _lift_found(self, e: AtlasEntry, move_m: float) -> bool:
        """``lift_front``'s search: the entry's front room against the move and the arm's
        reach from the lift's front moment to its black one."""
        m = self.moves[e.posture] if self.moves is not None else None
        gap = math.inf if m is None else max(
            self.rise_clear_s(e, up, False) - self.rise_clear_s(e, up)
            for up in (m.lift(e, "high").move, m.rise(e).move))
        return self.front_room_m(e) >= min(move_m, self.reach_bound_m(gap))

    def _descent_found(self, e: AtlasEntry, move_m: float) -> bool:
        """``descent_front``'s search (a move out of the keyboard, ``move_m`` <= 0): the
        entry's front room against the move and the arm's travel to rest over the
        descent's black-to-front time at the motors' slowest."""
        m = self.moves[e.posture] if self.moves is not None else None
        gap = math.inf
        if m is not None:
            d = m.descend(e, "high").move
            gap = self.descent_clear_s(e, d) - self.descent_clear_s(e, d, False)
        return self.front_room_m(e) >= min(-move_m, self.reach_bound_m(MAX_SCALE * gap))

    def _shipped(self, e: AtlasEntry, move: Move, rising: bool, front: bool) -> float | None:
        """The move table's moment when ``move`` is one of the entry's own
        ``CLEAR_MOVES`` (the very object its ``Moves`` keeps), else None."""
        if self.moves is None:
            return None
        m = self.moves[e.posture]
        table: MoveTable = m.table
        if rising:
            if move is m.lift(e, "high").move:
                return table.clear_s(e, column(0, front), self._params)
            if move is m.rise(e).move:
                return table.clear_s(e, column(1, front), self._params)
            return None
        if move is m.descend(e, "high").move:
            return table.clear_s(e, column(2, front), self._params)
        return None

    def _point(self, e: AtlasEntry, move: Move, rising: bool, front: bool) -> float:
        """The path parameter where the finger crosses the clear height: rising, the least
        from which every point after it is clear (1: none but the end); descending, the
        greatest up to which every point is (0: the start is not). A descent from a pose
        is the lift to it backwards: one search for both (memoised by the low end, the
        way up and the rule; a hand without the body rule has one rule)."""
        front = front and self.atlases[e.posture].bodies is not None
        low, up = (move.q_a, move.dq) if rising else (move.q_a + move.dq, -move.dq)
        key = (id(e), low.tobytes(), up.tobytes(), front)
        got = self._path.get(key)
        if got is None:
            got = self._path[key] = self._rise_point(e, low, up, front)
        return got if rising else 1.0 - got

    def _rise_point(self, e: AtlasEntry, q_low: np.ndarray, dq: np.ndarray,
                    front: bool) -> float:
        samples, bisections = (FRONT_SAMPLES, FRONT_BISECTIONS) if front \
            else (SAMPLES, BISECTIONS)
        ss = np.linspace(0.0, 1.0, samples)
        bad = [i for i, s in enumerate(ss) if not self._clear(e, q_low + s * dq, front)]
        if not bad:
            return 0.0
        i = bad[-1]
        if i == samples - 1:
            return 1.0
        lo, hi = ss[i], ss[i + 1]  # (lo below, hi clear: the answer hi, the safe side)
        for _ in range(bisections):
            mid = 0.5 * (lo + hi)
            if self._clear(e, q_low + mid * dq, front):
                hi = mid
            else:
                lo = mid
        return float(hi)

    def _clear(self, e: AtlasEntry, q_finger: np.ndarray, front: bool) -> bool:
        h = self.hand
        q = self.atlases[e.posture].base.copy()
        q[h.joint_slice(e.finger)] = q_finger
        q = h.apply_couplings(q)
        bodies = self.atlases[e.posture].bodies
        if bodies is None:
            return bool(h.tip_position(q, h.fingers.index(e.finger))[2] >= HIGH_SAFE_Z_M)
        p, r = bodies.points(q, e.finger)
        low = p[:, 2] - r
        if not front:
            return bool(np.min(low) >= BODY_CLEAR_Z_M)
        # (each body clear by the black rule, or in front of the black keys and clear
        # above the white ones)
        return bool(np.all((low >= BODY_CLEAR_Z_M)
                           | ((p[:, 1] + r <= FRONT_Y_M) & (low >= FRONT_CLEAR_Z_M))))


def _time_at(move: Move, s: float, rising: bool) -> float:
    """When ``move``'s profile reaches path point ``s``, read at ``TIME_STEPS`` steps on
    the safe side: rising, the first step at or past it; descending, the last step at or
    before it (0 for a point at the start, or a move of no duration)."""
    if s <= 0.0 or move.duration_s <= 0.0:
        return 0.0
    t = np.linspace(0.0, move.duration_s, TIME_STEPS + 1)
    if rising:
        return float(t[min(int(np.searchsorted(move.s(t), s, side="left")), TIME_STEPS)])
    return float(t[max(int(np.searchsorted(move.s(t), s, side="right")) - 1, 0)])
