"""A finger's body against the keys: its segments and pad, the hand's collision bodies.

The spec's point rule and the atlas's tip clearance are about a fingertip point; a
finger is a body (``planner.hand.bodies``, the one definition the URDF, the physics
replay and ``check``'s body rule read: each segment a slab of two capsules as wide as
the seed's finger, the distal one ending in the pad sphere whose bottom is the pad
point). A 1.5x hand's finger end (21.4 mm wide, 17.1 mm thick on the default hand) does
not fit between two black keys (13.5 mm of white key there), and a curled distal
segment's sphere reaches below its pad point. ``FingerBodies`` places a finger's
capsules and pad as sampled sphere-swept points and measures how deep they enter the
replay's physical keys (``planner.simulate.keyboard``: a white key's front and back
boxes, a black key's box; ``planner.music.keybodies.box_penetration``): the planner's
clearance (``clear``), the plan's bodies in ``planner.simulate.planbody``, and the
catch's bodies against the ball. ``check``'s body rule (``planner.check.bodykeys``)
judges the same shapes against the keys' footprints, exactly.

Tolerances (each a physical value with its source):

* ``OTHER_KEY_TOLERANCE_M`` 0.5 mm: a key the body touches by that much is pushed down
  0.5 mm at most, a tenth of the spec's 5 mm key-down depth (it does not sound); it is
  also the atlas's grid (``STEP_M / 2``: where a tip lands at most off its sample).
* Spec section 2's own rule, judged as ``check`` judges it: no body reaches the key-down
  depth (5 mm) inside another key's footprint column
  (``planner.music.keybodies.sphere_depths``), the column grown by
  ``OTHER_KEY_TOLERANCE_M`` on every side (the rail lands up to half the atlas's grid
  step off the pose's sample). A body beside a black key's wall, below its top, touches
  the key's box by a fraction of a millimetre from the side but lies inside its
  footprint column deeper than the key-down depth: a wrong key by the rule.
* ``OWN_BED_MARGIN_M`` 1 mm: the pressed key's bed is 10 mm down (spec: key dip); spec
  section 2 (bodies) allows no body more than 1 mm past it (``check``'s
  ``criteria.BED_MARGIN_M``, the one definition): a body reaching further would be held
  up by the bed before its pad point is down.

The knuckles' small boxes and the palm are not tested here (they are far above the keys
in every play pose); ``check``'s body rule judges them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from planner.check.criteria import BED_MARGIN_M, BODY_BED_DEPTH_M, DOWN_DEPTH_M
from planner.hand.bodies import BOX, SPHERE, collision_bodies
from planner.hand.chain import FrameChain
from planner.hand.model import HandModel
from planner.music import keyboard as kb
from planner.music.keybodies import box_penetration, footprints, key_depths
from planner.play.fingerchain import FingerChain
from planner.play.halving import all_along, max_along, min_along, sum3
from planner.simulate.keyboard import key_bodies

OTHER_KEY_TOLERANCE_M = 0.0005  # see the module docstring
OWN_BED_MARGIN_M = BED_MARGIN_M  # 1 mm: spec section 2 (bodies), check's own rule
AXIS_SAMPLES = 9  # a capsule's axis is tested at this many points (its ends included)
MANY_CHUNK = 2048  # configurations tested at once by ``clear_many`` (bounded memory)


@dataclass(frozen=True)
class FingerShapes:
    """One finger's pad sphere and capsules (a sphere: both ends equal), pad first, each
    in its link's frame."""

    frames: tuple[int, ...]  # Pinocchio frame ids
    p0: np.ndarray  # (k, 3) link frame, m
    p1: np.ndarray  # (k, 3)
    radius_m: np.ndarray  # (k,)
    n_points: tuple[int, ...]  # each shape's axis points: 1 (a sphere) or AXIS_SAMPLES


