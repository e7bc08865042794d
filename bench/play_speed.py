"""`play`'s speed, two checkouts side by side (not a test): ``cli.py play SONG --json``
of this tree and of another (``--vs PATH``, e.g. main's checkout), each in a fresh
process as a user runs it, alternating song by song and run by run (A B, then B A, ...)
so that a machine whose speed drifts weighs on both alike. Per song the median of the
runs of: planning after the hand's set-up (``planning_s``), the real-time factor (song
seconds / planning), the first row (``first_row_s``) and the set-up (``setup_s``); then
the medians over the songs and the ratio of each tree's to the other's.

    python bench/play_speed.py --vs /work/main [--repeat 3] [--corpus DIR] [--only SUB]
                               [--no-samples] [--tsv FILE] [--warm] [--hands 2]
                               [--keep DIR] [--extra DIR ...]

``--keep DIR``: each tree's files kept (``DIR/this/``, ``DIR/vs/``, the last run's) and
compared byte for byte at the end (a speed-up plans the same files); ``--extra DIR``: the
songs of another folder too (``bench/random_songs.py``'s).

``--hands 2``: ``cli.py play SONG --hands 2 --json``, the two-hand corpus
(``../shared/corpus2h/`` unless ``--corpus``) and no sample songs; its clock is
``plan_two_hands``' (after the pair's set-up, every way and the file), and a two-hand
plan writes its file at the end: no first row (``nan``).

The clock is the planner's own (``plan_song``: from after ``Planner(hand)``, the atlas
and the timed moves loaded, to the file closed, the self-check's verdict included).
``--warm``: as ``bench_corpus.py`` and ``batch`` plan, one process per tree plans every
song with one ``Planner`` (its memos of the hand's moves filled by the songs before), the
trees' processes in turn (A B, B A, ...), ``--repeat`` passes; no first row or set-up.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FIELDS = ("planning_s", "first_row_s", "setup_s")


def run(tree: Path, song: Path, out: str, hands: int = 1) -> dict:
    env = {**os.environ, "PYTHONPATH": str(tree)}
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    two = ["--hands", "2"] if hands == 2 else []
    r = subprocess.run([sys.executable, str(tree / "cli.py"), "play", str(song), "-o", out,
                        "--json", *two], capture_output=True, text=True, env=env, check=False)
    if r.returncode not in (0, 1):
        raise SystemExit(f"{tree}: {song.name}: exit {r.returncode}: {r.stderr.strip()[-300:]}")
    j = json.loads(r.stdout)
    j.setdefault("first_row_s", math.nan)  # (two hands: the file is written at the end)
    return j


def _out(keep: str | None, tmp: str, tree: str, song: Path) -> str:
    """Where ``tree``'s run of ``song`` writes: ``keep/tree/SONG.csv``, else a scratch file."""
    if keep is None:
        return os.path.join(tmp, f"{tree}.csv")
    (Path(keep) / tree).mkdir(parents=True, exist_ok=True)
    return str(Path(keep) / tree / f"{song.stem}.csv")


def worker(songs: list[str]) -> int:
    """``--warm``'s process: every song planned with one ``Planner``, one JSON line each
    (the planner of ``PYTHONPATH``: this file imports it)."""
    from planner.hand.model import load_hand
    from planner.music.midi import load_song
    from planner.play.stream import Planner, plan_song

    hand = load_hand("default")
    planner = Planner(hand)
    with tempfile.TemporaryDirectory() as d:
        for p in songs:
            song = load_song(p)
            res = plan_song(song, hand, os.path.join(d, "o.csv"), planner=planner)
            print(json.dumps({"song": p, "song_s": max(n.offset_s for n in song.notes),
                              "planning_s": res.planning_s}), flush=True)
    return 0


def warm(trees: dict[str, Path], songs: list[Path], repeat: int) -> int:
    got: dict[str, dict[str, list[float]]] = {k: {s.stem: [] for s in songs} for k in trees}
    song_s = {}
    for r in range(repeat):
        for k in (["this", "vs"] if r % 2 == 0 else ["vs", "this"]):
            env = {**os.environ, "PYTHONPATH": str(trees[k])}
            out = subprocess.run([sys.executable, __file__, "--worker", *map(str, songs)],
                                 capture_output=True, text=True, env=env, check=True).stdout
            for line in out.splitlines():
                j = json.loads(line)
                got[k][Path(j["song"]).stem].append(j["planning_s"])
                song_s[Path(j["song"]).stem] = j["song_s"]
    rtf = {k: {s: song_s[s] / statistics.median(v) for s, v in got[k].items()} for k in trees}
    print(f"{'song':40s} {'this RTF':>9s} {'vs RTF':>8s} {'ratio':>6s}")
    for s in got["this"]:
        print(f"{s[:40]:40s} {rtf['this'][s]:8.0f}x {rtf['vs'][s]:7.0f}x "
              f"{rtf['this'][s] / rtf['vs'][s]:6.2f}")
    print(f"\n{len(songs)} songs, one Planner per pass, {repeat} passes per tree:")
    for k, tree in trees.items():
        v = list(rtf[k].values())
        print(f"  {k:5s} ({tree}): real-time factor {statistics.median(v):.0f}x median "
              f"(lowest {min(v):.0f}x)")
    ratios = [rtf["this"][s] / rtf["vs"][s] for s in rtf["this"]]
    print(f"  this / vs, per song: x{statistics.median(ratios):.2f} median "
          f"(x{min(ratios):.2f}-x{max(ratios):.2f})")
    return 0


