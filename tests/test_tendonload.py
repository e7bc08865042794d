"""The tendon bound's terms (planner.play.tendonload.TendonLoad.terms): the path's
tangent and curvature found for every sample at once are each sample's own, central
differences of the couplings sample by sample, and the terms are those of a motor matrix
and the dynamics at each sample, on moves of the default hand's atlas and of the Mk5
(its couplings not linear)."""

from __future__ import annotations

import numpy as np
import pytest

from planner.check.limits import KEY_FORCE_N
from planner.check.motormap import motor_torque_matrix
from planner.hand.model import load_hand
from planner.play.atlas import Atlas
from planner.play.tendonload import TendonLoad


def _terms_sample_by_sample(tl: TendonLoad, q_a, dq, pressing=()):
    """``terms`` written out sample by sample (the keys of fingers ``pressing`` pushing
    back everywhere): each sample's couplings and differences, its own motor matrix."""
    hand, kin, m = tl.hand, tl.kin, tl.motors
    step = tl.params()["tendon_step"]
    n = len(tl.samples)
    static, K, C = np.empty((n, 2, len(m))), np.empty((n, len(m))), np.empty((n, len(m)))
    Q = hand.apply_couplings(q_a[None, :] + tl.samples[:, None] * dq[None, :])
    for i, s in enumerate(tl.samples.tolist()):
        q0, q1 = (hand.apply_couplings(q_a + x * dq) for x in (s - step, s + step))
        q = Q[i]
        q_s = (q1 - q0) / (2.0 * step)
        q_ss = (q1 - 2.0 * q + q0) / (step * step)
        M = motor_torque_matrix(hand, q)[m]
        g = kin.gravity(q)
        pushed = g.copy()
        for J in kin.point_jacobians(q, [kin.tip_ids[f] for f in pressing]):
            pushed -= J.T @ np.array([0.0, 0.0, KEY_FORCE_N])
        static[i, 0], static[i, 1] = M @ g, M @ pushed
        tau_k, tau_c = kin.inertials(q, ((np.zeros(hand.n), q_s), (q_s, q_ss)))
        K[i], C[i] = M @ tau_k, M @ tau_c
    return static, K, C


@pytest.mark.parametrize("hand_name", ["default", "mk5"])
def test_the_terms_are_each_samples_own(hand_name):
    """Twelve moves of each hand (across at crossing height, and down from it onto the
    key with the finger's key pushing back): ``terms`` equal to the bit the terms found
    sample by sample."""
    hand = load_hand(hand_name)
    tl = TendonLoad(hand)
    assert tl.linear is (hand_name == "default")
    atlas = Atlas(hand)
    rng = np.random.default_rng(3)
    fingers = list(hand.fingers)
    done = 0
    for _ in range(200):
        f = fingers[rng.integers(len(fingers))]
        pc_a, pc_b = rng.integers(12, size=2)
        a, b = atlas.entry_at(f, int(pc_a), 0), atlas.entry_at(f, int(pc_b), 0)
        if a is None or b is None:
            continue
        js = hand.joint_slice(f)
        q_a, dq = atlas.base.copy(), np.zeros(hand.n)
        q_a[js], dq[js] = a.high, b.high - a.high
        got, want = tl.terms(q_a, dq), _terms_sample_by_sample(tl, q_a, dq)
        for x, y in zip(got, want):
            np.testing.assert_array_equal(x, y)
        q_a[js], dq[js] = b.high, b.press - b.high
        fi = fingers.index(f)
        got, want = tl.terms(q_a, dq, (fi,)), _terms_sample_by_sample(tl, q_a, dq, (fi,))
        for x, y in zip(got, want):
            np.testing.assert_array_equal(x, y)
        done += 1
        if done == 6:
            break
    assert done == 6
