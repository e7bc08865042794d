"""Play: song -> fingering -> key states -> IK keyframes -> timed trajectory -> file.

Orchestration only: each stage lives in its own module. Rows are written
and flushed chunk by chunk while the song is planned.
"""

from __future__ import annotations

import dataclasses
import itertools
import json
import math
import os
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from planner.errors import InputError
from planner.fingering import FINGER_ORDER, HandReach, assign_fingers, fit_rail
from planner.hand.model import HandModel, load_hand
from planner.ik import (
    PRESS_TOL_M,
    HandIK,
    IKResult,
    PressTarget,
    exposed_range_x,
    press_target,
    surfaces_under,
)
from planner.music import keyboard as kb
from planner.music.midi import Song, load_song, pitch_name
from planner.play.stream import guard_rows, play_metadata
from planner.selfcheck import SelfCheck, SkipReason, Verdict
from planner.targets import MOVE_S, descent_time_s, press_intervals
from planner.trajectory import (
    Phase,
    build_timing,
    min_jerk,
    min_jerk_rates,
    phase_duration,
    sample,
    solve_timing,
)
from planner.trajfile import TrajectoryWriter

DROP_LATE = 0.5  # a note whose key cannot go down before this fraction of it is over is left out
EARLY_FRAMES = 0.4  # a key goes down at most this fraction of a frame before the half-frame
# before its note's first frame: never in the frame before (a note early is a wrong note)
CHUNK_PHASES = 40
PART_NOTES = 256  # a long song is fingered in parts of at least this many notes
FIRST_PART_NOTES = 32  # ... the first of at least this many
TRAVEL_LEAD_S = 0.25  # a chunk cut before a change of hand position ends this long before the last release
FIRST_CHUNK_PHASES = 12
REST_HOVER_Z_M = 0.020
VERTICAL_SLIDE_M = 0.015  # a finger moving up or down may slide this far along the keys
HIGH_M = 0.020  # a fingertip crossing keys sideways stays this far above white tops (7.5 mm over black)
RELEASE_WEIGHT = 0.3  # an onset on time matters more than a release on time
TRAVEL_SAFE_Z_M = 0.040  # fingertips lifted this high when a straight travel would dip
TRAVEL_LIFTS_M = (0.028, TRAVEL_SAFE_Z_M)  # higher lifts tried when HIGH_M is not enough
WRIST_TRAVEL_RAD = -0.35  # wrist extension (20 deg) raising the fingers for a rail-only travel
TRAVEL_CLEARANCE_M = 0.002  # a fingertip moving over the keys stays this far above their tops
KEY_UP_SLACK_M = 0.0005  # a finger leaving its key is this far above the key-up depth once the arm moves
HOLD_SLACK_M = 0.0005  # a held key's tip stays this far below the key-down depth ...
HOLD_DEEPER_M = 0.001  # ... and at most this far below full dip (the key bed is 2 mm below it)
SHIFT_STEPS = (1, 2, 4)  # the arm's steps while a finger holds its key (the fewest that keep it down)
ARRIVE_M = 0.001  # a finger touches its key once what is left of the arm's move shifts it less
PRESS_LAG_STEP_S = 0.005  # a press from high above its key while the arm moves: its start tried this often
ACROSS_SPLITS = 2  # a finger crossing keys high is given up to 3 waypoints
PATH_STEP_M = 0.003  # a finger's path over the keys is checked at least this often
GRAZE_M = 0.5 * kb.DOWN_DEPTH_M  # a finger moving over keys may sink this far into one, never near sounding it
TRAVEL_INFLATE_M = 0.002  # ... of every key within this distance of it (a fingertip is not a point)
TRAVEL_OVERLAPS = tuple(np.round(np.arange(0.1, 1.0001, 0.05), 2))  # fractions of a motion done before the next starts
_SIM_DT_S = 0.002
HOVER_MIN_M = 0.005  # issue: a finger not pressing is at least this far above the keys under it
LOW_M = 0.0055  # issue: non-pressing tips at least 5 mm above the keys
PAIR_TABLE_DIR = Path(__file__).parents[1] / "tables"
PAIR_TABLE_FIRST = -12  # the shipped table starts at this interval (crossed fingers: the fingering asks)
PAIR_RETRY_ITER = 120  # a two-finger chord's IK that has not converged goes on this many steps
RANGE_MAX_M = 0.06  # a finger's sideways reach with the arm still: probed up to this far a side
RANGE_TOL_M = 0.001  # ... to this precision
START_PRESSED_S = 1e-9  # notes at t = 0 are down from the first row on


@dataclass(frozen=True)
class NoteReport:
    index: int
    pitch: int
    onset_s: float
    finger: str | None
    reason: str | None  # None: played as written


@dataclass
class PlayResult:
    rows: int
    duration_s: float
    notes: list[NoteReport]
    planning_s: float
    first_row_s: float
    ik_solves: int
    cut: list[tuple[int, float]] = field(default_factory=list)  # (note, s) let go that early
    travels: int = 0  # changes of hand position (rail and wrist) after the start, every key up
    shifts: int = 0  # ... and those made while a finger held its key
    verdict: Verdict | None = None  # the rows replayed by the check's rules (selfcheck)

    @property
    def infeasible(self) -> list[NoteReport]:
        return [n for n in self.notes if n.reason is not None]


