"""Tests of hand files (planner.hand.spec): the seed's other tip/middle ratios and the
motor-bound speed limits read from an edited default.toml, the ranges a ratio needs, a
hand without its rail, and the one-line errors of a malformed or missing hand file.

The edited files are written by tests/handfiles.py.
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from planner.errors import InputError
from planner.hand.builders import load_hand_spec
from planner.hand.model import HandModel, load_hand
from planner.hand.spec import list_hands
from tests.handfiles import (
    DEFAULT_TOML,
    LONG_FINGERS,
    default_text,
    edit,
    edit_finger,
    load_text,
    random_q,
    write_hand,
)


# =========================================================================== tip/middle ratios
@pytest.mark.parametrize("ratio", [0.556, 0.333])
def test_other_seed_ratios_from_a_hand_file(tmp_path: Path, ratio: float) -> None:
    """Seed Table 4: theta_tip = 0.667 / 0.556 / 0.333 theta_mid."""
    text = edit_finger(default_text(), "middle", "dip_ratio = 0.667", f"dip_ratio = {ratio}")
    h = load_text(tmp_path, text)
    rng = np.random.default_rng(4)
    for _ in range(5):
        q = random_q(h, rng)
        for f in LONG_FINGERS:
            r = ratio if f == "middle" else 0.667
            assert q[h.index[f"{f}_dip"]] == pytest.approx(r * q[h.index[f"{f}_pip"]], abs=1e-15)
        assert np.all(h.coupling_errors(q) == 0.0)
    mimic = ET.fromstring(h.urdf).find("joint[@name='middle_dip']/mimic")
    assert mimic.get("multiplier") == f"{ratio:g}"
    # the PIP tendon motor now turns (a_pip + ratio a_dip) / spool per PIP radian
    m = h.motor_names.index("middle_pip")
    assert h.motor_ratio(h.q_neutral)[m] == pytest.approx((0.011 + ratio * 0.0075) / 0.005, rel=1e-12)
    assert h.urdf_sha256 != load_hand("default").urdf_sha256


def test_spec_rejects_dip_range_too_small_for_ratio(tmp_path: Path) -> None:
    """DIP up to 60 deg cannot hold 0.667 x a 100 deg PIP (66.7 deg); with 0.556 it can (55.6)."""
    text = edit_finger(default_text(), "index", "dip = { lower_deg = 0.0, upper_deg = 90.0 }",
                       "dip = { lower_deg = 0.0, upper_deg = 60.0 }")
    with pytest.raises(InputError) as e:
        load_hand_spec(str(write_hand(tmp_path, text)))
    msg = str(e.value)
    assert "\n" not in msg and "index" in msg and "dip range" in msg and "dip_ratio" in msg
    ok = edit_finger(text, "index", "dip_ratio = 0.667", "dip_ratio = 0.556")
    spec = load_hand_spec(str(write_hand(tmp_path, ok, "ok.toml")))
    assert spec.joint("index_dip").upper == pytest.approx(math.radians(60.0))
    # a negative PIP lower limit must fit too: -10 deg x 0.667 is below the DIP's 0
    neg = edit_finger(default_text(), "ring", "pip = { lower_deg = 0.0, upper_deg = 100.0 }",
                      "pip = { lower_deg = -10.0, upper_deg = 100.0 }")
    with pytest.raises(InputError, match="ring: dip range"):
        load_hand_spec(str(write_hand(tmp_path, neg, "neg.toml")))


# =========================================================================== speed limits
def test_joint_speed_limits_when_the_motor_binds(tmp_path: Path) -> None:
    """With the caps lifted the motors set the limits: PIP 278 x 5 mm / (11 + 0.667 x 7.5 mm)."""
    text = edit(default_text(), "velocity_cap_rad_s = 20.0", "velocity_cap_rad_s = 1000.0")
    text = text.replace("velocity_cap_rad_s = 8.0", "velocity_cap_rad_s = 1000.0")
    h = load_text(tmp_path, text)
    v_pip = 278.0 * 0.005 / (0.011 + 0.667 * 0.0075)
    assert v_pip == pytest.approx(86.8614, abs=1e-4)
    for f in ("index", "middle", "ring"):
        assert h.velocity[h.index[f"{f}_pip"]] == pytest.approx(v_pip, rel=1e-12)
        assert h.velocity[h.index[f"{f}_dip"]] == pytest.approx(0.667 * v_pip, rel=1e-12)
        assert h.velocity[h.index[f"{f}_mcp_flex"]] == pytest.approx(278.0 * 0.005 / 0.015)
    assert h.velocity[h.index["pinky_pip"]] == pytest.approx(
        278.0 * 0.005 / (0.009 + 0.667 * 0.006), rel=1e-12)
    assert h.velocity[h.index["thumb_ip"]] == pytest.approx(278.0 * 0.005 / 0.009, rel=1e-12)
    # wrist: gear 2 -> 278 / 2 = 139 rad/s
    for wj in ("wrist_flex", "wrist_dev"):
        assert h.velocity[h.index[wj]] == pytest.approx(139.0, rel=1e-12)
    # at the limit the tendon motor runs at exactly its 278 rad/s
    m = h.motor_names.index("index_pip")
    assert h.motor_velocities(h.q_neutral, h.velocity)[m] == pytest.approx(278.0, rel=1e-12)


# =========================================================================== errors
def test_unknown_hand_names_the_valid_hands() -> None:
    with pytest.raises(InputError) as e:
        load_hand("nope")
    msg = str(e.value)
    assert msg == "unknown hand 'nope'; valid hands: default, default-left, agh, mk5"


def _one_line_error(tmp_path: Path, text: str, *needles: str) -> str:
    path = write_hand(tmp_path, text, "bad.toml")
    with pytest.raises(InputError) as e:
        load_hand_spec(str(path))
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith("malformed hand file bad.toml: "), msg
    for n in needles:
        assert n in msg, msg
    # load_hand (the CLI's entry point) gives the same error
    with pytest.raises(InputError, match=re.escape(msg)):
        load_hand(str(path))
    return msg


def test_error_toml_syntax(tmp_path: Path) -> None:
    _one_line_error(tmp_path, edit(default_text(), 'name = "default"', 'name = "default'),
                    "line 15")


def test_error_missing_key(tmp_path: Path) -> None:
    text = edit(default_text(), "spool_radius_m = 0.005", "")
    _one_line_error(tmp_path, text, "missing key 'spool_radius_m'")
    text = edit_finger(default_text(), "ring", "middle_in = 1.59375\n", "")
    _one_line_error(tmp_path, text, "missing key 'middle_m'")


def test_error_non_numeric_length(tmp_path: Path) -> None:
    text = edit_finger(default_text(), "index", "base_in = 2.8125", 'base_in = "long"')
    _one_line_error(tmp_path, text, "'base_in' must be a finite number", "'long'")
    text = edit_finger(default_text(), "index", "base_in = 2.8125", "base_in = -1.0")
    _one_line_error(tmp_path, text, "length 'base' must be positive")


def test_error_lower_not_below_upper(tmp_path: Path) -> None:
    text = edit_finger(default_text(), "middle", "pip = { lower_deg = 0.0, upper_deg = 100.0 }",
                       "pip = { lower_deg = 100.0, upper_deg = 100.0 }")
    _one_line_error(tmp_path, text, "'pip': lower_deg must be below upper_deg")
    text = edit(default_text(), "lower_m = -0.62", "lower_m = 0.80")
    _one_line_error(tmp_path, text, "rail: lower_m must be below upper_m")
    text = edit(default_text(), "flex = { lower_deg = -70.0", "flex = { lower_deg = 85.0")
    _one_line_error(tmp_path, text, "wrist flex: lower_deg must be below upper_deg")


def test_error_wrong_finger_names(tmp_path: Path) -> None:
    text = edit(default_text(), 'name = "pinky"', 'name = "little"')
    _one_line_error(tmp_path, text, "[[finger]] entries must be exactly index, middle, ring, pinky",
                    "little")
    text = edit(default_text(), 'name = "pinky"', 'name = "ring"')
    _one_line_error(tmp_path, text, "[[finger]] entries must be exactly")
    # a [[finger]] without a name
    text = edit(default_text(), 'name = "pinky"\n', "")
    _one_line_error(tmp_path, text, "[[finger]] entries must be exactly", "None")
    # the Mk5 and AGH-free builders share the rule (the Mk5's once sorted None with str)
    mk5 = (DEFAULT_TOML.parent / "mk5.toml").read_text(encoding="utf-8")
    _one_line_error(tmp_path, edit(mk5, 'name = "pinky"\n', ""),
                    "[[finger]] entries must be exactly", "None")


def test_error_zero_or_negative_transmission(tmp_path: Path) -> None:
    """A zero spool or moment arm must be an input error, not a ZeroDivisionError traceback;
    a negative one must not give negative joint speed limits."""
    text = edit(default_text(), "spool_radius_m = 0.005", "spool_radius_m = 0.0")
    _one_line_error(tmp_path, text, "'spool_radius_m' must be positive")
    text = edit_finger(default_text(), "index", "mcp = 0.015,", "mcp = 0.0,")
    _one_line_error(tmp_path, text, "'mcp' must be positive")
    text = edit_finger(default_text(), "index", "pip = 0.011,", "pip = -0.011,")
    _one_line_error(tmp_path, text, "'pip' must be positive")
    text = edit(default_text(), "moment_arm_m = { cmc_flex = 0.015", "moment_arm_m = { cmc_flex = 0")
    _one_line_error(tmp_path, text, "'cmc_flex' must be positive")


def test_error_negative_rotor_inertia(tmp_path: Path) -> None:
    text = edit(default_text(), "motor_rotor_inertia_g_cm2 = 34.9", "motor_rotor_inertia_g_cm2 = -1")
    _one_line_error(tmp_path, text, "'tendon.motor_rotor_inertia_g_cm2' = -1 is outside "
                    "[0, 1e+07] g cm^2")


# (issue 32: every number of a hand file checked on load against its unit's range; the
# one line names the key, its value and the range)
OUT_OF_RANGE = [
    ("velocity_cap_rad_s = 20.0", "velocity_cap_rad_s = 0.0",
     "'finger_speed.velocity_cap_rad_s' = 0.0 is outside [0.1, 100000] rad/s"),
    ("velocity_cap_rad_s = 20.0", "velocity_cap_rad_s = 1e-6",
     "'finger_speed.velocity_cap_rad_s' = 1e-06 is outside [0.1, 100000] rad/s"),
    ("velocity_cap_rad_s = 20.0", "velocity_cap_rad_s = 1e300",
     "'finger_speed.velocity_cap_rad_s' = 1e+300 is outside [0.1, 100000] rad/s"),
    ("acceleration_rad_s2 = 500.0", "acceleration_rad_s2 = 1e300",
     "'finger_speed.acceleration_rad_s2' = 1e+300 is outside [1, 1e+06] rad/s^2"),
    ("mass_kg = 0.40", "mass_kg = -1.0", "'palm.mass_kg' = -1.0 is outside (0, 100] kg"),
    ("mass_kg = 0.40", "mass_kg = 0", "'palm.mass_kg' = 0 is outside (0, 100] kg"),
    ("masses_kg = { base = 0.035", "masses_kg = { base = -0.035",
     "'finger[0].masses_kg.base' = -0.035 is outside (0, 100] kg"),
    ("velocity_m_s = 3.0", "velocity_m_s = 0.0", "'rail.velocity_m_s' = 0.0 is outside"),
    ("acceleration_m_s2 = 40.0", "acceleration_m_s2 = 1e9", "'rail.acceleration_m_s2' = 1000000000.0"),
    ("design_force_n = 40.0", "design_force_n = 0.0", "'tendon.design_force_n' = 0.0 is outside"),
    ('name = "default"', 'name = "de\\u0007fault"', "'name' is not printable text"),
]


@pytest.mark.parametrize("old,new,needle", OUT_OF_RANGE, ids=[n for _, n, _ in OUT_OF_RANGE])
def test_every_number_is_checked_against_its_unit(tmp_path: Path, old, new, needle) -> None:
    _one_line_error(tmp_path, edit(default_text(), old, new), needle)


def test_the_shipped_hands_are_within_every_range() -> None:
    for name in list_hands():
        load_hand_spec(name)


def test_error_unreadable_hand_file(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="cannot read hand file") as e:
        load_hand_spec(str(tmp_path / "missing.toml"))
    assert "\n" not in str(e.value)


def test_rail_can_be_turned_off(tmp_path):
    """A hand file with ``[rail] enabled = false``: no rail joint or motor, 21 hand joints,
    and play still plans (notes out of reach of the fixed hand are reported, not dropped)."""
    from planner.hand.builders import load_hand_spec
    from planner.hand.spec import hands_dir
    from planner.music.midi import load_song
    from planner.play import plan_song
    from tests.handfiles import fitted_text

    text = fitted_text()  # (no [play] posture: its reach axis goes with the rail's off)
    assert "enabled = true" in text and hands_dir().exists()
    p = tmp_path / "norail.toml"
    p.write_text(text.replace("enabled = true", "enabled = false").replace(
        'name = "default"', 'name = "norail"'), encoding="utf-8")
    hand = HandModel(load_hand_spec(str(p)))
    assert "rail" not in hand.joint_names and "rail" not in hand.motor_names
    assert len(hand.joint_names) == 21
    song = load_song(Path(__file__).resolve().parents[1] / "songs" / "twinkle.mid")
    res = plan_song(song, hand, str(tmp_path / "t.csv"))
    assert res.verdict.notes == 14 and res.verdict.played + len(res.verdict.skipped) == 14
