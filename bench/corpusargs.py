"""What the corpus benchmarks share: their arguments (the folder of songs, the checkout
measured, the hand, a subset by name) and the songs those arguments choose."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def add_corpus_args(ap: argparse.ArgumentParser) -> None:
    """``--corpus``, ``--tree``, ``--hand``, ``--only``."""
    ap.add_argument("--corpus", default=str(ROOT.parent / "shared" / "corpus"))
    ap.add_argument("--tree", default=str(ROOT), help="the checkout whose planner is measured")
    ap.add_argument("--hand", default="default")
    ap.add_argument("--only", default=None,
                    help="only songs whose name holds one of these (comma-separated)")


def chosen_songs(a: argparse.Namespace) -> list[Path]:
    """The folder's songs (``*.mid``, sorted) that ``--only`` keeps; none: the reason on
    stderr and an empty list (the caller exits 2)."""
    songs = sorted(Path(a.corpus).glob("*.mid"))
    if a.only:
        songs = [s for s in songs if any(w in s.stem for w in a.only.split(","))]
    if not songs:
        print(f"{a.corpus}: no song (*.mid) selected", file=sys.stderr)
    return songs
