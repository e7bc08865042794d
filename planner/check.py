"""The independent replay check: what does a trajectory file really do?

``check_trajectory(path, song)`` reads a ``hand-trajectory`` v1 file (spec
section 4), rebuilds the hand it names, replays every row through forward
kinematics and reports

* **play**: which keys go down in every frame (spec section 2: a fingertip
  point inside a key's footprint -- for a white key minus the black keys'
  rectangles -- at least ``DOWN_DEPTH_M`` below the key's resting top), key-bed
  hits (a fingertip in a footprint more than ``KEY_BED_DEPTH_M`` below that
  top), and with a song: frame-level precision / recall / F1 (RoboPianist's
  metric), note-level hits, missed notes and wrong presses;
* **catch**: the ball's flight (integrated here), where it meets the palm,
  fingertips touching it early and the grasp after the intercept;
* **both**: a limit audit (joint positions, speeds, accelerations, motor
  speeds, motor columns against the joints, static motor torque, couplings).

Independence: this module shares only the hand model, the keyboard geometry,
the trajectory reader and the MIDI reader with the planner. It never imports
``planner.play``, ``planner.ik``, ``planner.trajectory``, ``planner.catch`` or
the fingering / targets modules, and it runs its own copy of the Pinocchio
model (so it never touches the shared hand's data, and can put the root where
the file's metadata says).

Choices (each one a named constant below):

* Times. The song's clock is the trajectory's clock (t = 0 in both). A note
  sounds in frame ``t`` when ``onset_s <= t < offset_s``.
* Frame F1 (``frame_scores``): per frame, a binary classification over the 88
  keys scored like ``sklearn.metrics.precision_recall_fscore_support(...,
  average="binary", zero_division=1)``: precision = tp/(tp+fp), recall =
  tp/(tp+fn), F1 = 2 tp/(2 tp+fp+fn), each 1 when its denominator is 0 -- so
  a frame with nothing expected and nothing pressed scores 1, and a frame with
  only false positives or only misses scores 0. The three are averaged over
  the trajectory's frames.
* Note hits: a note is hit when its key is down in at least
  ``NOTE_HIT_FRACTION`` (50 %) of the frames in ``[onset, offset)``; a note
  with no frame inside that interval (shorter than a frame period, or
  after the trajectory's end) cannot be hit and is listed as missed with the
  reason.
* Wrong presses: a key down in a frame where no note of that key sounds,
  grouped into contiguous episodes per key. An episode runs from its first
  frame's time to the time of the frame after its last one (one median frame
  period past the last row at the end of the file), and lists every finger
  that held the key down during it.
* Speeds and accelerations are first and second differences of consecutive
  rows (non-uniform steps handled). For a trajectory whose continuous speed
  and acceleration respect the limits, the differences do too (they are
  averages of the continuous quantity), so they are a sound test. Tolerances
  are 1 % of the limit plus the effect of the file's 6-decimal rounding
  (``1e-6/dt`` for speeds, ``2e-6/dt^2`` for second differences: 0.02 rad/s^2
  at 100 Hz). The speed is reported at the later row of its pair, the
  acceleration at the middle row of its triple.
* Motor torque: the static torque only -- gravity (with the file's
  ``T_world_root`` orientation) plus, for play, a nominal
  ``KEY_FORCE_N`` = 0.5 N upward on every fingertip that holds a key down
  (the planner may press harder), and for a catch, after the intercept, the
  ball's weight on the palm centre -- mapped to the motors with
  ``HandModel.motor_torques`` and compared with ``motor_peak_torque`` (1 %).
  Inertial torques are not counted.
* Motor columns must equal ``HandModel.motor_angles(q)`` of the row's joints
  within ``MOTOR_TOL_RAD`` (1e-5 rad) plus the rounding of the file (half a
  unit of the 6th decimal on the motor value and on each joint, weighted by
  the motor's sensitivity to it: 100 rad/m for the rail's belt). Couplings
  likewise within ``COUPLING_TOL_RAD`` plus rounding.
* Catch: the ball flies from ``p0, v0`` at t = 0 (acceleration g - k|v|v,
  closed form when k = 0, else RK4 with steps of at most 1 ms). At
  ``intercept_t`` (joint rows interpolated linearly in time) its centre must
  lie within ``INTERCEPT_TOL_M`` (15 mm) of ``palm_center + radius * n`` (n the
  palm frame's +z). Before ``intercept_t`` no fingertip may be closer than the
  radius to the ball's centre. From ``intercept_t`` on the ball is taken to
  be held: its centre is ``palm_center + radius * n`` of each row. Within
  ``GRASP_WINDOW_S`` (150 ms) after ``intercept_t`` some row must have at least
  ``GRASP_MIN_TIPS`` (3) fingertips, the thumb among them, within
  ``radius + GRASP_TOL_M`` (10 mm) of the ball's centre, and every later row
  must keep that grasp (the catch holds to the end of the file).
* ``T_world_root``: the FK uses the metadata's pose. For ``play`` it must equal
  the hand's mount (the keyboard frame is defined by that mount) within
  ``T_TOL``; for ``catch`` the catch frame has its origin at the launch point,
  so the hand may be mounted anywhere in it -- the pose is only required to be
  a rigid transform.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field, fields, is_dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from planner.errors import InputError
from planner.hand.model import HandModel, load_hand
from planner.hand.spec import FINGERS, PALM_FRAME
from planner.music.keyboard import (
    DOWN_DEPTH_M,
    HIGHEST_PITCH,
    KEY_BED_DEPTH_M,
    LOWEST_PITCH,
    key_table,
)
from planner.trajfile import Trajectory, read_trajectory

__all__ = [
    "CatchResult",
    "CheckReport",
    "KeyBedHit",
    "KeyEpisode",
    "LimitCheck",
    "MissedNote",
    "PlayResult",
    "Replay",
    "ball_positions",
    "check_cli",
    "check_trajectory",
    "expected_keys",
    "fk_frames",
    "frame_f1",
    "frame_scores",
    "key_contacts",
    "key_episodes",
    "keys_down",
    "pitch_name",
]

N_KEYS = HIGHEST_PITCH - LOWEST_PITCH + 1  # 88
FILE_QUANTUM = 1e-6  # the writer's 6 decimals
POSITION_TOL = 1e-6  # rad or m beyond a joint limit
RATE_TOL = 0.01  # 1 % of a speed / acceleration / torque limit
MOTOR_TOL_RAD = 1e-5  # motor column vs motor_angles(q), plus file rounding
COUPLING_TOL_RAD = 1e-5  # |coupling error|, plus file rounding
KEY_BED_TOL_M = 2e-6  # fingertip rounding (1e-6 rad over a ~0.4 m chain)
KEY_FORCE_N = 0.5  # nominal key reaction on a pressing fingertip
T_TOL = 1e-9  # metadata T_world_root vs the hand's mount (play)
NOTE_HIT_FRACTION = 0.5  # a note is hit when its key is down in >= 50 % of its frames
INTERCEPT_TOL_M = 0.015  # ball centre vs palm_center + radius * normal at intercept_t
GRASP_WINDOW_S = 0.150  # the grasp must close within this after intercept_t
GRASP_TOL_M = 0.010  # a fingertip "closed around" the ball: distance <= radius + this
GRASP_MIN_TIPS = 3  # ... at least this many, the thumb among them
BALL_STEP_S = 1e-3  # RK4 step of the ball flight with drag
G = 9.81
_GRAVITY = np.array([0.0, 0.0, -G])
_NAMES = ("C", "C#", "D", "D#", "E", "F", "F#", "G", "G#", "A", "A#", "B")


def pitch_name(pitch: int) -> str:
    """Scientific pitch name: 60 -> 'C4', 61 -> 'C#4', 21 -> 'A0'."""
    return f"{_NAMES[pitch % 12]}{pitch // 12 - 1}"


# ====================================================================== results


@dataclass(frozen=True)
class LimitCheck:
    """One audited quantity: how many samples exceed their limit and the worst one.

    ``worst`` is the sample with the largest value relative to its limit (for
    positions: the largest excess beyond a bound; when nothing is violated,
    the closest approach), ``limit`` its limit, ``name`` the joint or motor,
    ``time_s`` the row's time. ``count`` counts (row, joint) samples.
    """

    category: str
    count: int
    worst: float
    limit: float
    name: str
    time_s: float
    unit: str

    @property
    def ok(self) -> bool:
        return self.count == 0


@dataclass(frozen=True)
class KeyEpisode:
    """A key held down over contiguous frames: [start_s, end_s), by these fingers."""

    pitch: int
    name: str
    start_s: float
    end_s: float
    fingers: tuple[str, ...]


@dataclass(frozen=True)
class KeyBedHit:
    """A fingertip more than KEY_BED_DEPTH_M below the top of the key it is over."""

    time_s: float
    finger: str
    pitch: int
    name: str
    depth_m: float


@dataclass(frozen=True)
class MissedNote:
    onset_s: float
    offset_s: float
    pitch: int
    name: str
    fraction_down: float  # of the note's frames
    reason: str


@dataclass(frozen=True)
class PlayResult:
    """Keys, notes and the frame metrics of a play trajectory.

    ``f1``/``precision``/``recall`` and the note counts are None without a song.
    ``played`` are all key-down episodes (what the trajectory plays).
    """

    frames: int
    played: tuple[KeyEpisode, ...]
    key_bed_hits: tuple[KeyBedHit, ...]
    f1: float | None = None
    precision: float | None = None
    recall: float | None = None
    notes: int | None = None
    notes_hit: int | None = None
    missed: tuple[MissedNote, ...] = ()
    wrong_presses: tuple[KeyEpisode, ...] = ()

    @property
    def hit_rate(self) -> float | None:
        if self.notes is None:
            return None
        return 1.0 if self.notes == 0 else self.notes_hit / self.notes


@dataclass(frozen=True)
class TipTouch:
    time_s: float
    finger: str
    distance_m: float  # tip to ball centre


@dataclass(frozen=True)
class CatchResult:
    """The catch audit; ``ok`` when the ball meets the palm, nothing touches it
    early, and the grasp closes within the window and holds."""

    intercept_t: float
    radius_m: float
    ball_at_intercept: tuple[float, float, float]
    palm_target: tuple[float, float, float]  # palm_center + radius * normal
    intercept_error_m: float | None
    intercept_ok: bool
    early_touches: tuple[TipTouch, ...]
    grasp_time_s: float | None
    grasp_fingers: tuple[str, ...]
    grasp_held: bool
    min_tip_distance_after_m: float | None
    problems: tuple[str, ...]

    @property
    def ok(self) -> bool:
        return not self.problems


@dataclass(frozen=True)
class Replay:
    """Per-row arrays of the replay (not serialised), for plots and animations.

    ``tips`` (T, 5, 3) world fingertip points in ``FINGERS`` order; ``palm``
    (T, 4, 4) world palm_center poses; ``down``/``finger``/``depth`` as in
    ``key_contacts``; ``expected`` (T, 88) bool or None without a song.
    """

    t_s: np.ndarray
    q: np.ndarray
    tips: np.ndarray
    palm: np.ndarray
    down: np.ndarray | None = None
    finger: np.ndarray | None = None
    expected: np.ndarray | None = None


@dataclass(frozen=True)
class CheckReport:
    """Everything the check found. ``ok`` is the verdict; ``problems`` says why not."""

    trajectory: str
    song: str | None
    task: str
    hand: str
    urdf_sha256: str
    complete: bool
    rows: int
    duration_s: float
    rate_hz: float
    limits: tuple[LimitCheck, ...]
    play: PlayResult | None
    catch: CatchResult | None
    min_f1: float | None
    problems: tuple[str, ...]
    replay: Replay | None = field(default=None, compare=False, repr=False)

    @property
    def ok(self) -> bool:
        return not self.problems

    def to_dict(self) -> dict[str, Any]:
        """A JSON-serialisable dict (the replay arrays are left out)."""
        d = _plain(self)
        d.pop("replay", None)
        d["ok"] = self.ok
        if self.play is not None:
            d["play"]["hit_rate"] = self.play.hit_rate
        if self.catch is not None:
            d["catch"]["ok"] = self.catch.ok
        for lc, dd in zip(self.limits, d["limits"]):
            dd["ok"] = lc.ok
        return d

    def summary(self) -> str:
        """A readable multi-line account, verdict first."""
        L = [f"check {self.trajectory}: {'OK' if self.ok else 'FAILED'}"]
        for p in self.problems:
            L.append(f"  - {p}")
        L.append(f"task {self.task}, hand {self.hand}, {self.rows} rows, "
                 f"{self.duration_s:.3f} s at {self.rate_hz:g} Hz"
                 + ("" if self.complete else " (INCOMPLETE file: no end marker)"))
        if self.play is not None:
            p = self.play
            L.append(f"keys: {len(p.played)} key presses, {len(p.key_bed_hits)} key-bed hits")
            if p.f1 is not None:
                L.append(f"song {self.song}: frame F1 {p.f1:.4f} (precision {p.precision:.4f}, "
                         f"recall {p.recall:.4f}); notes hit {p.notes_hit}/{p.notes}"
                         + (f"; required F1 >= {self.min_f1:g}" if self.min_f1 is not None else ""))
            _listing(L, "wrong presses", p.wrong_presses, lambda w: (
                f"{w.start_s:8.3f}-{w.end_s:.3f} s  {w.name:4s} ({w.pitch})  "
                f"{'+'.join(w.fingers) or '?'}"))
            _listing(L, "missed notes", p.missed, lambda m: (
                f"{m.onset_s:8.3f}-{m.offset_s:.3f} s  {m.name:4s} ({m.pitch})  "
                f"down {m.fraction_down:.0%}  {m.reason}"))
            _listing(L, "key-bed hits", p.key_bed_hits, lambda h: (
                f"{h.time_s:8.3f} s  {h.finger:6s} {h.name:4s} ({h.pitch})  "
                f"{h.depth_m * 1000:.2f} mm below the top (max {KEY_BED_DEPTH_M * 1000:g})"))
        if self.catch is not None:
            c = self.catch
            err = "n/a" if c.intercept_error_m is None else f"{c.intercept_error_m * 1000:.1f} mm"
            L.append(f"catch at t={c.intercept_t:.3f} s: ball {err} from palm target "
                     f"(max {INTERCEPT_TOL_M * 1000:g} mm); "
                     + (f"grasp at {c.grasp_time_s:.3f} s by {'+'.join(c.grasp_fingers)}"
                        + ("" if c.grasp_held else ", NOT held")
                        if c.grasp_time_s is not None else "no grasp"))
            _listing(L, "early touches", c.early_touches, lambda e: (
                f"{e.time_s:8.3f} s  {e.finger:6s} {e.distance_m * 1000:.1f} mm from the centre"))
        L.append("limits (count, worst / limit, where):")
        for lc in self.limits:
            L.append(f"  {lc.category:18s} {'ok  ' if lc.ok else 'FAIL'} {lc.count:6d}  "
                     f"{lc.worst:.6g} / {lc.limit:.6g} {lc.unit}  {lc.name} at {lc.time_s:.3f} s")
        return "\n".join(L)


def _listing(L: list[str], title: str, items, fmt, first: int = 10) -> None:
    if not items:
        return
    L.append(f"{title} ({len(items)}):")
    L.extend("  " + fmt(x) for x in items[:first])
    if len(items) > first:
        L.append(f"  ... and {len(items) - first} more")


def _plain(x: Any) -> Any:
    if is_dataclass(x) and not isinstance(x, type):
        return {f.name: _plain(getattr(x, f.name)) for f in fields(x)}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    if isinstance(x, dict):
        return {str(k): _plain(v) for k, v in x.items()}
    if isinstance(x, np.ndarray):
        return _plain(x.tolist())
    if isinstance(x, (np.bool_, bool)):
        return bool(x)
    if isinstance(x, (np.integer, int)):
        return int(x)
    if isinstance(x, (np.floating, float)):
        v = float(x)
        return v if math.isfinite(v) else None
    return x


# ====================================================================== kinematics


class _Kin:
    """A private Pinocchio model of the hand with the root at ``T_world_root``."""

    def __init__(self, hand: HandModel, T_world_root: np.ndarray) -> None:
        self.hand = hand
        self.T = np.asarray(T_world_root, dtype=float)
        self.R = self.T[:3, :3]
        self.p = self.T[:3, 3]
        self.model = hand.pin_model.copy()
        self.model.gravity.linear = self.R.T @ _GRAVITY
        self.data = self.model.createData()
        m = self.model
        self.idx = np.array([m.idx_qs[m.getJointId(n)] for n in hand.joint_names])
        self.tip_ids = [m.getFrameId(f) for f in hand.tip_frames]
        self.palm_id = m.getFrameId(PALM_FRAME)

    def pin_q(self, q: np.ndarray) -> np.ndarray:
        qp = np.zeros(self.model.nq)
        qp[self.idx] = q
        return qp

    def frames(self, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World tips (T, 5, 3) and palm poses (T, 4, 4) of every row of ``Q``."""
        Q = np.atleast_2d(Q)
        T = len(Q)
        tips = np.empty((T, len(self.tip_ids), 3))
        palm = np.empty((T, 4, 4))
        QP = np.zeros((T, self.model.nq))
        QP[:, self.idx] = Q
        m, d = self.model, self.data
        for k in range(T):
            pin.framesForwardKinematics(m, d, QP[k])
            for j, f in enumerate(self.tip_ids):
                tips[k, j] = d.oMf[f].translation
            palm[k] = d.oMf[self.palm_id].homogeneous
        tips = tips @ self.R.T + self.p
        palm = np.einsum("ij,tjk->tik", self.T, palm)
        return tips, palm

    def gravity(self, q: np.ndarray) -> np.ndarray:
        return pin.computeGeneralizedGravity(self.model, self.data, self.pin_q(q))[self.idx]

    def point_jacobians(self, q: np.ndarray, frame_ids: list[int]) -> list[np.ndarray]:
        """World position Jacobians (3, n) of frames, our joint order."""
        pin.computeJointJacobians(self.model, self.data, self.pin_q(q))
        pin.updateFramePlacements(self.model, self.data)
        out = []
        for fid in frame_ids:
            J = pin.getFrameJacobian(self.model, self.data, fid,
                                     pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
            out.append(self.R @ J[:3, self.idx])
        return out


def fk_frames(hand: HandModel, q: np.ndarray,
              T_world_root: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Forward kinematics of every row: fingertips (T, 5, 3) in ``FINGERS`` order
    and palm_center poses (T, 4, 4), in the world of ``T_world_root`` (default
    the hand's mount)."""
    T = hand.T_world_root if T_world_root is None else T_world_root
    return _Kin(hand, T).frames(np.asarray(q, dtype=float))


# ====================================================================== keys


@dataclass(frozen=True)
class KeyContacts:
    """Per-frame key state from fingertip points.

    ``down`` (T, 88) bool: key ``pitch - 21`` is down. ``finger`` (T, 88) int8:
    index into ``FINGERS`` of the (deepest) fingertip holding it down, -1 when
    up. ``tip_key`` (T, 5) int: key index under each fingertip or -1;
    ``tip_depth`` (T, 5): depth of each fingertip below that key's resting top
    (NaN when over no key).
    """

    down: np.ndarray
    finger: np.ndarray
    tip_key: np.ndarray
    tip_depth: np.ndarray


def key_contacts(tips: np.ndarray) -> KeyContacts:
    """Apply the spec's key-down rule to fingertip points ``tips`` (T, F, 3)."""
    tips = np.asarray(tips, dtype=float)
    T, F = tips.shape[:2]
    kt = key_table()
    x, y = tips[..., 0, None], tips[..., 1, None]
    inside = (kt["x_min"] <= x) & (x <= kt["x_max"]) & (kt["y_min"] <= y) & (y <= kt["y_max"])
    black = kt["black"]
    in_black = inside & black
    # white footprints minus the black rectangles; footprints of one colour do not overlap
    in_white = inside & ~black & ~in_black.any(axis=-1, keepdims=True)
    hit = in_black | in_white
    any_hit = hit.any(axis=-1)
    tip_key = np.where(any_hit, hit.argmax(axis=-1), -1)
    top = kt["top_z"][np.maximum(tip_key, 0)]
    tip_depth = np.where(any_hit, top - tips[..., 2], np.nan)
    pressing = any_hit & (np.nan_to_num(tip_depth, nan=-1.0) >= DOWN_DEPTH_M)
    down = np.zeros((T, N_KEYS), dtype=bool)
    finger = np.full((T, N_KEYS), -1, dtype=np.int8)
    best = np.full((T, N_KEYS), -np.inf)
    rows = np.arange(T)
    for f in range(F):
        r = rows[pressing[:, f]]
        k = tip_key[r, f]
        d = tip_depth[r, f]
        deeper = d > best[r, k]
        down[r, k] = True
        finger[r[deeper], k[deeper]] = f
        best[r[deeper], k[deeper]] = d[deeper]
    return KeyContacts(down, finger, tip_key, tip_depth)


def keys_down(hand: HandModel, t_s: np.ndarray, q: np.ndarray,
              T_world_root: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Keys down in each row of ``q`` (times ``t_s``, only used for the shape check).

    Returns ``(down, finger)``: ``down`` (T, 88) bool, column ``pitch - 21``;
    ``finger`` (T, 88) int8, the index into ``FINGERS`` of the fingertip that
    holds the key down (the deepest one if several), -1 where the key is up.
    """
    q = np.atleast_2d(np.asarray(q, dtype=float))
    if len(np.atleast_1d(t_s)) != len(q):
        raise ValueError("t_s and q must have the same number of rows")
    tips, _ = fk_frames(hand, q, T_world_root)
    c = key_contacts(tips)
    return c.down, c.finger


def expected_keys(notes, t_s: np.ndarray) -> np.ndarray:
    """(T, 88) bool: key ``pitch - 21`` sounds in frame t when onset_s <= t < offset_s."""
    t_s = np.asarray(t_s, dtype=float)
    out = np.zeros((len(t_s), N_KEYS), dtype=bool)
    for n in notes:
        if not LOWEST_PITCH <= n.pitch <= HIGHEST_PITCH:
            raise InputError(f"note pitch {n.pitch} is outside the keyboard (21..108)")
        k0 = np.searchsorted(t_s, n.onset_s, side="left")
        k1 = np.searchsorted(t_s, n.offset_s, side="left")
        out[k0:k1, n.pitch - LOWEST_PITCH] = True
    return out


def frame_scores(expected: np.ndarray, pressed: np.ndarray) -> tuple[np.ndarray, ...]:
    """Per-frame (precision, recall, f1) of ``pressed`` against ``expected`` (T, K) bool.

    Each frame is scored like sklearn's ``precision_recall_fscore_support(
    expected[t], pressed[t], average="binary", zero_division=1)``: a ratio
    with a zero denominator is 1, so a frame with nothing expected and nothing
    pressed scores (1, 1, 1); F1 is 2 tp / (2 tp + fp + fn).
    """
    e = np.atleast_2d(np.asarray(expected, dtype=bool))
    p = np.atleast_2d(np.asarray(pressed, dtype=bool))
    if e.shape != p.shape:
        raise ValueError(f"expected {e.shape} and pressed {p.shape} differ in shape")
    tp = np.sum(e & p, axis=-1).astype(float)
    fp = np.sum(~e & p, axis=-1).astype(float)
    fn = np.sum(e & ~p, axis=-1).astype(float)

    def ratio(num, den):
        return np.divide(num, den, out=np.ones_like(num), where=den > 0)

    return ratio(tp, tp + fp), ratio(tp, tp + fn), ratio(2 * tp, 2 * tp + fp + fn)


def frame_f1(expected: np.ndarray, pressed: np.ndarray) -> float:
    """RoboPianist's frame F1: the mean over frames of ``frame_scores``' F1 (1.0 for no frames)."""
    f1 = frame_scores(expected, pressed)[2]
    return float(f1.mean()) if f1.size else 1.0


def _frame_period(t_s: np.ndarray) -> float:
    return float(np.median(np.diff(t_s))) if len(t_s) > 1 else 0.01


def key_episodes(mask: np.ndarray, t_s: np.ndarray,
                 finger: np.ndarray | None = None) -> list[KeyEpisode]:
    """Contiguous runs of True in each key column of ``mask`` (T, 88), sorted by start.

    An episode lasts from its first frame's time to the next frame's time
    (one median period past the last row at the end of the file).
    """
    t_s = np.asarray(t_s, dtype=float)
    T = len(t_s)
    t_end = np.append(t_s[1:], t_s[-1] + _frame_period(t_s)) if T else t_s
    m = np.asarray(mask, dtype=bool)
    pad = np.zeros((1, m.shape[1]), dtype=bool)
    edges = np.diff(np.vstack([pad, m, pad]).astype(np.int8), axis=0)
    out = []
    for k in np.flatnonzero(m.any(axis=0)):
        starts = np.flatnonzero(edges[:, k] == 1)
        stops = np.flatnonzero(edges[:, k] == -1)  # exclusive
        for a, b in zip(starts, stops):
            fingers: tuple[str, ...] = ()
            if finger is not None:
                fs = finger[a:b, k]
                fingers = tuple(FINGERS[i] for i in sorted(set(fs[fs >= 0].tolist())))
            p = int(k) + LOWEST_PITCH
            out.append(KeyEpisode(p, pitch_name(p), float(t_s[a]), float(t_end[b - 1]), fingers))
    out.sort(key=lambda e: (e.start_s, e.pitch))
    return out


# ====================================================================== ball


def _ball_params(meta: dict[str, Any], path: str) -> dict[str, Any]:
    b = meta.get("ball")
    if not isinstance(b, dict):
        raise InputError(f"{path}: catch metadata lacks 'ball'")
    out: dict[str, Any] = {}
    for k in ("p0", "v0"):
        v = b.get(k)
        if (not isinstance(v, list) or len(v) != 3
                or not all(_is_num(x) and math.isfinite(x) for x in v)):
            raise InputError(f"{path}: ball {k!r} must be a list of 3 finite numbers")
        out[k] = np.array(v, dtype=float)
    for k, lo, strict in (("radius", 0.0, True), ("mass", 0.0, False), ("drag", 0.0, False)):
        v = b.get(k)
        if not _is_num(v) or not math.isfinite(v) or v < lo or (strict and v == lo):
            what = "positive" if strict else "non-negative"
            raise InputError(f"{path}: ball {k!r} must be a {what} number, got {v!r}")
        out[k] = float(v)
    return out


def _is_num(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def ball_positions(p0, v0, drag: float, times) -> np.ndarray:
    """Ball centre at ``times`` (s, from launch at t = 0), acceleration g - k|v|v.

    Closed form when ``drag`` is 0; otherwise classic RK4 with steps of at most
    ``BALL_STEP_S`` that land exactly on every requested time. Times before 0
    give ``p0`` (the ball has not left).
    """
    p0 = np.asarray(p0, dtype=float)
    v0 = np.asarray(v0, dtype=float)
    times = np.atleast_1d(np.asarray(times, dtype=float))
    tt = np.maximum(times, 0.0)
    if drag == 0.0:
        return p0 + np.outer(tt, v0) + 0.5 * np.outer(tt * tt, _GRAVITY)
    k = float(drag)

    def acc(v):
        return _GRAVITY - k * math.sqrt(v @ v) * v

    out = np.empty((len(tt), 3))
    order = np.argsort(tt, kind="stable")
    t, p, v = 0.0, p0.copy(), v0.copy()
    for i in order:
        target = tt[i]
        n = max(1, math.ceil((target - t) / BALL_STEP_S - 1e-9)) if target > t else 0
        h = (target - t) / n if n else 0.0
        for _ in range(n):
            a1 = acc(v)
            v2 = v + 0.5 * h * a1
            a2 = acc(v2)
            v3 = v + 0.5 * h * a2
            a3 = acc(v3)
            v4 = v + h * a3
            a4 = acc(v4)
            p = p + h / 6.0 * (v + 2 * v2 + 2 * v3 + v4)
            v = v + h / 6.0 * (a1 + 2 * a2 + 2 * a3 + a4)
        t = target
        out[i] = p
    return out


# ====================================================================== the check


def _load_hand(meta: dict[str, Any], path: str, hand_override) -> HandModel:
    if isinstance(hand_override, HandModel):
        return hand_override
    name = hand_override if hand_override is not None else meta["hand"]
    if not isinstance(name, str) or not name:
        raise InputError(f"{path}: metadata 'hand' must be a hand name, got {name!r}")
    try:
        return load_hand(name)
    except InputError as e:
        raise InputError(f"{path}: cannot rebuild hand {name!r}: {e}") from None


def _check_columns(tr: Trajectory, hand: HandModel, path: str) -> None:
    for what, have, want in (("joint", tr.joint_names, hand.joint_names),
                             ("motor", tr.motor_names, hand.motor_names)):
        if tuple(have) == tuple(want):
            continue
        pre = "motor." if what == "motor" else ""
        missing = [pre + n for n in want if n not in have]
        extra = [pre + n for n in have if n not in want]
        parts = []
        if missing:
            parts.append("missing " + ", ".join(missing))
        if extra:
            parts.append("extra " + ", ".join(extra))
        if not parts:
            parts.append(f"order differs from the hand's ({', '.join(pre + n for n in want)})")
        raise InputError(f"{path}: {what} columns do not match hand {hand.name!r}: "
                         + "; ".join(parts))


def _T_world_root(meta: dict[str, Any], hand: HandModel, path: str) -> np.ndarray:
    raw = meta["T_world_root"]
    try:
        T = np.array(raw, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{path}: T_world_root must be a 4x4 list of numbers") from None
    if T.shape != (4, 4) or not np.all(np.isfinite(T)):
        raise InputError(f"{path}: T_world_root must be a 4x4 list of finite numbers")
    R = T[:3, :3]
    if (not np.allclose(T[3], [0, 0, 0, 1], atol=1e-9)
            or not np.allclose(R.T @ R, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0):
        raise InputError(f"{path}: T_world_root is not a rigid transform")
    if meta["task"] == "play":
        diff = float(np.max(np.abs(T - hand.T_world_root)))
        if diff > T_TOL:
            raise InputError(f"{path}: T_world_root differs from hand {hand.name!r}'s mount by "
                             f"{diff:.3g} (the keyboard frame is that mount)")
    return T


def _worst(category: str, excess: np.ndarray, value: np.ndarray, limit: np.ndarray,
           tol: np.ndarray, names, times: np.ndarray, unit: str) -> LimitCheck:
    """Build a LimitCheck from (R, C) arrays: ``excess`` ranks samples (bigger is
    worse), a sample violates when its ``value`` is beyond ``limit + tol``."""
    if excess.size == 0:
        return LimitCheck(category, 0, 0.0, float(np.max(limit)) if np.size(limit) else 0.0,
                          "", 0.0, unit)
    count = int(np.count_nonzero(~(value <= limit + tol)))  # NaN (inf - inf) is no pass
    r, c = np.unravel_index(int(np.argmax(excess)), excess.shape)
    lim = np.broadcast_to(limit, value.shape)
    return LimitCheck(category, count, float(value[r, c]), float(lim[r, c]), names[c],
                      float(times[r]), unit)


@np.errstate(over="ignore", invalid="ignore")  # absurd values give inf: counted, not printed
def _limit_audit(hand: HandModel, kin: _Kin, tr: Trajectory, pressing_tips: np.ndarray | None,
                 ball_load: np.ndarray | None) -> list[LimitCheck]:
    t, Q, QM = tr.t_s, tr.q, tr.q_motor
    jn, mn = hand.joint_names, tuple(f"motor.{m}" for m in hand.motor_names)
    out = []

    # positions: excess beyond the nearer bound (<= 0 inside); infinite bounds never bind
    lo = np.where(np.isfinite(hand.lower), hand.lower, -np.inf)
    hi = np.where(np.isfinite(hand.upper), hand.upper, np.inf)
    below, above = lo - Q, Q - hi
    excess = np.maximum(below, above)
    bound = np.where(below > above, lo, hi)
    r, c = np.unravel_index(int(np.argmax(excess)), excess.shape)
    out.append(LimitCheck("joint_position", int(np.count_nonzero(excess > POSITION_TOL)),
                          float(Q[r, c]), float(bound[r, c]), jn[c], float(t[r]), "rad|m"))

    dt = np.diff(t)
    if len(t) >= 2:
        V = np.diff(Q, axis=0) / dt[:, None]
        tol = RATE_TOL * hand.velocity + FILE_QUANTUM / dt[:, None]
        out.append(_worst("joint_velocity", np.abs(V) / hand.velocity, np.abs(V), hand.velocity,
                          tol, jn, t[1:], "rad/s|m/s"))
        VM = np.diff(QM, axis=0) / dt[:, None]
        tol = RATE_TOL * hand.motor_speed + FILE_QUANTUM / dt[:, None]
        out.append(_worst("motor_velocity", np.abs(VM) / hand.motor_speed, np.abs(VM),
                          hand.motor_speed, tol, mn, t[1:], "rad/s"))
    else:
        out.append(LimitCheck("joint_velocity", 0, 0.0, 0.0, "", 0.0, "rad/s|m/s"))
        out.append(LimitCheck("motor_velocity", 0, 0.0, 0.0, "", 0.0, "rad/s"))
    if len(t) >= 3:
        V = np.diff(Q, axis=0) / dt[:, None]
        h = 0.5 * (dt[1:] + dt[:-1])[:, None]
        A = np.diff(V, axis=0) / h
        tol = RATE_TOL * hand.acceleration + 2 * FILE_QUANTUM / (dt[1:] * dt[:-1])[:, None]
        out.append(_worst("joint_acceleration", np.abs(A) / hand.acceleration, np.abs(A),
                          hand.acceleration, tol, jn, t[1:-1], "rad/s^2|m/s^2"))
    else:
        out.append(LimitCheck("joint_acceleration", 0, 0.0, 0.0, "", 0.0, "rad/s^2|m/s^2"))

    # motor columns vs the joints: tolerance plus the rounding of the file
    QMc = hand.motor_angles(Q)
    sens = np.zeros_like(QMc)
    step = 1e-4
    for j in range(hand.n):
        Qp = Q.copy()
        Qp[:, j] += step
        sens += np.abs(hand.motor_angles(Qp) - QMc) / step
    err = np.abs(QM - QMc)
    tol = MOTOR_TOL_RAD + 0.5 * FILE_QUANTUM * (1.0 + sens)
    out.append(_worst("motor_consistency", err / tol, err, tol, 0.0, mn, t, "rad"))

    # couplings
    if hand.couplings:
        ce = np.abs(hand.coupling_errors(Q))
        slope = np.stack([np.abs(c.slope(Q[:, c.src])) for c in hand.couplings], axis=-1)
        tol = COUPLING_TOL_RAD + 0.5 * FILE_QUANTUM * (1.0 + slope)
        names = [jn[c.dep] for c in hand.couplings]
        out.append(_worst("coupling", ce / tol, ce, tol, 0.0, names, t, "rad"))
    else:
        out.append(LimitCheck("coupling", 0, 0.0, COUPLING_TOL_RAD, "", 0.0, "rad"))

    # static motor torque
    tau = np.array([kin.gravity(q) for q in Q])
    if pressing_tips is not None:
        tip_ids = kin.tip_ids
        for k in np.flatnonzero(pressing_tips.any(axis=1)):
            Js = kin.point_jacobians(Q[k], [tip_ids[f] for f in np.flatnonzero(pressing_tips[k])])
            for J in Js:
                tau[k] -= J.T @ np.array([0.0, 0.0, KEY_FORCE_N])
    if ball_load is not None:
        for k in np.flatnonzero(ball_load > 0):
            (J,) = kin.point_jacobians(Q[k], [kin.palm_id])
            tau[k] -= J.T @ (ball_load[k] * _GRAVITY)
    TM = _motor_torques(hand, Q, tau)
    ratio = np.abs(TM) / hand.motor_peak_torque
    out.append(_worst("motor_torque", ratio, np.abs(TM), hand.motor_peak_torque,
                      RATE_TOL * hand.motor_peak_torque, mn, t, "N m"))
    return out


def _motor_torques(hand: HandModel, Q: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """``hand.motor_torques`` of every row; one matrix when every law is linear."""
    linear = (all(c.kind == "linear" for c in hand.couplings)
              and all(a.mk5 is None for a in hand.actuators))
    if linear:
        q0 = hand.q_neutral
        M = np.stack([hand.motor_torques(q0, e) for e in np.eye(hand.n)], axis=1)
        return tau @ M.T
    return np.array([hand.motor_torques(q, g) for q, g in zip(Q, tau)])


def _play(tr: Trajectory, tips: np.ndarray, song_notes, song_path: str | None
          ) -> tuple[PlayResult, KeyContacts, np.ndarray | None]:
    t = tr.t_s
    kc = key_contacts(tips)
    played = key_episodes(kc.down, t, kc.finger)
    deep = np.nan_to_num(kc.tip_depth, nan=-1.0) > KEY_BED_DEPTH_M + KEY_BED_TOL_M
    hits = []
    for r, f in zip(*np.nonzero(deep)):
        p = int(kc.tip_key[r, f]) + LOWEST_PITCH
        hits.append(KeyBedHit(float(t[r]), FINGERS[f], p, pitch_name(p),
                              float(kc.tip_depth[r, f])))
    if song_notes is None:
        return PlayResult(len(t), tuple(played), tuple(hits)), kc, None

    exp = expected_keys(song_notes, t)
    prec, rec, f1 = frame_scores(exp, kc.down)
    wrong = key_episodes(kc.down & ~exp, t, kc.finger)
    missed = []
    n_hit = 0
    t_last = float(t[-1])
    for n in song_notes:
        k0 = np.searchsorted(t, n.onset_s, side="left")
        k1 = np.searchsorted(t, n.offset_s, side="left")
        nf = k1 - k0
        frac = float(kc.down[k0:k1, n.pitch - LOWEST_PITCH].mean()) if nf else 0.0
        if nf and frac >= NOTE_HIT_FRACTION:
            n_hit += 1
            continue
        if nf:
            reason = "key never down" if frac == 0 else \
                f"key down in {frac:.0%} of its frames (< {NOTE_HIT_FRACTION:.0%})"
        elif n.onset_s > t_last:
            reason = "after the trajectory's end"
        else:
            reason = "no frame inside the note"
        missed.append(MissedNote(float(n.onset_s), float(n.offset_s), int(n.pitch),
                                 pitch_name(n.pitch), frac, reason))
    res = PlayResult(len(t), tuple(played), tuple(hits),
                     f1=float(f1.mean()), precision=float(prec.mean()), recall=float(rec.mean()),
                     notes=len(song_notes), notes_hit=n_hit, missed=tuple(missed),
                     wrong_presses=tuple(wrong))
    return res, kc, exp


def _catch(tr: Trajectory, kin: _Kin, tips: np.ndarray, palm: np.ndarray, path: str
           ) -> tuple[CatchResult, np.ndarray]:
    meta = tr.metadata
    ball = _ball_params(meta, path)
    ti = meta.get("intercept_t")
    if not _is_num(ti) or not math.isfinite(ti):
        raise InputError(f"{path}: catch metadata 'intercept_t' must be a finite number")
    ti = float(ti)
    r = ball["radius"]
    t = tr.t_s
    problems = []

    # intercept: joints interpolated linearly at ti
    b_i = ball_positions(ball["p0"], ball["v0"], ball["drag"], [ti])[0]
    target = np.full(3, np.nan)
    err = None
    if t[0] <= ti <= t[-1]:
        qi = np.array([np.interp(ti, t, tr.q[:, j]) for j in range(tr.q.shape[1])])
        _, P = kin.frames(qi[None])
        target = P[0, :3, 3] + r * P[0, :3, 2]
        err = float(np.linalg.norm(b_i - target))
        if err > INTERCEPT_TOL_M:
            problems.append(f"ball misses the palm: {err * 1000:.1f} mm from palm_center + radius"
                            f" * normal at t={ti:.3f} s (max {INTERCEPT_TOL_M * 1000:g} mm)")
    else:
        problems.append(f"intercept_t {ti:.3f} s is outside the trajectory "
                        f"({t[0]:.3f}..{t[-1]:.3f} s)")

    # before the intercept: no fingertip inside the ball
    before = t < ti
    touches = []
    if before.any():
        bp = ball_positions(ball["p0"], ball["v0"], ball["drag"], t[before])
        d = np.linalg.norm(tips[before] - bp[:, None, :], axis=-1)
        for k, f in zip(*np.nonzero(d < r)):
            touches.append(TipTouch(float(t[before][k]), FINGERS[f], float(d[k, f])))
    if touches:
        problems.append(f"{len(touches)} fingertip contacts with the ball before the intercept "
                        f"(first: {touches[0].finger} at {touches[0].time_s:.3f} s)")

    # after: the ball rides on the palm; the grasp must close and hold
    after = np.flatnonzero(t >= ti)
    centre = palm[after, :3, 3] + r * palm[after, :3, 2]
    d_after = np.linalg.norm(tips[after] - centre[:, None, :], axis=-1)
    closed = d_after <= r + GRASP_TOL_M
    thumb = FINGERS.index("thumb")
    grasped = (closed.sum(axis=1) >= GRASP_MIN_TIPS) & closed[:, thumb]
    in_window = t[after] <= ti + GRASP_WINDOW_S + 1e-9
    g_time, g_fingers, held = None, (), False
    first = np.flatnonzero(grasped & in_window)
    if first.size:
        k = int(first[0])
        g_time = float(t[after[k]])
        g_fingers = tuple(FINGERS[f] for f in np.flatnonzero(closed[k]))
        held = bool(grasped[k:].all())
        if not held:
            lost = k + int(np.argmin(grasped[k:]))
            problems.append(f"grasp lost at t={t[after[lost]]:.3f} s")
    else:
        best = int(closed.sum(axis=1)[in_window].max()) if in_window.any() else 0
        problems.append(f"no grasp within {GRASP_WINDOW_S * 1000:g} ms of the intercept "
                        f"(needs {GRASP_MIN_TIPS} fingertips including the thumb within "
                        f"radius + {GRASP_TOL_M * 1000:g} mm; best row had {best})")
    load = np.where(t >= ti, ball["mass"], 0.0)
    res = CatchResult(ti, r, tuple(float(x) for x in b_i), tuple(float(x) for x in target), err,
                      err is not None and err <= INTERCEPT_TOL_M, tuple(touches), g_time,
                      g_fingers, held,
                      float(d_after.min()) if d_after.size else None, tuple(problems))
    return res, load


def check_trajectory(traj_path: str, song_path: str | None = None, *,
                     allow_incomplete: bool = False, min_f1: float | None = None,
                     hand_override: str | HandModel | None = None) -> CheckReport:
    """Replay ``traj_path`` and audit it (see the module docstring).

    ``song_path``: a MIDI file (play only) for F1, note hits and wrong presses.
    ``min_f1``: the verdict also requires frame F1 >= this (needs a song).
    ``hand_override``: a hand name / hand file or a HandModel to use instead of
    metadata["hand"] (its URDF hash must still match the file's).
    Raises InputError when the file cannot be replayed: incomplete (unless
    allowed), unknown hand, URDF hash or column mismatch, bad T_world_root, bad
    catch metadata.
    """
    tr = read_trajectory(traj_path, allow_incomplete=allow_incomplete)
    meta = tr.metadata
    hand = _load_hand(meta, traj_path, hand_override)
    if meta["urdf_sha256"] != hand.urdf_sha256:
        raise InputError(f"{traj_path}: urdf_sha256 mismatch: the file was planned for "
                         f"{meta['urdf_sha256']!r}, hand {hand.name!r} is {hand.urdf_sha256!r}")
    _check_columns(tr, hand, traj_path)
    T_world_root = _T_world_root(meta, hand, traj_path)
    rate = meta["rate_hz"]
    if not _is_num(rate) or not rate > 0:
        raise InputError(f"{traj_path}: rate_hz must be a positive number, got {rate!r}")
    if min_f1 is not None and not (0.0 <= min_f1 <= 1.0):
        raise InputError(f"--min-f1 must be within 0..1, got {min_f1}")
    task = meta["task"]
    if song_path is not None and task != "play":
        raise InputError(f"a song was given but {traj_path} is a {task} trajectory")
    if min_f1 is not None and song_path is None:
        raise InputError("--min-f1 needs a song")

    kin = _Kin(hand, T_world_root)
    tips, palm = kin.frames(tr.q)
    problems: list[str] = []
    play = catch = None
    replay_kw: dict[str, Any] = {}
    pressing = ball_load = None
    if task == "play":
        notes = None
        if song_path is not None:
            from planner.music.midi import load_song

            notes = load_song(song_path).notes
        play, kc, exp = _play(tr, tips, notes, song_path)
        pressing = np.nan_to_num(kc.tip_depth, nan=-1.0) >= DOWN_DEPTH_M
        replay_kw = {"down": kc.down, "finger": kc.finger, "expected": exp}
        if play.key_bed_hits:
            h = play.key_bed_hits[0]
            problems.append(f"{len(play.key_bed_hits)} key-bed hits (first: {h.finger} on {h.name}"
                            f" at {h.time_s:.3f} s, {h.depth_m * 1000:.2f} mm deep)")
        if play.wrong_presses:
            w = play.wrong_presses[0]
            problems.append(f"{len(play.wrong_presses)} wrong presses (first: {w.name} at "
                            f"{w.start_s:.3f} s)")
        if min_f1 is not None and play.f1 < min_f1:
            problems.append(f"frame F1 {play.f1:.4f} < {min_f1:g}")
    else:
        catch, ball_load = _catch(tr, kin, tips, palm, traj_path)
        problems.extend(catch.problems)

    limits = _limit_audit(hand, kin, tr, pressing, ball_load)
    for lc in limits:
        if not lc.ok:
            problems.append(f"{lc.count} {lc.category.replace('_', ' ')} violations (worst "
                            f"{lc.worst:.6g} vs {lc.limit:.6g} {lc.unit}, {lc.name} at "
                            f"{lc.time_s:.3f} s)")
    return CheckReport(
        trajectory=os.fspath(traj_path), song=None if song_path is None else os.fspath(song_path),
        task=task, hand=hand.name, urdf_sha256=hand.urdf_sha256, complete=tr.complete,
        rows=len(tr.t_s), duration_s=float(tr.t_s[-1] - tr.t_s[0]), rate_hz=float(rate),
        limits=tuple(limits), play=play, catch=catch, min_f1=min_f1, problems=tuple(problems),
        replay=Replay(tr.t_s, tr.q, tips, palm, **replay_kw))


def check_cli(args) -> int:
    """``cli.py check``: print the summary (or one JSON object with --json);
    0 when the check passes, 1 otherwise. ``--played OUT.mid`` writes the
    key-down episodes as notes (velocity 64). ``--report DIR`` / ``--html FILE``
    are handed to ``planner.report`` (``write_check_report(report, DIR)``,
    ``write_html(report, FILE)``) when that module exists."""
    report = check_trajectory(args.trajectory, args.song,
                              allow_incomplete=bool(getattr(args, "allow_incomplete", False)),
                              min_f1=getattr(args, "min_f1", None))
    played = getattr(args, "played", None)
    if played:
        from planner.music.midi import Note, write_notes_midi

        eps = report.play.played if report.play is not None else ()
        write_notes_midi([Note(e.pitch, e.start_s, e.end_s, 64) for e in eps], played)
    if getattr(args, "report", None) or getattr(args, "html", None):
        import importlib.util

        if importlib.util.find_spec("planner.report") is None:
            raise InputError("--report needs planner.report")
        from planner.report import write_check_report, write_html

        if args.report:
            write_check_report(report, args.report)
        if args.html:
            write_html(report, args.html)
    if getattr(args, "json", False):
        print(json.dumps(report.to_dict()))
    else:
        print(report.summary())
    return 0 if report.ok else 1
