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

POSES = ("press", "rise", "hover", "high")  # an atlas entry's poses (``AtlasEntry``): a
# place's, as the planner puts the finger over its key
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


def place_poses(places: Places) -> tuple[list[tuple[int, str, int, int]], np.ndarray]:
    """Every place a finger presses a key from, as its atlas entry's key (posture, finger,
    pitch class, grid index), and its four poses (``POSES``; ``Atlas.full_q``'s, the idle
    fingers tucked, the rail at 0, couplings applied), four rows per place in the keys'
    order: a finger's entries of a posture at once."""
    h = places.hand
    n = round(SPAN_M / STEP_M)
    keys, blocks = [], []
    for p, at in enumerate(places.atlases):
        tucked = places.idle.tuck(at.base)
        for f in h.fingers:
            got = [(pc, k, at.entry_at(f, pc, k)) for pc in range(12) for k in range(-n, n + 1)]
            got = [g for g in got if g[2] is not None]
            if not got:
                continue
            B = np.repeat(tucked[None, :], len(POSES) * len(got), axis=0)
            if at.rail is not None:
                B[:, at.rail] = 0.0
            B[:, h.joint_slice(f)] = [getattr(e, pose) for _, _, e in got for pose in POSES]
            blocks.append(h.apply_couplings(B))
            keys += [(p, f, pc, k) for pc, k, _ in got]
    return keys, (np.concatenate(blocks) if blocks else np.zeros((0, len(h.joint_names))))


def hand_poses(places: Places) -> np.ndarray:
    """Every pose the play planner puts the hand in while it plays, the rail at 0: per
    posture the natural hand with its idle fingers tucked, and every atlas entry's four
    poses (press, rise, hover, high) so (couplings applied). (At rest the idle fingers
    are natural; they tuck while the carriage runs from its end of the rail to its first
    place, where it arrives with them tucked: ``planner.play.rest``.)"""
    return pose_set(places)[0]


def pose_set(places: Places) -> tuple[np.ndarray, list[tuple[int, str, int, int]]]:
    """``hand_poses`` (the tucked natural hands first, then ``place_poses``' rows) and the
    places' keys (``place_poses``): place ``j``'s four poses are rows ``B + 4 j`` to
    ``B + 4 j + 3``, ``B`` the postures' count."""
    h = places.hand
    keys, Q = place_poses(places)
    tucked = [places.idle.tuck(at.base) for at in places.atlases]
    return h.apply_couplings(np.concatenate([np.array(tucked).reshape(len(tucked), -1), Q])
                             if len(tucked) else Q), keys


@dataclass(frozen=True)
class PoseExtents:
    """A hand's ``hand_poses`` measured once, shared by its ``HandReach`` (``hand_reach``)
    and its places' own reach (``planner.play.handclear.PlaceReach``): per distinct pose
    its bodies' lowest and highest x (``InnerEdge.extents_m``, the rail at 0: each row is
    measured alone, so a pose's numbers are the same in any set), ``places``' keys
    (``place_poses``) and per place its four poses' rows in the distinct poses
    (``rows``, shape (places, 4))."""

    lo_m: np.ndarray
    hi_m: np.ndarray
    keys: tuple[tuple[int, str, int, int], ...]
    rows: np.ndarray

    def inner_m(self, side: str) -> np.ndarray:
        """Per distinct pose, its bodies' farthest reach towards the other hand
        (``InnerEdge.inner_m``'s: below the rail for a right hand, above for a left one)."""
        return -self.lo_m if side == "right" else self.hi_m


def pose_extents(places: Places, edge: InnerEdge | None = None) -> PoseExtents:
    """``places``' ``PoseExtents`` (``edge``: the hand's ``InnerEdge``, built when None)."""
    Q, keys = pose_set(places)
    uniq, inv = np.unique(Q, axis=0, return_inverse=True)  # (the same poses once: 2798
    # of 16091 rows on the default hand)
    lo, hi = (edge or InnerEdge(places.hand)).extents_m(uniq)
    b = len(Q) - len(POSES) * len(keys)  # (the tucked natural hands first)
    return PoseExtents(lo, hi, tuple(keys), np.ravel(inv)[b:].reshape(len(keys), len(POSES)))


