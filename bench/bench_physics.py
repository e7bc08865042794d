"""Physics as the proof, at scale: every song of a folder planned, checked and replayed in
MuJoCo (full contact), per category: the check's frame F1 (its verdict's rule: the bodies,
spec section 2; an older tree's: the pad points) and the body rule's (an older tree reported
it apart, ``bodies``; nan before it), the physics' frame F1, wrong keys in physics, the
plans `check` fails, the planning's and the replay's real-time factors (simulated seconds
per wall second of ``simulate_trajectory``, and per second of this process's CPU time: on
a shared machine the wall clock measures the load as much as the code), the longest motor
saturation (ms).

    python bench/bench_physics.py [--corpus DIR] [--tree DIR] [--hand NAME] [--only S,..]
    python bench/bench_physics.py --speed-against TREE [--reps N] [--only S,..]

``--tree DIR``: the planner of another checkout (a worktree of an older revision: ``git
worktree add --detach /tmp/old REV``), so that two revisions are measured by the same
script; run it once per tree and compare the tables. Needs MuJoCo (the physics extra).
``--speed-against TREE``: the replay's speed side by side instead: every song planned once
(this checkout's planner), then replayed by this checkout and by ``TREE`` in fresh
processes, alternating, ``--reps`` times each; per song the median real-time factors (wall
and CPU) of both, their ratio, and whether the two verdicts are the same (physics F1, wrong
keys, notes hit, longest saturation).
Not a test: it prints what this machine measures.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "bench"))

from corpusargs import add_corpus_args, chosen_songs


def category(p: Path) -> str:
    return p.stem.split("_")[0]


# One replay in a fresh process whose ``planner`` is the tree in sys.argv[1]: the modules
# the replay imports are imported before the clock starts.
WORKER = r"""
import json, sys, time
sys.path.insert(0, sys.argv[1])
import mujoco
import planner.check, planner.planfile, planner.simulate.replay, planner.simulate.scores
from planner.simulate import simulate_trajectory
import planner
assert planner.__file__.startswith(sys.argv[1]), planner.__file__
t0, c0 = time.perf_counter(), time.process_time()
r = simulate_trajectory(sys.argv[2], sys.argv[3])
wall, cpu = time.perf_counter() - t0, time.process_time() - c0
print(json.dumps(dict(sim_s=r.duration_s, wall_s=wall, cpu_s=cpu, f1=r.play.f1,
                      wrong=len(r.play.wrong_keys), hit=r.play.notes_hit,
                      sat_ms=1000 * max(m.saturated_s for m in r.motors))))
