"""Tests of the default hand (hands/default.toml) and of the hand model.

The numbers come from the seed "Engineering Calculations Summary"
(shared/seeds/000_776cdc32671efdf6.txt): Table 2 upper-limit lengths, the
fingertip-velocity and DH worked examples, the 0.144 N m press torque, the
278 rad/s motor at a 5 mm spool, 50 % tendon efficiency, 2:1 wrist gears, the
tip/middle ratios 0.667 / 0.556 / 0.333, 2.5-3 kg and ~20 +/- 1 DOF.

Edited hand files (the other ratios, the motor-bound speed limits, the errors) are
tested in test_hand_spec.py; tests/handfiles.py writes them.
"""

from __future__ import annotations

import hashlib
import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import tomllib

from planner.hand.builders import load_hand_spec
from planner.hand.model import HandModel
from planner.hand.spec import (
    FINGERS,
    INCH_M,
    PALM_FRAME,
    TIP_FRAMES,
    HandSpec,
    Joint,
    Link,
    rpy_matrix,
)
from planner.hand.urdf import urdf_sha256, urdf_text
from tests.handfiles import DEFAULT_TOML, LONG_FINGERS, random_q

# Seed Table 2, "Length upper Limit" column, inches: (base, middle, top)
TABLE2_UPPER_IN = {
    "index": (2.8125, 1.6875, 1.6875),
    "middle": (3.46875, 1.96875, 1.6875),
    "ring": (3.28125, 1.59375, 1.6875),
    "pinky": (2.53125, 1.3125, 1.40625),
}
TABLE2_THUMB_IN = (2.25, 2.0625)  # base, top
TABLE2_PALM_IN = (7.125, 5.25)  # length, breadth


@pytest.fixture(scope="module")
def toml_data() -> dict:
    return tomllib.loads(DEFAULT_TOML.read_text(encoding="utf-8"))


@pytest.fixture(scope="module")
def urdf_root(hand) -> ET.Element:
    return ET.fromstring(hand.urdf)


# =========================================================================== URDF
def test_urdf_loads_in_pinocchio(hand) -> None:
    model = pin.buildModelFromXML(hand.urdf)
    assert model.nq == model.nv == 23  # 21 hand joints, the rail and the reach
    for frame in (*TIP_FRAMES, PALM_FRAME):
        assert model.existFrame(frame), frame
    assert set(model.names[1:]) == set(hand.joint_names)


def test_urdf_loads_in_placo(hand, tmp_path: Path) -> None:
    import placo

    path = tmp_path / "default.urdf"
    path.write_text(hand.urdf, encoding="utf-8")
    robot = placo.RobotWrapper(str(path), placo.Flags.ignore_collisions)
    assert set(robot.joint_names()) == set(hand.joint_names)
    frames = set(robot.frame_names())
    assert {*TIP_FRAMES, PALM_FRAME} <= frames
    assert robot.total_mass() == pytest.approx(2.925, abs=1e-12)


def test_dof_21_hand_joints_plus_rail_and_reach(hand, urdf_root) -> None:
    """Seed Table 1: ~20 +/- 1 DOF. 3 thumb + 4 x 4 fingers + 2 wrist = 21, plus the rig's
    rail and reach."""
    movable = [j for j in urdf_root.iter("joint") if j.get("type") != "fixed"]
    assert len(movable) == 23
    kinds = {j.get("name"): j.get("type") for j in movable}
    assert kinds.pop("rail") == kinds.pop("reach") == "prismatic"
    assert len(kinds) == 21 and 19 <= len(kinds) <= 21
    assert set(kinds.values()) == {"revolute"}
    assert hand.n == 23 and sum(1 for n in hand.joint_names if n not in ("rail", "reach")) == 21
    # 4 DIPs follow their PIPs: 17 independent hand joints, and the rig's two
    assert len(hand.couplings) == 4 and len(hand.independent) == 19


