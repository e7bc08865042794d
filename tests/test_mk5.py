"""Tests of the Mk5 leverism coupling laws against the document's tables."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planner.hand.mk5 import (
    derive_c_point,
    dq1_dq0,
    dq2_dq1,
    dq2_dq1_printed,
    q0_of_qmot,
    q1_limits,
    q1_of_q0,
    q1_span_upper_bound,
    q2_of_q1,
    qmot_of_q0,
    with_c_point,
)
from planner.hand.mk5_tables import FINGERS, MK5_TABLES, Mk5FingerParams, table_consistency

DEG = math.pi / 180.0
ALL = [(v, f) for v in ("mk5.0", "mk5.1") for f in FINGERS]
ALL_IDS = [f"{v}-{f}" for v, f in ALL]

# Table q2_max entries that the table's own geometry does not reproduce.
# value: q2(q1_max) computed from the coordinates, in degrees.
Q2MAX_INCONSISTENT = {("mk5.0", "thumb"): 142.9212}


def params(version: str, finger: str) -> Mk5FingerParams:
    return MK5_TABLES[version][finger]


def central_diff(fun, x: np.ndarray, step: float = 1e-6) -> np.ndarray:
    return (np.asarray(fun(x + step)) - np.asarray(fun(x - step))) / (2.0 * step)


# --------------------------------------------------------------------------- tables
def test_tables_have_all_fingers_in_si_units() -> None:
    assert set(MK5_TABLES) == {"mk5.0", "mk5.1"}
    for table in MK5_TABLES.values():
        assert tuple(table) == FINGERS
    p = params("mk5.1", "index")
    assert p.l1x == pytest.approx(0.034)
    assert p.q2_max == pytest.approx(193.06 * DEG)
    assert p.r_mot == pytest.approx(0.005)
    assert p.c_point is None
    assert params("mk5.0", "index").r_mot is None  # no r_mot row in the Mk5.0 table


# --------------------------------------------------------------------------- consistency
# Half a unit of the table's last printed digit (0.01 mm / 0.01 deg) plus float slack.
_LEN_TOL = 0.005e-3 + 1e-12
_ANG_TOL = 0.005 * DEG + 1e-12
# Entries whose rounding disagrees with the coordinates: (table, computed) in mm or deg.
CONSISTENCY_MISMATCHES = {
    ("mk5.1", "pinky", "q1_off"): (2.46, 2.4540),
    ("mk5.1", "pinky", "q2_bias"): (-170.53, -170.5377),
}
_QUANTITIES = ("k", "l", "d", "b", "q1_off", "q2_bias")
_CONSISTENT = [
    (v, f, q) for v, f in ALL for q in _QUANTITIES if (v, f, q) not in CONSISTENCY_MISMATCHES
]


@pytest.mark.parametrize(("version", "finger", "name"), _CONSISTENT)
def test_table_entry_consistent_with_coordinates(version: str, finger: str, name: str) -> None:
    """With P0 = (0, 0), every table k=|L1-L0|, l=|L1-P1|, d=|P1|, b=|L0|,
    q1_off=angle(P1) and q2_bias=angle(L1-P1) equals its value recomputed
    from the coordinates to within the table's rounding (0.01 mm / 0.01 deg),
    except the two Mk5.1 pinky entries in CONSISTENCY_MISMATCHES."""
    table, geom = table_consistency(params(version, finger))[name]
    tol = _ANG_TOL if name in ("q1_off", "q2_bias") else _LEN_TOL
    assert abs(table - geom) <= tol


@pytest.mark.parametrize(("key", "values"), list(CONSISTENCY_MISMATCHES.items()))
def test_table_rounding_mismatches(key: tuple[str, str, str], values: tuple[float, float]) -> None:
    """Mk5.1 pinky: the table gives q1_off = 2.46 deg and q2_bias = -170.53 deg,
    but its coordinates (P1 = (35, 1.5), L1 - P1 = (-6, -1)) give 2.4540 deg
    and -170.5377 deg (Mk5.0 pinky, same L1 - P1, correctly says -170.54).
    The errors are 0.006 and 0.008 deg: rounding slips, harmless for q2."""
    version, finger, name = key
    table, geom = table_consistency(params(version, finger))[name]
    assert table == pytest.approx(values[0] * DEG, abs=1e-12)
    assert geom == pytest.approx(values[1] * DEG, abs=1e-4 * DEG)
    assert abs(table - geom) > _ANG_TOL


def test_p0_is_the_origin() -> None:
    """b = |L0 - P0| and d = |P1 - P0| hold with P0 = (0, 0) for every finger."""
    for version, finger in ALL:
        p = params(version, finger)
        assert abs(p.b - math.hypot(p.l0x, p.l0y)) <= _LEN_TOL
        assert abs(p.d - math.hypot(p.p1x, p.p1y)) <= _LEN_TOL


# --------------------------------------------------------------------------- q2(q1)
@pytest.mark.parametrize(("version", "finger"), ALL, ids=ALL_IDS)
def test_q2_zero_when_open(version: str, finger: str) -> None:
    assert abs(q2_of_q1(params(version, finger), 0.0)) < 0.1 * DEG


@pytest.mark.parametrize(
    ("version", "finger"),
    [vf for vf in ALL if vf not in Q2MAX_INCONSISTENT],
    ids=[i for vf, i in zip(ALL, ALL_IDS) if vf not in Q2MAX_INCONSISTENT],
)
def test_q2_at_q1max_matches_table(version: str, finger: str) -> None:
    p = params(version, finger)
    assert abs(q2_of_q1(p, p.q1_max) - p.q2_max) < 0.1 * DEG


def test_q2max_mk50_thumb_table_is_inconsistent() -> None:
    """Mk5.0 thumb: the table says q2_max = 135.65 deg at q1_max = 86.35 deg,
    but the table's own geometry (L0=(-5.55, 2.85), L1=(11.5, 1.5),
    P1=(20, 1.5) mm, q2_bias=-180 deg) gives 142.92 deg, 7.27 deg more.
    Using the table's rounded k, l, d, q1_off instead gives 142.88 deg, so
    rounding does not explain it; the geometry reaches 135.65 deg only at
    q1 = 82.06 deg. The table entry is inconsistent; we keep the computed value."""
    p = params("mk5.0", "thumb")
    q2 = q2_of_q1(p, p.q1_max)
    assert q2 == pytest.approx(Q2MAX_INCONSISTENT[("mk5.0", "thumb")] * DEG, abs=0.01 * DEG)
    assert q2_of_q1(p, p.q1_max, lengths="table") == pytest.approx(142.8815 * DEG, abs=0.01 * DEG)
    assert q2_of_q1(p, 82.059 * DEG) == pytest.approx(135.65 * DEG, abs=0.01 * DEG)
    assert q2 - p.q2_max == pytest.approx(7.27 * DEG, abs=0.01 * DEG)


@pytest.mark.parametrize(
    ("version", "finger", "q2_open_deg"),
    [
        ("mk5.1", "thumb", 0.0424),
        ("mk5.1", "index", -0.1616),
        ("mk5.0", "thumb", -0.6840),
        ("mk5.0", "pinky", -0.0584),
    ],
)
def test_table_lengths_do_not_reproduce_open_pose(
    version: str, finger: str, q2_open_deg: float
) -> None:
    """Why q2 uses k, l, d, q1_off recomputed from the coordinates: at q1 = 0
    the triangle L0-P1-L1 is nearly flat (h within 0.1 mm of k + l), so the
    table's 0.01 mm rounding of k and l shifts q2(0) by up to -0.16 deg
    (Mk5.1 index/middle/ring) and -0.68 deg (Mk5.0 thumb); with the
    coordinates |q2(0)| < 0.01 deg for every finger."""
    p = params(version, finger)
    assert q2_of_q1(p, 0.0, lengths="table") == pytest.approx(q2_open_deg * DEG, abs=1e-4 * DEG)
    assert abs(q2_of_q1(p, 0.0)) < 0.01 * DEG


@pytest.mark.parametrize(("version", "finger"), ALL, ids=ALL_IDS)
def test_q2_continuous_and_increasing_beyond_range(version: str, finger: str) -> None:
    """atan2 (not the principal atan of the printed tan^-1(y/x)) keeps q2
    continuous: the principal atan would jump by pi where P1x(q1) = L0x,
    at q1 ~ 95-102 deg, just past q1_max. No wrapping: q2 exceeds pi."""
    p = params(version, finger)
    _, hi = q1_limits(p)
    q1 = np.linspace(0.0, min(hi, 130 * DEG) - 1e-6, 4001)
    q2 = np.asarray(q2_of_q1(p, q1))
    assert np.all(np.diff(q2) > 0.0)
    assert np.max(np.abs(np.diff(q2))) < 0.01
    d, off = p.d_geom, p.q1_off_geom
    jump = math.acos(p.l0x / d) - off  # where the principal atan would jump
    assert p.q1_max < jump < 105 * DEG


@pytest.mark.parametrize(("version", "finger"), ALL, ids=ALL_IDS)
def test_q1_limits_bound_assembly(version: str, finger: str) -> None:
    p = params(version, finger)
    lo, hi = q1_limits(p)
    assert lo < 0.0 < p.q1_max < hi
    q2_of_q1(p, np.array([lo + 1e-9, hi - 1e-9]))
    for bad in (lo - 1e-6, hi + 1e-6):
        with pytest.raises(ValueError):
            q2_of_q1(p, bad)


def test_q2_vectorised_matches_scalar() -> None:
    p = params("mk5.1", "ring")
    q1 = np.linspace(0.0, p.q1_max, 7)
    vec = q2_of_q1(p, q1)
    assert isinstance(vec, np.ndarray)
    assert isinstance(q2_of_q1(p, 0.3), float)
    assert np.allclose(vec, [q2_of_q1(p, float(x)) for x in q1], atol=0, rtol=0)


# --------------------------------------------------------------------------- Jacobians
@pytest.mark.parametrize(("version", "finger"), ALL, ids=ALL_IDS)
def test_dq2_dq1_matches_finite_differences(version: str, finger: str) -> None:
    p = params(version, finger)
    q1 = np.linspace(0.0, p.q1_max, 61)
    fd = central_diff(lambda x: q2_of_q1(p, x), q1)
    assert np.max(np.abs(np.asarray(dq2_dq1(p, q1)) - fd)) < 1e-6


@pytest.mark.parametrize(("version", "finger"), ALL, ids=ALL_IDS)
def test_printed_jacobian_is_correct(version: str, finger: str) -> None:
    """The document's printed dq2/dq1, although its first term looks odd,
    is exact: 1/(2 - (d^2 - b^2)/(d^2 - L0.P1)) == (d^2 - L0.P1)/h^2 because
    h^2 = d^2 + b^2 - 2 L0.P1 (P0 = origin). It needs the exact b = |L0|;
    with the table's rounded b (e.g. 6.40 vs 6.4031 mm) it is off by 3e-5 to 1e-4."""
    p = params(version, finger)
    q1 = np.linspace(0.0, p.q1_max, 61)
    exact = np.asarray(dq2_dq1(p, q1))
    assert np.max(np.abs(np.asarray(dq2_dq1_printed(p, q1)) - exact)) < 1e-9
    rounded = np.asarray(dq2_dq1_printed(p, q1, b=p.b))
    if abs(p.b - p.b_geom) > 1e-9:
        assert np.max(np.abs(rounded - exact)) > 1e-6


