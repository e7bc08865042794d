"""The hand's strength (planner.hand.strength, planner.hand.grip, ``hand --strength``):
each number against an independent computation (finite differences of the forward
kinematics and of the motor map instead of Pinocchio's Jacobian and motor_torques),
against a hand calculation where one is short, and the error paths."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from planner.hand.builders import load_hand_spec
from planner.hand.grip import CYLINDER_DIAMETER_M, flexion_joints, grip, grip_at
from planner.hand.model import HandModel, load_hand
from planner.hand.spec import INCH_M, hands_dir
from planner.hand.strength import (
    DESCENT_PART,
    FLEXED_RAD,
    close_time,
    finger_posture,
    hand_strength,
    pad_normal,
    press_strength,
    tip_force,
)
from planner.play.atlas import SPAN_M, STEP_M, Atlas

ROOT = Path(__file__).resolve().parents[1]
FINGERS = ("thumb", "index", "middle", "ring", "pinky")


def _capacity(a) -> float:
    """Independently: the motor's peak, or its cable's design force x spool radius."""
    return a.peak_torque_nm if a.tendon_force_n is None else min(a.peak_torque_nm,
                                                                 a.tendon_force_n * a.radius_m)


def _fd_tip_force(hand: HandModel, q: np.ndarray, finger: str) -> float:
    """Virtual work by finite differences: moving motor m's driven joint (couplings
    applied) by dq moves the pad by dp and the motor by dqm; to push with f along u the
    motor holds f (u . dp/dq) / (dqm/dq) / efficiency."""
    f = FINGERS.index(finger)
    u = pad_normal(hand, q, finger)
    h = 1e-6
    best = math.inf
    own = set(hand.spec.joints_of(finger))
    for m, a in enumerate(hand.actuators):
        if a.drives not in own:
            continue
        j = hand.index[a.drives]
        qp, qm = q.copy(), q.copy()
        qp[j] += h
        qm[j] -= h
        qp, qm = hand.apply_couplings(qp), hand.apply_couplings(qm)
        dp = (hand.tip_positions(qp)[f] - hand.tip_positions(qm)[f]) / (2 * h)
        dmot = (hand.motor_angles(qp)[m] - hand.motor_angles(qm)[m]) / (2 * h)
        per_n = abs(float(u @ dp) / dmot / a.efficiency)
        if per_n > 1e-9:
            best = min(best, _capacity(a) / per_n)
    return best


@pytest.mark.parametrize("name", ["default", "mk5"])
@pytest.mark.parametrize("flex", [0.0, FLEXED_RAD])
def test_tip_force_against_finite_differences(name, flex) -> None:
    h = load_hand(name)
    for f in FINGERS:
        q = finger_posture(h, f, flex)
        force, part = tip_force(h, q, f)
        assert force == pytest.approx(_fd_tip_force(h, q, f), rel=1e-5), f
        assert part.startswith("tendon force (motor.")  # 40 N x 5 mm < every motor's peak


def test_straight_index_by_hand(hand) -> None:
    """Straight index finger of default.toml, a force along the pad normal (perpendicular
    to the finger). Lever about the MCP: base + middle + top - half the pad
    = (2.8125 + 1.6875 + 1.6875) in - 0.5 x 0.4 x 0.9 x 0.9375 in = 0.1528763 m.
    MCP tendon at 40 N at the spool -> 20 N at the joint x 15 mm = 0.3 N m:
        F = 0.3 / 0.1528763 = 1.96237 N.
    The PIP tendon would allow 20 N x (0.011 + 0.667 x 0.0075) / (lever about the PIP
    0.0814388 + 0.667 x lever about the DIP 0.0385763) = 2.987 N: the MCP's limits."""
    lever = (2.8125 + 1.6875 + 1.6875) * INCH_M - 0.5 * 0.4 * 0.9 * 0.9375 * INCH_M
    assert lever == pytest.approx(0.1528763, abs=1e-7)
    force, part = tip_force(hand, finger_posture(hand, "index", 0.0), "index")
    assert force == pytest.approx(0.3 / lever, rel=1e-9)
    assert part == "tendon force (motor.index_mcp)"


def test_flexed_posture(hand, mk5) -> None:
    q = finger_posture(hand, "index", FLEXED_RAD)
    for j in ("index_mcp_flex", "index_pip"):
        assert q[hand.index[j]] == pytest.approx(FLEXED_RAD)
    assert q[hand.index["index_dip"]] == pytest.approx(0.667 * FLEXED_RAD)
    assert q[hand.index["index_mcp_abd"]] == 0.0
    assert [mk5.joint_names[j] for j in flexion_joints(mk5, "ring")] == ["ring_q1"]


