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
from planner.play.armmoves import PLACE_STRIDE, RAIL_STEP_M, ArmMoves
from planner.play.atlas import STEP_M, Atlas, AtlasEntry, posture_count
from planner.play.follow import canonical_pitch, follow_ends, paths_clear
from planner.play.followtable import FollowTable, table_path
from planner.play.followtable import params as follow_params
from planner.play.highclear import HighClear
from planner.play.idle import IdleFingers
from planner.play.moves import Moves
from planner.play.movetable import drop_stale_cross
from planner.play.profile import Move

_HALF = PLACE_STRIDE // 2  # (``posture_of``'s offset)


class Places:
    """Every play posture's atlas and moves of one hand (built once, ``Planner``)."""

    def __init__(self, hand: HandModel) -> None:
        self.hand = hand
        self.atlases = tuple(Atlas(hand, posture=i) for i in range(posture_count(hand)))
        self.moves = tuple(Moves(hand, a) for a in self.atlases)
        self.high = HighClear(hand, self.atlases, self.moves)  # (when a tip is high enough
        # for the arm; the move tables' moments)
        drop_stale_cross([m.table for m in self.moves])
        self.atlas, self.home = self.atlases[0], self.moves[0]  # (the rest pose's posture)
        self.rail = self.atlas.rail
        self.reach = hand.index.get("reach")
        self.natural_dx = self.atlas.natural_dx  # (x: the same in every posture)
        self.arm = [j for j in (self.rail, self.reach) if j is not None]
        # (the whole hand's bounds, for the moves of the whole hand: the rest pose's)
        self.acceleration, self.jerk = self.home.acceleration, self.home.jerk
        self.arms = ArmMoves(hand, self.atlases, self.moves)  # (the arm's moves)
        # (the programme asks these of ~10^5 pairs of places a song: read from a list)
        self._reach_of = [self.reach_m(p) for p in range(len(self.atlases))]
        # (follows across postures: their times and answers, by the entries' ids)
        self._cross_s: dict[tuple[int, int], float] = {}
        self._cross_clear: dict[tuple[int, int], bool] = {}
        self._cross_arm: dict[tuple[int, int, float], tuple | None] = {}  # (``follow_s``)
        self.idle = IdleFingers(hand, self.atlases, self.rail)  # (fingers that press no key)
        # (the follow test's answers on the rail's grid, shipped: ``follow_path_clear``)
        self.follows = FollowTable()
        path = table_path(hand.urdf_sha256)
        if self.rail is not None and self.atlas.bodies is not None and path.exists():
            self.follows.load(path, follow_params(self))
        self._finger_i = {f: i for i, f in enumerate(hand.fingers)}

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

    def presses_clear(self, finger: str, pitch: int, places: list[int]) -> list[bool]:
        """Whether ``finger``'s press pose on key ``pitch`` from each of ``places`` (an
        entry there) keeps its body clear of every other key with the rail where the place
        puts it (the atlas's body rule, ``FingerBodies.clear``: the atlas tested the pose
        at its entry's own ``dx``, which the rail's grid misses by up to half its step,
        and a body's side beside a key's wall can reach a millimetre deeper for that).
        All True without the body rule; the shipped answers where the table has every
        place (``planner.play.followtable``)."""
        if self.atlas.bodies is None or self.rail is None or not places:
            return [True] * len(places)
        if len(self.follows):  # (the shipped answers: ``planner.play.followtable``)
            fi = self._finger_i[finger]
            got = [self.follows.press(fi, pitch, q) for q in places]
            if None not in got:
                return got
        Q = []
        for place in places:
            e = self.entry(finger, pitch, place)
            q = self.atlases[e.posture].base.copy()
            q[self.rail] = self.rail_m(place)
            q[self.hand.joint_slice(finger)] = e.press
            Q.append(q)
        fb = self.atlas.bodies
        ok, _ = fb.clear_many(fb.points_many(self.hand.apply_couplings(np.array(Q)), finger),
                              fb.radii(finger), pitch)
        return ok.tolist()

    def body_refused(self, finger: str, pitch: int, place: int) -> bool:
        """Whether ``finger`` would press key ``pitch`` from ``place`` but for its body."""
        p = self.posture_of(place)
        return self.atlases[p].body_refused(finger, pitch, (place - p * PLACE_STRIDE) * RAIL_STEP_M)

    def distance_m(self, a: int, b: int) -> float:
        """How far the arm moves between two places (rail and reach, m)."""
        pa, pb = (a + _HALF) // PLACE_STRIDE, (b + _HALF) // PLACE_STRIDE
        return (abs((a - pa * PLACE_STRIDE) - (b - pb * PLACE_STRIDE)) * RAIL_STEP_M
                + abs(self._reach_of[pa] - self._reach_of[pb]))

    def arm_time_s(self, a: int, b: int) -> float:
        """The arm's move from place ``a`` to place ``b`` (``ArmMoves.arm_time_s``)."""
        return self.arms.arm_time_s(a, b)

    def arm_move(self, a: tuple[float, float], b: tuple[float, float]) -> Move:
        """The arm from (rail, reach) ``a`` to ``b`` (``ArmMoves.arm_move``)."""
        return self.arms.arm_move(a, b)

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

    def rail_lift_s(self, e: AtlasEntry, front: bool = True) -> float:
        """Key up to the lifting finger clear above every key for good (``front``: by the
        front rule, ``planner.play.highclear``): the arm may move from then on."""
        u = self.lift(e, "high")
        return max(0.0, self.high.rise_clear_s(e, u.move, front) - u.cross_s)

    def rail_descent_s(self, e: AtlasEntry, front: bool = True) -> float:
        """The start of the descent from crossing height that the arm must have ended
        by, to key down: the descent's part below the clear height (``front``: by the
        front rule; ``after_rail_s`` is all of it)."""
        d = self.descend(e, "high")
        return max(0.0, d.cross_s - self.high.descent_clear_s(e, d.move, front))

    def move_gap_s(self, a: AtlasEntry, b: AtlasEntry) -> float | None:
        """A finger's lift from ``a``, its move across and its descent onto ``b`` (the
        moves of ``b``'s posture, another posture's entry by its poses alone: its key
        crossings are its own posture's, not found again by forward kinematics)."""
        if a.posture == b.posture:
            return self.moves[b.posture].move_gap_s(a, b)
        lat = self.moves[b.posture].across_s(a, b)
        if lat is None:
            return None
        return self.before_rail_s(a) + lat + self.after_rail_s(b)

    def across(self, a: AtlasEntry, b: AtlasEntry) -> Move | None:
        return self.moves[b.posture].across(a, b)

    # ------------------------------------------------------------------ follows
    def follow_s(self, a: AtlasEntry, b: AtlasEntry) -> float:
        """How long the arm takes carrying a finger holding its key from entry ``a`` to
        entry ``b`` of the same key (``Moves.follow_s``; across postures, the rail, the
        reach axis and the finger's joints on one straight move: ``carry_move``)."""
        if a.posture == b.posture:
            return self.moves[a.posture].follow_s(a, b)
        key = (id(a), id(b))
        got = self._cross_s.get(key)
        if got is None and len(self.follows):  # (the shipped time of the pair)
            row = self._cross_row(a, b)
            if row is not None:
                got = self._cross_s[key] = row[1]
        if got is None:
            qa, qb = follow_ends(self.atlases[a.posture], self.atlases[b.posture], a, b)
            cols = self.arms.carry_cols(a.finger)
            dq = qb[cols] - qa[cols]
            # (the arm's caps from rail 0: the same for every move of the same steps, the
            # rail and reach prismatic, and so memoised by them alone)
            arm = (a.posture, b.posture, float(dq[0]))
            caps = self._cross_arm.get(arm)
            if caps is None:
                caps = self._cross_arm[arm] = self.arms.arm_caps(
                    np.array([0.0, self.reach_m(a.posture)]), dq[:len(self.arm)])
            got = self._cross_s[key] = self.arms.carry(qa[cols], dq, [a.finger], caps).duration_s
        return got

    def follow_clear(self, a: AtlasEntry, b: AtlasEntry) -> bool:
        """Whether a finger holding its key can follow it from entry ``a`` to entry ``b``
        (``Moves.follow_clear``; across postures, with the atlas's body rule only:
        ``planner.play.follow``, found by forward kinematics when first asked)."""
        if a.posture == b.posture:
            return self.moves[a.posture].follow_clear(a, b)
        if self.reach is None or self.atlas.bodies is None or a.pitch_class != b.pitch_class:
            return False
        key = (id(a), id(b))
        got = self._cross_clear.get(key)
        if got is None and len(self.follows):  # (the shipped answer of the pair)
            row = self._cross_row(a, b)
            if row is not None:
                got = self._cross_clear[key] = row[0]
        if got is None:
            qa, qb = follow_ends(self.atlases[a.posture], self.atlases[b.posture], a, b)
            got = self._cross_clear[key] = bool(paths_clear(
                self.atlas, a.finger, canonical_pitch(a), qa[None], qb[None], self.arm)[0])
        return got

    def sample_of(self, e: AtlasEntry) -> int:
        """The entry's sample in its atlas (``Atlas.entry_at``'s ``k``: its ``dx`` less the
        finger's natural one, in ``STEP_M``)."""
        return round((e.dx_m - self.natural_dx[e.finger]) / STEP_M)

    def _cross_row(self, a: AtlasEntry, b: AtlasEntry) -> tuple[bool, float] | None:
        """The shipped follow across postures of entries ``a`` and ``b`` (of one finger
        and key; ``FollowTable.cross``) when they are their atlases' entries at their
        samples (the pair the table found); None otherwise."""
        ka, kb_ = self.sample_of(a), self.sample_of(b)
        if self.atlases[a.posture].entry_at(a.finger, a.pitch_class, ka) is not a \
                or self.atlases[b.posture].entry_at(b.finger, b.pitch_class, kb_) is not b:
            return None
        return self.follows.cross(self._finger_i[a.finger], a.pitch_class, a.posture, ka,
                                  b.posture, kb_)

    def follow(self, a: AtlasEntry, b: AtlasEntry) -> Move | None:
        return self.moves[a.posture].follow(a, b) if a.posture == b.posture else None

    def follow_path_clear(self, a: AtlasEntry, b: AtlasEntry, pitch: int, rail_a_m: float,
                          rail_b_m: float) -> bool:
        """Whether a finger holding key ``pitch`` follows it from entry ``a`` with the rail
        at ``rail_a_m`` to entry ``b`` at ``rail_b_m``: the body rule's test on the very
        move the motion makes (``planner.play.follow``; the move table tested each pair
        at its entries' own ``dx``, which the rail's grid misses by up to half the atlas's
        step). True without the body rule (the table's answer stands). On the rail's
        grid, with the entries of the finger on the key there, the shipped answer
        (``planner.play.followtable``: the same test on the same move)."""
        if self.atlas.bodies is None or self.rail is None:
            return True
        if len(self.follows):
            got = self._follow_row(a, b, pitch, rail_a_m, rail_b_m)
            if got is not None:
                return got
        qa, qb = self.follow_ends_on_rail(a, b, rail_a_m, rail_b_m)
        return bool(paths_clear(self.atlas, a.finger, pitch, qa[None], qb[None], self.arm)[0])

    def _follow_row(self, a: AtlasEntry, b: AtlasEntry, pitch: int, rail_a_m: float,
                    rail_b_m: float) -> bool | None:
        """``follow_path_clear``'s answer from the shipped table: when both rails are on
        the grid (the very floats ``rail_m`` gives) and ``a`` and ``b`` are the finger's
        entries on the key there (the move the table tested); None otherwise."""
        ia, ib = round(rail_a_m / RAIL_STEP_M), round(rail_b_m / RAIL_STEP_M)
        if ia * RAIL_STEP_M != rail_a_m or ib * RAIL_STEP_M != rail_b_m:
            return None
        pa, pb = self.place(a.posture, ia), self.place(b.posture, ib)
        if self.entry(a.finger, pitch, pa) is not a or self.entry(b.finger, pitch, pb) is not b:
            return None
        return self.follows.get(self._finger_i[a.finger], pitch, pa, pb)

    def follow_ends_on_rail(self, a: AtlasEntry, b: AtlasEntry, rail_a_m: float,
                            rail_b_m: float) -> tuple[np.ndarray, np.ndarray]:
        """The whole hand at ``follow_path_clear``'s ends: each entry's posture's base,
        the rail where given, the finger pressing."""
        js = self.hand.joint_slice(a.finger)
        qa, qb = self.atlases[a.posture].base.copy(), self.atlases[b.posture].base.copy()
        qa[self.rail], qb[self.rail] = rail_a_m, rail_b_m
        qa[js], qb[js] = a.press, b.press
        return qa, qb

    def descend(self, e: AtlasEntry, start: str):
        return self.moves[e.posture].descend(e, start)

    def lift(self, e: AtlasEntry, end: str):
        return self.moves[e.posture].lift(e, end)

    def repeat(self, e: AtlasEntry):
        return self.moves[e.posture].repeat(e)

    def repeat_pair(self, e: AtlasEntry):
        return self.moves[e.posture].repeat_pair(e)

    def rise(self, e: AtlasEntry):
        return self.moves[e.posture].rise(e)

    def to_hover(self, e: AtlasEntry) -> Move:
        return self.moves[e.posture].to_hover(e)
