"""The arm's moves of one hand: the rail and the reach axis between two places, and the
arm carrying fingers that hold their keys (``planner.play.places``' places; the motion's
very moves, and their durations for the programme).

``ArmMoves.arm_move`` is one time-optimal straight move of the arm's joints (the rail,
and the reach axis if the rig has one) within their speed, acceleration and jerk bounds,
its path's acceleration within what every motor holds with the natural hand's inertia
along the line; ``carry_move`` adds the held fingers' joints to the same straight move;
``tendon_slowed`` times a move within every motor's capacity while fingers hold keys.
"""

from __future__ import annotations

import numpy as np

from planner.hand.model import HandModel
from planner.play.atlas import PATH_SAMPLES, Atlas
from planner.play.moves import Moves
from planner.play.profile import Move, capped_move, path_caps
from planner.play.railcap import path_acceleration_cap
from planner.play.tendonload import hand_load, slowed

RAIL_STEP_M = 0.006  # the hand positions the programme weighs, this far apart on the rail
PLACE_STRIDE = 1000  # place = posture * PLACE_STRIDE + rail index (a rail index lies within
# +-PLACE_STRIDE / 2: 3 m of rail either way)


def posture_of(place: int) -> int:
    """The play posture of a place (``Places.posture_of``)."""
    return (place + PLACE_STRIDE // 2) // PLACE_STRIDE


def rail_i(place: int) -> int:
    """The rail index of a place (on the ``RAIL_STEP_M`` grid)."""
    return place - posture_of(place) * PLACE_STRIDE


class ArmMoves:
    """The arm's moves of one hand over its postures' atlases and moves (``Places.arms``)."""

    def __init__(self, hand: HandModel, atlases: tuple[Atlas, ...],
                 moves: tuple[Moves, ...]) -> None:
        self.hand, self.atlases, self.moves = hand, atlases, moves
        self.atlas, self.home = atlases[0], moves[0]  # (the rest pose's posture)
        self.rail = self.atlas.rail
        self.reach = hand.index.get("reach")
        self.arm = [j for j in (self.rail, self.reach) if j is not None]
        self._arm_s: dict[tuple[int, int, int], float] = {}
        # (the programme asks these of ~10^5 pairs of places a song: memoised by the pair)
        self._arm_ab: dict[tuple[int, int], float] = {}
        # (``tendon_slowed``'s factors, by the move and its joints: an arm's move carrying
        # the same held keys comes again wherever a passage does: 37 of 187 on three corpus
        # pieces)
        self._sigma: dict[tuple, float] = {}

    def reach_m(self, posture: int) -> float:
        return 0.0 if self.reach is None else float(self.atlases[posture].base[self.reach])

    def arm_time_s(self, a: int, b: int) -> float:
        """The arm's move from place ``a`` to place ``b`` (memoised by the pair)."""
        got = self._arm_ab.get((a, b))
        if got is None:
            got = self._arm_ab[(a, b)] = self._arm_time_s(a, b)
        return got

    def _arm_time_s(self, a: int, b: int) -> float:
        """The arm's move from place ``a`` to place ``b`` (memoised by the postures and the
        rail's steps of the move or of its reverse, which takes the same time: the move
        of the rail and the reach together is the same line of configurations backwards,
        the rail prismatic along x; it is found from the lower posture, so that the answer
        is the same whichever way was asked first. The rail's sign matters when the
        posture changes: a right hand is not its mirror image, and the path's acceleration
        cap is the motors' against gravity and the hand's inertia along the line)."""
        pa, pb = posture_of(a), posture_of(b)
        steps = rail_i(b) - rail_i(a)
        if pa == pb:
            key = (0, 0, abs(steps))
        else:
            key = (pa, pb, steps) if pa < pb else (pb, pa, -steps)
        got = self._arm_s.get(key)
        if got is None and pa != pb:  # (the move table's, made by the same ``arm_move``)
            got = self.moves[key[0]].table.arm_s(key[1], key[2])
        if got is None:
            got = self.arm_move(
                (0.0, self.reach_m(key[0])), (key[2] * RAIL_STEP_M, self.reach_m(key[1]))
            ).duration_s
        self._arm_s[key] = got
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
        qa = np.array(a[:len(self.arm)])
        dq = np.array(b[:len(self.arm)]) - qa
        return capped_move(qa, dq, self.arm_caps(qa, dq))

    def arm_caps(self, qa: np.ndarray, dq: np.ndarray) -> tuple[float, float, float] | None:
        """The path caps (``path_caps``) of the arm's straight move by ``dq`` (its joints
        ``arm``) from ``qa``, its acceleration within what every motor holds with the
        natural hand's inertia along the line (``path_acceleration_cap``)."""
        h, m, cols = self.hand, self.home, self.arm
        caps = path_caps(dq.tolist(), h.velocity[cols].tolist(), m.acceleration[cols].tolist(),
                         m.jerk[cols].tolist())
        if caps is None:
            return None
        full = np.zeros(h.n)
        full[cols] = dq
        line = np.tile(self.atlas.base, (PATH_SAMPLES, 1))  # (the samples' rows at once)
        line[:, cols] = qa + np.linspace(0.0, 1.0, PATH_SAMPLES)[:, None] * dq
        line = h.apply_couplings(line)
        v, acc, j = caps
        return v, min(acc, path_acceleration_cap(h, line, full)), j

    def tendon_slowed(self, move: Move, posture: int, cols: np.ndarray,
                      pressing: tuple[int, ...]) -> Move:
        """``move`` of the joints ``cols`` (the rest of the hand at posture ``posture``'s
        natural pose), the fingers ``pressing`` holding their keys, timed within every
        motor's capacity (``planner.play.tendonload.hand_load``: the groups' reactions add
        up on the wrist's and arm's motors; slowed if need be)."""
        key = (posture, cols.tobytes(), move.q_a.tobytes(), move.dq.tobytes(),
               move.duration_s, move.ta_s, move.tj_s, pressing)
        sigma = self._sigma.get(key)
        if sigma is None:  # (what the factor depends on: the key's, to the bit)
            q_a, dq = self.atlases[posture].base.copy(), np.zeros(self.hand.n)
            q_a[cols], dq[cols] = move.q_a, move.dq
            sigma = self._sigma[key] = hand_load(self.hand).time_scale(move, q_a, dq,
                                                                        pressing)
        return slowed(move, sigma)

    def carry_move(self, arm_a: np.ndarray, arm_b: np.ndarray, held) -> Move:
        """The arm from ``arm_a`` to ``arm_b`` (its joints ``arm``) carrying the fingers
        of ``held``, (entry before, entry after) pairs of one key each, on one straight
        time-optimal move: the arm's joints first in ``q_a``, then each finger's."""
        qa = np.concatenate([arm_a] + [a.press for a, _ in held])
        qb = np.concatenate([arm_b] + [b.press for _, b in held])
        return self.carry(qa, qb - qa, [a.finger for a, _ in held])

    def carry(self, qa: np.ndarray, dq: np.ndarray, fingers: list[str],
               caps: tuple | None = None) -> Move:
        """The move by ``dq`` from ``qa`` (the arm's joints, then ``fingers``' joints):
        the arm's caps (``arm_caps``, or ``caps`` when given) and every finger joint's
        speed, acceleration and jerk bounds, the tightest of each."""
        n = len(self.arm)
        if caps is None:
            caps = self.arm_caps(qa[:n], dq[:n])
        cols = np.concatenate([self.hand.joint_slice(f) for f in fingers])
        fc = path_caps(dq[n:].tolist(), self.hand.velocity[cols].tolist(),
                       self.home.acceleration[cols].tolist(), self.home.jerk[cols].tolist())
        if caps is None or fc is None:
            caps = caps or fc
        else:
            caps = tuple(min(x, y) for x, y in zip(caps, fc))
        return capped_move(qa, dq, caps)

    def carry_cols(self, finger: str) -> np.ndarray:
        return np.r_[self.arm, self.hand.joint_slice(finger)]
