"""planner.play.atlas and planner.play.moves: the poses are where they say, their paths
are clear (as points and as bodies), the timed crossings are at the key-down depth, the
force bound is exact. The default hand's atlas is one per play posture
(``planner.play.places``); a case is taken from the first posture that has it."""

from __future__ import annotations

import numpy as np
import pytest

from planner.check.criteria import BODY_BED_DEPTH_M, DOWN_DEPTH_M
from planner.hand.model import load_hand
from planner.ik import PREPARE_HEIGHT_M, PRESS_TOL_M, press_target
from planner.music import keyboard as kb
from planner.play.atlas import HIGH_Z_M, REPEAT_DEPTH_M, STEP_M, Atlas, max_key_force_n, path_clear
from planner.play.atlassolve import BODY_REFUSALS, Refusal
from planner.play.movetable import HIGH_SAFE_Z_M
from planner.play.places import Places

# (the thumb has no press pose on the default hand: below)
CASES = [("index", 57), ("index", 58), ("middle", 60), ("middle", 61), ("ring", 63),
         ("ring", 64), ("pinky", 65), ("pinky", 66)]


@pytest.fixture(scope="module")
def places():
    return Places(load_hand("default"))


@pytest.fixture(scope="module")
def atlas(places):
    return places.atlas


@pytest.fixture(scope="module")
def moves(places):
    return places


def _lowest(atlas, q, finger):
    """The finger's lowest body point (z, m)."""
    p, r = atlas.bodies.points(q, finger)
    return float(np.min(p[:, 2] - r))


def _tip(atlas, e, pose, rail):
    h = atlas.hand
    return h.tip_positions(atlas.full_q(e, pose, rail))[h.fingers.index(e.finger)]