"""


def replay_in(tree: Path, traj: Path, song: Path) -> dict:
    import json
    import os
    import subprocess

    env = {**os.environ, "PYTHONPATH": str(tree)}
    out = subprocess.run([sys.executable, "-c", WORKER, str(tree), str(traj), str(song)],
                         cwd=str(tree), env=env, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def speed_against(songs: list[Path], other: Path, reps: int, hand_name: str) -> int:
    """The replay's speed, this checkout against ``other`` (see the module docstring)."""
    from planner.hand.model import load_hand
    from planner.music.midi import load_song
    from planner.play import Planner, plan_song

    hand = load_hand(hand_name)
    pl = Planner(hand)
    trees = {"this": ROOT, "other": other.resolve()}
    print(f"this = {trees['this']}, other = {trees['other']}; {reps} reps each, interleaved\n")
    print("| song | sim s | RTF other | RTF this | ratio | CPU-RTF other | CPU-RTF this | "
          "CPU ratio | same verdict |")
    print("|---|---|---|---|---|---|---|---|---|")
    med: dict[str, list[float]] = defaultdict(list)
    with tempfile.TemporaryDirectory() as d:
        for p in songs:
            traj = Path(d) / f"{p.stem}.csv"
            plan_song(load_song(p), hand, str(traj), planner=pl)
            runs: dict[str, list[dict]] = {k: [] for k in trees}
            for _ in range(reps):
                for k, tree in trees.items():
                    runs[k].append(replay_in(tree, traj, p))
            f = {(k, c): statistics.median(r["sim_s"] / r[c] for r in v)
                 for k, v in runs.items() for c in ("wall_s", "cpu_s")}
            for key, v in f.items():
                med[f"{key[0]} {key[1]}"].append(v)
            verdict = [{k: r[k] for k in ("f1", "wrong", "hit", "sat_ms")} for r in
                       (runs["other"][0], runs["this"][0])]
            print(f"| {p.stem} | {runs['this'][0]['sim_s']:.2f} | {f['other', 'wall_s']:.1f} | "
                  f"{f['this', 'wall_s']:.1f} | {f['this', 'wall_s'] / f['other', 'wall_s']:.2f} "
                  f"| {f['other', 'cpu_s']:.1f} | {f['this', 'cpu_s']:.1f} | "
                  f"{f['this', 'cpu_s'] / f['other', 'cpu_s']:.2f} | "
                  f"{'yes' if verdict[0] == verdict[1] else f'NO {verdict}'} |", flush=True)
    m = {k: statistics.median(v) for k, v in med.items()}
    print(f"| **median** | | {m['other wall_s']:.1f} | {m['this wall_s']:.1f} | "
          f"{m['this wall_s'] / m['other wall_s']:.2f} | {m['other cpu_s']:.1f} | "
          f"{m['this cpu_s']:.1f} | {m['this cpu_s'] / m['other cpu_s']:.2f} | |")
    return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_corpus_args(ap)
    ap.add_argument("--speed-against", type=Path, default=None, metavar="TREE",
                    help="the replay's speed, this checkout against TREE, side by side")
    ap.add_argument("--reps", type=int, default=3, help="--speed-against: replays per tree")
    a = ap.parse_args()
    sys.path.insert(0, a.tree)
    from planner.check import check_trajectory
    from planner.hand.model import load_hand
    from planner.music.midi import load_song
    from planner.play import Planner, plan_song
    from planner.simulate import simulate_trajectory

    songs = chosen_songs(a)
    if not songs:
        return 2
    if a.speed_against is not None:
        return speed_against(songs, a.speed_against, a.reps, a.hand)
    hand = load_hand(a.hand)
    pl = Planner(hand)
    rows = []
    print(f"tree {a.tree}")
    print(f"{'song':40s} {'check F1':>8s} {'body F1':>8s} {'phys F1':>8s} {'wrong':>5s} "
          f"{'plan RTF':>8s} {'sim RTF':>7s} {'cpu RTF':>7s} {'sat ms':>6s} check")
    with tempfile.TemporaryDirectory() as d:
        for p in songs:
            out = str(Path(d) / "o.csv")
            song = load_song(p)
            plan = plan_song(song, hand, out, planner=pl)
            rep = check_trajectory(out, str(p))
            body = getattr(rep, "bodies", rep.play)  # (this tree: the verdict is the bodies')
            body_f1 = float("nan") if body is None or body.f1 is None else body.f1
            t0, c0 = time.perf_counter(), time.process_time()
            sim = simulate_trajectory(out, str(p))
            sim_s, cpu_s = time.perf_counter() - t0, time.process_time() - c0
            song_s = max(n.offset_s for n in song.notes)
            sat_ms = 1000.0 * max((m.saturated_s for m in sim.motors), default=0.0)
            row = (category(p), p.stem, rep.play.f1, sim.play.f1, len(sim.play.wrong_keys),
                   song_s / plan.planning_s, sim.duration_s / sim_s, body_f1, not rep.ok,
                   sim.duration_s / cpu_s, sat_ms)
            rows.append(row)
            print(f"{p.stem[:40]:40s} {row[2]:8.4f} {row[7]:8.4f} {row[3]:8.4f} {row[4]:5d} "
                  f"{row[5]:7.0f}x {row[6]:6.1f}x {row[9]:6.1f}x {row[10]:6.0f} "
                  f"{'FAIL' if row[8] else 'ok'}", flush=True)
    by = defaultdict(list)
    for r in rows:
        by[r[0]].append(r)
        by["(all)"].append(r)
    print(f"\n{'category':12s} {'songs':>5s} {'check F1':>8s} {'body F1':>8s} {'phys F1':>8s} "
          f"{'min phys':>8s} {'wrong':>6s} {'fails':>5s} {'plan RTF':>8s} {'sim RTF':>7s} "
          f"{'cpu RTF':>7s} {'sat ms':>6s}")
    for c, rs in sorted(by.items()):
        print(f"{c:12s} {len(rs):5d} {statistics.mean(r[2] for r in rs):8.4f} "
              f"{statistics.mean(r[7] for r in rs):8.4f} "
              f"{statistics.mean(r[3] for r in rs):8.4f} {min(r[3] for r in rs):8.4f} "
              f"{sum(r[4] for r in rs):6d} {sum(r[8] for r in rs):5d} "
              f"{statistics.median(r[5] for r in rs):7.0f}x "
              f"{statistics.median(r[6] for r in rs):6.1f}x "
              f"{statistics.median(r[9] for r in rs):6.1f}x {max(r[10] for r in rs):6.0f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
