"""planner.play.railcap.rail_acceleration_cap: the rail accelerates no harder than the
motors can hold the hand's inertia (inverse dynamics), checked against a finite
difference of the joint torques and against the motors' capacity."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from planner.hand.model import load_hand
from planner.hand.tendon import actuator_capacity
from planner.play import Planner
from planner.play.railcap import RAIL_TORQUE_SHARE, rail_acceleration_cap

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def planner():
    return Planner(load_hand("default"))


def _motor_torques_at(hand, q, a_rail):
    m = hand.pin_model
    acc = np.zeros(m.nv)
    acc[hand.pin_v_idx[hand.index["rail"]]] = a_rail
    tau = pin.rnea(m, m.createData(), hand.pin_q(q), np.zeros(m.nv), acc)[hand.pin_v_idx]
    return hand.motor_torques(q, tau)


def test_at_the_cap_the_busiest_motor_uses_its_share(planner):
    hand, q = planner.hand, planner.atlas.base
    a = rail_acceleration_cap(hand, [q])
    cap = actuator_capacity(hand).torque_nm
    use = np.abs(_motor_torques_at(hand, q, a)) / cap
    assert use.max() == pytest.approx(RAIL_TORQUE_SHARE, rel=1e-9)
    assert hand.motor_names[int(np.argmax(use))] == "wrist_dev"  # the wrist holds the hand
    # and the file's 40 m/s^2 would ask more than the motor has
    assert (np.abs(_motor_torques_at(hand, q, 40.0)) / cap).max() > 1.0


def test_the_torque_grows_linearly_with_the_acceleration(planner):
    hand, q = planner.hand, planner.atlas.base
    t0, t1, t2 = (_motor_torques_at(hand, q, a) for a in (0.0, 10.0, 20.0))
    np.testing.assert_allclose(t2 - t1, t1 - t0, atol=1e-10)


def test_the_planner_moves_the_rail_within_the_cap(planner):
    r = planner.atlas.rail
    assert planner.moves.acceleration[r] == pytest.approx(
        rail_acceleration_cap(planner.hand, [planner.atlas.base, planner.atlas.park()]))
    assert planner.moves.acceleration[r] < planner.hand.acceleration[r]
    move = planner.moves.rail_move(0.0, 0.3)
    assert move.peak_acceleration * abs(move.dq[0]) <= planner.moves.acceleration[r] + 1e-9
    assert move.jerk * abs(move.dq[0]) <= planner.moves.jerk[r] + 1e-9


def test_check_judges_the_inertia_a_play_asks_of_the_motors(planner, tmp_path):
    """``check`` on a play adds the torques that move the hand through its rows (RNEA,
    central differences) to gravity and the keys: leaps planned with the rail capped
    passes; planned with the hand file's 40 m/s^2 rail (as before the cap) the wrist
    deviation motor is over its capacity while the rail carries the hand sideways."""
    from planner.check import check_trajectory
    from planner.music.midi import load_song
    from planner.play import plan_song

    song = ROOT / "songs" / "leaps.mid"
    ok = tmp_path / "capped.csv"
    plan_song(load_song(song), planner.hand, str(ok), planner=planner)
    rep = check_trajectory(str(ok), str(song))
    torque = next(lc for lc in rep.limits if lc.category == "motor_torque")
    assert torque.count == 0 and torque.worst <= 2.0

    fast = Planner(planner.hand)
    r = fast.atlas.rail
    fast.moves.acceleration[r] = planner.hand.acceleration[r]  # 40 m/s^2: no cap
    bad = tmp_path / "uncapped.csv"
    plan_song(load_song(song), fast.hand, str(bad), planner=fast)
    rep = check_trajectory(str(bad), str(song))
    torque = next(lc for lc in rep.limits if lc.category == "motor_torque")
    assert torque.count > 0 and torque.name == "motor.wrist_dev" and torque.worst > 2.0
    assert not rep.ok
