"""Tests of the Mk5 hand (hands/mk5.toml, planner.hand.builders.mk5) and the q1 -> motor map."""

from __future__ import annotations

import math
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from planner.hand import mk5
from planner.hand.builders import load_hand_spec
from planner.hand.builders.mk5 import Q2_MARGIN_RAD
from planner.hand.mk5_tables import MK5_TABLES
from planner.hand.model import load_hand
from planner.hand.spec import FINGERS, PALM_FRAME, TIP_FRAMES, Mk5Coupling

ROOT = Path(__file__).resolve().parents[1]
TABLE = MK5_TABLES["mk5.1"]


@pytest.fixture(scope="module")
def hand():
    return load_hand("mk5")


def random_q(hand, rng: np.random.Generator) -> np.ndarray:
    lo = np.where(np.isfinite(hand.lower), hand.lower, -1.0)
    hi = np.where(np.isfinite(hand.upper), hand.upper, 1.0)
    return hand.apply_couplings(rng.uniform(lo, hi))


# --------------------------------------------------------------------------- q1 -> motor
@pytest.mark.parametrize("finger", FINGERS)
def test_qmot_of_q1_is_the_documented_linear_stand_in(finger: str) -> None:
    p = TABLE[finger]
    q1 = np.linspace(0.0, p.q1_max, 11)
    expected = (p.r / p.r_mot) * q1 * p.q0_max / p.q1_max
    assert np.allclose(mk5.qmot_of_q1(p, q1), expected, rtol=0, atol=1e-15)
    # end points of the table: open -> q0 = 0, closed -> q0 = q0_max
    assert mk5.qmot_of_q1(p, 0.0) == 0.0
    assert mk5.q0_of_qmot(p, mk5.qmot_of_q1(p, p.q1_max)) == pytest.approx(p.q0_max, abs=1e-15)
    assert np.allclose(mk5.dqmot_dq1(p, q1), (p.r / p.r_mot) * p.q0_max / p.q1_max)
    assert isinstance(mk5.dqmot_dq1(p, 0.3), float)


def test_qmot_of_q1_needs_r_mot() -> None:
    p = MK5_TABLES["mk5.0"]["index"]
    with pytest.raises(ValueError, match="r_mot"):
        mk5.qmot_of_q1(p, 0.1)
    with pytest.raises(ValueError, match="r_mot"):
        mk5.dqmot_dq1(p, 0.1)


def test_qmot_of_q1_inverts_the_exact_law_when_c_is_known() -> None:
    """Mk5.0 thumb: the only finger with a crank pivot C (r_mot borrowed from Mk5.1)."""
    p = replace(mk5.with_c_point(MK5_TABLES["mk5.0"]["thumb"]), r_mot=0.005)
    q1 = np.linspace(0.0, p.q1_max, 13)
    qm = np.asarray(mk5.qmot_of_q1(p, q1))
    assert np.allclose(mk5.q1_of_q0(p, mk5.q0_of_qmot(p, qm)), q1, atol=1e-12)
    assert mk5.qmot_of_q1(p, p.q1_max) == pytest.approx(mk5.qmot_of_q0(p, p.q0_max), abs=1e-12)
    h = 1e-6
    mid = q1[1:-1]
    fd = (np.asarray(mk5.qmot_of_q1(p, mid + h)) - np.asarray(mk5.qmot_of_q1(p, mid - h))) / (2 * h)
    assert np.allclose(mk5.dqmot_dq1(p, mid), fd, rtol=1e-6, atol=1e-8)
    with pytest.raises(ValueError, match="stroke"):
        mk5.qmot_of_q1(p, p.q1_max + 0.1)


# --------------------------------------------------------------------------- the hand
def test_mk5_hand_structure(hand) -> None:
    spec = hand.spec
    assert spec.name == "mk5"
    assert spec.tip_frames == TIP_FRAMES
    assert len(spec.couplings) == 5 and all(isinstance(c, Mk5Coupling) for c in spec.couplings)
    for f in FINGERS:
        p = TABLE[f]
        assert spec.joints_of(f) == (f"{f}_q1", f"{f}_q2")
        j1, j2 = spec.joint(f"{f}_q1"), spec.joint(f"{f}_q2")
        assert (j1.lower, j1.upper) == (0.0, p.q1_max)
        assert j1.axis == j2.axis == (-1.0, 0.0, 0.0)
        assert j2.xyz_m == pytest.approx((0.0, p.d_geom, 0.0))  # true size, scale 1.0
        q1 = np.linspace(0.0, p.q1_max, 2001)
        rel = np.asarray(mk5.q2_of_q1(p, q1)) - q1
        assert j2.lower == pytest.approx(rel.min() - Q2_MARGIN_RAD, abs=1e-6)
        assert j2.upper == pytest.approx(rel.max() + Q2_MARGIN_RAD, abs=1e-6)
        assert j2.lower < rel.min() and rel.max() < j2.upper
        a = next(a for a in spec.actuators if a.name == f)
        assert a.kind == "tendon" and a.drives == f"{f}_q1" and a.mk5 is not None
        assert a.radius_m == p.r_mot and a.efficiency == 0.5
        # the q1 speed limit is within what the motor allows and the mechanical cap
        assert j1.velocity <= min(20.0, a.speed_rad_s / abs(float(mk5.dqmot_dq1(p, 0.0)))) + 1e-12
    assert set(hand.joint_names) >= {"rail", "wrist_flex", "wrist_dev"}
    assert hand.n == 3 + 10 and len(hand.independent) == 8


