"""The hand's collision bodies (planner.hand.bodies), their URDF <collision> elements, the
exact geometry against the keys (planner.music.keybodies) and check's body rule
(planner.check.bodykeys, spec section 2)."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from planner.check import check_trajectory
from planner.check.bodykeys import body_keys
from planner.check.criteria import BODY_BED_DEPTH_M, DOWN_DEPTH_M
from planner.check.kinematics import Kinematics
from planner.hand.bodies import BOX, CAPSULE, SPHERE, collision_bodies, place
from planner.hand.builders import load_hand_spec
from planner.music import keyboard as kb
from planner.music.keybodies import box_lowest_z, footprints, sphere_depths, swept_lowest_z
from planner.music.midi import Note, write_notes_midi
from tests.trajbuild import min_jerk, press_posture, write_traj

HANDS = ("default", "default-left", "agh", "mk5")


def _segments(spec):
    """Links that are finger segments: a box longest along y, carrying one fingertip."""
    tips_of = {j.parent for j in spec.joints if j.child in spec.tip_frames}
    return [ln for ln in spec.links if ln.mass_kg > 0 and ln.size_m[1] > max(ln.size_m[0], ln.size_m[2])
            and ln.name not in ("palm", "forearm")], tips_of


@pytest.mark.parametrize("name", HANDS)
def test_every_segment_is_enclosed_width_length_thickness(name):
    """Each finger segment's capsules reach the hand file's width across it (default
    index base: 0.9375 in = 23.81 mm), its thickness at the capsules' axes, and its
    length along it; the distal one ends in the pad sphere."""
    spec = load_hand_spec(name)
    bodies = collision_bodies(spec)
    segs, distal = _segments(spec)
    assert segs
    for ln in segs:
        mine = [b for b in bodies if b.link == ln.name and b.kind == CAPSULE]
        assert mine, ln.name
        sx, sy, sz = ln.size_m
        cx, cy, _ = ln.com_m
        x_lo = min(b.p0_m[0] - b.radius_m for b in mine)
        x_hi = max(b.p0_m[0] + b.radius_m for b in mine)
        assert x_lo == pytest.approx(cx - sx / 2, abs=1e-12)
        assert x_hi == pytest.approx(cx + sx / 2, abs=1e-12)
        for b in mine:
            assert 2 * b.radius_m == pytest.approx(min(sx, sz), abs=1e-12)  # the thickness
            assert min(b.p0_m[1], b.p1_m[1]) - b.radius_m == pytest.approx(cy - sy / 2, abs=1e-12)
            assert max(b.p0_m[1], b.p1_m[1]) + b.radius_m >= cy + sy / 2 - 1e-12
        if ln.name in distal:
            pad = [b for b in bodies if b.link == ln.name and b.kind == SPHERE]
            assert len(pad) == 1 and pad[0].radius_m == pytest.approx(0.4 * sx, rel=1e-12)
    if name == "default":
        idx = next(ln for ln in spec.links if ln.name == "index_base")
        assert idx.size_m[0] == pytest.approx(0.9375 * 0.0254, abs=1e-12)  # seed Table 2


def test_pad_bottom_is_the_pad_point():
    """The pad sphere's bottom (its link's -z) is the tip link's origin."""
    spec = load_hand_spec("default")
    bodies = {b.name: b for b in collision_bodies(spec)}
    for j in spec.joints:
        if j.child in spec.tip_frames:
            pad = bodies[j.child.removesuffix("_tip") + "_pad"]
            assert pad.link == j.parent
            bottom = np.array(pad.p0_m) - (0.0, 0.0, pad.radius_m)
            np.testing.assert_allclose(bottom, j.xyz_m, atol=1e-15)


def test_palm_and_knuckles_are_their_boxes():
    spec = load_hand_spec("default")
    bodies = {b.name: b for b in collision_bodies(spec)}
    palm = next(ln for ln in spec.links if ln.name == "palm")
    assert bodies["palm_box"].kind == BOX
    np.testing.assert_allclose(2 * np.array(bodies["palm_box"].half_m), palm.size_m)
    assert bodies["index_knuckle_box"].half_m == (0.005, 0.005, 0.005)


@pytest.mark.parametrize("name", HANDS)
def test_urdf_has_collisions_of_every_body(name):
    """``cli.py hand --urdf``'s text: every link with bodies has its <collision>s (a capsule
    as a cylinder and two end spheres); the cylinder's axis joins the ends."""
    from planner.hand.model import load_hand

    hand = load_hand(name)
    root = ET.fromstring(hand.urdf)
    bodies = collision_bodies(hand.spec)
    for b in bodies:
        link = root.find(f"link[@name='{b.link}']")
        names = {c.get("name"): c for c in link.findall("collision")}
        if b.kind == CAPSULE:
            cyl = names[f"{b.name}_cylinder"]
            assert f"{b.name}_end0" in names and f"{b.name}_end1" in names
            g = cyl.find("geometry/cylinder")
            assert float(g.get("radius")) == pytest.approx(b.radius_m, rel=1e-11)
            assert float(g.get("length")) == pytest.approx(b.length_m, rel=1e-11)
            r, p, y = (float(v) for v in cyl.find("origin").get("rpy").split())
            from planner.hand.spec import rpy_matrix

            axis = rpy_matrix((r, p, y))[:, 2] * b.length_m
            np.testing.assert_allclose(np.abs(axis), np.abs(np.subtract(b.p1_m, b.p0_m)),
                                       atol=1e-11)
        else:
            c = names[b.name]
            kind = c.find("geometry")[0].tag
            assert kind == b.kind
    with_mass = {ln.name for ln in hand.spec.links if ln.mass_kg > 0}
    assert {b.link for b in bodies} == with_mass