def test_every_movable_joint_is_named(hand, urdf_root) -> None:
    names = [j.get("name") for j in urdf_root.iter("joint") if j.get("type") != "fixed"]
    assert all(isinstance(n, str) and n.strip() == n and n for n in names)
    assert len(set(names)) == len(names)
    assert tuple(names) == hand.joint_names  # our joint order is the file order
    # every link and joint name is unique and every joint connects existing links
    links = {lk.get("name") for lk in urdf_root.iter("link")}
    for j in urdf_root.iter("joint"):
        assert j.find("parent").get("link") in links
        assert j.find("child").get("link") in links


def test_frames_exist_as_links(urdf_root) -> None:
    links = {lk.get("name") for lk in urdf_root.iter("link")}
    assert {"thumb_tip", "index_tip", "middle_tip", "ring_tip", "pinky_tip", "palm_center"} <= links


def test_dip_joints_carry_mimic(urdf_root) -> None:
    joints = {j.get("name"): j for j in urdf_root.iter("joint")}
    mimics = [j.get("name") for j in joints.values() if j.find("mimic") is not None]
    assert sorted(mimics) == sorted(f"{f}_dip" for f in LONG_FINGERS)
    for f in LONG_FINGERS:
        m = joints[f"{f}_dip"].find("mimic")
        assert m.attrib == {"joint": f"{f}_pip", "multiplier": "0.667", "offset": "0"}


def test_palm_down_fingers_along_y_at_zero(hand) -> None:
    """Spec section 3 / default.toml frames: at q = 0 the palm faces down and the fingers point +y."""
    q = np.zeros(hand.n)
    T = hand.palm_pose(q)
    assert np.allclose(T[:3, 2], [0.0, 0.0, -1.0], atol=1e-12)  # outward palm normal
    for f in LONG_FINGERS:
        mcp = hand.frame_pose(q, f"{f}_base")[:3, 3]
        tip = hand.frame_pose(q, f"{f}_tip")[:3, 3]
        d = tip - mcp
        assert d[0] == pytest.approx(0.0, abs=1e-12) and d[1] > 0.09


# =========================================================================== lengths
def _origin(urdf_root: ET.Element, joint: str) -> np.ndarray:
    j = next(j for j in urdf_root.iter("joint") if j.get("name") == joint)
    return np.array([float(x) for x in j.find("origin").get("xyz").split()])


@pytest.mark.parametrize("finger", LONG_FINGERS)
def test_finger_lengths_are_table2_upper_limits(hand, urdf_root, finger: str) -> None:
    """Segment lengths read back from the generated URDF (not the TOML).

    base = MCP -> PIP, middle = PIP -> DIP (joint origins); top = DIP -> end of the
    distal segment: the tip pad frame sits ``pad`` below and ``pad / 2`` short of
    the end, so top = y - z / 2 of the tip frame's origin in the distal link.
    """
    base, middle, top = (x * INCH_M for x in TABLE2_UPPER_IN[finger])
    assert np.linalg.norm(_origin(urdf_root, f"{finger}_mcp_flex")) == 0.0  # knuckle at the abd axis
    assert np.linalg.norm(_origin(urdf_root, f"{finger}_pip")) == pytest.approx(base, abs=1e-12)
    assert np.linalg.norm(_origin(urdf_root, f"{finger}_dip")) == pytest.approx(middle, abs=1e-12)
    tip = _origin(urdf_root, f"{finger}_tip_fixed")
    assert tip[0] == 0.0 and tip[2] < 0.0
    assert tip[1] - tip[2] / 2 == pytest.approx(top, abs=1e-12)
    # the distal segment's box is `top` long
    link = next(lk for lk in urdf_root.iter("link") if lk.get("name") == f"{finger}_top")
    size = [float(x) for x in link.find("visual/geometry/box").get("size").split()]
    assert size[1] == pytest.approx(top, abs=1e-12)

    # the same through Pinocchio: distances between consecutive joint centres at any q
    rng = np.random.default_rng(3)
    model, data = hand.pin_model, hand.pin_model.createData()
    ids = [model.getJointId(f"{finger}_{j}") for j in ("mcp_flex", "pip", "dip")]
    for _ in range(3):
        q = random_q(hand, rng)
        pin.forwardKinematics(model, data, hand.pin_q(q))
        p = [data.oMi[i].translation for i in ids]
        assert np.linalg.norm(p[1] - p[0]) == pytest.approx(base, abs=1e-12)
        assert np.linalg.norm(p[2] - p[1]) == pytest.approx(middle, abs=1e-12)


