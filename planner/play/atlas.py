"""The hand atlas: where each finger's joints go to press, wait above and cross over a
key, for every place of the key relative to the hand.

The arm holds one posture (the natural hovering hand, ``base``); the rail carries it
along the keyboard (x), so a finger's configuration over a key depends only on the key's
pitch class and on ``dx`` = the key's centre minus the rail. The atlas samples ``dx``
every ``STEP_M`` around each finger's natural place and solves, by single-finger IK
(placo, through ``planner.ik``), four poses per sample:

* ``press``: the tip at the key's press point at full dip (``planner.ik.press_target``);
* ``rise``: straight above it, ``REPEAT_DEPTH_M`` below the key's top: the key has come
  up past the key-down depth (spec: 5 mm) by 2 mm, 70 % of its dip back, where a key
  action is ready to strike again (a piano's repetition lever re-arms at about half the
  dip), so a finger repeating a note goes no higher;
* ``hover``: straight above that point, ``PREPARE_HEIGHT_M`` over the key's top (a finger
  about to press waits there: the spec's 5 mm, plus 0.5 mm);
* ``high``: straight above it at ``HIGH_Z_M`` (7.5 mm above the black keys' tops), from
  where the finger moves sideways over any key.

A finger of one degree of freedom (one independent joint: the Mk5's) has the same four
poses at the same heights, found on its tip's one arc instead (``planner.play.arc``):
the press where flexing brings the tip to full dip, on the part of the key it presses,
the others where opening brings it back up (not straight above: it cannot hold x, y).

An entry is kept when the four converge (1 mm), every joint is within its planning limits
(its hard stops less its stop margin: ``HandModel.plan_lower``, ``plan_upper``), and
the straight joint-space moves high -> hover -> press, high -> press and rise -> press
keep the tip clear of every other key (forward kinematics, sampled). Its ``max_force_n`` is the largest key force the
motors hold at the press pose (tau = J^T f plus gravity, through the actuator model),
each within its capacity (its peak torque, or its tendon's design force at the spool:
``planner.hand.tendon``): a note asking more is not pressed there.

Entries are solved on first use and kept for the process (``Atlas`` is built once per
hand). ``dx`` off the grid snaps to the nearest sample: the tip lands at most
``STEP_M / 2`` (0.5 mm) off the press point, inside the seed's 1 mm precision.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np

from planner.hand.model import HandModel
from planner.hand.tendon import actuator_capacity
from planner.ik import (
    PREPARE_HEIGHT_M,
    HandIK,
    IKResult,
    PressTarget,
    press_target,
    press_x_range,
    surfaces_under,
)
from planner.music import keyboard as kb
from planner.play.arc import Arc, arc_joint
from planner.play.fingerbody import OTHER_KEY_TOLERANCE_M, OWN_BED_MARGIN_M, FingerBodies

STEP_M = 0.001  # the atlas samples dx this often
SPAN_M = 0.045  # ... this far either side of a finger's natural place
HIGH_Z_M = kb.BLACK_TOP_Z_M + 0.0075  # a finger moving sideways keeps its tip this high
PRESS_DEPTH_ITERATIONS = 3  # ``Atlas._press``: the pad's depth found again from the body's
REPEAT_DEPTH_M = kb.DOWN_DEPTH_M - 0.002  # a repeated key rises to this depth (see above)
BASE_HOVER_Z_M = 0.005  # the natural hand's tips, above the white tops
CURL = 0.35  # the natural hand's finger flexion, a fraction of each joint's range
THUMB_Y_M = 0.015  # where the natural hand's thumb tip sits (y): in front of the black keys
LONG_Y_M = 0.095  # ... and the long fingers' (over the black keys' middle)
CLEARANCE_M = 0.001  # a tip passing over a key it does not press stays this far above it
TIP_RADIUS_M = 0.002  # ... counting the pad's size (a key's footprint grows by this)
WRIST_DIGITS = 9  # the natural wrist's fit is kept to 1e-9 rad (``_natural_hand``)
PATH_SAMPLES = 12  # a straight move is checked at this many points
BODY_SAMPLES = 5  # ... and its finger's body at this many (each a forward kinematics of
# every segment: the ends and every quarter, so that a curl between two clear ends shows)
CANON_OCTAVE = 4  # entries are solved on the keys of this octave (C4..B4)
TABLE_DIR = Path(__file__).parents[1] / "tables"
_POSES = ("press", "rise", "hover", "high")


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


class Press(NamedTuple):
    """A press pose's IK target and result (``Atlas._press``)."""

    target: PressTarget
    result: IKResult