class Planner:
    """Everything built once per hand: IK solver, rest posture, reach table."""

    def __init__(self, hand: HandModel) -> None:
        self.hand = hand
        self.ik = HandIK(hand)
        self.rail = hand.index.get("rail")
        self._cache: dict = {}
        self._anchors: dict = {}  # hand positions of this song, by the IK problem that made them
        shipped = _shipped_table(hand)  # (read once: the pairs and the ranges)
        self._pairs: dict = _pair_answers(shipped)  # pair_ok's answers (shipped ones first)
        self.bases: list[np.ndarray] = []
        self.ik_solves = 0
        self.rest = self._rest_posture()
        tips = hand.tip_positions(self.rest)
        rail0 = self.rest[self.rail] if self.rail is not None else 0.0
        offsets = {f: float(tips[i, 0] - rail0) for i, f in enumerate(hand.fingers)}
        reach = {f: self._probe_reach(f, tips[i], ("rail",)) for i, f in enumerate(hand.fingers)}
        lo = hand.lower[self.rail] if self.rail is not None else 0.0
        hi = hand.upper[self.rail] if self.rail is not None else 0.0
        vmax = hand.velocity[self.rail] if self.rail is not None else 1e-9
        amax = hand.acceleration[self.rail] if self.rail is not None else 1e-9
        # (a chord's spread is left to the whole-hand IK: a probe with the wrist still
        # rejected octaves the hand can play)
        repeat, move = self._finger_times(tips)
        self.reach = HandReach(offsets, reach, float(vmax), (float(lo), float(hi)), float(amax),
                               repeat_s=repeat, move_s=move,
                               range_m=shipped.get("range_m") or self._finger_ranges(tips))

    def pair_ok(self, f1: str, p1: int, f2: str, p2: int) -> bool:
        """Whether finger ``f1`` on ``p1`` and ``f2`` on ``p2`` can be down at once with
        every other fingertip clear of the keys: the whole-hand IK of a chord, from the
        natural hand at the rail the fingering's reach model fits to the two. The keyboard
        repeats every octave and the rail only translates the hand, so the answer is
        worked out once per pair of fingers, pitch class and interval (in the octave of
        middle C) and remembered."""
        if f1 == f2:
            return p1 == p2
        if FINGER_ORDER.index(f1) > FINGER_ORDER.index(f2):
            f1, p1, f2, p2 = f2, p2, f1, p1
        key = (f1, f2, p1 % 12, p2 - p1)
        if key not in self._pairs:
            a = 60 + p1 % 12
            b = a + p2 - p1
            ok = kb.LOWEST_PITCH <= b <= kb.HIGHEST_PITCH
            if ok:
                q = self.posture_at(fit_rail((f1, f2), np.array([kb.key(a).center_x_m, kb.key(b).center_x_m]),
                                             self.reach)[0])
                targets = [press_target(f1, a), press_target(f2, b)]
                r = self.ik.solve(targets, q, q)
                if not r.converged:  # (slow to converge from there: on from where it got to)
                    rail = float(r.q[self.rail]) if self.rail is not None else 0.0
                    r = self.ik.solve(targets, r.q, self.posture_at(rail), max_iter=PAIR_RETRY_ITER)
                    self.ik_solves += 1
                ok = r.converged
                self.ik_solves += 1
            self._pairs[key] = ok
        return self._pairs[key]

    def pair_table(self) -> dict:
        """Every answer of ``pair_ok`` the fingering may ask for (the fingers in order,
        the keys within the reach model's stretch), as written to ``PAIR_TABLE_DIR``."""
        r = self.reach
        rows = {}
        for i, f1 in enumerate(FINGER_ORDER):
            for f2 in FINGER_ORDER[i + 1:]:
                lim = np.array([r.reach_m[f1], r.reach_m[f2]])
                for pc in range(12):
                    a = 60 + pc
                    row = []
                    for iv in range(PAIR_TABLE_FIRST, kb.HIGHEST_PITCH - a + 1):
                        xs = np.array([kb.key(a).center_x_m, kb.key(a + iv).center_x_m])
                        if np.any(np.abs(fit_rail((f1, f2), xs, r)[1]) > lim):
                            row.append("-")
                        else:
                            row.append("1" if self.pair_ok(f1, a, f2, a + iv) else "0")
                    rows[f"{f1} {f2} {pc}"] = "".join(row).rstrip("-")
        return {"urdf_sha256": self.hand.urdf_sha256, "hand": self.hand.name,
                "about": "Planner.pair_ok by finger pair (in the hand's order) and pitch class of "
                         "the first finger's key: one character per interval in semitones to the "
                         "second's, from first_interval on (1 both keys down at once, 0 not, - not "
                         "worked out); written by scripts/make_pair_table.py",
                "first_interval": PAIR_TABLE_FIRST, "pairs": rows,
                "range_m": self._finger_ranges(self.hand.tip_positions(self.rest))}

    def _rest_posture(self) -> np.ndarray:
        """The natural hovering hand at rail 0: fingertips over their knuckles, 20 mm above
        the keys, the thumb in front of the index (computed by IK, not typed)."""
        h = self.hand
        q0 = h.q_neutral.copy()
        for f in h.fingers:  # a curled start
            idx = h.joint_slice(f)
            for j in idx[1:]:
                q0[j] = 0.5 * (h.lower[j] + h.upper[j]) * 0.6
        q0 = h.apply_couplings(np.clip(q0, h.lower, h.upper))
        targets = []
        for f in h.fingers:
            j = h.spec.joint(h.spec.joints_of(f)[0])
            index_root = h.spec.joint(h.spec.joints_of("index")[0])
            x = j.xyz_m[0] if f != "thumb" else index_root.xyz_m[0] - 0.035
            y = 0.095 if f != "thumb" else 0.030
            targets.append(PressTarget(f, 0, (x, y, REST_HOVER_Z_M), (y, y)))
        r = self.ik.solve(targets, q0, q0, hover=())
        return r.q

    def _finger_times(self, tips: np.ndarray) -> tuple[dict[str, float], dict[str, float]]:
        """Per finger, from the rest posture over the white key under it: the time from
        key up to key down again on the same key (release to ``LOW_M`` and press, each
        counted from its key crossing), and on the next white key up (release to
        ``HIGH_M``, across, press from ``HIGH_M``), as the timeline plans them."""
        h = self.hand
        repeat, move = {}, {}

        def T(a: np.ndarray, b: np.ndarray) -> float:
            return phase_duration(b - a, h.velocity, h.acceleration)

        for i, f in enumerate(h.fingers):
            x = float(tips[i, 0])
            pitch = min((p for p in kb.ALL_PITCHES if not kb.is_black(p)),
                        key=lambda p: abs(kb.key(p).center_x_m - x))
            nxt = pitch + (1 if not kb.is_black(pitch + 1) else 2)
            r = self.ik.solve([press_target(f, pitch)], self.rest, self.rest)
            r2 = self.ik.solve_finger(press_target(f, nxt), r.q)
            q_low = self._vertical(r.q, f, kb.key(pitch).top_z_m + LOW_M, pitch).q
            q_high = self._vertical(r.q, f, kb.key(pitch).top_z_m + HIGH_M, pitch).q
            q_high2 = self._vertical(r2.q, f, kb.key(nxt).top_z_m + HIGH_M, nxt).q
            up, down = _key_crossing(h, r.q, q_low, f, pitch), _key_crossing(h, q_low, r.q, f, pitch)
            repeat[f] = (1.0 - up) * T(r.q, q_low) + down * T(q_low, r.q)
            up = _key_crossing(h, r.q, q_high, f, pitch)
            down = _key_crossing(h, q_high2, r2.q, f, nxt)
            move[f] = (1.0 - up) * T(r.q, q_high) + T(q_high, q_high2) + down * T(q_high2, r2.q)
        return repeat, move

    def _finger_ranges(self, tips: np.ndarray) -> dict[str, float] | None:
        """Per finger, how far apart (m) two keys it plays from one hand position may be:
        from the hand on white keys (one finger each, the thumb on the key under it at
        rest; adjacent keys, and every other key), how far its tip moves sideways at full
        dip with the arm still (rail and wrist), to the left and to the right, added
        (bisection to ``RANGE_TOL_M``, at most ``RANGE_MAX_M`` a side); the larger of the
        two shapes. None if the hand takes neither."""
        h = self.hand
        whites = [p for p in kb.ALL_PITCHES if not kb.is_black(p)]
        first = min(range(len(whites)), key=lambda k: abs(kb.key(whites[k]).center_x_m - tips[0, 0]))
        rail0 = self.rest[self.rail] if self.rail is not None else 0.0
        natural = HandReach({f: float(tips[i, 0] - rail0) for i, f in enumerate(h.fingers)},
                            {f: 1.0 for f in h.fingers}, 1.0, (-np.inf, np.inf), 1.0)
        out: dict[str, float] = {}
        for step in (1, 2):
            keys = dict(zip(h.fingers, whites[first:first + step * len(h.fingers):step]))
            targets = [press_target(f, p) for f, p in keys.items()]
            rail_m, _ = fit_rail(h.fingers, np.array([kb.key(p).center_x_m for p in keys.values()]), natural)
            q0 = self.posture_at(rail_m)
            r = self.ik.solve(targets, q0, q0)
            if not r.converged:
                continue
            for t in targets:
                k = h.fingers.index(t.finger)
                x0 = float(h.tip_positions(r.q)[k, 0])
                total = 0.0
                for sign in (-1.0, 1.0):
                    lo, hi = 0.0, RANGE_MAX_M
                    while hi - lo > RANGE_TOL_M:
                        d = 0.5 * (lo + hi)
                        goal = PressTarget(t.finger, t.pitch, (x0 + sign * d, t.point_m[1], t.point_m[2]), t.y_range_m)
                        if self.ik.solve_finger(goal, r.q).converged:
                            lo = d
                        else:
                            hi = d
                    total += lo
                out[t.finger] = max(out.get(t.finger, 0.0), total)
        return out or None

    def _probe_reach(self, finger: str, tip: np.ndarray, locked_joints: tuple[str, ...]) -> float:
        """How far (m) a fingertip can move sideways from rest with ``locked_joints`` still
        (rail only: the reach of the hand at a rail position, the wrist helping; rail and
        wrist: how far a finger spreads from the others).

        Found by IK: the largest d in 2.5 mm steps for which the tip reaches
        rest +/- d at hover height (the smaller of the two sides)."""
        ik = self.ik
        locked = [n for n in locked_joints if n in self.hand.index]
        for n in locked:
            ik.solver.mask_dof(n)
        try:
            best = []
            for sign in (-1.0, 1.0):
                d_ok = 0.0
                for step in range(1, 25):
                    d = 0.0025 * step
                    y = float(tip[1])
                    t = PressTarget(finger, 0, (float(tip[0]) + sign * d, y, float(tip[2])), (y - 0.03, y + 0.03))
                    r = ik.solve([t], self.rest, self.rest, hover=())
                    if not r.converged:
                        break
                    d_ok = d
                best.append(d_ok)
        finally:
            for n in locked:
                ik.solver.unmask_dof(n)
        return min(best)

    def posture_at(self, rail_m: float) -> np.ndarray:
        q = self.rest.copy()
        if self.rail is not None:
            q[self.rail] = min(max(rail_m, self.hand.lower[self.rail]), self.hand.upper[self.rail])
        return q

    # ------------------------------------------------------------ hand positions
    def anchor(self, targets: list[PressTarget], rail_m: float, q_from: np.ndarray,
               upcoming: list[PressTarget] = (), chord: list[PressTarget] = ()) -> int | None:
        """A new hand position (rail and wrist) for the keys ``targets``: whole-hand IK with
        those fingers pressing, the fingers that play ``upcoming`` keys next waiting just
        above them, and the others hovering; or, with ``chord``, the fingers of ``chord``
        pressing too (a chord the hand does not play, only takes the shape of, so that
        each of those fingers reaches its key from there by itself). Returns its index in
        ``bases`` (the hand there with every finger up), or None when the IK cannot reach."""
        neutral = q_from is None  # (from the natural hand at that rail, not where it is)
        q_from = self.posture_at(rail_m) if neutral else q_from
        key = (tuple(targets), tuple(upcoming), tuple(chord), rail_m, neutral)
        if key in self._anchors:  # the same shape at the same rail: the same position
            return self._anchors[key]
        self._anchors[key] = seg = self._anchor(targets, rail_m, q_from, upcoming, chord)
        return seg

    def _anchor(self, targets, rail_m: float, q_from: np.ndarray, upcoming, chord) -> int | None:
        posture = self.posture_at(rail_m)
        presses = list(targets) + list(chord)
        r = self.ik.solve(presses, q_from, posture, prepare=upcoming)
        self.ik_solves += 1
        if not r.converged:
            r = self.ik.solve(presses, posture, posture, prepare=upcoming)
            self.ik_solves += 1
        if not r.converged and upcoming:
            r = self.ik.solve(presses, posture, posture)
            self.ik_solves += 1
        if not r.converged:
            return None
        seg = len(self.bases)
        self.bases.append(r.q)
        base = r.q.copy()
        for t in targets:  # the pressing fingers wait high above their keys
            self._cache[(t.finger, t.pitch, seg, "press")] = (r.q, r)
            self._check_lift(t.finger, t.pitch, seg)
            js = self.hand.joint_slice(t.finger)
            base[js] = self.above_q(t.finger, t.pitch, seg, HIGH_M)[js]
        for t in chord:  # the others high above where they took the chord's shape
            js = self.hand.joint_slice(t.finger)
            base[js] = self._vertical(r.q, t.finger, kb.key(t.pitch).top_z_m + HIGH_M).q[js]
        self.bases[seg] = base
        tips = self.hand.tip_positions(base)
        if not np.all(_above_keys(tips, HOVER_MIN_M - PRESS_TOL_M)):
            return None  # a finger cannot get off the keys there: no place to wait in
        return seg

    def _vertical(self, q: np.ndarray, finger: str, z_m: float, pitch: int | None = None) -> IKResult:
        """Single-finger IK moving ``finger``'s tip up or down from where it is in ``q`` to
        height ``z_m``, its x (across the keys) unchanged (the rest of the hand stays as in
        ``q``). Its y (along the keys) may slide within the range where it may press
        ``pitch`` (or ``VERTICAL_SLIDE_M`` either way), so the finger moves as little as it
        can: a straight-up path would need every joint of the finger."""
        tip = self.hand.tip_positions(q)[self.hand.fingers.index(finger)]
        y = float(tip[1])
        if pitch is None:
            y_range = (y - VERTICAL_SLIDE_M, y + VERTICAL_SLIDE_M)
        else:
            lo, hi = press_target(finger, pitch).y_range_m
            y_range = (min(lo, y), max(hi, y))
        t = PressTarget(finger, pitch or 0, (float(tip[0]), y, z_m), y_range)
        self.ik_solves += 1
        return self.ik.solve_finger(t, q)

    def lift_to(self, q: np.ndarray, finger: str, z_m: float) -> np.ndarray:
        """``q`` with ``finger`` raised straight up to height ``z_m`` (not lowered)."""
        js = np.concatenate([_arm_joints(self.hand), np.arange(self.hand.n)[self.hand.joint_slice(finger)]])
        key = (finger, z_m, q[js].tobytes())
        if key not in self._cache:
            if self.hand.tip_positions(q)[self.hand.fingers.index(finger), 2] >= z_m:
                self._cache[key] = q[js]
            else:
                self._cache[key] = self._vertical(q, finger, z_m).q[js]
        out = q.copy()
        out[js] = self._cache[key]
        return out

    def rest_high_q(self, finger: str, seg: int) -> np.ndarray:
        """``finger`` lifted straight up from its place in hand position ``seg`` to
        ``HIGH_M`` above the white keys' top; cached."""
        key = (finger, seg, "rest_high")
        if key not in self._cache:
            self._cache[key] = self._vertical(self.bases[seg], finger, HIGH_M).q
        return self._cache[key]

    def press_q(self, finger: str, pitch: int, seg: int) -> tuple[np.ndarray, IKResult]:
        """``finger`` pressing ``pitch`` at full dip, the rest of the hand as in position
        ``seg`` (only the finger's own joints move); cached."""
        key = (finger, pitch, seg, "press")
        if key not in self._cache:
            r = self.ik.solve_finger(press_target(finger, pitch), self.bases[seg])
            self._cache[key] = (r.q, r)
            self.ik_solves += 1
            self._check_lift(finger, pitch, seg)
        return self._cache[key]

    def _check_lift(self, finger: str, pitch: int, seg: int) -> None:
        """A key the finger cannot leave straight up by ``LOW_M`` (to let it go, or to wait
        over it) is not one it can play from this hand position: its press is marked not
        converged."""
        key = (finger, pitch, seg, "press")
        q, r = self._cache[key]
        if not r.converged:
            return
        up = self._vertical(q, finger, kb.key(pitch).top_z_m + LOW_M, pitch)
        tip = self.hand.tip_positions(up.q)[self.hand.fingers.index(finger)]
        lo, hi = exposed_range_x(pitch)
        over = lo - TRAVEL_INFLATE_M <= tip[0] <= hi + TRAVEL_INFLATE_M
        if up.converged or (over and tip[2] >= kb.key(pitch).top_z_m + LOW_M - PRESS_TOL_M):
            self._cache[(finger, pitch, seg, LOW_M)] = up.q
        else:
            self._cache[key] = (q, dataclasses.replace(r, converged=False))

    def above_q(self, finger: str, pitch: int, seg: int, height_m: float) -> np.ndarray:
        """``finger`` waiting ``height_m`` above the top of ``pitch``, straight above
        where it presses it, in hand position ``seg``; cached."""
        key = (finger, pitch, seg, height_m)
        if key not in self._cache:
            qp, _ = self.press_q(finger, pitch, seg)
            self._cache[key] = self._vertical(qp, finger, kb.key(pitch).top_z_m + height_m, pitch).q
        return self._cache[key]


def pair_table_path(urdf_sha256: str) -> Path:
    """Where the shipped ``Planner.pair_table`` of the hand with this URDF is."""
    return PAIR_TABLE_DIR / f"pairs-{urdf_sha256[:16]}.json"


def _shipped_table(hand: HandModel) -> dict:
    """``Planner.pair_table`` as shipped for this hand's URDF ({} if there is none)."""
    path = pair_table_path(hand.urdf_sha256)
    if not path.exists():
        return {}
    data = json.loads(path.read_text())
    return data if data.get("urdf_sha256") == hand.urdf_sha256 else {}


def _pair_answers(data: dict) -> dict:
    """``Planner.pair_ok``'s answers in a shipped table ``data`` ({} if none: they are then
    worked out when asked)."""
    out = {}
    for k, row in data.get("pairs", {}).items():
        f1, f2, pc = k.split()
        for iv, c in enumerate(row, start=data.get("first_interval", 0)):
            if c != "-":
                out[(f1, f2, int(pc), iv)] = c == "1"
    return out


def _key_crossing(hand: HandModel, qa: np.ndarray, qb: np.ndarray, finger: str, pitch: int,
                  depth_m: float = kb.DOWN_DEPTH_M) -> float:
    """Fraction of the duration of a min-jerk phase from ``qa`` to ``qb`` at which
    ``finger``'s tip passes ``depth_m`` below the top of ``pitch`` (default: the key-down
    depth; FK along the path)."""
    # only the arm's and this finger's joints move its tip: they key the cache
    js = np.concatenate([_arm_joints(hand), np.arange(hand.n)[hand.joint_slice(finger)]])
    key = (hand.urdf_sha256, finger, pitch, depth_m, qa[js].tobytes(), qb[js].tobytes())
    if key in _CROSSINGS:
        return _CROSSINGS[key]
    if len(_CROSSINGS) > 200_000:
        _CROSSINGS.clear()
    _CROSSINGS[key] = frac = _crossing(hand, qa, qb, finger, pitch, depth_m)
    return frac


_CROSSINGS: dict = {}


def _above_keys(tips: np.ndarray, margin_m: float) -> np.ndarray:
    """Per fingertip (rows of ``tips``, m): is it ``margin_m`` or more above the top of
    every key whose footprint, grown by ``TRAVEL_INFLATE_M``, holds it."""
    return tips[:, 2] >= surfaces_under(tips[:, 0], tips[:, 1], TRAVEL_INFLATE_M) + margin_m


def _least(values, ok) -> float:
    """The least of the increasing ``values`` for which ``ok`` holds, by bisection (``ok``
    of the last one is known true; a value found is always one ``ok`` accepted)."""
    lo, hi = -1, len(values) - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if ok(values[mid]):
            hi = mid
        else:
            lo = mid
    return values[hi]


