"""The hand's transmission found once (``MotorMap.fixed``): a hand whose laws
are all linear has the same ``dq_dindependent`` columns and ``motor_ratio`` at every
pose, so ``motor_torques`` and ``motor_ratio`` read them from set-up. They must give
the straightforward computation's numbers to the bit (plans stay byte-identical)."""

from __future__ import annotations

import numpy as np
import pytest

from planner.hand.mk5_tables import MK5_TABLES
from planner.hand.model import load_hand


def straight_ratio(hand, q: np.ndarray) -> np.ndarray:
    """``motor_ratio`` as it was written first: S built at ``q`` for every call."""
    from planner.hand import mk5

    S = hand.dq_dindependent(q)
    col = {int(j): k for k, j in enumerate(hand.independent)}
    r = np.empty(hand.n_motor)
    for m, a in enumerate(hand.actuators):
        if a.mk5 is not None:
            r[m] = mk5.dqmot_dq1(MK5_TABLES[a.mk5.table][a.mk5.finger], q[hand.motor_map.drive[m]])
        else:
            r[m] = float(hand.motor_map.C[m] @ S[:, col[int(hand.motor_map.drive[m])]])
    return r


def straight_torques(hand, q: np.ndarray, tau: np.ndarray) -> np.ndarray:
    S = hand.dq_dindependent(q)
    col = {int(j): k for k, j in enumerate(hand.independent)}
    ratio = straight_ratio(hand, q)
    out = np.empty(hand.n_motor)
    for m, a in enumerate(hand.actuators):
        out[m] = float(S[:, col[int(hand.motor_map.drive[m])]] @ tau) / ratio[m] / a.efficiency
    return out


@pytest.mark.parametrize("name", ["default", "mk5", "agh"])
def test_motor_torques_and_ratio_are_the_straight_computation_to_the_bit(name: str) -> None:
    hand = load_hand(name)
    rng = np.random.default_rng(7)
    lo, hi = np.clip(hand.lower, -3, 3), np.clip(hand.upper, -3, 3)
    for _ in range(300):
        q = hand.apply_couplings(rng.uniform(lo, hi))
        tau = rng.normal(size=hand.n) * 10.0 ** rng.uniform(-6, 2, size=hand.n)
        assert np.array_equal(hand.motor_ratio(q), straight_ratio(hand, q))
        assert np.array_equal(hand.motor_torques(q, tau), straight_torques(hand, q, tau))


def test_a_source_not_finite_is_computed_not_read(hand) -> None:
    """A NaN coupling source makes the straight computation's slopes NaN: the fixed
    transmission is not read there."""
    src = int(hand.couplings[0].src)
    q = hand.q_neutral.copy()
    q[src] = np.nan
    tau = np.ones(hand.n)
    assert np.array_equal(hand.motor_torques(q, tau), straight_torques(hand, q, tau),
                          equal_nan=True)
    assert np.isnan(hand.motor_torques(q, tau)).any()


def test_fixed_transmission_only_for_linear_hands(hand) -> None:
    assert hand.motor_map.fixed is not None
    assert load_hand("mk5").motor_map.fixed is None
    ratio = hand.motor_ratio(hand.q_neutral)
    ratio[:] = 0.0  # (a copy: the hand's own stays)
    assert np.all(hand.motor_ratio(hand.q_neutral) != 0.0)


def test_inertials_at_one_pose_are_each_inertial(hand) -> None:
    """``Kinematics.inertials`` (RNEA at rest found once) against ``inertial`` of each."""
    from planner.check.kinematics import Kinematics

    kin = Kinematics(hand, hand.T_world_root)
    rng = np.random.default_rng(4)
    for _ in range(20):
        q = hand.apply_couplings(rng.uniform(np.clip(hand.plan_lower, -2, 2),
                                             np.clip(hand.plan_upper, -2, 2)))
        moves = [(rng.normal(size=hand.n), rng.normal(size=hand.n)) for _ in range(3)]
        moves.append((np.zeros(hand.n), rng.normal(size=hand.n)))
        got = kin.inertials(q, moves)
        for g, (v, a) in zip(got, moves):
            assert np.array_equal(g, kin.inertial(q, v, a))
