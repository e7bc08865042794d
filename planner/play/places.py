"""The hand positions the fingering weighs and the motion takes: an arm posture and a rail
position, and the timed moves over every posture's atlas.

A hand file's ``[play]`` may give the rig's reach axis several positions (the wrist the
same in each: a change of posture is a translation of the hand along the keyboard's y,
so that a tip at crossing height stays there). Each posture has its atlas
(``planner.play.atlas``: the fingers' poses with the forearm there) and its timed moves
(``planner.play.moves``). A **place** is one int, ``posture * PLACE_STRIDE + rail
index`` (the rail on the ``RAIL_STEP_M`` grid): equal places are one hand position, and
a hand with one posture has places equal to its rail indices.

``Places`` answers what the programme (``planner.play.costs``) and the motion
(``planner.play.motion``) ask of a hand position: an entry of a finger over a key from
there, the arm's move between two places (the rail and the reach axis together, one
time-optimal straight move), and every timed move of an entry, from its posture's moves.
A finger moving from an entry of one posture to one of another crosses at crossing
height while the arm moves: the move's key crossings and its clearance depend on heights
alone, the same in every posture.
"""

from __future__ import annotations

import numpy as np

from planner.hand.model import HandModel
from planner.play.atlas import PATH_SAMPLES, Atlas, AtlasEntry, posture_count
from planner.play.moves import Moves, path_acceleration_cap
from planner.play.profile import Move, capped_move, path_caps
from planner.play.tendonload import hand_load, slowed

RAIL_STEP_M = 0.006  # the hand positions the programme weighs, this far apart on the rail
PLACE_STRIDE = 1000  # place = posture * PLACE_STRIDE + rail index (a rail index lies within
# +-PLACE_STRIDE / 2: 3 m of rail either way)


