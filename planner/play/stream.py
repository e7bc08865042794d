"""The play planner, end to end: fingering (one dynamic programme over the atlas),
motion (time-optimal segments, note by note) between the way in from rest and the way
back (``planner.play.rest``), rows streamed as they are final, the planner's own replay
(``planner.selfcheck``) as its summary and its end marker's claims.
"""

from __future__ import annotations

import contextlib
import gc
import math
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

from planner.errors import InputError
from planner.hand.model import HandModel
from planner.music.midi import SHIFT_DIGITS, Song, shift_notes
from planner.music.parts import PartChoice
from planner.play.armload import rows_load
from planner.play.costs import CostMemo
from planner.play.fingering import Assignment, Fingering, FingeringProblem
from planner.play.motion import Motion
from planner.play.places import Places
from planner.play.rest import REST_RAIL_M, Legs, WayIn, legs_between, rest_pose, way_in
from planner.play.roomcost import RoomCost
from planner.play.tendonload import hand_load
from planner.selfcheck import SelfCheck, Verdict
from planner.trajfile import MIN_ROWS, KeptText, TrajectoryWriter

COMMIT_LAG_S = 0.5  # rows are written up to this long before the last note placed
SETTLE_S = 0.1  # rows go on this long after the hand is still
ROW_BLOCK = 6000  # rows sampled, guarded, written and replayed at once (60 s at 100 Hz)


@dataclass(frozen=True)
class PlayPlan(KeptText):
    """What ``plan_song`` did: rows written, the fingering, the verdict of its replay;
    planned in memory (no path), the file's ``text``, its ``trajectory`` and ``write``."""

    rows: int
    duration_s: float
    fingering: Fingering
    verdict: Verdict
    planning_s: float
    first_row_s: float
    text: str | None = None
    song_start_s: float = 0.0  # the song's time 0 in the file's time (the way in from rest)
    part: PartChoice | None = None  # the part of the file played, when it had several


def play_metadata(song: Song, hand: HandModel, rate_hz: float, song_name: str) -> dict:
    """A play trajectory's metadata (spec section 4), with the song's note count and the
    options it was read with, so that ``check`` reads it the same way; ``song_name``
    defaults to the song's file name; ``part`` only when the file had several parts."""
    song_name = song_name or os.path.basename(song.source)
    part = {} if song.part is None else {"part": {
        "played": [list(tc) for tc in song.part.played],
        "split_pitch": song.part.split_pitch, "reason": song.part.reason}}
    return {"task": "play", "hand": hand.name, "urdf_sha256": hand.urdf_sha256,
            "T_world_root": hand.T_world_root.tolist(), "rate_hz": rate_hz,
            "song": song_name, "notes": len(song.notes), "track": song.track,
            "channel": song.channel, "transpose": song.transpose, **part}


class Planner:
    """The per-hand part of the play planner (atlases, timed moves), built once."""

    def __init__(self, hand: HandModel, rest_rail_m: float = REST_RAIL_M) -> None:
        self.hand = hand
        self.places = Places(hand)  # (every play posture's atlas and moves)
        self.atlas, self.moves = self.places.atlas, self.places.home  # (the rest pose's)
        self.memo = CostMemo()  # (the fingering's costs that depend on the hand alone)
        # (the hand's rest pose: every plan's first row; two hands rest apart)
        self.rest_q = rest_pose(self.atlas, rest_rail_m)
        # (the idle fingers' pose, ``IdleFingers.pose``, found and kept with the set-up: it
        # depends on the hand alone; every plan's first rows tuck them there)
        self.places.idle.tuck(self.rest_q)
        # (the whole hand's motor bounds, of a note's rows and of the arm's moves carrying
        # fingers: the hand's alone, built here and not while the first row waits)
        rows_load(hand)
        hand_load(hand)


