"""Nonlinear finger coupling laws of the "Hand Mk5" leverism (Mk5.0 and Mk5.1).

Source: the "Hand Mk5 Coupling Laws" document (formulas plus two parameter
tables, one per hand revision, columns THUMB INDEX MIDDLE RING PINKY; the tables
are in ``planner.hand.mk5_tables``).

Joint variables (all angles in radians, all lengths in metres):

* ``q_mot`` -- motor pulley angle (forearm).
* ``q0``    -- angle of the crank ``A - C``; ``q0 = 0`` when the finger is
  fully open (the table's ``q0_off`` is "angle of A-C when fully open" and
  ``A = C + f (cos(q0 + q0_off), sin(q0 + q0_off))``).
* ``q1``    -- angle of the first phalanx about ``P0`` (measured by the joint
  encoder); ``q1 = 0`` fully open.
* ``q2``    -- angle of the second phalanx, i.e. of the lever ``L1 - P1``,
  measured *in the palm frame* from its fully-open direction ``q2_bias``.
  It is therefore an absolute angle (it reaches ~190 deg at full closure);
  the relative flexion of the second joint is ``q2 - q1``.

Frame assumption: ``P0`` (the proximal joint axis) is the origin ``(0, 0)``;
the table gives ``L0``, ``L1``, ``P1`` in that frame with the finger fully
open. This is confirmed by the table itself: ``b = |L0 - P0|``,
``d = |P1 - P0|`` and ``q1_off = angle(P1 - P0)`` all match the coordinates
to the table's printed precision with ``P0 = (0, 0)`` (see
:func:`table_consistency`). ``P1`` in the ``q2`` law is the *rotating* joint
``P1(q1) = d (cos(q1 + q1_off), sin(q1 + q1_off))``; the table's ``P1`` is
its position at ``q1 = 0``.

What reproduces the table (checked in ``tests/test_mk5.py``):

* ``q2`` must use lengths recomputed from the coordinates
  (``k = |L1 - L0|``, ``l = |L1 - P1|``, ``d = |P1|``,
  ``q1_off = atan2(P1y, P1x)``). The quadrilateral is close to flat at
  ``q1 = 0`` (``h`` is within 0.1 mm of ``k + l``), so the table's 0.01 mm
  rounding of ``k`` and ``l`` moves ``q2(0)`` by up to -0.16 deg (Mk5.1
  index/middle/ring) and -0.68 deg (Mk5.0 thumb). With the recomputed
  lengths and the table's ``q2_bias``, ``|q2(0)| < 0.01 deg`` for every
  finger and ``q2(q1_max)`` matches the table's ``q2_max`` within 0.03 deg
  for every finger except the Mk5.0 thumb, whose table entry (135.65 deg) is
  inconsistent with its own geometry (computed 142.92 deg).
* The printed ``tan^-1(y / x)`` must be read as ``atan2(y, x)``. On
  ``[0, q1_max]`` both agree (``P1x(q1) > L0x`` there) but the principal
  ``atan`` jumps by pi where ``P1x(q1) = L0x`` (q1 ~ 95-102 deg), while
  ``atan2`` is continuous until ``P1(q1) - L0`` crosses the negative x axis,
  far outside the joint range. No wrapping is applied to ``q2``: its range
  legitimately exceeds pi.

The ``q0 -> q1`` law needs the crank pivot ``C``, which the table does not
give; see :func:`derive_c_point` for what can and cannot be derived.
The Mk5.0 table has no ``r_mot`` row, so ``r_mot`` is ``None`` there.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Literal

import numpy as np
import numpy.typing as npt

from planner.hand.mk5_tables import Mk5FingerParams

ArrayLike = float | npt.NDArray[np.float64]
LengthSource = Literal["coords", "table"]

_ACOS_TOL = 1e-12  # tolerance on |acos argument| - 1 before declaring a linkage unassemblable


# --------------------------------------------------------------------------- helpers
def _as_out(x: npt.NDArray[np.float64]) -> ArrayLike:
    return float(x) if np.ndim(x) == 0 else x


def _safe_acos_arg(c: npt.NDArray[np.float64], what: str) -> npt.NDArray[np.float64]:
    if np.any(np.abs(c) > 1.0 + _ACOS_TOL) or np.any(~np.isfinite(c)):
        raise ValueError(f"{what}: linkage cannot be assembled (acos argument outside [-1, 1])")
    return np.clip(c, -1.0, 1.0)


def _wrap_pi(x: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """Wrap to [-pi, pi)."""
    return (x + math.pi) % (2.0 * math.pi) - math.pi


def _q2_geometry(p: Mk5FingerParams, lengths: LengthSource) -> tuple[float, float, float, float]:
    """``(d, q1_off, k, l)`` for the q2 law from the coordinates or the table."""
    if lengths == "coords":
        return p.d_geom, p.q1_off_geom, p.k_geom, p.l_geom
    if lengths == "table":
        return p.d, p.q1_off, p.k, p.l
    raise ValueError(f"lengths must be 'coords' or 'table', got {lengths!r}")


# --------------------------------------------------------------------------- q1 -> q2
def q2_of_q1(p: Mk5FingerParams, q1: ArrayLike, *, lengths: LengthSource = "coords") -> ArrayLike:
    """Second-phalanx angle ``q2`` (rad) from first-phalanx angle ``q1`` (rad).

    ``q2 = atan2(P1y - L0y, P1x - L0x) + acos((l^2 - k^2 + h^2) / (2 l h))
    - q2_bias - pi`` with ``P1(q1) = d (cos(q1 + q1_off), sin(q1 + q1_off))``
    (P0 = origin) and ``h = |P1(q1) - L0|``. Geometrically this is the
    palm-frame direction of ``L1 - P1`` minus its fully-open direction
    ``q2_bias`` (the ``acos`` is the triangle angle at ``P1``).

    ``lengths="coords"`` (default) takes ``d, q1_off, k, l`` from the
    coordinates, which reproduces the table; ``"table"`` uses the table's
    rounded values (kept only to document the difference). Vectorised over
    ``q1``; raises ``ValueError`` where the linkage cannot be assembled.
    """
    d, q1_off, k, l = _q2_geometry(p, lengths)
    q1a = np.asarray(q1, dtype=float)
    th = q1a + q1_off
    vx = d * np.cos(th) - p.l0x
    vy = d * np.sin(th) - p.l0y
    h = np.hypot(vx, vy)
    c = _safe_acos_arg((l * l - k * k + h * h) / (2.0 * l * h), "q2_of_q1")
    return _as_out(np.arctan2(vy, vx) + np.arccos(c) - p.q2_bias - math.pi)


def dq2_dq1(p: Mk5FingerParams, q1: ArrayLike, *, lengths: LengthSource = "coords") -> ArrayLike:
    """Analytic derivative ``dq2/dq1`` (rad/rad) of :func:`q2_of_q1`.

    Chain rule with ``P1' = dP1/dq1 = (-P1y, P1x)`` and ``v = P1 - L0``:

    * ``d/dq1 atan2(v) = (v x P1') / h^2 = (d^2 - L0.P1) / h^2``
    * ``dh/dq1 = (v . P1') / h = (L0x P1y - L0y P1x) / h``
    * ``d/dq1 acos(c) = -(dc/dh) (dh/dq1) / sqrt(1 - c^2)`` with
      ``dc/dh = (h^2 - l^2 + k^2) / (2 l h^2)``

    giving ``(d^2 - L0.P1)/h^2 + (L0x P1y - L0y P1x)(l^2 - k^2 - h^2)
    / (2 l h^3 sqrt(1 - c^2))``.

    The document's printed Jacobian (see :func:`dq2_dq1_printed`) is *not*
    garbled: since ``h^2 = d^2 + b^2 - 2 L0.P1`` (P0 = origin, b = |L0|),
    ``1 / (2 - (d^2 - b^2) / (d^2 - L0.P1))`` equals ``(d^2 - L0.P1) / h^2``,
    and its second term is identical to the one above. It is exact provided
    ``b`` and ``d`` are the exact ``|L0|`` and ``|P1|``, not rounded values.
    """
    d, q1_off, k, l = _q2_geometry(p, lengths)
    q1a = np.asarray(q1, dtype=float)
    th = q1a + q1_off
    p1x = d * np.cos(th)
    p1y = d * np.sin(th)
    vx = p1x - p.l0x
    vy = p1y - p.l0y
    h2 = vx * vx + vy * vy
    h = np.sqrt(h2)
    c = _safe_acos_arg((l * l - k * k + h2) / (2.0 * l * h), "dq2_dq1")
    dphi = (d * d - (p.l0x * p1x + p.l0y * p1y)) / h2
    dpsi = (
        (p.l0x * p1y - p.l0y * p1x)
        * (l * l - k * k - h2)
        / (2.0 * l * h2 * h * np.sqrt(1.0 - c * c))
    )
    return _as_out(dphi + dpsi)


def dq2_dq1_printed(
    p: Mk5FingerParams, q1: ArrayLike, *, b: float | None = None, lengths: LengthSource = "coords"
) -> ArrayLike:
    """The document's printed Jacobian formula, transcribed literally (rad/rad).

    ``1 / (2 - (d^2 - b^2) / (d^2 - (L0x P1x + L0y P1y)))
    + (L0x P1y - L0y P1x)(l^2 - k^2 - h^2) / (2 l h^3 sqrt(1 - c^2))``.

    ``b`` defaults to the exact ``|L0|``; pass the table's rounded ``p.b`` to
    see the error rounding introduces. Kept for verification; use
    :func:`dq2_dq1`.
    """
    d, q1_off, k, l = _q2_geometry(p, lengths)
    bb = p.b_geom if b is None else b
    q1a = np.asarray(q1, dtype=float)
    th = q1a + q1_off
    p1x = d * np.cos(th)
    p1y = d * np.sin(th)
    h = np.hypot(p1x - p.l0x, p1y - p.l0y)
    c = _safe_acos_arg((l * l - k * k + h * h) / (2.0 * l * h), "dq2_dq1_printed")
    first = 1.0 / (2.0 - (d * d - bb * bb) / (d * d - (p.l0x * p1x + p.l0y * p1y)))
    second = (
        (p.l0x * p1y - p.l0y * p1x)
        * (l * l - k * k - h * h)
        / (2.0 * l * h**3 * np.sqrt(1.0 - c * c))
    )
    return _as_out(first + second)


def q1_limits(p: Mk5FingerParams, *, lengths: LengthSource = "coords") -> tuple[float, float]:
    """Interval of ``q1`` (rad), containing 0, on which the q2 leverism assembles.

    The triangle ``L0, P1(q1), L1`` exists iff ``|k - l| <= h(q1) <= k + l``
    with ``h^2 = d^2 + b^2 - 2 d b cos(q1 + q1_off - angle(L0))``. Returns the
    connected interval around the fully open pose (``q1 = 0``); an end is
    infinite if the linkage never disassembles on that side. The joint's
    range ``[0, q1_max]`` lies inside it for every table finger, but only
    0.4-3.9 deg of hyperextension (q1 < 0) is possible before ``h`` reaches
    ``k + l``.
    """
    d, q1_off, k, l = _q2_geometry(p, lengths)
    b = p.b_geom
    phi_l0 = math.atan2(p.l0y, p.l0x)
    # h^2 grows with |delta|, delta = q1 + q1_off - angle(L0); the bounds on h
    # give |delta| in [lo, hi]. lo = 0 (hi = pi) when h cannot get short (long) enough.
    cos_hi = (d * d + b * b - (k - l) ** 2) / (2.0 * d * b)
    cos_lo = (d * d + b * b - (k + l) ** 2) / (2.0 * d * b)
    never_short = cos_hi >= 1.0
    never_long = cos_lo <= -1.0
    abs_lo = 0.0 if never_short else math.acos(max(-1.0, cos_hi))
    abs_hi = math.pi if never_long else math.acos(min(1.0, cos_lo))
    delta0 = math.remainder(q1_off - phi_l0, 2.0 * math.pi)
    if not abs_lo <= abs(delta0) <= abs_hi:
        raise ValueError("q2 leverism cannot be assembled at q1 = 0")
    if never_short and never_long:
        return (-math.inf, math.inf)
    if never_short:  # allowed: delta in [-abs_hi, abs_hi]
        return (-abs_hi - delta0, abs_hi - delta0)
    if never_long:  # allowed: delta in [abs_lo, 2 pi - abs_lo] (through +-pi)
        if delta0 >= 0.0:
            return (abs_lo - delta0, 2.0 * math.pi - abs_lo - delta0)
        return (abs_lo - 2.0 * math.pi - delta0, -abs_lo - delta0)
    if delta0 >= 0.0:
        return (abs_lo - delta0, abs_hi - delta0)
    return (-abs_hi - delta0, -abs_lo - delta0)


# --------------------------------------------------------------------------- q0 -> q1
def _resolve_c(p: Mk5FingerParams, c: tuple[float, float] | None) -> tuple[float, float]:
    if c is not None:
        return (float(c[0]), float(c[1]))
    if p.c_point is None:
        raise ValueError(
            "the crank pivot C is not in the Mk5 tables: pass c=(cx, cy) in metres "
            "or set it with with_c_point()"
        )
    return p.c_point


def q1_of_q0(p: Mk5FingerParams, q0: ArrayLike, c: tuple[float, float] | None = None) -> ArrayLike:
    """First-phalanx angle ``q1`` (rad) from crank angle ``q0`` (rad).

    ``q1 = atan2(Ay - P0y, Ax - P0x) + acos((s^2 - t^2 + a^2) / (2 s a))
    - q1_bias - pi`` with ``A = C + f (cos(q0 + q0_off), sin(q0 + q0_off))``,
    ``a = |A - P0|``, P0 = origin. ``c`` is the pivot ``C`` (m); if omitted
    ``p.c_point`` is used. The result is wrapped to [-pi, pi). Vectorised
    over ``q0``; raises ``ValueError`` where the linkage cannot be assembled.

    Note: taken literally, the ``-pi`` puts ``B`` at direction
    ``q1_bias + pi`` when ``q1 = 0`` (i.e. +90 deg, not the -90 deg the
    table's description of ``q1_bias`` suggests). The printed formula is
    implemented as is; only with it does a valid ``C`` exist (Mk5.0 thumb).
    """
    cx, cy = _resolve_c(p, c)
    q0a = np.asarray(q0, dtype=float)
    ang = q0a + p.q0_off
    ax = cx + p.f * np.cos(ang)
    ay = cy + p.f * np.sin(ang)
    a = np.hypot(ax, ay)
    cc = _safe_acos_arg((p.s * p.s - p.t * p.t + a * a) / (2.0 * p.s * a), "q1_of_q0")
    return _as_out(_wrap_pi(np.arctan2(ay, ax) + np.arccos(cc) - p.q1_bias - math.pi))


def dq1_dq0(p: Mk5FingerParams, q0: ArrayLike, c: tuple[float, float] | None = None) -> ArrayLike:
    """Analytic derivative ``dq1/dq0`` (rad/rad) of :func:`q1_of_q0`.

    With ``A' = dA/dq0 = f (-sin(q0 + q0_off), cos(q0 + q0_off))``:
    ``d/dq0 atan2(A) = (A x A') / a^2``, ``da/dq0 = (A . A') / a``,
    ``dc/da = (a^2 - s^2 + t^2) / (2 s a^2)`` and
    ``dq1/dq0 = (A x A') / a^2 - (dc/da)(da/dq0) / sqrt(1 - c^2)``.
    """
    cx, cy = _resolve_c(p, c)
    q0a = np.asarray(q0, dtype=float)
    ang = q0a + p.q0_off
    dax = -p.f * np.sin(ang)
    day = p.f * np.cos(ang)
    ax = cx + p.f * np.cos(ang)
    ay = cy + p.f * np.sin(ang)
    a2 = ax * ax + ay * ay
    a = np.sqrt(a2)
    s, t = p.s, p.t
    cc = _safe_acos_arg((s * s - t * t + a2) / (2.0 * s * a), "dq1_dq0")
    dphi = (ax * day - ay * dax) / a2
    da = (ax * dax + ay * day) / a
    dc_da = (a2 - s * s + t * t) / (2.0 * s * a2)
    return _as_out(dphi - dc_da * da / np.sqrt(1.0 - cc * cc))


def q1_span_upper_bound(p: Mk5FingerParams) -> float:
    """Upper bound (rad) on ``|q1(q0_max) - q1(0)|`` over *every* pivot ``C``.

    Valid for any ``C`` for which the ``q0 -> q1`` linkage stays assembled
    over the stroke ``q0 in [0, q0_max]`` (and for either sign of the acos
    branch). ``q1 = angle(A) + psi(a) + const`` with
    ``psi(a) = acos((s^2 - t^2 + a^2) / (2 s a))`` and ``a in [|t-s|, t+s]``:

    * ``A`` travels an arc of length ``f |q0_max|`` at distance ``>= |t - s|``
      from P0, so ``angle(A)`` changes by at most ``f |q0_max| / |t - s|``;
    * ``a`` changes by at most the chord ``2 f sin(|q0_max| / 2)``, so ``psi``
      changes by at most its largest variation over a window of that width
      (evaluated on a dense grid; ``psi`` is monotonic).
    """
    s, t, f = p.s, p.t, p.f
    stroke = abs(p.q0_max)
    a_min, a_max = abs(t - s), t + s
    if a_min == 0.0:
        return math.inf
    dir_bound = f * stroke / a_min
    chord = 2.0 * f * math.sin(stroke / 2.0)
    if chord >= a_max - a_min:
        return dir_bound + math.pi
    a = np.linspace(a_min, a_max - chord, 200_001)

    def psi(x: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
        return np.arccos(np.clip((s * s - t * t + x * x) / (2.0 * s * x), -1.0, 1.0))

    psi_bound = float(np.max(np.abs(psi(a) - psi(a + chord))))
    return dir_bound + psi_bound


def _circle_intersections(
    c0: npt.NDArray[np.float64], r0: float, c1: npt.NDArray[np.float64], r1: float
) -> list[npt.NDArray[np.float64]]:
    dv = c1 - c0
    dist = math.hypot(dv[0], dv[1])
    if dist == 0.0 or dist > r0 + r1 or dist < abs(r0 - r1):
        return []
    x = (dist * dist + r0 * r0 - r1 * r1) / (2.0 * dist)
    y = math.sqrt(max(r0 * r0 - x * x, 0.0))
    e = dv / dist
    n = np.array([-e[1], e[0]])
    return [c0 + x * e + y * n, c0 + x * e - y * n]


def _stroke_is_valid(p: Mk5FingerParams, c: tuple[float, float], samples: int = 2001) -> bool:
    """True if, with pivot ``c``, ``q1(0) = 0``, ``q1(q0_max) = q1_max``, the
    linkage stays assembled over the stroke and ``q1`` is monotonic in ``q0``."""
    q0 = np.linspace(0.0, p.q0_max, samples)
    try:
        q1 = np.asarray(q1_of_q0(p, q0, c))
    except ValueError:
        return False
    steps = np.diff(q1)
    if np.any(np.abs(steps) > 0.1):  # a wrap/branch jump, not a smooth stroke
        return False
    monotonic = bool(np.all(steps > 0.0) or np.all(steps < 0.0))
    return (
        monotonic
        and abs(q1[0]) < 1e-9
        and abs(float(_wrap_pi(np.asarray(q1[-1] - p.q1_max)))) < 1e-9
    )


def derive_c_point(p: Mk5FingerParams) -> tuple[float, float]:
    """Derive the crank pivot ``C = (cx, cy)`` (m) from the table's stroke.

    Two conditions, two unknowns: ``q1(q0 = 0) = 0`` (fully open; ``q0 = 0``
    there because ``q0_off`` is the fully-open angle of ``A - C``) and
    ``q1(q0_max) = q1_max``. They are solved in closed form: with the printed
    formula, ``B(q1) = s (cos(q1 + q1_bias + pi), sin(...))`` and ``A`` must
    be at distance ``t`` from ``B`` at both ends, while the crank fixes
    ``A(q0_max) - A(0) = f (u(q0_max + q0_off) - u(q0_off))``; so ``A(0)``
    is an intersection of two circles of radius ``t``. A candidate is kept
    only if the printed formula (its ``+acos`` branch) reproduces both end
    conditions and ``q1`` is continuous and monotonic over the stroke.

    Raises ``ValueError`` with the reason if no such ``C`` exists -- in
    particular when ``q1_max`` exceeds :func:`q1_span_upper_bound`, which is
    the case for every 12 deg-stroke finger of both tables (bound ~53 deg
    vs the required 90 deg); only the Mk5.0 thumb has a solution.
    """
    need = p.q1_max
    bound = q1_span_upper_bound(p)
    # the formula is wrapped, so a span of need + 2 pi n would also do.
    n = round(need / (2.0 * math.pi))
    smallest = min(abs(need - 2.0 * math.pi * m) for m in (n - 1, n, n + 1))
    if smallest > bound:
        raise ValueError(
            f"no crank pivot C exists: a q0 stroke of {math.degrees(p.q0_max):.2f} deg "
            f"(f={p.f * 1e3:.2f} mm, s={p.s * 1e3:.2f} mm, t={p.t * 1e3:.2f} mm) can move q1 "
            f"by at most {math.degrees(bound):.2f} deg, but the table requires "
            f"q1_max={math.degrees(need):.2f} deg"
        )

    def u(angle: float) -> npt.NDArray[np.float64]:
        return np.array([math.cos(angle), math.sin(angle)])

    beta0 = p.q1_bias + math.pi
    b_open = p.s * u(beta0)
    b_closed = p.s * u(beta0 + p.q1_max)
    delta = p.f * (u(p.q0_max + p.q0_off) - u(p.q0_off))
    solutions: list[tuple[float, float]] = []
    for a_open in _circle_intersections(b_open, p.t, b_closed - delta, p.t):
        c_pt = a_open - p.f * u(p.q0_off)
        cand = (float(c_pt[0]), float(c_pt[1]))
        if _stroke_is_valid(p, cand):
            solutions.append(cand)
    if not solutions:
        raise ValueError(
            "no crank pivot C reproduces q1(0)=0 and q1(q0_max)=q1_max with the printed "
            "formula's acos branch and a continuous, monotonic stroke"
        )
    if len(solutions) > 1:
        raise ValueError(f"crank pivot C is ambiguous: candidates {solutions}")
    return solutions[0]


def with_c_point(p: Mk5FingerParams) -> Mk5FingerParams:
    """Copy of ``p`` with ``cx, cy`` set by :func:`derive_c_point` (may raise ValueError)."""
    cx, cy = derive_c_point(p)
    return replace(p, cx=cx, cy=cy)


# --------------------------------------------------------------------------- motor -> q0
def _r_mot(p: Mk5FingerParams) -> float:
    if p.r_mot is None:
        raise ValueError("r_mot is not given for this finger (the Mk5.0 table has no r_mot row)")
    return p.r_mot


def q0_of_qmot(p: Mk5FingerParams, q_mot: ArrayLike) -> ArrayLike:
    """Crank angle ``q0 = (r_mot / r) q_mot`` (rad) from motor angle ``q_mot`` (rad).

    From equal arc lengths of the two tendon bushings (inextensible wire).
    """
    return _as_out(np.asarray(q_mot, dtype=float) * (_r_mot(p) / p.r))


def qmot_of_q0(p: Mk5FingerParams, q0: ArrayLike) -> ArrayLike:
    """Motor angle ``q_mot = (r / r_mot) q0`` (rad); inverse of :func:`q0_of_qmot`."""
    return _as_out(np.asarray(q0, dtype=float) * (p.r / _r_mot(p)))


# --------------------------------------------------------------------------- q1 -> motor
_BISECT_ITERS = 60  # halves a <= 45 deg bracket to ~1e-18 rad


def _q0_of_q1_exact(p: Mk5FingerParams, q1: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """Invert :func:`q1_of_q0` over the stroke ``[0, q0_max]`` by bisection (vectorised).

    Assumes ``q1(q0)`` is monotonic on the stroke (true for a pivot found by
    :func:`derive_c_point`). Raises ``ValueError`` for ``q1`` outside
    ``[q1(0), q1(q0_max)]`` (plus 1e-9 rad).
    """
    lo = np.zeros_like(q1)
    hi = np.full_like(q1, p.q0_max)
    f_lo = float(q1_of_q0(p, 0.0))
    f_hi = float(q1_of_q0(p, p.q0_max))
    a, b = min(f_lo, f_hi), max(f_lo, f_hi)
    if np.any(q1 < a - 1e-9) or np.any(q1 > b + 1e-9):
        raise ValueError(
            f"q1 outside the crank stroke [{math.degrees(a):.4f}, {math.degrees(b):.4f}] deg"
        )
    rising = f_hi > f_lo  # q1 as a function of (lo -> hi)
    for _ in range(_BISECT_ITERS):
        mid = 0.5 * (lo + hi)
        below = (np.asarray(q1_of_q0(p, mid)) < q1) == rising
        lo = np.where(below, mid, lo)
        hi = np.where(below, hi, mid)
    return 0.5 * (lo + hi)


def qmot_of_q1(p: Mk5FingerParams, q1: ArrayLike) -> ArrayLike:
    """Motor pulley angle ``q_mot`` (rad) from the encoder angle ``q1`` (rad).

    ``q_mot = (r / r_mot) q0(q1)`` (:func:`qmot_of_q0`). The ``q0(q1)`` stage:

    * **Exact** -- if a crank pivot ``C`` is set on ``p`` (``p.c_point``,
      e.g. by :func:`with_c_point`, which succeeds only where
      :func:`derive_c_point` does: the Mk5.0 thumb), ``q1(q0)``
      (:func:`q1_of_q0`) is inverted numerically by bisection over
      ``[0, q0_max]``; ``q1`` must lie in the stroke's range.
    * **Stand-in (documented assumption)** -- otherwise. The tables do not
      give ``C``, and for every 12 deg-stroke finger (all Mk5.1 fingers) no
      ``C`` can reproduce the 90 deg ``q1`` span (see
      :func:`derive_c_point`). The stage is then replaced by the *linear map
      through the table's end points*: ``q1 = 0 <-> q0 = 0`` and
      ``q1 = q1_max <-> q0 = q0_max``, i.e. ``q0 = q1 q0_max / q1_max``. It
      is exact at both ends, not in between (the real four-bar is
      nonlinear), and it extrapolates linearly outside ``[0, q1_max]``.
      ``q0_max < 0``, so ``q_mot`` decreases as the finger closes.

    Raises ``ValueError`` if ``p.r_mot`` is ``None`` (the Mk5.0 table has no
    ``r_mot`` row). Vectorised over ``q1``.
    """
    _r_mot(p)
    q1a = np.asarray(q1, dtype=float)
    if p.c_point is not None:
        q0 = _q0_of_q1_exact(p, q1a)
    else:
        q0 = q1a * (p.q0_max / p.q1_max)
    return qmot_of_q0(p, q0)


def dqmot_dq1(p: Mk5FingerParams, q1: ArrayLike) -> ArrayLike:
    """``dq_mot / dq1`` (rad/rad) of :func:`qmot_of_q1` (same two cases).

    Stand-in: the constant ``(r / r_mot) q0_max / q1_max`` (negative).
    Exact (``C`` set): ``(r / r_mot) / dq1_dq0(q0(q1))``. Raises
    ``ValueError`` if ``p.r_mot`` is ``None``.
    """
    k = p.r / _r_mot(p)
    q1a = np.asarray(q1, dtype=float)
    if p.c_point is not None:
        q0 = _q0_of_q1_exact(p, q1a)
        return _as_out(k / np.asarray(dq1_dq0(p, q0)))
    return _as_out(np.full_like(q1a, k * p.q0_max / p.q1_max))
