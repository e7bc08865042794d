"""A finger's moves between atlas poses, timed: the one model of what the motion can
do, read by the fingering (as costs) and by the motion (as segments).

Every move is a time-optimal straight joint-space move (``profile.straight_move``)
between two poses of one finger, or of the rail. The moments that matter to the music
are the key crossings: a key sounds while a tip is ``DOWN_DEPTH_M`` below its top, so a
descent puts its key down part-way (``down_s`` after its start) and a lift lets it up
part-way (``up_s``). From them:

* ``press_min_s``: the shortest key-down interval a press can make (descend to full dip,
  lift at once);
* ``repeat_gap_s``: key up to key down again on the same key: one ``profile.Bounce`` up
  the press -> rise line until the key is ``REARM_M`` up, and back (``repeat``);
* ``move_gap_s``: key up on one key to key down on another, the rail still (lift to
  crossing height, across, down);
* ``before_rail_s`` / ``after_rail_s``: key up to the end of the lift, and the start of a
  descent from crossing height to key down, around a move of the rail (which waits for
  every finger at crossing height).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from functools import lru_cache
from typing import NamedTuple

import numpy as np

from planner.hand.model import HandModel
from planner.music import keyboard as kb
from planner.play.acrossproof import AcrossProof
from planner.play.atlas import (
    PATH_SAMPLES,
    Atlas,
    AtlasEntry,
)
from planner.play.follow import FOLLOW_STEP_M, HOLD_MARGIN_M
from planner.play.followmoves import FollowMoves
from planner.play.margin import margin_scale
from planner.play.margin import params as margin_params
from planner.play.movetable import (
    ACROSS_SAMPLES,
    ENDS,
    HIGH_SAFE_Z_M,
    REPEAT_COLUMNS,
    MoveTable,
    high_boxes,
    table_path,
)
from planner.play.profile import (
    LIMIT_FRACTION,
    Move,
    bounce_move,
    move_time_s,
    move_times_s,
    path_caps,
    straight_move,
)
from planner.play.railcap import rail_acceleration_cap
from planner.play.tendonload import slowed, tendon_load

REARM_M = 0.0005  # a repeat's top: the finger's lowest point this far above the key-down
# depth (the spec's 5 mm; any less deep is up, spec section 2), no higher: the key up in the
# rows the repeat gives (``planner.play.keytimes``). The physics' hand rises higher still (it
# sits 1.1-1.3 mm above its rows where a key pushes back: keytimes), so its key comes up too.
# Measured on the two voice pieces' 40 legato repeats (docs/history/2026-12-07-play-repeat.md):
# 0.2 / 0.5 / 1.0 mm lose 1.15 / 1.68 / 2.12 rows a repeat in the check, 2.67 / 2.40 / 2.52
# in the physics (a lower top crosses slower: its key goes down later there)
# what a move table's repeats were found with (``MoveTable.repeat_row``: read only if equal)
REPEAT_PARAMS = json.dumps({"rearm_m": REARM_M, "columns": REPEAT_COLUMNS})
CROSS_TOL = 1e-4  # the key crossing's path parameter is found to this precision (a few µs)
# an entry's moves timed within the tendons' capacity (``planner.play.tendonload``), each
# pair of poses one way or the other (the bound is the same both ways: computed from the
# first pose), the press's key pushing back on the finger in the first three
SCALE_PAIRS = (("press", "high"), ("press", "hover"), ("press", "rise"), ("hover", "high"))


@dataclass(frozen=True)
class Timed:
    """A move and the time after its start at which its key goes down (descent) or up
    (lift); ``cross_s`` is None for a move that crosses no key depth."""

    move: Move
    cross_s: float | None

    @property
    def duration_s(self) -> float:
        return self.move.duration_s


class EntryRecord(NamedTuple):
    """What the programme reads of an entry, kept by ``Moves``: its ``entry_times`` (its
    lifts and descents timed at their key crossings), its high and press poses as lists
    of floats, and its places in the move table (``MoveTable.index``, None: not in it)."""

    entry: AtlasEntry
    before_rail_s: float
    after_rail_s: float
    press_min_s: float
    high: list[float]
    press: list[float]
    places: tuple[int, int] | None


class RepeatMoves:
    """A ``Moves``' repeated key (its part of that class: the same hand, atlas, limits
    and memos): one ``Bounce`` up the press -> rise line to ``REARM_M`` above the key-down
    depth and back (``repeat``), the lift and descent from rest to the same top
    (``repeat_pair``), and the programme's ``repeat_gap_s``."""

    repeat_params = REPEAT_PARAMS  # (what its rows are found with: the move table's
    # ``repeat_arrays`` reads it here, as ``movetable`` cannot import this module)

    def repeat_gap_s(self, e: AtlasEntry) -> float:
        """Key up to key down again on the same key: the repeat's ``Bounce`` from its
        key-up crossing to its key-down crossing (``repeat``; no repeat from below: up to
        crossing height and down)."""
        return self.repeat_row(e)[4]

    def _repeat_row(self, e: AtlasEntry) -> tuple[float, ...]:
        """``repeat_found``'s row as the move table ships it (bit for bit), or found."""
        got = self.table.repeat_row(e, REPEAT_PARAMS)
        return self.repeat_found(e) if got is None else got

    def repeat_found(self, e: AtlasEntry) -> tuple[float, ...]:
        """(sigma, s_c, scale, cross_s, gap_s): the repeat's top and key crossing on the
        press -> rise line (``found_apex``), how much its line slows its ``Bounce``
        (``_line_scale``), the slowed bounce's key-up crossing, and ``repeat_gap_s``; the
        first four NaN where the line never lets the key up (``found_apex``: None)."""
        apex = self.found_apex(e)
        if apex is None:
            nan = float("nan")
            return nan, nan, nan, nan, self.before_rail_s(e) + self.after_rail_s(e)
        sigma, s_c = apex
        move = self._bounce(e, sigma)
        scale = self._line_scale(e, move)
        b = _slowed(move, scale)
        cross_s = b.time_at_s(s_c / sigma)
        return sigma, s_c, scale, cross_s, b.duration_s - 2.0 * cross_s

    def _repeat(self, e: AtlasEntry) -> Timed | None:
        """The repeat: one ``Bounce`` from the press straight up the atlas's press -> rise
        line until the finger's lowest point is ``REARM_M`` above the key-down depth
        (``repeat_apex``: the key up) and back, timed at its key-up crossing (its key-down
        crossing is as long before its end: the same point of the line both ways); None
        where the line never lets the key up (``repeat_apex``)."""
        sigma, _, scale, cross_s, _ = self.repeat_row(e)
        if math.isnan(sigma):  # (``Motion`` asks only where ``repeat_gap_s`` has one)
            return None
        return Timed(_slowed(self._bounce(e, sigma), scale), cross_s)

    def _bounce(self, e: AtlasEntry, sigma: float):
        js = self.js[e.finger]
        return bounce_move(e.press, e.press + sigma * (e.rise - e.press),
                           self.hand.velocity[js], self.acceleration[js], self.jerk[js])

    def repeat_apex(self, e: AtlasEntry) -> tuple[float, float] | None:
        """``found_apex``, as the move table ships it or found."""
        sigma, s_c = self.repeat_row(e)[:2]
        return None if math.isnan(sigma) else (sigma, s_c)

    def _repeat_pair(self, e: AtlasEntry) -> tuple[Timed, Timed] | None:
        """A repeat with time to spare (``Motion``): the lift up the same line to the same
        top and the descent back, two moves from rest (the finger may wait between)."""
        apex = self.repeat_apex(e)
        if apex is None:
            return None
        sigma, s_c = apex
        top = e.press + sigma * (e.rise - e.press)
        up, down = self._move(e.finger, e.press, top), self._move(e.finger, top, e.press)
        up, down = _slowed(up, self._line_scale(e, up)), _slowed(down, self._line_scale(e, down))
        # (on the partial line the crossing lies at s_c / sigma going up, the rest going down)
        return (Timed(up, up.time_at_s(s_c / sigma)),
                Timed(down, down.time_at_s(1.0 - s_c / sigma)))

    def _line_scale(self, e: AtlasEntry, move) -> float:
        """How much a move (or ``Bounce``) of the entry's finger along part of its press ->
        rise line is slowed (``_slowed``): as the atlas's own move along the whole line is
        (``entry_scale``: its tendons within their share, its lag beside the black keys)
        where that bound covers
        it: no joint faster nor accelerating harder (it then is no faster anywhere along
        the line: it leaves the press as that one does, or slower, and stops short of its
        end; the bounds are the line's, ``planner.play.tendonload``); else its own."""
        column = SCALE_PAIRS.index(("press", "rise"))
        whole = self._move(e.finger, e.press, e.rise)
        size, whole_size = float(np.max(np.abs(move.dq))), float(np.max(np.abs(whole.dq)))
        if (move.peak_acceleration * size <= whole.peak_acceleration * whole_size * (1 + 1e-12)
                and move.peak_speed * size <= whole.peak_speed * whole_size * (1 + 1e-12)):
            return self.entry_scale(e, column)
        qa, qb = move.q_a, move.q_a + move.dq
        top = kb.key(60 + e.pitch_class).top_z_m
        scale = self.finger_scale(e.finger, qa, qb, move, top)
        return scale * margin_scale(self.atlas, e.finger, e.pitch_class, e.dx_m,
                                    _slowed(move, scale))

    def found_apex(self, e: AtlasEntry) -> tuple[float, float] | None:
        """(sigma, s_c): the path parameters on the press -> rise line where the finger's
        lowest point is ``REARM_M`` above the key-down depth (the repeat's top; the rise
        itself, 1, where a body of the finger keeps it lower: 4 in 661 entries of the
        default hand come up 0.4 mm) and where it crosses the key-down depth (the lift to
        the rise's crossing, ``lift``: the move table's); None when the line never lets
        the key up."""
        lift = self.lift(e, "rise")
        s_c = float(lift.move.s(lift.cross_s))
        if s_c >= 1.0:
            return None
        depth = self._depth_fn(e)

        def g(s: float) -> float:
            return depth(e.press + s * (e.rise - e.press)) - (kb.DOWN_DEPTH_M - REARM_M)

        g1 = g(1.0)
        if g1 >= 0.0:
            return 1.0, s_c
        # (the crossing's end is still down: the top lies between it and the rise)
        return _crossing(g, g(s_c), g1, CROSS_TOL, s_c), s_c


