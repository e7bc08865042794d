"""The arm's moves of a ``Motion`` (``planner.play.motion``), and the fingers that ride
along on them holding their keys.

The arm (the rail, and the reach axis when the move changes the play posture) moves
once every finger is at crossing height, but for those holding a key that can follow it
(``planner.play.follow``: the tip on the key, the body holding it down and clear of every
other key, along the very move) and strike none of the notes the move is for; their
keys come up ``HOLD_PAST_S`` after the move at the earliest (the programme's rule,
``Costs._riders``). The move is as late as lets the next key go down on time.
"""

from __future__ import annotations

import bisect
from typing import TYPE_CHECKING

import numpy as np

from planner.play.follow import HOLD_PAST_S
from planner.play.places import Places
from planner.play.profile import Move, straight_move

if TYPE_CHECKING:
    from planner.play.atlas import AtlasEntry
    from planner.play.fingering import Assignment


def part(move: Move, first: int, n: int) -> Move:
    """Joints ``first .. first + n`` of a straight move, on its own timing (the path
    parameter is shared: every part is where the whole move says at every instant)."""
    return Move(move.q_a[first:first + n].copy(), move.dq[first:first + n].copy(),
                move.duration_s, move.ta_s, move.tj_s)


def up_move(moves: Places, st):
    """The finger's way up to crossing height from its pose (a timed lift when it presses:
    its key comes up ``cross_s`` into it)."""
    if st.pose == "press":
        return moves.lift(st.entry, "high")
    return moves.rise(st.entry)


