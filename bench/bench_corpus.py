"""Benchmark of `play` on real music: every song of ``../shared/corpus/`` (or a folder
given), the sample songs and the stress songs, planned and judged by the independent
check. Per song and per category: frame F1 (over the song's frames), notes hit, frames a
note's key went down late and came up early (mean per note hit), wrong presses, limit
violations, real-time factor.

    python bench/bench_corpus.py [--corpus DIR] [--out FILE.tsv] [--only SUBSTRING]
                                 [--random N] [--against REV]

``--against REV`` also runs this benchmark as it is at git revision REV (a worktree in a
temporary folder; its planner, its songs), one after the other on the same machine, and
prints both side by side: how a change compares with what main did before it. A
revision whose benchmark ran two planners (``--planner both``) shows both.

Not a test: it prints what this machine measures. Issue 13's targets: corpus mean F1
>= 0.98, none below 0.92, every soprano chorale >= 0.99, sample songs >= 0.98; median
real-time factor >= 200x.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
from collections import defaultdict
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

from planner.check import NOTE_HIT_FRACTION, check_trajectory
from planner.hand.model import load_hand
from planner.music.midi import load_song

try:  # (a revision before format version 2 has no shift: --against runs it too)
    from planner.music.midi import shift_notes
except ImportError:
    def shift_notes(notes, shift_s):
        return notes
from planner.play import Planner, plan_song


def early_late_frames(report, notes) -> tuple[float, float]:
    """Mean frames per hit note (criteria: down in half its frames) that its key went
    down after the note's first frame (late) and came up before its last frame (early),
    from the check's replay (rows at the song's frames)."""
    rp = report.replay
    late = early = n = 0
    for note in notes:
        k0, k1 = np.searchsorted(rp.t_s, [note.onset_s, note.offset_s], side="left")
        seg = rp.down[k0:k1, note.pitch - 21]
        if k1 <= k0 or seg.mean() < NOTE_HIT_FRACTION:
            continue
        n += 1
        late += int(np.argmax(seg))
        early += int(np.argmax(seg[::-1]))
    return (late / n, early / n) if n else (0.0, 0.0)


def category(path: Path) -> str:
    name = path.stem
    if path.parent.name == "stress":
        return "stress"
    if path.parent.name == "songs":
        return "sample"
    if path.parent.name == "random":
        return "random " + name.rsplit("_", 1)[0]
    return name.split("_")[0] if not name.startswith("chorale") else "_".join(name.split("_")[:2])


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--corpus", default=str(ROOT.parent / "shared" / "corpus"))
    ap.add_argument("--out", default=None, help="also write the per-song rows here (TSV)")
    ap.add_argument("--only", default=None, help="only songs whose name holds this")
    ap.add_argument("--random", type=int, default=4,
                    help="random songs per kind (bench/random_songs.py), 0 for none")
    ap.add_argument("--against", default=None, metavar="REV",
                    help="also run this benchmark at git revision REV, side by side")
    a = ap.parse_args()
    rows = []
    if a.against:
        rows += run_at_revision(a.against, a)
    rows += run_here(a, "this")
    summarise(rows)
    if a.out:
        with open(a.out, "w", encoding="utf-8") as f:
            f.write("planner\tcategory\tsong\tf1\thit\tnotes\tlate_frames\tearly_frames\t"
                    "wrong\tlimit_violations\trtf\n")
            f.writelines("\t".join(str(x) for x in r) + "\n" for r in rows)


def songs_of(a) -> tuple[list[Path], tempfile.TemporaryDirectory]:
    songs = sorted(Path(a.corpus).glob("*.mid")) + sorted((ROOT / "songs").glob("*.mid")) \
        + sorted((ROOT / "songs" / "stress").glob("*.mid"))
    tmp = tempfile.TemporaryDirectory()
    if a.random:
        from random_songs import write_all

        songs += write_all(Path(tmp.name) / "random", a.random)
    if a.only:
        songs = [s for s in songs if a.only in s.name]
    return songs, tmp


def run_here(a, label: str) -> list[tuple]:
    """Plan and check every song with this tree's planner; the per-song rows."""
    songs, tmp = songs_of(a)
    hand = load_hand("default")
    planner = Planner(hand)
    rows = []
    print(f"{'planner':7s} {'song':40s} {'F1':>6s} {'hit':>9s} {'late':>5s} {'early':>5s} "
          f"{'wrong':>5s} {'limits':>6s} {'RTF':>5s}")
    with tmp, tempfile.TemporaryDirectory() as d:
        for p in songs:
            song = load_song(p)
            out = os.path.join(d, "o.csv")
            res = plan_song(song, hand, out, planner=planner)
            rep = check_trajectory(out, str(p))
            late, early = early_late_frames(rep, shift_notes(song.notes,
                                                             getattr(rep, "song_start_s", 0.0)))
            song_s = max(n.offset_s for n in song.notes)
            lim = sum(lc.count for lc in rep.limits)
            row = (label, category(p), p.stem, rep.play.f1, rep.play.notes_hit, rep.play.notes,
                   late, early, len(rep.play.wrong_presses), lim, song_s / res.planning_s)
            rows.append(row)
            print(f"{label:7s} {p.stem[:40]:40s} {row[3]:6.4f} {row[4]:4d}/{row[5]:<4d} "
                  f"{late:5.2f} {early:5.2f} {row[8]:5d} {lim:6d} {row[10]:5.0f}x", flush=True)
    return rows