class Atlas:
    """The atlas of one hand (see the module docstring)."""

    def __init__(self, hand: HandModel, ik: HandIK | None = None, posture: int = 0) -> None:
        self.hand = hand
        # every pose keeps each joint its stop margin inside its hard stops
        self.ik = ik or HandIK(hand, (hand.plan_lower, hand.plan_upper))
        self.rail = hand.index.get("rail")  # None: a hand on a fixed mount (rail at 0)
        # the fingers with one independent joint: their poses are found on their arc
        self.arc_joint = {f: j for f in hand.fingers if (j := arc_joint(hand, f)) is not None}
        self.posture = hand.spec.play_posture  # (None: the fitted wrist, reach 0, full dip)
        self.posture_index = posture  # (which of its reach positions: ``AtlasEntry.posture``)
        if posture and (self.posture is None or posture >= len(self.posture.reach_m)):
            raise ValueError(f"hand {hand.name!r} has no play posture {posture}")
        self.press_depth_m = kb.KEY_DIP_M if self.posture is None else self.posture.press_depth_m
        self.base = self._natural_hand()
        self._arcs = {f: Arc(hand, f, j, self.base) for f, j in self.arc_joint.items()}
        tips = hand.tip_positions(self.base)
        self.natural_dx = {f: float(tips[i, 0] - self.rail_of(self.base))
                           for i, f in enumerate(hand.fingers)}
        # the fingers whose natural tips rest in front of the black keys press white keys
        # there (``press_target``'s ``front``; with a ``[play]`` posture only)
        self.front = frozenset(f for i, f in enumerate(hand.fingers)
                               if self.posture is not None and tips[i, 1] < kb.BLACK_Y0_M)
        # the fingers' bodies, with a ``[play]`` posture: its poses, its moves and its key
        # crossings (``planner.play.moves``) follow the body rule (spec section 2)
        self.bodies = FingerBodies(hand) if self.posture is not None else None
        self._entries: dict[tuple[str, int, int], AtlasEntry | None] = {}
        # (the samples whose poses the IK found within the limits and the body rule
        # refused: a note only they could play is left out for its bodies, ``body``)
        self._body_refused: set[tuple[str, int, int]] = set()
        self.solves = 0
        self._load(table_path(hand.urdf_sha256, posture))

    # ------------------------------------------------------------------ set-up
    def park(self) -> np.ndarray:
        """The natural hand with the wrist fitted to hold the tips at crossing height (for
        a hand that plays nothing: it waits clear of the keys)."""
        return self._natural_hand(HIGH_Z_M)

    def raised(self, z_min_m: float) -> np.ndarray:
        """The natural hand at rail 0 with its wrist fitted so that its lowest fingertip
        is at ``z_min_m`` (within 0.1 mm; the fit of ``_natural_hand`` is least squares,
        some tips below its height): a hand held clear of every key."""
        z = z_min_m
        for _ in range(8):
            q = self._natural_hand(z)
            low = float(np.min(self.hand.tip_positions(q)[:, 2]))
            if abs(low - z_min_m) < 1e-4:
                break
            z += z_min_m - low
        return q

    def _natural_hand(self, z_m: float = BASE_HOVER_Z_M) -> np.ndarray:
        """The natural hand at rail 0: every finger ``CURL`` flexed with no abduction, and
        the wrist (flexion, deviation) that puts the tips, in the least-squares sense,
        (a hand file's ``[play]`` posture gives reach and wrist instead, at that height)
        ``BASE_HOVER_Z_M`` above the white tops, midway between full dip and crossing
        height, so that each finger has room both ways. A finger of one degree of
        freedom (``planner.play.arc``) takes no part in the fit: its one joint is what
        sets its height, flexed from open until its tip is down at that height (open
        if its arc never comes down to it; the wrist stays at its neutral when every
        finger is such)."""
        h = self.hand
        q0 = h.q_neutral.copy()
        for f in h.fingers:
            js = h.joint_slice(f)
            for j in js[1:]:
                q0[j] = min(max(h.lower[j] + CURL * (h.upper[j] - h.lower[j]),
                                h.plan_lower[j]), h.plan_upper[j])
            q0[js[0]] = min(max(0.0, h.plan_lower[js[0]]), h.plan_upper[js[0]])
        q0 = h.apply_couplings(q0)
        wrist = [h.index[n] for n in ("wrist_flex", "wrist_dev")]
        if self.posture is not None:  # (the hand file's posture: its reach always, its
            # wrist at the playing height; a hand raised higher fits its wrist)
            p = self.posture
            if "reach" in h.index:
                q0[h.index["reach"]] = p.reach_m[self.posture_index]
        fit = [i for i, f in enumerate(h.fingers) if f not in self.arc_joint]
        if self.posture is not None and z_m == BASE_HOVER_Z_M:
            fit = []  # (the posture's wrist; a one-DOF finger still comes down to the height)
            q0[wrist] = (self.posture.wrist_flex_rad, self.posture.wrist_dev_rad)

        def heights(w: np.ndarray) -> np.ndarray:
            q = q0.copy()
            q[wrist] = w
            return h.tip_positions(q)[fit, 2] - z_m

        w = q0[wrist].copy()
        for _ in range(50 if fit else 0):  # Gauss-Newton on two angles, finite differences
            r = heights(w)
            J = np.stack([(heights(w + 1e-6 * e) - r) / 1e-6 for e in np.eye(2)], axis=1)
            step = np.linalg.lstsq(J, -r, rcond=None)[0]
            w = np.clip(w + step, h.plan_lower[wrist], h.plan_upper[wrist])
            if np.max(np.abs(step)) < 1e-10:
                break
        # the fit converges to 1e-10 rad; its last digits differ between machines (BLAS,
        # numpy): kept to 1e-9 rad, the natural hand (and so the shipped tables, which are
        # used only for the same natural hand) is the same everywhere
        if fit:
            q0[wrist] = np.round(w, WRIST_DIGITS)
        for f, j in self.arc_joint.items():
            s = Arc(h, f, j, q0).descend(z_m)
            if s is not None:
                q0[j] = s
        return h.apply_couplings(q0)

    def rail_of(self, q: np.ndarray) -> float:
        """The rail position of a configuration (0 on a fixed mount)."""
        return 0.0 if self.rail is None else float(q[self.rail])

    def _solved_on(self, finger: str, pitch_class: int, k: int) -> int | None:
        """The key an entry is solved on: of the canonical octave when the rail can carry
        the hand there; on a fixed mount, the key of that pitch class at that place (None
        if none is within half a grid step)."""
        if self.rail is not None:
            return 12 * (CANON_OCTAVE + 1) + pitch_class
        x = self.natural_dx[finger] + k * STEP_M
        for p in kb.ALL_PITCHES:
            if p % 12 == pitch_class and abs(kb.key(p).center_x_m - x) <= STEP_M / 2:
                return p
        return None

    # ------------------------------------------------------------------ lookup
    def grid_index(self, finger: str, pitch: int, rail_m: float) -> int:
        """The sample of ``dx`` nearest to key ``pitch`` seen from ``rail_m``."""
        dx = kb.key(pitch).center_x_m - rail_m
        return round((dx - self.natural_dx[finger]) / STEP_M)

    def rail_for(self, finger: str, pitch: int, k: int) -> float:
        """The rail position at which key ``pitch`` sits at sample ``k`` of ``finger``."""
        return kb.key(pitch).center_x_m - (self.natural_dx[finger] + k * STEP_M)

    def entry(self, finger: str, pitch: int, rail_m: float) -> AtlasEntry | None:
        """The finger's poses over key ``pitch`` with the rail at ``rail_m`` (snapped to
        the grid); None when the finger cannot press it from there."""
        k = self.grid_index(finger, pitch, rail_m)
        if abs(k) * STEP_M > SPAN_M:
            return None
        return self.entry_at(finger, pitch % 12, k)

    def entry_at(self, finger: str, pitch_class: int, k: int) -> AtlasEntry | None:
        key = (finger, pitch_class, k)
        if key not in self._entries:
            self._entries[key] = self._solve(finger, pitch_class, k)
        return self._entries[key]

    def body_refused(self, finger: str, pitch: int, rail_m: float) -> bool:
        """Whether the finger would press key ``pitch`` from ``rail_m`` (snapped to the grid)
        but for its body (the poses found within the limits, a body not clear of the keys)."""
        k = self.grid_index(finger, pitch, rail_m)
        if abs(k) * STEP_M > SPAN_M:
            return False
        self.entry_at(finger, pitch % 12, k)
        return (finger, pitch % 12, k) in self._body_refused

    def samples(self, finger: str, pitch: int) -> list[int]:
        """Every grid sample at which ``finger`` can press key ``pitch`` (solving them)."""
        n = round(SPAN_M / STEP_M)
        return [k for k in range(-n, n + 1) if self.entry_at(finger, pitch % 12, k) is not None]

    def full_q(self, entry: AtlasEntry, pose: str, rail_m: float,
               q_into: np.ndarray | None = None) -> np.ndarray:
        """A whole-hand configuration: ``q_into`` (default the natural hand) with the rail
        at ``rail_m`` and the entry's finger in ``pose`` ("press", "rise", "hover" or
        "high")."""
        q = (self.base if q_into is None else q_into).copy()
        if self.rail is not None:
            q[self.rail] = rail_m
        q[self.hand.joint_slice(entry.finger)] = getattr(entry, pose)
        return self.hand.apply_couplings(q)

    # ------------------------------------------------------------------ the table
    def solve_all(self) -> int:
        """Solve every entry of the grid (for the shipped table); returns how many exist."""
        n = round(SPAN_M / STEP_M)
        return sum(self.entry_at(f, pc, k) is not None for f in self.hand.fingers
                   for pc in range(12) for k in range(-n, n + 1))

    def save(self, path: Path) -> None:
        """Write every solved entry (and every sample found empty) to ``path`` (npz)."""
        keys = sorted(self._entries, key=lambda k: (self.hand.fingers.index(k[0]), k[1], k[2]))
        width = max(len(self.hand.joint_slice(f)) for f in self.hand.fingers)
        poses = {p: np.full((len(keys), width), np.nan) for p in _POSES}
        force = np.full(len(keys), np.nan)
        for i, key in enumerate(keys):
            e = self._entries[key]
            if e is not None:
                for p in _POSES:
                    q = getattr(e, p)
                    poses[p][i, :len(q)] = q
                force[i] = e.max_force_n
        idx = np.array([(self.hand.fingers.index(f), pc, k) for f, pc, k in keys], dtype=np.int16)
        with open(path, "wb") as fh:
            body = np.array([key in self._body_refused for key in keys], dtype=bool)
            np.savez_compressed(fh, key=idx, max_force_n=force, body_refused=body,
                                params=np.array(self._params()),
                                **poses)

    def _params(self) -> str:
        """What the entries depend on besides the URDF: a table made otherwise is not used.
        The mount (the root's pose over the keyboard) is not in the URDF: a hand file whose
        mount moves keeps its URDF and its table's name, and the pose makes the old table
        stale."""
        return json.dumps({"urdf_sha256": self.hand.urdf_sha256, "step_m": STEP_M,
                           "T_world_root": [round(float(x), 12)
                                            for x in self.hand.T_world_root.ravel()],
                           "span_m": SPAN_M, "high_z_m": HIGH_Z_M, "repeat_depth_m": REPEAT_DEPTH_M,
                           "base_hover_z_m": BASE_HOVER_Z_M, "curl": CURL,
                           "clearance_m": CLEARANCE_M, "tip_radius_m": TIP_RADIUS_M,
                           "path_samples": PATH_SAMPLES, "canon_octave": CANON_OCTAVE,
                           "capacity_nm": [round(float(x), 12) for x in
                                           actuator_capacity(self.hand).torque_nm],
                           "base": [round(float(x), 12) for x in self.base],
                           "stop_margin": [round(float(x), 12) for x in self.hand.stop_margin],
                           **self._posture_params()},
                          sort_keys=True)

    def _posture_params(self) -> dict:
        """A ``[play]`` posture and the body rule it brings (none without one: the tables
        of the hands without it stay as they were)."""
        p = self.posture
        if p is None:
            return {}
        return {"posture": [round(float(x), 12) for x in (p.reach_m[self.posture_index],
                                                          p.wrist_flex_rad, p.wrist_dev_rad,
                                                          p.press_depth_m)],
                "body_rule": [OTHER_KEY_TOLERANCE_M, OWN_BED_MARGIN_M, BODY_SAMPLES,
                              "footprint-grown", "press-body-to-bed-both-ways", PRESS_DEPTH_ITERATIONS]}

    def _load(self, path: Path) -> None:
        if not path.exists():
            return
        with np.load(path, allow_pickle=False) as z:
            if str(z["params"]) != self._params():
                return
            refused = z["body_refused"] if "body_refused" in z else np.zeros(len(z["key"]), bool)
            for (fi, pc, k), r in zip(z["key"], refused):
                if r:
                    self._body_refused.add((self.hand.fingers[int(fi)], int(pc), int(k)))
            for (fi, pc, k), force, *qs in zip(z["key"], z["max_force_n"],
                                               *(z[p] for p in _POSES)):
                f = self.hand.fingers[int(fi)]
                if np.isnan(force):
                    self._entries[(f, int(pc), int(k))] = None
                    continue
                n = len(self.hand.joint_slice(f))
                self._entries[(f, int(pc), int(k))] = AtlasEntry(
                    f, int(pc), self.natural_dx[f] + int(k) * STEP_M,
                    *(q[:n].copy() for q in qs), float(force), self.posture_index)

    # ------------------------------------------------------------------ solving
    def _solve(self, finger: str, pitch_class: int, k: int) -> AtlasEntry | None:
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
        poses = (self._arc_poses(finger, pitch, rail) if finger in self.arc_joint
                 else self._ik_poses(finger, pitch, base))
        if poses is None:
            return None
        js = h.joint_slice(finger)
        if not all(h.within_plan_limits(q) for q in poses):
            return None
        for qa, qb in ((poses[3], poses[2]), (poses[2], poses[0]), (poses[3], poses[0]),
                       (poses[1], poses[0])):
            if not path_clear(h, qa, qb, finger, pitch):
                return None
        for qa, qb in ((poses[3], poses[2]), (poses[2], poses[0]), (poses[3], poses[0]),
                       (poses[1], poses[0])):
            if self.bodies is not None and not bodies_clear(self.bodies, qa, qb, finger, pitch):
                self._body_refused.add((finger, pitch_class, k))
                return None
        return AtlasEntry(finger, pitch_class, self.natural_dx[finger] + k * STEP_M,
                          *(q[js].copy() for q in poses), max_key_force_n(h, poses[0], finger),
                          self.posture_index)

    def _ik_poses(self, finger: str, pitch: int, base: np.ndarray) -> list[np.ndarray] | None:
        """Press, rise, hover and high by single-finger IK: the tip on the key's press
        point, then straight above it at each height."""
        r = self._press(finger, pitch, base)
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

    def _press(self, finger: str, pitch: int, base: np.ndarray) -> Press | None:
        """The press pose by single-finger IK: the pad point ``press_depth_m`` below the
        key's top; with the body rule, deeper where the finger's lowest body point would
        stop short of the key bed (a pad that is its finger's lowest point, on a black
        key: 6 mm down leaves the key 1 mm past the key-down depth, which a servo's
        tracking under the key's spring loses, 2-2.5 mm measured in physics), until its
        body reaches the bed (``KEY_DIP_M``; the pad no deeper than the dip); shallower
        where the press depth would put the lowest body past the bed by more than the
        bed's margin (``OWN_BED_MARGIN_M``, check's rule: a pad sphere of 5 mm below its
        pad point at the press depth of 6 mm reaches 11.1 mm, past the 11 mm allowed),
        until it is at the bed: the key is fully down either way (the bed stops it)."""
        front = finger in self.front
        depth = self.press_depth_m
        for _ in range(PRESS_DEPTH_ITERATIONS):
            target = press_target(finger, pitch, depth, front)
            self.solves += 1
            r = self.ik.solve_finger(target, base)
            if not r.converged:
                return None
            if self.bodies is None:
                break
            tip = self.hand.tip_positions(r.q)[self.hand.fingers.index(finger)]
            want = kb.KEY_DIP_M - self._body_below_tip_m(r.q, finger, tip)  # (<= the dip)
            if depth - OWN_BED_MARGIN_M + 1e-4 <= want <= depth + 1e-4:
                break  # (the body between the bed and its margin past it)
            depth, base = want, r.q
        return Press(target, r)

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


