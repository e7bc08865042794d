"""The fingers that press no key, and where they wait.

A finger with no atlas entry in any play posture (the default hand's thumb: no pose of
it presses a key with its body clear of the others) plays nothing, but its body still
moves with the arm. Natural, the default hand's thumb hangs 52 mm below the keys' tops
inside a white key's footprint column in its third posture (reach -0.10 m): a wrong
press by check's body rule (spec section 2) in every plan that went there. Such a finger
holds, all song long, the pose nearest its natural one whose body enters no key's column
in any posture at any rail (``IdleFingers.pose``); the motion starts with it there
(``Motion``) and the way in from rest tucks it while the rail runs in the rest posture
(``planner.play.rest.legs_between``). Without the body rule (a hand with no ``[play]``
posture) it keeps its natural pose.
"""

from __future__ import annotations

import itertools

import numpy as np

from planner.hand.model import HandModel
from planner.music.keybodies import sphere_depths
from planner.play.atlas import SPAN_M, STEP_M, Atlas

IDLE_STEPS = 7  # an idle finger's pose is searched on this many values of each joint


class IdleFingers:
    """The fingers of one hand that press no key, and their poses (memoised)."""

    def __init__(self, hand: HandModel, atlases: tuple[Atlas, ...], rail: int | None) -> None:
        self.hand, self.atlases, self.rail = hand, atlases, rail
        self.atlas = atlases[0]
        self._poses: dict[str, np.ndarray | None] = {}
        self._fingers: tuple[str, ...] | None = None

    @property
    def fingers(self) -> tuple[str, ...]:
        """The fingers that press no key from any place in any posture (no atlas entry:
        the default hand's thumb)."""
        if self._fingers is None:
            n = round(SPAN_M / STEP_M)  # (nearest the natural place first: a finger
            # that plays finds an entry at once)
            self._fingers = tuple(
                f for f in self.hand.fingers
                if not any(a.entry_at(f, pc, k) is not None for a in self.atlases
                           for k in sorted(range(-n, n + 1), key=abs) for pc in range(12)))
        return self._fingers

    def tuck(self, q: np.ndarray) -> np.ndarray:
        """``q`` with every idle finger (``fingers``) at its ``pose`` (``q`` itself
        without the body rule: there is none)."""
        if self.atlas.bodies is None or self.rail is None:
            return q
        poses = [(f, p) for f in self.fingers if (p := self.pose(f)) is not None]
        if not poses:
            return q
        q = q.copy()
        for f, pose in poses:
            q[self.hand.joint_slice(f)] = pose
        return self.hand.apply_couplings(q)

    def pose(self, finger: str) -> np.ndarray | None:
        """The joints (``hand.joint_slice(finger)``) of a finger that presses no key in
        any posture: of the poses on a grid of each joint's planning range
        (``IDLE_STEPS`` steps), the nearest its natural one (the sum of the joints'
        moves) whose body enters no key's footprint column in any play posture, at any
        rail (spec section 2's body rule: then it presses nothing, wherever the arm
        goes); its natural joints when they are such; None without the body rule (the
        finger keeps its pose) or when no pose of the grid is (memoised). Measured
        against the body held as high as its joints let it (the thumb at a corner of its
        travel, 1.40 rad of joint moves from natural against this pose's 0.38): the same
        F1 by check and in physics on the sample songs, 0-2 rows shorter."""
        got = self._poses.get(finger, False)
        if got is not False:
            return got
        h, js = self.hand, self.hand.joint_slice(finger)
        natural = self.atlas.base[js]
        got = None
        if self.atlas.bodies is not None and self.rail is not None:
            grid = itertools.product(*(np.linspace(h.plan_lower[j], h.plan_upper[j], IDLE_STEPS)
                                       for j in js))
            for c in [natural, *sorted((np.array(c) for c in grid),
                                       key=lambda c: (float(np.abs(c - natural).sum()),
                                                      tuple(c)))]:
                if self._enters_no_key(finger, c):
                    got = c
                    break
        self._poses[finger] = got
        return got

    def narrow(self) -> None:
        """Two hands on one rail (``planner.play.twohands``): every idle finger holds, of
        the grid poses whose body enters no key's column (``pose``'s rule), the one whose
        body reaches least far from the rail on the hand's inner side (the thumb's: below
        it on a right hand, above it on a left one), ties to the nearest its natural
        pose, so that the other hand's carriage may come nearer (``planner.play.handgap``:
        the default hand's thumb tucked under the palm reaches 64 mm inside the rail, at
        its natural-nearest pose 122 mm). Without the body rule nothing changes."""
        if self.atlas.bodies is None or self.rail is None:
            return
        h, fb = self.hand, self.atlas.bodies
        sign = -1.0 if h.side == "right" else 1.0  # (the inner side: the thumb's)
        for f in self.fingers:  # (every grid pose's reach at once, then the body rule
            # tested from the least reach up: the first pose it admits is the one)
            js = h.joint_slice(f)
            natural = self.atlas.base[js]
            cands = [np.array(c) for c in itertools.product(
                *(np.linspace(h.plan_lower[j], h.plan_upper[j], IDLE_STEPS) for j in js))]
            Q = []
            for c in cands:
                for a in self.atlases:
                    q = a.base.copy()
                    q[self.rail], q[js] = 0.0, c
                    Q.append(q)
            P = fb.points_many(h.apply_couplings(np.array(Q)), f)
            reach = (sign * P[..., 0] + fb.radii(f)).reshape(len(cands), -1).max(axis=1)
            for *_, i in sorted((round(float(reach[i]), 9), float(np.abs(c - natural).sum()),
                                 tuple(c), i) for i, c in enumerate(cands)):
                if self._enters_no_key(f, cands[i]):
                    self._poses[f] = cands[i]
                    break

    def _enters_no_key(self, finger: str, joints: np.ndarray) -> bool:
        """Whether ``finger``'s body with its joints at ``joints``, the rest of the hand
        natural, lies outside every key's footprint column in every posture (the rail
        at either end of its travel and at 0: the keyboard's columns repeat by octave,
        and a body out of them is so by its height or by lying in front of the keys)."""
        h, fb, js = self.hand, self.atlas.bodies, self.hand.joint_slice(finger)
        r = h.index["rail"]
        Q = []
        for a in self.atlases:
            for rail in (h.plan_lower[r], 0.0, h.plan_upper[r]):
                q = a.base.copy()
                q[self.rail], q[js] = rail, joints
                Q.append(q)
        P = fb.points_many(h.apply_couplings(np.array(Q)), finger)
        radii = fb.radii(finger)
        return all(np.all(sphere_depths(p, radii) < 0.0) for p in P)