def run_at_revision(rev: str, a) -> list[tuple]:
    """This benchmark as it is at ``rev``, in a temporary git worktree; its rows, labelled
    with the revision (and the planner, where it ran two)."""
    import subprocess

    sha = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", rev], check=True,
                         capture_output=True, text=True).stdout.strip()
    with tempfile.TemporaryDirectory() as d:
        tree = Path(d) / "tree"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(tree), sha],
                       check=True, capture_output=True)
        try:
            tsv = Path(d) / "rows.tsv"
            cmd = [sys.executable, str(tree / "bench" / "bench_corpus.py"), "--corpus",
                   str(Path(a.corpus).resolve()), "--random", str(a.random), "--out", str(tsv)]
            if a.only:
                cmd += ["--only", a.only]
            subprocess.run(cmd, check=True, cwd=tree)
            rows = []
            for line in tsv.read_text(encoding="utf-8").splitlines()[1:]:
                f = line.split("\t")
                rows.append((f"{sha}:{f[0]}" if f[0] != "this" else sha, f[1], f[2],
                             float(f[3]), int(f[4]), int(f[5]), float(f[6]), float(f[7]),
                             int(f[8]), int(f[9]), float(f[10])))
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(tree)],
                           check=False, capture_output=True)
    return rows


def summarise(rows: list[tuple]) -> None:
    by = defaultdict(list)
    for r in rows:
        by[(r[1], r[0])].append(r)
        if r[1] not in ("sample", "stress") and not r[1].startswith("random"):
            by[("corpus (all)", r[0])].append(r)
        if r[1].startswith("random"):
            by[("random (all)", r[0])].append(r)
    print(f"\n{'category':20s} {'planner':10s} {'songs':>5s} {'mean F1':>8s} {'min F1':>7s} "
          f"{'late':>5s} {'early':>5s} {'wrong':>5s} {'median RTF':>10s}")
    for (cat, k), rs in sorted(by.items(), key=lambda kv: (kv[0][0].endswith("(all)"), kv[0])):
        print(f"{cat:20s} {k:10s} {len(rs):5d} {statistics.mean(r[3] for r in rs):8.4f} "
              f"{min(r[3] for r in rs):7.4f} {statistics.mean(r[6] for r in rs):5.2f} "
              f"{statistics.mean(r[7] for r in rs):5.2f} {sum(r[8] for r in rs):5d} "
              f"{statistics.median(r[10] for r in rs):9.0f}x")


if __name__ == "__main__":
    main()
