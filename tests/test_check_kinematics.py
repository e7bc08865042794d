"""The check's kinematics (planner/check/kinematics.py) row by row and by the block: the
block functions (``gravities``, ``moving``) and the torques built on them
(``planner.check.limits``) give the plain per-row computation's numbers to the bit."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from planner.check.kinematics import Kinematics
from planner.check.limits import KEY_FORCE_N, row_motor_torques
from planner.hand.model import load_hand
from planner.play.armload import rows_load

HANDS = ("default", "default-left", "mk5", "agh")


def _poses(hand, n: int, seed: int) -> np.ndarray:
    """``n`` poses spread over the joints' ranges (a finite stand-in where a bound is not),
    every third one rounded as a file's rows are, some rows repeated (a hand still)."""
    rng = np.random.default_rng(seed)
    lo = np.where(np.isfinite(hand.lower), hand.lower, -1.0)
    hi = np.where(np.isfinite(hand.upper), hand.upper, 1.0)
    Q = lo + rng.random((n, hand.n)) * (hi - lo)
    Q[::3] = np.round(Q[::3], 6)
    if n > 9:
        Q[5:9] = Q[4]
    return Q


@pytest.mark.parametrize("name", HANDS)
def test_rnea_at_rest_is_the_generalized_gravity_to_the_bit(name):
    """What ``Kinematics.moving`` rests on: RNEA(q, 0, 0) equals
    ``computeGeneralizedGravity(q)`` (no free-flyer: q and v of one size), 3,000 poses."""
    hand = load_hand(name)
    kin = Kinematics(hand, hand.T_world_root)
    m, d, z = kin.model, kin.data, np.zeros(kin.model.nv)
    for q in _poses(hand, 3000, 1):
        qp = kin.pin_q(q)
        assert np.array_equal(pin.rnea(m, d, qp, z, z), pin.computeGeneralizedGravity(m, d, qp))


@pytest.mark.parametrize("name", HANDS)
def test_block_gravity_and_motion_are_each_rows_own(name):
    hand = load_hand(name)
    kin = Kinematics(hand, hand.T_world_root)
    rng = np.random.default_rng(2)
    Q = _poses(hand, 300, 3)
    V, A = rng.standard_normal((2, len(Q), hand.n))
    V[10:20] = 0.0  # (rows where nothing moves: only accelerating)
    G = kin.gravities(Q)
    assert np.array_equal(G, np.array([kin.gravity(q) for q in Q]))
    got = kin.moving(Q, V, A, G)
    want = np.array([kin.inertial(q, v, a) for q, v, a in zip(Q, V, A)])
    assert np.array_equal(got, want)
    assert np.array_equal(kin.moving(Q, V, A, G + 1e-12), want) is False


def _plain_motor_torques(hand, kin, t, Q, pressing, motor_map):
    """``row_motor_torques`` as it read before the block functions (the reference): each
    row's gravity, the keys' push, and RNEA(q, v, a) - RNEA(q, 0, 0) of the moving rows."""
    tau = np.array([kin.gravity(q) for q in Q])
    for k in np.flatnonzero(pressing.any(axis=1)):
        for J in kin.point_jacobians(Q[k], [kin.tip_ids[f] for f in np.flatnonzero(pressing[k])]):
            tau[k] -= J.T @ np.array([0.0, 0.0, KEY_FORCE_N])
    dt0, dt1 = np.diff(t)[:-1, None], np.diff(t)[1:, None]
    V = (Q[2:] - Q[:-2]) / (dt0 + dt1)
    A = 2.0 * ((Q[2:] - Q[1:-1]) / dt1 - (Q[1:-1] - Q[:-2]) / dt0) / (dt0 + dt1)
    for k in np.flatnonzero(np.any(V != 0.0, axis=1) | np.any(A != 0.0, axis=1)):
        tau[k + 1] += kin.inertial(Q[k + 1], V[k], A[k])
    return np.einsum("tj,mj->tm", tau[1:-1], motor_map)


