"""scripts/make_atlas.py: the parts it makes, by one function each whether made with the
rest or alone (``--only``)."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
_PATH = ROOT / "scripts" / "make_atlas.py"
_SPEC = importlib.util.spec_from_file_location("make_atlas", _PATH)
ma = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(ma)


def test_the_parts_named_are_made_in_their_order():
    """``--only``'s names in ``PARTS``' order whatever order they are given in; a fresh
    move table's proofs and repeats made with it; all by default; a name not a part is
    refused."""
    assert ma.parts_named(",".join(ma.PARTS)) == ma.PARTS
    assert ma.parts_named("follows,atlas") == ("atlas", "follows")
    assert ma.parts_named(" repeats ") == ("repeats",)
    assert ma.parts_named("moves") == ("moves", "proofs", "repeats")
    for bad in ("", "moves,", "repeat", "moves-only"):
        with pytest.raises(ValueError, match="unknown part"):
            ma.parts_named(bad)


def test_an_unknown_part_is_one_line_on_stderr_and_exit_2():
    r = subprocess.run([sys.executable, str(_PATH), "--only", "moves,bogus"], cwd=ROOT,
                       capture_output=True, text=True, check=False)
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr.splitlines()[-1] == "--only: unknown part 'bogus' (parts: " \
        "atlas,moves,proofs,repeats,follows)"
    assert not [s for s in r.stderr.splitlines()[:-1] if "Warn" not in s]


def test_the_repeats_part_writes_the_shipped_repeats(tmp_path, monkeypatch):
    """The repeats part (``make_repeats``, as the whole remake makes it) into a copy of the
    mk5's shipped move table without its repeats: the table holds again the very arrays
    the shipped one does, the others as they were."""
    from planner.hand.model import load_hand

    hand = load_hand("mk5")
    shipped = ma.moves_path(hand.urdf_sha256, 0)
    copy = tmp_path / shipped.name
    with np.load(shipped) as z:
        arrays = {k: z[k] for k in z.files}
    assert "repeat" in arrays and "repeat_params" in arrays
    np.savez_compressed(copy, **{k: v for k, v in arrays.items() if not k.startswith("repeat")})
    monkeypatch.setattr(ma, "moves_path", lambda sha, posture=0: tmp_path / shipped.name)
    ma.make_repeats(hand, ma.make(hand, 0, fresh=False))  # (the shipped atlas)
    with np.load(copy) as z:
        assert sorted(z.files) == sorted(arrays)
        for k in z.files:
            assert np.array_equal(z[k], arrays[k], equal_nan=z[k].dtype.kind == "f"), k
