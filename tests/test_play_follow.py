"""A held key carried through a move of the arm (planner.play.follow): the body rule's
follow test, and a held key following a change of posture judged by check's own rule."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from planner.check.bodykeys import body_keys
from planner.check.criteria import BODY_BED_DEPTH_M
from planner.check.kinematics import Kinematics
from planner.hand.bodies import collision_bodies
from planner.hand.model import load_hand
from planner.music import keyboard as kb
from planner.music.keybodies import sphere_depths
from planner.music.midi import Note
from planner.play.atlas import TIP_RADIUS_M
from planner.play.fingerbody import OTHER_KEY_TOLERANCE_M, OWN_BED_MARGIN_M
from planner.play.fingering import Assignment
from planner.play.follow import HOLD_MARGIN_M, canonical_pitch, follow_ends, paths_clear
from planner.play.motion import Motion
from planner.play.places import Places


@pytest.fixture(scope="module")
def places():
    return Places(load_hand("default"))


def _entries(atlas, finger=None):
    return sorted((e for e in atlas._entries.values()
                   if e is not None and (finger is None or e.finger == finger)),
                  key=lambda e: (e.finger, e.pitch_class, e.dx_m))


def test_clear_many_is_the_body_rule(places):
    """The batched body test (only the boxes and footprints near the points measured) is
    the atlas's body rule written out over every key, configuration by configuration:
    no other key's box entered past ``OTHER_KEY_TOLERANCE_M``, its own (pressed to the
    bed) past ``OWN_BED_MARGIN_M``; no other key's footprint column, grown by
    ``OTHER_KEY_TOLERANCE_M``, entered to the key-down depth; its own no deeper than
    check's bed depth (press poses with the rail shifted up to 12 mm: clear and not)."""
    atlas, rng = places.atlas, np.random.default_rng(7)
    fb, hand = atlas.bodies, places.hand
    E = _entries(atlas)
    seen = {True: 0, False: 0}
    for i in rng.choice(len(E), 30, replace=False):
        e = E[i]
        q, _ = follow_ends(atlas, atlas, e, e)
        Q = np.repeat(q[None], 8, axis=0)
        Q[:, atlas.rail] += rng.uniform(-0.012, 0.012, 8)
        Q = hand.apply_couplings(Q)
        pitch = canonical_pitch(e)
        ok, depth = fb.clear_many(fb.points_many(Q, e.finger), fb.radii(e.finger), pitch)
        for k, qk in enumerate(Q):
            p, r = fb.points(qk, e.finger)
            pen, own_box = fb.box_depths(p, r, pitch), fb.box_pitch == pitch
            grown, own = sphere_depths(p, r, OTHER_KEY_TOLERANCE_M), sphere_depths(p, r)
            mine = np.arange(len(own)) == pitch - kb.LOWEST_PITCH
            want = bool(np.all(pen[~own_box] <= OTHER_KEY_TOLERANCE_M)
                        and np.all(pen[own_box] <= OWN_BED_MARGIN_M)
                        and np.all(grown[~mine] < kb.DOWN_DEPTH_M)
                        and own[mine][0] <= BODY_BED_DEPTH_M)
            assert ok[k] == want == fb.clear_points(p, r, pitch)
            assert depth[k] == pytest.approx(own[mine][0], abs=1e-12) \
                or depth[k] == own[mine][0] == -np.inf
            seen[want] += 1
    assert seen[True] and seen[False]


def test_a_follow_refuses_a_body_entering_a_neighbour(places):
    """A follow whose end pose keeps the tip inside the key's footprint and the key held
    down, but puts the finger's body into another key, is refused (the point rule alone,
    the tip's, would not see it)."""
    atlas = places.atlas
    fb, hand = atlas.bodies, places.hand
    found = 0
    for e in _entries(atlas, "index"):
        pitch = canonical_pitch(e)
        k = kb.key(pitch)
        for shift_mm in (-8, -6, -4, 4, 6, 8):
            b = replace(e, dx_m=e.dx_m + shift_mm / 1000)
            qa, qb = follow_ends(atlas, atlas, e, b)
            q = hand.apply_couplings(qb)
            x, y, _ = hand.tip_position(q, hand.fingers.index("index"))
            p, r = fb.points(q, "index")
            own = sphere_depths(p, r)[pitch - kb.LOWEST_PITCH]
            if not (k.x_min_m + TIP_RADIUS_M <= x <= k.x_max_m - TIP_RADIUS_M
                    and k.y_min_m + TIP_RADIUS_M <= y <= k.y_max_m - TIP_RADIUS_M
                    and own >= kb.DOWN_DEPTH_M + HOLD_MARGIN_M) or fb.clear_points(p, r, pitch):
                continue
            assert not paths_clear(atlas, "index", pitch, qa[None], qb[None], [atlas.rail])[0]
            found += 1
        if found >= 5:
            break
    assert found >= 5