def test_index_lengths_in_metres(urdf_root) -> None:
    """Index 2.8125 / 1.6875 / 1.6875 in = 0.0714375 / 0.0428625 / 0.0428625 m."""
    assert np.linalg.norm(_origin(urdf_root, "index_pip")) == pytest.approx(0.0714375, abs=1e-12)
    assert np.linalg.norm(_origin(urdf_root, "index_dip")) == pytest.approx(0.0428625, abs=1e-12)
    tip = _origin(urdf_root, "index_tip_fixed")
    assert tip[1] - tip[2] / 2 == pytest.approx(0.0428625, abs=1e-12)


def test_thumb_and_palm_lengths(urdf_root) -> None:
    tb, tt = (x * INCH_M for x in TABLE2_THUMB_IN)
    assert np.linalg.norm(_origin(urdf_root, "thumb_ip")) == pytest.approx(tb, abs=1e-12)
    tip = _origin(urdf_root, "thumb_tip_fixed")
    assert tip[1] - tip[2] / 2 == pytest.approx(tt, abs=1e-12)
    p_len, p_wid = (x * INCH_M for x in TABLE2_PALM_IN)
    for f in LONG_FINGERS:  # every MCP sits at the palm's far edge
        assert _origin(urdf_root, f"{f}_mcp_abd")[1] == pytest.approx(p_len, abs=1e-12)
    palm = next(lk for lk in urdf_root.iter("link") if lk.get("name") == "palm")
    size = [float(x) for x in palm.find("visual/geometry/box").get("size").split()]
    assert size[:2] == pytest.approx([p_wid, p_len], abs=1e-12)


# =========================================================================== mass
def test_total_mass_and_inertias(hand) -> None:
    """Seed Table 1: 2.5-3 kg. Model: 2.925 kg, of which 0.25 kg is the rail carriage and
    0.25 kg the reach axis's carriage (the rig's, not the hand's: the hand is 2.425 kg)."""
    model = pin.buildModelFromXML(hand.urdf)
    total = sum(inertia.mass for inertia in model.inertias)
    assert 2.5 <= total <= 3.0
    assert total == pytest.approx(2.925, abs=1e-12)
    assert total == pytest.approx(sum(lk.mass_kg for lk in hand.spec.links), abs=1e-12)
    for name, inertia in zip(model.names, model.inertias):
        if name == "universe":
            assert inertia.mass == 0.0
            continue
        assert inertia.mass > 0, name
        eig = np.linalg.eigvalsh(inertia.inertia)
        assert np.all(eig > 0), name
        assert np.allclose(inertia.inertia, inertia.inertia.T)
    # per link (URDF): positive principal moments satisfying the triangle inequality
    for lk in hand.spec.links:
        if lk.mass_kg > 0:
            ixx, iyy, izz = lk.inertia()
            assert min(ixx, iyy, izz) > 0
            assert ixx + iyy >= izz and iyy + izz >= ixx and ixx + izz >= iyy


# =========================================================================== determinism
def test_urdf_is_deterministic_and_hashed(hand) -> None:
    a = urdf_text(load_hand_spec("default"))
    b = urdf_text(load_hand_spec("default"))
    assert a.encode("utf-8") == b.encode("utf-8") == hand.urdf.encode("utf-8")
    assert HandModel(load_hand_spec("default")).urdf == hand.urdf
    digest = hashlib.sha256(hand.urdf.encode("utf-8")).hexdigest()
    assert hand.urdf_sha256 == digest == urdf_sha256(a)
    assert str(DEFAULT_TOML) and load_hand_spec(str(DEFAULT_TOML)) == load_hand_spec("default")


