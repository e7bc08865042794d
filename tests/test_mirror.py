"""The left hand (``planner.hand.mirror``): the default hand mirrored through the plane of
its rail's carriage, exactly: frames, collision bodies, Jacobians, limits, couplings,
motors, the hand file option ``side`` and ``extends``."""

from __future__ import annotations

import numpy as np
import pytest

from planner.errors import InputError
from planner.hand.bodies import collision_bodies
from planner.hand.builders import load_hand_spec
from planner.hand.mirror import S_MIRROR, mirror_pose, mirror_rpy
from planner.hand.model import HandModel, load_hand
from planner.hand.spec import rpy_matrix

RIGHT, LEFT = "default", "default-left"
N_CONFIGS = 25


@pytest.fixture(scope="module")
def hands() -> tuple[HandModel, HandModel]:
    return load_hand(RIGHT), load_hand(LEFT)


def _configs(hand: HandModel, n: int = N_CONFIGS, seed: int = 7) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.array([hand.apply_couplings(rng.uniform(hand.lower, hand.upper)) for _ in range(n)])


def _carried(hand: HandModel) -> list[str]:
    """The frames the rail carries (all but the root and the rail's own fixed end)."""
    m = hand.pin_model
    rail = m.getJointId("rail")
    out = []
    for f in m.frames:
        j = f.parentJoint
        while j > 0 and j != rail:
            j = m.parents[j]
        if j == rail:
            out.append(f.name)
    return out


def test_the_mirror_of_a_rotation_is_s_r_s() -> None:
    rng = np.random.default_rng(3)
    for rpy in rng.uniform(-np.pi, np.pi, (50, 3)):
        R = rpy_matrix(tuple(rpy))
        assert np.allclose(rpy_matrix(mirror_rpy(tuple(rpy))), S_MIRROR @ R @ S_MIRROR,
                           atol=1e-14)


def test_every_frame_is_the_right_hands_reflected_through_the_carriage(hands) -> None:
    right, left = hands
    assert np.array_equal(right.T_world_root, left.T_world_root)  # one rail, one mount
    assert np.allclose(right.T_world_root[:3, :3], np.eye(3))  # (the plane is world x)
    frames = _carried(right)
    assert {"palm_center", "thumb_tip", "pinky_tip", "reach_carriage"} <= set(frames)
    worst = 0.0
    for q in _configs(right):
        plane_x = right.frame_pose(q, "carriage")[0, 3]
        assert left.frame_pose(q, "carriage")[0, 3] == plane_x  # the rail is not reflected
        for f in frames:
            want = mirror_pose(right.frame_pose(q, f), plane_x)
            worst = max(worst, float(np.abs(left.frame_pose(q, f) - want).max()))
    assert worst < 1e-12
    # the thumb on the bass side of a right hand, on the treble side of a left one
    tips_r, tips_l = right.tip_positions(right.q_neutral), left.tip_positions(left.q_neutral)
    assert tips_r[0, 0] < tips_r[4, 0] and tips_l[0, 0] > tips_l[4, 0]


def test_the_collision_bodies_mirror(hands) -> None:
    right, left = hands
    def key(b, s):  # (a body in its link's frame, reflected by s: as a set member)
        p0, p1 = s @ np.array(b.p0_m), s @ np.array(b.p1_m)
        ends = tuple(sorted((tuple(np.round(p0, 12)), tuple(np.round(p1, 12)))))
        return (b.link, b.kind, ends, round(b.radius_m, 12), tuple(np.round(b.half_m, 12)),
                b.finger)
    br, bl = collision_bodies(right.spec), collision_bodies(left.spec)
    assert len(br) == len(bl) > 30
    on_rail = set(_carried(right))
    assert all(b.link in on_rail for b in br)  # (the root has no body)
    assert {key(b, np.eye(3)) for b in bl} == {key(b, S_MIRROR) for b in br}
    # in the world, at any configuration: every body reflected through the carriage's plane
    def world(hand, bodies, q, plane_x=None):
        out = set()
        for b in bodies:
            T = hand.frame_pose(q, b.link)
            ends = [T[:3, :3] @ np.array(p) + T[:3, 3] for p in (b.p0_m, b.p1_m)]
            if plane_x is not None:
                ends = [np.r_[2 * plane_x - e[0], e[1:]] for e in ends]
            R = T[:3, :3] if plane_x is None else S_MIRROR @ T[:3, :3] @ S_MIRROR
            box = np.round(np.abs(R) @ np.array(b.half_m), 9)  # (the box's extent)
            out.add((b.kind, tuple(sorted(tuple(np.round(e, 9)) for e in ends)),
                     round(b.radius_m, 12), tuple(box), b.finger))
        return out
    for q in _configs(right, 3, seed=5):
        plane_x = right.frame_pose(q, "carriage")[0, 3]
        assert world(left, bl, q) == world(right, br, q, plane_x)