def test_row_motor_torques_are_the_plain_computation_to_the_bit():
    """A smooth stretch of rows (held rows among them, some fingertips pressing)."""
    hand = load_hand("default")
    load = rows_load(hand)
    rng = np.random.default_rng(4)
    t = np.arange(120) * 0.01
    q0 = _poses(hand, 1, 5)[0]
    Q = q0 + np.outer(np.sin(t * 3.0), 0.05 * rng.standard_normal(hand.n))
    Q[40:60] = Q[40]
    pressing = rng.random((len(t), 5)) < 0.3
    got = row_motor_torques(hand, load.kin, t, Q, pressing, load.motor_map)
    want = _plain_motor_torques(hand, load.kin, t, Q, pressing, load.motor_map)
    assert np.array_equal(got, want)


@pytest.mark.parametrize("name", HANDS)
def test_point_jacobians_are_those_of_every_frame_placed(name):
    """``point_jacobians`` without placing every frame first: the Jacobians of the frames
    asked for are those read after ``updateFramePlacements`` (the reference), to the bit."""
    hand = load_hand(name)
    kin = Kinematics(hand, hand.T_world_root)
    m, d = kin.model, kin.data
    frames = kin.tip_ids + [kin.palm_id]
    for q in _poses(hand, 200, 6):
        pin.computeJointJacobians(m, d, kin.pin_q(q))
        pin.updateFramePlacements(m, d)
        want = [kin.R @ pin.getFrameJacobian(m, d, f, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
                                             )[:3, kin.idx] for f in frames]
        pin.forwardKinematics(m, d, kin.pin_q(np.zeros(hand.n)))  # (other placements held)
        got = kin.point_jacobians(q, frames)
        assert all(np.array_equal(g, w) for g, w in zip(got, want))


@pytest.mark.parametrize("name", HANDS)
def test_tips_alone_are_the_frames_tips(name):
    hand = load_hand(name)
    kin = Kinematics(hand, hand.T_world_root)
    Q = _poses(hand, 200, 7)
    tips, _ = kin.frames(Q)
    assert np.array_equal(kin.tips(Q), tips)
    new = np.ones(len(Q), dtype=bool)
    new[1:] = np.any(Q[1:] != Q[:-1], axis=1)
    assert np.array_equal(kin.tips_of(Q[new]), kin.frames_of(Q[new])[0])


@pytest.mark.parametrize("name", HANDS)
def test_inertials_given_the_gravity_are_each_inertial(name):
    hand = load_hand(name)
    kin = Kinematics(hand, hand.T_world_root)
    rng = np.random.default_rng(8)
    for q in _poses(hand, 100, 9):
        moves = [tuple(rng.standard_normal((2, hand.n))) for _ in range(2)]
        want = [kin.inertial(q, v, a) for v, a in moves]
        for got in (kin.inertials(q, moves), kin.inertials(q, moves, kin.gravity(q))):
            assert all(np.array_equal(g, w) for g, w in zip(got, want))


def _plain_tips_pushed(kin, Q, pressing, force, tau):
    """``tips_pushed`` as it read before its products were stacked (the reference): per
    pressing row its Jacobians, per tip ``R @ J`` and ``tau[k] -= J.T @ force``."""
    m, d, idx = kin.model, kin.data, kin.idx
    world = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    for k in np.flatnonzero(pressing.any(axis=1)):
        pin.computeJointJacobians(m, d, kin.pin_q(Q[k]))
        for f in np.flatnonzero(pressing[k]):
            J = kin.R @ pin.getFrameJacobian(m, d, kin.tip_ids[f], world)[:3, idx]
            tau[k] -= J.T @ force


@pytest.mark.parametrize("name", HANDS)
def test_tips_pushed_stacked_is_each_rows_own_to_the_bit(name):
    """The keys' push of every pressing tip, the products stacked: each row's torques the
    per-row computation's to the bit (zeros' signs too: the bytes), up to five tips a row
    subtracted in order, rows pressing nothing untouched, no tip pressing anywhere."""
    hand = load_hand(name)
    kin = Kinematics(hand, hand.T_world_root)
    rng = np.random.default_rng(10)
    Q = _poses(hand, 400, 11)
    pressing = rng.random((len(Q), len(kin.tip_ids))) < 0.4
    pressing[:7] = True
    force = np.array([0.0, 0.0, KEY_FORCE_N])
    for P in (pressing, np.zeros_like(pressing)):
        tau0 = rng.standard_normal((len(Q), hand.n))
        got, want = tau0.copy(), tau0.copy()
        kin.tips_pushed(Q, P, force, got)
        _plain_tips_pushed(kin, Q, P, force, want)
        assert got.tobytes() == want.tobytes()
