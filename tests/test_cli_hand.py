"""The `hand` subcommand of cli.py, run as a subprocess (spec section 1: exit 2 + one
stderr line on bad input, no traceback)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from planner.hand.model import load_hand
from planner.hand.spec import hands_dir

ROOT = Path(__file__).resolve().parents[1]


def run_cli(*args: str) -> subprocess.CompletedProcess[str]:
    r = subprocess.run([sys.executable, "cli.py", *args], cwd=ROOT, capture_output=True,
                       text=True, timeout=300, check=False)
    assert "Traceback" not in r.stderr, r.stderr
    return r


@pytest.fixture(scope="module")
def default_urdf() -> str:
    return load_hand("default").urdf


def test_hand_list() -> None:
    r = run_cli("hand", "--list")
    assert r.returncode == 0 and r.stderr == ""
    names = [line.split()[0] for line in r.stdout.splitlines() if line.strip()]
    assert names == ["default", "default-left", "agh", "mk5"]
    assert "Seed hand (000_776cdc32671efdf6)" in r.stdout


def test_hand_summary() -> None:
    r = run_cli("hand")
    assert r.returncode == 0 and r.stderr == ""
    assert r.stdout.startswith("hand default: ")
    assert "a right hand, 21 hand joints (17 independent) + rig: rail, reach" in r.stdout
    assert f"urdf_sha256 {load_hand('default').urdf_sha256}" in r.stdout
    for f in ("index", "middle", "ring", "pinky"):
        assert f"{f}_dip = 0.667 x {f}_pip" in r.stdout
    # same output with the hand named explicitly
    assert run_cli("hand", "--hand", "default").stdout == r.stdout
    assert ("play postures: reach -0.175, -0.150, -0.100 m, wrist -11.5 / +0.0 deg, presses "
            "6.0 mm deep") in r.stdout


def test_hand_json_names_its_play_postures() -> None:
    import json

    play = json.loads(run_cli("hand", "--json").stdout)["play"]
    assert play["reach_m"] == [-0.175, -0.15, -0.1] and play["press_depth_m"] == 0.006
    assert json.loads(run_cli("hand", "--hand", "mk5", "--json").stdout)["play"] == {
        "reach_m": [0.0], "wrist_flex_rad": 0.0, "wrist_dev_rad": 0.0, "press_depth_m": 0.006}


def test_hand_urdf_to_file(tmp_path: Path, default_urdf: str) -> None:
    out = tmp_path / "x.urdf"
    r = run_cli("hand", "--urdf", str(out))
    assert r.returncode == 0 and r.stderr == "" and r.stdout == ""
    assert out.read_bytes() == default_urdf.encode("utf-8")
    # a relative path is relative to the working directory
    r = subprocess.run([sys.executable, str(ROOT / "cli.py"), "hand", "--urdf", "x.urdf"],
                       cwd=tmp_path / ".", capture_output=True, text=True, timeout=300, check=False)
    assert r.returncode == 0 and "Traceback" not in r.stderr
    assert (tmp_path / "x.urdf").read_bytes() == default_urdf.encode("utf-8")


def test_hand_urdf_to_stdout(default_urdf: str) -> None:
    r = subprocess.run([sys.executable, "cli.py", "hand", "--urdf", "-"], cwd=ROOT,
                       capture_output=True, timeout=300, check=False)
    assert r.returncode == 0 and r.stderr == b""
    assert r.stdout == default_urdf.encode("utf-8")


def test_hand_file_by_path(tmp_path: Path, default_urdf: str) -> None:
    path = tmp_path / "copy.toml"
    path.write_text((hands_dir() / "default.toml").read_text(encoding="utf-8"), encoding="utf-8")
    r = run_cli("hand", "--hand", str(path), "--urdf", "-")
    assert r.returncode == 0 and r.stdout == default_urdf


def test_unknown_hand() -> None:
    r = run_cli("hand", "--hand", "nope")
    assert r.returncode == 2 and r.stdout == ""
    lines = r.stderr.splitlines()
    assert len(lines) == 1 and r.stderr.endswith("\n")
    assert "unknown hand" in lines[0] and "default, default-left, agh, mk5" in lines[0]


@pytest.mark.parametrize("content, needle", [
    ('name = "broken\n', "malformed hand file broken.toml"),  # TOML syntax error
    ('name = "broken"\n', "missing key"),  # valid TOML, not a hand
])
def test_broken_hand_file(tmp_path: Path, content: str, needle: str) -> None:
    path = tmp_path / "broken.toml"
    path.write_text(content, encoding="utf-8")
    r = run_cli("hand", "--hand", str(path))
    assert r.returncode == 2 and r.stdout == ""
    lines = r.stderr.splitlines()
    assert len(lines) == 1, r.stderr
    assert lines[0].startswith("error: ") and needle in lines[0]


def test_zero_moment_arm_is_an_input_error(tmp_path: Path) -> None:
    text = (hands_dir() / "default.toml").read_text(encoding="utf-8")
    path = tmp_path / "zero.toml"
    path.write_text(text.replace("mcp = 0.015,", "mcp = 0.0,", 1), encoding="utf-8")
    r = run_cli("hand", "--hand", str(path))
    assert r.returncode == 2 and len(r.stderr.splitlines()) == 1
    assert "'mcp' must be positive" in r.stderr


def test_missing_hand_file_and_bad_usage(tmp_path: Path) -> None:
    r = run_cli("hand", "--hand", str(tmp_path / "absent.toml"))
    assert r.returncode == 2 and len(r.stderr.splitlines()) == 1
    assert "cannot read hand file" in r.stderr
    r = run_cli("hand", "--bogus")
    assert r.returncode == 2 and len(r.stderr.splitlines()) == 1
