"""The follow test's fast paths give the exact path's answers: a chain of axis-aligned
joints carried a coordinate at a time (``FingerChain.carry_axes``, ``carry_coords``)
gives ``carry_general``'s numbers to the bit; the boxes' penetrations and the held test
on coordinate arrays (``follow.box_penetration``, ``held_coords``) give
``FingerBodies``' own; the held test of the points low enough to matter (``low_points``)
gives every point's answer, to the last bit of a point's height; one move's answer remembered by ``paths_clear`` is the answer of
the same move tested among many (the path that remembers nothing), on random moves of
every finger, both answers met."""

from __future__ import annotations

import numpy as np
import pytest

from planner.hand.model import load_hand
from planner.music import keyboard as kb
from planner.play.fingerbody import AXIS_SAMPLES, many_box_penetration
from planner.play.fingerchain import FingerChain, axis_steps
from planner.play.follow import (
    HOLD_MARGIN_M,
    box_penetration,
    finger_chain,
    held_clear,
    held_coords,
    held_coords_all,
    low_points,
    paths_clear,
)
from planner.play.places import Places


@pytest.fixture(scope="module", params=["default", "default-left"])
def places(request) -> Places:
    return Places(load_hand(request.param))


def _fingers(places: Places) -> list[str]:
    return [f for f in places.hand.fingers
            if any(e.finger == f for a in places.atlases for e in a.solved().values())]


def _configurations(places: Places, finger: str, n: int, rng) -> np.ndarray:
    """``n`` hands of any posture, the finger between two of its entries' poses, the
    arm anywhere along the keys: (n, joints), couplings applied."""
    entries = [e for a in places.atlases for e in a.solved().values() if e.finger == finger]
    js = places.hand.joint_slice(finger)
    Q = []
    for _ in range(n):
        ea, eb = (entries[i] for i in rng.choice(len(entries), 2))
        q = places.atlases[ea.posture].base.copy()
        q[js] = ea.press + rng.uniform() * (eb.high - ea.press)
        q[places.rail] = rng.uniform(-0.4, 0.4)
        Q.append(q)
    return places.hand.apply_couplings(np.array(Q))


@pytest.mark.parametrize("n", [1, 7, 300])
def test_axis_aligned_chain_is_the_general_chain_to_the_bit(places, n):
    rng = np.random.default_rng(n)
    fb = places.atlas.bodies
    fast = 0
    for f in _fingers(places):
        chain = FingerChain(places.hand, fb.shapes[f], f, AXIS_SAMPLES)
        Q = _configurations(places, f, n, rng)
        tip, P = chain.carry_general(Q)
        got_tip, got = chain.carry(Q)
        assert np.array_equal(got_tip, tip) and np.array_equal(got, P), f
        c_tip, coords = chain.carry_coords(Q)
        assert np.array_equal(c_tip, tip), f
        for c in range(3):
            assert np.array_equal(coords[c], P[:, :, c].T), (f, c)
        fast += chain.axis_aligned and finger_chain(fb, f).axis_aligned
    assert fast  # (the fast path was met: the hand's long fingers are axis-aligned)


def test_a_chain_not_axis_aligned_is_carried_the_general_way():
    """The Mk5's fingers turn about axes that are not coordinate axes: ``carry`` and
    ``carry_coords`` give ``carry_general``'s numbers."""
    places = Places(load_hand("mk5"))
    fb = places.atlas.bodies
    rng = np.random.default_rng(2)
    general = 0
    for f in _fingers(places):
        chain = FingerChain(places.hand, fb.shapes[f], f, AXIS_SAMPLES)
        general += not chain.axis_aligned
        Q = _configurations(places, f, 20, rng)
        tip, P = chain.carry_general(Q)
        got_tip, got = chain.carry(Q)
        c_tip, coords = chain.carry_coords(Q)
        assert np.array_equal(got_tip, tip) and np.array_equal(got, P)
        assert np.array_equal(c_tip, tip)
        assert all(np.array_equal(coords[c], P[:, :, c].T) for c in range(3))
    assert general


def test_axis_steps_refuses_a_turned_axis(places):
    fb = places.atlas.bodies
    f = next(f for f in _fingers(places) if finger_chain(fb, f).axis_aligned)
    joints = list(finger_chain(fb, f).joints)
    T = finger_chain(fb, f).T_world_root
    assert axis_steps(joints, T) is not None
    name, prismatic, _, R, t = joints[-1]
    joints[-1] = (name, prismatic, np.array([0.6, 0.8, 0.0]), R, t)
    assert axis_steps(joints, T) is None


def test_box_penetration_is_fingerbodys(places):
    rng = np.random.default_rng(3)
    fb = places.atlas.bodies
    for f in _fingers(places)[:2]:
        P = fb.points_many(_configurations(places, f, 200, rng), f)
        r = fb.radii(f)
        for pitch in (60, 61, 64, 66):
            _, lo, hi = fb.pressed_boxes(pitch)
            want = many_box_penetration(P, r, lo, hi)  # (K, B)
            got = box_penetration(*(np.ascontiguousarray(P[:, :, c].T) for c in range(3)),
                                  r, lo, hi)  # (B, K)
            assert np.array_equal(got, want.T), (f, pitch)


def test_held_coords_is_clear_many_and_the_hold(places):
    rng = np.random.default_rng(11)
    fb = places.atlas.bodies
    seen = set()
    for f in _fingers(places):
        P = fb.points_many(_configurations(places, f, 120, rng), f)
        r = fb.radii(f)
        for pitch in range(59, 68):
            clear, depth = fb.clear_many(P, r, pitch)
            want = clear & (depth >= kb.DOWN_DEPTH_M + HOLD_MARGIN_M)
            got = held_coords(fb, *(np.ascontiguousarray(P[:, :, c].T) for c in range(3)),
                              r, pitch)
            assert np.array_equal(got, want), (f, pitch)
            assert np.array_equal(held_clear(fb, P, r, pitch), want), (f, pitch)
            seen.update(got.tolist())
    assert seen == {True, False}