def test_mounted_keeps_hash_and_moves_tips(hand) -> None:
    T = np.eye(4)
    T[:3, :3] = rpy_matrix(tuple(math.radians(a) for a in (126.0, 0.0, 90.0)))
    T[:3, 3] = [-0.2287, 0.3, -0.3148]
    other = hand.mounted(T)
    assert other.urdf_sha256 == hand.urdf_sha256 and other.urdf == hand.urdf
    assert np.array_equal(hand.T_world_root, np.array(hand.spec.T_world_root))  # original untouched
    rng = np.random.default_rng(1)
    move = T @ np.linalg.inv(hand.T_world_root)
    for _ in range(3):
        q = random_q(hand, rng)
        p0 = hand.tip_positions(q)
        p1 = other.tip_positions(q)
        expected = (move[:3, :3] @ p0.T).T + move[:3, 3]
        assert np.allclose(p1, expected, atol=1e-12)
        assert np.allclose(other.palm_pose(q), move @ hand.palm_pose(q), atol=1e-12)
    # gravity follows the mount: in the root frame it is R^T (0, 0, -9.81)
    assert np.allclose(other.pin_model.gravity.linear, T[:3, :3].T @ [0.0, 0.0, -9.81])
    assert np.allclose(hand.pin_model.gravity.linear, [0.0, 0.0, -9.81])


def test_within_margins_limits_are_the_planners(hand) -> None:
    """``within_margins``: the hand whose limits are the hard stops less each joint's stop
    margin (index_pip 0..100 deg: 2..98 deg), its margins then 0; the hand itself untouched,
    the same URDF and hash."""
    other = hand.within_margins()
    j = hand.index["index_pip"]
    assert other.lower[j] == pytest.approx(math.radians(2.0)) and hand.lower[j] == 0.0
    assert other.upper[j] == pytest.approx(hand.upper[j] - math.radians(2.0))
    assert np.array_equal(other.lower, hand.plan_lower)
    assert np.array_equal(other.upper, hand.plan_upper)
    assert np.array_equal(other.plan_lower, other.lower) and not np.any(other.stop_margin)
    assert hand.stop_margin[j] == pytest.approx(math.radians(2.0))
    assert other.urdf_sha256 == hand.urdf_sha256
    q = other.apply_couplings(np.clip(np.zeros(hand.n), other.lower, other.upper))
    assert hand.within_plan_limits(q) and not hand.within_plan_limits(hand.q_neutral)


# =========================================================================== couplings
def test_apply_couplings_default_ratio(hand) -> None:
    rng = np.random.default_rng(2)
    for _ in range(10):
        raw = random_q(hand, rng, coupled=False)
        errs = hand.coupling_errors(raw)
        q = hand.apply_couplings(raw)
        for k, f in enumerate(LONG_FINGERS):
            pip, dip = hand.index[f"{f}_pip"], hand.index[f"{f}_dip"]
            assert q[dip] == pytest.approx(0.667 * raw[pip], abs=1e-15)
            assert errs[k] == pytest.approx(raw[dip] - 0.667 * raw[pip], abs=1e-15)
        others = [i for i in range(hand.n) if i not in set(hand.dependent)]
        assert np.array_equal(q[others], raw[others])
        assert np.all(hand.coupling_errors(q) == 0.0)
        assert hand.within_limits(q)
    # batched form
    Q = np.stack([random_q(hand, rng, coupled=False) for _ in range(4)])
    assert np.all(hand.coupling_errors(hand.apply_couplings(Q)) == 0.0)
    assert hand.coupling_errors(Q).shape == (4, 4)