def _arm_joints(hand: HandModel) -> np.ndarray:
    """The joints that belong to no finger (rail, wrist)."""
    if hand.urdf_sha256 not in _ARM:
        fj = {j for f in hand.fingers for j in np.arange(hand.n)[hand.joint_slice(f)]}
        _ARM[hand.urdf_sha256] = np.array([j for j in range(hand.n) if j not in fj], dtype=int)
    return _ARM[hand.urdf_sha256]


_ARM: dict[str, np.ndarray] = {}


def _crossing(hand: HandModel, qa: np.ndarray, qb: np.ndarray, finger: str, pitch: int,
              depth_m: float) -> float:
    k = hand.fingers.index(finger)
    z_cross = kb.key(pitch).top_z_m - depth_m
    u = np.linspace(0.0, 1.0, 17)
    s = min_jerk(u)
    z = np.array([hand.tip_positions(qa + (qb - qa) * si)[k, 2] for si in s]) - z_cross
    for i in range(len(u) - 1):
        if z[i] == 0.0:
            return float(u[i])
        if z[i] * z[i + 1] < 0.0:
            return float(u[i] + (u[i + 1] - u[i]) * z[i] / (z[i] - z[i + 1]))
    return 0.5


def plan_song(song: Song, hand: HandModel, out_path: str, rate_hz: float = 100.0,
              song_name: str = "", progress: bool = False, planner: Planner | None = None) -> PlayResult:
    """Plan ``song`` on ``hand`` and stream the trajectory to ``out_path`` ('-' = stdout)."""
    if not (math.isfinite(rate_hz) and 1.0 <= rate_hz <= 10000.0):
        raise InputError(f"--rate must be between 1 and 10000 Hz, got {rate_hz}")
    t_start = time.perf_counter()
    pl = planner or Planner(hand)
    pl._anchors.clear()  # (a planner reused for another song gives the same bytes as a new one)
    notes = list(song.notes)
    reasons: dict[int, str] = {}
    finger_of: dict[int, str] = {}
    rail_of: dict[int, float] = {}
    cut: list[tuple[int, float]] = []

    def parts():
        """The press intervals of each part of the song, fingered when the planner gets
        there: a long song starts streaming after its first part's fingering, not all."""
        for idx in _parts(notes):
            assignments, infeasible = assign_fingers([notes[i] for i in idx], pl.reach, pl.pair_ok)
            assignments = [dataclasses.replace(a, note_index=idx[a.note_index]) for a in assignments]
            reasons.update({idx[x.note_index]: x.reason for x in infeasible})
            finger_of.update({a.note_index: a.finger for a in assignments})
            rail_of.update({a.note_index: a.rail_m for a in assignments})
            cut.extend((a.note_index, notes[a.note_index].offset_s - a.release_s)
                       for a in assignments if a.release_s is not None)
            yield press_intervals(notes, assignments)

    selfcheck = SelfCheck(hand, rate_hz)
    writer = TrajectoryWriter(out_path, play_metadata(song, hand, rate_hz, song_name),
                              hand.joint_names, hand.motor_names, on_rows=selfcheck.add_rows)
    try:
        result = _run(pl, hand, notes, parts(), rail_of, writer, rate_hz, reasons, progress, t_start)
        cut_short = {i: f"cut short: let go {early:.2f} s early (its finger, or the hand, is "
                        "needed for the notes after it)" for i, early in cut}
        verdict = selfcheck.verdict(notes, {i: (SkipReason.LEFT_OUT, why) for i, why in
                                            {**cut_short, **reasons}.items()})
        writer.close(verdict.end_info())
    except BaseException as e:
        writer.abort(discard=isinstance(e, InputError))
        raise
    result.planning_s = time.perf_counter() - t_start
    result.cut = sorted(cut)
    result.verdict = verdict
    skipped = {s.note: s.detail for s in verdict.skipped}
    result.notes = [NoteReport(i, n.pitch, n.onset_s, finger_of.get(i), skipped.get(i))
                    for i, n in enumerate(notes)]
    return result


def _parts(notes) -> list[list[int]]:
    """Note indices (by onset) cut into parts of at least ``PART_NOTES`` notes (the first:
    ``FIRST_PART_NOTES``, so that the first rows come soon), each cut where every key is
    up for at least ``MOVE_S`` (so no press interval is shortened for a note of the next
    part). A song without such a pause is one part."""
    order = sorted(range(len(notes)), key=lambda i: (notes[i].onset_s, notes[i].pitch))
    out: list[list[int]] = [[]]
    end = -math.inf
    for i in order:
        if (len(out[-1]) >= (FIRST_PART_NOTES if len(out) == 1 else PART_NOTES)
                and notes[i].onset_s >= end + MOVE_S):
            out.append([])
        out[-1].append(i)
        end = max(end, notes[i].offset_s)
    return [p for p in out if p]


