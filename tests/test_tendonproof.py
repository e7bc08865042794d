"""The tendon bound's sufficient test (planner.play.tendonproof): its bound of each
motor's torque is above the full computation's (``TendonLoad.terms``, the largest of
``|S| + |K| A + |C| W`` over the samples) on sampled moves across of every finger, in the
atlas's boxes and in a box around every finger's natural pose (the thumb, which plays no
key, among them); where it proves a move, the full computation's scale is 1; and a hand
with a weakened tendon is not proved where its moves need the tendon."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from planner.hand.builders import load_hand_spec
from planner.hand.model import HandModel, load_hand
from planner.play.atlas import Atlas
from planner.play.moves import Moves
from planner.play.profile import straight_move
from planner.play.tendonload import TendonLoad, scale_for, speed_squared_bound


def _full(tl: TendonLoad, move, q_a, dq) -> tuple[np.ndarray, float]:
    """The full computation's largest ``|S| + |K| A + |C| W`` of each motor over the
    move's samples, and its scale (``scale_for`` of the same terms)."""
    static, K, C = tl.terms(q_a, dq)
    A, V = move.peak_acceleration, move.peak_speed
    W = speed_squared_bound(tl.samples, A, V)
    worst = np.max(np.abs(static[:, 0, :]) + np.abs(K) * A + np.abs(C) * W[:, None], axis=0)
    return worst, scale_for(static, K, C, W, A, tl.capacity_nm)


def _move(hand: HandModel, finger: str, base: np.ndarray, qa: np.ndarray, qb: np.ndarray):
    """The finger's straight move from ``qa`` to ``qb`` (the rest at ``base``) as
    ``Moves.finger_scale`` hands it to the bound: whole-hand start and difference."""
    js = hand.joint_slice(finger)
    move = straight_move(qa, qb, hand.velocity[js], np.array(hand.acceleration)[js],
                         np.array(hand.jerk)[js])
    q_a, dq = base.copy(), np.zeros(hand.n)
    q_a[js], dq[js] = qa, qb - qa
    return move, q_a, dq


@pytest.fixture(scope="module")
def default_moves():
    hand = load_hand("default")
    atlas = Atlas(hand)
    return hand, atlas, Moves(hand, atlas)


def test_the_bound_holds_on_the_atlas_moves_across(default_moves):
    """Forty random moves across (high pose to high pose of two entries) of each finger
    the default hand plays with: every motor's bound at or above the full computation's
    largest torque, every move proved (none is an ulp long here), the full scale 1."""
    hand, atlas, moves = default_moves
    tl = moves.tendons
    rng = np.random.default_rng(11)
    by_finger: dict[str, list] = {}
    for e in atlas.solved().values():
        by_finger.setdefault(e.finger, []).append(e)
    assert sorted(by_finger) == ["index", "middle", "pinky", "ring"]
    for finger, entries in by_finger.items():
        done = 0
        while done < 40:
            a, b = (entries[i] for i in rng.integers(len(entries), size=2))
            if np.max(np.abs(b.high - a.high)) < 1e-6:
                continue
            move, q_a, dq = _move(hand, finger, atlas.base, a.high, b.high)
            bound = tl.proof.bound_nm(q_a, dq, move.peak_acceleration, move.peak_speed)
            worst, scale = _full(tl, move, q_a, dq)
            assert bound is not None
            assert np.all(worst <= bound), (finger, worst, bound)
            assert tl.proof.proves(q_a, dq, move.peak_acceleration, move.peak_speed)
            assert scale == 1.0
            assert tl.time_scale(move, q_a, dq) == 1.0
            done += 1


