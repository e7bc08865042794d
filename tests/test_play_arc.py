"""planner.play.arc: a one-degree-of-freedom finger's poses on its arc (the Mk5), the
atlas's table keyed by the mount, the Mk5 playing and catching what check confirms."""

from __future__ import annotations

import dataclasses
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from planner.hand.model import HandModel, load_hand
from planner.ik import PREPARE_HEIGHT_M, exposed_range_x, press_target, press_x_range
from planner.music import keyboard as kb
from planner.play.arc import ARC_TOL_RAD, Arc, arc_joint
from planner.play.atlas import BASE_HOVER_Z_M, HIGH_Z_M, REPEAT_DEPTH_M, TIP_RADIUS_M, Atlas

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def mk5_atlas():
    return Atlas(load_hand("mk5"))


def test_arc_joint_is_the_one_independent_joint():
    mk5, default = load_hand("mk5"), load_hand("default")
    for f in mk5.fingers:
        assert arc_joint(mk5, f) == mk5.index[f"{f}_q1"]
    assert all(arc_joint(default, f) is None for f in default.fingers)
    agh = load_hand("agh")  # middle and ring: their base follows another finger's shaft
    assert [f for f in agh.fingers if arc_joint(agh, f) is not None] == ["middle", "ring"]


@pytest.mark.parametrize("pitch", [60, 64, 61])
def test_mk5_poses_are_on_the_arc_at_their_heights(mk5_atlas, pitch):
    """Every entry of the index finger: the press tip at the play posture's press depth on
    the part of the key it presses, rise / hover / high at their heights, each on the arc
    (q2 = its coupling)."""
    h, a = mk5_atlas.hand, mk5_atlas
    ks = a.samples("index", pitch)
    assert ks, pitch
    top = kb.key(pitch).top_z_m
    x_lo, x_hi = press_x_range("index", pitch, TIP_RADIUS_M)
    y_lo, y_hi = press_target("index", pitch).y_range_m
    for k in ks:
        rail = a.rail_for("index", pitch, k)
        e = a.entry("index", pitch, rail)
        tips = {p: h.tip_positions(a.full_q(e, p, rail))[h.fingers.index("index")]
                for p in ("press", "rise", "hover", "high")}
        assert tips["press"][2] == pytest.approx(top - a.press_depth_m, abs=1e-7)
        assert x_lo <= tips["press"][0] <= x_hi and y_lo <= tips["press"][1] <= y_hi
        assert tips["rise"][2] == pytest.approx(top - REPEAT_DEPTH_M, abs=1e-7)
        assert tips["hover"][2] == pytest.approx(top + PREPARE_HEIGHT_M, abs=1e-7)
        assert tips["high"][2] == pytest.approx(HIGH_Z_M, abs=1e-7)
        assert np.allclose(h.coupling_errors(a.full_q(e, "press", rail)), 0.0, atol=1e-12)
    # the press x is where the rail puts the tip: the samples lie in the key's x window
    # (those whose bodies are clear of the neighbours: a part of it)
    assert len(ks) <= (x_hi - x_lo) / 0.001 + 1.5


def test_press_x_range_is_the_part_press_target_presses():
    d = kb.key(62)  # D4: a white key between two black keys
    assert press_x_range("index", 62, 0.002) == pytest.approx(
        (exposed_range_x(62)[0] + 0.002, exposed_range_x(62)[1] - 0.002))
    assert exposed_range_x(62)[1] - exposed_range_x(62)[0] < d.x_max_m - d.x_min_m
    # the thumb presses a white key in front of the black keys: its whole width
    assert press_x_range("thumb", 62, 0.002) == pytest.approx((d.x_min_m + 0.002,
                                                               d.x_max_m - 0.002))
    b = kb.key(61)
    assert press_x_range("index", 61, 0.0) == (b.x_min_m, b.x_max_m)


def test_mk5_natural_hand_hovers_on_the_arcs(mk5_atlas):
    """Every finger flexed from open until its tip is down at the hover height, the wrist
    at 0 (no finger of the mk5 takes part in the wrist's fit); the thumb (which presses no
    key) waits there over the white keys' front, clear of the black keys."""
    h, a = mk5_atlas.hand, mk5_atlas
    tips = h.tip_positions(a.base)
    assert np.allclose(tips[:, 2], BASE_HOVER_Z_M, atol=1e-7)
    assert a.base[h.index["wrist_flex"]] == 0.0 and a.base[h.index["wrist_dev"]] == 0.0
    assert all(a.base[h.index[f"{f}_q1"]] > 0.0 for f in h.fingers)
    assert 0.0 < tips[0, 1] < kb.BLACK_Y0_M - TIP_RADIUS_M