class _Timeline:
    """Builds the phase list in causal order, one finger (or the arm) at a time.

    Every finger is always in one of four places: at its place in the hand position
    (``rest``), high above the keys (``high``), waiting above a key (``LOW_M`` or
    ``HIGH_M`` over it), or pressing it. A press is: (if the finger is not already
    waiting above that key) up to ``HIGH_M`` above where it is, across to ``HIGH_M``
    above the key, then down onto the key, its key-down moment anchored on the note's
    onset; the release goes back to ``LOW_M``, anchored on the note's end. An idle
    finger is brought ``LOW_M`` above the key it strikes next (``prepare``), as early
    as it may. A change of hand position (``travel``) happens when every key is up:
    the fingers lift, the arm (rail and wrist) moves, the fingers land, with overlaps
    checked by simulation; nothing else moves until the arm stops, except a finger
    waiting above its key, which may start down but touches it only once the arm
    has stopped.

    Phases are numbered globally; ``phases`` holds the chunk not yet timed and
    ``carried`` the timed phases still running where the last chunk was cut.
    """

    def __init__(self, pl: Planner, hand: HandModel, q0: np.ndarray, seg: int | None, dt: float):
        self.pl, self.hand, self.dt = pl, hand, dt
        self.q = q0.copy()  # configuration reached so far (end of all phases)
        self.seg = seg
        self.place: dict[str, tuple] = {f: ("rest",) for f in hand.fingers}
        self.pre_pressed: set[int] = set()  # notes down in the very first row
        self.phases: list[tuple[Phase, str, int | None]] = []  # the chunk being planned
        self.offset = 0  # number of phases planned in earlier chunks (global index of phases[0])
        self.carried: list[tuple[int, Phase, float]] = []  # (global index, phase, start) still running at the last cut
        # the last travel's arm motions, as (global index, duration): nothing the travel's
        # simulation did not see starts before they end
        self.arm_motion: tuple[tuple[int, float], ...] = ()
        self.arm_deltas: dict[int, np.ndarray] = {}  # global index -> joint motion, of those
        self._land_ok: set[int] = set()  # the travel's landings a press may blend with
        self.travels = 0
        self.shifts = 0  # hand moves made while a key was held
        self.shift_from: dict[int, np.ndarray] = {}  # a shift's arm step (global index) -> where it starts
        self._blend_floor = 0  # no motion blends with one before this (global index)
        self.failure: str | None = None  # why the last press could not be made, if not reach
        self.arm_joints = _arm_joints(hand)

    def _move(self, q_new: np.ndarray, anchor: float, ideal: float, weight: float, kind: str,
              note: int | None, min_s: float = 0.0, order=None, follows=(), earliest: float = 0.0,
              pitch: int | None = None) -> None:
        d = q_new - self.q
        if not np.any(d) and order is None:
            return
        if self.arm_motion and not follows:
            # nothing moves that the travel's simulation did not see until the arm stops
            follows = self.arm_motion
        T = max(phase_duration(d, self.hand.velocity, self.hand.acceleration), min_s)
        blend_s, after = self._blend(d, T, kind, pitch) if order is None else (0.0, -1)
        if order is None:
            # a finger's motions come one after the other even where they move different
            # joints of it (a press bending one joint after a landing that moved others)
            order = self._whole_fingers(np.flatnonzero(d))
        self.phases.append((Phase(d, T, anchor, ideal, weight, earliest_s=earliest, order_joints=order,
                                  follows=follows, blend_s=blend_s, blend_after=after), kind, note))
        self.q = q_new.copy()

    def _blend(self, d: np.ndarray, T: float, kind: str, pitch: int | None) -> tuple[float, int]:
        """How long (s) a finger's new motion ``d`` (``T`` s; a ``move``, or a ``press`` of
        ``pitch``) may start before the finger's previous motion ends, and that motion's
        global index: one curve instead of a stop at every waypoint.

        Only a finger's own motions after the last change of hand position blend: a move
        after a move, the lift after a release once the key is up (straight up), a press
        after a move while the tip is still ``TRAVEL_CLEARANCE_M`` above its key (so the
        key goes down exactly when it would without the blend). For every overlap up to
        the one returned (every ``_SIM_DT_S``) the sum of the two motions stays within
        every joint's speed and acceleration limit, and the tip, sampled by forward
        kinematics, above the keys it passes as ``_finger_path_clear`` asks."""
        none = (0.0, -1)
        moved = np.flatnonzero(d)
        if kind not in ("move", "press") or moved.size == 0:
            return none
        finger = self._finger_of(moved)
        if finger is None:
            return none
        js = self.hand.joint_slice(finger)
        k = next((i for i in range(len(self.phases) - 1, -1, -1) if np.any(self.phases[i][0].delta[js])), None)
        if k is None or (self.offset + k < self._blend_floor and self.offset + k not in self._land_ok):
            return none
        prev, prev_kind, _ = self.phases[k]
        if np.any(np.delete(prev.delta, js)) or (prev_kind, kind) not in (
                ("move", "move"), ("release", "move"), ("move", "press")):
            return none
        Tp = prev.duration_s
        # (never three motions of a joint at once: the previous one's blend with the one
        # before it and this blend do not overlap)
        b_max = min(Tp - prev.blend_s, 0.5 * T)
        q_a = self.q - prev.delta  # the finger where its previous motion starts
        q_b = self.q + d
        if prev_kind == "release":
            # the lift starts once the key is up, and only straight up
            b_max = min(b_max, (1.0 - prev.anchor) * Tp)
            i = self.hand.fingers.index(finger)
            slide = self.hand.tip_positions(q_b)[i, :2] - self.hand.tip_positions(self.q)[i, :2]
            if np.hypot(*slide) > VERTICAL_SLIDE_M:
                return none
        if kind == "press":
            b_max = min(b_max, _key_crossing(self.hand, self.q, q_b, finger, pitch,
                                             depth_m=-TRAVEL_CLEARANCE_M) * T)
        if b_max < _SIM_DT_S:
            return none
        # speed and acceleration of the sum, every _SIM_DT_S of overlap
        vmax, amax = 0.995 * self.hand.velocity[js], 0.995 * self.hand.acceleration[js]
        dp, dq = prev.delta[js], d[js]
        o = np.arange(_SIM_DT_S, b_max + 1e-12, _SIM_DT_S)[:, None]  # (O, 1) overlaps
        t = Tp - o * (1.0 - np.linspace(0.0, 1.0, 16 + int(b_max / 0.001)))  # (O, M), from its start
        v1, a1 = min_jerk_rates(t / Tp)
        v2, a2 = min_jerk_rates((t - Tp + o) / T)
        v = np.abs(v1[..., None] * (dp / Tp) + v2[..., None] * (dq / T))  # (O, M, J)
        a = np.abs(a1[..., None] * (dp / Tp ** 2) + a2[..., None] * (dq / T ** 2))
        ok = np.all((v <= vmax) & (a <= amax), axis=(1, 2))
        n_ok = len(ok) if ok.all() else int(np.argmin(ok))  # overlaps up to the first that fails
        best = float(o[n_ok - 1, 0]) if n_ok else 0.0
        if prev_kind == "move" or kind == "move":
            # the tip's path over the keys, at a third, two thirds and all of the overlap
            while best >= _SIM_DT_S and not self._blend_clear(q_a, prev.delta, Tp, d, T, best, finger):
                best = math.floor(0.5 * best / _SIM_DT_S) * _SIM_DT_S
        return (best, self.offset + k) if best >= _SIM_DT_S else none

    def _blend_clear(self, q_a, dp, Tp, dq, T, b, finger) -> bool:
        i = self.hand.fingers.index(finger)
        qs = []
        for o in (b / 3.0, 2.0 * b / 3.0, b):
            t = np.linspace(Tp - o, Tp, 7)
            s1, s2 = min_jerk(t / Tp), min_jerk((t - Tp + o) / T)
            qs.extend(q_a + np.outer(s1, dp) + np.outer(s2, dq))
        tips = np.array([self.hand.tip_positions(q)[i] for q in self.hand.apply_couplings(np.array(qs))])
        return bool(np.all(_above_keys(tips, -GRAZE_M)))

    def _whole_fingers(self, joints: np.ndarray) -> np.ndarray:
        """``joints`` with every joint of each finger they touch."""
        out = set(joints.tolist())
        for f in self.hand.fingers:
            js = self.hand.joint_slice(f)
            if out.intersection(js.tolist()):
                out.update(js.tolist())
        return np.array(sorted(out), dtype=int)

    def _frame_edge(self, t_s: float) -> float:
        """Half a frame before the first frame at or after ``t_s``: a key that goes down
        (or up) then is down (or up) from exactly that frame on."""
        return math.ceil(t_s / self.dt - 1e-9) * self.dt - 0.5 * self.dt

    def _with_finger(self, finger: str, q_src: np.ndarray, q_into: np.ndarray | None = None) -> np.ndarray:
        js = self.hand.joint_slice(finger)
        q = (self.q if q_into is None else q_into).copy()
        q[js] = q_src[js]
        return q

    def _tip_z(self, q: np.ndarray, finger: str) -> float:
        return float(self.hand.tip_positions(q)[self.hand.fingers.index(finger), 2])

    def travel(self, seg: int, t_s: float, ready: dict[str, int] | None = None) -> bool:
        """Go to hand position ``seg``: every finger up, the arm (rail and wrist) across,
        every finger down to its place there, high above the keys (``ready``: finger ->
        pitch: above the key it presses next).

        The arm may start before the fingers are all the way up, and the fingers may
        start down before the arm has arrived: the least overlap is found by simulating
        the three motions (forward kinematics every ``_SIM_DT_S``) so that no fingertip
        comes within ``TRAVEL_CLEARANCE_M`` of a key top it moves over once the arm is
        moving. The fingers first stay as low as they are (a released key's finger
        ``LOW_M`` above it), then go up to ``HIGH_M``, then further to each of
        ``TRAVEL_LIFTS_M``, until the simulation finds the motion clear; the fingers
        that strike first land ``LOW_M`` above their keys if that is clear, else
        ``HIGH_M``. If nothing is clear, every fingertip goes to ``TRAVEL_SAFE_Z_M``
        and the wrist up to ``WRIST_TRAVEL_RAD``, the rail moves alone, then the wrist
        and the fingers come down; if even that is not clear, the hand stays (False)."""
        self._blend_floor = math.inf  # the travel's motions are timed by its own simulation
        try:
            return self._travel(seg, t_s, ready)
        finally:
            self._blend_floor = self.offset + len(self.phases)

    def _travel(self, seg: int, t_s: float, ready: dict[str, int] | None) -> bool:
        hand = self.hand
        self.travels += 1
        arm = self.arm_joints
        q_end = self.q.copy()
        q_end[arm] = self.pl.bases[seg][arm]
        ready = ready or {}
        for f in hand.fingers:
            js = hand.joint_slice(f)
            q_end[js] = (self.pl.above_q(f, ready[f], seg, HIGH_M) if f in ready
                         else self.pl.rest_high_q(f, seg))[js]
        # the fingers that strike first land LOW_M above their keys if they can
        q_low = q_end.copy()
        for f in ready:
            q_low = self._with_finger(f, self.pl.above_q(f, ready[f], seg, LOW_M), q_low)
        land_z = LOW_M
        # the fingers as they are (released keys left LOW_M below), else all up to HIGH_M
        last, lifts, q0, lifting = self._last_motions()
        c = self._travel_overlap(q0, lifts, q_low, ready)
        if c is None:
            for f in hand.fingers:
                self._release_high(f)
                self.go_high(f)
            last, lifts, q0, lifting = self._last_motions()
            c = self._travel_overlap(q0, lifts, q_low, ready)
        # or high above them, sooner, if that strikes sooner (a press from there waits for
        # a clear way down: ``_press_lag``)
        c_high = self._travel_overlap(q0, lifts, q_end, ready) if ready else None
        if c_high is not None and (c is None or self._strike_s(c_high, q0, lifts, q_end, ready, seg, True)
                                   < self._strike_s(c, q0, lifts, q_low, ready, seg, False)):
            land_z, c = HIGH_M, c_high
        elif c is None:
            land_z = HIGH_M
            c = self._travel_overlap(q0, lifts, q_end)
        else:
            q_end = q_low
        moving = arm
        q_final = None  # where the fingers go straight down to after landing, if not q_end
        # phase -> the arm's lag after its start (all of a motion that does not lift)
        arm_after = None if c is None else {g: c[0] if g in lifting else ph.duration_s
                                            for g, ph in last.items()}
        for z_up in TRAVEL_LIFTS_M:
            if c is not None:
                break
            # a second lift of every finger, higher, and higher still where the arm's move
            # (a wrist flexing) would bring the finger down
            q_up = self.q.copy()
            for f in hand.fingers:
                q_up = self.pl.lift_to(q_up, f, z_up)
                q_there = q_up.copy()
                q_there[arm] = q_end[arm]
                drop = z_up - self._tip_z(q_there, f)
                if drop > 0.0:
                    q_up = self.pl.lift_to(q_up, f, z_up + drop)
            c, arm_after = self._lift_again(q_up, arm, q_end, t_s)
            if c is None:
                # a finger's straight way down from there dips into a key: land as high
                # at the new place, then straight down
                q_end_up = q_end.copy()
                for f in hand.fingers:
                    q_end_up = self.pl.lift_to(q_end_up, f, z_up)
                if np.any(q_end_up != q_end):
                    c, arm_after = self._lift_again(q_up, arm, q_end_up, t_s)
                    if c is not None:
                        q_final, q_end = q_end, q_end_up
            if c is None:
                # a finger whose way down at the new place dips even from that high (from
                # curled in front of the keys to reaching over them) rides along lifted and
                # finds its own way there afterwards (``_across``, as when it plays)
                q_there = q_up.copy()
                q_there[arm] = q_end[arm]
                riders = [f for f in hand.fingers
                          if not self._finger_path_clear(q_there, q_end, f, base=q_there)]
                # (each must have a way there over the keys once the arm has stopped)
                if riders and all(self._high_path(self.pl.lift_to(q_there, f, TRAVEL_SAFE_Z_M),
                                                  self.pl.lift_to(q_end, f, TRAVEL_SAFE_Z_M),
                                                  f, ACROSS_SPLITS, base=q_there) is not None
                                  for f in riders):
                    q_land = q_end.copy()
                    for f in riders:
                        q_land = self._with_finger(f, q_up, q_land)
                    c, arm_after = self._lift_again(q_up, arm, q_land, t_s)
                    if c is not None:
                        q_end = q_land
                        ready = {f: p for f, p in ready.items() if f not in riders}
        if c is None:
            # last resort: every finger to TRAVEL_SAFE_Z_M and the wrist raised
            # (extended), the rail alone across, then the wrist and the fingers down
            q_up = self.q.copy()
            for f in hand.fingers:
                q_up = self.pl.lift_to(q_up, f, TRAVEL_SAFE_Z_M)
            wrist = [self.hand.index[n] for n in ("wrist_flex",) if n in self.hand.index]
            q_up[wrist] = np.maximum(self.hand.lower[wrist], WRIST_TRAVEL_RAD)
            moving = np.array([self.hand.index["rail"]]) if "rail" in self.hand.index else arm
            c, arm_after = self._lift_again(q_up, moving, q_end, t_s)
            if c is None:
                self.travels -= 1
                return False
        k_arm = len(self.phases)
        q_arm = self.q.copy()
        q_arm[moving] = self.pl.bases[seg][moving]
        self.arm_motion = ()
        self._move(q_arm, 0.5, t_s, 0.0, "travel", None,
                   follows=tuple((g, arm_after[g]) for g in sorted(arm_after)))
        T_arm = self.phases[k_arm][0].duration_s if len(self.phases) > k_arm else None
        if T_arm is not None:
            # nothing else moves before the arm has stopped
            self.arm_motion = ((self.offset + k_arm, T_arm),)
            self.arm_deltas = {self.offset + k_arm: self.phases[k_arm][0].delta}
        self._land_ok = set()
        for i, js in enumerate(self._land_groups(moving)):
            q_next = self.q.copy()
            q_next[js] = q_end[js]
            n = len(self.phases)
            c_k = c[2] if i < len(hand.fingers) and hand.fingers[i] in ready else c[1]
            follows = ((self.offset + k_arm, c_k * T_arm),) if T_arm is not None else ()
            self._move(q_next, 0.5, t_s, 0.0, "move", None, follows=follows)
            if len(self.phases) > n and np.intersect1d(js, self.arm_joints).size > 0:
                # the wrist coming down after a rail-only travel: it too must stop first
                self.arm_motion += ((self.offset + n, self.phases[n][0].duration_s),)
                self.arm_deltas[self.offset + n] = self.phases[n][0].delta
            elif len(self.phases) > n and i < len(hand.fingers) and hand.fingers[i] in ready and land_z == LOW_M:
                self._land_ok.add(self.offset + n)
        if q_final is not None:
            for f in hand.fingers:
                n = len(self.phases)
                self._move(self._with_finger(f, q_final), 0.5, t_s, 0.0, "move", None)
                if len(self.phases) > n and f in ready:
                    self._land_ok.add(self.offset + n)
        self.seg = seg
        for f in hand.fingers:
            self.place[f] = ("above", ready[f], land_z) if f in ready else ("high",)
        return True

    def _strike_s(self, c: tuple[float, float, float], q0: np.ndarray, lifts, q_end: np.ndarray,
                  ready: dict[str, int], seg: int, high: bool) -> float:
        """When (s after the lifts start) the last of the ``ready`` fingers would have its
        key down after the travel to ``q_end`` with overlaps ``c`` (``_travel_overlap``):
        its landing done, then its press from there (high: from ``HIGH_M``), started as
        ``_press_lag`` allows."""
        hand = self.hand
        q_up = q0 + sum((d for d, _ in lifts), np.zeros(hand.n))
        d_arm = np.zeros(hand.n)
        d_arm[self.arm_joints] = (q_end - q_up)[self.arm_joints]
        T_arm = phase_duration(d_arm, hand.velocity, hand.acceleration)
        last = 0.0
        for f, p in ready.items():
            d_land = np.zeros(hand.n)
            js = hand.joint_slice(f)
            d_land[js] = (q_end - q_up)[js]
            landed = c[0] + c[2] * T_arm + phase_duration(d_land, hand.velocity, hand.acceleration)
            q_press = self._with_finger(f, self.pl.press_q(f, p, seg)[0], q_end)
            T = phase_duration(q_press - q_end, hand.velocity, hand.acceleration)
            lag = self._press_lag(f, p, q_end, q_press, T, d_arm, T_arm, path=high)
            last = max(last, max(landed, c[0] + lag) + _key_crossing(hand, q_end, q_press, f, p) * T)
        return last

    def shift(self, seg: int, finger: str, pitch: int, t_s: float, budget_s: float) -> bool:
        """Move the arm to hand position ``seg`` while ``finger`` holds ``pitch`` down:
        the other fingers first go ``HIGH_M`` up (they are idle: no other key is down),
        then the arm goes there, the holding finger following it on its key: through
        ``n`` equal steps of the arm (1, 2 or 4, the fewest that do), the finger at each
        step where single-finger IK presses the key from there. Kept only if, sampled
        along it, the holding finger's tip stays on the part of its key no other key
        overhangs (``TRAVEL_INFLATE_M`` inside its sides), below the depth at which the key
        is down (by ``HOLD_SLACK_M``) and no more than ``HOLD_DEEPER_M`` below full dip
        (the key bed is 2 mm below it), every other tip ``TRAVEL_CLEARANCE_M`` above the
        keys under it, and the steps take no more than ``budget_s``. False (nothing added)
        otherwise."""
        hand = self.hand
        js_h = hand.joint_slice(finger)
        arm = self.arm_joints
        # the idle fingers as they would be once up
        q_up = self.q.copy()
        for f in hand.fingers:
            if f != finger:
                q_f, _ = self._high_q(f, q_up)
                q_up = q_up if q_f is None else q_f
        target = press_target(finger, pitch)
        q_end = q_up.copy()
        q_end[arm] = self.pl.bases[seg][arm]
        q_end[js_h] = self.pl.press_q(finger, pitch, seg)[0][js_h]
        for n in SHIFT_STEPS:
            path = [q_up]
            for i in range(1, n):
                q = q_up.copy()
                q[arm] = q_up[arm] + (i / n) * (q_end[arm] - q_up[arm])
                r = self.pl.ik.solve_finger(target, q)
                self.pl.ik_solves += 1
                if not r.converged:
                    break
                q[js_h] = r.q[js_h]
                path.append(q)
            else:
                path.append(q_end)
                T = sum(phase_duration(b - a, hand.velocity, hand.acceleration) for a, b in itertools.pairwise(path))
                if T > budget_s:
                    return False
                if all(self._held_clear(a, b, finger, pitch) for a, b in itertools.pairwise(path)):
                    break
        else:
            return False
        # the idle fingers up, then the arm's steps after them
        n0 = len(self.phases)
        for f in hand.fingers:
            if f != finger:
                self.go_high(f)
        follows = tuple((self.offset + i, self.phases[i][0].duration_s) for i in range(n0, len(self.phases)))
        self._blend_floor = math.inf
        for q in path[1:]:
            k_arm = len(self.phases)
            q_next = self.q.copy()
            q_next[arm], q_next[js_h] = q[arm], q[js_h]
            q_before = self.q.copy()
            self._move(q_next, 0.5, t_s, 0.0, "travel", None, follows=follows or self.arm_motion)
            follows = ()
            if len(self.phases) > k_arm:
                self.shift_from[self.offset + k_arm] = q_before
                self.arm_motion = ((self.offset + k_arm, self.phases[k_arm][0].duration_s),)
                self.arm_deltas = {self.offset + k_arm: self.phases[k_arm][0].delta}
        self._blend_floor = self.offset + len(self.phases)
        self._land_ok = set()
        self.seg = seg
        for f in hand.fingers:  # (held where they were over the old position: "high")
            if f != finger:
                self.place[f] = ("high",)
        self.shifts += 1
        return True

    def sweep_clear(self, j: int, d: np.ndarray, joints: np.ndarray, before: np.ndarray) -> bool:
        """Whether the fingertip moved by ``joints`` stays ``TRAVEL_CLEARANCE_M`` above the
        keys it passes over (sampled every ``PATH_STEP_M`` of its travel at least) when the
        shift's arm step ``j`` (index in the chunk) moves by ``d`` instead, from where it
        starts less ``before`` (the press it no longer makes), and both ends of that move
        are within the joint limits."""
        q0 = self.shift_from.get(self.offset + j)
        if q0 is None:
            return False
        q0 = q0 + before
        if not (self.hand.within_limits(q0) and self.hand.within_limits(q0 + d)):
            return False  # (a straight move between two places within the limits stays within)
        tips = self._tip_track(q0, q0 + d, self.hand.fingers.index(self._finger_of(joints)), 11)
        return bool(np.all(_above_keys(tips, TRAVEL_CLEARANCE_M)))

    def _tip_track(self, qa: np.ndarray, qb: np.ndarray, k: int, n_min: int, ends: bool = True) -> np.ndarray:
        """Fingertip ``k`` on the straight joint-space move from ``qa`` to ``qb``: at least
        ``n_min`` samples counting both ends (left out without ``ends``), no further apart
        than ``PATH_STEP_M`` of the tip's straight-line travel (the path itself bends: a
        long crossing may dip between coarse samples)."""
        hand = self.hand
        span = np.linalg.norm(hand.tip_positions(qb)[k] - hand.tip_positions(qa)[k])
        u = np.linspace(0.0, 1.0, max(n_min, math.ceil(span / PATH_STEP_M) + 2))
        return np.array([hand.tip_positions(hand.apply_couplings(qa + ui * (qb - qa)))[k]
                         for ui in (u if ends else u[1:-1])])

    def _finger_of(self, joints: np.ndarray) -> str | None:
        """The finger all of ``joints`` belong to (None if no one finger)."""
        return next((f for f in self.hand.fingers if np.all(np.isin(joints, self.hand.joint_slice(f)))), None)

    def _held_clear(self, qa: np.ndarray, qb: np.ndarray, finger: str, pitch: int) -> bool:
        """On the straight move from ``qa`` to ``qb`` (sampled), ``finger`` holds ``pitch``
        down (see ``shift``) and every other fingertip clears the keys under it."""
        hand = self.hand
        k = hand.fingers.index(finger)
        key = kb.key(pitch)
        lo, hi = exposed_range_x(pitch)
        others = [i for i in range(len(hand.fingers)) if i != k]
        for u in np.linspace(0.0, 1.0, 11):
            tips = hand.tip_positions(hand.apply_couplings(qa + u * (qb - qa)))
            x, z = tips[k, 0], tips[k, 2]
            if not (lo + TRAVEL_INFLATE_M <= x <= hi - TRAVEL_INFLATE_M
                    and key.top_z_m - kb.KEY_DIP_M - HOLD_DEEPER_M <= z <= key.top_z_m - kb.DOWN_DEPTH_M - HOLD_SLACK_M):
                return False
            if not np.all(_above_keys(tips[others], TRAVEL_CLEARANCE_M)):
                return False
        return True

    def _lift_again(self, q_up: np.ndarray, moving: np.ndarray, q_end: np.ndarray,
                    t_s: float) -> tuple[tuple | None, dict[int, float] | None]:
        """Lift every joint group the arm's move (``moving``) leaves out further, to
        ``q_up``, if the simulation finds the travel from there clear: the lift phases
        are added, each group's after its last motion (the wrist's only once every
        finger has finished: no key is down then). Returns the overlaps and, per phase
        the arm must wait for, its lag after that phase's start (a new lift: the
        simulated one; a finger not lifted again: its whole last motion); (None, None)
        and nothing added if the travel is not clear."""
        hand = self.hand
        extra = []
        for js in self._land_groups(moving):
            d = np.zeros(hand.n)
            d[js] = (q_up - self.q)[js]
            if np.any(d):
                extra.append((d, phase_duration(d, hand.velocity, hand.acceleration)))
        c = self._travel_overlap(self.q, extra, q_end, arm=moving)
        if c is None:
            return None, None
        # (the same phases as simulated, in the same order)
        before = {g: ph.duration_s for g, ph in self._last_motions()[0].items()}
        new = []
        for js in self._land_groups(moving):
            q_next = self.q.copy()
            q_next[js] = q_up[js]
            n = len(self.phases)
            wrist = np.intersect1d(js, self.arm_joints).size > 0
            self._move(q_next, 0.5, t_s, 0.0, "move", None,
                       follows=tuple(sorted(before.items())) if wrist else ())
            if len(self.phases) > n:
                new.append(self.offset + n)
        waits = {g: before[g] for g in self._last_motions()[0] if g in before}
        return c, waits | {g: c[0] for g in new}

    def _land_groups(self, arm: np.ndarray) -> list[np.ndarray]:
        """The joints landing together after the arm's move: each finger's, and the arm
        joints the move leaves out (the wrist, when only the rail travels)."""
        groups = [np.arange(self.hand.n)[self.hand.joint_slice(f)] for f in self.hand.fingers]
        rest = np.setdiff1d(self.arm_joints, arm)
        return groups + ([rest] if rest.size else [])

    def _last_motions(self) -> tuple[dict[int, Phase], list[tuple[np.ndarray, float]], np.ndarray, set[int]]:
        """Each finger's last motion (global index -> phase); the (delta, duration) of
        those that lift the fingertip, the configuration before them, and their indices. The arm may
        start while a lift still runs (the simulation sees it), but only after a motion
        that does not lift has ended: started early, it would be lower than simulated."""
        last: dict[int, Phase] = {}
        lifting: list[int] = []
        for i, f in enumerate(self.hand.fingers):
            js = self.hand.joint_slice(f)
            found = [(self.offset + k, ph) for k, (ph, _, _) in enumerate(self.phases) if np.any(ph.delta[js])]
            found = found or [(g, ph) for g, ph, _ in self.carried if np.any(ph.delta[js])]
            if found:
                g, ph = found[-1]
                last[g] = ph
                if self._tip_z(self.q, f) > self.hand.tip_positions(self.q - ph.delta)[i, 2]:
                    lifting.append(g)
        lifts = [(last[g].delta, last[g].duration_s) for g in sorted(lifting)]
        q0 = self.q - sum((d for d, _ in lifts), np.zeros(self.hand.n))
        return last, lifts, q0, set(lifting)

    def _travel_overlap(self, q0: np.ndarray, lifts: list[tuple[np.ndarray, float]],
                        q_end: np.ndarray, ready: dict[str, int] | None = None,
                        arm: np.ndarray | None = None) -> tuple[float, float, float] | None:
        """The most overlap that keeps every fingertip ``TRAVEL_CLEARANCE_M`` clear of the
        keys once the arm moves, as (the time after the start of each of the fingers'
        ``lifts`` (joint motions, durations, all from ``q0``) when the arm may start, the
        fraction of the arm's move before the fingers start down to their places in
        ``q_end``); the first as small as the fingers landing last allow, then the
        second. The simulation starts every lift at once: a lift that starts earlier
        is higher when the arm starts, so the arm waiting that long after each lift's
        start is on the safe side. A finger of ``ready`` (finger -> pitch) over the
        part of its key no other key overhangs need only clear that key; a finger leaving
        a key (above it when the travel begins: it may be on its way up from it) may be
        anywhere over that part of it, less ``TRAVEL_INFLATE_M`` on each side, above the
        depth at which the key is down (the key has come up with it, so its key-up
        moment stays the release's, and no other key is there). None if even no overlap keeps them
        clear."""
        hand = self.hand
        own: dict[int, list[tuple[float, float, float, bool]]] = {}
        for f, p in (ready or {}).items():
            own.setdefault(hand.fingers.index(f), []).append(exposed_range_x(p) + (kb.key(p).top_z_m, False))
        for f, place in self.place.items():
            if place[0] == "above":
                # (a floor for the tip, margin included: the key is up before the arm
                # moves, so its key-up moment stays the release's)
                lo, hi = exposed_range_x(place[1])
                own.setdefault(hand.fingers.index(f), []).append(
                    (lo + TRAVEL_INFLATE_M, hi - TRAVEL_INFLATE_M,
                     kb.key(place[1]).top_z_m - kb.DOWN_DEPTH_M + KEY_UP_SLACK_M, True))

        def clear(tips: np.ndarray, margin: np.ndarray) -> bool:
            """tips (N, 5, 3) at N samples, margin (N,)."""
            low = ~np.all(tips[:, :, 2] >= kb.BLACK_TOP_Z_M + margin[:, None], axis=1)
            if not low.any():
                return True  # above every key top
            tips, margin = tips[low], margin[low]
            n = len(tips)
            surface = surfaces_under(tips[:, :, 0].ravel(), tips[:, :, 1].ravel(), TRAVEL_INFLATE_M).reshape(n, -1)
            for k, regions in own.items():
                x = tips[:, k, 0]
                mine = np.full(n, np.inf)
                for lo, hi, top, floor in regions:
                    # (a floor: the margin does not add to it)
                    top_k = top - margin if floor else np.full(n, top)
                    mine = np.where((lo <= x) & (x <= hi), np.minimum(mine, top_k), mine)
                surface[:, k] = np.where(mine < np.inf, mine, surface[:, k])
            return bool(np.all(tips[:, :, 2] >= surface + margin[:, None]))

        arm = self.arm_joints if arm is None else arm
        q_up = q0 + sum((d for d, _ in lifts), np.zeros(hand.n))
        d_arm = np.zeros(hand.n)
        d_arm[arm] = (q_end - q_up)[arm]
        T_arm = phase_duration(d_arm, hand.velocity, hand.acceleration)
        land = []
        for js in self._land_groups(arm):
            d = np.zeros(hand.n)
            d[js] = (q_end - q_up)[js]
            land.append((d, phase_duration(d, hand.velocity, hand.acceleration)))
        D_lift = np.array([d for d, _ in lifts]).reshape(-1, hand.n)
        T_lift = np.array([T for _, T in lifts])
        D_land = np.array([d for d, _ in land]).reshape(-1, hand.n)
        T_land = np.array([T for _, T in land])
        # a landing starts no sooner than the lift of the same joints ends
        after_lift = np.array([max((T for d_l, T in lifts if np.any(d_l[np.abs(d) > 0])), default=0.0)
                               for d, _ in land])

        is_ready = np.array([k < len(hand.fingers) and hand.fingers[k] in (ready or {})
                             for k in range(len(land))], dtype=bool)

        def safe(c_lift: float, c_land: float, c_ready: float | None = None) -> bool:
            x_arm = float(np.max(c_lift * T_lift, initial=0.0))
            c_k = np.where(is_ready, c_land if c_ready is None else c_ready, c_land)
            x_land = np.maximum(x_arm + c_k * T_arm, after_lift)
            # the lifts as late as the arm allows (all starting at 0): the fingers at their
            # lowest when the arm starts; and, where that delays a landing, the lifts long
            # over: the landings at their earliest
            cases = [(q0, 1.0, x_land)]
            if np.any(x_land > x_arm + c_k * T_arm):
                cases.append((q0 + D_lift.sum(axis=0), 0.0, x_arm + c_k * T_arm))
            return all(run(x_arm, q_from, lifting, x_l) for q_from, lifting, x_l in cases)

        def run(x_arm: float, q_from: np.ndarray, lifting: float, x_land: np.ndarray) -> bool:
            t_end = max(x_arm + T_arm, float(np.max(x_land + T_land, initial=0.0)))
            t = np.arange(x_arm, t_end + _SIM_DT_S, _SIM_DT_S)
            Q = (q_from + lifting * min_jerk(t[:, None] / T_lift[None, :]) @ D_lift
                 + min_jerk((t - x_arm) / T_arm)[:, None] * d_arm[None, :]
                 + min_jerk((t[:, None] - x_land[None, :]) / T_land[None, :]) @ D_land)
            Q = hand.apply_couplings(Q)
            # once the arm has stopped, the fingers come down onto their new places: no
            # margin then, only no contact
            margin = np.where(t <= x_arm + T_arm, TRAVEL_CLEARANCE_M, 0.0)
            # every 5th sample first: a dip shows there sooner
            for idx in (np.arange(0, len(Q), 5), np.setdiff1d(np.arange(len(Q)), np.arange(0, len(Q), 5))):
                if not clear(np.array([hand.tip_positions(Q[i]) for i in idx]).reshape(len(idx), -1, 3), margin[idx]):
                    return False
            return True

        # the arm as early as the lifts allow (fingers down only after it stops), then
        # the fingers down as early as that allows
        if not safe(1.0, 1.0):
            return None
        c_lift = _least(TRAVEL_OVERLAPS, lambda c: safe(c, 1.0))
        c_land = _least(TRAVEL_OVERLAPS, lambda c: safe(c_lift, c))
        # the fingers that strike first may come down sooner still
        options = [c for c in TRAVEL_OVERLAPS if c <= c_land]
        c_ready = _least(options, lambda c: safe(c_lift, c_land, c)) if is_ready.any() else c_land
        return float(np.max(c_lift * T_lift, initial=0.0)), c_land, c_ready

    def _release_high(self, finger: str) -> None:
        """If ``finger``'s last motion was a release to ``LOW_M``, make it a release
        straight to ``HIGH_M`` (one motion instead of two before the hand travels)."""
        pl = self.place[finger]
        if pl[0] != "above" or pl[2] != LOW_M:
            return
        js = self.hand.joint_slice(finger)
        for k in range(len(self.phases) - 1, -1, -1):
            ph, kind, note = self.phases[k]
            if not np.any(ph.delta[js]):
                continue
            if kind != "release" or np.any(np.delete(ph.delta, js)):
                return
            q_from = self.q - ph.delta
            q_new = self._with_finger(finger, self.pl.above_q(finger, pl[1], self.seg, HIGH_M))
            d = q_new - q_from
            frac = _key_crossing(self.hand, q_from, q_new, finger, pl[1])
            T = phase_duration(d, self.hand.velocity, self.hand.acceleration)
            self.phases[k] = (dataclasses.replace(ph, delta=d, duration_s=T, anchor=frac), kind, note)
            self.q = self.q + (d - ph.delta)
            self.place[finger] = ("above", pl[1], HIGH_M)
            return

    def go_high(self, finger: str) -> None:
        """Lift ``finger`` straight up to ``HIGH_M`` above the white keys' top, from wherever it is."""
        q, place = self._high_q(finger)
        if q is not None:
            self._move(q, 0.5, 0.0, 0.0, "move", None)
            self.place[finger] = place

    def _high_q(self, finger: str, q_into: np.ndarray | None = None) -> tuple[np.ndarray | None, tuple]:
        """``q_into`` (default: where the hand is) with ``finger`` where ``go_high`` takes
        it, and its place then; (None, its place) if it is that high already."""
        pl = self.place[finger]
        if pl[0] == "high" or (pl[0] == "above" and pl[2] == HIGH_M):
            return None, pl
        if pl[0] == "rest":
            return self._with_finger(finger, self.pl.rest_high_q(finger, self.seg), q_into), ("high",)
        return (self._with_finger(finger, self.pl.above_q(finger, pl[1], self.seg, HIGH_M), q_into),
                ("above", pl[1], HIGH_M))

    def press(self, finger: str, pitch: int, t_s: float, note: int, velocity: int) -> bool:
        qp, r = self.pl.press_q(finger, pitch, self.seg)
        if not r.converged:
            return False
        if self.place[finger] != ("above", pitch, LOW_M):
            self.go_high(finger)
            if not self._across(finger, self.pl.above_q(finger, pitch, self.seg, HIGH_M), t_s):
                self.failure = "no way over the keys to it"
                return False
        q_new = self._with_finger(finger, qp)
        frac = _key_crossing(self.hand, self.q, q_new, finger, pitch)
        # the key goes down just before the first frame of the note
        # MIDI velocity sets the key speed: no faster than descent_time_s per 30 mm
        drop = max(self._tip_z(self.q, finger) - self._tip_z(q_new, finger), 0.0)
        T = max(phase_duration(q_new - self.q, self.hand.velocity, self.hand.acceleration),
                descent_time_s(velocity) * drop / 0.030)
        follows = ()
        if self.arm_motion and self.place[finger] == ("above", pitch, LOW_M):
            # waiting right above its key: it may start down while the arm still moves,
            # but come within TRAVEL_CLEARANCE_M of it only once the arm has (all but) stopped
            follows = tuple((g, self._press_lag(finger, pitch, self.q, q_new, T, self.arm_deltas[g], T_arm))
                            for g, T_arm in self.arm_motion)
        elif len(self.arm_motion) == 1 and self.place[finger] == ("above", pitch, HIGH_M):
            # landed high above its key: the same, once the way down is clear of the keys
            g, T_arm = self.arm_motion[0]
            follows = ((g, self._press_lag(finger, pitch, self.q, q_new, T, self.arm_deltas[g], T_arm,
                                           path=True)),)
        self._move(q_new, frac, self._frame_edge(t_s), 1.0, "press", note, min_s=T, follows=follows,
                   earliest=self._frame_edge(t_s) - EARLY_FRAMES * self.dt - frac * T, pitch=pitch)
        self.place[finger] = ("down", pitch)
        return True

    def _press_lag(self, finger: str, pitch: int, q_above: np.ndarray, q_press: np.ndarray, T: float,
                   d_arm: np.ndarray, T_arm: float, path: bool = False) -> float:
        """The earliest start (s after the start of the arm's last motion, ``d_arm`` in
        ``T_arm`` s) of ``finger``'s press from ``q_above`` (the arm's motion done) to
        ``q_press`` (``T`` s) at which its tip comes within ``TRAVEL_CLEARANCE_M`` of its
        key only once what is left of the arm's motion moves it less than ``ARRIVE_M``;
        with ``path``, also staying ``TRAVEL_CLEARANCE_M`` above every key it passes over
        until then (over the part of its own key no other key overhangs, that key's top),
        by forward kinematics every ``_SIM_DT_S``, the start tried every ``PRESS_LAG_STEP_S``
        (a later start is clearer: less of the arm's motion is left). Without ``path`` the
        tip is ``LOW_M`` above that part of its key already (the travel's simulation)."""
        hand = self.hand
        k = hand.fingers.index(finger)
        touch = _key_crossing(hand, q_above, q_press, finger, pitch, depth_m=-TRAVEL_CLEARANCE_M)
        tip = hand.tip_positions(q_above)[k]
        dist = float(np.linalg.norm(tip - hand.tip_positions(q_above - d_arm)[k]))
        arrive = 0.0
        if dist > ARRIVE_M:
            lo, hi = 0.0, 1.0  # min-jerk progress s(u) >= 1 - ARRIVE_M / dist
            for _ in range(30):
                mid = 0.5 * (lo + hi)
                if 1.0 - float(min_jerk(np.array(mid))) <= ARRIVE_M / dist:
                    hi = mid
                else:
                    lo = mid
            arrive = hi * T_arm
        lag = max(arrive - touch * T, 0.0)
        if not path:
            return lag
        x_lo, x_hi = exposed_range_x(pitch)
        top = kb.key(pitch).top_z_m
        d_press = q_press - q_above
        while lag < T_arm:
            tau = np.arange(lag, min(lag + touch * T, T_arm), _SIM_DT_S)  # (up to the touch)
            Q = (q_above[None, :] - (1.0 - min_jerk(tau / T_arm))[:, None] * d_arm[None, :]
                 + min_jerk((tau - lag) / T)[:, None] * d_press[None, :])
            tips = np.array([hand.tip_positions(q)[k] for q in hand.apply_couplings(Q)])
            under = surfaces_under(tips[:, 0], tips[:, 1], TRAVEL_INFLATE_M)
            under = np.where((x_lo <= tips[:, 0]) & (tips[:, 0] <= x_hi), top, under)
            if np.all(tips[:, 2] >= under + TRAVEL_CLEARANCE_M):
                return lag
            lag += PRESS_LAG_STEP_S
        return T_arm

    def wait_above(self, finger: str, pitch: int) -> None:
        """Before anything moves (the start configuration): an idle ``finger`` waits
        ``LOW_M`` above ``pitch``, the key it presses next, if it reaches it from here."""
        if self.seg is None or self.phases or self.place[finger][0] == "down":
            return
        if self.pl.press_q(finger, pitch, self.seg)[1].converged:
            self.q = self._with_finger(finger, self.pl.above_q(finger, pitch, self.seg, LOW_M))
            self.place[finger] = ("above", pitch, LOW_M)

    def prepare(self, finger: str, pitch: int) -> None:
        """Bring an idle ``finger`` to wait ``LOW_M`` above ``pitch``, the key it presses
        next, as early as it may (no timing wish: the timing QP starts it at once)."""
        pl = self.place[finger]
        if pl[0] == "down" or pl == ("above", pitch, LOW_M) or self.seg is None:
            return
        if not self.pl.press_q(finger, pitch, self.seg)[1].converged:
            return
        if pl != ("above", pitch, HIGH_M):
            self.go_high(finger)
            if not self._across(finger, self.pl.above_q(finger, pitch, self.seg, HIGH_M), 0.0):
                return  # (no clear way there: it stays up)
        self._move(self._with_finger(finger, self.pl.above_q(finger, pitch, self.seg, LOW_M)),
                   0.5, 0.0, 0.0, "move", None)
        self.place[finger] = ("above", pitch, LOW_M)

    def _finger_path_clear(self, qa: np.ndarray, qb: np.ndarray, finger: str,
                           base: np.ndarray | None = None) -> bool:
        """True if ``finger``'s tip stays above every key it passes over (footprints grown
        ``TRAVEL_INFLATE_M``; it may graze a top by ``GRAZE_M``, half the depth at which a
        key sounds) on the straight joint-space move from ``qa`` to ``qb`` (the rest of
        the hand as in ``base``, default where it is now)."""
        k = self.hand.fingers.index(finger)
        # (the straight move of this finger's joints alone, the rest of the hand as in base)
        tips = self._tip_track(self._with_finger(finger, qa, base), self._with_finger(finger, qb, base), k, 9,
                               ends=False)
        return bool(np.all(_above_keys(tips, -GRAZE_M)))

    def _across(self, finger: str, q_to: np.ndarray, t_s: float) -> bool:
        """Move ``finger`` (up already) sideways to its joints in ``q_to``; if the straight
        move would dip into a key, over the top: up to ``TRAVEL_SAFE_Z_M``, across (through
        waypoints if need be), down. Nothing moves when every way dips (False)."""
        q_to = self._with_finger(finger, q_to)
        if self._finger_path_clear(self.q, q_to, finger):
            self._move(q_to, 0.5, t_s, 0.0, "move", None)
            return True
        up_a = self.pl.lift_to(self.q, finger, TRAVEL_SAFE_Z_M)
        up_b = self._with_finger(finger, self.pl.lift_to(q_to, finger, TRAVEL_SAFE_Z_M))
        path = self._high_path(up_a, up_b, finger, ACROSS_SPLITS)
        if path is None:
            return False
        for q in [up_a] + path + [q_to]:
            self._move(q, 0.5, t_s, 0.0, "move", None)
        return True

    def _high_path(self, qa: np.ndarray, qb: np.ndarray, finger: str, splits: int,
                   base: np.ndarray | None = None) -> list | None:
        """Waypoints after ``qa`` to ``qb`` (both high) along which ``finger`` stays clear
        of the keys: straight, else through a waypoint lifted to ``TRAVEL_SAFE_Z_M`` from
        the joint-space midpoint, each half alike (``splits`` levels); None if none."""
        if self._finger_path_clear(qa, qb, finger, base):
            return [qb]
        if splits == 0:
            return None
        mid = self.pl.lift_to(self.hand.apply_couplings(0.5 * (qa + qb)), finger, TRAVEL_SAFE_Z_M)
        first = self._high_path(qa, mid, finger, splits - 1, base)
        second = self._high_path(mid, qb, finger, splits - 1, base) if first is not None else None
        return None if second is None else first + second

    def snapshot(self) -> dict:
        """The timeline's state, to go back to (``restore``) when motions added are undone."""
        return {k: (v.copy() if isinstance(v, (np.ndarray, list, dict, set)) else v)
                for k, v in self.__dict__.items()}

    def restore(self, state: dict) -> None:
        self.__dict__.update(state)

    def release(self, finger: str, pitch: int, t_s: float, note: int | None = None) -> None:
        q_new = self._with_finger(finger, self.pl.above_q(finger, pitch, self.seg, LOW_M))
        frac = _key_crossing(self.hand, self.q, q_new, finger, pitch)
        # up just before the first frame after the note
        self._move(q_new, frac, self._frame_edge(t_s), RELEASE_WEIGHT, "release", note)
        self.place[finger] = ("above", pitch, LOW_M)

    def rest_all(self, t_s: float) -> None:
        """At the end every finger lifts off the keys."""
        if self.seg is None:
            return
        for f in self.hand.fingers:
            self.go_high(f)