@pytest.mark.parametrize("finger", ["thumb", "index", "middle", "ring", "pinky"])
def test_the_bound_holds_around_every_fingers_natural_pose(finger):
    """A box of 0.3 rad each way around the finger's natural pose (within its joint
    limits), thirty random moves within it at the joints' full speed: the bound at or
    above the full computation's largest torque on every motor."""
    hand = load_hand("default")
    atlas = Atlas(hand)
    tl = TendonLoad(hand)
    js = hand.joint_slice(finger)
    centre = atlas.base[js]
    lo = np.maximum(centre - 0.3, hand.lower[js])
    hi = np.minimum(centre + 0.3, hand.upper[js])
    coupled = hand.apply_couplings(np.stack((np.r_[atlas.base[:js[0]], lo, atlas.base[js[-1] + 1:]],
                                             np.r_[atlas.base[:js[0]], hi, atlas.base[js[-1] + 1:]])))
    tl.proof.add_box(finger, coupled[:, js].min(axis=0), coupled[:, js].max(axis=0))
    rng = np.random.default_rng(5)
    for _ in range(30):
        qa, qb = (lo + rng.random(len(js)) * (hi - lo) for _ in range(2))
        move, q_a, dq = _move(hand, finger, atlas.base, qa, qb)
        bound = tl.proof.bound_nm(q_a, dq, move.peak_acceleration, move.peak_speed)
        worst, scale = _full(tl, move, q_a, dq)
        assert bound is not None
        assert np.all(worst <= bound), (finger, worst, bound)
        if tl.proof.proves(q_a, dq, move.peak_acceleration, move.peak_speed):
            assert scale == 1.0


def test_a_move_outside_the_boxes_or_of_two_fingers_is_not_proved(default_moves):
    """A move with an end outside every box of its finger, and a move of two fingers at
    once, prove nothing (the full computation runs)."""
    hand, atlas, moves = default_moves
    tl = moves.tendons
    js = hand.joint_slice("index")
    e = next(e for e in atlas.solved().values() if e.finger == "index")
    far = e.high.copy()
    far[1] = hand.upper[js][1]  # (the knuckle bent to its stop: no high pose is)
    move, q_a, dq = _move(hand, "index", atlas.base, e.high, far)
    assert tl.proof.bound_nm(q_a, dq, move.peak_acceleration, move.peak_speed) is None
    dq2 = dq.copy()
    dq2[hand.joint_slice("middle")[1]] = 0.01
    assert tl.proof.bound_nm(q_a, dq2, move.peak_acceleration, move.peak_speed) is None


def test_a_weakened_tendon_is_not_proved(default_moves):
    """The default hand with its middle finger's knuckle tendon at 9 N of its 40 N (its
    capacity between the finger's load held still and its load moving) and the default
    hand's boxes: the full computation slows some of that finger's moves across, and no
    move of that finger is proved; nor the index finger's, which the full computation does
    not slow (the test asks every tendon motor's static bound within its share, the middle
    finger's too: on the safe side)."""
    _, atlas, moves = default_moves
    spec = load_hand_spec("default")
    weak = HandModel(dataclasses.replace(spec, actuators=tuple(
        dataclasses.replace(a, tendon_force_n=9.0)
        if a.name == "middle_mcp" else a for a in spec.actuators)))
    tl = TendonLoad(weak)
    for finger, boxes in moves.tendons.proof.boxes.items():
        tl.proof.boxes[finger].extend(boxes)
    rng = np.random.default_rng(2)
    entries = {f: [e for e in atlas.solved().values() if e.finger == f]
               for f in ("middle", "index")}
    slowed = unslowed = 0
    for _ in range(40):
        a, b = (entries["middle"][i] for i in rng.integers(len(entries["middle"]), size=2))
        move, q_a, dq = _move(weak, "middle", atlas.base, a.high, b.high)
        is_proved = tl.proof.proves(q_a, dq, move.peak_acceleration, move.peak_speed)
        assert not is_proved
        slowed += _full(tl, move, q_a, dq)[1] > 1.0
        a, b = (entries["index"][i] for i in rng.integers(len(entries["index"]), size=2))
        if np.max(np.abs(b.high - a.high)) >= 1e-6:
            move, q_a, dq = _move(weak, "index", atlas.base, a.high, b.high)
            assert not tl.proof.proves(q_a, dq, move.peak_acceleration, move.peak_speed)
            unslowed += _full(tl, move, q_a, dq)[1] == 1.0
    assert slowed > 0
    assert unslowed > 0
