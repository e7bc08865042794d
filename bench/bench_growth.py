"""How `play`'s planning time grows with the song (issue 14, item 5): songs of N notes of
three kinds, each planned once, time per note and time to the first row, and the ratio of
the time per note at each N to the smallest N.

    python bench/bench_growth.py [--sizes 1000 5000 20000]

Kinds: ``dense`` (one-tick notes, 16.7 ms, on five keys back to back), ``same`` (one-tick
notes on C4, 20 per second), ``spread`` (100 ms notes over two octaves, 8 per second).
Not a test: it prints what this machine measures.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from planner.hand.model import load_hand
from planner.music.midi import Note, Song
from planner.play import Planner, plan_song

TICK_S = 1 / 960  # one tick at 480 per beat, 120 bpm


def song(kind: str, n: int) -> Song:
    if kind == "dense":
        notes = [Note((60, 62, 64, 65, 67)[i % 5], 16 * TICK_S * i, 16 * TICK_S * (i + 1), 80)
                 for i in range(n)]
    elif kind == "same":
        notes = [Note(60, 0.05 * i, 0.05 * i + 16 * TICK_S, 80) for i in range(n)]
    else:
        keys = (60, 64, 67, 72, 76, 79, 84, 79, 76, 72, 67, 64)
        notes = [Note(keys[i % len(keys)], 0.125 * i, 0.125 * i + 0.1, 80) for i in range(n)]
    return Song(tuple(notes), max(x.offset_s for x in notes))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", type=int, nargs="+", default=[1000, 5000, 20000])
    ap.add_argument("--kinds", nargs="+", default=["dense", "same", "spread"])
    a = ap.parse_args()
    hand = load_hand("default")
    print(f"{'kind':8s} {'notes':>7s} {'song s':>8s} {'plan s':>8s} {'ms/note':>8s} "
          f"{'x smallest':>10s} {'first row s':>11s}")
    with tempfile.TemporaryDirectory() as d:
        for kind in a.kinds:
            base = None
            for n in a.sizes:
                s = song(kind, n)
                pl = Planner(hand)
                t0 = time.perf_counter()
                res = plan_song(s, hand, os.path.join(d, "o.csv"), planner=pl)
                dt = time.perf_counter() - t0
                per = 1000 * dt / n
                base = base or per
                print(f"{kind:8s} {n:7d} {s.duration_s:8.1f} {dt:8.2f} {per:8.2f} "
                      f"{per / base:10.2f} {res.first_row_s:11.2f}", flush=True)


if __name__ == "__main__":
    main()