SHIFT_GAP_S = 0.25  # the hand moves while a key is held when the next notes come this soon after
SHIFT_BUDGET_S = 0.1  # ... and the held note is at least this much longer than the move
REFIT_MIN_M = 0.002  # a hand position is sought at a rail refitted to its window if that moves it this far
WINDOW_NOTES = 200  # a new hand position is chosen for at most this many notes ahead


def _window(events, group, t: float, rail: float, rail_of: dict[int, float],
            reasons: dict[int, str]) -> list:
    """The presses the hand position chosen at ``t`` should serve: those after ``t`` that
    the fingering plays at the same rail position (at most ``WINDOW_NOTES``)."""
    out = []
    for e in events:
        if e[1] != 1 or e[0] <= t + 1e-9 or e[3].press.note_index in reasons:
            continue
        q_ = e[3].press
        if abs(rail_of[q_.note_index] - rail) > 1e-9 or len(out) >= WINDOW_NOTES:
            break
        out.append(q_)
    return out


def _covered(pl: Planner, seg: int, window) -> int:
    """How many presses of ``window``, in order, the fingers reach from hand position
    ``seg`` without moving the arm."""
    for k, p in enumerate(window):
        if not pl.press_q(p.finger, p.pitch, seg)[1].converged:
            return k
    return len(window)


