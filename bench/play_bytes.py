"""The play's bytes (not a test): ``python cli.py play SONG -o DIR/NAME.csv`` for every
sample song, every stress song and every corpus piece (``../shared/corpus/``, or
``--corpus DIR``), each in a fresh process as a user runs it, with ``DIR/SHA256SUMS``:
a change that is meant to change no plan (a speed-up, a refactoring) leaves every sum as
it was (``sha256sum -c OLD/SHA256SUMS`` in the new DIR, or ``--against OLD``).

    python bench/play_bytes.py DIR [--tree PATH] [--corpus DIR] [--only SUBSTRING]
                                   [--extra DIR ...] [--against OLD_DIR] [--hand NAME]
    python bench/play_bytes.py DIR --hands 2 [--pairs N] [--tree PATH] [--against OLD_DIR]

``--hands 2``: two hands instead (``cli.py play SONG --hands 2``): every piece of the
two-hand corpus (``../shared/corpus2h/``, or ``--corpus DIR``) and ``--pairs N`` random
two-hand songs (``bench/random_songs.py``'s ``two_hand_notes``, seeds 0 .. N - 1, written
into ``DIR/songs/``), each in a fresh process, the pair's set-up included.

``--tree PATH`` runs another checkout's ``cli.py`` (its planner on ``PYTHONPATH``): the
same songs planned by main and by a branch, each into its own DIR. ``--hand NAME`` plans
with another hand (``cli.py play --hand NAME``; default: the default hand). Exit 1 when
``--against`` finds a file that differs.
"""

from __future__ import annotations

import argparse
import hashlib
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def songs_of(corpus: Path, only: str | None, extra: list[str]) -> list[Path]:
    if not any(corpus.glob("*.mid")):
        raise SystemExit(f"no corpus songs in {corpus} (--corpus DIR)")
    songs = sorted((ROOT / "songs").glob("*.mid")) + sorted((ROOT / "songs" / "stress").glob("*.mid")) \
        + sorted(corpus.glob("*.mid")) + [s for d in extra for s in sorted(Path(d).glob("*.mid"))]
    return [s for s in songs if only is None or only in s.name]


def pair_songs(corpus: Path, only: str | None, pairs: int, out: Path) -> list[Path]:
    """The two-hand songs: the corpus's pieces, then ``pairs`` random two-hand songs."""
    if not any(corpus.glob("*.mid")):
        raise SystemExit(f"no two-hand corpus songs in {corpus} (--corpus DIR)")
    sys.path.insert(0, str(ROOT / "bench"))
    from random_songs import write_pairs

    songs = sorted(corpus.glob("*.mid")) + write_pairs(out / "songs", pairs)
    return [s for s in songs if only is None or only in s.name]


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("--tree", default=str(ROOT), help="the checkout whose cli.py plans")
    ap.add_argument("--corpus", default=str(ROOT.parent / "shared" / "corpus"))
    ap.add_argument("--only", default=None, help="only songs whose name holds this")
    ap.add_argument("--extra", action="append", default=[],
                    help="another folder of songs (tests/data, bench/random_songs.py's)")
    ap.add_argument("--against", default=None, help="a DIR of this script's to compare with")
    ap.add_argument("--hand", default=None, help="hand name or file (cli.py play --hand)")
    ap.add_argument("--hands", type=int, choices=(1, 2), default=1,
                    help="2: the two-hand corpus and random two-hand songs, play --hands 2")
    ap.add_argument("--pairs", type=int, default=4, help="--hands 2: random two-hand songs")
    a = ap.parse_args(argv)
    if a.hands == 2 and a.corpus == str(ROOT.parent / "shared" / "corpus"):
        a.corpus = str(ROOT.parent / "shared" / "corpus2h")
    out, tree = Path(a.out), Path(a.tree).resolve()
    out.mkdir(parents=True, exist_ok=True)
    env = {**os.environ, "PYTHONPATH": str(tree)}
    sums = []
    songs = (pair_songs(Path(a.corpus), a.only, a.pairs, out) if a.hands == 2
             else songs_of(Path(a.corpus), a.only, a.extra))
    for song in songs:
        csv = out / f"{song.stem}.csv"
        hand = (["--hands", "2"] if a.hands == 2 else []) + (
            [] if a.hand is None else ["--hand", a.hand])
        r = subprocess.run([sys.executable, str(tree / "cli.py"), "play", str(song), "-o", str(csv), *hand],
                           capture_output=True, text=True, env=env, check=False)
        if r.returncode not in (0, 1):  # (1: the plan's own replay rejects it; still a plan)
            print(f"{song.name}: exit {r.returncode}: {r.stderr.strip()[-300:]}")
        sums.append(f"{hashlib.sha256(csv.read_bytes()).hexdigest()}  {csv.name}\n")
    (out / "SHA256SUMS").write_text("".join(sums))
    print(f"{len(sums)} files -> {out}")
    if a.against is None:
        return 0
    old = dict(line.split()[::-1] for line in (Path(a.against) / "SHA256SUMS").read_text().splitlines())
    differ = [name for name, h in (line.split()[::-1] for line in sums) if old.get(name) != h]
    print(f"{len(sums) - len(differ)} of {len(sums)} identical to {a.against}"
          + "".join(f"\n  DIFFERS: {n}" for n in differ))
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