@pytest.mark.parametrize("lengths", ["coords", "table"])
def test_dq2_dq1_with_table_lengths_matches_finite_differences(lengths: str) -> None:
    for version, finger in ALL:
        p = params(version, finger)
        q1 = np.linspace(0.0, p.q1_max, 31)
        fd = central_diff(lambda x, p=p: q2_of_q1(p, x, lengths=lengths), q1)
        assert np.max(np.abs(np.asarray(dq2_dq1(p, q1, lengths=lengths)) - fd)) < 1e-6


# --------------------------------------------------------------------------- q1(q0) and C
@pytest.mark.parametrize(
    ("version", "finger"),
    [vf for vf in ALL if vf != ("mk5.0", "thumb")],
    ids=[i for vf, i in zip(ALL, ALL_IDS) if vf != ("mk5.0", "thumb")],
)
def test_c_point_not_derivable_for_12deg_stroke(version: str, finger: str) -> None:
    """With f = 5.5 mm and a ~12 deg crank stroke, A moves ~1.15 mm, so for
    ANY pivot C, q1 can change by at most ~53.7 deg (q1_span_upper_bound):
    the table's q1_max = 90 deg cannot be reached and C is not derivable."""
    p = params(version, finger)
    assert q1_span_upper_bound(p) < 54.0 * DEG < p.q1_max
    with pytest.raises(ValueError, match="no crank pivot C exists"):
        derive_c_point(p)