# =========================================================================== Jacobians
@pytest.mark.parametrize("mounted", [False, True])
def test_tip_jacobians_match_finite_differences(hand, mounted: bool) -> None:
    h = hand
    if mounted:
        T = np.eye(4)
        T[:3, :3] = rpy_matrix((0.3, -0.7, 1.9))
        T[:3, 3] = [0.1, -0.2, 0.3]
        h = hand.mounted(T)
    rng = np.random.default_rng(10 + mounted)
    eps = 1e-6
    for _ in range(5):
        q = random_q(h, rng, coupled=False)
        J = h.tip_jacobians(q)
        assert J.shape == (5, 3, h.n)
        fd = np.empty_like(J)
        for i in range(h.n):
            dq = np.zeros(h.n)
            dq[i] = eps
            fd[:, :, i] = (h.tip_positions(q + dq) - h.tip_positions(q - dq)) / (2 * eps)
        assert np.max(np.abs(J - fd)) < 1e-6
        # the rail moves every tip along the root x axis one for one
        assert np.allclose(J[:, :, h.index["rail"]], h.T_world_root[:3, 0], atol=1e-12)
        # a finger's joints move only its own tip
        for k, f in enumerate(FINGERS):
            own = set(h.joint_slice(f))
            for other_k in range(5):
                if other_k != k:
                    assert np.all(J[other_k][:, sorted(own)] == 0.0)


# =========================================================================== actuators
def test_motor_angles_linear_map(hand, toml_data) -> None:
    t = toml_data["tendon"]
    spool = t["spool_radius_m"]
    assert spool == 0.005
    fingers = {f["name"]: f for f in toml_data["finger"]}
    rng = np.random.default_rng(6)
    for _ in range(5):
        q = random_q(hand, rng)
        qm = dict(zip(hand.motor_names, hand.motor_angles(q)))
        for f in LONG_FINGERS:
            arm, ratio = fingers[f]["moment_arm_m"], fingers[f]["dip_ratio"]
            q_pip = q[hand.index[f"{f}_pip"]]
            assert qm[f"{f}_pip"] == pytest.approx(
                (arm["pip"] + ratio * arm["dip"]) / spool * q_pip, rel=1e-12, abs=1e-15)
            assert qm[f"{f}_mcp"] == pytest.approx(
                arm["mcp"] / spool * q[hand.index[f"{f}_mcp_flex"]], rel=1e-12, abs=1e-15)
            assert qm[f"{f}_abd"] == pytest.approx(q[hand.index[f"{f}_mcp_abd"]], abs=1e-15)
        tarm = toml_data["thumb"]["moment_arm_m"]
        assert qm["thumb_ip"] == pytest.approx(tarm["ip"] / spool * q[hand.index["thumb_ip"]])
        assert qm["thumb_cmc_flex"] == pytest.approx(
            tarm["cmc_flex"] / spool * q[hand.index["thumb_cmc_flex"]])
        for w in ("wrist_flex", "wrist_dev"):  # gear 2:1: the motor turns twice per joint turn
            assert qm[w] == pytest.approx(2.0 * q[hand.index[w]], abs=1e-15)
        assert qm["rail"] == pytest.approx(q[hand.index["rail"]] / 0.010, abs=1e-12)
    # linear: f(a x + b y) = a f(x) + b f(y), and batched
    x, y = random_q(hand, rng), random_q(hand, rng)
    assert np.allclose(hand.motor_angles(2.0 * x - 0.5 * y),
                       2.0 * hand.motor_angles(x) - 0.5 * hand.motor_angles(y), atol=1e-12)
    assert np.allclose(hand.motor_angles(np.stack([x, y])),
                       np.stack([hand.motor_angles(x), hand.motor_angles(y)]))


