"""Random songs of the kind the planner is for (one right hand), for benchmarks: songs no
planner was tuned on. Each generator takes a seed and returns notes; the same seed gives
the same song.

    python bench/random_songs.py OUT_DIR [--seeds N]   # writes OUT_DIR/<kind>_<seed>.mid
    python bench/random_songs.py OUT_DIR --hands 2 [--seeds N]   # OUT_DIR/pair_<seed>.mid

Two hands (``--hands 2``, for ``play --hands 2``): per seed a right part from one generator
and a left part from another, an octave lower, each on its own channel
(``two_hand_notes``; the songs of the two-hand rounds' measurements,
``docs/history/2026-12-07-two-hands9.md``).
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from planner.music.midi import Note, write_notes_midi

C_MAJOR = (0, 2, 4, 5, 7, 9, 11)


def _scale_pitch(degree: int, root: int = 60) -> int:
    octave, step = divmod(degree, 7)
    return root + 12 * octave + C_MAJOR[step]


def walk(rng, leapy: bool = False, n: int = 64) -> list[Note]:
    """A melody in C major moving by steps (and leaps up to a sixth), 90-150 bpm, eighths
    and quarters, legato (95 % of each slot)."""
    beat = 60.0 / rng.uniform(90, 150)
    t, d, out = 0.0, int(rng.integers(0, 7)), []
    for _ in range(n):
        step = int(rng.choice([-5, -4, -3, 3, 4, 5])) if leapy and rng.random() < 0.3 else \
            int(rng.choice([-2, -1, -1, 1, 1, 2]))
        d = int(np.clip(d + step, -7, 12))
        dur = beat * float(rng.choice([0.5, 0.5, 1.0]))
        out.append(Note(_scale_pitch(d), t, t + 0.95 * dur, int(rng.integers(50, 110))))
        t += dur
    return out


def repeated(rng, n: int = 48) -> list[Note]:
    """Notes repeated two to four times, then a step: 100-140 bpm eighths, detached."""
    beat = 60.0 / rng.uniform(100, 140)
    t, d, out = 0.0, int(rng.integers(0, 7)), []
    while len(out) < n:
        for _ in range(int(rng.integers(2, 5))):
            out.append(Note(_scale_pitch(d), t, t + 0.4 * beat, 80))
            t += 0.5 * beat
        d = int(np.clip(d + rng.choice([-2, -1, 1, 2]), -5, 10))
    return out


def two_voices(rng, n: int = 40) -> list[Note]:
    """A melody in quarters over a lower voice in half notes, a third to a sixth below
    (a chorale's soprano and alto in one hand), 60-90 bpm."""
    beat = 60.0 / rng.uniform(60, 90)
    d, out = int(rng.integers(2, 7)), []
    for k in range(n):
        d = int(np.clip(d + rng.choice([-1, -1, 1, 1, 2, -2]), 0, 11))
        out.append(Note(_scale_pitch(d), k * beat, (k + 1) * beat, 80))
        if k % 2 == 0:
            lower = d - int(rng.choice([2, 3, 4, 5]))
            out.append(Note(_scale_pitch(lower), k * beat, (k + 2) * beat, 70))
    return out


def chords(rng, n: int = 24) -> list[Note]:
    """Triads in close position on the degrees of C major, one per beat at 60-100 bpm."""
    beat = 60.0 / rng.uniform(60, 100)
    out = []
    for k in range(n):
        root = int(rng.integers(0, 7))
        for j in (0, 2, 4):
            out.append(Note(_scale_pitch(root + j), k * beat, (k + 0.9) * beat, 80))
    return out


def trill(rng, n: int = 48) -> list[Note]:
    """Trills of a tone or a semitone, 8-12 notes a second, moving every 12 notes."""
    slot = 1.0 / rng.uniform(8, 12)
    out, base = [], int(rng.integers(55, 75))
    for k in range(n):
        if k % 12 == 0:
            base = int(np.clip(base + rng.integers(-5, 6), 50, 80))
            other = base + int(rng.choice([1, 2]))
        out.append(Note(base if k % 2 == 0 else other, k * slot, (k + 0.85) * slot, 80))
    return out


GENERATORS = {"walk": walk, "walk_leapy": lambda rng: walk(rng, leapy=True),
              "repeated": repeated, "two_voices": two_voices, "chords": chords, "trill": trill}


def write_all(out_dir: Path, seeds: int) -> list[Path]:
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    for kind, gen in GENERATORS.items():
        for seed in range(seeds):
            p = out_dir / f"{kind}_{seed}.mid"
            write_notes_midi(gen(np.random.default_rng([seed, len(kind)])), p)
            paths.append(p)
    return paths


def two_hand_notes(seed: int) -> list[Note]:
    """A two-hand song: a right part (channel 0) from generator ``seed`` mod 6, seed
    ``seed``, and a left part (channel 1) from another generator, seed 1000 + ``seed``,
    an octave lower (no lower than A0, MIDI 21)."""
    kinds = list(GENERATORS)
    kr, kl = kinds[seed % 6], kinds[(seed + 1 + seed // 6) % 6]
    right = [replace(n, channel=0) for n in GENERATORS[kr](np.random.default_rng(seed))]
    left = [replace(n, pitch=max(21, n.pitch - 12), channel=1)
            for n in GENERATORS[kl](np.random.default_rng(1000 + seed))]
    return right + left


def write_pairs(out_dir: Path, seeds: int) -> list[Path]:
    """``two_hand_notes`` of seeds 0 .. ``seeds`` - 1 as ``OUT_DIR/pair_<seed>.mid``."""
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    for seed in range(seeds):
        p = out_dir / f"pair_{seed}.mid"
        write_notes_midi(two_hand_notes(seed), p)
        paths.append(p)
    return paths


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("out_dir")
    ap.add_argument("--seeds", type=int, default=4)
    ap.add_argument("--hands", type=int, choices=(1, 2), default=1)
    a = ap.parse_args()
    write = write_pairs if a.hands == 2 else write_all
    for p in write(Path(a.out_dir), a.seeds):
        print(p)


if __name__ == "__main__":
    main()