def test_close_time_by_hand(hand, mk5) -> None:
    """MCP -20..90 deg = 1.919862 rad at 20 rad/s and 500 rad/s^2: v^2/a = 0.8 rad < d,
    so t = d/v + v/a = 0.0959931 + 0.04 = 0.1359931 s (the PIP's 100 deg take less)."""
    t, part = close_time(hand, "index")
    assert t == pytest.approx(math.radians(110) / 20 + 20 / 500, rel=1e-9)
    assert part.startswith("index_mcp_flex at its 20 rad/s cap")
    for f in FINGERS:  # every mk5 finger: q1 over [0, q1_max]
        j = mk5.index[f"{f}_q1"]
        d, v, a = mk5.upper[j], mk5.velocity[j], mk5.acceleration[j]
        want = d / v + v / a if d >= v * v / a else 2 * math.sqrt(d / a)
        assert close_time(mk5, f)[0] == pytest.approx(want, rel=1e-12)
        # 90 deg at 80 rad/s^2 never reaches the 20 rad/s cap: the acceleration is named
        assert d < v * v / a and close_time(mk5, f)[1] == f"{f}_q1 at its 80 rad/s^2 " \
            "(it never reaches its 20 rad/s)"


def test_press_is_the_weakest_atlas_pose(hand) -> None:
    press = press_strength(hand)
    atlas = Atlas(hand)
    n = round(SPAN_M / STEP_M)
    # (the default hand's thumb has no press pose clear of the keys as a body: none)
    assert press["thumb"] == (None, "no press pose: the finger reaches no key from the mount",
                              None)
    atlases = [atlas] + [Atlas(hand, posture=i) for i in (1, 2)]  # (every play posture's)
    for f in FINGERS[1:]:
        entries = [(a, e) for a in atlases for pc in range(12) for k in range(-n, n + 1)
                   if (e := a.entry_at(f, pc, k)) is not None]
        atlas, weakest = min(entries, key=lambda ae: ae[1].max_force_n)
        force, part, need = press[f]
        assert force == weakest.max_force_n and part.startswith("tendon force")
        # at that pose 1 % more overloads some motor, 1 % less none (independent capacity)
        q = atlas.full_q(weakest, "press", 0.0)
        cap = np.array([_capacity(a) for a in hand.actuators])
        load = lambda F: np.max(np.abs(hand.press_torques(q, {f: F})) / cap)  # noqa: B023
        assert load(0.99 * force) < 1.0 < load(1.01 * force)
        assert 0 < need < 0.144  # the seed's 0.144 N m: its 20 mm pulley, our 5 mm spool


def test_mk5_press_is_its_weakest_arc_pose(mk5) -> None:
    """The Mk5's fingers press on their arc (planner.play.arc): the thumb reaches no key
    from the mount; the others' press poses are refused for their descent (the motors
    cannot drive a key down its travel with the pad's friction, planner.play.force):
    their weakest press holds 0 N and names it; at its pose a 1 N key needs more motor
    torque than the seed's 0.144 N m (q1 gets 0.227 of the motor's turn)."""
    press = press_strength(mk5)
    assert press["thumb"] == (None, "no press pose: the finger reaches no key from the mount",
                              None)
    atlas = Atlas(mk5)
    n = round(SPAN_M / STEP_M)
    for f in FINGERS[1:]:
        entries = [e for pc in range(12) for k in range(-n, n + 1)
                   if (e := atlas.entry_at(f, pc, k)) is not None]
        assert entries and all(e.max_force_n == 0.0 for e in entries)
        force, part, need = press[f]
        assert force == 0.0 and part == DESCENT_PART
        assert need > 0.144


def test_grip_default(hand) -> None:
    g = grip(hand)
    assert g.diameter_m == pytest.approx(0.0635)
    assert g.fingers == ("index", "middle", "ring", "pinky")
    assert all(lim.startswith("tendon force") for lim in g.limiting)
    assert not next(c for c in g.closures if c.finger == "thumb").reached
    # the LP's forces, checked independently: balance (forces, moments about the axis
    # point), inside the true friction cones (mu 0.8), every motor within its capacity
    f, cts = g.forces_n, g.contacts
    assert np.allclose(f.sum(axis=0), 0.0, atol=1e-7)
    centre = cts[0].point + 0.5 * CYLINDER_DIAMETER_M * cts[0].normal
    assert np.allclose(sum(np.cross(c.point - centre, fc) for c, fc in zip(cts, f)), 0.0,
                       atol=1e-8)
    for c, fc in zip(cts, f):
        fn = fc @ c.normal
        assert fn >= -1e-9 and np.linalg.norm(fc - fn * c.normal) <= 0.8 * fn + 1e-7
    tau = sum(c.jacobian.T @ fc for c, fc in zip(cts, f))
    cap = np.array([_capacity(a) for a in hand.actuators])
    load = np.abs(hand.motor_torques(g.q, tau)) / cap
    assert load.max() == pytest.approx(1.0, abs=1e-6)  # the optimum is at a capacity
    assert g.force_n == pytest.approx(sum(fc @ c.normal for c, fc in zip(cts, f)
                                          if c.name.startswith("palm")))
    # the pads' Jacobians are Pinocchio's; the palm points' by finite differences
    for c in cts[:2]:
        j = hand.index["wrist_flex"]
        qp, qm = g.q.copy(), g.q.copy()
        qp[j] += 1e-6
        qm[j] -= 1e-6
        moved = [(hand.palm_pose(x) @ np.linalg.solve(hand.palm_pose(g.q),
                                                      np.append(c.point, 1.0)))[:3]
                 for x in (qp, qm)]
        assert np.allclose((moved[0] - moved[1]) / 2e-6, c.jacobian[:, j], atol=1e-6)
    assert 1.0 < g.force_kgf < 25.0  # far below the seed's 25-40 kg
    # every place tried gives no more
    for off in (0.0, 0.02, 0.04, 0.06):
        assert grip_at(hand, off).force_n <= g.force_n + 1e-6


