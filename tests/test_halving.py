"""The halving reductions (``planner.play.halving``) give numpy's numbers to the bit, and
the body rule's box penetration built on them (``fingerbody.many_box_penetration``) gives
``keybodies.box_penetration``'s."""

import numpy as np
import pytest

from planner.music.keybodies import box_penetration
from planner.play.fingerbody import many_box_penetration
from planner.play.halving import all_along, max_along, min_along, sum3

SHAPES = [(1, 1), (1, 7), (14, 55), (3, 1, 4), (14, 55, 3), (42, 55, 9), (2, 257, 2), (600, 3),
          (5, 0, 2)]


@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("axis", [0, 1])
def test_min_max_all_are_numpys(shape, axis):
    rng = np.random.default_rng(sum(shape) + axis)
    x = rng.normal(size=shape) * rng.choice([1e-3, 1.0, 1e3], size=shape)
    if shape[axis] == 0:
        with pytest.raises(ValueError):
            min_along(x, axis)
    else:
        for ours, theirs in ((min_along, np.min), (max_along, np.max)):
            got = ours(x, axis)
            assert got.shape == theirs(x, axis=axis).shape
            assert np.array_equal(got, theirs(x, axis=axis))
    for p in (0.0, 0.05, 0.5, 1.0):
        b = rng.random(shape) >= p
        assert np.array_equal(all_along(b, axis), b.all(axis=axis))


def test_reduction_leaves_its_input():
    x = np.arange(6.0).reshape(1, 6)
    got = min_along(x, 0)
    got[0] = 99.0
    assert x[0, 0] == 0.0


@pytest.mark.parametrize("shape", [(3,), (7, 3), (14, 55, 2, 3), (42, 55, 9, 3), (2000, 3)])
def test_sum3_is_numpys_order(shape):
    rng = np.random.default_rng(len(shape))
    x = rng.random(shape) * rng.choice([1e-9, 1e-3, 1.0, 1e4], size=shape)
    assert np.array_equal(sum3(x), x.sum(axis=-1))


def test_many_box_penetration_is_box_penetrations():
    rng = np.random.default_rng(3)
    for K, m, B in [(1, 1, 1), (14, 55, 3), (42, 55, 9), (5, 19, 0), (300, 37, 4)]:
        P = rng.normal(scale=0.02, size=(K, m, 3))
        r = rng.uniform(0.004, 0.012, size=m)
        c = rng.normal(scale=0.02, size=(B, 3))
        h = rng.uniform(0.002, 0.02, size=(B, 3))
        assert np.array_equal(many_box_penetration(P, r, c - h, c + h),
                              box_penetration(P, r, c - h, c + h))