class Places:
    """Every play posture's atlas and moves of one hand (built once, ``Planner``)."""

    def __init__(self, hand: HandModel) -> None:
        self.hand = hand
        self.atlases = tuple(Atlas(hand, posture=i) for i in range(posture_count(hand)))
        self.moves = tuple(Moves(hand, a) for a in self.atlases)
        self.atlas, self.home = self.atlases[0], self.moves[0]  # (the rest pose's posture)
        self.rail = self.atlas.rail
        self.reach = hand.index.get("reach")
        self.natural_dx = self.atlas.natural_dx  # (x: the same in every posture)
        self.arm = [j for j in (self.rail, self.reach) if j is not None]
        # (the whole hand's bounds, for the moves of the whole hand: the rest pose's)
        self.acceleration, self.jerk = self.home.acceleration, self.home.jerk
        self._arm_s: dict[tuple[int, int, int], float] = {}

    @property
    def postures(self) -> int:
        return len(self.atlases)

    # ------------------------------------------------------------------ places
    @staticmethod
    def place(posture: int, rail_i: int) -> int:
        return posture * PLACE_STRIDE + rail_i

    @staticmethod
    def posture_of(place: int) -> int:
        return (place + PLACE_STRIDE // 2) // PLACE_STRIDE

    def rail_i(self, place: int) -> int:
        return place - self.posture_of(place) * PLACE_STRIDE

    def rail_m(self, place: int) -> float:
        return self.rail_i(place) * RAIL_STEP_M

    def reach_m(self, posture: int) -> float:
        return 0.0 if self.reach is None else float(self.atlases[posture].base[self.reach])

    def entry(self, finger: str, pitch: int, place: int) -> AtlasEntry | None:
        """``finger``'s entry over key ``pitch`` from ``place`` (None: it cannot press it)."""
        p = self.posture_of(place)
        return self.atlases[p].entry(finger, pitch, (place - p * PLACE_STRIDE) * RAIL_STEP_M)

    def body_refused(self, finger: str, pitch: int, place: int) -> bool:
        """Whether ``finger`` would press key ``pitch`` from ``place`` but for its body."""
        p = self.posture_of(place)
        return self.atlases[p].body_refused(finger, pitch, (place - p * PLACE_STRIDE) * RAIL_STEP_M)

    def distance_m(self, a: int, b: int) -> float:
        """How far the arm moves between two places (rail and reach, m)."""
        pa, pb = self.posture_of(a), self.posture_of(b)
        return (abs(self.rail_i(a) - self.rail_i(b)) * RAIL_STEP_M
                + abs(self.reach_m(pa) - self.reach_m(pb)))

    def arm_time_s(self, a: int, b: int) -> float:
        """The arm's move from place ``a`` to place ``b`` (memoised)."""
        pa, pb = self.posture_of(a), self.posture_of(b)
        key = (min(pa, pb), max(pa, pb), abs(self.rail_i(a) - self.rail_i(b)))
        got = self._arm_s.get(key)
        if got is None:
            got = self._arm_s[key] = self.arm_move(
                (0.0, self.reach_m(pa)), (key[2] * RAIL_STEP_M, self.reach_m(pb))).duration_s
        return got

    def arm_move(self, a: tuple[float, float], b: tuple[float, float]) -> Move:
        """The arm (its joints ``arm``: the rail, and the reach axis if the rig has one) from
        (rail, reach) ``a`` to ``b``: the rail's own move when the reach stays
        (``Moves.rail_move``), else one time-optimal straight move of both axes under
        their speed, acceleration and jerk bounds, its path's acceleration within what
        every motor holds with the natural hand's inertia along the line
        (``path_acceleration_cap``, as the way in from rest)."""
        if self.reach is None or self.rail is None or a[1] == b[1]:
            rail = self.home.rail_move(a[0], b[0])
            if self.reach is None or self.rail is None:
                return rail
            return Move(np.array([a[0], a[1]]), np.array([rail.dq[0], 0.0]), rail.duration_s,
                        rail.ta_s, rail.tj_s)
        h, m, cols = self.hand, self.home, self.arm
        qa, qb = np.array(a[:len(cols)]), np.array(b[:len(cols)])
        dq = qb - qa
        caps = path_caps(dq.tolist(), h.velocity[cols].tolist(), m.acceleration[cols].tolist(),
                         m.jerk[cols].tolist())
        if caps is None:
            return capped_move(qa, dq, None)
        full = np.zeros(h.n)
        full[cols] = dq
        line = []
        for s in np.linspace(0.0, 1.0, PATH_SAMPLES):
            q = self.atlas.base.copy()
            q[cols] = qa + s * dq
            line.append(h.apply_couplings(q))
        v, acc, j = caps
        return capped_move(qa, dq, (v, min(acc, path_acceleration_cap(h, line, full)), j))

    def tendon_slowed(self, move: Move, posture: int, cols: np.ndarray,
                      pressing: tuple[int, ...]) -> Move:
        """``move`` of the joints ``cols`` (the rest of the hand at posture ``posture``'s
        natural pose), the fingers ``pressing`` holding their keys, timed within every
        motor's capacity (``planner.play.tendonload.hand_load``: the groups' reactions add
        up on the wrist's and arm's motors; slowed if need be)."""
        q_a, dq = self.atlases[posture].base.copy(), np.zeros(self.hand.n)
        q_a[cols], dq[cols] = move.q_a, move.dq
        return slowed(move, hand_load(self.hand).time_scale(move, q_a, dq, pressing))

    # ------------------------------------------------------------------ moves
    def moves_of(self, e: AtlasEntry) -> Moves:
        return self.moves[e.posture]

    def press_min_s(self, e: AtlasEntry) -> float:
        return self.moves[e.posture].press_min_s(e)

    def repeat_gap_s(self, e: AtlasEntry) -> float:
        return self.moves[e.posture].repeat_gap_s(e)

    def before_rail_s(self, e: AtlasEntry) -> float:
        return self.moves[e.posture].before_rail_s(e)

    def after_rail_s(self, e: AtlasEntry) -> float:
        return self.moves[e.posture].after_rail_s(e)

    def move_gap_s(self, a: AtlasEntry, b: AtlasEntry) -> float | None:
        """A finger's lift from ``a``, its move across and its descent onto ``b`` (the
        moves of ``b``'s posture: another posture's entry is found by forward kinematics,
        its heights the same)."""
        if a.posture == b.posture:
            return self.moves[b.posture].move_gap_s(a, b)
        lat = self.moves[b.posture].across_s(a, b)
        if lat is None:
            return None
        return self.before_rail_s(a) + lat + self.after_rail_s(b)

    def across(self, a: AtlasEntry, b: AtlasEntry) -> Move | None:
        return self.moves[b.posture].across(a, b)

    def follow_s(self, a: AtlasEntry, b: AtlasEntry) -> float:
        return self.moves[a.posture].follow_s(a, b)

    def follow_clear(self, a: AtlasEntry, b: AtlasEntry) -> bool:
        return a.posture == b.posture and self.moves[a.posture].follow_clear(a, b)

    def follow(self, a: AtlasEntry, b: AtlasEntry) -> Move | None:
        return self.moves[a.posture].follow(a, b) if a.posture == b.posture else None

    def descend(self, e: AtlasEntry, start: str):
        return self.moves[e.posture].descend(e, start)

    def lift(self, e: AtlasEntry, end: str):
        return self.moves[e.posture].lift(e, end)

    def rise(self, e: AtlasEntry):
        return self.moves[e.posture].rise(e)

    def to_hover(self, e: AtlasEntry) -> Move:
        return self.moves[e.posture].to_hover(e)