def test_a_remembered_move_is_the_move_tested_among_many(places):
    """Moves of a held key from one entry to another of the same key at rails a few
    steps apart (the programme's questions): each asked alone (remembered, and asked
    again) gives the answer of the same move in one batch of all of them."""
    rng = np.random.default_rng(5)
    hand, rail, arm = places.hand, places.rail, places.arm
    seen = set()
    for f in _fingers(places):
        js = hand.joint_slice(f)
        for pitch in (60, 61, 63, 65, 66, 71):
            QA, QB = [], []
            for _ in range(25):
                pa, pb = rng.integers(len(places.atlases), size=2)
                rail_a = kb.key(pitch).center_x_m + rng.uniform(-0.06, 0.06)
                rail_b = rail_a + rng.uniform(-0.04, 0.04)
                ea = places.atlases[pa].entry(f, pitch, rail_a)
                eb = places.atlases[pb].entry(f, pitch, rail_b)
                if ea is None or eb is None:
                    continue
                qa, qb = places.atlases[pa].base.copy(), places.atlases[pb].base.copy()
                qa[rail], qb[rail] = rail_a, rail_b
                qa[js], qb[js] = ea.press, eb.press
                QA.append(qa)
                QB.append(qb)
            if not QA:
                continue
            QA, QB = np.array(QA), np.array(QB)
            many = paths_clear(places.atlas, f, pitch, QA, QB, arm)
            for i in range(len(QA)):
                for _ in range(2):  # (computed, then remembered)
                    one = paths_clear(places.atlas, f, pitch, QA[i:i + 1], QB[i:i + 1], arm)
                    assert one.tolist() == [bool(many[i])], (f, pitch, i)
            seen.update(many.tolist())
    assert seen == {True, False}


def _coords(P: np.ndarray) -> tuple[np.ndarray, ...]:
    return tuple(np.ascontiguousarray(P[:, :, c].T) for c in range(3))


def test_the_low_points_give_every_points_answer(places):
    """``held_coords`` (the points ``low_points`` keeps) answers as ``held_coords_all``
    (every point), one configuration or many at once, every finger, nine keys."""
    rng = np.random.default_rng(17)
    fb = places.atlas.bodies
    dropped, seen = 0, set()
    for f in _fingers(places):
        P = fb.points_many(_configurations(places, f, 90, rng), f)
        r = fb.radii(f)
        X, Y, Z = _coords(P)
        for pitch in range(59, 68):
            for K in (slice(0, 1), slice(1, 19), slice(None)):
                x, y, z = X[:, K], Y[:, K], Z[:, K]
                want = held_coords_all(fb, x, y, z, r, pitch)
                assert np.array_equal(held_coords(fb, x, y, z, r, pitch), want), (f, pitch, K)
                keep = low_points(fb, z, r, pitch)
                dropped += keep is not None and 0 < keep.sum() < len(r)
                seen.update(want.tolist())
    assert dropped and seen == {True, False}


def _hold_edge(fb, x: np.ndarray, y: np.ndarray, z: np.ndarray, r: np.ndarray,
               pitch: int) -> tuple[float, float]:
    """The two adjacent heights of the first point between which ``held_coords_all``'s
    answer turns (held below, not held above), by bisection on the floats."""
    lo, hi = kb.key(pitch).top_z_m - 0.008 + r[0], kb.key(pitch).top_z_m + r[0]

    def held(h: float) -> bool:
        z[0, 0] = h
        return bool(held_coords_all(fb, x, y, z, r, pitch)[0])
    assert held(lo) and not held(hi)
    while np.nextafter(lo, hi) < hi:
        mid = lo + (hi - lo) / 2
        if mid in (lo, hi):
            mid = np.nextafter(lo, hi)
        lo, hi = (mid, hi) if held(mid) else (lo, mid)
    return lo, hi


def test_the_low_points_hold_to_the_last_bit(places):
    """One point over the middle of a white key's front, every other far above the keys
    (dropped by ``low_points``): at the height where the key stops being held (the
    hold's depth, one unit in the last place of the height apart) the fast path answers
    as every point's and as ``FingerBodies.clear_many`` with the hold's depth, on both
    sides; with every point high, neither holds the key."""
    fb = places.atlas.bodies
    f = _fingers(places)[0]
    r = fb.radii(f)
    for pitch in (60, 64, 65):
        k = kb.key(pitch)
        x = np.full((len(r), 1), k.center_x_m)
        y = np.full((len(r), 1), k.y_min_m + 0.01)
        z = np.full((len(r), 1), k.top_z_m + 0.05)
        lo, hi = _hold_edge(fb, x, y, z, r, pitch)
        assert np.nextafter(lo, hi) == hi
        for h, want in ((lo, True), (hi, False)):
            z[0, 0] = h
            keep = low_points(fb, z, r, pitch)
            assert keep is not None and keep.tolist() == [True] + [False] * (len(r) - 1)
            assert held_coords(fb, x, y, z, r, pitch).tolist() == [want], (pitch, h)
            # (and the general path's answer: ``clear_many`` and the hold's depth)
            clear, depth = fb.clear_many(np.stack([x.T, y.T, z.T], axis=-1), r, pitch)
            assert (clear & (depth >= kb.DOWN_DEPTH_M + HOLD_MARGIN_M)).tolist() == [want]
        z[0, 0] = k.top_z_m + 0.05
        assert not held_coords(fb, x, y, z, r, pitch)[0]
        assert not held_coords_all(fb, x, y, z, r, pitch)[0]
