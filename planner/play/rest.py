"""The hand's rest pose, and a plan's way in from it and out to it.

Every play plan starts at the hand's rest pose and ends there (spec section 4, version
2): a controller starts the rows from a known, still pose and leaves the hand in it. The
rest pose is the natural hand raised until its lowest fingertip is at crossing height
(``Atlas.raised``: above every key, so no key is down in the first or the last row),
with the rail at its rest position (``REST_RAIL_M``, within its planning travel).

The way in is two time-optimal straight moves (``legs_between``): the rail, with the
hand in its rest posture, to where the motion starts; then the wrist and fingers, the
rail still, to the motion's first pose (``Motion.q0``: each finger at crossing height
over its first key); a hand with an idle finger (``planner.play.idle``: the default hand's
thumb) tucks it while the rail runs. The way out is the same backwards. Each starts and
ends with
every speed zero. When the song's first notes come too soon to be reached from rest,
the song starts later in the file: ``song_start_s``, a whole number of rows, written in
the file's metadata, by which every reader shifts the song
(``planner.trajfile.song_start_s``, ``planner.music.midi.shift_notes``).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from planner.play.atlas import HIGH_Z_M, PATH_SAMPLES, Atlas
from planner.play.motion import Motion
from planner.play.moves import Moves
from planner.play.profile import Move, capped_move, path_caps
from planner.play.railcap import path_acceleration_cap

REST_RAIL_M = 0.0  # the rail rests with the hand over middle C (spec: x = 0), the
# keyboard's middle: the longest way in to any key is half the keyboard's


@dataclass(frozen=True)
class Legs:
    """Straight moves one after the other from ``t0_s``: positions at any time (before
    the first, its start; after the last, its end)."""

    t0_s: float
    moves: tuple[Move, ...]

    @property
    def end_s(self) -> float:
        return self.t0_s + sum(m.duration_s for m in self.moves)

    def at(self, t_s: np.ndarray) -> np.ndarray:
        t_s = np.asarray(t_s, dtype=float)
        out = np.tile(self.moves[0].q_a, (len(t_s), 1))
        t0 = self.t0_s
        for m in self.moves:
            on = t_s >= t0
            if on.any():
                out[on] = m.at(t_s[on] - t0)
            t0 += m.duration_s
        return out


@dataclass(frozen=True)
class WayIn:
    """The legs from rest to the motion's start (from t = 0 to ``arrive_s``) and the
    song's shift into the file (``song_start_s``, a whole number of rows)."""

    legs: Legs
    song_start_s: float

    @property
    def arrive_s(self) -> float:
        return self.legs.end_s


def rest_pose(atlas: Atlas, rail_m: float = REST_RAIL_M) -> np.ndarray:
    """The hand's rest pose: the natural hand with its lowest fingertip at crossing
    height (``Atlas.raised``) and the rail at ``rail_m`` (``REST_RAIL_M``; two hands park
    at the ends of their travel: ``planner.play.twohands``) within its travel."""
    h = atlas.hand
    q = atlas.raised(HIGH_Z_M)
    if atlas.rail is not None:
        q[atlas.rail] = min(max(rail_m, h.plan_lower[atlas.rail]), h.plan_upper[atlas.rail])
    return h.apply_couplings(q)


def _at_rail(atlas: Atlas, q: np.ndarray, rail_m: float) -> np.ndarray:
    out = q.copy()
    if atlas.rail is not None:
        out[atlas.rail] = rail_m
    return out


def legs_between(moves: Moves, rest_q: np.ndarray, q: np.ndarray, leaving: bool,
                 t0_s: float = 0.0, tucked_q: np.ndarray | None = None) -> Legs:
    """From rest to ``q`` (or from ``q`` to rest, ``leaving``) in two legs: the rail runs
    only while the hand is in its rest posture (every tip above crossing height), and
    the wrist and fingers move only while the rail is still. ``tucked_q``: the rest pose
    with the fingers that press no key tucked (``IdleFingers.tuck``), when it differs: they
    tuck while the rail runs (in the rest posture, where their body is clear of the keys
    tucked or not) and untuck in the last leg out, so that the arm never carries them
    untucked into a posture whose keys they would enter."""
    atlas = moves.atlas
    start = rest_q if tucked_q is None else tucked_q
    poses = [rest_q, _at_rail(atlas, start, atlas.rail_of(q)), q]
    if leaving:
        poses.reverse()
    return Legs(t0_s, tuple(whole_hand_move(moves, a, b) for a, b in itertools.pairwise(poses)))


def whole_hand_move(moves: Moves, q_a: np.ndarray, q_b: np.ndarray) -> Move:
    """The time-optimal straight move of every joint from ``q_a`` to ``q_b``: each joint
    within its speed, acceleration and jerk limits (the rail's acceleration within what
    the wrist holds: ``Moves.acceleration``), and the path's acceleration within what
    every motor holds with the hand's inertia and gravity at ``PATH_SAMPLES`` points of
    the line (``path_acceleration_cap``: the wrist turns and the rail runs at once here)."""
    h = moves.hand
    q_a = np.asarray(q_a, dtype=float)
    dq = np.asarray(q_b, dtype=float) - q_a
    caps = path_caps(dq.tolist(), h.velocity.tolist(), moves.acceleration.tolist(),
                     moves.jerk.tolist())
    if caps is None:
        return capped_move(q_a, dq, None)
    v, a, j = caps
    line = [h.apply_couplings(q_a + s * dq) for s in np.linspace(0.0, 1.0, PATH_SAMPLES)]
    return capped_move(q_a, dq, (v, min(a, path_acceleration_cap(h, line, dq)), j))


def way_in(moves: Moves, motion: Motion, rest_q: np.ndarray, assignments,
           rate_hz: float, tucked_q: np.ndarray | None = None) -> WayIn:
    """From rest to ``motion.q0``, and the song's shift: the first note of each finger
    prepared over its key (``Motion.prepare``) can go down on time only if its descent
    from crossing height starts after the hand has arrived; the song is shifted by the
    whole rows that make this hold for every such note (0 when it holds already)."""
    legs = legs_between(moves, rest_q, motion.q0, leaving=False, tucked_q=tucked_q)
    dt = 1.0 / rate_hz
    need_s = 0.0
    for a in motion.prepared(assignments):
        e = motion.entry(a)
        t_down = motion.t_down(a.note)  # (song time: the motion's notes are not shifted yet)
        need_s = max(need_s, legs.end_s + motion.moves.descend(e, "high").cross_s - t_down)
    rows = math.ceil(need_s / dt - 1e-9) if need_s > 0.0 else 0
    return WayIn(legs, rows / rate_hz)  # (35 / 100 = 0.35; 35 * 0.01 = 0.35000000000000003)
