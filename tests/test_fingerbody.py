"""The fingers' bodies against the keys (planner.play.fingerbody, planner.simulate.planbody):
the hand's collision bodies (planner.hand.bodies), the physics replay's shapes, measured
without the physics."""

from __future__ import annotations

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

import planner
from planner.music import keyboard as kb
from planner.play.atlas import Atlas
from planner.play.fingerbody import FingerBodies
from planner.simulate.keyboard import key_bodies
from planner.simulate.scene import build_scene
from planner.trajfile import read_trajectory

SONG = "songs/twinkle.mid"


@pytest.fixture(scope="module")
def bodies(hand):
    return FingerBodies(hand)


@pytest.fixture(scope="module")
def twinkle_rows(tmp_path_factory, hand):
    path = tmp_path_factory.mktemp("body") / "twinkle.csv"
    planner.plan_song(planner.load_song(SONG), hand, str(path))
    tr = read_trajectory(str(path))
    start = round(tr.metadata["song_start_s"] * 100)  # (rows from the song's time 0 on)
    return tr.q[start:]


def test_shapes_are_the_replays_geoms(hand, bodies):
    """Each finger: its pad sphere and segment capsules (two a segment), the MJCF's (same
    radii, the pad sphere's centre a pad radius above the pad point in the distal link's
    frame)."""
    scene = build_scene(hand, hand.T_world_root, keyboard=True, contact="full")
    m = scene.model
    for f in hand.fingers:
        s = bodies.shapes[f]
        assert s.radius_m[0] == pytest.approx(float(m.geom(f"{f}_pad").size[0]), abs=1e-12)
        caps = sorted(float(m.geom_size[g][0]) for g in range(m.ngeom)
                      if "_capsule" in m.geom(g).name and scene.geom_finger[g]
                      == planner.hand.spec.FINGERS.index(f))
        assert sorted(s.radius_m[1:]) == pytest.approx(caps, abs=1e-12)


def test_penetration_agrees_with_mujoco(hand, bodies):
    """At the repeat's rise poses of a sample of the atlas's entries (keys at rest: each
    finger's body 3 mm into its own key; the planned rows' bodies touch no other key):
    where MuJoCo finds a finger geom into a key by up to 5 mm, ``penetration`` finds the
    same depth within 0.7 mm (its capsule axes sampled at 9 points); where MuJoCo finds
    none, at most 0.7 mm."""
    from planner.play.places import Places

    rows = []
    for atlas in Places(hand).atlases:
        for (f, pc, k), e in sorted(atlas._entries.items())[::97]:
            if e is not None:
                rows.append(atlas.full_q(e, "rise", atlas.rail_for(f, 60 + pc, k)))
    scene = build_scene(hand, hand.T_world_root, keyboard=True, contact="full")
    m, data = scene.model, mujoco.MjData(scene.model)
    worst, compared = 0.0, 0
    for q in rows:
        data.qpos[:] = 0.0
        data.qpos[scene.hand_qpos] = q
        mujoco.mj_forward(m, data)
        depth: dict[tuple[int, int], float] = {}
        for c in data.contact[:data.ncon]:
            g = [x for x in c.geom if scene.geom_finger[x] >= 0]
            k = [scene.key_geom_key[x] for x in c.geom if scene.key_geom_key[x] >= 0]
            if g and k:
                key = (int(scene.geom_finger[g[0]]), int(k[0]) + kb.LOWEST_PITCH)
                depth[key] = max(depth.get(key, 0.0), -float(c.dist))
        for fi, f in enumerate(hand.fingers):
            pen = bodies.penetration(q, f, None)
            for p in np.unique(bodies.box_pitch):
                ours = max(float(pen[bodies.box_pitch == p].max()), 0.0)
                theirs = depth.get((fi, int(p)), 0.0)
                if theirs < 0.005 and max(ours, theirs) > 0.0:
                    worst = max(worst, abs(ours - theirs))
                    compared += 1
    assert compared > 50 and worst < 0.0007


def test_press_poses_of_the_fitted_wrist_reach_below_their_pad_point(tmp_path, bodies):
    """The finding (docs/history/play-second-design.md, "The fingers' bodies"): the atlas
    of one fitted arm posture (the default hand until session 37: no ``[play]``, the rail
    0.17 m over the keys) curls the distal segment past vertical, so the pad sphere's
    bottom lies below the pad point and the key's bed holds the finger up before the
    point is down; the shipped play posture's press of the same key is clear."""
    from tests.handfiles import fitted_text, load_text

    for hand, clear in ((load_text(tmp_path, fitted_text()), False), (bodies.hand, True)):
        fb = FingerBodies(hand)
        atlas = Atlas(hand)
        rail_m = kb.key(64).center_x_m - atlas.natural_dx["middle"]  # E4 at its natural place
        e = atlas.entry("middle", 64, rail_m)
        assert e is not None
        q = atlas.full_q(e, "press", rail_m)
        p, r = fb.points(q, "middle")
        tip = hand.tip_positions(q)[hand.fingers.index("middle")]
        below = tip[2] - float(np.min(p[:, 2] - r))
        assert (below > 0.002) is not clear  # (more than the spec's 2 mm below the bed)
        assert fb.clear(q, "middle", 64) is clear


