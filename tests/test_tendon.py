"""Tendon statics (planner.hand.tendon): seed 004's joint moments over moment arms
through the couplings, the 50 % tendon efficiency, the 40 N design force as a bound
beside each motor's peak torque, and what check reports of it."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from planner.check import check_trajectory
from planner.errors import InputError
from planner.hand.builders import load_hand_spec
from planner.hand.model import HandModel
from planner.hand.spec import hands_dir
from planner.hand.tendon import (
    GEAR,
    MOTOR_TORQUE,
    TENDON_FORCE,
    actuator_capacity,
    spool_tensions_n,
    tendon_motors,
    tendon_tensions,
)

ROOT = Path(__file__).resolve().parents[1]


def _tau(hand: HandModel, **joint_torques_nm: float) -> np.ndarray:
    tau = np.zeros(hand.n)
    for name, v in joint_torques_nm.items():
        tau[hand.index[name]] = v
    return tau


def test_index_finger_by_hand(hand) -> None:
    """Seed 004: M = L T cos(delta); the hand file's moment arm is the perpendicular
    L cos(delta), so T = M / a at the joints, and T / 0.5 at the spool (seed 000: 50 %
    lost in the tendons). Index finger of default.toml: arms MCP 15 mm, PIP 11 mm,
    DIP 7.5 mm, DIP = 0.667 PIP.

    MCP tendon, 0.3 N m at the MCP:
        T_joint = 0.3 / 0.015 = 20 N;  T_spool = 20 / 0.5 = 40 N (the design force).
    PIP tendon (crosses PIP and DIP; the linkage makes dDIP = 0.667 dPIP), 0.1 N m at
    the PIP and 0.05 N m at the DIP; virtual work over the coupled motion:
        T_joint (0.011 + 0.667 x 0.0075) = 0.1 + 0.667 x 0.05
        T_joint = 0.13335 / 0.0160025 = 8.33307 N;  T_spool = 16.66615 N.
    """
    tau = _tau(hand, index_mcp_flex=0.3, index_pip=0.1, index_dip=0.05)
    tt = tendon_tensions(hand, hand.q_neutral, tau)
    got = dict(zip(tt.names, tt.tension_n))
    end = dict(zip(tt.names, tt.joint_end_n))
    assert got["index_mcp"] == pytest.approx(40.0, rel=1e-12)
    assert end["index_mcp"] == pytest.approx(20.0, rel=1e-12)
    assert got["index_pip"] == pytest.approx(16.66615, abs=1e-5)
    assert end["index_pip"] == pytest.approx(8.333073, abs=1e-6)
    assert all(v == 0.0 for k, v in got.items() if not k.startswith("index"))
    assert list(tt.design_force_n) == [40.0] * len(tt.names)
    assert tt.worst() == ("index_mcp", pytest.approx(40.0)) and tt.ok
    # an extending torque loads the antagonist: the same magnitude, the other sign
    neg = tendon_tensions(hand, hand.q_neutral, -tau)
    assert np.allclose(neg.tension_n, -tt.tension_n)
    over = tendon_tensions(hand, hand.q_neutral, 1.01 * tau)
    assert not over.ok and over.load.max() == pytest.approx(1.01)


def test_thumb_and_each_tendon_alone(hand) -> None:
    """Every tendon of the default hand: a unit torque on one joint it alone crosses
    gives 1 / (arm x efficiency) at its spool (thumb IP: 1 / (0.009 x 0.5) = 222.2 N)."""
    tt = tendon_tensions(hand, hand.q_neutral, _tau(hand, thumb_ip=1.0))
    assert dict(zip(tt.names, tt.tension_n))["thumb_ip"] == pytest.approx(1 / 0.0045)
    names = {hand.motor_names[m] for m in tendon_motors(hand)}
    assert names == {"thumb_cmc_flex", "thumb_ip"} | {
        f"{f}_{j}" for f in ("index", "middle", "ring", "pinky") for j in ("mcp", "pip")}


def test_mk5_tension_by_virtual_work(mk5) -> None:
    """The Mk5's nonlinear chain, independently by finite differences: the cable's
    excursion is l = r_mot q_mot(q1); the joints move as q(q1) (couplings applied);
    T_joint dl/dq1 = tau . dq/dq1, and the spool pulls T_joint / efficiency."""
    f = "index"
    i1 = mk5.index[f"{f}_q1"]
    m = mk5.motor_names.index(f)
    a = mk5.actuators[m]
    tau = _tau(mk5, index_q1=0.05, index_q2=0.02)
    h = 1e-6
    for q1 in (0.2, 0.8, 1.3):
        def q_of(x):
            q = mk5.q_neutral.copy()
            q[i1] = x
            return mk5.apply_couplings(q)
        dq = (q_of(q1 + h) - q_of(q1 - h)) / (2 * h)
        dl = a.radius_m * (mk5.motor_angles(q_of(q1 + h))[m]
                           - mk5.motor_angles(q_of(q1 - h))[m]) / (2 * h)
        t_joint = float(tau @ dq) / dl
        tt = tendon_tensions(mk5, q_of(q1), tau)
        k = tt.names.index(f)
        assert tt.joint_end_n[k] == pytest.approx(t_joint, rel=1e-6)
        assert tt.tension_n[k] == pytest.approx(t_joint / a.efficiency, rel=1e-6)


def test_capacity_names_the_limiting_part(hand, mk5) -> None:
    """40 N x 5 mm spool = 0.2 N m < the 0.4 N m peak: the tendon, not the motor,
    limits every tendon motor of both hands; servos and the rail are limited by their
    motor's torque, the wrist by its geared motor."""
    cap = actuator_capacity(hand)
    for m, a in enumerate(hand.actuators):
        if a.kind == "tendon":
            assert cap.torque_nm[m] == pytest.approx(0.2) and cap.limiting(m) == TENDON_FORCE
        else:
            assert cap.torque_nm[m] == a.peak_torque_nm and np.isinf(cap.tendon_torque_nm[m])
            assert cap.limiting(m) == (GEAR if a.kind == "gear" else MOTOR_TORQUE)
    assert cap.part(hand.motor_names.index("index_mcp")) == "tendon force (motor.index_mcp)"
    cm = actuator_capacity(mk5)
    assert np.allclose(cm.torque_nm[tendon_motors(mk5)], 40.0 * 0.005)
    # the spool tension of a motor torque: tau / r
    tm = np.zeros(hand.n_motor)
    tm[hand.motor_names.index("ring_pip")] = 0.1
    assert spool_tensions_n(hand, tm).max() == pytest.approx(20.0)