def test_arc_crossings_bisect_to_their_tolerance():
    h = load_hand("mk5")
    j = h.index["index_q1"]
    arc = Arc(h, "index", j, h.q_neutral)
    z = 0.5 * (arc.z.max() + arc.z.min())
    s = arc.descend(z)
    assert arc.tip(s)[2] <= z < arc.tip(s - 2 * ARC_TOL_RAD)[2]
    assert arc.descend(arc.z.max() + 0.01) is None  # the open tip is below it
    assert arc.ascend(arc.z.max() + 0.01, s) is None  # the arc never gets so high


def test_the_table_is_keyed_by_the_mount(mk5_atlas):
    """A hand file whose mount moves keeps its URDF: its old table is not used."""
    h = mk5_atlas.hand
    T = h.T_world_root.copy()
    T[2, 3] += 0.01
    moved = HandModel(dataclasses.replace(h.spec, T_world_root=tuple(map(tuple, T))))
    assert moved.urdf_sha256 == h.urdf_sha256
    other = Atlas(moved)
    assert other._params() != mk5_atlas._params()
    assert other._entries == {}  # the shipped table (mk5_atlas's) was not loaded
    assert len(mk5_atlas._entries) > 0


def test_mk5_plans_twinkle_and_check_confirms(tmp_path):
    """With its arcs the mk5 pressed 12 of twinkle's 14 notes by its pad points, its
    fingers' bodies on the neighbouring keys (28 wrong presses by check's body rule);
    from its play posture (its fitted wrist, 6 mm presses) no press keeps its body clear
    of the white keys' neighbours: the notes are left out, named ``body``, none pressed
    wrongly, and check confirms it (docs/history/2026-12-06-body-verdict.md)."""
    from planner import check

    out = tmp_path / "t.csv"
    song = str(ROOT / "songs" / "twinkle.mid")
    r = subprocess.run([sys.executable, str(ROOT / "cli.py"), "play", song, "--hand", "mk5",
                        "-o", str(out)], capture_output=True, text=True, cwd=tmp_path,
                       check=False)
    assert r.returncode == 0, r.stderr
    assert "14 notes, 0 played, 14 infeasible" in r.stderr
    # (12 for their bodies; E4's two: its one body-clear press holds less than the note's
    # 1.5 N within the motors)
    assert r.stderr.count("body: no finger presses") == 12
    assert r.stderr.count("torque: no finger presses E4") == 2
    rep = check.check_trajectory(str(out), song)
    assert rep.ok and not rep.play.wrong_presses, rep.problems


def test_mk5_catches_a_tennis_ball_and_check_confirms(tmp_path):
    from planner import check
    from planner.catch.plan.api import plan_catch

    p = plan_catch(30.0, 1.5, 0.0, "mk5", str(tmp_path / "c.csv"))
    assert p.feasible, p.reasons
    assert p.plan.timing.grasp_fingers == ("thumb", "middle", "ring")
    assert check.check_trajectory(str(tmp_path / "c.csv")).ok


def test_the_shipped_mk5_table_is_the_arcs_own(mk5_atlas):
    """planner/tables/atlas-<hash>.npz of the mk5 (scripts/make_atlas.py) holds what the
    arc gives: every entry of two keys solved afresh matches it to the bit."""
    from planner.play.atlas import table_path

    h = mk5_atlas.hand
    assert table_path(h.urdf_sha256).exists(), "run python scripts/make_atlas.py --hand mk5"
    fresh = Atlas(h)
    fresh._entries.clear()
    n = 0
    for f, pc in (("middle", 0), ("ring", 6)):
        for k in range(-45, 46):
            a, b = mk5_atlas.entry_at(f, pc, k), fresh.entry_at(f, pc, k)
            assert (a is None) == (b is None), (f, pc, k)
            if a is not None:
                n += 1
                for pose in ("press", "rise", "hover", "high"):
                    assert np.array_equal(getattr(a, pose), getattr(b, pose)), (f, pc, k)
                assert a.max_force_n == b.max_force_n
    assert n >= 5  # (9 with the body rule: 91 samples each before)


def test_mk5_white_press_holds_the_keys_weight_down_its_stroke(mk5_atlas):
    """From the key-down depth to full dip, the index's white-key press holds at least a
    key's weight (play's 0.5 N, check's key force): 0.70 N at 5 mm, rising to its 3.35 N
    at full dip, the arc's bottom, where play asks the note's force."""
    from planner.play.atlas import max_key_force_n
    from planner.play.force import MAX_FORCE_N, MIN_FORCE_N

    h, arc = mk5_atlas.hand, mk5_atlas._arcs["index"]
    s_down, s_press = arc.descend(-kb.DOWN_DEPTH_M), arc.descend(-kb.KEY_DIP_M)
    forces = [max_key_force_n(h, arc.q(s), "index") for s in np.linspace(s_down, s_press, 9)]
    assert min(forces) == pytest.approx(0.70, abs=0.01) and min(forces) > MIN_FORCE_N
    assert forces == sorted(forces)
    assert forces[-1] == pytest.approx(3.35, abs=0.01) and forces[-1] > MAX_FORCE_N