def test_motor_torques_satisfy_virtual_work(hand) -> None:
    """For each motor's own admissible motion dq = S dz: tau_m dq_m eff = tau . dq."""
    rng = np.random.default_rng(8)
    col = {int(j): k for k, j in enumerate(hand.independent)}
    for _ in range(5):
        q = random_q(hand, rng)
        tau = rng.normal(size=hand.n)
        tm = hand.motor_torques(q, tau)
        S = hand.dq_dindependent(q)
        for m, a in enumerate(hand.actuators):
            dz = np.zeros(len(hand.independent))
            dz[col[hand.index[a.drives]]] = 1e-4
            dq = S @ dz
            q2 = q + dq
            assert np.all(np.abs(hand.coupling_errors(q2)) < 1e-15)  # admissible
            dqm = hand.motor_angles(q2) - hand.motor_angles(q)
            others = np.delete(dqm, m)
            assert np.all(np.abs(others) < 1e-13), a.name  # only this motor turns
            lhs = tm[m] * dqm[m] * a.efficiency
            rhs = float(tau @ dq)
            assert lhs == pytest.approx(rhs, rel=1e-9), a.name


def test_joint_speed_limits_from_motor_speed(hand, toml_data) -> None:
    """Seed: 278 rad/s at a 5 mm spool; the mechanical cap (20 rad/s) binds in the default hand."""
    cap = toml_data["finger_speed"]["velocity_cap_rad_s"]
    w, spool = toml_data["tendon"]["motor_speed_rad_s"], toml_data["tendon"]["spool_radius_m"]
    assert (w, spool) == (278.0, 0.005)
    fingers = {f["name"]: f for f in toml_data["finger"]}
    for f in LONG_FINGERS:
        arm, ratio = fingers[f]["moment_arm_m"], fingers[f]["dip_ratio"]
        v_pip = min(cap, 278.0 * 0.005 / (arm["pip"] + ratio * arm["dip"]))
        assert hand.velocity[hand.index[f"{f}_pip"]] == pytest.approx(v_pip, rel=1e-12)
        assert hand.velocity[hand.index[f"{f}_dip"]] == pytest.approx(ratio * v_pip, rel=1e-12)
        assert hand.velocity[hand.index[f"{f}_mcp_flex"]] == pytest.approx(
            min(cap, 278.0 * 0.005 / arm["mcp"]), rel=1e-12)
    wcap = toml_data["wrist"]["flex"]["velocity_cap_rad_s"]
    assert toml_data["wrist"]["gear_ratio"] == 2.0
    for wj in ("wrist_flex", "wrist_dev"):
        assert hand.velocity[hand.index[wj]] == pytest.approx(min(wcap, 278.0 / 2), rel=1e-12)
    assert np.all(hand.velocity > 0)
    # at every joint's speed limit no motor exceeds its speed
    rng = np.random.default_rng(12)
    q = random_q(hand, rng)
    assert np.all(np.abs(hand.motor_velocities(q, hand.velocity)) <= hand.motor_speed * (1 + 1e-12))


# =========================================================================== seed examples
def planar_chain(lengths_m: list[float]) -> tuple[pin.Model, int]:
    """A planar serial chain: revolute joints about z, links along x, a `tip` frame at the end,
    described with the planner's own Link / Joint / HandSpec and written by ``urdf_text``."""
    links = [Link("base", 0.1, (0.0, 0.0, 0.0), (0.01, 0.01, 0.01))]
    joints = []
    parent, offset = "base", 0.0
    for i, L in enumerate(lengths_m, start=1):
        links.append(Link(f"link{i}", 0.01, (L / 2, 0.0, 0.0), (L, 0.01, 0.01)))
        joints.append(Joint(f"j{i}", "revolute", parent, f"link{i}", (offset, 0.0, 0.0),
                            axis=(0.0, 0.0, 1.0), lower=-math.pi, upper=math.pi, velocity=10.0,
                            acceleration=100.0, effort=1.0))
        parent, offset = f"link{i}", L
    links.append(Link("tip", 0.0, (0.0, 0.0, 0.0), (0.001, 0.001, 0.001)))
    joints.append(Joint("tip_fixed", "fixed", parent, "tip", (offset, 0.0, 0.0)))
    spec = HandSpec(name="seed_planar", description="seed worked example", links=tuple(links),
                    joints=tuple(joints), couplings=(), actuators=(),
                    T_world_root=tuple(tuple(float(x) for x in row) for row in np.eye(4)),
                    tip_frames=("tip",), rail_enabled=False)
    model = pin.buildModelFromXML(urdf_text(spec))
    assert model.nq == len(lengths_m)
    return model, model.getFrameId("tip")


