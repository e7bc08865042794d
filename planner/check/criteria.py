"""The rules a plan is judged by: one definition, imported by ``check`` and by the
planners' self-checks alike.

* Key down (spec section 2): a fingertip point inside a key's footprint (for a
  white key minus the black keys' rectangles) at least ``DOWN_DEPTH_M`` below the
  key's resting top (``key_contacts``); or any collision body of the hand reaching
  that deep inside a footprint, and none more than ``BED_MARGIN_M`` past the key bed
  (the body rule, ``planner.check.bodykeys``).
* The song's frames: a note sounds in frame ``t`` when ``onset_s <= t < offset_s``
  (``expected_keys``). The frames a song is scored over are the rows' clock,
  k / rate_hz from t = 0, up to the end of the last note (``song_frames``): rows
  missing at the end count as frames with nothing pressed, rows after the song
  do not dilute the score (RoboPianist scores the song's length).
* Frame F1 (``frame_scores``): per frame, a binary classification over the 88
  keys scored like ``sklearn.metrics.precision_recall_fscore_support(...,
  average="binary", zero_division=1)``, averaged over the song's frames.
* Notes (``note_outcomes``): a note is hit when its key is down in at least
  ``NOTE_HIT_FRACTION`` of its frames; it is late when its key first goes down
  more than ``LATE_S`` after its onset (20 ms: the onset asynchrony listeners
  begin to hear, Hirsh 1959; the planner reports the same threshold).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from planner.errors import InputError
from planner.music.keyboard import (
    DOWN_DEPTH_M,
    HIGHEST_PITCH,
    KEY_BED_DEPTH_M,
    KEY_DIP_M,
    LOWEST_PITCH,
    key_table,
    pitch_name,
)

__all__ = [
    "BED_MARGIN_M", "BODY_BED_DEPTH_M", "DOWN_DEPTH_M", "HANDS_GAP_M", "KEY_BED_DEPTH_M", "LATE_S", "NOTE_HIT_FRACTION", "N_KEYS",
    "KeyContacts", "NoteOutcome", "expected_keys", "frame_f1", "frame_scores",
    "key_contacts", "note_outcomes", "pitch_name", "song_frames",
]

N_KEYS = HIGHEST_PITCH - LOWEST_PITCH + 1  # 88
BED_MARGIN_M = 0.001  # spec section 2 (bodies): no body more than 1 mm below the key bed
BODY_BED_DEPTH_M = KEY_DIP_M + BED_MARGIN_M  # ... so 11 mm below a key's resting top
NOTE_HIT_FRACTION = 0.5  # a note is hit when its key is down in >= 50 % of its frames
LATE_S = 0.020  # a key first down later than this after its onset is late (see above)
INTERCEPT_TOL_M = 0.015  # ball centre vs palm_center + radius * normal at intercept_t
GRASP_WINDOW_S = 0.150  # the grasp must close within this after intercept_t
GRASP_TOL_M = 0.010  # a fingertip "closed around" the ball: distance <= radius + this
GRASP_MIN_TIPS = 3  # ... at least this many, the thumb among them
# Two hands on one keyboard (``planner.check.handgap``): the least distance between any body
# of one and any of the other. Twice the rail's stop margin (default.toml [drive]
# stop_margin_m, 5 mm: a belt axis' end-stop bumpers and its homing repeatability): each
# carriage may stand that far from where its rows put it, towards the other.
HANDS_GAP_M = 0.010


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
    tip_key, tip_depth = tip_depths(tips)
    any_hit = tip_key >= 0
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


def tip_depths(tips: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``KeyContacts.tip_key`` and ``tip_depth`` of fingertip points ``tips`` (T, F, 3):
    the key under each tip (-1: none) and how deep below its top (NaN: none)."""
    tips = np.asarray(tips, dtype=float)
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
    return tip_key, np.where(any_hit, top - tips[..., 2], np.nan)


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


def song_frames(notes, rate_hz: float) -> np.ndarray:
    """The frames a song is scored over: k / rate_hz from 0 while before the end of its
    last note (at least one frame)."""
    end_s = max((n.offset_s for n in notes), default=0.0)
    return np.arange(max(1, math.ceil(end_s * rate_hz - 1e-9))) / rate_hz


@dataclass(frozen=True)
class NoteOutcome:
    """What the replay finds of one note: the fraction of its frames with its key
    down, whether that makes it hit, and how late its key first went down (s, None
    when never down within the note)."""

    frames: int
    fraction_down: float
    hit: bool
    late_s: float | None

    @property
    def late(self) -> bool:
        return self.late_s is not None and self.late_s > LATE_S


def note_outcomes(notes, t_s: np.ndarray, down: np.ndarray) -> list[NoteOutcome]:
    """``NoteOutcome`` of every note, from key states ``down`` (T, 88) at frames ``t_s``."""
    t_s = np.asarray(t_s, dtype=float)
    out = []
    for n in notes:
        k0 = int(np.searchsorted(t_s, n.onset_s, side="left"))
        k1 = int(np.searchsorted(t_s, n.offset_s, side="left"))
        col = down[k0:k1, n.pitch - LOWEST_PITCH]
        frac = float(col.mean()) if k1 > k0 else 0.0
        first = int(np.argmax(col)) if col.any() else None
        late = None if first is None else max(0.0, float(t_s[k0 + first] - n.onset_s))
        out.append(NoteOutcome(k1 - k0, frac, k1 > k0 and frac >= NOTE_HIT_FRACTION, late))
    return out
