"""The servos' tracking margin (planner/play/margin.py): a move between an entry's poses is
slowed until its lag at the finger's speed plus its body's reach into every other black
key stays within the body rule's tolerance; the move tables ship the scales."""

from __future__ import annotations

import numpy as np
import pytest

from planner.music import keyboard as kb
from planner.play.atlas import Atlas
from planner.play.fingerbody import OTHER_KEY_TOLERANCE_M
from planner.play.margin import (
    MOMENTS,
    TRACKING_MARGIN_M,
    TRACKING_SPEED_RAD_S,
    lag_m,
    margin_scale,
)
from planner.play.moves import SCALE_PAIRS, Moves
from planner.play.tendonload import slowed


@pytest.fixture(scope="module")
def atlas(hand) -> Atlas:
    return Atlas(hand, posture=0)


@pytest.fixture(scope="module")
def moves(hand, atlas) -> Moves:
    return Moves(hand, atlas)


def _worst(atlas: Atlas, e, move) -> float:
    """The largest reach into another black key plus the lag, over ``MOMENTS`` moments
    of ``move`` and 200 more between them, of the moments where the body at rest is
    within the tolerance (from the bodies' points and the keys' boxes, one moment at a
    time)."""
    hand, bodies = atlas.hand, atlas.bodies
    pitch = 60 + e.pitch_class
    worst = -np.inf
    t = np.unique(np.r_[np.linspace(0.0, move.duration_s, MOMENTS),
                        np.linspace(0.0, move.duration_s, 200)])
    h = 1e-6
    for ti in t:
        q = atlas.base.copy()
        q[hand.joint_slice(e.finger)] = move.at(ti)[0]
        q[atlas.rail] = kb.key(pitch).center_x_m - e.dx_m
        p, r = bodies.points(hand.apply_couplings(q), e.finger)
        black = np.array([kb.is_black(int(b)) and int(b) != pitch for b in bodies.box_pitch])
        d = np.maximum(np.maximum(bodies.box_lo[black][None] - p[:, None],
                                  p[:, None] - bodies.box_hi[black][None]), 0.0)
        depth = float(np.max(r[:, None] - np.sqrt((d * d).sum(axis=-1))))
        if depth >= OTHER_KEY_TOLERANCE_M:
            continue
        v = (move.at(min(ti + h, move.duration_s))[0] - move.at(max(ti - h, 0.0))[0]) \
            / (min(ti + h, move.duration_s) - max(ti - h, 0.0))
        worst = max(worst, depth + float(lag_m(np.max(np.abs(v)))))
    return worst


def test_the_lag_scales_with_speed():
    assert float(lag_m(TRACKING_SPEED_RAD_S)) == pytest.approx(TRACKING_MARGIN_M)
    assert float(lag_m(TRACKING_SPEED_RAD_S / 2)) == pytest.approx(TRACKING_MARGIN_M / 2)


def test_slowed_moves_fit_their_lag_and_unslowed_ones_did_not(atlas, moves):
    """The default hand's posture-0 middle-finger lifts that the margin slows: before, a
    moment's reach plus lag passes the tolerance; slowed by their scale, none does (to
    the moments' sampling: 2 % over between them)."""
    slowed_seen = 0
    for e in atlas.solved().values():
        if e.finger != "middle":
            continue
        a, b = SCALE_PAIRS[0]
        base = moves._move(e.finger, getattr(e, a), getattr(e, b))
        tendon = moves.finger_scale(e.finger, getattr(e, a), getattr(e, b), base,
                                    kb.key(60 + e.pitch_class).top_z_m)
        move = slowed(base, tendon)
        s = margin_scale(atlas, e.finger, e.pitch_class, e.dx_m, move)
        assert s >= 1.0
        if s == 1.0:
            continue
        assert _worst(atlas, e, move) > OTHER_KEY_TOLERANCE_M
        assert _worst(atlas, e, slowed(move, s)) <= OTHER_KEY_TOLERANCE_M * 1.02
        assert moves.entry_scale(e, 0) == pytest.approx(tendon * s, rel=1e-12)
        slowed_seen += 1
        if slowed_seen == 3:
            break
    assert slowed_seen == 3


def test_no_body_rule_no_margin(mk5):
    atlas = Atlas(mk5)
    moves = Moves(mk5, atlas)
    e = next(e for e in atlas.solved().values())
    move = moves.lift(e, "high").move
    assert margin_scale(atlas, e.finger, e.pitch_class, e.dx_m, move) == 1.0
