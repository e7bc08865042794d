"""A finger's moves across shown within the tendons' share by a bound over a box of
moves at once (``planner.play.tendonproof.BoxBound``), before the per-move test.

``Moves`` keeps one per posture: each finger's box of high poses (``high_boxes``) with
the entries that made it. A move across between two of them lies in the box; a move from
an entry outside it (another posture's, or one found later) to one of them lies in the
box stretched to the first entry's high pose, which the cells over every posture hold
(``TendonProof.cells_gain``). Either bound is at least the move's own (the same terms,
summed over more poses), so where it proves the move, the full bound's answer is 1.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from planner.hand.model import HandModel
from planner.play.atlas import Atlas, AtlasEntry
from planner.play.profile import Move
from planner.play.tendonproof import BoxBound, TendonProof


class FingerBox(NamedTuple):
    """A finger's box of high poses (its joints, couplings applied), the least and
    greatest of its entries' high poses joint by joint (before the couplings), and the
    entries by id."""

    lo: np.ndarray
    hi: np.ndarray
    least: np.ndarray
    most: np.ndarray
    by_id: dict[int, AtlasEntry]


class AcrossProof:
    """The box bounds of one posture's moves across (``proves``)."""

    def __init__(self, hand: HandModel, atlas: Atlas, proof: TendonProof,
                 boxes: dict[str, tuple[np.ndarray, np.ndarray]]) -> None:
        self.hand, self.base, self.proof = hand, atlas.base, proof
        highs: dict[str, list[AtlasEntry]] = {}
        for e in atlas.solved().values():
            highs.setdefault(e.finger, []).append(e)
        self.boxes: dict[str, FingerBox] = {}
        for f, (lo, hi) in boxes.items():
            H = np.array([e.high for e in highs[f]])
            self.boxes[f] = FingerBox(lo, hi, H.min(axis=0), H.max(axis=0),
                                      {id(e): e for e in highs[f]})
        # (the box bounds when first asked: by finger, and by the entry a move starts from
        # when it is not one of the box's, with the entry)
        self._own: dict[str, BoxBound | None] = {}
        self._from: dict[int, tuple[AtlasEntry, BoxBound | None]] = {}

    def proves(self, a: AtlasEntry, b: AtlasEntry, move: Move) -> bool:
        """Whether the box bound shows ``move`` (across from ``a``'s high pose to
        ``b``'s, ``b`` one of the box's entries) within every tendon motor's share."""
        box = self.boxes.get(a.finger)
        if box is None or move.duration_s == 0.0 or box.by_id.get(id(b)) is not b:
            return False
        if box.by_id.get(id(a)) is a:
            if a.finger not in self._own:
                self._own[a.finger] = self.proof.box_bound(a.finger, box.lo, box.hi,
                                                           box.most - box.least)
            bound = self._own[a.finger]
        else:
            got = self._from.get(id(a))
            if got is None or got[0] is not a:
                got = self._from[id(a)] = (a, self._stretched(a, box))
            bound = got[1]
        return bound is not None and bound.proves(move.dq, move.peak_acceleration,
                                                  move.peak_speed)

    def _stretched(self, a: AtlasEntry, box: FingerBox) -> BoxBound | None:
        """The bound over the box stretched to ``a``'s high pose (the move's start as
        ``TendonProof.bound_nm`` takes it: the couplings applied to the hand at rest with
        ``a``'s finger at its high pose)."""
        js = self.hand.joint_slice(a.finger)
        q = self.base.copy()
        q[js] = a.high
        p = self.hand.apply_couplings(q)[js]
        reach = np.maximum(box.most, a.high) - np.minimum(box.least, a.high)
        return self.proof.box_bound(a.finger, np.minimum(box.lo, p), np.maximum(box.hi, p),
                                    reach)