class ArmMotion:
    """``Motion``'s moves of the arm (a part of ``Motion``: its fingers, tracks, posture
    and rows written, ``_to_high``, the notes expected, ``entry``, ``t_down``)."""

    def _move_rail(self, rail_m: float, posture: int, arrive_by_s: float,
                   strikers: set[str]) -> None:
        """The arm to ``rail_m`` in play posture ``posture``, as late as lets the next key
        go down on time, once every finger is at crossing height, except those holding a
        key which can follow it (``Moves.follow``: the rail and their joints on one
        straight time-optimal move, the tip kept on the key; into another posture, the
        reach axis too: ``ArmMoves.carry_move``) and strike none of the notes the move is
        for (``strikers``): their keys come up ``HOLD_PAST_S`` after the move at the
        earliest, which ends early for them only where it need not wait for the other
        fingers' lifts (the programme's rule, ``Costs._riders``)."""
        r0 = self.arm_track.q[0]
        # (the lifts' rule, finger by finger: a change of posture that moves the hand into
        # the keyboard times a lift by the black rule unless its bodies stay in front of
        # the black keys: ``HighClear.lift_front``)
        front = self.lift_rules(posture)
        holds = [h for h in self._holds(rail_m, posture) if h[1].finger not in strikers]
        while True:  # (a follower whose key would come up before the move ends lifts)
            # with followers the move ends before their keys come up: early, if need be
            end_by = min([arrive_by_s] + [st.up_s - self.moves.lift(e, "high").cross_s
                                          - HOLD_PAST_S for st, e in holds])
            move, t0 = self._rail_timing(r0, rail_m, posture, end_by, holds)
            natural = self._natural_ready(holds, front) + move.duration_s
            late = [(st.up_s - self.moves.lift(e, "high").cross_s - HOLD_PAST_S, i)
                    for i, (st, e) in enumerate(holds)]
            late = [(end, i) for end, i in late if t0 + move.duration_s > end + HOLD_PAST_S / 2
                    or end + 1e-9 < min(arrive_by_s, natural)]
            if not late:
                break
            # (the late follower whose key comes up first lifts; the others are weighed
            # again without it: a note already over may have made the move late for all)
            drop = min(late)[1]
            holds = [h for i, h in enumerate(holds) if i != drop]
        held = {id(st) for st, _ in holds}
        for st in self.fingers.values():
            if id(st) not in held and st.pose != "high":
                self._to_high(st, self.lift_by_s(st, t0, arrive_by_s, front(st)))
        t0 = max([t0] + [st.safe_s if front(st) else st.black_s
                         for st in self.fingers.values() if id(st) not in held])
        k = len(self.arm_track.q)
        self.arm_track.add(t0, part(move, 0, k))
        self.arm_reaches = (self.places.reach_m(self.posture), self.places.reach_m(posture))
        self.posture = posture
        for st, e in holds:
            n = len(st.entry.press)
            st.track.add(t0, part(move, k, n))
            st.entry = e
            k += n

    def _rail_timing(self, r0: float, rail_m: float, posture: int, arrive_by_s: float, holds):
        """The arm's move (with its followers' joints after it) and its start: as late
        as lets the next key go down on time, not before the hand is ready."""
        a = (r0, self.places.reach_m(self.posture))
        b = (rail_m, self.places.reach_m(posture))
        move = self.places.arm_move(a, b)
        n = len(self.arm_track.q)
        if holds and posture != self.posture:  # (the reach axis too: ``ArmMoves.carry_move``)
            move = self.places.arms.carry_move(np.array(a[:n]), np.array(b[:n]),
                                          [(st.entry, e) for st, e in holds])
        elif holds:  # (the same posture: the reach axis, if any, stays)
            qa, qb = [np.array(a[:n])], [np.array(b[:n])]
            vmax = [self.hand.velocity[self.arm[:n]]]
            amax = [self.places.home.acceleration[self.arm[:n]]]
            jmax = [self.places.home.jerk[self.arm[:n]]]
            for st, e in holds:
                js = self.hand.joint_slice(st.entry.finger)
                qa.append(st.entry.press)
                qb.append(e.press)
                vmax.append(self.hand.velocity[js])
                amax.append(self.places.moves_of(e).acceleration[js])
                jmax.append(self.places.moves_of(e).jerk[js])
            move = straight_move(np.concatenate(qa), np.concatenate(qb), np.concatenate(vmax),
                                 np.concatenate(amax), np.concatenate(jmax))
        if holds:  # (timed within the tendons' capacity, the followers' keys pushing back)
            cols = np.concatenate([self.arm[:n]] + [self.hand.joint_slice(st.entry.finger)
                                                    for st, _ in holds])
            move = self.places.arms.tendon_slowed(move, self.posture, cols, tuple(
                self.hand.fingers.index(st.entry.finger) for st, _ in holds))
        ready = max(self.arm_track.free_s, self.committed_s)
        held = {id(st) for st, _ in holds}
        front = self.lift_rules(posture)  # (the lifts': ``planner.play.highclear``)
        for st in self.fingers.values():
            if id(st) in held:
                ready = max(ready, st.track.free_s)
            elif st.pose == "high":  # (a finger moving across up there may go on)
                ready = max(ready, st.safe_s if front(st) else st.black_s)
            else:  # it lifts first: as soon as its press is done, at the latest (the arm
                up = up_move(self.moves, st)  # moves once it is clear above every key)
                ready = max(ready, st.track.free_s
                            + self.moves.high.rise_clear_s(st.entry, up.move, front(st)))
        return move, max(ready, arrive_by_s - move.duration_s)

    def _arrive_by_s(self, a: Assignment, e: AtlasEntry, reaches: tuple[float, float]
                     ) -> float:
        """When the arm's move for note ``a`` (its entry ``e``) from reach ``reaches[0]``
        to ``reaches[1]`` must end: the latest that lets every key of its onset struck
        from the same place (``expect``) go down on time, each after its own descent's
        part below the clear height (by its rule, ``HighClear.descent_front``; the
        programme's ``arrive``, ``ArmCosts._release_of``)."""
        t = self.t_down(a.note)
        high = self.moves.high
        by = t - self.moves.rail_descent_s(e, high.descent_front(e, *reaches))
        for g in self._strikers.get(t, ()):
            times, notes = self._next.get(g, ((), ()))
            i = bisect.bisect_left(times, t)
            while i < len(times) and times[i] == t:
                b = notes[i]
                if b.rail_m == a.rail_m and b.posture == a.posture:
                    eb = self.entry(b)
                    if eb is not None:
                        by = min(by, t - self.moves.rail_descent_s(
                            eb, high.descent_front(eb, *reaches)))
                i += 1
        return by

    def descent_front(self, e: AtlasEntry) -> bool:
        """Whether a descent onto ``e`` from crossing height, while the arm's last move
        may still run, keeps the front rule (``HighClear.descent_front`` of that move's
        reaches: the same posture, or out of the keyboard where ``e``'s room holds)."""
        return self.moves.high.descent_front(e, *self.arm_reaches)

    def lift_rules(self, posture: int):
        """Whether a finger's lift before a move of the arm into play posture ``posture``
        keeps the front rule (``HighClear.lift_front`` of its entry), as a function of
        the finger (``_Finger``)."""
        a, b = self.places.reach_m(self.posture), self.places.reach_m(posture)
        if a == b:
            return lambda st: True
        return lambda st: self.moves.high.lift_front(st.entry, a, b)

    def _natural_ready(self, holds, front) -> float:
        """When the arm could start with ``holds`` riding along and every other finger
        lifted at its key's own time (none let up early; ``front``: whether a finger's
        lift keeps the front rule, ``lift_rules``)."""
        held = {id(st) for st, _ in holds}
        ready = max(self.arm_track.free_s, self.committed_s)
        for st in self.fingers.values():
            if id(st) in held:
                ready = max(ready, st.track.free_s)
            elif st.pose == "high":
                ready = max(ready, st.safe_s if front(st) else st.black_s)
            else:
                up = up_move(self.moves, st)
                t0 = max(st.track.free_s, self.committed_s)
                if st.pose == "press":
                    t0 = max(t0, st.up_s - up.cross_s)
                ready = max(ready, t0 + self.moves.high.rise_clear_s(st.entry, up.move,
                                                                     front(st)))
        return ready

    def _holds(self, rail_m: float, posture: int):
        """The pressing fingers that may keep their keys through a move of the arm to
        ``rail_m`` in play posture ``posture``: their tips can follow
        (``Places.follow_clear``: in another posture too, with the atlas's body rule; and
        on the very move, from the rail where it is: ``Places.follow_path_clear``)."""
        out = []
        for st in self.fingers.values():
            if st.pose != "press":
                continue
            e = self.places.atlases[posture].entry(st.entry.finger,
                                                   self.notes[st.note].pitch, rail_m)
            if e is None:
                continue
            if (posture == self.posture and self.moves.follow(st.entry, e) is not None
                    or posture != self.posture and self.places.follow_clear(st.entry, e)) \
                    and self.places.follow_path_clear(st.entry, e, self.notes[st.note].pitch,
                                                      self.arm_track.q[0], rail_m):
                out.append((st, e))
        return out