def test_seed_fingertip_velocity_example() -> None:
    """Seed (Joseph): L = 8.7884, 4.9784, 4.2672 cm; theta = 56, -28, -10 deg (relative joint
    angles, the seed's Jacobian uses theta1 + theta2 + ...); rates 30, 10, -10 deg/s
    -> (xdot, ydot) = (-6.1369, 7.7667) cm/s.

    Pinocchio gives (-6.13702, 7.76688) cm/s: the seed's figures agree to 1.2e-4 and
    1.8e-4 cm/s (it truncated rather than rounded the last digit)."""
    model, fid = planar_chain([0.087884, 0.049784, 0.042672])
    data = model.createData()
    q = np.radians([56.0, -28.0, -10.0])
    qd = np.radians([30.0, 10.0, -10.0])
    J = pin.computeFrameJacobian(model, data, q, fid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
    v_cm = 100.0 * J[:3] @ qd
    assert v_cm[0] == pytest.approx(-6.1369, abs=1e-3)
    assert v_cm[1] == pytest.approx(7.7667, abs=1e-3)
    assert v_cm[2] == pytest.approx(0.0, abs=1e-15)
    # the same through the seed's closed-form Jacobian
    L, c = np.array([8.7884, 4.9784, 4.2672]), np.cumsum(q)
    xdot = sum(-L[k] * np.sin(c[k]) * qd[: k + 1].sum() for k in range(3))
    ydot = sum(L[k] * np.cos(c[k]) * qd[: k + 1].sum() for k in range(3))
    assert v_cm[:2] == pytest.approx([xdot, ydot], abs=1e-12)
    assert v_cm[:2] == pytest.approx([-6.137018, 7.766880], abs=1e-6)


def _fk_cm(model: pin.Model, fid: int, deg: list[float]) -> np.ndarray:
    data = model.createData()
    pin.framesForwardKinematics(model, data, np.radians(deg))
    return 100.0 * data.oMf[fid].translation


def test_seed_dh_example() -> None:
    """Seed (DH example): L1 = 5 cm, L2 = 3 cm, theta1 = 45 deg, theta2 = 30 deg, reported as
    (6.14, 5.04) cm. Its arithmetic is inconsistent: it writes 3 sin(pi/4 + pi/6) as 3 (1/2)
    and 3 cos(...) as 2.60, i.e. it uses 30 deg as the *absolute* angle of link 2, which is a
    relative joint angle theta2 = 30 - 45 = -15 deg. FK(45, -15) = (6.1336, 5.0355) cm,
    the seed's (6.14, 5.04) at its rounding (it rounds each term first: 3.54 + 2.60 = 6.14,
    3.54 + 1.50 = 5.04); theta2 = +30 deg really gives (4.3120, 6.4333) cm.
    """
    model, fid = planar_chain([0.05, 0.03])
    p = _fk_cm(model, fid, [45.0, -15.0])
    assert p[0] == pytest.approx(6.1336, abs=1e-3) and p[1] == pytest.approx(5.0355, abs=1e-3)
    # the seed rounds each term to 2 decimals before adding: x = 3.54 + 2.60, y = 3.54 + 1.50
    data = model.createData()
    pin.framesForwardKinematics(model, data, np.radians([45.0, -15.0]))
    elbow = 100.0 * data.oMi[model.getJointId("j2")].translation
    link2 = 100.0 * data.oMf[fid].translation - elbow
    assert [round(elbow[0], 2), round(link2[0], 2)] == [3.54, 2.60]
    assert [round(elbow[1], 2), round(link2[1], 2)] == [3.54, 1.50]
    assert round(round(elbow[0], 2) + round(link2[0], 2), 2) == 6.14
    assert round(round(elbow[1], 2) + round(link2[1], 2), 2) == 5.04
    assert round(p[1], 2) == 5.04 and round(p[0], 2) == 6.13  # 6.1336 itself rounds to 6.13
    q = _fk_cm(model, fid, [45.0, 30.0])
    assert q[0] == pytest.approx(4.3120, abs=1e-3) and q[1] == pytest.approx(6.4333, abs=1e-3)
    assert abs(q[0] - 6.14) > 1.8 and abs(q[1] - 5.04) > 1.3  # not the reported position


# =========================================================================== press torque
def test_press_torque_index_mcp(hand) -> None:
    """1 N upward reaction on the straight index tip (palm down, fingers along +y).

    Model: |tau_mcp| = 1 N x 152.876 mm (MCP -> tip pad, horizontal), the MCP motor torque
    = 0.152876 N m x 5 mm spool / 15 mm moment arm / 0.5 efficiency = 0.10192 N m.
    Seed: 0.144 N m, computed for a 20 mm diameter (10 mm radius) pulley with the team's
    own finger dimensions and attachment points (not given in the seed); with a 10 mm
    radius our finger would need 0.2038 N m.
    """
    q = np.zeros(hand.n)
    assert hand.within_limits(q)
    tau = hand.press_torques(q, {"index": 1.0}) - hand.press_torques(q, {})
    mcp = hand.frame_pose(q, "index_base")[:3, 3]  # the MCP flexion axis
    tip = hand.frame_pose(q, "index_tip")[:3, 3]
    d = float(np.linalg.norm((tip - mcp)[:2]))
    b, m_, t = TABLE2_UPPER_IN["index"]
    pad = 0.4 * 0.9 * 0.9375 * INCH_M  # tip pad radius: 0.4 x the distal width
    assert d == pytest.approx((b + m_ + t) * INCH_M - pad / 2, abs=1e-12)
    assert d == pytest.approx(0.15287625, abs=1e-9)
    m = hand.motor_names.index("index_mcp")
    expected = 1.0 * d / 0.015 * 0.005 / 0.5
    assert abs(tau[m]) == pytest.approx(expected, rel=1e-9)
    assert tau[m] == pytest.approx(0.1019175, abs=1e-7)  # flexor pulls against the key
    print(f"index MCP motor torque {tau[m]:.4f} N m (seed: 0.144 N m at a 10 mm pulley radius)")
    # only the index's flexors and the wrist feel the key
    loaded = {hand.motor_names[k] for k in np.flatnonzero(np.abs(tau) > 1e-12)}
    assert loaded == {"index_mcp", "index_pip", "wrist_flex"}
    assert tau[hand.motor_names.index("index_pip")] > 0


def test_palm_poses_are_palm_pose_row_by_row(hand) -> None:
    """``palm_poses`` (the joints and the palm frame alone) gives ``palm_pose``'s numbers
    bit for bit, mounted or not, and leaves the other frames of ``pin_data`` alone."""
    rng = np.random.default_rng(7)
    Q = np.array([random_q(hand, rng) for _ in range(12)])
    T = np.array([1.0, 0.0, 0.0, 0.3, 0.0, 0.0, -1.0, 0.1, 0.0, 1.0, 0.0, 0.5, 0, 0, 0, 1.0])
    for h in (hand, hand.mounted(T.reshape(4, 4))):
        want = np.array([h.palm_pose(q) for q in Q])
        tip_frame = h.pin_data.oMf[h.pin_model.getFrameId(h.tip_frames[0])].homogeneous.copy()
        got = h.palm_poses(Q)
        assert got.shape == (12, 4, 4) and np.array_equal(got, want)
        assert np.array_equal(
            h.pin_data.oMf[h.pin_model.getFrameId(h.tip_frames[0])].homogeneous, tip_frame)
