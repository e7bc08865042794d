"""How far apart two hands on one rail must keep their carriages, and which keys then
stay in reach of each (``play --hands 2``: ``planner.play.twohands``).

The left hand's carriage stays left of the right one's (one rail, two carriages:
``docs/user/two-hands.md``). Every body of one hand must stay ``CLEARANCE_M`` from every
body of the other. The rule here is one number per pair, the **rail gap**: the rails at
least ``rail_gap_m`` apart at every instant, where the gap is each hand's widest reach
towards the other (``inner_extent_m``: over every pose the play planner puts the hand
in, the farthest point of any collision body from its rail on the other hand's side)
plus the clearance. Then no body of one hand is ever within the clearance of the other
in x alone, whatever the two hands' postures, heights and reach axes: a guarantee by
construction that costs no test of the bodies at planning time. Its price: two hands
whose fingers could interleave at different heights are kept a thumb's width further
apart than the bodies need. The default hand: its index finger reaches 106 mm inside the
rail; its thumb, which presses no key, tucked under the palm for two hands
(``IdleFingers.narrow``) 64 mm (tucked as one hand tucks it, 122 mm).

``reach`` gives, per hand, how far from its rail its fingers press keys (key centre x
minus rail, over every finger's atlas entries): so two notes sounding at once, the left
one at ``x_l`` and the right one at ``x_r``, can be played apart only when
``x_r - x_l >= key_gap_m`` (the rails ``rail_gap_m`` apart, each finger at its farthest
reach towards the other).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from planner.check.criteria import HANDS_GAP_M
from planner.check.kinematics import Kinematics
from planner.hand.bodies import body_links, collision_bodies, place
from planner.play.atlas import SPAN_M, STEP_M
from planner.play.places import Places

CLEARANCE_M = HANDS_GAP_M  # every body of one hand this far from every body of the other
# (10 mm: the check's rule, twice the rig's stop margin; docs/user/two-hands.md)


@dataclass(frozen=True)
class HandReach:
    """One hand's lateral reach: ``inner_extent_m``, how far its bodies reach from its
    rail towards the other hand (positive, m); ``key_lo_m``/``key_hi_m``: the lowest and
    highest key centre x its fingers press, minus its rail."""

    side: str
    inner_extent_m: float
    key_lo_m: float
    key_hi_m: float


@dataclass(frozen=True)
class HandGap:
    """The pair's rule (module docstring): the rails at least ``rail_gap_m`` apart (the
    left one lower), so two notes at once at least ``key_gap_m`` apart (key centres)."""

    left: HandReach
    right: HandReach
    clearance_m: float = CLEARANCE_M

    @property
    def rail_gap_m(self) -> float:
        return self.left.inner_extent_m + self.right.inner_extent_m + self.clearance_m

    @property
    def key_gap_m(self) -> float:
        return self.rail_gap_m + self.right.key_lo_m - self.left.key_hi_m


def hand_poses(places: Places) -> np.ndarray:
    """Every pose the play planner puts the hand in while it plays, the rail at 0: per
    posture the natural hand with its idle fingers tucked, and every atlas entry's four
    poses (press, rise, hover, high) so (couplings applied). (At rest the idle fingers
    are natural; they tuck while the carriage runs from its end of the rail to its first
    place, where it arrives with them tucked: ``planner.play.rest``.)"""
    h = places.hand
    Q = []
    n = round(SPAN_M / STEP_M)
    for at in places.atlases:
        tucked = places.idle.tuck(at.base)
        Q.append(tucked)
        for f in h.fingers:
            for pc in range(12):
                for k in range(-n, n + 1):
                    e = at.entry_at(f, pc, k)
                    if e is not None:
                        Q += [at.full_q(e, pose, 0.0, tucked)
                              for pose in ("press", "rise", "hover", "high")]
    return h.apply_couplings(np.array(Q))


def hand_reach(places: Places) -> HandReach:
    """The hand's ``HandReach`` over ``hand_poses`` (its bodies placed by the check's own
    kinematics; the rail at 0, so a point's x is its distance from the rail)."""
    h = places.hand
    bodies = collision_bodies(h.spec)
    kin = Kinematics(h, h.T_world_root)
    Q = hand_poses(places)
    P = place(bodies, kin.link_poses(Q, body_links(bodies)))
    r = P.radius_m
    half = np.einsum("tbk,bk->tb", np.abs(P.axes[:, :, 0, :]), P.half_m)  # (boxes' x extent)
    lo = min(float((np.minimum(P.a[..., 0], P.b[..., 0]) - r).min(initial=np.inf)),
             float((P.centre[..., 0] - half).min(initial=np.inf)))
    hi = max(float((np.maximum(P.a[..., 0], P.b[..., 0]) + r).max(initial=-np.inf)),
             float((P.centre[..., 0] + half).max(initial=-np.inf)))
    n = round(SPAN_M / STEP_M)
    dx = [places.natural_dx[f] + k * STEP_M for at in places.atlases for f in h.fingers
          for pc in range(12) for k in range(-n, n + 1) if at.entry_at(f, pc, k) is not None]
    if not dx:
        raise ValueError(f"{h.name}: no finger presses any key")
    inner = -lo if h.side == "right" else hi
    return HandReach(h.side, inner, min(dx), max(dx))


def hand_gap(left: Places, right: Places, clearance_m: float = CLEARANCE_M) -> HandGap:
    """The pair's ``HandGap``: the left hand's reach, the right hand's."""
    return HandGap(hand_reach(left), hand_reach(right), clearance_m)
