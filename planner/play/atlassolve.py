"""How one atlas entry is solved (``planner.play.atlas``' ``Atlas`` is built on
``EntrySolver``): a finger's four poses over a key by single-finger IK (or along its arc),
within the planning limits, the tip's straight moves between them clear of the other keys
and, with a ``[play]`` posture, the finger's bodies too (``planner.play.fingerbody``); and
the largest key force the motors hold at the press.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from planner.hand.model import HandModel
from planner.ik import (
    PREPARE_HEIGHT_M,
    IKResult,
    PressTarget,
    press_target,
    press_x_range,
    surfaces_under,
)
from planner.music import keyboard as kb
from planner.music.keybodies import key_depths
from planner.play.fingerbody import OTHER_KEY_TOLERANCE_M, OWN_BED_MARGIN_M, FingerBodies
from planner.play.force import descent_poses, held_force_n, press_capacity_n
from planner.play.planar import planar_press_target

STEP_M = 0.001  # the atlas samples dx this often
PAD_CENTRE_TOL_M = 1e-4  # a press the body rule refuses is tried again with the pad
# sphere's centre over the press point where it lies further aside than this (``_solve``),
PAD_CENTRE_ITERATIONS = 3  # ... at most this often (the sphere moves with the pad point
# but for the finger's change of pose: each try brings its centre nearer)
HIGH_Z_M = kb.BLACK_TOP_Z_M + 0.0075  # a finger moving sideways keeps its tip this high
PRESS_DEPTH_ITERATIONS = 3  # ``Atlas._press``: the pad's depth found again from the body's
REPEAT_DEPTH_M = kb.DOWN_DEPTH_M - 0.002  # a repeated key rises to this depth (see above)
CLEARANCE_M = 0.001  # a tip passing over a key it does not press stays this far above it
TIP_RADIUS_M = 0.002  # ... counting the pad's size (a key's footprint grows by this)
PATH_SAMPLES = 12  # a straight move is checked at this many points
BODY_SAMPLES = 5  # ... and its finger's body at this many (each a forward kinematics of
# every segment: the ends and every quarter, so that a curl between two clear ends shows)


@dataclass(frozen=True, eq=False)  # (entries are made once and compared by identity)
class AtlasEntry:
    """One finger over one key at one ``dx`` (key centre x - rail): its joints (in
    ``hand.joint_slice(finger)`` order) pressing, waiting and crossing high."""

    finger: str
    pitch_class: int
    dx_m: float
    press: np.ndarray
    rise: np.ndarray
    hover: np.ndarray
    high: np.ndarray
    max_force_n: float
    posture: int = 0  # which of the hand's play postures (``Atlas.posture_index``)


class Refusal(enum.Enum):
    """Why an atlas sample has no entry (``EntrySolver._verdict``; ``EntrySolver.refusal``
    measures it), in the order the rules are tried: the first three leave nothing for the
    body rule to judge, the last two are the body rule's (a note only they leave without a
    finger is left out for its bodies: ``body``)."""

    REACH = "reach"  # no pose: the IK puts the tip on the key's press point, or straight
    # above it at the rise, hover or crossing height, no nearer than its tolerance (a
    # one-DOF finger: its arc comes down off the part of the key it presses)
    LIMITS = "limits"  # a pose outside the planning limits (hard stops less their margins)
    TIP_PATH = "tip_path"  # the tip's straight move between two poses passes through
    # another key (``path_clear``)
    PAD_UP = "pad_up"  # the press made with the back of the finger (``_pad_faces_key``)
    BODY = "body"  # a body reaches another key or past its own key's bed, at a pose or
    # along a move (``bodies_clear``)


BODY_REFUSALS = frozenset({Refusal.PAD_UP, Refusal.BODY})


class SampleVerdict(NamedTuple):
    """One atlas sample judged again (``EntrySolver.refusal``): why it has no entry (None:
    it has one) and, where a press pose was found, how its bodies lie there: the deepest
    any body reaches below another key's top inside that key's footprint column (grown by
    the body rule's tolerance; a key sounds from the key-down depth, 5 mm), the deepest
    into another key's box at rest (the rule allows 0.5 mm), the deepest below its own
    key's top inside its column (the bed is 10 mm down, the rule allows 11 mm), how far
    the pad point lies beside the pad sphere's centre along x, and the first depth again
    with the pad point moved by that much (the sphere's centre over the press point;
    ``_pad_off_centre_m``); m, nan without a press pose."""

    refusal: Refusal | None
    other_column_m: float
    other_box_m: float
    own_column_m: float
    pad_offset_m: float
    centred_column_m: float


class Tried(NamedTuple):
    """A sample's poses as ``EntrySolver._tried`` leaves them: the key they are solved on,
    the poses (press, rise, hover, high; the last tried where none passes; None: no pose)
    and why they make no entry (None: they make one)."""

    pitch: int
    poses: list[np.ndarray] | None
    refusal: Refusal | None


class Press(NamedTuple):
    """A press pose's IK target and result (``Atlas._press``)."""

    target: PressTarget
    result: IKResult


class EntrySolver:
    """The solving of ``Atlas``' entries (its base: it reads the atlas's hand, IK,
    natural hand, bodies and grid)."""

    def _solve(self, finger: str, pitch_class: int, k: int) -> AtlasEntry | None:
        tried = self._tried(finger, pitch_class, k)
        if tried is None:
            return None
        pitch, poses, refusal = tried
        if refusal in BODY_REFUSALS:
            self._body_refused.add((finger, pitch_class, k))
        if refusal is not None:
            return None
        h = self.hand
        js = h.joint_slice(finger)
        return AtlasEntry(finger, pitch_class, self.natural_dx[finger] + k * STEP_M,
                          *(q[js].copy() for q in poses),
                          press_capacity_n(h, descent_poses(h, poses[2], poses[0]), finger, pitch),
                          self.posture_index)

    def _tried(self, finger: str, pitch_class: int, k: int) -> Tried | None:
        """A sample's poses (the pad's body centred on the key where the body rule refused
        the first) and why they make no entry (``Tried``); None where the sample has no
        key or the rail cannot go there."""
        h = self.hand
        pitch = self._solved_on(finger, pitch_class, k)
        if pitch is None:
            return None
        rail = self.rail_for(finger, pitch, k)
        base = self.base.copy()
        if self.rail is not None:
            if not h.plan_lower[self.rail] <= rail <= h.plan_upper[self.rail]:
                return None
            base[self.rail] = rail
        arc = finger in self.arc_joint
        poses = (self._arc_poses(finger, pitch, rail) if arc
                 else self._ik_poses(finger, pitch, base))
        verdict = self._verdict(finger, pitch, poses)
        shift, tried = 0.0, poses
        for _ in range(PAD_CENTRE_ITERATIONS):  # (the pad's body centred on the key)
            if verdict not in BODY_REFUSALS or arc or tried is None:
                break
            step = self._pad_off_centre_m(tried[0], finger)
            if abs(step) <= PAD_CENTRE_TOL_M:
                break
            shift += step
            tried = self._ik_poses(finger, pitch, base, shift)
            if self._verdict(finger, pitch, tried) is None:
                poses, verdict = tried, None
        return Tried(pitch, poses, verdict)

    def refusal(self, finger: str, pitch_class: int, k: int) -> SampleVerdict | None:
        """Sample ``k`` of ``finger`` over ``pitch_class`` solved again (neither read from
        the table nor kept) and judged: why it has no entry and where its bodies lie at its
        press pose, and at the press with the pad sphere's centre over the press point
        (``SampleVerdict``); None where the sample has no key or no rail place. A
        measurement (``bench/atlas_refusals.py``) by the entry's own steps."""
        tried = self._tried(finger, pitch_class, k)
        if tried is None:
            return None
        pitch, poses, refusal = tried
        nan = float("nan")
        if poses is None or self.bodies is None:
            return SampleVerdict(refusal, nan, nan, nan, nan, nan)
        column, box, own, offset = self._bodies_at(poses[0], finger, pitch)
        centred = nan
        if finger not in self.arc_joint:
            base = self.base.copy()
            if self.rail is not None:
                base[self.rail] = self.rail_for(finger, pitch, k)
            press = self._press(finger, pitch, base, offset)
            if press is not None:
                centred = self._bodies_at(press.result.q, finger, pitch)[0]
        return SampleVerdict(refusal, column, box, own, offset, centred)

    def _bodies_at(self, q: np.ndarray, finger: str, pitch: int
                   ) -> tuple[float, float, float, float]:
        """``SampleVerdict``'s depths at the press pose ``q`` and the pad's offset."""
        p, r = self.bodies.points(q, finger)
        others = [o for o in range(pitch - 4, pitch + 5)
                  if o != pitch and kb.LOWEST_PITCH <= o <= kb.HIGHEST_PITCH]
        column = key_depths(p[None], r, others, OTHER_KEY_TOLERANCE_M)[0]
        boxes = self.bodies.box_depths(p, r, pitch)[self.bodies.box_pitch != pitch]
        own = key_depths(p[None], r, [pitch])[0, 0]
        return (float(column.max()), float(boxes.max()), float(own),
                self._pad_off_centre_m(q, finger))

    def _verdict(self, finger: str, pitch: int, poses: list[np.ndarray] | None
                 ) -> Refusal | None:
        """Whether ``poses`` (press, rise, hover, high) make an entry (None) or why not:
        within the planning limits, the tip's moves between them clear of the other keys
        and, with the body rule, the pad facing the key and the finger's bodies clear all
        along them."""
        h = self.hand
        if poses is None:
            return Refusal.REACH
        if not all(h.within_plan_limits(q) for q in poses):
            return Refusal.LIMITS
        if self.bodies is not None and not self._pad_faces_key(poses[0], finger):
            return Refusal.PAD_UP
        for qa, qb in ((poses[3], poses[2]), (poses[2], poses[0]), (poses[3], poses[0]),
                       (poses[1], poses[0])):
            if not path_clear(h, qa, qb, finger, pitch):
                return Refusal.TIP_PATH
        for qa, qb in ((poses[3], poses[2]), (poses[2], poses[0]), (poses[3], poses[0]),
                       (poses[1], poses[0])):
            if self.bodies is not None and not bodies_clear(self.bodies, qa, qb, finger, pitch):
                return Refusal.BODY
        return None

    def _pad_off_centre_m(self, q: np.ndarray, finger: str) -> float:
        """How far (x, m) the press at ``q`` has its pad point beside the pad sphere's
        centre: an abducted finger's pad sphere lies to one side of its pad point, so a pad
        point on the key's centre puts the sphere's side into the next key (the index
        finger 17-27 mm off its natural place: the sphere's centre 1.7-2.5 mm aside, its
        8.6 mm radius reaching the neighbour's column; 0.5-1 mm further over clears it)."""
        p, _ = self.bodies.points(q, finger)  # (shape 0: the pad sphere, its centre)
        tip = self.hand.tip_positions(q)[self.hand.fingers.index(finger)]
        return float(tip[0] - p[0, 0])

    def _ik_poses(self, finger: str, pitch: int, base: np.ndarray,
                  shift_m: float = 0.0) -> list[np.ndarray] | None:
        """Press, rise, hover and high by single-finger IK: the tip on the key's press
        point (``shift_m`` along x from it, ``_press``), then straight above it at each
        height."""
        r = self._press(finger, pitch, base, shift_m)
        if r is None:
            return None
        target = r.target
        r = r.result
        tip = self.hand.tip_positions(r.q)[self.hand.fingers.index(finger)]
        top = kb.key(pitch).top_z_m
        # (with the body rule the key rises as far as the finger's body lets it: its
        # rise lifts the body, not only the pad point, to the repeat depth)
        below_tip = 0.0 if self.bodies is None else self._body_below_tip_m(r.q, finger, tip)
        poses = [r.q]
        for z in (top - REPEAT_DEPTH_M + below_tip, top + PREPARE_HEIGHT_M, HIGH_Z_M):
            self.solves += 1
            up = self.ik.solve_finger(
                PressTarget(finger, pitch, (float(tip[0]), float(tip[1]), z), target.y_range_m),
                poses[-1])
            if not up.converged:
                return None
            poses.append(up.q)
        return poses

    def _press(self, finger: str, pitch: int, base: np.ndarray,
               shift_m: float = 0.0) -> Press | None:
        """The press pose by single-finger IK: the pad point ``press_depth_m`` below the
        key's top; with the body rule, deeper where the finger's lowest body point would
        stop short of the key bed (a pad that is its finger's lowest point, on a black
        key: 6 mm down leaves the key 1 mm past the key-down depth, which a servo's
        tracking under the key's spring loses, 2-2.5 mm measured in physics), until its
        body reaches the bed (``KEY_DIP_M``; the pad no deeper than the dip); shallower
        where the press depth would put the lowest body past the bed by more than the
        bed's margin (``OWN_BED_MARGIN_M``, check's rule: a pad sphere of 5 mm below its
        pad point at the press depth of 6 mm reaches 11.1 mm, past the 11 mm allowed),
        until it is at the bed: the key is fully down either way (the bed stops it).
        ``shift_m``: the pad point that far along x from the press point (the pad's body
        centred on it, ``_solve``), kept inside the part of the key the finger presses
        (``press_x_range``, inset by the pad's radius); None outside it."""
        front = finger in self.front
        depth = self.press_depth_m
        if shift_m:
            x_lo, x_hi = press_x_range(finger, pitch, TIP_RADIUS_M, front)
            x = press_target(finger, pitch, depth, front).point_m[0] + shift_m
            if not x_lo <= x <= x_hi:
                return None
        for _ in range(PRESS_DEPTH_ITERATIONS):
            target = press_target(finger, pitch, depth, front)
            if shift_m:
                x, y, z = target.point_m
                target = PressTarget(finger, pitch, (x + shift_m, y, z), target.y_range_m)
            target = planar_press_target(self.hand, target, base, TIP_RADIUS_M, front)
            if target is None:
                return None
            self.solves += 1
            r = self.ik.solve_finger(target, base)
            if not r.converged:
                return None
            if self.bodies is None:
                break
            tip = self.hand.tip_positions(r.q)[self.hand.fingers.index(finger)]
            want = kb.KEY_DIP_M - self._body_below_tip_m(r.q, finger, tip)  # (<= the dip)
            if depth - OWN_BED_MARGIN_M + 1e-4 <= want <= depth + 1e-4:
                break  # (the body between the bed and its margin past it, 0.1 mm in)
            depth, base = want, r.q
        return Press(target, r)

    def _pad_faces_key(self, q: np.ndarray, finger: str) -> bool:
        """True when the press at ``q`` presses with the pad: the pad point (a point of
        the pad sphere's surface, ``planner.hand.bodies``) lies below the sphere's
        centre, so the pad's outward normal there points down, into the key. A press
        shallower than the press depth (the lowest body at the bed) could otherwise be
        made by the back of a finger whose pad faces up (the AGH hand's near pair at its
        play lean: the pad point 7.2 mm above the centre, 4.3 mm above the key's top,
        the key pressed by the distal segment; and at its waiting pose the key was down
        already)."""
        p, _ = self.bodies.points(q, finger)  # (shape 0: the pad sphere, its centre)
        tip = self.hand.tip_positions(q)[self.hand.fingers.index(finger)]
        return bool(p[0, 2] > tip[2])

    def _body_below_tip_m(self, q: np.ndarray, finger: str, tip: np.ndarray) -> float:
        """How far the finger's lowest body point lies below its pad point at ``q`` (m, >= 0)."""
        p, r = self.bodies.points(q, finger)
        return max(0.0, float(tip[2] - np.min(p[:, 2] - r)))

    def _arc_poses(self, finger: str, pitch: int, rail: float) -> list[np.ndarray] | None:
        """Press, rise, hover and high of a one-DOF finger on its arc
        (``planner.play.arc``): the press where flexing brings the tip down to full dip,
        which must be on the part of the key the finger presses (``press_x_range``, inset
        by the pad's radius, and the press target's y range); the others where opening
        from there brings it back up to each height."""
        arc = self._arcs[finger]
        top = kb.key(pitch).top_z_m
        s = [arc.descend(top - self.press_depth_m)]
        if s[0] is None:
            return None
        x, y, _ = arc.tip(s[0], rail)
        front = finger in self.front
        x_lo, x_hi = press_x_range(finger, pitch, TIP_RADIUS_M, front)
        y_lo, y_hi = press_target(finger, pitch, self.press_depth_m, front).y_range_m
        if not (x_lo <= x <= x_hi and y_lo <= y <= y_hi):
            return None
        for z in (top - REPEAT_DEPTH_M, top + PREPARE_HEIGHT_M, HIGH_Z_M):
            s.append(arc.ascend(z, s[-1]))
            if s[-1] is None:
                return None
        return [arc.q(si, rail) for si in s]


def path_clear(hand: HandModel, qa: np.ndarray, qb: np.ndarray, finger: str,
               own_pitch: int | None) -> bool:
    """True when ``finger``'s tip, on the straight joint-space move qa -> qb, stays
    ``CLEARANCE_M`` above every key it passes over (footprints grown by
    ``TIP_RADIUS_M``) except inside key ``own_pitch``'s footprint (shrunk by it), where
    it may press down to full dip."""
    f = hand.fingers.index(finger)
    s = np.linspace(0.0, 1.0, PATH_SAMPLES)
    tips = np.array([hand.tip_positions(hand.apply_couplings(qa + si * (qb - qa)))[f]
                     for si in s])
    x, y, z = tips[:, 0], tips[:, 1], tips[:, 2]
    over = surfaces_under(x, y, TIP_RADIUS_M)
    ok = z >= over + CLEARANCE_M
    if own_pitch is not None:
        k = kb.key(own_pitch)
        inside = ((k.x_min_m + TIP_RADIUS_M <= x) & (x <= k.x_max_m - TIP_RADIUS_M)
                  & (k.y_min_m + TIP_RADIUS_M <= y) & (y <= k.y_max_m - TIP_RADIUS_M)
                  & (z >= k.top_z_m - kb.KEY_DIP_M - 1e-4))
        if k.black is False:  # a white key's footprint stops at the black keys beside it
            inside &= surfaces_under(x, y, TIP_RADIUS_M) <= k.top_z_m
        ok |= inside
    return bool(ok.all())


def bodies_clear(bodies: FingerBodies, qa: np.ndarray, qb: np.ndarray, finger: str,
                 own_pitch: int) -> bool:
    """True when ``finger``'s body (``planner.play.fingerbody``: the collision bodies of
    spec section 3) is clear of the keys all along the straight joint-space move qa -> qb
    (``BODY_SAMPLES`` points, both ends included): no other key reached by more than
    ``OTHER_KEY_TOLERANCE_M``, its own key (pressed) by at most ``OWN_BED_MARGIN_M``."""
    return all(bodies.clear(bodies.hand.apply_couplings(qa + si * (qb - qa)), finger, own_pitch)
               for si in np.linspace(0.0, 1.0, BODY_SAMPLES))


def max_key_force_n(hand: HandModel, q: np.ndarray, finger: str) -> float:
    """The largest upward key force (N) on ``finger``'s tip that every motor holds at
    ``q`` with gravity (``planner.play.force.held_force_n`` with a vertical push)."""
    return held_force_n(hand, q, finger)
