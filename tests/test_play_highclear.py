"""When a finger going up or down is clear above every key (planner/play/highclear.py):
the arm may move from the lift's clear moment on and until the descent's."""

from __future__ import annotations

import numpy as np
import pytest

from planner.play.highclear import BODY_CLEAR_Z_M
from planner.play.places import Places


@pytest.fixture(scope="module")
def places(hand) -> Places:
    return Places(hand)


def _lowest_body_z(places: Places, e, move, t_s: float) -> float:
    h, atlas = places.hand, places.atlases[e.posture]
    q = atlas.base.copy()
    q[h.joint_slice(e.finger)] = move.at(t_s)[0]
    p, r = atlas.bodies.points(h.apply_couplings(q), e.finger)
    return float(np.min(p[:, 2] - r))


def _entries(places: Places):
    for posture, atlas in enumerate(places.atlases):
        for finger in ("index", "middle", "ring", "pinky"):
            for pitch in (60, 61, 64, 66):
                e = atlas.entry(finger, pitch, 0.0)
                if e is not None:
                    yield e


def test_a_lift_is_clear_from_its_clear_moment_to_its_end(places):
    seen = 0
    for e in _entries(places):
        u = places.lift(e, "high")
        t_clear = places.high.rise_clear_s(e, u.move)
        # (the key comes up first; the last part of the lift overlaps the arm's move)
        assert u.cross_s < t_clear < u.move.duration_s
        assert places.rail_lift_s(e) < places.before_rail_s(e)
        for t in np.linspace(t_clear, u.move.duration_s, 25):
            assert _lowest_body_z(places, e, u.move, t) >= BODY_CLEAR_Z_M - 1e-9
        # (just before it, the finger is still lower: the moment is not too late by much)
        assert _lowest_body_z(places, e, u.move, t_clear - 0.002) < BODY_CLEAR_Z_M + 3e-4
        seen += 1
    assert seen >= 8


def test_a_descent_is_clear_until_its_clear_moment(places):
    for e in _entries(places):
        d = places.descend(e, "high")
        t_clear = places.high.descent_clear_s(e, d.move)
        assert 0.0 < t_clear < d.cross_s
        assert places.rail_descent_s(e) == pytest.approx(d.cross_s - t_clear)
        for t in np.linspace(0.0, t_clear, 25):
            assert _lowest_body_z(places, e, d.move, t) >= BODY_CLEAR_Z_M - 1e-9
        assert _lowest_body_z(places, e, d.move, t_clear + 0.002) < BODY_CLEAR_Z_M + 3e-4
