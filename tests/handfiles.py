"""Hand files for the hand tests (no test here): the default hand's TOML text, edits of
it written to a temporary hand file and loaded, and random joint vectors."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from planner.hand.model import HandModel
from planner.hand.spec import FINGERS, hands_dir, load_hand_spec

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