def test_swept_lowest_point_is_exact():
    """A capsule's lowest point in a rectangle's column, against dense sampling of its
    axis (the sampled value is never below the exact one, and within 1e-6 m of it)."""
    rng = np.random.default_rng(0)
    n = 200
    a = rng.uniform(-0.05, 0.05, (n, 3))
    b = a + rng.uniform(-0.04, 0.04, (n, 3))
    r = rng.uniform(0.003, 0.012, n)
    lo, hi = np.tile([0.0, 0.0], (n, 1)), np.tile([0.02, 0.03], (n, 1))
    z = swept_lowest_z(a, b, r, lo, hi)
    ts = np.linspace(0.0, 1.0, 2001)
    for i in range(n):
        c = a[i] + ts[:, None] * (b[i] - a[i])
        d = np.maximum(np.maximum(lo[i] - c[:, :2], c[:, :2] - hi[i]), 0.0)
        d = np.sqrt((d * d).sum(axis=1))
        low = np.where(d <= r[i], c[:, 2] - np.sqrt(np.maximum(r[i] ** 2 - d * d, 0.0)), np.inf)
        if np.isfinite(low.min()):
            assert z[i] <= low.min() + 1e-12 and low.min() - z[i] < 1e-6
        else:
            assert not np.isfinite(z[i]) or low.min() - z[i] >= 0.0


def test_sphere_depths_are_the_exact_column_depths():
    """The atlas's sampled bodies (spheres) judged as check judges a body: the depth below
    each key's top of the lowest sphere point inside its footprint, against the exact
    column search (``swept_lowest_z`` with a = b) over every footprint rectangle."""
    rng = np.random.default_rng(1)
    p = np.c_[rng.uniform(0.15, 0.25, 40), rng.uniform(0.0, 0.16, 40),
              rng.uniform(-0.012, 0.03, 40)]
    r = rng.uniform(0.004, 0.012, 40)
    fp = footprints()
    want = np.full(88, -np.inf)
    for pi, ri in zip(p, r):
        n = len(fp.key)
        z = swept_lowest_z(np.tile(pi, (n, 1)), np.tile(pi, (n, 1)), np.full(n, ri), fp.lo, fp.hi)
        np.maximum.at(want, fp.key, fp.top_m - z)
    got = sphere_depths(p, r)
    assert np.isfinite(got).sum() > 5
    assert np.array_equal(np.isfinite(got), np.isfinite(want))
    np.testing.assert_allclose(got[np.isfinite(got)], want[np.isfinite(want)], atol=1e-9)


def test_box_lowest_point_is_the_linear_programmes():
    """A tilted box in a column: its lowest point against the LP's optimum (scipy)."""
    from scipy.optimize import linprog
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(5)
    n = 60
    c = rng.uniform(-0.03, 0.05, (n, 3))
    R = Rotation.random(n, random_state=2).as_matrix()
    h = rng.uniform(0.002, 0.03, (n, 3))
    lo, hi = np.tile([0.0, 0.0], (n, 1)), np.tile([0.02, 0.03], (n, 1))
    z = box_lowest_z(c, R, h, lo, hi)
    for i in range(n):
        A = np.vstack([R[i][0], -R[i][0], R[i][1], -R[i][1]])
        bb = np.array([0.02 - c[i, 0], c[i, 0], 0.03 - c[i, 1], c[i, 1]])
        res = linprog(R[i][2], A_ub=A, b_ub=bb, bounds=list(zip(-h[i], h[i])), method="highs")
        if res.status == 2:
            assert not np.isfinite(z[i])
        else:
            assert z[i] == pytest.approx(res.fun + c[i, 2], abs=1e-12)


# ---------------------------------------------------------------- check's body section

PRESS_S, RELEASE_S, END_S = 0.30, 0.80, 1.20


def _depth_for(hand, pitch, finger, key_pitch, want_m, y_m=None):
    """The pad point's depth (press_posture, at ``y_m``) at which the deepest body reaches
    ``want_m`` below key ``key_pitch``'s top in its footprint (bisection)."""
    kin = Kinematics(hand, hand.T_world_root)
    bodies = collision_bodies(hand.spec)

    def reach(d):
        bk = body_keys(kin, press_posture(pitch, finger, d, y_m)[None], bodies)
        return bk.depth_m[0, key_pitch - kb.LOWEST_PITCH]

    lo, hi = -0.03, 0.012
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if reach(mid) < want_m else (lo, mid)
    return round(0.5 * (lo + hi), 6)