def plan_song(song: Song, hand: HandModel, out_path: str | None = None, rate_hz: float = 100.0,
              song_name: str = "", planner: Planner | None = None,
              on_progress: Callable[[int, int], None] | None = None,
              rail_bounds: Sequence[tuple[float, float]] | None = None,
              room: RoomCost | None = None) -> PlayPlan:
    """Plan ``song`` on ``hand`` and stream the trajectory to ``out_path`` ('-': stdout;
    None: keep it in memory, ``PlayPlan.text``).
    ``on_progress(notes_decided, notes)`` is called as the notes are decided (played or
    left out), chunk by chunk. The clock (``planning_s``, ``first_row_s``) starts after
    the hand's set-up (``Planner``, built here when none is given). ``rail_bounds``: per
    note, the rail's (lowest, highest) position it may be pressed from (two hands:
    ``planner.play.twohands``; None: the whole travel); ``room``: what the room the hand
    takes from the other hand's notes costs (two hands, the hand planned first:
    ``planner.play.roomcost``; None: nothing)."""
    if not (math.isfinite(rate_hz) and 1.0 <= rate_hz <= 10000.0):
        raise InputError(f"--rate must be between 1 and 10000 Hz, got {rate_hz}")
    pl = planner or Planner(hand)
    t_start = time.perf_counter()
    notes = list(song.notes)
    selfcheck = SelfCheck(hand, rate_hz)
    writer = TrajectoryWriter(out_path, play_metadata(song, hand, rate_hz, song_name), hand,
                              on_rows=selfcheck.add_rows, defer_header=True)
    try:
        with _cyclic_gc_paused():
            rows, fingering = _plan(notes, pl, rate_hz, hand, writer, on_progress,
                                    rail_bounds, room)
        left_out = {s.note: (s.reason, s.detail) for s in fingering.skipped}
        left_out.update({o.note: (o.skip, o.detail)
                         for o in rows.motion.outcomes.values() if o.skip is not None})
        verdict = selfcheck.verdict(rows.motion.notes, left_out)  # (in the file's time)
        writer.close(verdict.end_info())
    except BaseException as e:
        writer.abort(discard=isinstance(e, InputError))
        raise
    return PlayPlan(writer.rows, writer.rows / rate_hz, fingering, verdict,
                    time.perf_counter() - t_start, rows.first_row_s - t_start, writer.text,
                    rows.shift_s, song.part)


@contextlib.contextmanager
def _cyclic_gc_paused():
    """Python's cyclic garbage collector paused while a song is planned (as it was
    before, after). The programme keeps long-lived containers (the hand's cost memo, a
    window's states before and their losses) that every full collection scans again:
    measured on the 38 corpus songs planned by one Planner, with the check between
    songs, 6.7 s of collection against 1.1 s at d387769, median CPU real-time factor
    50x against 68x paused. Planning makes no reference cycles (a test counts the
    unreachable objects it leaves: none), so reference counting frees all it drops."""
    was = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was:
            gc.enable()


def _plan(notes, pl: Planner, rate_hz: float, hand: HandModel, writer: TrajectoryWriter,
          on_progress=None, rail_bounds=None, room=None):
    """Fingering chunk by chunk (``FingeringProblem.chunks``, in the song's time), each
    chunk's notes placed in time order (a cut before the notes that start with it) in
    the file's time (the song shifted by the way in from rest: ``planner.play.rest``),
    rows written up to where nothing can change any more, then the way back to rest.
    Returns the rows (their motion and the song's shift) and the fingering (song time)."""
    problem = FingeringProblem(notes, pl.places, rate_hz, pl.memo, rail_bounds, room)
    rest_q = pl.rest_q.copy()
    rows: _Rows | None = None
    done: dict[int, Assignment] = {}
    skipped: list = []
    loss = 0.0
    for ch in problem.chunks():
        skipped.extend(ch.skipped)
        loss = ch.loss_frames
        if on_progress is not None:
            on_progress(len(done) + len(ch.assignments) + len(skipped), len(notes))
        steps = [((notes[a.note].onset_s, 1, notes[a.note].pitch), a) for a in ch.assignments]
        steps += [((t, 0, n), (n, t)) for n, t in ch.cuts]
        steps.sort(key=lambda s: s[0])
        if rows is None and ch.assignments:
            first = min(ch.assignments, key=lambda a: (notes[a.note].onset_s, notes[a.note].pitch))
            rows = _start(Motion(notes, pl.places, rate_hz, first.rail_m, first.posture), pl,
                          rest_q, ch.assignments, writer, rate_hz)
        elif rows is None and math.isfinite(ch.until_s):  # (nothing playable yet, more
            # to come: the hand waits at its natural place, the rows go on; parked if no
            # finger reaches any key: then nothing ever will be)
            rows = _start(Motion(notes, pl.places, rate_hz, pl.atlas.rail_of(pl.rest_q)),
                          pl, rest_q, (), writer, rate_hz)
        shift = 0.0 if rows is None else rows.shift_s
        if rows is not None:
            rows.motion.expect([_shifted(a, shift) for a in ch.assignments])
        for _, item in steps:
            if isinstance(item, Assignment):
                rows.motion.place(_shifted(item, shift))
                done[item.note] = item
                rows.commit_to(rows.motion.t_down(item.note) - COMMIT_LAG_S)
            else:
                n, t = item
                rows.motion.cut(n, t + shift)
                done[n] = replace(done[n], release_s=t)
        # (every note before ``until_s`` is placed: the rows can go on to a lag before it)
        if rows is not None and math.isfinite(ch.until_s):
            rows.commit_to(ch.until_s + shift - COMMIT_LAG_S)
    if rows is None:  # nothing to play: the hand waits, still
        rows = _start(Motion(notes, pl.places, rate_hz, pl.atlas.rail_of(pl.rest_q),
                             park=True), pl, rest_q, (), writer, rate_hz)
    end = max((n.offset_s for n in notes), default=0.0) + rows.shift_s
    rows.finish(rows.motion.finish(end), rest_q)
    fingering = Fingering(tuple(done[n] for n in sorted(done)),
                          tuple(sorted(skipped, key=lambda s: s.note)), loss)
    return rows, fingering


