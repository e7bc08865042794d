"""Hand files for the hand tests (no test here): the default hand's TOML text, edits of
it written to a temporary hand file and loaded, and random joint vectors."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from planner.hand.builders import load_hand_spec
from planner.hand.model import HandModel
from planner.hand.spec import FINGERS, hands_dir

DEFAULT_TOML = hands_dir() / "default.toml"
LONG_FINGERS = FINGERS[1:]  # index, middle, ring, pinky


def random_q(hand: HandModel, rng: np.random.Generator, coupled: bool = True) -> np.ndarray:
    q = rng.uniform(hand.lower, hand.upper)
    return hand.apply_couplings(q) if coupled else q


def default_text() -> str:
    return DEFAULT_TOML.read_text(encoding="utf-8")


def edit_finger(text: str, finger: str, old: str, new: str) -> str:
    """Replace ``old`` by ``new`` once, inside the ``[[finger]]`` block of ``finger``."""
    blocks = text.split("[[finger]]")
    hits = [i for i, b in enumerate(blocks) if re.search(rf'^name = "{finger}"$', b, re.MULTILINE)]
    assert len(hits) == 1, finger
    i = hits[0]
    assert blocks[i].count(old) == 1, (finger, old)
    blocks[i] = blocks[i].replace(old, new)
    return "[[finger]]".join(blocks)


def edit(text: str, old: str, new: str) -> str:
    assert text.count(old) >= 1, old
    return text.replace(old, new, 1)


def write_hand(tmp_path: Path, text: str, name: str = "hand.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def load_text(tmp_path: Path, text: str) -> HandModel:
    return HandModel(load_hand_spec(str(write_hand(tmp_path, text))))


DEFAULT_MOUNT = "xyz_m = [0.0, -0.40, 0.05]"  # the default hand's play mount, as its file has it


def fitted_text() -> str:
    """The default hand as it was until session 37: no ``[play]`` posture (the wrist fitted
    to the natural hand, reach 0, presses to full dip, the tip rule alone: the atlas's
    path of the ``mk5`` and the ``agh``) and the rail 0.17 m over the keys."""
    text = edit(default_text(), DEFAULT_MOUNT, "xyz_m = [0.0, -0.40, 0.17]")
    return text[:text.index("[play]")] + text[text.index("[forearm]"):]


def remounted_play(tmp_path: Path, xyz_m: str, pitches: tuple[int, int], fitted: bool = False):
    """A hand file: the default hand (``fitted``: ``fitted_text``'s) with its play mount at
    ``xyz_m`` (TOML text, e.g. "[0.0, -0.40, 0.06]"); a two-note song of ``pitches``;
    ``play`` of it with that hand file. Returns (hand file, song, trajectory, play's exit
    code)."""
    from planner.cli import main
    from planner.music.midi import Note, write_notes_midi

    text = fitted_text() if fitted else default_text()
    hand = write_hand(tmp_path, re.sub(r"xyz_m = \[0\.0, -0\.40, 0\.\d+\]", f"xyz_m = {xyz_m}",
                                       text, count=1), "mounted.toml")
    song = tmp_path / "s.mid"
    write_notes_midi([Note(pitches[0], 0.0, 0.4, 80), Note(pitches[1], 0.5, 0.9, 80)], str(song))
    out = tmp_path / "s.csv"
    return hand, song, out, main(["play", str(song), "--hand", str(hand), "-o", str(out)])