def _centroid_target(finger: str, pitches) -> PressTarget:
    """A press target in the middle of ``finger``'s press points on ``pitches`` (their
    mean), free to slide along the keys where all of them allow."""
    ts = [press_target(finger, p) for p in pitches]
    pts = np.array([t.point_m for t in ts])
    lo = max(t.y_range_m[0] for t in ts)
    hi = min(t.y_range_m[1] for t in ts)
    x, y, z = pts.mean(axis=0)
    if lo > hi:
        lo = hi = float(y)
    return PressTarget(finger, ts[0].pitch, (float(x), float(y), float(z)), (lo, hi))


def _best_position(pl: Planner, tl: _Timeline, events, group, t: float, rail: float,
                   rail_of: dict[int, float], reasons: dict[int, str],
                   held: PressTarget | None = None) -> tuple[int | None, int]:
    """The candidate hand position for ``group`` (see ``_reposition``) whose fingers reach
    the most presses of the window, in order, and that number; with ``held``, a finger
    that keeps its key down there too (its later keys in the window left out of the
    shape). (None, 0) if none serves the group."""
    busy = {g.finger for g in group}
    window = list(group) + _window(events, group, t, rail, rail_of, reasons)
    first: dict[str, PressTarget] = {}
    keys: dict[str, list[int]] = {}
    for q_ in window:
        if held is not None and q_.finger == held.finger:
            continue
        if q_.finger not in busy:
            first.setdefault(q_.finger, press_target(q_.finger, q_.pitch))
        if q_.pitch not in keys.setdefault(q_.finger, []):
            keys[q_.finger].append(q_.pitch)
    presses = [press_target(g.finger, g.pitch) for g in group] + ([held] if held is not None else [])
    candidates = [(presses, (), list(first.values()))]
    if any(len(ps) > 1 for ps in keys.values()):
        candidates.append(([held] if held is not None else [],
                           (), [_centroid_target(f, ps) for f, ps in keys.items()]))
    candidates.append((presses, list(first.values()), ()))
    candidates.append((presses, (), ()))  # the group alone, every other finger hovering
    seg = None
    best = len(group) - 1  # a position must at least serve the group itself
    # at the fingering's rail position; where none there serves more than the group (the
    # fingering's lateral model is generous), also at the rail that puts the fingers
    # nearest their first keys of the window
    fingers = [g.finger for g in group] + list(first)
    xs = np.array([kb.key(g.pitch).center_x_m for g in group] + [kb.key(p.pitch).center_x_m for p in first.values()])
    for r_ in (rail, fit_rail(fingers, xs, pl.reach)[0]):
        if r_ != rail and (best > len(group) or len(window) == len(group) or abs(r_ - rail) < REFIT_MIN_M):
            break
        # from where the hand is (it moves least), else from the natural hand at that rail
        # (a wrist twisted far by earlier positions may leave no shape within reach)
        seg_before = seg
        for q_from in (tl.q, None):
            for targets, upcoming, chord in candidates:
                s_ = pl.anchor(targets, r_, q_from, upcoming, chord)
                if s_ is None:
                    continue
                c = _covered(pl, s_, window)
                if c > best:
                    seg, best = s_, c
                if c == len(window):
                    break
            if seg is not seg_before:
                break
    return seg, (best if seg is not None else 0)


