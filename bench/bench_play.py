"""Benchmark of `play`: real-time factor (song time / planning time, after imports and
the one-time hand set-up) for every sample song, and the time to the first row written.

    python bench/bench_play.py [--repeat N] [--rounds N]

Not a test: it prints ratios measured on this machine. Targets (issue 13): at least
200x faster than the song plays, first row within 50 ms.
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
from planner.music.midi import Note, Song, load_song
from planner.play import Planner, plan_song


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--rounds", type=int, default=16, help="sample songs in the long song, times over")
    a = ap.parse_args()
    root = Path(__file__).resolve().parents[1]
    t0 = time.perf_counter()
    hand = load_hand("default")
    t1 = time.perf_counter()
    planner = Planner(hand)
    t2 = time.perf_counter()
    print(f"hand model {1000 * (t1 - t0):.0f} ms, planner set-up (the atlas) "
          f"{1000 * (t2 - t1):.0f} ms (once per process)")
    print(f"{'song':16s} {'song s':>7s} {'plan ms':>8s} {'RTF':>6s} {'first row ms':>13s}")
    total_song = total_plan = 0.0
    with tempfile.TemporaryDirectory() as d:
        for p in sorted((root / "songs").glob("*.mid")):
            song = load_song(p)
            song_s = max(n.offset_s for n in song.notes)
            best = None
            for _ in range(a.repeat):
                # (one planner for every run: its timed-move caches fill on the first)
                res = plan_song(song, hand, os.path.join(d, "o.csv"), planner=planner)
                if best is None or res.planning_s < best.planning_s:
                    best = res
            total_song += song_s
            total_plan += best.planning_s
            print(f"{p.stem:16s} {song_s:7.2f} {1000 * best.planning_s:8.1f} "
                  f"{song_s / best.planning_s:6.0f}x {1000 * best.first_row_s:13.1f}")
    print(f"{'all':16s} {total_song:7.2f} {1000 * total_plan:8.1f} {total_song / total_plan:6.0f}x")
    # a long song: every sample song in turn, 0.5 s apart, ``--rounds`` times over
    notes, t0_s = [], 0.0
    songs = [load_song(p) for p in sorted((root / "songs").glob("*.mid"))]
    for _ in range(a.rounds):
        for song in songs:
            notes += [Note(n.pitch, n.onset_s + t0_s, n.offset_s + t0_s, n.velocity) for n in song.notes]
            t0_s = max(n.offset_s for n in notes) + 0.5
    long = Song(tuple(notes), t0_s, (), "long")
    with tempfile.TemporaryDirectory() as d:
        res = plan_song(long, hand, os.path.join(d, "o.csv"), planner=planner)
    song_s = max(n.offset_s for n in notes)
    print(f"{'long (' + str(len(notes)) + ' notes)':16s} {song_s:7.1f} {1000 * res.planning_s:8.1f} "
          f"{song_s / res.planning_s:6.0f}x {1000 * res.first_row_s:13.1f}")


if __name__ == "__main__":
    main()
