"""The rail and a finger holding its key together: the follows of one play posture's
``Moves`` (``planner.play.moves``), timed, and kept where the follow test passes
(``planner.play.follow``; a hand without the body rule: the tip on the key, the key down,
by forward kinematics at ``PATH_SAMPLES``). The move table (``planner.play.movetable``)
has the answer of every pair of one finger's entries on one key; another pair's is found
when first asked.
"""

from __future__ import annotations

import numpy as np

from planner.ik import surfaces_under
from planner.music import keyboard as kb
from planner.play.atlas import PATH_SAMPLES, TIP_RADIUS_M, AtlasEntry
from planner.play.follow import HOLD_MARGIN_M, canonical_pitch, paths_clear
from planner.play.profile import Move, move_time_s, path_caps, straight_move


class FollowMoves:
    """``Moves``' follows (a part of ``Moves``: its hand, atlas, move table, limits and
    memos)."""

    def follow(self, a: AtlasEntry, b: AtlasEntry) -> Move | None:
        """The rail and a finger holding its key together, from entry ``a`` to entry
        ``b`` of the same key (another place relative to the rail): one time-optimal
        straight move of the rail and the finger's joints (rail first in ``dq``), kept
        only when forward kinematics finds the tip inside the key's footprint and the key
        down (``HOLD_MARGIN_M`` past the key-down depth, as far from the key bed) all the
        way, and with the atlas's body rule the finger's body holding the key down and
        clear of every other key (``planner.play.follow``); None otherwise."""
        key = ("follow", id(a), id(b))
        if key not in self._lat:
            self._lat[key] = self._follow(a, b)
        return self._lat[key]

    def follow_s(self, a: AtlasEntry, b: AtlasEntry) -> float:
        """How long ``follow(a, b)`` takes if its path is clear (no forward kinematics,
        no Move: the programme asks this first, and the path only of the moves that
        fit): the move of ``_follow_ends``, its rail from the key's centre less each
        entry's ``dx``."""
        key = (id(a), id(b))
        got = self._follow_s.get(key)
        if got is None:
            x = kb.key(60 + a.pitch_class).center_x_m
            pa, pb = self._poses(a).press, self._poses(b).press
            caps = path_caps([(x - b.dx_m) - (x - a.dx_m), *[y - z for z, y in zip(pa, pb)]],
                             *self._follow_limits[a.finger])
            got = self._follow_s[key] = 0.0 if caps is None else move_time_s(*caps)
        return got

    def follow_clear(self, a: AtlasEntry, b: AtlasEntry) -> bool:
        """Whether ``follow(a, b)`` is a move (the move table's answer, without making
        it; forward kinematics when the table has none)."""
        ia, ib = self._record(a).places, self._record(b).places
        table = self._follow_bytes.get((a.finger, a.pitch_class))
        if ia is not None and ib is not None and table is not None \
                and a.pitch_class == b.pitch_class:
            return table[0][ia[1] * table[1] + ib[1]] == 1
        ok = self.table.follow_clear(a, b)
        return self.follow(a, b) is not None if ok is None else ok

    def _follow_ends(self, a: AtlasEntry, b: AtlasEntry):
        key = ("ends", id(a), id(b))
        got = self._lat.get(key)
        if got is None:
            h, r = self.hand, self.atlas.rail
            k = kb.key(60 + a.pitch_class)
            js = self.js[a.finger]
            cols = np.r_[r, js]
            qa, qb = self.atlas.base.copy(), self.atlas.base.copy()
            qa[r], qb[r] = k.center_x_m - a.dx_m, k.center_x_m - b.dx_m
            qa[js], qb[js] = a.press, b.press
            move = straight_move(qa[cols], qb[cols], h.velocity[cols], self.acceleration[cols],
                                 self.jerk[cols])
            got = self._lat[key] = (qa, qb, move, cols)
        return got

    def _follow(self, a: AtlasEntry, b: AtlasEntry) -> Move | None:
        h, r = self.hand, self.atlas.rail
        if r is None:
            return None
        qa, qb, move, cols = self._follow_ends(a, b)
        ok = self.table.follow_clear(a, b)
        if ok is not None:
            return move if ok else None
        if self.atlas.bodies is not None:  # (the body rule: ``planner.play.follow``)
            ok = paths_clear(self.atlas, a.finger, canonical_pitch(a), qa[None], qb[None],
                             [r])[0]
            return move if ok else None
        k = kb.key(60 + a.pitch_class)
        f = h.fingers.index(a.finger)
        q = qa.copy()
        tips = np.empty((PATH_SAMPLES, 3))
        for i, s in enumerate(np.linspace(0.0, 1.0, PATH_SAMPLES)):
            q[cols] = qa[cols] + s * (qb[cols] - qa[cols])
            x, y, z = tips[i] = h.tip_position(h.apply_couplings(q), f)
            inside = (k.x_min_m + TIP_RADIUS_M <= x <= k.x_max_m - TIP_RADIUS_M
                      and k.y_min_m + TIP_RADIUS_M <= y <= k.y_max_m - TIP_RADIUS_M)
            depth = k.top_z_m - z
            if not (inside and kb.DOWN_DEPTH_M + HOLD_MARGIN_M <= depth
                    <= kb.KEY_BED_DEPTH_M - HOLD_MARGIN_M):
                return None
        # (a white key's tip stays off the black keys beside it: nothing higher under it)
        if k.black is False and np.any(surfaces_under(tips[:, 0], tips[:, 1], TIP_RADIUS_M)
                                       > k.top_z_m):
            return None
        return move