def _start(motion: Motion, pl: Planner, rest_q: np.ndarray, assignments,
           writer: TrajectoryWriter, rate_hz: float) -> _Rows:
    """The motion's start: its first fingers over their keys, the way in from rest, the
    song's shift (into the file's metadata, before its first row)."""
    motion.prepare(assignments)
    way = way_in(pl.moves, motion, rest_q, assignments, rate_hz, _tucked(pl, rest_q))
    motion.start_after(way.arrive_s, shift_notes(motion.notes, way.song_start_s))
    writer.add_metadata(song_start_s=way.song_start_s)
    return _Rows(pl.hand, writer, motion, rate_hz, way)


def _tucked(pl: Planner, rest_q: np.ndarray) -> np.ndarray | None:
    """The rest pose with the idle fingers tucked (``IdleFingers.tuck``), None when it is the
    rest pose itself (no leg to tuck them)."""
    q = pl.places.idle.tuck(rest_q)
    return None if q is rest_q else q


def _shifted(a: Assignment, shift_s: float) -> Assignment:
    """An assignment in the file's time (its cut, if any, ``shift_s`` later)."""
    if a.release_s is None or shift_s == 0.0:
        return a
    return replace(a, release_s=round(a.release_s + shift_s, SHIFT_DIGITS))


class _Rows:
    """Samples the way in, the motion and the way out at the rows' clock and writes
    them, guarded."""

    def __init__(self, hand: HandModel, writer: TrajectoryWriter, motion: Motion,
                 rate_hz: float, way: WayIn) -> None:
        self.hand, self.writer, self.motion = hand, writer, motion
        self.dt = 1.0 / rate_hz
        self.way = way
        self.out: Legs | None = None  # the way back to rest
        self.next_row = 0
        self.first_row_s = math.nan

    @property
    def shift_s(self) -> float:
        return self.way.song_start_s

    @property
    def written_to_s(self) -> float:
        return (self.next_row - 1) * self.dt

    def commit_to(self, t_s: float) -> None:
        """The motion fixed up to ``t_s`` and its rows written, when that is more than
        ``COMMIT_LAG_S`` past the rows written already (rows go out in chunks; the first
        ones as soon as there are any)."""
        if t_s > self.written_to_s + (COMMIT_LAG_S if self.next_row else 0.0):
            self.motion.commit(t_s)
            self.write_to(t_s)

    def finish(self, still_s: float, rest_q: np.ndarray) -> None:
        """The way back to rest from where the motion is still (at ``still_s``), and the
        rows to its end and ``SETTLE_S`` after (at least a file's ``MIN_ROWS``)."""
        still_s = max(still_s, self.way.arrive_s)
        q_end = self.motion.rows(np.array([still_s]))[0]
        self.out = legs_between(self.motion.moves, rest_q, q_end, leaving=True, t0_s=still_s,
                                tucked_q=self.motion.places.idle.tuck(rest_q))
        self.write_to(max(self.out.end_s + SETTLE_S, (MIN_ROWS - 1) * self.dt))

    def _sample(self, t: np.ndarray) -> np.ndarray:
        """The rows at times ``t``: the way in, the motion (couplings applied by it), the
        way back; the legs' rows get their couplings here (a straight line keeps a
        linear coupling, not the Mk5's)."""
        q = self.motion.rows(t)
        for legs, on in ((self.way.legs, t < self.way.arrive_s),
                         (self.out, None if self.out is None else t >= self.out.t0_s)):
            if on is not None and on.any():
                q[on] = self.hand.apply_couplings(legs.at(t[on]))
        return q

    def write_to(self, t_s: float) -> None:
        """Rows up to ``t_s``, in blocks of at most ``ROW_BLOCK`` (memory stays bounded
        through a long silence)."""
        n = math.floor(t_s / self.dt + 1e-9) + 1
        while self.next_row < n:
            end = min(n, self.next_row + ROW_BLOCK)
            t = np.arange(self.next_row, end) * self.dt
            q = self._sample(t)
            self.writer.write_rows(t, q, self.hand.motor_angles(q))  # (guarded by the writer)
            if math.isnan(self.first_row_s):
                self.first_row_s = time.perf_counter()
            self.next_row = end