def test_span_bound_holds_for_random_pivots() -> None:
    """Sanity check of q1_span_upper_bound: no assembled random C exceeds it."""
    p = params("mk5.1", "index")
    bound = q1_span_upper_bound(p)
    rng = np.random.default_rng(0)
    q0 = np.linspace(0.0, p.q0_max, 200)
    spans = []
    for c in rng.uniform(-0.04, 0.04, size=(20000, 2)):
        try:
            q1 = np.unwrap(np.asarray(q1_of_q0(p, q0, (c[0], c[1]))))
        except ValueError:
            continue
        spans.append(abs(q1[-1] - q1[0]))
    assert len(spans) > 100
    assert max(spans) <= bound


def test_c_point_mk50_thumb() -> None:
    """Mk5.0 thumb (44.68 deg stroke): the two end conditions have exactly one
    valid solution, C = (11.930, 3.600) mm, with a monotonic stroke."""
    p = params("mk5.0", "thumb")
    c = derive_c_point(p)
    assert c == pytest.approx((11.9301e-3, 3.6001e-3), abs=1e-7)
    assert q1_of_q0(p, 0.0, c) == pytest.approx(0.0, abs=1e-12)
    assert q1_of_q0(p, p.q0_max, c) == pytest.approx(p.q1_max, abs=1e-12)
    q1 = np.asarray(q1_of_q0(p, np.linspace(0.0, p.q0_max, 500), c))
    assert np.all(np.diff(q1) > 0.0)
    pc = with_c_point(p)
    assert pc.c_point == c
    assert q1_of_q0(pc, p.q0_max) == pytest.approx(p.q1_max, abs=1e-12)