def _body_check(tmp_path, hand, pitch, finger, depth_m, note_pitch, y_m=None):
    """One press (hover 25 mm above, down to ``depth_m``, back up; at ``y_m``) as a file,
    and one note of ``note_pitch`` while it is held; checked."""
    hover = press_posture(pitch, finger, -0.025, y_m)
    down = press_posture(pitch, finger, depth_m, y_m)
    t = np.arange(round(END_S * 100) + 1) / 100.0
    q = hand.apply_couplings(min_jerk([0.0, 0.1, PRESS_S, RELEASE_S, END_S - 0.1, END_S],
                                      [hover, hover, down, down, hover, hover], t))
    traj = write_traj(tmp_path / "press.csv", hand, t, q)
    song = tmp_path / "song.mid"
    write_notes_midi([Note(note_pitch, 0.1, END_S - 0.1, 80)], str(song))
    return check_trajectory(traj, str(song))


def test_a_clean_press_by_the_bodies(tmp_path, hand):
    """C#4 pressed by the index's body 7 mm (its pad point above the key: the test's
    posture curls the distal segment past vertical, so the pad sphere is the finger's
    lowest point): the note sounds by the body rule, check's verdict, no wrong key, no
    bed hit."""
    d = _depth_for(hand, 61, "index", 61, 0.007)
    rep = _body_check(tmp_path, hand, 61, "index", d, 61)
    p = rep.play
    assert rep.ok, rep.summary()
    assert p.notes_hit == 1 and p.wrong_presses == () and p.body_bed_hits == ()
    assert p.f1 > 0.5 and len(p.played) == 1 and p.played[0].fingers == ("index",)


BEHIND_M = 0.12  # a white key pressed behind the black keys' front (as the planner once
# did: the finger's width reaches the black neighbour)


def test_a_neighbour_pressed_6_mm_is_a_wrong_key_by_body(tmp_path, hand):
    """The index on E4 behind the black keys, its body reaching D#4 6 mm below D#4's top
    (its pad point nowhere near D#4): a wrong key, the index named, and check fails."""
    d = _depth_for(hand, 64, "index", 63, 0.006, BEHIND_M)
    rep = _body_check(tmp_path, hand, 64, "index", d, 64, BEHIND_M)
    wrong = [w for w in rep.play.wrong_presses if w.pitch == 63]
    assert len(wrong) == 1 and wrong[0].fingers == ("index",)
    assert rep.play.body_bed_hits == ()
    assert not rep.ok and any("wrong presses (first: D#4" in p and "by index" in p
                              for p in rep.problems), rep.problems


def test_a_body_2_mm_past_the_bed_is_a_bed_hit(tmp_path, hand):
    """C#4 pressed until the pad sphere is 12 mm below its top (2 mm past the 10 mm bed,
    the limit 11 mm): a body bed hit with its row, time and link; check fails; the JSON
    has it."""
    d = _depth_for(hand, 61, "index", 61, 0.012)
    rep = _body_check(tmp_path, hand, 61, "index", d, 61)
    hits = rep.play.body_bed_hits
    assert len(hits) == 1 and hits[0].pitch == 61 and hits[0].link == "index_top"
    assert hits[0].depth_m == pytest.approx(0.012, abs=2e-4)
    assert hits[0].depth_m > BODY_BED_DEPTH_M
    assert hits[0].time_s == pytest.approx(hits[0].row / 100.0)
    assert rep.play.wrong_presses == ()
    js = rep.to_dict()["play"]
    assert js["body_bed_hits"][0]["body"] == "index_pad"
    assert not rep.ok and any("body key-bed hits (first: index_top on C#4" in p
                              for p in rep.problems), rep.problems
    assert "body key-bed hits" in rep.summary()


def test_body_rule_contains_the_point_rule(tmp_path, hand):
    """Every key down by a pad point is down by the bodies (the point is its pad sphere's
    bottom): on a press 6 mm deep by the point rule."""
    kin = Kinematics(hand, hand.T_world_root)
    q = press_posture(62, "middle", 0.006)
    bk = body_keys(kin, q[None], collision_bodies(hand.spec))
    assert bk.down[0, 62 - kb.LOWEST_PITCH]
    assert bk.depth_m[0, 62 - kb.LOWEST_PITCH] >= 0.006 - 1e-9 >= DOWN_DEPTH_M


def test_placed_bodies_follow_the_links(hand):
    """``place`` puts a pad sphere's bottom on the fingertip when its link's -z is down."""
    kin = Kinematics(hand, hand.T_world_root)
    bodies = collision_bodies(hand.spec)
    q = hand.q_neutral[None]
    poses = kin.link_poses(q, tuple(dict.fromkeys(b.link for b in bodies)))
    pl = place(bodies, poses)
    tips, _ = kin.frames(q)
    for i, s in enumerate(pl.swept):
        b = bodies[s]
        if b.name.endswith("_pad"):
            R = poses[b.link][0, :3, :3]
            k = hand.fingers.index(b.finger)
            np.testing.assert_allclose(pl.a[0, i] - R[:, 2] * b.radius_m, tips[0, k], atol=1e-12)
    assert math.isfinite(float(pl.centre.sum()))