def _with_force(tmp_path, force: float) -> HandModel:
    text = (hands_dir() / "default.toml").read_text(encoding="utf-8")
    path = tmp_path / f"f{force:g}.toml"
    path.write_text(text.replace("design_force_n = 40.0", f"design_force_n = {force}"),
                    encoding="utf-8")
    return HandModel(load_hand_spec(str(path)))


def test_grip_scales_with_the_tendon_force(tmp_path, hand) -> None:
    """Tendon-limited, the LP's optimum is linear in the design force: 20 N gives half;
    1000 N leaves the motors' 0.4 N m peak limiting, twice the 40 N grip."""
    g40 = grip_at(hand, 0.03).force_n
    assert grip_at(_with_force(tmp_path, 20.0), 0.03).force_n == pytest.approx(g40 / 2, rel=1e-5)
    strong = grip_at(_with_force(tmp_path, 1000.0), 0.03)
    assert strong.force_n == pytest.approx(2 * g40, rel=1e-5)
    assert all(lim.startswith("motor torque") for lim in strong.limiting)


def test_grip_mk5_at_its_own_scale(mk5) -> None:
    """On its true-size palm (seed 000 Table 2's 4.75 in, issue 17 item 1) the Mk5's four
    fingers close on the cylinder; the tendons' 40 N limit the grip (on the 1.5x palm they
    met only its side: 0 N)."""
    g = grip(mk5)
    assert g.force_n == pytest.approx(1.45797, rel=1e-4)
    assert g.fingers == ("index", "middle", "ring", "pinky")
    assert all(lim.startswith("tendon force") for lim in g.limiting)


def test_strength_table_and_json(hand) -> None:
    st = hand_strength(hand)
    assert [f.finger for f in st.fingers] == list(FINGERS)
    r = subprocess.run([sys.executable, "cli.py", "hand", "--strength"], cwd=ROOT,
                       capture_output=True, text=True, check=False)
    assert r.returncode == 0 and r.stderr == ""
    assert r.stdout == st.summary() + "\n"
    assert "seed 25-40 kg +-5" in r.stdout and "seed 150-300 +-50" in r.stdout
    r = subprocess.run([sys.executable, "cli.py", "hand", "--strength", "--json"], cwd=ROOT,
                       capture_output=True, text=True, check=False)
    d = json.loads(r.stdout)
    assert d["command"] == "hand" and d["name"] == "default"
    s = d["strength"]
    assert s["grip"]["force_n"] == pytest.approx(st.grip.force_n)
    assert s["grip"]["cylinder_diameter_m"] == pytest.approx(CYLINDER_DIAMETER_M)
    assert s["requirements"]["grip_kg"] == [25.0, 40.0]
    assert s["fingers"][1]["straight_force_n"] == pytest.approx(st.fingers[1].straight_force_n)
    assert set(s["fingers"][0]) == {"finger", "straight_force_n", "straight_part",
                                    "flexed_force_n", "flexed_part", "press_force_n",
                                    "press_part", "press_torque_nm", "close_time_s",
                                    "close_part"}


@pytest.mark.parametrize("args, needle", [
    (["--hand", "nope", "--strength"], "unknown hand 'nope'"),
    (["--strength", "--list"], "--strength cannot be combined with --list or --urdf"),
    (["--strength", "--urdf", "x.urdf"], "--strength cannot be combined with --list or --urdf"),
])
def test_strength_errors(tmp_path, args, needle) -> None:
    r = subprocess.run([sys.executable, str(ROOT / "cli.py"), "hand", *args], cwd=tmp_path,
                       capture_output=True, text=True, check=False)
    assert r.returncode == 2 and r.stdout == ""
    assert len(r.stderr.splitlines()) == 1 and needle in r.stderr
    assert list(tmp_path.iterdir()) == []


def test_strength_bad_hand_file(tmp_path) -> None:
    path = tmp_path / "bad.toml"
    path.write_text('name = "bad"\n', encoding="utf-8")
    r = subprocess.run([sys.executable, str(ROOT / "cli.py"), "hand", "--hand", str(path),
                        "--strength"], cwd=tmp_path, capture_output=True, text=True, check=False)
    assert r.returncode == 2 and r.stdout == "" and len(r.stderr.splitlines()) == 1
    assert "malformed hand file bad.toml" in r.stderr