class FingerBodies:
    """Every finger's shapes of one hand and the keys' boxes (see the module docstring)."""

    def __init__(self, hand: HandModel) -> None:
        self.hand = hand
        self.shapes: dict[str, FingerShapes] = {}
        shapes = [b for b in collision_bodies(hand.spec) if b.kind != BOX and b.finger]
        for f in hand.fingers:
            mine = sorted((b for b in shapes if b.finger == f), key=lambda b: b.kind != SPHERE)
            self.shapes[f] = FingerShapes(
                tuple(hand.pin_model.getFrameId(b.link) for b in mine),
                np.array([b.p0_m for b in mine]), np.array([b.p1_m for b in mine]),
                np.array([b.radius_m for b in mine]),
                tuple(1 if b.p0_m == b.p1_m else AXIS_SAMPLES for b in mine))
        boxes = [(k.pitch, b) for k in key_bodies() for b in k.boxes]
        self.box_pitch = np.array([p for p, _ in boxes])
        self._pressed: dict[int | None, tuple[np.ndarray, ...]] = {}
        c = np.array([b.center_m for _, b in boxes])
        h = np.array([b.half_m for _, b in boxes])
        self.box_lo, self.box_hi = c - h, c + h
        self._t = np.linspace(0.0, 1.0, AXIS_SAMPLES)[:, None]
        self._chains: dict[str, list[FrameChain]] = {}  # per finger, per shape (``points_many``)
        self._tips: dict[str, FrameChain] = {}  # (``tip_chain``)
        self._fingers: dict[str, FingerChain | None] = {}  # (``points_many``; None: its
        # links are not one chain)

    def points(self, q: np.ndarray, finger: str, update: bool = True
               ) -> tuple[np.ndarray, np.ndarray]:
        """The finger's shapes at ``q`` as sampled axis points (world, (m, 3)) and each
        point's radius (m,); ``update`` False: the hand's kinematics are at ``q`` already
        (another finger's call at the same ``q`` just before)."""
        h, s = self.hand, self.shapes[finger]
        if update:
            h.update_frames(q)
        R, t = h.T_world_root[:3, :3], h.T_world_root[:3, 3]
        pts, rad = [], []
        for fid, a, b, r, n in zip(s.frames, s.p0, s.p1, s.radius_m, s.n_points):
            M = h.pin_data.oMf[fid]
            wa = R @ (M.rotation @ a + M.translation) + t
            wb = R @ (M.rotation @ b + M.translation) + t
            pts.append(wa + self._t[:n] * (wb - wa))
            rad.append(np.full(n, r))
        return np.concatenate(pts), np.concatenate(rad)

    def tip_chain(self, finger: str) -> FrameChain:
        """The finger's tip frame as a ``FrameChain`` (made once)."""
        got = self._tips.get(finger)
        if got is None:
            got = self._tips[finger] = FrameChain(self.hand, f"{finger}_tip")
        return got

    def radii(self, finger: str) -> np.ndarray:
        """The radius of each of ``points``' points (m,)."""
        s = self.shapes[finger]
        return np.repeat(s.radius_m, s.n_points)

    def points_many(self, Q: np.ndarray, finger: str) -> np.ndarray:
        """``points`` at each of the configurations ``Q`` (K, n) at once (world, (K, m, 3);
        the radii are ``points``'): the shapes' ends carried by ``FrameChain``, the same
        rigid transforms as Pinocchio's to rounding (``tests/test_fingerbody.py``); a
        finger whose links are one chain, all of them in one pass (``FingerChain``, the
        same numbers to the bit: ``tests/test_fingerchain.py``)."""
        s = self.shapes[finger]
        one = self._fingers.get(finger, False)
        if one is False:
            try:
                one = FingerChain(self.hand, s, finger, AXIS_SAMPLES)
            except ValueError:
                one = None
            self._fingers[finger] = one
        if one is not None:
            return one.carry(Q)[1]
        chains = self._chains.get(finger)
        if chains is None:
            names = self.hand.pin_model.frames
            chains = self._chains[finger] = [FrameChain(self.hand, names[fid].name)
                                             for fid in s.frames]
        pts = []
        for ch, a, b, n in zip(chains, s.p0, s.p1, s.n_points):
            w = ch.points(Q, np.stack([a, b]))
            wa, wb = w[:, :1], w[:, 1:]
            pts.append(wa + self._t[None, :n] * (wb - wa))
        return np.concatenate(pts, axis=1)

    def penetration(self, q: np.ndarray, finger: str, own_pitch: int | None,
                    update: bool = True) -> np.ndarray:
        """How deep (m) the finger's body reaches into each key box (keys at rest; key
        ``own_pitch`` pressed to its bed), (boxes,); <= 0 where it is clear."""
        return self.box_depths(*self.points(q, finger, update), own_pitch)

    def box_depths(self, p: np.ndarray, r: np.ndarray, own_pitch: int | None) -> np.ndarray:
        """``penetration`` of sphere-swept points ``p`` (m, 3), radii ``r`` (m,)."""
        lo, hi = self.box_lo, self.box_hi
        if own_pitch is not None:
            own = self.box_pitch == own_pitch
            lo, hi = lo.copy(), hi.copy()
            lo[own, 2] -= kb.KEY_DIP_M
            hi[own, 2] -= kb.KEY_DIP_M
        return box_penetration(p, r, lo, hi)

    def clear(self, q: np.ndarray, finger: str, own_pitch: int | None) -> bool:
        """True when the finger's body at ``q`` is clear of the keys (``clear_points``)."""
        return self.clear_points(*self.points(q, finger), own_pitch)

    def clear_points(self, p: np.ndarray, r: np.ndarray, own_pitch: int | None) -> bool:
        """True when sphere-swept points ``p`` (m, 3), radii ``r`` (m,) are clear of the
        keys (``clear_many`` of one configuration)."""
        return bool(self.clear_many(p[None], r, own_pitch)[0][0])

    def clear_many(self, P: np.ndarray, r: np.ndarray, own_pitch: int | None
                   ) -> tuple[np.ndarray, np.ndarray]:
        """Whether each configuration's sphere-swept points ``P`` (K, m, 3), radii ``r``
        (m,), reach no key but ``own_pitch`` by more than ``OTHER_KEY_TOLERANCE_M`` nor
        ``DOWN_DEPTH_M`` deep in its footprint grown by ``OTHER_KEY_TOLERANCE_M``, and
        their own key (pressed) by at most ``OWN_BED_MARGIN_M`` (the box pressed to its
        bed; in the footprint, ``check``'s ``BODY_BED_DEPTH_M``); and how deep each
        reaches inside ``own_pitch``'s footprint column (-inf where it does not enter it,
        or without ``own_pitch``): ((K,) bool, (K,) m). Only the boxes and footprints
        that the points' bounding box reaches are measured (the others are clear)."""
        ok, own_depth = np.empty(len(P), dtype=bool), np.empty(len(P))
        for lo_i in range(0, len(P), MANY_CHUNK):
            sl = slice(lo_i, lo_i + MANY_CHUNK)
            ok[sl], own_depth[sl] = self._clear_chunk(P[sl], r, own_pitch)
        return ok, own_depth

    def pressed_boxes(self, pitch: int | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The keys' boxes with key ``pitch``'s pressed to its bed, and which are its:
        (own (B,) bool, lo (B, 3), hi (B, 3)), made once per key."""
        return self._pressed_boxes(pitch)[:3]

    def _pressed_boxes(self, pitch: int | None) -> tuple[np.ndarray, ...]:
        """``pressed_boxes`` and each box's allowed penetration (``boxes_clear``'s: the
        pressed key's ``OWN_BED_MARGIN_M``, another's ``OTHER_KEY_TOLERANCE_M``)."""
        got = self._pressed.get(pitch)
        if got is None:
            own = self.box_pitch == pitch
            lo, hi = self.box_lo.copy(), self.box_hi.copy()
            lo[own, 2] -= kb.KEY_DIP_M
            hi[own, 2] -= kb.KEY_DIP_M
            allowed = np.where(own, OWN_BED_MARGIN_M, OTHER_KEY_TOLERANCE_M)
            got = self._pressed[pitch] = (own, lo, hi, allowed)
        return got

    def boxes_clear(self, P: np.ndarray, r: np.ndarray, own_pitch: int | None
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Whether each configuration's points ``P`` (K, m, 3), radii ``r`` (m,), reach
        no other key's box by more than ``OTHER_KEY_TOLERANCE_M`` and the pressed key's
        (``own_pitch``, at its bed) by no more than ``OWN_BED_MARGIN_M``: (ok (K,) bool,
        and the points' bounds grown by the largest radius and the tolerance, lo and hi
        (3,))."""
        reach = float(r.max()) + OTHER_KEY_TOLERANCE_M
        flat = P.reshape(-1, 3)
        p_lo, p_hi = min_along(flat, 0) - reach, max_along(flat, 0) + reach
        _, lo, hi, allowed = self._pressed_boxes(own_pitch)
        near = all_along((lo <= p_hi) & (hi >= p_lo), 1)
        pen = many_box_penetration(P, r, lo[near], hi[near])  # (K, boxes near)
        return all_along(pen <= allowed[near], 1), p_lo, p_hi

    def _clear_chunk(self, P: np.ndarray, r: np.ndarray, own_pitch: int | None
                     ) -> tuple[np.ndarray, np.ndarray]:
        ok, p_lo, p_hi = self.boxes_clear(P, r, own_pitch)
        fp = footprints()
        near = np.all((fp.lo <= p_hi[:2]) & (fp.hi >= p_lo[:2]), axis=1)
        others = sorted({int(k) + kb.LOWEST_PITCH for k in fp.key[near]} - {own_pitch})
        if others:
            ok &= np.all(key_depths(P, r, others, OTHER_KEY_TOLERANCE_M) < DOWN_DEPTH_M, axis=1)
        own_depth = np.full(len(P), -np.inf)
        if own_pitch is not None:
            own_depth = key_depths(P, r, [own_pitch])[:, 0]
            ok &= own_depth <= BODY_BED_DEPTH_M
        return ok, own_depth


def many_box_penetration(P: np.ndarray, r: np.ndarray, lo: np.ndarray, hi: np.ndarray
                         ) -> np.ndarray:
    """``keybodies.box_penetration`` of many configurations' points ``P`` (K, m, 3), radii
    ``r`` (m,), boxes [lo, hi] (B, 3): (K, B), the same numbers (its sum of three
    squares in numpy's order, its maximum by halving: ``planner.play.halving``)."""
    d = np.maximum(np.maximum(lo - P[..., None, :], P[..., None, :] - hi), 0.0)
    dist = np.sqrt(sum3(d * d))  # (K, m, B); 0 inside
    return max_along(r[:, None] - dist, 1)