def posture_count(hand: HandModel) -> int:
    """How many play postures ``hand`` has (its ``[play]`` reach positions; one without)."""
    p = hand.spec.play_posture
    return 1 if p is None else len(p.reach_m)


def table_path(urdf_sha256: str, posture: int = 0) -> Path:
    """Where the atlas of a hand's URDF (in its play posture ``posture``, after the first)
    is shipped (a cache: without it, entries are solved when first asked for;
    ``scripts/make_atlas.py`` writes it)."""
    return TABLE_DIR / f"atlas-{urdf_sha256[:16]}{f'-p{posture}' if posture else ''}.npz"


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
    ``q`` with gravity: tau(f) = tau(0) + f (tau(1) - tau(0)), each |tau_m| <= its
    capacity (``actuator_capacity``: peak torque, or tendon force x spool radius)."""
    tau0 = hand.press_torques(q, {})
    tau1 = hand.press_torques(q, {finger: 1.0}) - tau0
    peak = actuator_capacity(hand).torque_nm
    best = math.inf
    for t0, t1, p in zip(tau0, tau1, peak):
        if abs(t0) > p:
            return 0.0
        if t1 > 1e-12:
            best = min(best, (p - t0) / t1)
        elif t1 < -1e-12:
            best = min(best, (-p - t0) / t1)
    return float(best)
