"""A hand file's values, read and checked: a required number, a length (inches or
metres), a positive number, an angle range (degrees in the file, radians out), a
vector, a motor's rotor inertia. Every error is an ``InputError`` naming the key."""

from __future__ import annotations

import math
from typing import Any

from planner.errors import InputError
from planner.hand.spec import INCH_M, ROTOR_KEY


def get_value(d: dict[str, Any], key: str, kind: type = float) -> Any:
    if key not in d:
        raise InputError(f"missing key {key!r}")
    v = d[key]
    if kind is float:
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise InputError(f"{key!r} must be a finite number, got {v!r}")
        return float(v)
    if not isinstance(v, kind):
        raise InputError(f"{key!r} must be a {kind.__name__}, got {v!r}")
    return v


def get_length(d: dict[str, Any], key: str) -> float:
    """A length given as ``key_in`` (inches) or ``key_m`` (metres), in metres; must be > 0."""
    if f"{key}_in" in d:
        v = get_value(d, f"{key}_in") * INCH_M
    else:
        v = get_value(d, f"{key}_m")
    if v <= 0:
        raise InputError(f"length {key!r} must be positive")
    return v


def rotor_inertia(d: dict[str, Any], key: str = ROTOR_KEY) -> float:
    """A motor's rotor inertia (kg m^2) from its table's ``key`` (g cm^2, optional: 0)."""
    if key not in d:
        return 0.0
    v = get_value(d, key)
    if v < 0:
        raise InputError(f"{key!r} must not be negative, got {v!r}")
    return v * 1e-7


def get_positive(d: dict[str, Any], key: str) -> float:
    v = get_value(d, key)
    if v <= 0:
        raise InputError(f"{key!r} must be positive, got {v!r}")
    return v


def get_range(d: dict[str, Any], key: str) -> tuple[float, float]:
    r = get_value(d, key, dict)
    lo, hi = math.radians(get_value(r, "lower_deg")), math.radians(get_value(r, "upper_deg"))
    if not lo < hi:
        raise InputError(f"{key!r}: lower_deg must be below upper_deg")
    return lo, hi


def get_vec(d: dict[str, Any], key: str, n: int = 3) -> tuple[float, ...]:
    v = get_value(d, key, list)
    if len(v) != n or not all(isinstance(x, (int, float)) and math.isfinite(x) for x in v):
        raise InputError(f"{key!r} must be a list of {n} finite numbers")
    return tuple(float(x) for x in v)
