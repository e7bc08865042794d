"""planner.play.atlas and planner.play.moves: the poses are where they say, their paths
are clear, the timed crossings are at the key-down depth, the force bound is exact."""

from __future__ import annotations

import numpy as np
import pytest

from planner.hand.model import load_hand
from planner.ik import PREPARE_HEIGHT_M, PRESS_TOL_M, press_target
from planner.music import keyboard as kb
from planner.play.atlas import HIGH_Z_M, REPEAT_DEPTH_M, STEP_M, Atlas, max_key_force_n, path_clear
from planner.play.moves import Moves
from planner.play.movetable import HIGH_SAFE_Z_M

CASES = [("thumb", 53), ("index", 57), ("index", 58), ("middle", 60), ("middle", 61),
         ("ring", 64), ("pinky", 65), ("pinky", 66)]


@pytest.fixture(scope="module")
def atlas():
    return Atlas(load_hand("default"))


@pytest.fixture(scope="module")
def moves(atlas):
    return Moves(atlas.hand, atlas)


def _tip(atlas, e, pose, rail):
    h = atlas.hand
    return h.tip_positions(atlas.full_q(e, pose, rail))[h.fingers.index(e.finger)]


def _some(atlas, finger, pitch, rail0=0.0):
    """An entry of ``finger`` on ``pitch`` and the rail it is at (the middle sample)."""
    ks = atlas.samples(finger, pitch)
    assert ks, f"the {finger} reaches {pitch} from no rail"
    k = ks[len(ks) // 2]
    rail = atlas.rail_for(finger, pitch, k)
    return atlas.entry(finger, pitch, rail), rail


@pytest.mark.parametrize("finger, pitch", CASES)
def test_poses_are_where_the_atlas_says(atlas, finger, pitch):
    e, rail = _some(atlas, finger, pitch)
    key = kb.key(pitch)
    t = press_target(finger, pitch)
    p = _tip(atlas, e, "press", rail)
    # at the press point (y may slide in its range), within the seed's 1 mm and the grid's
    # half step, inside the footprint, at full dip: down, not through the key bed
    assert abs(p[0] - t.point_m[0]) <= PRESS_TOL_M + STEP_M / 2
    assert t.y_range_m[0] - PRESS_TOL_M <= p[1] <= t.y_range_m[1] + PRESS_TOL_M
    assert key.x_min_m < p[0] < key.x_max_m
    depth = key.top_z_m - p[2]
    assert kb.DOWN_DEPTH_M < depth < kb.KEY_BED_DEPTH_M
    assert abs(depth - kb.KEY_DIP_M) <= PRESS_TOL_M
    for pose, z in (("rise", key.top_z_m - REPEAT_DEPTH_M), ("hover", key.top_z_m + PREPARE_HEIGHT_M),
                    ("high", HIGH_Z_M)):
        q = _tip(atlas, e, pose, rail)
        assert abs(q[2] - z) <= PRESS_TOL_M, pose
        # above the press point (x), anywhere along the key's press range (y)
        assert abs(q[0] - p[0]) <= PRESS_TOL_M + 1e-9, pose
        assert t.y_range_m[0] - PRESS_TOL_M <= q[1] <= t.y_range_m[1] + PRESS_TOL_M, pose
    assert atlas.hand.within_limits(atlas.full_q(e, "press", rail))


def test_an_entry_is_the_same_an_octave_away(atlas):
    """The rail carries the hand along x: the finger's joints over a key depend only on
    the key's place relative to the rail (and its pitch class)."""
    e, rail = _some(atlas, "middle", 62)
    octave = kb.key(74).center_x_m - kb.key(62).center_x_m
    e2 = atlas.entry("middle", 74, rail + octave)
    assert e2 is e
    d = _tip(atlas, e2, "press", rail + octave) - _tip(atlas, e, "press", rail)
    np.testing.assert_allclose(d, [octave, 0.0, 0.0], atol=1e-9)


def test_out_of_the_sampled_span_there_is_no_entry(atlas):
    assert atlas.entry("index", 60, kb.key(60).center_x_m - atlas.natural_dx["index"] + 0.2) is None


@pytest.mark.parametrize("finger, pitch", CASES[:4])
def test_the_force_bound_is_where_a_motor_reaches_its_capacity(atlas, finger, pitch):
    """A motor's capacity: its peak torque, or for a tendon motor the torque at which its
    cable pulls its 40 N design force at the 5 mm spool (0.2 N m), whichever is less."""
    e, rail = _some(atlas, finger, pitch)
    h = atlas.hand
    q = atlas.full_q(e, "press", rail)
    f = max_key_force_n(h, q, finger)
    assert f == pytest.approx(e.max_force_n)
    cap = np.array([min(a.peak_torque_nm, a.tendon_force_n * a.radius_m)
                    if a.tendon_force_n is not None else a.peak_torque_nm
                    for a in h.actuators])
    ratio = lambda F: np.max(np.abs(h.press_torques(q, {finger: F})) / cap)
    assert ratio(f) == pytest.approx(1.0, abs=1e-9)
    assert ratio(0.99 * f) < 1.0 < ratio(1.01 * f)
    # it is a tendon that limits the press, at half its motor's peak
    m = int(np.argmax(np.abs(h.press_torques(q, {finger: f})) / cap))
    assert h.actuators[m].kind == "tendon" and cap[m] == pytest.approx(0.5 * h.motor_peak_torque[m])


def _pair(atlas, finger, p1, p2):
    """Entries of ``finger`` on two keys from one rail, and that rail."""
    for k in atlas.samples(finger, p1):
        rail = atlas.rail_for(finger, p1, k)
        b = atlas.entry(finger, p2, rail)
        if b is not None:
            return atlas.entry(finger, p1, rail), b, rail
    pytest.fail(f"the {finger} reaches {p1} and {p2} from no one rail")


def test_path_clear_sees_a_finger_sweeping_through_a_key(atlas):
    """Pressed on one key and straight (in joint space) to pressed on the next: the tip
    goes through the keys between at depth; from high to high it clears them."""
    a, b, rail = _pair(atlas, "middle", 60, 62)
    h = atlas.hand
    qa, qb = atlas.full_q(a, "press", rail), atlas.full_q(b, "press", rail)
    assert not path_clear(h, qa, qb, "middle", 60)
    assert path_clear(h, atlas.full_q(a, "high", rail), atlas.full_q(b, "high", rail), "middle", None)


@pytest.mark.parametrize("finger, pitch", CASES)
def test_timed_crossings_are_at_the_key_down_depth(atlas, moves, finger, pitch):
    e, rail = _some(atlas, finger, pitch)
    h = atlas.hand
    top = kb.key(pitch).top_z_m
    f = h.fingers.index(finger)
    js = h.joint_slice(finger)
    for timed, going_down in ((moves.descend(e, "high"), True), (moves.descend(e, "hover"), True),
                              (moves.descend(e, "rise"), True), (moves.lift(e, "high"), False),
                              (moves.lift(e, "rise"), False)):
        q = atlas.full_q(e, "press", rail)
        for dt, below in ((-1e-4, not going_down), (1e-4, going_down)):
            q[js] = timed.move.at(timed.cross_s + dt)[0]
            depth = top - h.tip_positions(h.apply_couplings(q))[f, 2]
            assert (depth >= kb.DOWN_DEPTH_M) == below
    assert moves.repeat_gap_s(e) < moves.move_gap_s(e, e) if moves.move_gap_s(e, e) else True


def test_move_gap_is_lift_across_descent(atlas, moves):
    a, b, rail = _pair(atlas, "ring", 64, 67)
    lat = moves.across(a, b)
    assert lat is not None
    assert moves.move_gap_s(a, b) == pytest.approx(
        moves.before_rail_s(a) + lat.duration_s + moves.after_rail_s(b))
    # the move across keeps the tip above every key top, wherever the rail is
    h = atlas.hand
    f = h.fingers.index("ring")
    q = atlas.full_q(a, "high", rail)
    for t in np.linspace(0, lat.duration_s, 9):
        q[h.joint_slice("ring")] = lat.at(t)[0]
        assert h.tip_positions(h.apply_couplings(q))[f, 2] >= HIGH_SAFE_Z_M - 1e-9


def test_the_shipped_table_is_the_solvers_own(atlas):
    """planner/tables/atlas-<hash>.npz (scripts/make_atlas.py) holds exactly what the IK
    gives: a sample of entries solved afresh match it to the bit."""
    from planner.play.atlas import table_path

    h = atlas.hand
    assert table_path(h.urdf_sha256).exists(), "run python scripts/make_atlas.py"
    shipped = Atlas(h)
    fresh = Atlas(h)
    fresh._entries.clear()
    n = 0
    for f, pc, k in [("thumb", 7, 10), ("index", 0, -5), ("middle", 1, 0), ("ring", 4, 12),
                     ("pinky", 10, -20), ("index", 6, 44), ("pinky", 3, -45)]:
        a, b = shipped.entry_at(f, pc, k), fresh.entry_at(f, pc, k)
        assert (a is None) == (b is None), (f, pc, k)
        if a is not None:
            n += 1
            for pose in ("press", "rise", "hover", "high"):
                assert np.array_equal(getattr(a, pose), getattr(b, pose)), (f, pc, k, pose)
            assert a.max_force_n == b.max_force_n and a.dx_m == b.dx_m
    assert n >= 4


def test_a_crossing_is_found_within_its_tolerance_on_the_key_down_side():
    """``moves._crossing`` (false position, Illinois, bisection as a safeguard) against
    the root of monotone functions, steep and flat, either way."""
    from planner.play.moves import _crossing

    rng = np.random.default_rng(0)
    for _ in range(500):
        root, slope, bend = rng.uniform(0.001, 0.999), rng.uniform(0.1, 50.0), rng.uniform(0, 3)
        sign = rng.choice([-1.0, 1.0])

        def g(s, root=root, slope=slope, bend=bend, sign=sign):
            return sign * slope * ((s - root) + bend * (s - root) ** 3)

        s = _crossing(g, g(0.0), g(1.0), 1e-4)
        assert g(s) >= 0.0 and abs(s - root) <= 1e-4