def test_mk5_urdf_loads_in_pinocchio_and_placo(hand, tmp_path: Path) -> None:
    import placo

    model = pin.buildModelFromXML(hand.urdf)
    for frame in (*TIP_FRAMES, PALM_FRAME):
        assert model.existFrame(frame), frame
    assert sum(1 for f in model.frames if f.name.endswith("_tip")) == 5
    path = tmp_path / "mk5.urdf"
    path.write_text(hand.urdf, encoding="utf-8")
    robot = placo.RobotWrapper(str(path), placo.Flags.ignore_collisions)
    names = set(robot.joint_names())
    assert {f"{f}_q{i}" for f in FINGERS for i in (1, 2)} <= names


def test_fingers_flex_towards_the_palm(hand) -> None:
    q = hand.q_neutral.copy()
    open_tips = hand.tip_positions(q)
    for f in FINGERS:
        q[hand.index[f"{f}_q1"]] = 0.5
    q = hand.apply_couplings(q)
    closed = hand.tip_positions(q)
    # mount has no rotation: world -z is the palm side
    assert np.all(closed[:, 2] < open_tips[:, 2] - 1e-3)


def test_apply_couplings_and_errors(hand) -> None:
    rng = np.random.default_rng(5)
    for _ in range(10):
        raw = rng.uniform(hand.lower, hand.upper)
        q = hand.apply_couplings(raw)
        for f in FINGERS:
            p = TABLE[f]
            q1 = q[hand.index[f"{f}_q1"]]
            assert q1 == raw[hand.index[f"{f}_q1"]]
            assert q[hand.index[f"{f}_q2"]] == pytest.approx(float(mk5.q2_of_q1(p, q1)) - q1, abs=1e-15)
        assert np.all(np.abs(hand.coupling_errors(q)) < 1e-14)
        assert hand.within_limits(q)
    assert np.abs(hand.coupling_errors(hand.apply_couplings(raw[None, :]))).max() < 1e-14


def test_motor_angles_match_the_documented_map(hand) -> None:
    rng = np.random.default_rng(7)
    q = random_q(hand, rng)
    qm = hand.motor_angles(q)
    for f in FINGERS:
        p = TABLE[f]
        q1 = q[hand.index[f"{f}_q1"]]
        m = hand.motor_names.index(f)
        assert qm[m] == pytest.approx(p.r / p.r_mot * q1 * p.q0_max / p.q1_max, abs=1e-15)
    # batch form
    Q = np.stack([random_q(hand, rng) for _ in range(4)])
    assert np.allclose(hand.motor_angles(Q), np.stack([hand.motor_angles(x) for x in Q]))


def test_motor_torques_satisfy_virtual_work(hand) -> None:
    rng = np.random.default_rng(11)
    for _ in range(5):
        q = random_q(hand, rng)
        tau = rng.normal(size=hand.n)
        tm = hand.motor_torques(q, tau)
        S = hand.dq_dindependent(q)
        eps = 1e-7
        for k, j in enumerate(hand.independent):
            dq = S[:, k] * eps  # a small motion consistent with the couplings
            # the same motion by finite differences of the coupling laws
            qp = hand.apply_couplings(q + np.eye(hand.n)[j] * eps)
            qn = hand.apply_couplings(q - np.eye(hand.n)[j] * eps)
            assert np.allclose((qp - qn) / 2, dq, rtol=1e-5, atol=1e-14)
            dqm = (hand.motor_angles(qp) - hand.motor_angles(qn)) / 2
            m = int(np.flatnonzero(np.abs(dqm) > 0)[0])
            assert np.count_nonzero(np.abs(dqm) > 1e-20) == 1
            lhs = float(tau @ dq) / hand.actuators[m].efficiency
            rhs = tm[m] * dqm[m]
            assert rhs == pytest.approx(lhs, rel=1e-6)


def test_motor_torque_to_joint_torque_magnitude(hand) -> None:
    """A fingertip-size torque on q1 alone gives motor torque tau / (ratio x efficiency)."""
    q = hand.q_neutral.copy()
    tau = np.zeros(hand.n)
    i = hand.index["index_q1"]
    tau[i] = 0.1
    p = TABLE["index"]
    ratio = p.r / p.r_mot * p.q0_max / p.q1_max
    m = hand.motor_names.index("index")
    assert hand.motor_torques(q, tau)[m] == pytest.approx(0.1 / ratio / 0.5, rel=1e-12)


# --------------------------------------------------------------------------- CLI
def run_cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "cli.py", *args], cwd=ROOT, capture_output=True,
                          text=True, timeout=120, check=False)


def test_cli_hand_mk5_summary_and_urdf(tmp_path: Path) -> None:
    r = run_cli("hand", "--hand", "mk5")
    assert r.returncode == 0, r.stderr
    assert "hand mk5" in r.stdout and "index_q2 = q2(index_q1) - index_q1" in r.stdout
    out = tmp_path / "mk5.urdf"
    r = run_cli("hand", "--hand", "mk5", "--urdf", str(out))
    assert r.returncode == 0, r.stderr
    assert out.read_text(encoding="utf-8") == load_hand("mk5").urdf
    r = run_cli("hand", "--list")
    assert r.returncode == 0 and "mk5" in r.stdout


def test_default_hand_still_loads() -> None:
    h = load_hand("default")
    assert h.name == "default" and not any(a.mk5 for a in h.actuators)
    assert load_hand_spec("default").joints_of("index") == (
        "index_mcp_abd", "index_mcp_flex", "index_pip", "index_dip")
    assert math.isfinite(float(h.motor_angles(h.q_neutral).sum()))
