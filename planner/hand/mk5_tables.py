"""The seed's parameter tables of the "Hand Mk5" leverism (Mk5.0 and Mk5.1), in SI units.

Source: the "Hand Mk5 Coupling Laws" document (seed 003_c67a0a60de048708): two
parameter tables, one per hand revision, columns THUMB INDEX MIDDLE RING PINKY. The
laws that use them are in ``planner.hand.mk5``; the frame (``P0`` the origin, points
fully open) and what the coordinates confirm are described there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

_MM = 1e-3
_DEG = math.pi / 180.0

FINGERS: tuple[str, ...] = ("thumb", "index", "middle", "ring", "pinky")


@dataclass(frozen=True)
class Mk5FingerParams:
    """Coupling parameters of one Mk5 finger, in SI units (metres, radians).

    ``P0`` is the origin. Points are given fully open: ``L0`` is the fixed
    end of the leverism (palm), ``L1`` its end on the second phalanx, ``P1``
    the second joint axis. ``q*_off``/``q*_bias`` are the fully-open angles
    of ``A - C`` (q0_off), ``P1 - P0`` (q1_off), ``B - P0`` (q1_bias) and
    ``L1 - P1`` (q2_bias). ``q*_max`` are the joint values at full closure.
    Lengths: ``k = |L1 - L0|``, ``d = |P1 - P0|``, ``l = |L1 - P1|``,
    ``b = |L0 - P0|``, ``s = |B - P0|``, ``t = |A - B|``, ``f = |A - C|``,
    ``r = |D - C|`` and ``r_mot`` the motor pulley radius (``None`` if the
    table does not give it). ``cx, cy`` is the crank pivot ``C``, which the
    tables do not give (``None`` unless set, e.g. by :func:`with_c_point`).
    """

    l0x: float
    l0y: float
    l1x: float
    l1y: float
    p1x: float
    p1y: float
    q0_off: float
    q2_bias: float
    q1_off: float
    q1_bias: float
    q0_max: float
    q1_max: float
    q2_max: float
    k: float
    d: float
    l: float  # the document's name for |L1 - P1|
    b: float
    s: float
    t: float
    f: float
    r: float
    r_mot: float | None = None
    cx: float | None = None
    cy: float | None = None

    @property
    def c_point(self) -> tuple[float, float] | None:
        """The crank pivot ``C`` (m), or ``None`` if unknown."""
        if self.cx is None or self.cy is None:
            return None
        return (self.cx, self.cy)

    @property
    def k_geom(self) -> float:
        """``|L1 - L0|`` recomputed from the coordinates (m)."""
        return math.hypot(self.l1x - self.l0x, self.l1y - self.l0y)

    @property
    def l_geom(self) -> float:
        """``|L1 - P1|`` recomputed from the coordinates (m)."""
        return math.hypot(self.l1x - self.p1x, self.l1y - self.p1y)

    @property
    def d_geom(self) -> float:
        """``|P1 - P0|`` recomputed from the coordinates (m), P0 = origin."""
        return math.hypot(self.p1x, self.p1y)

    @property
    def b_geom(self) -> float:
        """``|L0 - P0|`` recomputed from the coordinates (m), P0 = origin."""
        return math.hypot(self.l0x, self.l0y)

    @property
    def q1_off_geom(self) -> float:
        """Angle of ``P1 - P0`` recomputed from the coordinates (rad)."""
        return math.atan2(self.p1y, self.p1x)

    @property
    def q2_bias_geom(self) -> float:
        """Angle of ``L1 - P1`` recomputed from the coordinates (rad), in (-pi, pi]."""
        return math.atan2(self.l1y - self.p1y, self.l1x - self.p1x)


# --------------------------------------------------------------------------- tables
# Typed once, exactly as printed: lengths in mm, angles in deg. Row order is
# THUMB, INDEX, MIDDLE, RING, PINKY. Converted to SI by _build_table.
_RAW_TABLES: dict[str, dict[str, tuple[float, ...] | None]] = {
    "mk5.1": {
        "l0x": (-5, -5, -5, -5, -5),
        "l0y": (4, 4, 4, 4, 4),
        "l1x": (29, 34, 34, 34, 29),
        "l1y": (0.8, 0.8, 0.8, 0.8, 0.5),
        "p1x": (35, 40, 40, 40, 35),
        "p1y": (1.5, 1.5, 1.5, 1.5, 1.5),
        "q0_off": (-97.54, -97.54, -97.54, -97.54, -97.52),
        "q2_bias": (-173.35, -173.35, -173.35, -173.35, -170.53),
        "q1_off": (2.45, 2.15, 2.15, 2.15, 2.46),
        "q1_bias": (-90, -90, -90, -90, -90),
        "q0_max": (-12, -12, -12, -12, -11.97),
        "q1_max": (90, 90, 90, 90, 90),
        "q2_max": (191.44, 193.06, 193.06, 193.06, 188.7),
        "k": (34.15, 39.13, 39.13, 39.13, 34.18),
        "d": (35.03, 40.03, 40.03, 40.03, 35.03),
        "l": (6.04, 6.04, 6.04, 6.04, 6.08),
        "b": (6.4, 6.4, 6.4, 6.4, 6.4),
        "s": (5.5, 5.5, 5.5, 5.5, 5.5),
        "t": (14.5, 14.5, 14.5, 14.5, 14.5),
        "f": (5.5, 5.5, 5.5, 5.5, 5.5),
        "r": (8.5, 8.5, 8.5, 8.5, 8.5),
        "r_mot": (5, 5, 5, 5, 5),
    },
    "mk5.0": {
        "l0x": (-5.55, -5, -5, -5, -5),
        "l0y": (2.85, 4, 4, 4, 4),
        "l1x": (11.5, 24, 24, 24, 19),
        "l1y": (1.5, 0.8, 0.8, 0.8, 0.5),
        "p1x": (20, 30, 30, 30, 25),
        "p1y": (1.5, 1.5, 1.5, 1.5, 1.5),
        "q0_off": (-110.71, -97.54, -97.54, -97.54, -97.54),
        "q2_bias": (-180, -173.35, -173.35, -173.35, -170.54),
        "q1_off": (4.29, 2.86, 2.86, 2.86, 3.43),
        "q1_bias": (-90, -90, -90, -90, -90),
        "q0_max": (-44.68, -11.97, -11.97, -11.97, -11.97),
        "q1_max": (86.35, 90, 90, 90, 90),
        "q2_max": (135.65, 189.2, 189.2, 189.2, 183.31),
        "k": (17.1, 29.18, 29.18, 29.18, 24.25),
        "d": (20.06, 30.04, 30.04, 30.04, 25.04),
        "l": (8.5, 6.04, 6.04, 6.04, 6.08),
        "b": (6.24, 6.4, 6.4, 6.4, 6.4),
        "s": (6.52, 5.5, 5.5, 5.5, 5.5),
        "t": (13, 14.5, 14.5, 14.5, 14.5),
        "f": (6, 5.5, 5.5, 5.5, 5.5),
        "r": (7.5, 8.5, 8.5, 8.5, 8.5),
        "r_mot": None,  # no r_mot row in the Mk5.0 table
    },
}

_ANGLE_FIELDS = frozenset({"q0_off", "q2_bias", "q1_off", "q1_bias", "q0_max", "q1_max", "q2_max"})


def _build_table(raw: dict[str, tuple[float, ...] | None]) -> dict[str, Mk5FingerParams]:
    out: dict[str, Mk5FingerParams] = {}
    for i, finger in enumerate(FINGERS):
        kwargs: dict[str, float | None] = {}
        for name, row in raw.items():
            if row is None:
                kwargs[name] = None
            else:
                kwargs[name] = float(row[i]) * (_DEG if name in _ANGLE_FIELDS else _MM)
        out[finger] = Mk5FingerParams(**kwargs)  # type: ignore[arg-type]
    return out


MK5_TABLES: dict[str, dict[str, Mk5FingerParams]] = {
    version: _build_table(raw) for version, raw in _RAW_TABLES.items()
}


def table_consistency(p: Mk5FingerParams) -> dict[str, tuple[float, float]]:
    """Table value vs value recomputed from the coordinates (P0 = origin).

    Returns ``{name: (table, from_coordinates)}`` for ``k, l, d, b`` (m) and
    ``q1_off, q2_bias`` (rad; ``q2_bias`` from coordinates is shifted by a
    multiple of 2 pi to the table's branch). ``s, t, f, r`` involve the
    points ``A, B, C, D`` that the table does not give and cannot be checked.
    """
    q2b = p.q2_bias_geom
    q2b += 2.0 * math.pi * round((p.q2_bias - q2b) / (2.0 * math.pi))
    return {
        "k": (p.k, p.k_geom),
        "l": (p.l, p.l_geom),
        "d": (p.d, p.d_geom),
        "b": (p.b, p.b_geom),
        "q1_off": (p.q1_off, p.q1_off_geom),
        "q2_bias": (p.q2_bias, q2b),
    }