def _some(places, finger, pitch):
    """The first posture's atlas with an entry of ``finger`` on ``pitch``, that entry and
    the rail it is at (its middle sample)."""
    for atlas in places.atlases:
        ks = atlas.samples(finger, pitch)
        if ks:
            k = ks[len(ks) // 2]
            rail = atlas.rail_for(finger, pitch, k)
            return atlas, atlas.entry(finger, pitch, rail), rail
    pytest.fail(f"the {finger} reaches {pitch} from no rail in any posture")


@pytest.mark.parametrize("finger, pitch", CASES)
def test_poses_are_where_the_atlas_says(places, finger, pitch):
    atlas, e, rail = _some(places, finger, pitch)
    key = kb.key(pitch)
    t = press_target(finger, pitch, atlas.press_depth_m, finger in atlas.front)
    p = _tip(atlas, e, "press", rail)
    # at the press point (y may slide in its range), within the seed's 1 mm and the grid's
    # half step, inside the footprint, at the press depth (6 mm: the default hand's play
    # posture), or deeper or shallower where the finger's lowest body would stop short
    # of the key bed or reach past its margin (it is pressed to the bed): down, not
    # through the key bed
    assert abs(p[0] - t.point_m[0]) <= PRESS_TOL_M + STEP_M / 2
    assert t.y_range_m[0] - PRESS_TOL_M <= p[1] <= t.y_range_m[1] + PRESS_TOL_M
    assert key.x_min_m < p[0] < key.x_max_m
    depth = key.top_z_m - p[2]
    assert kb.DOWN_DEPTH_M < depth < kb.KEY_BED_DEPTH_M
    low = key.top_z_m - _lowest(atlas, atlas.full_q(e, "press", rail), finger)
    assert atlas.press_depth_m == 0.006
    assert depth >= atlas.press_depth_m - PRESS_TOL_M or abs(low - kb.KEY_DIP_M) <= 5e-4
    assert low <= kb.KEY_DIP_M + 1e-3  # (the body no more than the spec's 1 mm past the bed)
    assert abs(depth - atlas.press_depth_m) <= PRESS_TOL_M or abs(low - kb.KEY_DIP_M) <= 5e-4
    # the rise lifts the finger's body (its lowest point) to the repeat depth
    q_rise = atlas.full_q(e, "rise", rail)
    assert abs(_lowest(atlas, q_rise, finger) - (key.top_z_m - REPEAT_DEPTH_M)) <= PRESS_TOL_M
    for pose, z in (("hover", key.top_z_m + PREPARE_HEIGHT_M), ("high", HIGH_Z_M)):
        q = _tip(atlas, e, pose, rail)
        assert abs(q[2] - z) <= PRESS_TOL_M, pose
        # above the press point (x), anywhere along the key's press range (y)
        assert abs(q[0] - p[0]) <= PRESS_TOL_M + 1e-9, pose
        assert t.y_range_m[0] - PRESS_TOL_M <= q[1] <= t.y_range_m[1] + PRESS_TOL_M, pose
    assert atlas.hand.within_limits(atlas.full_q(e, "press", rail))


def test_an_entry_is_the_same_an_octave_away(places):
    """The rail carries the hand along x: the finger's joints over a key depend only on
    the key's place relative to the rail (and its pitch class)."""
    atlas, e, rail = _some(places, "middle", 62)
    octave = kb.key(74).center_x_m - kb.key(62).center_x_m
    e2 = atlas.entry("middle", 74, rail + octave)
    assert e2 is e
    d = _tip(atlas, e2, "press", rail + octave) - _tip(atlas, e, "press", rail)
    np.testing.assert_allclose(d, [octave, 0.0, 0.0], atol=1e-9)


def test_out_of_the_sampled_span_there_is_no_entry(atlas):
    assert atlas.entry("index", 60, kb.key(60).center_x_m - atlas.natural_dx["index"] + 0.2) is None


@pytest.mark.parametrize("finger, pitch", CASES[:4])
def test_the_force_bound_is_where_a_motor_reaches_its_capacity(places, finger, pitch):
    """A motor's capacity: its peak torque, or for a tendon motor the torque at which its
    cable pulls its 40 N design force at the 5 mm spool (0.2 N m), whichever is less."""
    atlas, e, rail = _some(places, finger, pitch)
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
def test_timed_crossings_are_at_the_key_down_depth(places, finger, pitch):
    """The body rule's key-down depth: the finger's lowest body point (spec section 2)."""
    atlas, e, rail = _some(places, finger, pitch)
    moves = places
    h = atlas.hand
    top = kb.key(pitch).top_z_m
    js = h.joint_slice(finger)
    for timed, going_down in ((moves.descend(e, "high"), True), (moves.descend(e, "hover"), True),
                              (moves.descend(e, "rise"), True), (moves.lift(e, "high"), False),
                              (moves.lift(e, "rise"), False)):
        q = atlas.full_q(e, "press", rail)
        for dt, below in ((-1e-4, not going_down), (1e-4, going_down)):
            q[js] = timed.move.at(timed.cross_s + dt)[0]
            depth = top - _lowest(atlas, h.apply_couplings(q), finger)
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


@pytest.mark.parametrize("posture", [0, 1, 2])
def test_the_shipped_table_is_the_solvers_own(atlas, posture):
    """planner/tables/atlas-<hash>[-p<i>].npz (scripts/make_atlas.py) holds exactly what
    the IK gives: a sample of entries solved afresh match it to the bit."""
    from planner.play.atlas import table_path

    h = atlas.hand
    assert table_path(h.urdf_sha256, posture).exists(), "run python scripts/make_atlas.py"
    shipped = Atlas(h, posture=posture)
    fresh = Atlas(h, posture=posture)
    fresh.forget()
    n = 0
    for f, pc, k in [("thumb", 7, 10), ("index", 0, -5), ("middle", 1, 0), ("ring", 4, 12),
                     ("pinky", 10, -20), ("index", 6, 20), ("pinky", 3, -25), ("middle", 4, 5),
                     ("ring", 6, -3), ("index", 1, 2), ("pinky", 8, 0)]:
        a, b = shipped.entry_at(f, pc, k), fresh.entry_at(f, pc, k)
        assert (a is None) == (b is None), (f, pc, k)
        if a is not None:
            n += 1
            for pose in ("press", "rise", "hover", "high"):
                assert np.array_equal(getattr(a, pose), getattr(b, pose)), (f, pc, k, pose)
            assert a.max_force_n == b.max_force_n and a.dx_m == b.dx_m
    assert n >= 3


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


@pytest.mark.parametrize("posture", [0, 1, 2])
def test_every_press_is_clear_of_the_other_keys_as_a_body(places, posture):
    """The atlas's body rule: at every kept entry's press pose (a sample of the shipped
    table) the finger's bodies reach no other key by more than 0.5 mm and their own no
    more than 2 mm past its bed (``FingerBodies.clear``)."""
    atlas = places.atlases[posture]
    n = 0
    for (f, pc, k), e in sorted(atlas._entries.items())[::7]:
        if e is None:
            continue
        pitch = 60 + pc
        rail = atlas.rail_for(f, pitch, k)
        assert atlas.bodies.clear(atlas.full_q(e, "press", rail), f, pitch), (f, pc, k)
        assert atlas.bodies.clear(atlas.full_q(e, "high", rail), f, None), (f, pc, k)
        n += 1
    assert n > 50


def test_the_seed_thumb_presses_no_key_with_its_body_clear(places):
    """A seed inconsistency the body rule makes plain: the default hand's thumb (seed
    Table 2's upper-limit column, 1.5x: its pad sphere 24 mm across, its distal segment 33
    mm, over a white key 22.5 mm wide) has no press pose clear of the neighbouring keys in
    any play posture; the fingering plays without it (docs/history/2026-12-06-play-posture.md,
    2026-12-06-play-quality2.md)."""
    for atlas in places.atlases:
        assert not any(atlas.samples("thumb", p) for p in range(60, 72))
    assert any(places.atlases[0].samples(f, 62) for f in ("index", "middle", "ring", "pinky"))


def test_the_thumb_is_refused_by_its_reach_and_then_by_its_width(places):
    """Why the thumb has no entry (``EntrySolver.refusal``, the entry's own steps): with the
    forearm in the first two postures its tip reaches no key (no pose); in the third it
    reaches the white keys' front, where its body, even with the pad sphere's centre over
    the key's centre, reaches below the key-down depth in a neighbour's column (it sounds),
    and no black key (their front 60 mm in)."""
    first, _, third = places.atlases
    for pc, k in ((0, 0), (4, -20), (1, 10)):
        assert first.refusal("thumb", pc, k).refusal is Refusal.REACH
    white = [third.refusal("thumb", pc, k) for pc, k in ((0, -21), (4, -15), (7, -27))]
    for v in white:
        assert v.refusal is Refusal.BODY
        assert v.other_column_m > DOWN_DEPTH_M and v.centred_column_m > DOWN_DEPTH_M
        assert abs(v.pad_offset_m) > 0.002  # (its pad point beside the sphere's centre)
    assert third.refusal("thumb", 1, -21).refusal is Refusal.REACH


def test_a_refusal_agrees_with_the_table(places):
    """``refusal`` solves a sample again by the entry's steps: None exactly where the
    shipped table has an entry, a body refusal exactly where it says ``body_refused``, and
    a kept press within the body rule (no other key's box reached by more than 0.5 mm nor
    its column to the key-down depth, its own key no more than 1 mm past the bed)."""
    atlas = places.atlases[1]
    kinds = set()
    for f, pc, k in [("index", 0, -5), ("middle", 1, 0), ("middle", 2, 4), ("ring", 4, 12),
                     ("ring", 6, -3), ("pinky", 5, 0), ("pinky", 8, 0), ("index", 6, 20)]:
        v = atlas.refusal(f, pc, k)
        pitch = atlas._solved_on(f, pc, k)
        has = atlas.entry_at(f, pc, k) is not None
        assert (v.refusal is None) == has, (f, pc, k)
        assert (v.refusal in BODY_REFUSALS) == atlas.body_refused(
            f, pitch, atlas.rail_for(f, pitch, k)), (f, pc, k)
        if has:
            assert v.other_box_m <= 0.0005 + 1e-9 and v.other_column_m < DOWN_DEPTH_M
            assert v.own_column_m <= BODY_BED_DEPTH_M + 1e-9
        kinds.add(v.refusal)
    assert {None, Refusal.BODY} <= kinds


def test_a_press_stops_with_its_body_at_the_bed_both_ways(places):
    """The press drives the finger's lowest body to the key bed from either side: the
    third posture's middle finger over a black key at its natural place, its pad point at
    the press depth (6 mm), has its pad sphere 11.1 mm down, past the bed's 1 mm margin
    (the body rule refused it); the press stops shallower, the body at the bed, the key
    fully down by the bodies' rule, every other key clear."""
    atlas = places.atlases[2]
    pitch = 61  # (C#4: the canonical octave's)
    e = atlas.entry_at("middle", pitch % 12, 0)
    assert e is not None
    rail = atlas.rail_for("middle", pitch, 0)
    q = atlas.full_q(e, "press", rail)
    key = kb.key(pitch)
    low = key.top_z_m - _lowest(atlas, q, "middle")
    assert abs(low - kb.KEY_DIP_M) <= 5e-4  # (the body at the bed)
    depth = key.top_z_m - _tip(atlas, e, "press", rail)[2]
    assert depth < atlas.press_depth_m - 5e-4  # (the pad shallower than the press depth)
    assert atlas.bodies.clear(q, "middle", pitch)


def _pad_centre_above_tip_m(atlas, q, finger):
    """How far the pad sphere's centre lies above the pad point at ``q`` (m)."""
    p, _ = atlas.bodies.points(q, finger)
    h = atlas.hand
    return float(p[0, 2] - h.tip_positions(q)[h.fingers.index(finger)][2])


def test_every_press_is_made_with_the_pad_facing_the_key(places):
    """A press counts only with the pad facing down into the key (the pad point below
    its sphere's centre): every kept entry of the default hand's postures does (a sample
    of each table), the pad's normal 74 deg from straight down at most."""
    n = 0
    for atlas in places.atlases:
        for (f, pc, k), e in sorted(atlas._entries.items())[::11]:
            if e is None:
                continue
            q = atlas.full_q(e, "press", atlas.rail_for(f, 60 + pc, k))
            assert _pad_centre_above_tip_m(atlas, q, f) > 0.0, (f, pc, k)
            n += 1
    assert n > 100


def test_a_finger_whose_pad_faces_up_presses_nothing():
    """The AGH hand's near pair leans pads up at its play posture (hands/agh.toml): a
    press made shallower until its lowest body is at the bed would put its thumb's key
    down with the back of its distal segment (the pad point 4.3 mm above the key's top,
    the key already down at the waiting pose: a wrong press before the note). The thumb
    gets no entry; the index, pad down, keeps its seven white keys."""
    hand = load_hand("agh")
    atlas = Places(hand).atlas
    for pc in range(12):
        assert atlas.entry_at("thumb", pc, 0) is None
    assert atlas.body_refused("thumb", 64, atlas.rail_for("thumb", 64, 0))
    kept = [pc for pc in range(12) if atlas.entry_at("index", pc, 0) is not None]
    assert kept == [0, 2, 4, 5, 7, 9, 11]
    e = atlas.entry_at("index", 4, 0)
    q = atlas.full_q(e, "press", atlas.rail_for("index", 64, 0))
    assert _pad_centre_above_tip_m(atlas, q, "index") > 0.0


def test_an_abducted_finger_presses_with_its_pad_body_centred_on_the_key(atlas):
    """The index over C 19-27 mm off its natural place (the first posture): with its pad
    point on the key's centre the pad sphere's centre lies 1.7-2.5 mm aside and its side
    reaches the next key's column (the body rule refuses it); the press is solved again
    with the sphere's centre over the press point: an entry, its body clear of every other
    key, the sphere's centre within 1.5 mm of the key's centre (0.2-1.2 mm: the finger's
    pose changes with the shift), the pad point 2.1-2.7 mm beside it. Where the pad point
    on the centre was clear (10 mm off), it stays there."""
    for k in (-27, -23, -19, 19, 23, 27):
        e = atlas.entry_at("index", 0, k)
        assert e is not None
        pitch = atlas._solved_on("index", 0, k)
        q = atlas.full_q(e, "press", atlas.rail_for("index", pitch, k))
        p, _ = atlas.bodies.points(q, "index")
        tip = atlas.hand.tip_positions(q)[atlas.hand.fingers.index("index")]
        x = kb.key(pitch).center_x_m
        assert abs(p[0, 0] - x) <= 0.0015 and abs(tip[0] - x) >= 0.002
        assert atlas.bodies.clear(q, "index", pitch)
    e = atlas.entry_at("index", 0, 10)
    pitch = atlas._solved_on("index", 0, 10)
    q = atlas.full_q(e, "press", atlas.rail_for("index", pitch, 10))
    tip = atlas.hand.tip_positions(q)[atlas.hand.fingers.index("index")]
    assert abs(tip[0] - kb.key(pitch).center_x_m) <= PRESS_TOL_M
