"""Keyboard geometry in the keyboard frame of the interface spec, section 2.

x runs along the keyboard towards higher pitch, with x = 0 on the centre line
of middle C (MIDI 60); y runs from the front edge of the white keys back into
the keyboard; z is up, with z = 0 on the resting top of the white keys.
Everything here is computed from the standard key dimensions below; no key
position is typed in.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache, lru_cache

import numpy as np

LOWEST_PITCH = 21  # A0
HIGHEST_PITCH = 108  # C8
MIDDLE_C = 60

WHITE_PITCH_M = 0.0235  # centre to centre
WHITE_WIDTH_M = 0.0225
WHITE_LENGTH_M = 0.150
BLACK_WIDTH_M = 0.010
BLACK_Y0_M = 0.060
BLACK_Y1_M = 0.150
BLACK_TOP_Z_M = 0.0125
KEY_DIP_M = 0.010
DOWN_DEPTH_M = 0.005  # a key is down when a fingertip is this far below its top
KEY_BED_DEPTH_M = 0.012  # deeper than this below the top goes through the key bed

_BLACK_IN_OCTAVE = frozenset({1, 3, 6, 8, 10})
PITCH_CLASS_NAMES = ("C", "C#", "D", "D#", "E", "F", "F#", "G", "G#", "A", "A#", "B")


def pitch_name(pitch: int) -> str:
    """Scientific pitch name: 60 -> 'C4', 61 -> 'C#4', 21 -> 'A0'."""
    return f"{PITCH_CLASS_NAMES[pitch % 12]}{pitch // 12 - 1}"


def is_black(pitch: int) -> bool:
    """True for the black keys (C#, D#, F#, G#, A#)."""
    return pitch % 12 in _BLACK_IN_OCTAVE


def white_index(pitch: int) -> int:
    """Number of white keys between middle C and the white key ``pitch`` (0 for C4)."""
    octave, pc = divmod(pitch - MIDDLE_C, 12)
    whites_before = sum(1 for c in range(pc) if c not in _BLACK_IN_OCTAVE)
    return octave * 7 + whites_before


@dataclass(frozen=True)
class Key:
    """One key: its footprint (x/y rectangle), resting top height and press point, in metres."""

    pitch: int
    black: bool
    x_min_m: float
    x_max_m: float
    y_min_m: float
    y_max_m: float
    top_z_m: float

    @property
    def center_x_m(self) -> float:
        return 0.5 * (self.x_min_m + self.x_max_m)

    def press_point(self) -> np.ndarray:
        """Where a fingertip presses the key at full dip: (x, y, z) in metres.

        White keys are pressed in front of the black keys (y halfway between
        the front edge and the black keys' front), black keys 30 mm behind
        their front end.
        """
        y = 0.5 * BLACK_Y0_M if not self.black else BLACK_Y0_M + 0.030
        return np.array([self.center_x_m, y, self.top_z_m - KEY_DIP_M])


def _white_center_x(pitch: int) -> float:
    return white_index(pitch) * WHITE_PITCH_M


@cache
def key(pitch: int) -> Key:
    """The key of a MIDI pitch in 21..108 (ValueError outside)."""
    if not LOWEST_PITCH <= pitch <= HIGHEST_PITCH:
        raise ValueError(f"pitch {pitch} is outside the keyboard ({LOWEST_PITCH}..{HIGHEST_PITCH})")
    if is_black(pitch):
        # centred on the boundary between the white neighbours pitch-1 and pitch+1
        xc = 0.5 * (_white_center_x(pitch - 1) + _white_center_x(pitch + 1))
        h = 0.5 * BLACK_WIDTH_M
        return Key(pitch, True, xc - h, xc + h, BLACK_Y0_M, BLACK_Y1_M, BLACK_TOP_Z_M)
    xc = _white_center_x(pitch)
    h = 0.5 * WHITE_WIDTH_M
    return Key(pitch, False, xc - h, xc + h, 0.0, WHITE_LENGTH_M, 0.0)


ALL_PITCHES = tuple(range(LOWEST_PITCH, HIGHEST_PITCH + 1))


@cache
def footprint(pitch: int) -> tuple[tuple[float, float, float, float], ...]:
    """A key's footprint (spec section 2) as rectangles (x_min, x_max, y_min, y_max), m: a
    black key's own; a white key's front (y up to the black keys' front, its full width)
    and its back (its rectangle less its black neighbours', as far back as they reach)."""
    k = key(pitch)
    if k.black:
        return ((k.x_min_m, k.x_max_m, k.y_min_m, k.y_max_m),)
    lo, hi = k.x_min_m, k.x_max_m
    if pitch - 1 >= LOWEST_PITCH and is_black(pitch - 1):
        lo = max(lo, key(pitch - 1).x_max_m)
    if pitch + 1 <= HIGHEST_PITCH and is_black(pitch + 1):
        hi = min(hi, key(pitch + 1).x_min_m)
    return ((k.x_min_m, k.x_max_m, k.y_min_m, BLACK_Y0_M), (lo, hi, BLACK_Y0_M, k.y_max_m))


@lru_cache(maxsize=1)
def key_table() -> dict[str, np.ndarray]:
    """All 88 keys as arrays (pitch, black, x_min, x_max, y_min, y_max, top_z) for vector tests."""
    keys = [key(p) for p in ALL_PITCHES]
    return {
        "pitch": np.array([k.pitch for k in keys]),
        "black": np.array([k.black for k in keys]),
        "x_min": np.array([k.x_min_m for k in keys]),
        "x_max": np.array([k.x_max_m for k in keys]),
        "y_min": np.array([k.y_min_m for k in keys]),
        "y_max": np.array([k.y_max_m for k in keys]),
        "top_z": np.array([k.top_z_m for k in keys]),
    }


def key_under(x_m: float, y_m: float) -> Key | None:
    """The key whose footprint contains (x, y), black keys taking precedence; None if none."""
    t = key_table()
    inside = (t["x_min"] <= x_m) & (x_m <= t["x_max"]) & (t["y_min"] <= y_m) & (y_m <= t["y_max"])
    idx = np.flatnonzero(inside)
    if idx.size == 0:
        return None
    black = [i for i in idx if t["black"][i]]
    return key(int(t["pitch"][black[0] if black else idx[0]]))


def surface_z(x_m: float, y_m: float) -> float:
    """Resting top height of whatever key lies under (x, y); white top (0) where there is none."""
    k = key_under(x_m, y_m)
    return 0.0 if k is None else k.top_z_m