def _reposition(pl: Planner, tl: _Timeline, events, group, t: float, rail: float,
                rail_of: dict[int, float], reasons: dict[int, str]) -> None:
    """Move the hand to a new position for the notes of ``group`` (struck at ``t``): a
    whole-hand IK with them pressed and the fingers that play next waiting above their
    keys; the hand travels there (or starts there, before t = 0).

    Candidate positions, tried in turn until one serves every press of the window (the
    presses after ``t`` that the fingering plays at this rail position): the hand in the
    shape of a chord of every finger it uses there on its first key, or on the middle
    of its keys, or (the fingers only waiting above their next keys) the group alone.
    The one from which the fingers alone reach the most of those presses, in order, is
    kept, so that the hand moves again as late as possible."""
    seg, _ = _best_position(pl, tl, events, group, t, rail, rail_of, reasons)
    if seg is None and len(group) > 1:
        # the chord whole is beyond the hand here: as much of it as it holds, from the
        # bottom (at least the lowest note); the rest is named
        for n in range(len(group) - 1, 0, -1):
            seg = pl.anchor([press_target(g.finger, g.pitch) for g in group[:n]], rail, tl.q)
            if seg is not None:
                xs = [kb.key(g.pitch).center_x_m for g in group]
                for g in group[n:]:
                    reasons.setdefault(g.note_index, f"chord wider than the hand here "
                                       f"({(max(xs) - min(xs)) * 1000:.0f} mm): left out")
                break
    if seg is None:
        return
    if tl.seg is None:  # the hand is brought there before t = 0
        tl.q = pl.bases[seg].copy()
        tl.seg = seg
        for g in group:  # with the first fingers just above their keys (those that reach)
            if not pl.press_q(g.finger, g.pitch, seg)[1].converged:
                continue
            tl.q = tl._with_finger(g.finger, pl.above_q(g.finger, g.pitch, seg, LOW_M))
            tl.place[g.finger] = ("above", g.pitch, LOW_M)
            if t < START_PRESSED_S:  # a song that starts at once starts with its keys down
                tl.q = tl._with_finger(g.finger, pl.press_q(g.finger, g.pitch, seg)[0])
                tl.place[g.finger] = ("down", g.pitch)
                tl.pre_pressed.add(g.note_index)
    elif not tl.travel(seg, t, {g.finger: g.pitch for g in group
                                if pl.press_q(g.finger, g.pitch, seg)[1].converged}):
        for g in group:
            reasons.setdefault(g.note_index, "no path of the hand there keeps the fingers clear of "
                               "the keys")


def _shift_while_held(pl: Planner, tl: _Timeline, events, k: int, groups, rail_of, reasons,
                      iv, notes, late_s=None) -> None:
    """Before the last held key (event ``k``, interval ``iv``) is let go of, if the next
    notes need a new hand position and come soon after, move the hand there while that
    key is still held: to a position (whole-hand IK) from which its finger still holds it
    and the next notes' fingers reach theirs; the holding finger follows the arm on its
    key (``_Timeline.shift``). Saves the lift-travel-land between legato notes. The move
    must fit in the note less ``SHIFT_BUDGET_S`` and less what of it a late key-down takes
    (``late_s``: the chunk timed as it is), and is undone if the chunk, timed with it and
    the release after it, would let the key up late: a key still down after its note is a
    wrong note."""
    if tl.seg is None:
        return
    t = events[k][0]
    nxt = next((e for e in events[k + 1:] if e[1] == 1), None)
    if nxt is None or nxt[0] - t > SHIFT_GAP_S:
        return
    group = [g for g in groups[nxt[0]] if g.note_index not in reasons]
    h = iv.press
    if len(group) != 1 or any(g.finger == h.finger for g in group) or all(
            pl.press_q(g.finger, g.pitch, tl.seg)[1].converged for g in group):
        return
    n = notes[h.note_index]
    rail = rail_of[group[0].note_index]
    budget = n.offset_s - n.onset_s - SHIFT_BUDGET_S
    t_rail = 0.0  # (the rail's own move alone must fit)
    if pl.rail is not None:
        d = abs(rail - float(tl.q[pl.rail]))
        t_rail = phase_duration(np.array([d]), pl.hand.velocity[[pl.rail]], pl.hand.acceleration[[pl.rail]])
    if t_rail > budget:
        return
    if late_s is not None:
        budget -= late_s(h.note_index, "press")
        if t_rail > budget:
            return
    held = press_target(h.finger, h.pitch)
    if pl.anchor([press_target(g.finger, g.pitch) for g in group] + [held], rail, tl.q) is None:
        return  # (the plainest shape first: the search below tries it last)
    # a position that serves the next notes as far as the one the hand would travel to
    seg, c = _best_position(pl, tl, events[k + 1:], group, nxt[0], rail, rail_of, reasons, held=held)
    if seg is None or c < _best_position(pl, tl, events[k + 1:], group, nxt[0], rail, rail_of, reasons)[1]:
        return
    before = tl.snapshot()
    if tl.shift(seg, h.finger, h.pitch, t, budget_s=budget) and late_s is not None:
        shifted = tl.snapshot()
        tl.release(h.finger, h.pitch, t, h.note_index)
        late = late_s(h.note_index, "release") > 0.5 * tl.dt
        tl.restore(before if late else shifted)


def _drop_hopeless(phases: list[Phase], meta: list, starts: np.ndarray, notes,
                   reasons: dict[int, str], dt: float, hand_v: np.ndarray, hand_a: np.ndarray,
                   sweep_clear=None) -> bool:
    """Notes whose key the timing QP can put down only after half of the note is over are
    left out (named in ``reasons``): struck that late they would mostly sound after
    their time, as wrong notes, and delay the notes after them. The press and its
    release become one motion from where the press started to where the release ends
    (both over the key), so every later motion still starts where it did. Returns True
    if any was left out (``phases`` and ``meta`` are changed in place)."""
    dropped = False
    for k, (p, kind, note) in enumerate(meta):
        if kind != "press" or note is None:
            continue
        n = notes[note]
        r = next((j for j in range(k + 1, len(meta)) if meta[j][1] == "release" and meta[j][2] == note), None)
        if r is None:
            continue
        late_down = starts[k] + p.anchor * p.duration_s - p.ideal_s > DROP_LATE * (n.offset_s - n.onset_s)
        # a key still down in the first frame after its note is a wrong press
        late_up = starts[r] + phases[r].anchor * phases[r].duration_s > phases[r].ideal_s + 0.5 * dt - 1e-9
        if not (late_down or late_up):
            continue
        d = phases[k].delta + phases[r].delta
        # (the sum of the two durations keeps the sum of the two moves within every limit)
        T = phases[k].duration_s + phases[r].duration_s
        own = p.order_joints if p.order_joints is not None else p.joints
        moves = [j for j in range(k + 1, r) if np.any(phases[j].delta[own])]
        if moves:
            # the hand moved while the key was to be held (``shift``): the finger goes from
            # where the press started to where the release ends during the arm's first
            # step instead (between two places within its limits), and no longer presses;
            # or it follows the arm's steps above its key; only if its tip then clears the
            # keys it passes over (``sweep_clear``), else the note is kept, late as it is
            fj = np.zeros_like(d, dtype=bool)
            fj[own] = True
            total = d + sum((phases[j].delta * fj for j in moves), np.zeros_like(d))
            d0 = np.where(fj, total, phases[moves[0]].delta)
            if sweep_clear is not None and sweep_clear(moves[0], d0, own, -phases[k].delta):
                for i, j in enumerate(moves):
                    dj = d0 if i == 0 else np.where(fj, 0.0, phases[j].delta)
                    Tj = max(phases[j].duration_s, phase_duration(dj, hand_v, hand_a))
                    phases[j] = dataclasses.replace(phases[j], delta=dj, duration_s=Tj)
                    meta[j] = (phases[j],) + tuple(meta[j][1:])
                phases[r] = dataclasses.replace(phases[r], delta=np.zeros_like(d), weight=0.0)
            elif sweep_clear is not None and all(sweep_clear(j, phases[j].delta, own, -phases[k].delta)
                                                 for j in moves):
                # else the finger need not press to follow the arm: from where the press
                # would have started (above its key), the arm's steps as planned keep it
                # over its key, clear of every key; at the end it goes where the release
                # would have taken it
                T_r = max(phases[r].duration_s, phase_duration(d, hand_v, hand_a))
                phases[r] = dataclasses.replace(phases[r], delta=d, duration_s=T_r, weight=0.0)
            else:
                continue
            phases[k] = dataclasses.replace(phases[k], delta=np.zeros_like(d), weight=0.0,
                                            blend_s=0.0, blend_after=-1)
        else:
            # (no blend with the motion before: it was checked against the press alone)
            phases[k] = dataclasses.replace(phases[k], delta=d, duration_s=T, anchor=0.5, weight=0.0,
                                            blend_s=0.0, blend_after=-1)
            phases[r] = dataclasses.replace(phases[r], delta=np.zeros_like(d), weight=0.0)
        for j in range(r + 1, len(phases)):  # (a blend with the release was checked against it alone)
            if phases[j].blend_after in (k, r):
                phases[j] = dataclasses.replace(phases[j], blend_s=0.0, blend_after=-1)
                meta[j] = (phases[j],) + tuple(meta[j][1:])
        meta[k] = (phases[k], "move", None)
        meta[r] = (phases[r], "move", None)
        reasons[note] = ("too late: the finger cannot get there before half of it is over" if late_down
                         else "too late: struck that late, its key could not be up by its end")
        dropped = True
    return dropped


