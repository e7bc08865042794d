"""The tendon bound (planner.play.tendonload): its terms (``TendonLoad.terms``: the
path's tangent and curvature found for every sample at once are each sample's own,
central differences of the couplings sample by sample, and the terms are those of a
motor matrix and the dynamics at each sample, on moves of the default hand's atlas and of
the Mk5, its couplings not linear), and its scale (``scale_for``: the three lines as one
array, the same as line by line)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planner.check.limits import KEY_FORCE_N
from planner.check.motormap import motor_torque_matrix
from planner.hand.model import load_hand
from planner.play.atlas import Atlas
from planner.play.tendonload import MAX_SCALE, TendonLoad, scale_for, speed_squared_bound


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


def _scale_line_by_line(static, K, C, speed2, peak_acceleration, capacity_nm) -> float:
    """``scale_for`` written out line by line (each line's rooms, the smallest kept)."""
    ka = np.abs(K)[:, None, :] * peak_acceleration
    cv = C[:, None, :] * speed2[:, None, None]
    cap = capacity_nm[None, None, :]
    u = 1.0
    for h0, slope in ((np.abs(static), ka), (static, ka + cv), (-static, ka - cv)):
        h0, slope = np.broadcast_arrays(h0, slope)
        grows = (slope > 0.0) & (h0 < cap)
        if np.any(grows):
            room = (np.broadcast_to(cap, h0.shape)[grows] - h0[grows]) / slope[grows]
            u = min(u, float(np.min(room)))
    return 1.0 if u >= 1.0 else min(MAX_SCALE, 1.0 / math.sqrt(u))


def test_the_scale_is_the_smallest_room_of_each_line():
    """The terms of 40 moves across of the default hand, against capacities of 1/4 to 1
    of the motors' share and peak accelerations of the path parameter of 10^3 to 3 10^7
    /s^2 (scales of 1, between, and ``MAX_SCALE``), and with a term that is not a number:
    ``scale_for`` is the scale found line by line, the same float."""
    hand = load_hand("default")
    tl = TendonLoad(hand)
    atlas = Atlas(hand)
    rng = np.random.default_rng(9)
    fingers = list(hand.fingers)
    seen = set()
    n = 0
    while n < 40:
        f = fingers[rng.integers(len(fingers))]
        a = atlas.entry_at(f, int(rng.integers(12)), int(rng.integers(-20, 21)))
        b = atlas.entry_at(f, int(rng.integers(12)), int(rng.integers(-20, 21)))
        if a is None or b is None:
            continue
        js = hand.joint_slice(f)
        q_a, dq = atlas.base.copy(), np.zeros(hand.n)
        q_a[js], dq[js] = a.high, b.high - a.high
        static, K, C = tl.terms(q_a, dq)
        for share in (0.25, 0.5, 1.0):
            for acc in (1e3, 3e6, 1e7, 3e7):
                speed2 = speed_squared_bound(tl.samples, acc, math.sqrt(acc))
                cap = share * tl.capacity_nm
                got = scale_for(static, K, C, speed2, acc, cap)
                assert got == _scale_line_by_line(static, K, C, speed2, acc, cap)
                seen.add("1" if got == 1.0 else "max" if got == MAX_SCALE else "between")
        n += 1
    assert seen == {"1", "between", "max"}
    static, K = static.copy(), K.copy()
    static[3], K[3] = -np.inf, np.inf  # (a room of inf / inf at one sample of the second
    # line: not a number, which Python's ``min`` passes by)
    speed2 = speed_squared_bound(tl.samples, 1e7, 3e3)
    with np.errstate(invalid="ignore"):
        for share in (0.25, 1.0):
            cap = share * tl.capacity_nm
            want = _scale_line_by_line(static, K, C, speed2, 1e7, cap)
            assert scale_for(static, K, C, speed2, 1e7, cap) == want
            seen.add(want)
    assert len(seen) > 3