class Moves(FollowMoves, RepeatMoves):
    """Timed moves of one hand's fingers over its atlas (memoised per entry). What
    forward kinematics decides (key crossings, clear paths across and while following a
    key) is read from the hand's shipped move table (``planner.play.movetable``) when
    there is one, and found when first needed otherwise. (A finger following its key
    through a move of the rail: ``FollowMoves``.)"""

    def __init__(self, hand: HandModel, atlas: Atlas) -> None:
        self.hand = hand
        self.atlas = atlas
        self.js = {f: hand.joint_slice(f) for f in hand.fingers}
        self._lat: dict = {}
        self.descend = lru_cache(maxsize=None)(self._descend)
        self.lift = lru_cache(maxsize=None)(self._lift)
        self.tendons = tendon_load(hand)
        self.entry_scale = lru_cache(maxsize=None)(self._entry_scale)
        self.rise = lru_cache(maxsize=None)(self._rise)
        self.repeat = lru_cache(maxsize=None)(self._repeat)
        self.repeat_pair = lru_cache(maxsize=None)(self._repeat_pair)
        self.repeat_row = lru_cache(maxsize=None)(self._repeat_row)
        self.to_hover = lru_cache(maxsize=None)(self._to_hover)
        self.table = MoveTable(hand.fingers, atlas.natural_dx, atlas.posture_index)
        self.table.load(table_path(hand.urdf_sha256, atlas.posture_index), self.params())
        proof = self.tendons.proof
        self.across_proof: AcrossProof | None = None  # (its moves across at once)
        if proof is not None:  # (each finger's high poses' box, for its moves across, with
            # its gain as the move table ships it: ``planner.play.tendonproof``)
            boxes = self.high_boxes()
            for f, (lo, hi) in boxes.items():
                proof.add_box(f, lo, hi, self.table.proof_gain(f, lo, hi, proof.params()))
            self.across_proof = AcrossProof(hand, atlas, proof, boxes)
            if self.table.proof_params == proof.params():  # (the cells over every
                for f, cells in self.table.proof_cells.items():  # posture: shipped only)
                    proof.add_cells(f, *cells)
        # every joint's acceleration limit, the rail's also within what the wrist holds
        self.acceleration = np.array(hand.acceleration, dtype=float)
        self.jerk = np.array(hand.jerk, dtype=float)
        if atlas.rail is not None:
            cap = rail_acceleration_cap(hand, [atlas.base, atlas.park()])
            self.acceleration[atlas.rail] = min(self.acceleration[atlas.rail], cap)
        # (each finger's limits as floats, alone and after the rail's: the durations the
        # programme asks for, ``across_s`` and ``follow_s``, are worked out without a Move)
        self._limits = {f: (hand.velocity[js].tolist(), self.acceleration[js].tolist(),
                            self.jerk[js].tolist())
                        for f, js in self.js.items()}
        self._follow_limits = {}
        if atlas.rail is not None:
            for f, js in self.js.items():
                cols = np.r_[atlas.rail, js]
                self._follow_limits[f] = (hand.velocity[cols].tolist(),
                                          self.acceleration[cols].tolist(),
                                          self.jerk[cols].tolist())
        self._across_s: dict[tuple[int, int], float | None] = {}
        self._follow_s: dict[tuple[int, int], float] = {}
        # (every entry's record by its id, ``_record``; the table as bytes)
        self._times: dict[int, EntryRecord] = _table_records(
            atlas, self.table, self.js, (hand.velocity, self.acceleration, self.jerk))
        self._across_bytes, self._follow_bytes = self.table.as_bytes()

    def high_boxes(self) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """``high_boxes`` of the atlas."""
        return high_boxes(self.hand, self.atlas)

    def params(self) -> str:
        """What the move table depends on besides the atlas (a table made otherwise is not
        used): the atlas's own parameters, the tests' samples and margins, the search's
        tolerance, the joints' limits."""
        h = self.hand
        # (with the body rule, its follow test: ``planner.play.follow``)
        rule = {} if self.atlas.bodies is None else {"follow_step_m": FOLLOW_STEP_M,
                                                     "margin": margin_params()}
        return json.dumps({**rule, "atlas": self.atlas._params(), "cross_tol": CROSS_TOL,
                           "limit_fraction": LIMIT_FRACTION, "path_samples": PATH_SAMPLES,
                           "across_samples": ACROSS_SAMPLES, "high_safe_z_m": HIGH_SAFE_Z_M,
                           "hold_margin_m": HOLD_MARGIN_M,
                           **self.tendons.params(),
                           "velocity": [round(float(x), 12) for x in h.velocity],
                           "acceleration": [round(float(x), 12) for x in h.acceleration],
                           "jerk": [round(float(x), 12) for x in h.jerk]},
                          sort_keys=True)

    def _move(self, finger: str, qa: np.ndarray, qb: np.ndarray) -> Move:
        js = self.js[finger]
        return straight_move(qa, qb, self.hand.velocity[js], self.acceleration[js], self.jerk[js])

    def _entry_move(self, e: AtlasEntry, a: str, b: str) -> Move:
        """The entry's finger from its pose ``a`` to its pose ``b``, timed within the
        tendons' capacity (``entry_scale``)."""
        pair = (a, b) if (a, b) in SCALE_PAIRS else (b, a)
        move = self._move(e.finger, getattr(e, a), getattr(e, b))
        return slowed(move, self.entry_scale(e, SCALE_PAIRS.index(pair)))

    def _entry_scale(self, e: AtlasEntry, column: int) -> float:
        """How much slower than its joints allow the move between the entry's poses
        ``SCALE_PAIRS[column]`` runs to keep its tendons within their share of capacity
        (``TendonLoad.time_scale``), and then to keep its servos' lag clear of the other
        black keys (``planner.play.margin``; the move table's, when it has the entry)."""
        got = self.table.tendon_scale(e, column)
        if got is not None:
            return got
        a, b = (getattr(e, p) for p in SCALE_PAIRS[column])
        top = kb.key(60 + e.pitch_class).top_z_m if column < 3 else None
        move = self._move(e.finger, a, b)
        scale = self.finger_scale(e.finger, a, b, move, top)
        return scale * margin_scale(self.atlas, e.finger, e.pitch_class, e.dx_m,
                                    slowed(move, scale))

    def finger_scale(self, finger: str, qa: np.ndarray, qb: np.ndarray, move: Move,
                     key_top_z_m: float | None = None) -> float:
        """``TendonLoad.time_scale`` of a finger's ``move`` from ``qa`` to ``qb`` (its
        joints; the rest of the hand at the atlas's natural posture), its key (top at
        ``key_top_z_m``; None: no key under it) pushing back where it is down."""
        js = self.js[finger]
        q_a, dq = self.atlas.base.copy(), np.zeros(self.hand.n)
        q_a[js], dq[js] = qa, qb - qa
        f = self.hand.fingers.index(finger)
        return self.tendons.time_scale(move, q_a, dq, () if key_top_z_m is None else (f,),
                                       key_top_z_m)

    def _cross(self, e: AtlasEntry, qa: np.ndarray, qb: np.ndarray, move: Move,
               going_down: bool) -> float:
        """Time within ``move`` at which the tip's depth below the key top (the finger's body's,
        with the atlas's body rule: ``Atlas.bodies``) passes
        ``DOWN_DEPTH_M`` (``_crossing`` on the path parameter, forward kinematics), on the
        key-down side of the crossing, to within ``CROSS_TOL``."""
        depth = self._depth_fn(e)

        def below(s: float) -> float:
            return depth(qa + s * (qb - qa)) - kb.DOWN_DEPTH_M

        g0, g1 = below(0.0), below(1.0)
        if (g0 >= 0.0) == (g1 >= 0.0):  # (no crossing: the key is down, or up, throughout)
            return move.time_at_s(0.0 if going_down else 1.0) if g0 >= 0.0 else \
                move.time_at_s(1.0 if going_down else 0.0)
        return move.time_at_s(_crossing(below, g0, g1, CROSS_TOL))

    def _depth_fn(self, e: AtlasEntry):
        f = self.hand.fingers.index(e.finger)
        q = self.atlas.base.copy()
        js = self.js[e.finger]
        top = kb.key(60 + e.pitch_class).top_z_m

        bodies = self.atlas.bodies
        if bodies is not None:  # (the body rule: the finger's lowest body point, spec section 2)
            def depth(qf: np.ndarray) -> float:
                q[js] = qf
                p, r = bodies.points(self.hand.apply_couplings(q), e.finger)
                return top - float(np.min(p[:, 2] - r))

            return depth

        def depth(qf: np.ndarray) -> float:
            q[js] = qf
            return top - float(self.hand.tip_position(self.hand.apply_couplings(q), f)[2])

        return depth

    def _descend(self, e: AtlasEntry, start: str) -> Timed:
        """From ``start`` ("high", "hover" or "rise") down to the press pose."""
        qa = getattr(e, start)
        m = self._entry_move(e, start, "press")
        c = self.table.crossing(e, ENDS.index(start))
        return Timed(m, self._cross(e, qa, e.press, m, True) if c is None else c)

    def _lift(self, e: AtlasEntry, end: str) -> Timed:
        """From the press pose up to ``end`` ("high", "hover" or "rise")."""
        qb = getattr(e, end)
        m = self._entry_move(e, "press", end)
        c = self.table.crossing(e, 3 + ENDS.index(end))
        return Timed(m, self._cross(e, e.press, qb, m, False) if c is None else c)

    def across(self, a: AtlasEntry, b: AtlasEntry) -> Move | None:
        """The finger from high over one key to high over another; None when the
        straight move would bring its tip lower than ``HIGH_SAFE_Z_M`` (above every key
        top, wherever the rail is: the arm may have moved since the finger rose)."""
        key = (a.finger, id(a), id(b))
        if key not in self._lat:
            move = None
            if self.across_s(a, b) is not None:
                move = self._move(a.finger, a.high, b.high)
                move = slowed(move, self._across_scale(a, b, move))
                # (the programme's duration is this move's from now on)
                self._across_s[(id(a), id(b))] = move.duration_s
            self._lat[key] = move
        return self._lat[key]

    def _across_scale(self, a: AtlasEntry, b: AtlasEntry, move: Move) -> float:
        """``finger_scale`` of the move across from ``a`` to ``b``: 1 at once where the
        box bound proves it (``AcrossProof``: a bound at least the move's own, so that
        ``finger_scale`` would find 1); else ``finger_scale``."""
        if self.across_proof is not None and self.across_proof.proves(a, b, move):
            return 1.0
        return self.finger_scale(a.finger, a.high, b.high, move)

    def across_s(self, a: AtlasEntry, b: AtlasEntry) -> float | None:
        """``across(a, b)``'s duration (None: not clear), without making the move (the
        programme asks this of thousands of pairs; ``path_caps``, as ``straight_move``)."""
        got = self._across_s.get((id(a), id(b)), False)
        if got is False:
            got = self._across_new(a, b, self._poses(a), self._poses(b))
        return got

    def _poses(self, e: AtlasEntry) -> EntryRecord:
        """The entry's record, or of an entry of another posture (a finger crossing to
        this one's at crossing height: ``Places.move_gap_s``) its poses alone (its moves
        are its own posture's)."""
        if e.posture == self.atlas.posture_index:
            return self._record(e)
        nan = float("nan")
        return EntryRecord(e, nan, nan, nan, e.high.tolist(), e.press.tolist(), None)

    def _across_new(self, a: AtlasEntry, b: AtlasEntry, ra: EntryRecord,
                    rb: EntryRecord) -> float | None:
        """``across_s`` not asked before, from the entries' records (``_record``: their
        high poses as floats, the same differences as the arrays', and their places in
        the across table as bytes: a fresh process asks a few thousand of these before
        its first row)."""
        got = None
        if self._across_clear(a, b, ra.places, rb.places):
            caps = path_caps([y - x for x, y in zip(ra.high, rb.high)], *self._limits[a.finger])
            got = 0.0 if caps is None else move_time_s(*caps)
        self._across_s[(id(a), id(b))] = got
        return got

    def _across_clear(self, a: AtlasEntry, b: AtlasEntry, ia: tuple[int, int] | None = None,
                      ib: tuple[int, int] | None = None) -> bool:
        """The move table's answer (at places ``ia``, ``ib`` of the finger's entries when
        given), or forward kinematics at ``ACROSS_SAMPLES``."""
        table = self._across_bytes.get(a.finger)
        if ia is not None and ib is not None and table is not None:
            return table[0][ia[0] * table[1] + ib[0]] == 1
        ok = self.table.across_clear(a, b)
        if ok is None:
            f = self.hand.fingers.index(a.finger)
            q = self.atlas.base.copy()
            js = self.js[a.finger]
            ok = True
            for s in ACROSS_SAMPLES:
                q[js] = a.high + s * (b.high - a.high)
                z = self.hand.tip_position(self.hand.apply_couplings(q), f)[2]
                ok &= bool(z >= HIGH_SAFE_Z_M)
        return ok

    def _rise(self, e: AtlasEntry) -> Timed:
        """Up from the waiting pose to crossing height (no key crossing)."""
        return Timed(self._entry_move(e, "hover", "high"), 0.0)

    def _to_hover(self, e: AtlasEntry) -> Move:
        """Down from crossing height to the waiting pose over the same key (checked by
        the atlas)."""
        return self._entry_move(e, "high", "hover")

    # ------------------------------------------------------------------ gaps
    def entry_times(self, e: AtlasEntry) -> tuple[float, float, float, float]:
        """(``before_rail_s``, ``after_rail_s``, ``press_min_s``, ``repeat_gap_s``) of an
        entry: its lifts and descents at crossing height and at ``rise``, timed at their
        key crossings (worked out for every entry of the move table when the hand is set
        up, ``_table_records``; for another entry when first asked)."""
        return (*self._record(e)[1:4], self.repeat_gap_s(e))

    def _record(self, e: AtlasEntry) -> EntryRecord:
        """The entry's record, as kept (made from its own lifts and descents when first
        asked of an entry the move table has no crossings for)."""
        got = self._times.get(id(e))
        if got is None or got.entry is not e:
            d, u = self.descend(e, "high"), self.lift(e, "high")
            got = self._times[id(e)] = EntryRecord(
                e, u.duration_s - u.cross_s, d.cross_s, (d.duration_s - d.cross_s) + u.cross_s,
                e.high.tolist(), e.press.tolist(), self.table.index(e))
        return got

    def press_min_s(self, e: AtlasEntry) -> float:
        return self._record(e).press_min_s

    def move_gap_s(self, a: AtlasEntry, b: AtlasEntry) -> float | None:
        ra, rb = self._record(a), self._record(b)
        lat = self._across_s.get((id(a), id(b)), False)
        if lat is False:
            lat = self._across_new(a, b, ra, rb)
        if lat is None:
            return None
        return ra.before_rail_s + lat + rb.after_rail_s

    def before_rail_s(self, e: AtlasEntry) -> float:
        return self._record(e).before_rail_s

    def after_rail_s(self, e: AtlasEntry) -> float:
        return self._record(e).after_rail_s

    def rail_move(self, rail_a: float, rail_b: float) -> Move:
        r = self.atlas.rail
        if r is None:  # (a fixed mount: the rail stays at 0)
            return Move(np.array([rail_a]), np.zeros(1), 0.0, 0.0, 0.0)
        return straight_move(np.array([rail_a]), np.array([rail_b]),
                             self.hand.velocity[[r]], self.acceleration[[r]], self.jerk[[r]])