def main(argv: list[str]) -> int:
    if argv[:1] == ["--worker"]:
        return worker(argv[1:])
    ap = argparse.ArgumentParser()
    ap.add_argument("--vs", required=True, help="the other checkout (its cli.py, its planner)")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--corpus", default=str(ROOT.parent / "shared" / "corpus"))
    ap.add_argument("--only", default=None, help="only songs whose name holds this")
    ap.add_argument("--no-samples", action="store_true", help="the corpus alone")
    ap.add_argument("--tsv", default=None, help="also write every run here")
    ap.add_argument("--warm", action="store_true", help="one Planner per pass (bench_corpus's)")
    ap.add_argument("--hands", type=int, choices=(1, 2), default=1,
                    help="2: play --hands 2 on the two-hand corpus")
    ap.add_argument("--keep", default=None, help="keep each tree's files here, compared")
    ap.add_argument("--extra", action="append", default=[], help="another folder of songs")
    a = ap.parse_args(argv)
    if a.hands == 2:
        if a.warm:
            raise SystemExit("--warm plans one hand")
        a.no_samples = True
        if a.corpus == str(ROOT.parent / "shared" / "corpus"):
            a.corpus = str(ROOT.parent / "shared" / "corpus2h")
    trees = {"this": ROOT, "vs": Path(a.vs).resolve()}
    songs = [] if a.no_samples else sorted((ROOT / "songs").glob("*.mid"))
    songs += sorted(Path(a.corpus).glob("*.mid"))
    songs += [s for d in a.extra for s in sorted(Path(d).glob("*.mid"))]
    songs = [s for s in songs if a.only is None or a.only in s.name]
    if not songs:
        raise SystemExit("no songs")
    if a.warm:
        return warm(trees, songs, a.repeat)
    runs: list[tuple[str, str, int, dict]] = []
    med: dict[str, dict[str, list[float]]] = {k: {f: [] for f in (*FIELDS, "rtf")} for k in trees}
    print(f"{'song':40s} {'this RTF':>9s} {'vs RTF':>8s} {'ratio':>6s} {'this 1st ms':>11s} "
          f"{'vs 1st ms':>9s}")
    with tempfile.TemporaryDirectory() as d:
        for i, song in enumerate(songs):
            got: dict[str, list[dict]] = {k: [] for k in trees}
            for r in range(a.repeat):
                order = ["this", "vs"] if (i + r) % 2 == 0 else ["vs", "this"]
                for k in order:
                    j = run(trees[k], song, _out(a.keep, d, k, song), a.hands)
                    got[k].append(j)
                    runs.append((k, song.stem, r, j))
            for k in trees:
                for f in FIELDS:
                    med[k][f].append(statistics.median(j[f] for j in got[k]))
                med[k]["rtf"].append(got[k][0]["song_s"] / med[k]["planning_s"][-1])
            print(f"{song.stem[:40]:40s} {med['this']['rtf'][-1]:8.1f}x {med['vs']['rtf'][-1]:7.1f}x "
                  f"{med['this']['rtf'][-1] / med['vs']['rtf'][-1]:6.2f} "
                  f"{1000 * med['this']['first_row_s'][-1]:11.0f} "
                  f"{1000 * med['vs']['first_row_s'][-1]:9.0f}", flush=True)
    print(f"\n{len(songs)} songs, {a.repeat} runs each, medians over the songs of each song's median:")
    for k, tree in trees.items():
        m = {f: statistics.median(v) for f, v in med[k].items()}
        print(f"  {k:5s} ({tree}): real-time factor {m['rtf']:.1f}x (lowest "
              f"{min(med[k]['rtf']):.1f}x), planning {1000 * m['planning_s']:.0f} ms, first row "
              f"{1000 * m['first_row_s']:.0f} ms (highest {1000 * max(med[k]['first_row_s']):.0f}), "
              f"set-up {1000 * m['setup_s']:.0f} ms")
    ratios = [x / y for x, y in zip(med["this"]["rtf"], med["vs"]["rtf"])]
    firsts = [y / x for x, y in zip(med["this"]["first_row_s"], med["vs"]["first_row_s"])]
    print(f"  this / vs, per song: real-time factor x{statistics.median(ratios):.2f} median "
          f"(x{min(ratios):.2f}-x{max(ratios):.2f}); first row x{statistics.median(firsts):.2f} "
          "sooner (median)")
    if a.keep:
        same = [s.stem for s in songs if (Path(a.keep) / "this" / f"{s.stem}.csv").read_bytes()
                == (Path(a.keep) / "vs" / f"{s.stem}.csv").read_bytes()]
        print(f"  files: {len(same)} of {len(songs)} identical" + "".join(
            f"\n  DIFFERS: {s.stem}" for s in songs if s.stem not in same))
    if a.tsv:
        with open(a.tsv, "w", encoding="utf-8") as f:
            f.write("tree\tsong\trun\tsong_s\tplanning_s\tfirst_row_s\tsetup_s\n")
            f.writelines(f"{k}\t{s}\t{r}\t{j['song_s']}\t{j['planning_s']}\t{j['first_row_s']}\t"
                         f"{j['setup_s']}\n" for k, s, r, j in runs)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
