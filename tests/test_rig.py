"""The rig that carries the hand (issue "Play on the real keyboard", item 1): the rail
along the keyboard and the ``reach`` axis towards and away from the player, each a URDF
prismatic joint with its own travel, speed, acceleration and belt motor from the hand
file; ``check`` judges them like every other joint."""

from __future__ import annotations

import numpy as np
import pytest

from planner.check import check_trajectory
from planner.errors import InputError
from planner.hand.model import load_hand
from tests.handfiles import default_text, edit, load_text
from tests.trajbuild import base_posture, write_traj


def test_default_hand_has_rail_and_reach(hand):
    assert hand.rig_joints == ("rail", "reach")
    j = hand.index["reach"]
    assert (hand.lower[j], hand.upper[j]) == (-0.20, 0.05)
    assert hand.acceleration[j] == 40.0
    assert hand.velocity[j] == pytest.approx(278.0 * 0.010)  # the belt motor's speed caps it
    assert "motor.reach" in [f"motor.{m}" for m in hand.motor_names]
    assert '<joint name="reach" type="prismatic">' in hand.urdf
    assert '<axis xyz="0 1 0"/>' in hand.urdf.split('<joint name="reach"')[1].split("</joint>")[0]


def test_other_hands_decide_their_own_rig():
    for name in ("mk5", "agh"):
        assert "reach" not in load_hand(name).index


def test_reach_moves_every_tip_along_the_keyboards_y(hand):
    q = hand.q_neutral.copy()
    moved = q.copy()
    moved[hand.index["reach"]] = -0.15
    d = hand.tip_positions(moved) - hand.tip_positions(q)
    assert np.allclose(d, [0.0, -0.15, 0.0], atol=1e-12)


def test_reach_motor_is_its_belt(hand):
    q = hand.q_neutral.copy()
    q[hand.index["reach"]] = -0.1
    m = hand.motor_angles(q[None, :])[0]
    assert m[hand.motor_names.index("reach")] == pytest.approx(-0.1 / 0.010)


def test_hand_file_without_reach_and_with_a_bad_one(tmp_path):
    text = default_text()
    no_reach = edit(text, "[reach]\n", "[reach]\nenabled = false\n").replace(
        "enabled = true\nlower_m = -0.20", "lower_m = -0.20", 1)
    # (the play posture holds the forearm on the reach axis: without the axis, at 0)
    with pytest.raises(InputError, match="play.reach_m: the hand has no reach joint"):
        load_text(tmp_path, no_reach)
    off = load_text(tmp_path, edit(no_reach, "reach_m = [-0.175, -0.15, -0.10]",
                                   "reach_m = 0.0"))
    assert "reach" not in off.index and off.rig_joints == ("rail",)
    assert off.spec.play_posture.reach_m == (0.0,)
    with pytest.raises(InputError, match="reach: lower_m must be below upper_m"):
        load_text(tmp_path, edit(text, "lower_m = -0.20", "lower_m = 0.10"))


def test_check_judges_the_reach_axis(hand, tmp_path):
    """A reach step of 5 cm in one row (5 m/s against 2.78) is a speed violation of the
    joint and of its motor, named."""
    q0 = base_posture(hand)
    q = np.tile(q0, (50, 1))
    q[25:, hand.index["reach"]] = q0[hand.index["reach"]] + 0.05
    t = np.arange(50) / 100.0
    path = write_traj(tmp_path / "r.csv", hand, t, q)
    rep = check_trajectory(path, None, strict=False)
    worst = {lc.category: lc for lc in rep.limits}
    assert worst["joint_velocity"].count >= 1 and worst["joint_velocity"].name == "reach"
    assert not rep.ok