def _posture_change(places):
    """A held note's finger, a key and two places, another posture each, between which
    its finger follows the key, and a second finger's key from the second place."""
    for f in ("middle", "index", "ring"):
        for a in _entries(places.atlases[0], f):
            pitch = canonical_pitch(a)
            rail0 = round((kb.key(pitch).center_x_m - a.dx_m) / 0.006) * 0.006
            if places.atlases[0].entry(f, pitch, rail0) is not a:
                continue
            for posture in (1, 2):
                for di in (-2, -1, 0, 1, 2):
                    rail1 = rail0 + 0.006 * di
                    b = places.atlases[posture].entry(f, pitch, rail1)
                    if b is None or not places.follow_clear(a, b):
                        continue
                    g = "pinky" if f != "pinky" else "index"
                    other = next((p for p in range(pitch + 3, pitch + 12)
                                  if places.atlases[posture].entry(g, p, rail1) is not None),
                                 None)
                    if other is not None:
                        return f, pitch, rail0, posture, rail1, g, other
    raise AssertionError("no posture change that a held key follows")


def test_a_held_key_follows_a_posture_change(places):
    """The middle finger holds its key through a move of the arm into another posture
    (rail and reach): the plan's rows, judged by check's body rule, keep that key down
    all through the move and put no other key down but the next note's."""
    f, pitch, rail0, posture, rail1, g, other = _posture_change(places)
    notes = (Note(pitch, 0.1, 1.5, 80), Note(other, 0.6, 1.0, 80))
    motion = Motion(notes, places, 100.0, rail0, 0)
    held = Assignment(0, f, rail0, None, 0)
    motion.prepare([held])
    assert motion.place(held).down_s is not None
    assert motion.place(Assignment(1, g, rail1, None, posture)).down_s is not None
    end = motion.finish(1.6)
    t = np.arange(0.0, end + 0.05, 0.01)
    Q = motion.rows(t)
    hand = places.hand
    reach = Q[:, hand.index["reach"]]
    assert reach[0] != reach[-1]  # (the posture changed)
    bk = body_keys(Kinematics(hand, hand.T_world_root), Q, collision_bodies(hand.spec))
    moving = np.flatnonzero(np.abs(np.diff(reach)) > 1e-9)
    k0, k1 = pitch - kb.LOWEST_PITCH, other - kb.LOWEST_PITCH
    assert bk.down[moving, k0].all() and bk.down[moving + 1, k0].all()
    lo, hi = np.searchsorted(t, [0.1, 1.5 - 0.05])
    assert bk.down[lo + 1:hi, k0].all()  # (held from its onset to its end)
    others = np.ones(88, dtype=bool)
    others[[k0, k1]] = False
    assert not bk.down[:, others].any()


def test_a_press_the_rail_grid_puts_into_a_neighbour_is_not_offered(places):
    """The index's entries over E4 from the rail's places (each entry's ``dx`` up to half
    the atlas's step off its sample): a press whose body, with the rail where the place
    puts it, the atlas's body rule refuses (found at rail 114 mm when measured) is not
    offered; the others are, and the rule passes them."""
    here = [q for q in (places.place(0, i) for i in range(40))
            if places.entry("index", 64, q) is not None]
    ok = places.presses_clear("index", 64, here)
    assert ok.count(False) >= 1 and ok.count(True) >= 5
    fb = places.atlas.bodies
    for q, clear in zip(here, ok):
        e = places.entry("index", 64, q)
        full = places.atlas.base.copy()
        full[places.rail] = places.rail_m(q)
        full[places.hand.joint_slice("index")] = e.press
        assert fb.clear(places.hand.apply_couplings(full), "index", 64) is clear


def test_the_arm_time_is_the_same_whichever_way_is_asked_first(places):
    """The programme's arm time of a posture change (memoised) is the move's own time,
    the same for the move and its reverse, whichever was asked first: one memo for both
    ways once gave the first asker's answer to both, and a plan depended on the songs
    planned before it by the same planner. Its rail mirrored is another move (a right
    hand is not its mirror image)."""
    a, b = places.place(0, 3), places.place(2, -4)
    places.arms._arm_s.clear()
    first = (places.arm_time_s(a, b), places.arm_time_s(b, a))
    places.arms._arm_s.clear()
    second = (places.arm_time_s(b, a), places.arm_time_s(a, b))
    assert first[0] == first[1] == second[0] == second[1]
    reach = places.reach_m
    fwd = places.arm_move((places.rail_m(a), reach(0)), (places.rail_m(b), reach(2)))
    back = places.arm_move((places.rail_m(b), reach(2)), (places.rail_m(a), reach(0)))
    assert fwd.duration_s == pytest.approx(first[0], rel=1e-9)
    assert back.duration_s == pytest.approx(first[0], rel=1e-9)
    mirror = places.arm_time_s(places.place(0, 3), places.place(2, 10))
    assert mirror != first[0]
