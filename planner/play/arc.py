"""A one-degree-of-freedom finger's arc: the one curve its tip can follow.

A finger with one independent joint among its joints (the Mk5's: its second phalanx
follows the first through the leverism, one motor per finger; the AGH's middle and
ring, whose base joint follows another finger's shaft) cannot put its tip on a point:
with the arm where the atlas holds it (``planner.play.atlas``: the natural hovering
hand, the rail along x), its tip moves along one curve as that joint turns. The atlas
finds such a finger's poses on that curve instead of by IK, which could only come
near a point the curve misses:

* ``press``: where the arc, flexing from open, first comes down to the key's full
  dip (the finger presses by flexing); the key's x is where the rail puts the tip,
  which must then lie on the part of the key the finger presses
  (``planner.ik.press_x_range``, and ``press_target``'s y range);
* ``rise``, ``hover``, ``high``: where the arc, opening from the press, first comes
  back up to each height (not straight above the press point: the finger has no
  second joint to hold its tip's x and y while it lifts).

The joint is sampled every ``(range) / (ARC_SAMPLES - 1)``; a crossing is then
bisected on the true forward kinematics to ``ARC_TOL_RAD``. The rail moves the tip
along x only (the atlas's rail, ``Atlas.rail_for``), so a crossing's joint angle is
the same at every rail position and is computed once per height.
"""

from __future__ import annotations

import numpy as np

from planner.hand.model import HandModel

ARC_SAMPLES = 721  # samples of the joint's range (1/8 deg for the Mk5's 90 deg)
ARC_TOL_RAD = 1e-10  # a crossing is bisected to this


def arc_joint(hand: HandModel, finger: str) -> int | None:
    """The finger's one independent joint, or None when it has more than one."""
    own = hand.own_independent(finger)
    return own[0] if len(own) == 1 else None


class Arc:
    """The tip's curve of one finger, the rest of the hand at ``q_base`` (rail at 0)."""

    def __init__(self, hand: HandModel, finger: str, joint: int, q_base: np.ndarray) -> None:
        self.hand, self.joint = hand, joint
        self.tip_index = hand.fingers.index(finger)
        self.q_base = q_base.copy()
        rail = hand.index.get("rail")
        if rail is not None:
            self.q_base[rail] = 0.0
        self.s = np.linspace(hand.plan_lower[joint], hand.plan_upper[joint], ARC_SAMPLES)
        Q = np.repeat(self.q_base[None, :], ARC_SAMPLES, axis=0)
        Q[:, joint] = self.s
        Q = hand.apply_couplings(Q)  # (every law at once, vectorised over the samples)
        self.z = np.array([hand.tip_position(q, self.tip_index)[2] for q in Q])
        self._cross: dict[tuple[float, float], float | None] = {}

    def q(self, s: float, rail_m: float = 0.0) -> np.ndarray:
        """The hand with the finger's joint at ``s`` (couplings applied), the rail at
        ``rail_m``."""
        q = self.q_base.copy()
        q[self.joint] = s
        rail = self.hand.index.get("rail")
        if rail is not None:
            q[rail] = rail_m
        return self.hand.apply_couplings(q)

    def tip(self, s: float, rail_m: float = 0.0) -> np.ndarray:
        """World position of the tip with the joint at ``s``."""
        return self.hand.tip_position(self.q(s, rail_m), self.tip_index)

    def descend(self, z_m: float) -> float | None:
        """The joint angle at which the tip, flexing from open, first comes down to
        ``z_m``; None if the open tip is not above it or it never gets so low."""
        return self._crossing(z_m, float(self.s[0]))

    def ascend(self, z_m: float, from_s: float) -> float | None:
        """The joint angle at which the tip, opening from ``from_s`` (where it is below
        ``z_m``), first comes back up to ``z_m``; None if it never does."""
        return self._crossing(z_m, from_s)

    def _crossing(self, z_m: float, from_s: float) -> float | None:
        key = (round(z_m, 12), from_s)
        if key not in self._cross:
            self._cross[key] = self._find(z_m, from_s)
        return self._cross[key]

    def _find(self, z_m: float, from_s: float) -> float | None:
        above = self.tip(from_s)[2] > z_m
        if from_s == self.s[0]:  # flexing from open: the tip must start above
            if not above:
                return None
            grid = self.s[1:]
        else:  # opening from below: back towards the open end
            if above:
                return None
            grid = self.s[self.s < from_s][::-1]
        side = self.z[np.searchsorted(self.s, grid)] > z_m
        hit = np.flatnonzero(side != above)
        if hit.size == 0:
            return None
        k = int(hit[0])
        a, b = (from_s if k == 0 else float(grid[k - 1])), float(grid[k])
        while abs(b - a) > ARC_TOL_RAD:  # a: on the start's side, b: past the crossing
            m = 0.5 * (a + b)
            if (self.tip(m)[2] > z_m) == above:
                a = m
            else:
                b = m
        return b
