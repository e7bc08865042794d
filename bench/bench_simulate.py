"""The physics replay: how fast it runs, and how it agrees with the kinematic check.

    python bench/bench_simulate.py               # simulated seconds per wall second, 60 s song
    python bench/bench_simulate.py --agreement   # every sample song: kinematic vs physics F1
                                                 # (both contact models), notes that differ

The 60 s song is a random walk (``bench/random_songs.py``, seed 0) repeated to 60 s or more,
planned once into a temporary folder. Needs MuJoCo (``pip install -e ".[physics]"``).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import planner
from planner.music.midi import Note, write_notes_midi
from planner.simulate import simulate_trajectory

SONG_S = 60.0


def _sixty_second_song(out: Path) -> Path:
    from random_songs import walk

    base = walk(np.random.default_rng(0))
    period = max(n.offset_s for n in base) + 0.5
    notes, k = [], 0
    while k * period < SONG_S:  # at least SONG_S long
        notes += [Note(n.pitch, n.onset_s + k * period, n.offset_s + k * period, n.velocity)
                  for n in base]
        k += 1
    path = out / "sixty.mid"
    write_notes_midi(notes, str(path))
    return path


def bench_speed() -> None:
    hand = planner.load_hand("default")
    with tempfile.TemporaryDirectory() as d:
        song = _sixty_second_song(Path(d))
        traj = Path(d) / "sixty.csv"
        planner.plan_song(planner.load_song(str(song)), hand, str(traj))
        for contact in ("full", "pads"):
            t0 = time.perf_counter()
            rep = simulate_trajectory(str(traj), str(song), contact=contact)
            wall = time.perf_counter() - t0
            print(f"contact {contact}: {rep.duration_s:.1f} s simulated in {wall:.1f} s "
                  f"(replay loop {rep.wall_s:.1f} s): {rep.duration_s / wall:.2f} simulated "
                  f"s per wall s; physics F1 {rep.play.f1:.4f}, kinematic {rep.kinematic_f1:.4f}")


def _differences(rep) -> str:
    p = rep.play
    parts = [f"{m.name}@{m.onset_s:.2f}s missed ({m.reason})" for m in p.missed]
    parts += [f"{w.name}@{w.start_s:.2f}s wrong ({'+'.join(w.fingers) or 'no finger'})"
              for w in p.wrong_keys]
    return "; ".join(parts[:6]) + (f"; ... {len(parts) - 6} more" if len(parts) > 6 else "")


def bench_agreement() -> None:
    hand = planner.load_hand("default")
    songs = sorted((ROOT / "songs").glob("*.mid"))
    print("| song | kinematic F1 | physics F1 (full) | wrong keys (full) | physics F1 (pads) | "
          "overhang frames (pads) | wrong keys (pads) |")
    print("|---|---|---|---|---|---|---|")
    notes_out = []
    with tempfile.TemporaryDirectory() as d:
        for song in songs:
            traj = Path(d) / f"{song.stem}.csv"
            planner.plan_song(planner.load_song(str(song)), hand, str(traj))
            full = simulate_trajectory(str(traj), str(song), contact="full")
            pads = simulate_trajectory(str(traj), str(song), contact="pads")
            over = sum(round((e.end_s - e.start_s) * 100) for e in pads.play.overhangs)
            print(f"| {song.stem} | {full.kinematic_f1:.4f} | {full.play.f1:.4f} | "
                  f"{len(full.play.wrong_keys)} | {pads.play.f1:.4f} | {over} | "
                  f"{len(pads.play.wrong_keys)} |", flush=True)
            notes_out.append(f"{song.stem} (full): {_differences(full)}")
            notes_out.append(f"{song.stem} (pads): {_differences(pads)}")
    print()
    for line in notes_out:
        print(line)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--agreement", action="store_true",
                    help="kinematic vs physics F1 on every sample song")
    a = ap.parse_args()
    sys.path.insert(0, str(ROOT / "bench"))
    bench_agreement() if a.agreement else bench_speed()


if __name__ == "__main__":
    main()
