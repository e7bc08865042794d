"""Keyboard surfaces and press targets of the IK module (planner/ik.py)."""

from planner.ik import exposed_range_x, press_target
from planner.music import keyboard as kb


def test_exposed_range_of_white_keys_lies_between_their_black_neighbours():
    lo, hi = exposed_range_x(62)  # D4: between C#4 and D#4
    assert lo == kb.key(61).x_max_m and hi == kb.key(63).x_min_m
    lo, hi = exposed_range_x(64)  # E4: no black key above
    assert lo == kb.key(63).x_max_m and hi == kb.key(64).x_max_m
    assert exposed_range_x(61) == (kb.key(61).x_min_m, kb.key(61).x_max_m)  # a black key: itself


def test_press_targets_are_on_their_keys_at_full_dip():
    for pitch in range(kb.LOWEST_PITCH, kb.HIGHEST_PITCH + 1):
        k = kb.key(pitch)
        for finger in ("thumb", "index"):
            t = press_target(finger, pitch)
            x, y, z = t.point_m
            assert k.x_min_m <= x <= k.x_max_m and z == k.top_z_m - kb.KEY_DIP_M
            assert k.y_min_m <= t.y_range_m[0] <= y <= t.y_range_m[1] <= k.y_max_m
