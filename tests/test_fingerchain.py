"""A finger's tip and body points in one pass down its chain (``FingerChain``) and the
follow test's body rule in one array (``follow.held_clear``): the numbers of the
computation as first written (a ``FrameChain`` per shape and for the tip;
``FingerBodies.clear_many`` and its own-key depth), to the bit, on configurations of
every size the planner asks (one follow's samples to a move table's chunk)."""

from __future__ import annotations

import numpy as np
import pytest

from planner.hand.chain import FrameChain
from planner.hand.model import load_hand
from planner.music import keyboard as kb
from planner.play.fingerbody import AXIS_SAMPLES
from planner.play.fingerchain import FingerChain
from planner.play.follow import HOLD_MARGIN_M, held_clear
from planner.play.places import Places


def shapes_as_first_written(hand, fb, Q, finger):
    """``FingerBodies.points_many`` as first written: each shape's ends by its own chain."""
    s = fb.shapes[finger]
    t = np.linspace(0.0, 1.0, AXIS_SAMPLES)[:, None]
    pts = []
    for fid, a, b, n in zip(s.frames, s.p0, s.p1, s.n_points):
        w = FrameChain(hand, hand.pin_model.frames[fid].name).points(Q, np.stack([a, b]))
        wa, wb = w[:, :1], w[:, 1:]
        pts.append(wa + t[None, :n] * (wb - wa))
    return np.concatenate(pts, axis=1)


def configurations(places: Places, finger: str, n: int, rng) -> np.ndarray:
    """``n`` hands of every posture, the finger at its atlas entries' poses (and between
    them), the arm anywhere along the keys: (n, joints), couplings applied."""
    entries = [e for a in places.atlases for e in a.solved().values()
               if e.finger == finger]
    hand = places.hand
    js = hand.joint_slice(finger)
    Q = []
    for _ in range(n):
        a, b = rng.choice(len(entries), 2)
        ea, eb = entries[a], entries[b]
        q = places.atlases[ea.posture].base.copy()
        s = rng.uniform()
        q[js] = ea.press + s * (eb.high - ea.press)
        q[places.rail] = rng.uniform(-0.4, 0.4)
        Q.append(q)
    return hand.apply_couplings(np.array(Q))


@pytest.fixture(scope="module", params=["default", "default-left"])
def places(request) -> Places:
    return Places(load_hand(request.param))


@pytest.mark.parametrize("n", [1, 12, 257])
def test_one_pass_gives_each_chains_numbers_to_the_bit(places, n):
    rng = np.random.default_rng(n)
    hand, fb = places.hand, places.atlas.bodies
    for f in hand.fingers:
        if not any(e.finger == f for e in places.atlas.solved().values()):
            continue
        Q = configurations(places, f, n, rng)
        tip, pts = FingerChain(hand, fb.shapes[f], f, AXIS_SAMPLES).carry(Q)
        assert np.array_equal(tip, FrameChain(hand, f"{f}_tip").positions(Q))
        assert np.array_equal(pts, shapes_as_first_written(hand, fb, Q, f))
        assert np.array_equal(fb.points_many(Q, f), pts)


def test_held_clear_is_clear_many_and_the_hold(places):
    rng = np.random.default_rng(7)
    fb = places.atlas.bodies
    seen = set()
    for f in ("index", "ring"):
        Q = configurations(places, f, 150, rng)
        P, r = fb.points_many(Q, f), fb.radii(f)
        for pitch in range(61, 68):
            clear, depth = fb.clear_many(P, r, pitch)
            want = clear & (depth >= kb.DOWN_DEPTH_M + HOLD_MARGIN_M)
            got = held_clear(fb, P, r, pitch)
            assert np.array_equal(got, want), (f, pitch)
            seen.update(got.tolist())
    assert seen == {True, False}  # (both answers met)