def test_a_straight_finger_rests_on_its_pad_point(hand, bodies):
    """The neutral hand (every joint 0: the distal segments level): the pad sphere's
    lowest point is the pad point."""
    q = hand.q_neutral
    for f in hand.fingers[1:]:
        p, r = bodies.points(q, f)
        tip = hand.tip_positions(q)[hand.fingers.index(f)]
        R = hand.frame_pose(q, f"{f}_tip")[:3, :3]
        if abs(R[2, 2]) > 1 - 1e-9:  # its pad faces straight down
            assert p[0, 2] - r[0] == pytest.approx(tip[2], abs=1e-9)


def test_plan_body_keys_flags_the_black_keys_beside_a_narrow_press(tmp_path, hand,
                                                                  twinkle_rows):
    """D4 pressed between C#4 and D#4 (13.5 mm of white key, a 21.4 mm finger end) by the
    fitted wrist's atlas (before session 37): the press's own bodies reach both black
    neighbours, before any physics. Twinkle as planned today (D4 pressed in front of the
    black keys): no row's bodies reach a key its pad point does not press."""
    from planner.check import key_contacts
    from planner.simulate.planbody import plan_body_keys
    from tests.handfiles import fitted_text, load_text

    fitted = load_text(tmp_path, fitted_text())
    atlas = Atlas(fitted)
    rail_m = kb.key(62).center_x_m - atlas.natural_dx["middle"]
    q = atlas.full_q(atlas.entry("middle", 62, rail_m), "press", rail_m)[None]
    flagged = plan_body_keys(fitted, q, key_contacts(fitted.tip_positions(q[0])[None]))
    black = [p - kb.LOWEST_PITCH for p in (61, 63)]
    assert flagged[0, black].all()
    kc = key_contacts(np.array([hand.tip_positions(q) for q in twinkle_rows]))
    assert not plan_body_keys(hand, twinkle_rows, kc).any()


def test_the_seed_hand_cannot_press_between_two_black_keys(hand, bodies):
    """A seed inconsistency, kept visible: seed 000's 1.5x hand (Table 2's upper-limit
    widths) on the spec's keyboard (section 2). Between C#4 and D#4 the D4 key is
    13.5 mm wide; a pad sphere wider than that enters the slot only by its cap (the
    pinky's 13.7 mm one 5.6 mm, the index's to ring's 17.1 mm 3.3 mm, the thumb's 24 mm
    2.0 mm), where it has to reach the black keys' 12.5 mm above the white tops plus the
    spec's 5 mm key-down depth. So no posture of any finger presses D, G or A between the black keys: they are
    pressed in front of them (docs/history/play-second-design.md, "The fingers' bodies")."""
    boxes = {k.pitch: k.boxes for k in key_bodies()}
    c_sharp, d_sharp = boxes[61][0], boxes[63][0]  # (a black key is one box)
    slot_m = (d_sharp.center_m[0] - d_sharp.half_m[0]) - (c_sharp.center_m[0] + c_sharp.half_m[0])
    assert slot_m == pytest.approx(0.0135, abs=1e-4)
    needed_m = kb.BLACK_TOP_Z_M + kb.DOWN_DEPTH_M  # below the black tops
    for f in hand.fingers:
        r = float(bodies.shapes[f].radius_m[0])  # the pad sphere: the finger's end
        assert 2 * r > slot_m, f
        cap_m = r - np.sqrt(r * r - (slot_m / 2) ** 2)  # how far the sphere enters the slot
        assert cap_m < needed_m, (f, cap_m)


def test_a_body_beside_a_black_keys_wall_is_refused(bodies):
    """Spec section 2 judges a body by how deep it reaches inside a key's footprint: a
    finger end (the ring's 8.6 mm sphere) 2 mm below the white tops, 0.2 mm into D#5's
    footprint from its side, touches the black key's box by 0.2 mm (under the 0.5 mm a
    physical touch is allowed) yet lies 18 mm below its top inside its footprint, a
    wrong note by check's rule: the atlas refuses it (and within 0.5 mm of the wall: the rail
    lands up to half the atlas's step off a sample). Moved 1 mm clear of the wall, it
    presses its own E5 (10.6 mm deep, within its bed's 1 mm)."""
    r = 0.0086
    x_wall = kb.footprint(75)[0][1]  # D#5's right side
    p = np.array([[x_wall + r - 0.0002, 0.10, -0.002]])
    rad = np.array([r])
    assert 0 < bodies.box_depths(p, rad, 76)[bodies.box_pitch == 75].max() <= 0.0005
    assert not bodies.clear_points(p, rad, 76)
    assert not bodies.clear_points(p + [0.0005, 0.0, 0.0], rad, 76)  # (0.3 mm clear)
    assert bodies.clear_points(p + [0.0012, 0.0, 0.0], rad, 76)


def test_points_many_are_points_at_each_configuration(hand, bodies):
    """``FingerBodies.points_many`` (``FrameChain``, many configurations at once) gives
    ``points`` (Pinocchio, one at a time) at each, to rounding."""
    rng = np.random.default_rng(3)
    Q = hand.apply_couplings(rng.uniform(hand.lower, hand.upper, (40, hand.n)))
    for f in hand.fingers:
        many = bodies.points_many(Q, f)
        for k in range(len(Q)):
            p, _ = bodies.points(Q[k], f)
            np.testing.assert_allclose(many[k], p, rtol=0, atol=1e-15)