def _table_records(atlas: Atlas, table: MoveTable, js: dict[str, list[int]],
                   limits: tuple[np.ndarray, np.ndarray, np.ndarray]
                   ) -> dict[int, EntryRecord]:
    """The record of every entry the move table has crossings for, by its id, at once:
    the same floats as ``Moves._record`` makes one by one (a lift and its descent are one
    move each way, of one duration; ``move_times_s`` is ``straight_move``'s, bit for bit),
    so that no plan spends its first window on them (``tests/test_play_moves.py`` holds
    them equal)."""
    cols = {p: i for i, p in enumerate(ENDS)}
    out: dict[int, EntryRecord] = {}
    solved = atlas.solved().values()
    for f, jf in js.items():
        es = [(e, k) for e in solved
              if e.finger == f and (k := table.key(e)) in table.crossings]
        if not es:
            continue
        index = [table.index(e) for e, _ in es]
        c = np.array([table.crossings[k] for _, k in es])
        es = [e for e, _ in es]
        press, high = np.array([e.press for e in es]), np.array([e.high for e in es])
        lim = [x[jf] for x in limits]  # (speed, acceleration, jerk)
        # (each timed within the tendons' capacity: ``Moves._entry_move``)
        sc = np.array([table.scales[table.key(e)] for e in es]).reshape(-1, 4)
        t_high = move_times_s(high - press, *lim) * sc[:, SCALE_PAIRS.index(("press", "high"))]
        d_high, u_high = c[:, cols["high"]], c[:, 3 + cols["high"]]
        for e, *rec in zip(es, (t_high - u_high).tolist(), d_high.tolist(),
                           ((t_high - d_high) + u_high).tolist(), high.tolist(),
                           press.tolist(), index):
            out[id(e)] = EntryRecord(e, *rec)
    return out


