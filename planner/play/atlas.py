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
  dip); a finger repeating a note goes up the line from the press towards it, only
  ``moves.REARM_M`` above the key-down depth where it bounces (``Moves.repeat``), to it
  where it has time to wait;
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
from pathlib import Path

import numpy as np

from planner.hand.model import HandModel
from planner.hand.tendon import actuator_capacity
from planner.ik import HandIK
from planner.music import keyboard as kb
from planner.play.arc import Arc, arc_joint
from planner.play.atlassolve import (
    BODY_SAMPLES,
    CLEARANCE_M,
    HIGH_Z_M,
    PAD_CENTRE_ITERATIONS,
    PATH_SAMPLES,
    PRESS_DEPTH_ITERATIONS,
    REPEAT_DEPTH_M,
    STEP_M,
    TIP_RADIUS_M,
    AtlasEntry,
    EntrySolver,
    bodies_clear,
    max_key_force_n,
    path_clear,
)
from planner.play.fingerbody import OTHER_KEY_TOLERANCE_M, OWN_BED_MARGIN_M, FingerBodies
from planner.play.force import DESCENT_SAMPLES
from planner.simulate.hand_mjcf import PAD_FRICTION

__all__ = ["BODY_SAMPLES", "CLEARANCE_M", "HIGH_Z_M", "PATH_SAMPLES", "REPEAT_DEPTH_M",
           "SPAN_M", "STEP_M", "TIP_RADIUS_M", "Atlas", "AtlasEntry", "bodies_clear",
           "max_key_force_n", "path_clear", "posture_count", "table_path"]

SPAN_M = 0.045  # ... this far either side of a finger's natural place
BASE_HOVER_Z_M = 0.005  # the natural hand's tips, above the white tops
CURL = 0.35  # the natural hand's finger flexion, a fraction of each joint's range
THUMB_Y_M = 0.015  # where the natural hand's thumb tip sits (y): in front of the black keys
LONG_Y_M = 0.095  # ... and the long fingers' (over the black keys' middle)
WRIST_DIGITS = 9  # the natural wrist's fit is kept to 1e-9 rad (``_natural_hand``)
CANON_OCTAVE = 4  # entries are solved on the keys of this octave (C4..B4)
TABLE_DIR = Path(__file__).parents[1] / "tables"
_POSES = ("press", "rise", "hover", "high")



class Atlas(EntrySolver):
    """The atlas of one hand (see the module docstring; its entries are solved by
    ``EntrySolver``)."""

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

    def forget(self) -> None:
        """Drop every entry found or read, so that the next asks solve afresh (a table
        remade from the hand, not read back from an older one)."""
        self._entries.clear()

    def asked(self) -> int:
        """How many samples have been asked (with or without an entry)."""
        return len(self._entries)

    def solved(self) -> dict[tuple[str, int, int], AtlasEntry]:
        """The entries found so far by (finger, pitch class, sample), in the order they
        were found or read (the samples with no entry left out)."""
        return {k: e for k, e in self._entries.items() if e is not None}

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
                           "press_force": ["descent-with-friction", DESCENT_SAMPLES,
                                           PAD_FRICTION, "x-locked-at-its-tip"],
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
                              "footprint-grown", "press-body-to-bed-both-ways", "pad-faces-key",
                              "pad-body-centred", PAD_CENTRE_ITERATIONS,
                              PRESS_DEPTH_ITERATIONS]}

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


def posture_count(hand: HandModel) -> int:
    """How many play postures ``hand`` has (its ``[play]`` reach positions; one without)."""
    p = hand.spec.play_posture
    return 1 if p is None else len(p.reach_m)


def table_path(urdf_sha256: str, posture: int = 0) -> Path:
    """Where the atlas of a hand's URDF (in its play posture ``posture``, after the first)
    is shipped (a cache: without it, entries are solved when first asked for;
    ``scripts/make_atlas.py`` writes it)."""
    return TABLE_DIR / f"atlas-{urdf_sha256[:16]}{f'-p{posture}' if posture else ''}.npz"
