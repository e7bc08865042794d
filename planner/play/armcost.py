"""What a move of the arm costs the fingering's programme, in frames of music lost
(``planner.play.costs``' currency): the fingers that do not ride along lift after their
keys come up, the arm moves (as slow as its slowest rider), the new fingers descend; a
note sounding rides along where its finger has its key at the new place, strikes none of
the new notes and its key stays down past the move's end (``HOLD_PAST_S``), as the motion
holds it (``planner.play.motion``).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from planner.play.follow import HOLD_PAST_S
from planner.play.keytimes import (  # (LATE_MIN_S: a key later, ``costs.State.late``)
    LATE_MIN_S,
    held_enough_at,
    held_enough_parts,
    late_frames,
    struck_s,
)

if TYPE_CHECKING:
    from planner.play.costs import Prev

TIE_RAIL_PER_M = 5.0  # frames per metre of rail moved: a tie-break, not a cost
# What ``ArmFloor._arm_floor`` gives away, in frames: far above the float rounding of the
# losses and the times it is worked from (a song's cost in frames, thousands at most,
# rounds at 1e-12), far below any tie-break (``TIE_RAIL_PER_M`` on a 1 mm step: 0.005):
# a move whose loss ties with the best is never ruled out by the floor.
FLOOR_SLACK = 1e-7
FLOOR_SLACK_S = 1e-9  # the same in the times it is worked from (a song's times, seconds
# to hours, round at 1e-12 and less)


class ArmTimes:
    """The finger timings around a move of the arm that ``ArmCosts`` reads (its base; it
    reads ``Costs``' memos): the columns of ``Costs._times`` by the move's rule, each
    finger's lift before the move, a held key's follow path."""

    def _times(self, note: int, finger: str, place: int
               ) -> tuple[float, float, float, float]:
        """(``Places.rail_lift_s``, ``Places.rail_descent_s``) of the entry by the front
        rule (a move of the arm that keeps the play posture), then the same by the black
        rule (one that changes it): around a move of the arm, key up to the lifting
        finger clear above every key, and the descent's part after the arm is still
        (memoised: the programme reads them for every transition)."""
        key = (self.pitch[note], finger, place)
        got = self._timing.get(key)
        if got is None:
            e, p = self.entry(note, finger, place), self.places
            got = self._timing[key] = (p.rail_lift_s(e), p.rail_descent_s(e),
                                       p.rail_lift_s(e, False), p.rail_descent_s(e, False))
        return got

    def _afters_of(self, prev: Prev, place: int, new: dict[int, str]) -> list[float]:
        """Each of ``new``'s notes' finger's descent's part after a move of the arm from
        ``prev``'s place to ``place`` is over (``Costs._times``, its ``_descent_column``;
        memoised by the posture moved from, the place and the key and finger: the column
        depends on the postures and the entry alone)."""
        col = self._afters.get((prev.posture, place))
        if col is None:
            col = self._afters[prev.posture, place] = {}
        pitch, out = self.pitch, []
        for n, f in new.items():
            a = col.get((pitch[n], f))
            if a is None:
                a = col[pitch[n], f] = self._times(n, f, place)[
                    self._descent_column(prev.state.place, place, n, f)]
            out.append(a)
        return out

    def _descent_column(self, here: int, place: int, n: int, f: str) -> int:
        """``Costs._times``' column of the descent's part of note ``n``'s finger ``f``
        after a move of the arm from place ``here`` to ``place``: the front rule's (1)
        where the move keeps the play posture, or takes the hand out of the keyboard and
        the entry's bodies stayed in front of the black keys
        (``HighClear.descent_front``), the black rule's (3) otherwise (the motion's
        ``Motion.descent_front``)."""
        po = self.places.posture_of
        if po(here) == po(place):
            return 1
        a, b = self.places.reach_m(po(here)), self.places.reach_m(po(place))
        return 1 if self.places.high.descent_front(self.entry(n, f, place), a, b) else 3

    def _lift_col(self, here: int, place: int, m: int, f: str, r: int) -> int:
        """``Costs._times``' column of the lift of note ``m``'s finger ``f`` (pressed from
        place ``r``) before a move of the arm from place ``here`` to ``place``: the front
        rule's (0) where the move keeps the play posture, moves the hand out of the
        keyboard, or in no further than the entry's bodies stay in front of the black
        keys, the black rule's (2) otherwise (``HighClear.lift_front``, which answers the
        move that keeps the posture too; ``_lifts`` does not ask it; memoised by key,
        finger, place pressed from and the postures moved between: the rule depends on
        the entry and the reaches alone)."""
        po, reach = self.places.posture_of, self.places.reach_m
        key = (self.pitch[m], f, r, po(here), po(place))
        got = self._lift_cols.get(key)
        if got is None:
            got = self._lift_cols[key] = 0 if self.places.high.lift_front(
                self.entry(m, f, r), reach(key[3]), reach(key[4])) else 2
        return got

    def _lifts(self, ctx: Prev, place: int) -> tuple[list, float, dict | None]:
        """When each finger of ``ctx``'s state is clear above every key before a move of
        the arm to ``place`` (latest first), the latest, and each one's ``Costs._times``
        column by note and finger (None: all the front rule's): ``Prev.lifts``, or each
        finger's by its entry's rule (``_lift_col``; memoised per posture moved to)."""
        q = self.places.posture_of(place)
        if q == ctx.posture:
            return ctx.lifts_same
        got = ctx.lifts_to.get(q)
        if got is None:
            here = ctx.state.place
            black = {(m, f): v for v, m, f in ctx.lifts_black}
            cols = {(m, f): self._lift_col(here, place, m, f, r)
                    for m, f, r in ctx.state.last_notes}
            lifts = sorted(((v if cols[m, f] == 0 else black[m, f], m, f)
                            for v, m, f in ctx.lifts), key=lambda x: -x[0])
            got = ctx.lifts_to[q] = (lifts, lifts[0][0] if lifts else -math.inf, cols)
        return got

    def _follow_path(self, m: int, f: str, here: int, place: int) -> bool:
        """``Places.follow_path_clear`` of finger ``f`` holding ``m``'s key from ``here``
        to ``place``, the rails the motion moves (memoised by key and places)."""
        key = (self.pitch[m], f, here, place)
        got = self._paths.get(key)
        if got is None:
            got = self._paths[key] = self.places.follow_path_clear(
                self.entry(m, f, here), self.entry(m, f, place), self.pitch[m],
                self.places.rail_m(here), self.places.rail_m(place))
        return got


class ArmFloor(ArmTimes):
    """What a move of the arm starts from (``_arm_setup``: the new notes' wish, the arm's
    time, the lifts, the notes that could ride along) and a floor of its loss
    (``_arm_floor``) that ``ArmCosts._rail_loss`` rules a move out by before its keys are
    cut for the arm (its base; it reads ``Costs``' memos)."""

    def _arm_setup(self, prev: Prev, new: dict[int, str], place: int) -> tuple:
        """What a move of the arm to ``place`` after ``prev`` starts from: ``_arm_start``'s
        answer and the notes that could ride along (``_ride_cands``)."""
        return (*self._arm_start(prev, new, place),
                self._ride_cands(prev, place, new) if prev.follows else [])

    def _arm_start(self, prev: Prev, new: dict[int, str], place: int) -> tuple:
        """Each new note's descent after a move of the arm to ``place`` after ``prev``
        (``_afters_of``), the new notes' wish (the latest the arm may arrive for each key
        to go down on time), the arm's time and ``_lifts``' answer."""
        afters = self._afters_of(prev, place, new)
        t_down = self._t_down
        arrive = min([t_down[n] - a for n, a in zip(new, afters)])
        return (afters, arrive, self.places.arm_time_s(prev.state.place, place),
                self._lifts(prev, place))

    def _first_clear(self, ctx: Prev, order: list, place: int, new: dict[int, str],
                     start: float) -> float | None:
        """``_arm_floor``'s latest lift of a finger that cannot ride along on a move of the
        arm to ``place`` striking ``new``, clear after the arm must start (``start``;
        ``order``: the lifts, latest first, ``_lifts``); None: none. A finger rides where
        ``_ride_cands`` finds it (it strikes no new note and ``_rider`` takes it): asked
        of the lifts down to the first that cannot ride, not of every note sounding."""
        strikers = new.values()
        follow_of = ctx.follow_of
        for v, m, f in order:  # (latest first)
            if v <= start:
                return None
            follow = follow_of.get((m, f))
            if follow is None or f in strikers or self._rider(ctx, place, *follow) is None:
                return v
        return None

    def _gap_floor(self, ctx: Prev, new: dict[int, str], place: int) -> float:
        """A floor of the frames the new notes' own fingers lose on a move of the arm to
        ``place`` after ``ctx``'s state, whatever the arm does (``ArmCosts._rail_loss``'
        loop): a striking finger never rides, so it lifts from its last key (``m``, up at
        ``up``: its own or this event's, ``Prev.lifts``), crosses (``_move_gap_s``'s
        gap) and strikes; a key ``x`` early loses ``x``'s frames and brings the note no
        more than ``x`` sooner, so it loses at least ``up + gap`` past its key's down in
        keys cut or the note late (less ``LATE_MIN_S``; ``FLOOR_SLACK_S`` off), each
        finger its own key and note. Only the gaps found already are read (a gap not
        asked yet counts nothing: the hand's answers are asked as on main); inf where
        no move gets there."""
        total, gaps, pitch, t_down = 0.0, self._gaps, self.pitch, self._t_down
        for n, f in new.items():
            last = ctx.last.get(f)
            if last is None:
                continue
            m, r = last
            gap = gaps.get((pitch[m], f, r, pitch[n], place), False)
            if gap is None:
                return math.inf
            if gap is not False:
                up = min(self._t_up[m], ctx.cut_up)
                total += max(0.0, self._over_frames(up + gap, t_down[n]))
        return total

    def _over_frames(self, clear: float, start: float) -> float:
        """``_arm_floor``'s floor whatever is cut: a lift clear at ``clear`` after the arm
        must start (``start``) costs its time past the start in keys cut or a note late,
        less ``LATE_MIN_S`` (frames; ``FLOOR_SLACK_S`` off)."""
        return (clear - start - LATE_MIN_S - FLOOR_SLACK_S) / self.dt

    def _cands_within(self, prev: Prev, new: dict[int, str], place: int, start: tuple,
                      limit: float, tie_rail: float) -> list | None:
        """``_ride_cands``' answer for a move of the arm to ``place`` after ``prev``
        striking ``new`` (``start``: ``_arm_start``'s arrival, time and lifts), or None
        where its floor (``_arm_floor``, with the rail's tie-break ``tie_rail``, less
        ``FLOOR_SLACK``) is above ``limit`` (the loss that would keep it). The floor's
        part whatever is cut (``_over_frames``, from ``_first_clear``'s lift) comes
        first: at or below the whole floor, it rules out most moves (40,736 of 41,840 on
        three corpus pieces) before the other notes sounding are weighed as riders."""
        arrive, T, lifts = start
        if limit < math.inf and lifts[1] > arrive - T:
            clear = self._first_clear(prev, lifts[0], place, new, arrive - T)
            if clear is not None and tie_rail + self._over_frames(
                    clear, arrive - T) - FLOOR_SLACK > limit:
                return None
        if limit < math.inf and tie_rail + self._gap_floor(
                prev, new, place) - FLOOR_SLACK > limit:
            return None
        cands = self._ride_cands(prev, place, new) if prev.follows else []
        if limit < math.inf and tie_rail + self._arm_floor(
                prev, lifts, cands, T, arrive) - FLOOR_SLACK > limit:
            return None
        return cands

    def _arm_floor(self, ctx: Prev, lifts: tuple, cands: list, T: float,
                   arrive: float) -> float:
        """A floor of the frames a move of the arm (its time ``T``; ``lifts``:
        ``_lifts``' answer) after ``ctx``'s state loses for the new notes (``arrive``:
        their wish), without the cut keys' ups worked out (``ArmCosts._cut_up_s``) nor
        the riders weighed (``ArmCosts._riders``). Of the fingers that cannot ride along
        (not in ``cands``, ``_ride_cands``' answer), each one clear after the arm must
        start (``arrive - T``) is cut by ``ArmCosts._cut_lifts`` no later than its cut
        (``start - lift``) or what holds its key (``_lift_part``'s ``hold``): it loses at
        least the frames from there to its key's due up; and the arm starts no sooner
        than the latest of their lifts from the earliest their keys come up
        (``_lift_part``'s ``first``), or the arm's start itself with no rider (the latest
        lift's cut is that), so the new note that wishes the arm earliest is that late at
        least (``late_frames``). Or, whatever is cut: a key ``x`` seconds early loses
        ``x``'s frames and brings the arm no more than ``x`` sooner, so the latest of
        those lifts costs its time past the start in keys cut or the note late
        (``late_frames`` less ``LATE_MIN_S``'s). ``FLOOR_SLACK_S`` off each time against
        the floats' rounding."""
        order, clear = lifts[0], lifts[1]
        start = arrive - T
        if clear <= start:  # (the arm leaves in time: nothing cut, nothing late)
            return 0.0
        riding = {c[0] for c in cands} if cands else None
        cut, first, first_clear = 0.0, -math.inf, None
        cols, parts = lifts[2], ctx.lift_parts
        for v, m, f in order:  # (latest first)
            if v <= start:
                break
            if riding and (m, f) in riding:
                continue
            if first_clear is None:
                first_clear = v
            col = 0 if cols is None else cols[m, f]
            got = parts.get((m, f, col))
            if got is None:
                got = self._lift_part(ctx, m, f, col)
            lift_s, _, _, hold, first_m = got
            due = v - lift_s
            cut += max(0.0, min(v - start, due - hold) - FLOOR_SLACK_S)
            first = max(first, min(v, first_m + lift_s))
        if first_clear is None:
            return 0.0
        if not riding:  # (the latest lift, cut, is clear no sooner than the arm's start)
            first = max(first, start)
        late = first + T - arrive - FLOOR_SLACK_S
        return max(self._over_frames(first_clear, start),
                   cut / self.dt + late_frames(late, self.dt))

    def _lift_part(self, ctx: Prev, m: int, f: str, col: int) -> tuple:
        """What a cut of note ``m``'s key (finger ``f``, ``Costs._times`` column ``col``)
        for a move of the arm after ``ctx``'s state works out whatever the cut
        (``Prev.lift_parts``, memoised; ``ArmCosts._cut_lifts``): its lift's time, its
        entry, the key-up no cut goes before (its shortest press, ``Moves.press_min_s``),
        the latest key-up any cut keeps (``hold``: the key-up no cut goes before, the
        note's hit, ``ArmCosts._cut_up_s``, a rider's busy finger) and the earliest
        (``first``: those but the hit, which a cut that loses the note anyway does not
        keep)."""
        got = ctx.lift_parts.get((m, f, col))
        if got is None:
            r = ctx.last[f][1]
            e = self.entry(m, f, r)
            floor = self._t_down[m] + ctx.late_of.get(m, 0.0) + self.places.press_min_s(e)
            (_, _, _, _, hit_s, _), free = self._up_parts(ctx, m, e)
            busy = floor if free is None else max(floor, free)
            got = ctx.lift_parts[m, f, col] = (self._times(m, f, r)[col], e, floor,
                                               max(busy, hit_s), busy)
        return got

    def _up_parts(self, prev: Prev, m: int, e) -> tuple:
        """``_cut_up_s``' parts of note ``m``'s key (its entry ``e``) whatever the cut:
        ``held_enough_parts``, and when a finger that rode along is free (None: it did
        not ride; ``Prev.up_parts``, memoised)."""
        got = prev.up_parts.get(m)
        if got is None:
            n = self.notes[m]
            free = prev.rode_of.get(m)
            got = prev.up_parts[m] = (
                held_enough_parts(n.onset_s, n.offset_s,
                                  self._t_down[m] + prev.late_of.get(m, 0.0),
                                  self._t_up[m], self.dt),
                None if free is None else free + self.places.lift(e, "high").cross_s)
        return got

    def _ride_cands(self, ctx: Prev, place: int, new: dict[int, str]) -> list:
        """The notes sounding in ``ctx``'s state that could ride along on a move of the
        arm to ``place`` (``_rider``'s answers): those whose finger strikes none of the
        ``new`` notes, whose path is clear (``Places.follow_clear``) and whose key's
        window holds the move."""
        cands = []  # (note, finger, the move's latest end, its time, its press done)
        strikers = new.values()
        for follow in ctx.follows:
            if follow[1] not in strikers:  # (one that strikes next does not ride)
                c = self._rider(ctx, place, *follow)
                if c is not None:
                    cands.append(c)
        return cands

    def _rider(self, ctx: Prev, place: int, m: int, f: str, a, window_s: float,
               press_s: float, down_s: float) -> tuple | None:
        """Note ``m`` sounding in ``ctx``'s state (finger ``f``, entry ``a``; its key's
        window, press and down: ``Prev.follows``) as a rider of a move to ``place``, if
        its finger strikes no new note: ((note, finger), the move's latest end, the
        move's time carrying it, when its press is done); None where it cannot ride."""
        # (an entry serves every key of its pitch class at its place: the key is the
        # entry and the rail's step, never the rail's index, which names another
        # entry for each of those keys)
        b = self.entry(m, f, place)
        if b is None:  # (it cannot press the key from there)
            return None
        key = (a, place - ctx.state.place)
        got = self._follows.get(key)  # (its time, whether its path is clear, its
        if got is None:  # lift's key crossing: found only when a note's time fits)
            got = self._follows[key] = [self.places.follow_s(a, b), None, None]
        # (the move fits inside the note, after its press and before its lift)
        if window_s >= got[0] + press_s:
            if got[1] is None:
                got[1] = self.places.follow_clear(a, b)
                got[2] = self.places.lift(b, "high").cross_s
            if got[1] and self._follow_path(m, f, ctx.state.place, place):  # (its press
                # done: the descent's end, ``press_min_s`` less the lift to its key crossing)
                done = down_s + press_s - self.places.lift(a, "high").cross_s
                return ((m, f), self._t_up[m] - got[2] - HOLD_PAST_S, got[0], done)
        return None


class ArmCosts(ArmFloor):
    """The arm's moves in ``planner.play.costs.Costs`` (its base: it reads the song's
    times, the memos and the finger timings that ``Costs`` keeps)."""

    def _rail_loss(self, prev: Prev, new: dict[int, str], place: int, kept=(),
                   lates: list | None = None, rode: list | None = None,
                   limit: float = math.inf, tie_rail: float | None = None) -> float | None:
        """Frames lost to a move of the rail to ``place`` after ``prev``: a finger of
        ``prev`` holding a key it can follow (``Moves.follow``) rides along on it; every
        other lifts after its key comes up; then the rail moves (as slow as its slowest
        follower), and the new fingers descend. Each new key goes down as late as the
        latest of what it waits for: the rail, its own finger crossing from its last key
        (while the rail moves) or striking again after following it, another finger
        leaving its key. A ``kept`` note (sounding past the event) must follow, or the
        move is not made (inf). ``lates``: gets (note, seconds) of each note struck late
        (``State.late``); ``rode``: gets (note, finger, the move's end) of each note
        riding along (its finger's place is ``place`` after: ``layers.rode_to``).
        ``limit``: the loss above which the move is of no use (the programme's bound):
        None, without working out the lifts, where its floor is above it already
        (``_cands_within``).
        ``tie_rail``: the rail's tie-break, when its caller has it."""
        afters, arrive, T, lifts = self._arm_start(prev, new, place)
        if tie_rail is None:
            tie_rail = TIE_RAIL_PER_M * self.places.distance_m(place, prev.state.place)
        cands = self._cands_within(prev, new, place, (arrive, T, lifts), limit, tie_rail)
        if cands is None:
            return None
        release_t, followers, cut_loss, cut_ups = self._release_of(
            prev, arrive, T, lifts, cands)
        if kept and not followers.issuperset(kept):
            return math.inf
        if rode is not None and followers:  # (the move ends as late as lets the new keys
            # go down on time, the motion's: ``ArmMotion._move_rail``)
            by_s = min([arrive]
                       + [self._t_up[m] - self.places.lift(self.entry(m, f, place), "high").cross_s
                          - HOLD_PAST_S for m, f in followers])
            end_s = max(release_t, by_s)  # (early for a rider whose key comes up before)
            rode.extend((m, f, end_s) for m, f in followers)
        around = prev.around.get(followers)
        if around is None:
            around = prev.around[followers] = (
                {f: m for m, f in followers}, {self.pitch[m]: (m, f) for m, f in followers},
                {f: (m, r) for m, f, r in prev.state.last_notes if (m, f) not in followers})
        by_finger, by_key, lifted = around
        t_up, t_down, dt, pitch = self._t_up, self._t_down, self.dt, self.pitch
        gaps = self._gaps  # (``_move_gap_s``' memo)
        loss = tie_rail + cut_loss
        for (n, f), after_s in zip(new.items(), afters):
            late = release_t + after_s - t_down[n]
            m = by_finger.get(f)
            came = prev.older.get(f) if m is None else (m, place)  # (its last key and
            # place: where it followed its key to, or below where it lifted from, or an
            # older note's, where it waits; ``Costs._leave_key_s``)
            if m is None and f in lifted:  # it lifts, crosses (while the rail moves), down
                m, r = lifted[f]
                came = (m, r)
                gap = gaps.get((pitch[m], f, r, pitch[n], place), False)
                if gap is False:
                    gap = self._move_gap_s(m, f, r, n, place)
                if gap is None:
                    return math.inf
                if gap > t_down[n] - t_up[m]:  # (it lets its key up early to strike on
                    # time, as far as its note still sounds: ``Motion.lift_by_s``; from
                    # where the arm's start cut it already, ``_cut_lifts``)
                    base = cut_ups.get(m, t_up[m])
                    up = min(base, self._cut_up_s(prev, m, t_down[n] - gap, self.entry(m, f, r)))
                    loss += (base - up) / dt
                    late = max(late, up + gap - t_down[n])
            elif m is not None:  # (it followed its key: it is at place now)
                early, again = self._strike_again(m, place, n, f, place)
                if math.isinf(again):
                    return math.inf
                loss += early / dt
                late = max(late, again)
            if by_key:
                other = by_key.get(self.pitch[n])
                if other is not None and other[1] != f:
                    late = max(late, self._leave_key_s(other, n, f, place, came))
            loss += late_frames(late, dt)
            if lates is not None and late > LATE_MIN_S:
                lates.append((n, struck_s(self.notes[n].onset_s, t_down[n] + late, self.dt)
                              - t_down[n]))
        return loss

    def _step(self, ctx: Prev, new: dict[int, str], place: int, kept, limit: float,
              tie_rail: float) -> tuple | None:
        """A transition's loss after ``ctx`` striking ``new`` from ``place`` and keeping
        ``kept`` held (``Costs._same_rail_loss``, or ``_rail_loss`` for a move of the arm),
        the notes it strikes late (``State.late``) and those that ride along on the arm's
        move: (loss, lates, rode); None where the move's floor is above ``limit``
        (``_rail_loss``; ``tie_rail``: its rail's tie-break)."""
        lates: list = []
        rode: list = []
        if place == ctx.state.place:
            step = self._same_rail_loss(ctx, new, lates)
        else:
            step = self._rail_loss(ctx, new, place, kept, lates, rode, limit, tie_rail)
            if step is None:
                return None
        return step, tuple(sorted(lates)), tuple(sorted(rode))

    def _cut_up_s(self, prev: Prev, m: int, cut_s: float, e) -> float:
        """When note ``m``'s key (its entry ``e``) comes up when its finger is wanted by
        ``cut_s``: the motion's rule, ``keytimes.held_enough_s`` (from when its key went
        down: a note struck late, ``State.late``, that much later), and not before its
        lift can start: a note that rode along on the arm's move into ``prev``'s state
        (``State.rode``) once that move is over (``Motion._to_high``). What does not
        depend on the cut is kept per state before and note (``Prev.up_parts``)."""
        got = self._up_parts(prev, m, e)
        up = held_enough_at(got[0], cut_s)
        if got[1] is not None:
            up = max(up, got[1])
        return up

    def _release(self, prev: Prev, new: dict[int, str], place: int) -> tuple:
        """``_release_of``'s answer for a move of the arm to ``place`` after ``prev``
        striking ``new``: the arm's arrival, the notes riding along, the frames lost by
        keys let up early for it and those keys' ups."""
        _, arrive, T, lifts, cands = self._arm_setup(prev, new, place)
        return self._release_of(prev, arrive, T, lifts, cands)

    def _release_of(self, ctx: Prev, arrive: float, T: float, lifted: tuple, cands: list
                    ) -> tuple[float, frozenset, float, dict]:
        """When the arm arrives at its place after ``ctx``'s state (the lifters' key up,
        a held note's at this event, their lift, and the move), and which notes ride
        along: of ``cands`` (``_ride_cands``), those whose key stays down
        ``HOLD_PAST_S`` past the move's end (``_riders``), as the motion holds them;
        then the frames lost by
        keys let up early for the arm to start on time (``arrive``: the latest the arm may
        arrive for each new key to go down on time after its descent) and those keys' ups
        (``_cut_lifts``; none where a note may ride along). ``T``: the arm's move's time;
        ``lifted``: ``_lifts``' answer."""
        lifts, lift_end, lift_col = lifted
        if not cands:  # (no note sounding that could ride along, ``_riders``' answer when
            # none rides: the last lift, or the lifts cut for the arm to start on time;
            # the move)
            if lift_end + T <= arrive:
                return lift_end + T, _NONE, 0.0, _NO_CUT
            release, loss, ups = self._cut_lifts(ctx, lifts, arrive - T, lift_col)
            return release + T, _NONE, loss, ups
        return self._riders(ctx, lifts, cands, T, arrive, lift_col)

    def _cut_lifts(self, ctx: Prev, lifts: list, start_s: float, lift_col: dict | None
                   ) -> tuple[float, float, dict]:
        """The motion's lifts before a move of the arm that must start by ``start_s`` to
        put the new keys down on time (``Motion.lift_by_s``: each finger's key up by
        then less its lift to clear above every key; ``lifts``: ``Prev.lifts`` or
        ``Prev.lifts_black`` or a mix, ``lift_col`` each one's ``Costs._times`` column by
        note and finger, None: all the front rule's, ``_lifts``): a key due up
        later comes up that early, but held as long as its note still sounds
        (``keytimes.held_enough_s``, ``_cut_up_s``) and never before its shortest press
        (``Moves.press_min_s``; the motion lifts once the press is done). Returns when
        every finger is clear, the frames the early keys-up lose, and their new key-ups
        by note."""
        release, loss, ups = -math.inf, 0.0, {}
        parts = ctx.lift_parts
        for clear, m, f in lifts:  # (latest first: once one is clear in time, all are)
            if clear <= start_s:
                release = max(release, clear)
                break
            col = 0 if lift_col is None else lift_col[m, f]
            got = parts.get((m, f, col))
            if got is None:  # (its lift's time, its entry, the key-up no cut goes before)
                got = self._lift_part(ctx, m, f, col)
            lift_s, e, floor = got[0], got[1], got[2]
            due = clear - lift_s  # (its key's up: its own, or this event's for a held note)
            up = min(due, self._cut_up_s(ctx, m, start_s - lift_s, e))
            up = max(up, min(due, floor))
            loss += (due - up) / self.dt
            ups[m] = up
            release = max(release, up + lift_s)
        return release, loss, ups

    def _riders(self, ctx: Prev, lifts: list, cands: list, T: float, arrive: float,
                lift_col: dict | None) -> tuple[float, frozenset, float, dict]:
        """The arm's arrival and the notes riding along, of ``cands`` (``lifts``: when each
        finger of the state before is clear above every key, ``Prev.lifts`` or
        ``Prev.lifts_black`` or a mix by the move's rule, ``_lifts``; note and finger, the
        latest end of the move that keeps its key down, the move's time carrying it, when
        its press is done): the move starts once every other finger has lifted on time
        and every rider's press is done, and takes the arm's ``T`` or its riders' moves;
        a rider whose key would come up before the move ends, or before it could end
        without hurrying the others' lifts where the new notes (``arrive``, their wish)
        do not ask that anyway, lifts instead: of those, the one whose key comes up first,
        and the others are weighed again without it (the motion's rule,
        ``Motion._move_rail``). Then the other fingers' keys let up early for the move to
        end by the new notes' wish and before every rider's key comes up (``_cut_lifts``:
        their frames lost, their key-ups; ``lift_col``: ``lifts``' columns)."""
        while True:
            riders = frozenset(c[0] for c in cands)
            release = next((v for v, m, f in lifts if (m, f) not in riders), -math.inf)
            start = max([release] + [c[3] for c in cands])
            move_s = max([T] + [c[2] for c in cands])
            late = [c for c in cands if c[1] < min(arrive, start + move_s)
                    or c[1] < c[3] + move_s]
            if not late:
                break
            first = min(late, key=lambda c: (c[1], c[0]))
            cands = [c for c in cands if c is not first]
        end_by = min([arrive] + [c[1] for c in cands])
        if start + move_s <= end_by:
            return start + move_s, riders, 0.0, _NO_CUT
        release, loss, ups = self._cut_lifts(
            ctx, [x for x in lifts if (x[1], x[2]) not in riders], end_by - move_s, lift_col)
        return max([release] + [c[3] for c in cands]) + move_s, riders, loss, ups


_NONE: frozenset = frozenset()  # (no note rides along)
_NO_CUT: dict = {}  # (no key let up early for the arm: ``_cut_lifts``; never written)