class InnerEdge:
    """How far a hand's bodies reach from its rail towards the other hand, pose by pose
    (the check's own bodies and kinematics, the rail at 0): ``inner_m(Q)``, per row of
    joints ``Q``, positive towards the other hand. ``HandReach.inner_extent_m`` is its
    most over every pose the planner plays in; a plan's rows reach less most of the time
    (the default hand's first-planned rows on the two-hand corpus: a median 67-77 mm
    against the 97 mm most), so the hand planned second keeps its clearance from the
    first one's bodies as they are, row by row (``planner.play.twohands``)."""

    def __init__(self, hand) -> None:
        self.hand = hand
        self.bodies = collision_bodies(hand.spec)
        self.kin = Kinematics(hand, hand.T_world_root)
        self.links = body_links(self.bodies)
        self.rail = hand.index.get("rail")

    def extents_m(self, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Per row of ``Q`` (the rail set to 0), the lowest and highest x of any body."""
        Q = np.array(Q, dtype=float)
        if self.rail is not None:
            Q[:, self.rail] = 0.0
        P = place(self.bodies, self.kin.link_poses(Q, self.links))
        r = P.radius_m
        half = np.einsum("tbk,bk->tb", np.abs(P.axes[:, :, 0, :]), P.half_m)  # (boxes' x)
        inf = np.full(len(Q), np.inf)
        lo = np.minimum((np.minimum(P.a[..., 0], P.b[..., 0]) - r).min(axis=1, initial=np.inf),
                        (P.centre[..., 0] - half).min(axis=1, initial=np.inf)) if len(Q) else inf
        hi = np.maximum((np.maximum(P.a[..., 0], P.b[..., 0]) + r).max(axis=1, initial=-np.inf),
                        (P.centre[..., 0] + half).max(axis=1, initial=-np.inf)) if len(Q) else -inf
        return lo, hi

    def inner_m(self, Q: np.ndarray, block: int = 2048) -> np.ndarray:
        """Per row of ``Q``, the bodies' farthest reach from the rail towards the other
        hand (below the rail for a right hand, above it for a left one), in blocks of
        ``block`` rows."""
        out = []
        for a in range(0, len(Q), block):
            lo, hi = self.extents_m(Q[a:a + block])
            out.append(-lo if self.hand.side == "right" else hi)
        return np.concatenate(out) if out else np.zeros(0)


def hand_reach(places: Places, ext: PoseExtents | None = None) -> HandReach:
    """The hand's ``HandReach`` over ``hand_poses`` (``InnerEdge``'s bodies; the rail at
    0, so a point's x is its distance from the rail); ``ext``: its ``pose_extents``
    (found when None)."""
    h = places.hand
    ext = ext or pose_extents(places)
    n = round(SPAN_M / STEP_M)
    dx = [places.natural_dx[f] + k * STEP_M for at in places.atlases for f in h.fingers
          for pc in range(12) for k in range(-n, n + 1) if at.entry_at(f, pc, k) is not None]
    if not dx:
        raise ValueError(f"{h.name}: no finger presses any key")
    inner = -float(ext.lo_m.min()) if h.side == "right" else float(ext.hi_m.max())
    return HandReach(h.side, inner, min(dx), max(dx))


def hand_gap(left: Places, right: Places, clearance_m: float = CLEARANCE_M,
             extents: tuple[PoseExtents, PoseExtents] | None = None) -> HandGap:
    """The pair's ``HandGap``: the left hand's reach, the right hand's (``extents``: each
    hand's ``pose_extents``, found when None)."""
    el, er = extents or (None, None)
    return HandGap(hand_reach(left, el), hand_reach(right, er), clearance_m)