def _moves_next(pl: Planner, tl: _Timeline, events, k: int, groups, reasons) -> bool:
    """True if the next group of notes after event ``k`` needs a new hand position."""
    for e in events[k + 1:]:
        if e[1] == 1:
            return tl.seg is None or not all(pl.press_q(g.finger, g.pitch, tl.seg)[1].converged
                                             for g in groups[e[0]] if g.note_index not in reasons)
    return False


def _run(pl: Planner, hand: HandModel, notes, parts, rail_of: dict[int, float],
         writer: TrajectoryWriter, rate_hz: float, reasons: dict[int, str], progress: bool,
         t_start: float) -> PlayResult:
    """Plan the parts (lists of press intervals, in time order) one after the other on
    one timeline; ``rail_of`` and ``reasons`` fill in as the parts are fingered."""
    dt = 1.0 / rate_hz
    end_song = max((n.offset_s for n in notes), default=0.0)
    parts = iter(parts)
    intervals = next(parts, [])
    rail0 = rail_of[intervals[0].press.note_index] if intervals else (
        float(pl.rest[pl.rail]) if pl.rail is not None else 0.0)
    q_start = pl.posture_at(rail0)
    tl = _Timeline(pl, hand, q_start, None, dt)
    next_row = 0
    t_cut = 0.0  # rows up to here are written; no new phase starts before it
    first_row_s = math.nan
    hold = tl.q.copy()  # the configuration before every phase not yet complete at t_cut
    joint_free = np.zeros(hand.n)  # when each joint's last planned motion ends
    last_row = None

    def chunk_phases() -> list[Phase]:
        """The chunk's phases as the timing QP takes them: each no sooner than the rows
        written and its joints' last timed motion, after the carried motions it follows."""
        carried_start = {g: x for g, _, x in tl.carried}
        phases = []
        for k, (ph, _, _) in enumerate(tl.phases):
            js = ph.joints if ph.order_joints is None else ph.order_joints
            earliest = max([t_cut, ph.earliest_s] + [float(joint_free[j]) for j in js.tolist()])
            follows = []
            for g, lag in ph.follows:
                if g >= tl.offset:
                    follows.append((g - tl.offset, lag))
                elif g in carried_start:
                    earliest = max(earliest, carried_start[g] + lag)
            # a blend with a motion timed in an earlier chunk is not taken (joint_free)
            blend = (ph.blend_s, ph.blend_after - tl.offset) if ph.blend_after >= tl.offset else (0.0, -1)
            phases.append(dataclasses.replace(ph, earliest_s=earliest, follows=tuple(follows),
                                              blend_s=blend[0], blend_after=blend[1]))
        return phases

    def late_s(note: int, kind: str) -> float:
        """How late (s) the timing QP would put ``note``'s key down (``kind`` "press") or up
        ("release") if the chunk were timed now (0 if that motion is not in the chunk)."""
        k = next((k for k, (_, kd, n) in enumerate(tl.phases) if kd == kind and n == note), None)
        if k is None:
            return 0.0
        phases = chunk_phases()
        x = solve_timing(build_timing(phases, t_cut))[k]
        return max(0.0, float(x + phases[k].anchor * phases[k].duration_s - phases[k].ideal_s))

    def flush(cut_s=None, final_t=None):
        """Time the chunk of phases (timing QP), write every row up to ``cut_s`` (all of
        them with ``final_t``), and carry the phases still running then over to the next
        chunk with their start times fixed."""
        nonlocal next_row, t_cut, first_row_s, hold, last_row, joint_free
        phases_meta = tl.phases
        phases = chunk_phases()
        starts = solve_timing(build_timing(phases, t_cut))
        # until none is left (each round leaves out at least one note, or ends): a note
        # left out moves the others, and one of them may be hopeless then
        while _drop_hopeless(phases, phases_meta, starts, notes, reasons, dt, hand.velocity,
                             hand.acceleration, tl.sweep_clear):
            starts = solve_timing(build_timing(phases, t_cut))
        every = [(g, p, x) for g, p, x in tl.carried] + [
            (tl.offset + k, p, float(x)) for k, (p, x) in enumerate(zip(phases, starts))]
        for _, p, x in every:
            js = p.joints if p.order_joints is None else p.order_joints
            joint_free[js] = np.maximum(joint_free[js], x + p.duration_s)
        end_t = max([t_cut] + [x + p.duration_s for _, p, x in every])
        if final_t is not None:
            end = max(end_t, final_t)
        else:
            end = max(t_cut, min(cut_s, end_t))
        n_rows_end = math.floor(end * rate_hz + 1e-9) + 1  # every row at or before end
        if n_rows_end > next_row:
            t = np.arange(next_row, n_rows_end) * dt
            q = hand.apply_couplings(sample([p for _, p, _ in every], np.array([x for _, _, x in every]), t, hold))
            guard_rows(hand, q, last_row, dt)
            last_row = q[-1].copy()
            writer.write_rows(t, q, hand.motor_angles(q))
            if math.isnan(first_row_s):
                first_row_s = time.perf_counter() - t_start
            next_row = n_rows_end
        t_cut = max(t_cut, end)
        tl.carried = [(g, p, x) for g, p, x in every if x + p.duration_s > t_cut]
        for _, p, x in every:
            if x + p.duration_s <= t_cut:
                hold = hold + p.delta
        tl.offset += len(phases_meta)
        tl.phases = []

    total = 2 * len(notes)
    done = 0
    down: dict[int, object] = {}
    group_t = -math.inf
    while intervals is not None:
        # events in time order: releases before presses at the same instant
        events = []
        for iv in intervals:
            events.append((iv.start_s, 1, iv.press.pitch, iv))
            events.append((iv.end_s, 0, iv.press.pitch, iv))
        events.sort(key=lambda e: (e[0], e[1], e[2]))
        groups: dict[float, list] = {}
        for e in events:
            if e[1] == 1:
                groups.setdefault(e[0], []).append(e[3].press)
        # for every press event, the next press of the same finger (what it prepares for)
        next_of: dict[int, object] = {}
        last_of: dict[str, int] = {}
        for e in events:
            if e[1] == 1:
                p_ = e[3].press
                if p_.finger in last_of:
                    next_of[last_of[p_.finger]] = p_
                last_of[p_.finger] = p_.note_index
        for k, (t, is_press, _, iv) in enumerate(events):
            p = iv.press
            if is_press:
                rail = rail_of[p.note_index]
                if abs(t - group_t) > 1e-9:  # the first key of a new group of notes
                    group_t = t
                    group = [g for g in groups[t] if g.note_index not in reasons]
                    reachable = tl.seg is not None and all(
                        pl.press_q(g.finger, g.pitch, tl.seg)[1].converged for g in group)
                    if not reachable and not down:
                        first = tl.seg is None
                        _reposition(pl, tl, events[k:], group, t, rail, rail_of, reasons)
                        # the fingers not striking now get ready for their next keys (at
                        # the start, they are there from the first row on)
                        busy = {g.finger for g in group}
                        for e in events[k:]:
                            if len(busy) == len(hand.fingers):
                                break
                            if e[1] == 1 and e[3].press.finger not in busy and e[3].press.note_index not in reasons:
                                busy.add(e[3].press.finger)
                                if first:
                                    tl.wait_above(e[3].press.finger, e[3].press.pitch)
                                else:
                                    tl.prepare(e[3].press.finger, e[3].press.pitch)
                        if first and tl.seg is not None:  # the start configuration
                            hold = tl.q.copy()
                if p.note_index in reasons:  # (no safe path of the hand to it)
                    continue
                if p.note_index in tl.pre_pressed:
                    ok = True
                else:
                    ok = tl.seg is not None and tl.press(p.finger, p.pitch, t, p.note_index, p.velocity)
                if ok:
                    down[p.note_index] = iv
                    tau = hand.press_torques(tl.q, {p.finger: p.force_n})
                    ratio = np.abs(tau) / hand.motor_peak_torque
                    if np.any(ratio > 1.0):
                        m = int(np.argmax(ratio))
                        reasons.setdefault(p.note_index, f"torque above bound (motor.{hand.motor_names[m]} "
                                           f"{abs(tau[m]):.2f} > {hand.motor_peak_torque[m]:.2f} N m)")
                else:
                    why = tl.failure or ("keys held elsewhere keep the hand away" if down else "out of reach")
                    tl.failure = None
                    reasons[p.note_index] = f"{why} (for the {p.finger})"
            elif p.note_index in down:
                if len(down) == 1:
                    _shift_while_held(pl, tl, events, k, groups, rail_of, reasons, iv, notes, late_s)
                tl.release(p.finger, p.pitch, t, p.note_index)
                del down[p.note_index]
                nxt = next_of.get(p.note_index)
                if nxt is not None and nxt.note_index not in reasons:
                    tl.prepare(nxt.finger, nxt.pitch)
                # the first rows go out as soon as there are a few, then in larger chunks
                if not down and len(tl.phases) >= (FIRST_CHUNK_PHASES if next_row == 0 else CHUNK_PHASES):
                    # before a change of hand position, cut early enough to leave the lifts
                    # and the travel free to start when they may; else early enough for
                    # the next press (and a finger's way to it) to start in time
                    moves = _moves_next(pl, tl, events, k, groups, reasons)
                    t_next = next((e[0] for e in events[k + 1:] if e[1] == 1), math.inf)
                    flush(cut_s=t - TRAVEL_LEAD_S if moves else min(t, t_next - TRAVEL_LEAD_S))
            if progress and total > 400 and (done + k) % 100 == 0:
                sys.stderr.write(f"\rplanning {done + k}/{total} key events ({100 * (done + k) // total}%)")
                sys.stderr.flush()
        done += len(events)
        intervals = next(parts, None)
    if progress and total > 400:
        sys.stderr.write(f"\rplanning {total}/{total} key events (100%)\n")
    tl.rest_all(end_song)
    flush(final_t=end_song + 0.25)
    return PlayResult(writer.rows, writer.rows * dt, [], 0.0, first_row_s, pl.ik_solves,
                      travels=tl.travels, shifts=tl.shifts)


# ---------------------------------------------------------------- CLI glue


def format_summary(song_name: str, res: PlayResult, song_s: float, out: str) -> str:
    n = len(res.notes)
    bad = res.infeasible
    rtf = song_s / res.planning_s if res.planning_s > 0 else math.inf
    lines = [(f"{song_name}: {n} notes, {n - len(bad)} played, {len(bad)} infeasible; "
             f"{res.rows} rows ({res.duration_s:.2f} s) -> {out}"),
             (f"planning {res.planning_s * 1000:.0f} ms for {song_s:.2f} s of music "
             f"(real-time factor {rtf:.0f}x), first row after {res.first_row_s * 1000:.0f} ms, "
             f"{res.ik_solves} IK solves, {res.travels + res.shifts} change"
             f"{'' if res.travels + res.shifts == 1 else 's'} of hand position"
             + (f" ({res.shifts} while a key was held)" if res.shifts else ""))]
    for nr in bad:
        lines.append(f"  infeasible: t={nr.onset_s:.3f} s {pitch_name(nr.pitch)} (MIDI {nr.pitch}): {nr.reason}")
    for i, early in res.cut:
        nt = res.notes[i]
        lines.append(f"  cut short: t={nt.onset_s:.3f} s {pitch_name(nt.pitch)} let go {early:.2f} s early "
                     "(its finger, or the hand, is needed for the notes after it)")
    lines.extend(res.verdict.problem_lines())
    return "\n".join(lines)


def play_cli(a) -> int:
    song = load_song(a.song, track=a.track, channel=a.channel, transpose=a.transpose)
    hand = load_hand(a.hand)
    out = a.output if a.output is not None else os.path.splitext(a.song)[0] + ".csv"
    name = os.path.basename(a.song)
    res = plan_song(song, hand, out, a.rate, song_name=name,
                    progress=sys.stderr.isatty())
    sys.stderr.write(format_summary(name, res, max((n.offset_s for n in song.notes), default=0.0),
                                    out) + "\n")
    if a.report or a.html:
        if out == "-":
            raise InputError("--report and --html need a trajectory file (-o PATH), not stdout")
        from planner.play.summary import write_reports

        write_reports(out, a.song, a.report, a.html)
    score = res.verdict.score
    if a.strict and (res.infeasible or score.late or score.wrong_presses):
        return 1
    return 0