def test_the_jacobians_mirror_and_match_finite_differences(hands) -> None:
    right, left = hands
    rail = right.index["rail"]
    S = S_MIRROR
    h = 1e-6
    for q in _configs(right, 8, seed=11):
        Jr, Jl = right.tip_jacobians(q), left.tip_jacobians(q)
        want = np.einsum("ij,fjn->fin", S, Jr)
        want[:, :, rail] = Jr[:, :, rail]  # (the rail: along +x for both hands)
        assert np.abs(Jl - want).max() < 1e-12
        fd = np.empty_like(Jl)
        for j in range(left.n):
            e = np.zeros(left.n)
            e[j] = h
            fd[:, :, j] = (left.tip_positions(q + e) - left.tip_positions(q - e)) / (2 * h)
        assert np.abs(fd - Jl).max() < 1e-7


def test_limits_couplings_and_motors_are_the_same_numbers(hands) -> None:
    right, left = hands
    assert left.side == "left" and right.side == "right"
    assert left.joint_names == right.joint_names and left.motor_names == right.motor_names
    for a in ("lower", "upper", "velocity", "acceleration", "jerk", "stop_margin",
              "motor_speed", "motor_peak_torque"):
        assert np.array_equal(getattr(left, a), getattr(right, a)), a
    assert np.array_equal(left.motor_map.C, right.motor_map.C)
    assert left.spec.couplings == right.spec.couplings
    assert left.spec.actuators == right.spec.actuators
    assert left.spec.play_posture == right.spec.play_posture
    q = _configs(right, 1)[0]
    assert np.array_equal(left.motor_angles(q), right.motor_angles(q))
    # the same mass, the same gravity on every joint but those the mirror turns over
    tau_r, tau_l = right.gravity_torques(q), left.gravity_torques(q)
    assert np.allclose(np.abs(tau_l), np.abs(tau_r), atol=1e-12)
    assert left.fingers_low_to_high == tuple(reversed(right.fingers_low_to_high))


def test_side_and_extends_in_a_hand_file(tmp_path) -> None:
    p = tmp_path / "mine.toml"
    p.write_text('extends = "default"\nname = "default-left"\nside = "left"\n'
                 'description = "The default hand mirrored: a left hand on a second carriage '
                 'of the same rail"\n')
    assert HandModel(load_hand_spec(str(p))).urdf == load_hand(LEFT).urdf
    p.write_text('extends = "default"\nside = "right"\n')
    assert HandModel(load_hand_spec(str(p))).urdf == load_hand(RIGHT).urdf
    # a table merges key by key: one number changed, the others the default's
    p.write_text('extends = "default-left"\n[rail]\nupper_m = 0.30\n')
    spec = load_hand_spec(str(p))
    assert spec.side == "left" and spec.joint("rail").upper == 0.30
    assert spec.joint("rail").lower == -0.62
    # another kind mirrors too
    p.write_text('extends = "mk5"\nside = "left"\n')
    mk5_left, mk5 = HandModel(load_hand_spec(str(p))), load_hand("mk5")
    q = mk5.q_neutral
    tips_r, tips_l = mk5.tip_positions(q), mk5_left.tip_positions(q)
    plane_x = mk5.frame_pose(q, "carriage")[0, 3]
    assert np.allclose(tips_l[:, 0], 2 * plane_x - tips_r[:, 0], atol=1e-12)


@pytest.mark.parametrize("text,needle", [
    ('extends = "default"\nside = "middle"\n', "side must be one of 'right', 'left'"),
    ('extends = 3\n', "'extends' must be a hand name"),
    ('extends = "nosuch"\n', "unknown hand 'nosuch'"),
    ('extends = "loop.toml"\n', "chains more than"),
])
def test_bad_side_or_extends_is_one_input_error(tmp_path, text, needle) -> None:
    p = tmp_path / "loop.toml"
    p.write_text(text)
    with pytest.raises(InputError, match=needle) as e:
        load_hand_spec(str(p))
    assert "\n" not in str(e.value)
