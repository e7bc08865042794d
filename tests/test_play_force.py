"""planner.play.force (a press counts only if the motors drive the key down its travel,
the pad's friction counted) and planner.play.planar (a finger locked in x presses where
its tip is across the key)."""

from __future__ import annotations

import numpy as np
import pytest

from planner.hand.model import load_hand
from planner.ik import press_target, press_x_range
from planner.music import keyboard as kb
from planner.play.atlas import TIP_RADIUS_M, Atlas, max_key_force_n
from planner.play.force import (
    MAX_FORCE_N,
    PAD_FRICTION,
    descent_poses,
    held_force_n,
    press_capacity_n,
    press_force_n,
    pressed_force_n,
)
from planner.play.planar import locked_in_x, planar_press_target
from planner.simulate.keyboard import front_force_n, key_body

C4 = 60


@pytest.fixture(scope="module")
def mk5_atlas():
    return Atlas(load_hand("mk5"))


@pytest.fixture(scope="module")
def default_atlas():
    return Atlas(load_hand("default"))


@pytest.fixture(scope="module")
def agh_atlas():
    return Atlas(load_hand("agh"))


def test_press_force_of_velocity():
    assert press_force_n(0) == 0.5 and press_force_n(127) == 3.0
    assert press_force_n(80) == pytest.approx(0.5 + 2.5 * (80 / 127) ** 2)


def test_mk5_press_pose_holds_the_note_but_the_descent_not_the_key(mk5_atlas):
    """The Mk5's index on its arc over C4: at full dip (the arc's bottom, where the mount's
    height puts it) the motors hold more than a forte note's force against a vertical
    push; where the pad meets the key's top, sliding along it as the arc moves it, they
    hold less than the key's 0.5 N down-weight, so its press counts for no note."""
    h, arc = mk5_atlas.hand, mk5_atlas._arcs["index"]
    top = kb.key(C4).top_z_m
    s_top, s_press = arc.descend(top), arc.descend(top - mk5_atlas.press_depth_m)
    assert s_top is not None and s_press is not None and s_top < s_press
    assert held_force_n(h, arc.q(arc.descend(top - kb.KEY_DIP_M)), "index") > MAX_FORCE_N
    slide = arc.tip(s_top + 1e-4)[:2] - arc.tip(s_top)[:2]
    at_top = held_force_n(h, arc.q(s_top), "index", slide / np.linalg.norm(slide), PAD_FRICTION)
    assert at_top < front_force_n(key_body(C4), 0.0) == pytest.approx(0.5)
    hover = arc.q(arc.ascend(top + 0.0055, s_press))
    assert press_capacity_n(h, descent_poses(h, hover, arc.q(s_press)), "index", C4) == 0.0


def test_friction_against_the_slide_lowers_the_force(default_atlas):
    h = default_atlas.hand
    q = default_atlas.base
    free = held_force_n(h, q, "index")
    assert 0.0 < held_force_n(h, q, "index", np.array([0.0, 1.0]), PAD_FRICTION) != free
    assert held_force_n(h, q, "index", np.array([0.0, 1.0]), 0.0) == pytest.approx(free)


def test_default_hand_presses_hold_their_descent(default_atlas):
    """On the default hand the descent holds the key's spring on every press tried: the
    capacity is the press pose's force, as before the descent was counted."""
    a, h = default_atlas, default_atlas.hand
    n = 0
    for f in ("thumb", "index", "pinky"):
        for pitch in (C4, C4 + 1, C4 + 4):
            for k in a.samples(f, pitch)[::10]:
                rail = a.rail_for(f, pitch, k)
                e = a.entry(f, pitch, rail)
                press, hover = a.full_q(e, "press", rail), a.full_q(e, "hover", rail)
                cap = press_capacity_n(h, descent_poses(h, hover, press), f, pitch)
                assert cap == pytest.approx(max_key_force_n(h, press, f), rel=1e-9)
                assert cap > 0.94
                n += 1
    assert n >= 9


def test_agh_index_is_locked_in_x_default_index_not(agh_atlas, default_atlas):
    assert locked_in_x(agh_atlas.hand, "index", agh_atlas.base)
    assert not locked_in_x(default_atlas.hand, "index", default_atlas.base)


def test_planar_press_target_takes_the_tips_x(agh_atlas, default_atlas):
    h, q = agh_atlas.hand, agh_atlas.base.copy()
    x_tip = float(h.tip_positions(q)[h.fingers.index("index"), 0])
    key = kb.key(C4)
    t = press_target("index", C4, 0.006, front=True)
    # the rail puts the tip 4 mm right of C4's centre: the target moves there
    q[agh_atlas.rail] += key.center_x_m + 0.004 - x_tip
    moved = planar_press_target(h, t, q, TIP_RADIUS_M, True)
    assert moved.point_m[0] == pytest.approx(key.center_x_m + 0.004, abs=1e-9)
    assert moved.point_m[1:] == t.point_m[1:] and moved.y_range_m == t.y_range_m
    # ... and off the key's pressed part: no target
    lo, hi = press_x_range("index", C4, TIP_RADIUS_M, True)
    q[agh_atlas.rail] += hi - lo
    assert planar_press_target(h, t, q, TIP_RADIUS_M, True) is None
    # a finger free in x keeps the key's centre
    d = default_atlas
    assert planar_press_target(d.hand, t, d.base, TIP_RADIUS_M, True) is t


def test_agh_index_presses_white_keys_across_them(agh_atlas):
    """Each white key of the octave: the AGH's index keeps presses at several rail places
    (one before the x rule), its press tip on the part of the key it presses."""
    a, h = agh_atlas, agh_atlas.hand
    i = h.fingers.index("index")
    for pitch in (60, 62, 64, 65, 67, 69, 71):
        ks = a.samples("index", pitch)
        assert len(ks) >= 3, pitch
        lo, hi = press_x_range("index", pitch, TIP_RADIUS_M, "index" in a.front)
        for k in ks:
            rail = a.rail_for("index", pitch, k)
            x = h.tip_positions(a.full_q(a.entry("index", pitch, rail), "press", rail))[i, 0]
            assert lo - 1e-9 <= x <= hi + 1e-9


def test_a_pose_presses_a_note_softer_where_it_holds_less():
    """``pressed_force_n``: the note's force where the pose holds it, all the pose holds
    where that is less, nothing where its descent does not drive the key down (0)."""
    assert pressed_force_n(1.5, 2.9) == 1.5
    assert pressed_force_n(3.0, 2.94) == 2.94
    assert pressed_force_n(3.0, 0.0) == 0.0


def test_a_forte_note_is_pressed_from_the_places_of_a_mezzo_forte_one():
    """The default hand's ring holds at most 2.94 N at any press (the index alone 3 N),
    so a velocity-127 note (3 N) had no place for the ring (nor the middle or pinky): the
    fingering gave every forte note to the index. Pressed softer where its pose holds
    less, the ring presses a forte G#4 from every place it presses a mezzo-forte one."""
    from planner.music.midi import Note
    from planner.play.costs import Costs
    from planner.play.places import Places

    places = Places(load_hand("default"))
    notes = [Note(68, 0.0, 0.5, 64), Note(68, 1.0, 1.5, 127)]
    assert press_force_n(127) > max(
        e.max_force_n for i in range(-40, 60) for p in range(places.postures)
        if (e := places.entry("ring", 68, places.place(p, i))) is not None)
    c = Costs(notes, places, 100.0)
    assert c.rails("ring", 0) and c.rails("ring", 1) == c.rails("ring", 0)
