"""Every number of a hand file, checked on load against its unit and a physical range.

A key's unit is its suffix (``mass_kg``, ``velocity_cap_rad_s``, ``lower_deg``), or the
suffix of the table it sits in (``masses_kg = { base = 0.028 }``). A number outside
its unit's range is refused in one line naming the key (``rail.mass_kg``), before any
part of the hand is built: a palm of -1 kg, a speed cap of 0 or 1e-6 rad/s (no move
ends), or of 1e300 (no motor turns that fast) never reach the planners. Strings (names,
descriptions) must be printable. The builders check the relations between numbers
(lower below upper, a ratio within its range).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from planner.errors import InputError


@dataclass(frozen=True)
class UnitRange:
    """A unit and the values a real hand can have in it (``low_open``: low excluded)."""

    unit: str
    low: float
    high: float
    low_open: bool = False

    def holds(self, v: float) -> bool:
        return (v > self.low if self.low_open else v >= self.low) and v <= self.high

    def text(self) -> str:
        return f"{'(' if self.low_open else '['}{self.low:g}, {self.high:g}] {self.unit}"


# longest suffix first: "_rad_s2" before "_rad_s", "_m_s2" before "_m_s" before "_m"
UNITS: tuple[tuple[str, UnitRange], ...] = (
    ("_rad_s2", UnitRange("rad/s^2", 1.0, 1e6)),       # a joint's acceleration cap
    ("_rad_s", UnitRange("rad/s", 0.1, 1e5)),          # a speed cap, a motor's speed
    ("_m_s2", UnitRange("m/s^2", 0.1, 1e4)),           # the rail's acceleration
    ("_m_s", UnitRange("m/s", 0.01, 100.0)),           # the rail's speed
    ("_g_cm2", UnitRange("g cm^2", 0.0, 1e7)),         # a rotor's inertia
    ("_kg", UnitRange("kg", 0.0, 100.0, low_open=True)),  # a mass
    ("_nm", UnitRange("N m", 0.0, 1e4, low_open=True)),   # a motor's torque
    ("_n", UnitRange("N", 0.0, 1e5, low_open=True)),      # a force
    ("_deg", UnitRange("deg", -360.0, 360.0)),         # an angle
    ("_in", UnitRange("in", -400.0, 400.0)),           # a length or place, inches
    ("_m", UnitRange("m", -10.0, 10.0)),               # a length or place, metres
)
PLAIN = UnitRange("(no unit)", -1e6, 1e6)  # ratios, efficiencies, scales


def unit_of(key: str, table_unit: UnitRange | None = None) -> UnitRange | None:
    """The unit a key's suffix names (None: it names none)."""
    for suffix, u in UNITS:
        if key.endswith(suffix):
            return u
    return table_unit


def check_hand_numbers(data: dict[str, Any]) -> None:
    """InputError naming the first key whose number is out of its unit's range (or not
    finite) or whose text is not printable."""
    _walk(data, "", None)


def _walk(x: Any, where: str, unit: UnitRange | None) -> None:
    if isinstance(x, dict):
        for k, v in x.items():
            if not isinstance(k, str) or not k.isprintable():
                raise InputError(f"key {k!r} in {where or 'the file'} is not printable text")
            _walk(v, f"{where}.{k}" if where else k, unit_of(k, unit))
    elif isinstance(x, list):
        for i, v in enumerate(x):
            _walk(v, f"{where}[{i}]", unit)
    elif isinstance(x, str):
        if not x.isprintable():
            raise InputError(f"{where!r} is not printable text: {x[:40]!r}")
    elif isinstance(x, (int, float)) and not isinstance(x, bool):
        u = unit or PLAIN
        if not math.isfinite(x) or not u.holds(x):
            raise InputError(f"{where!r} = {x!r} is outside {u.text()}, the range a real hand "
                             "can have")