def _crossing(g, g0: float, g1: float, tol: float, lo: float = 0.0) -> float:
    """The point of [``lo``, 1] where ``g`` (``g0`` at ``lo``, ``g1`` at 1, of opposite
    signs) reaches 0, on its side where ``g >= 0``, within ``tol``: false position with
    the Illinois correction (a few evaluations of ``g`` where bisection takes 14),
    bisecting whenever one end has been replaced three times in a row (the bracket always
    shrinks)."""
    hi, glo, ghi = 1.0, g0, g1
    side, run = 0, 0  # the end the last steps replaced (-1: lo, +1: hi), how many in a row
    while hi - lo > tol:
        if run >= 3:
            m = 0.5 * (lo + hi)
        else:
            m = hi - ghi * (hi - lo) / (ghi - glo)
            m = min(max(m, lo + 0.25 * tol), hi - 0.25 * tol)
        gm = g(m)
        if (gm >= 0.0) == (glo >= 0.0):
            lo, glo = m, gm
            run, side = (run + 1 if side == -1 else 1), -1
            if run >= 2:
                ghi *= 0.5  # (the end kept twice weighs half: Illinois)
        else:
            hi, ghi = m, gm
            run, side = (run + 1 if side == 1 else 1), 1
            if run >= 2:
                glo *= 0.5
    return lo if glo >= 0.0 else hi


def _slowed(move, sigma: float):
    """``tendonload.slowed`` of a ``Move``, or a ``Bounce`` slowed alike."""
    return move.slowed(sigma) if move.back else slowed(move, sigma)