def test_q1_of_q0_requires_c() -> None:
    with pytest.raises(ValueError, match="not in the Mk5 tables"):
        q1_of_q0(params("mk5.1", "index"), 0.0)


@pytest.mark.parametrize(("version", "finger"), ALL, ids=ALL_IDS)
def test_dq1_dq0_matches_finite_differences(version: str, finger: str) -> None:
    p = params(version, finger)
    if (version, finger) == ("mk5.0", "thumb"):
        c = derive_c_point(p)
    else:
        # No table-consistent C exists; use one that assembles over the stroke.
        c = (-0.012, 0.004)
    q0 = np.linspace(p.q0_max, 0.0, 61)
    fd = central_diff(lambda x: q1_of_q0(p, x, c), q0)
    assert np.max(np.abs(np.asarray(dq1_dq0(p, q0, c)) - fd)) < 1e-6


# --------------------------------------------------------------------------- motor
@pytest.mark.parametrize("finger", FINGERS)
def test_qmot_round_trip(finger: str) -> None:
    p = params("mk5.1", finger)
    q_mot = np.linspace(-3.0, 3.0, 13)
    q0 = np.asarray(q0_of_qmot(p, q_mot))
    assert np.allclose(q0, q_mot * 5.0 / 8.5, rtol=1e-15, atol=0)
    assert np.allclose(qmot_of_q0(p, q0), q_mot, rtol=1e-14, atol=1e-15)
    assert q0_of_qmot(p, qmot_of_q0(p, p.q0_max)) == pytest.approx(p.q0_max, rel=1e-14)


def test_qmot_needs_r_mot() -> None:
    with pytest.raises(ValueError, match="r_mot"):
        q0_of_qmot(params("mk5.0", "thumb"), 1.0)