def test_higher_design_force_leaves_the_motor_limiting(tmp_path) -> None:
    text = (hands_dir() / "default.toml").read_text(encoding="utf-8")
    path = tmp_path / "strong.toml"
    path.write_text(text.replace("design_force_n = 40.0", "design_force_n = 100.0"),
                    encoding="utf-8")
    h = HandModel(load_hand_spec(str(path)))
    cap = actuator_capacity(h)
    m = h.motor_names.index("middle_mcp")
    assert cap.torque_nm[m] == 0.4 and cap.limiting(m) == MOTOR_TORQUE


@pytest.mark.parametrize("edit, needle", [
    (("design_force_n = 40.0\n", ""), "missing key 'design_force_n'"),
    (("design_force_n = 40.0", "design_force_n = -1.0"), "'tendon.design_force_n' = -1.0 is outside"),
    (("design_force_n = 40.0", 'design_force_n = "strong"'), "must be a finite number"),
])
def test_bad_design_force(tmp_path, edit, needle) -> None:
    text = (hands_dir() / "default.toml").read_text(encoding="utf-8")
    assert edit[0] in text
    path = tmp_path / "bad.toml"
    path.write_text(text.replace(*edit), encoding="utf-8")
    with pytest.raises(InputError, match=needle):
        load_hand_spec(str(path))
    r = subprocess.run([sys.executable, "cli.py", "hand", "--hand", str(path)], cwd=ROOT,
                       capture_output=True, text=True, check=False)
    assert r.returncode == 2 and r.stdout == ""
    assert len(r.stderr.splitlines()) == 1 and needle in r.stderr


def _plan(tmp_path) -> Path:
    out = tmp_path / "twinkle.csv"
    r = subprocess.run([sys.executable, "cli.py", "play", "songs/twinkle.mid", "-o", str(out)],
                       cwd=ROOT, capture_output=True, text=True, check=False)
    assert r.returncode == 0, r.stderr
    return out


def test_check_reports_every_tendon(tmp_path, hand) -> None:
    traj = _plan(tmp_path)
    r = check_trajectory(str(traj))
    assert r.ok
    assert [t.name for t in r.tendons] == [f"motor.{hand.motor_names[m]}"
                                           for m in tendon_motors(hand)]
    lc = next(lc for lc in r.limits if lc.category == "tendon_tension")
    worst = max(r.tendons, key=lambda t: t.worst_n)
    assert lc.ok and (lc.name, lc.worst, lc.limit) == (worst.name, worst.worst_n, 40.0)
    assert all(t.ok and 0 < t.worst_n < 40.0 and t.limit_n == 40.0 for t in r.tendons)
    d = r.to_dict()
    assert [x["name"] for x in d["tendons"]] == [t.name for t in r.tendons]
    assert set(d["tendons"][0]) == {"name", "count", "worst_n", "limit_n", "time_s", "ok"}
    s = r.summary()
    assert "tendons (count, worst tension at the spool / design force, when):" in s
    assert "  tendon_tension     ok  " in s
    # the same plan checked against a cable of a tenth of the force: the tendons fail
    text = (hands_dir() / "default.toml").read_text(encoding="utf-8")
    weak = tmp_path / "weak.toml"
    weak.write_text(text.replace("design_force_n = 40.0", "design_force_n = 4.0"),
                    encoding="utf-8")
    r2 = check_trajectory(str(traj), hand_override=str(weak))
    bad = [t for t in r2.tendons if not t.ok]
    assert not r2.ok and bad and all(t.worst_n > 4.0 * 1.01 for t in bad)
    assert {t.name for t in bad} == {t.name for t in r.tendons if t.worst_n > 4.04}
    assert any("tendon tension violations" in p for p in r2.problems)
