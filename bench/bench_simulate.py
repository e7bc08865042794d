"""The physics replay: how fast it runs, and how it agrees with the kinematic check.

    python bench/bench_simulate.py               # simulated seconds per wall second, 60 s song
    python bench/bench_simulate.py --speed --against /work/main   # every sample song in
                                                 # full contact, this tree and another one
                                                 # (a worktree of the old code) in one run,
                                                 # interleaved: real-time factors (median
                                                 # of --reps), physics F1, wrong keys,
                                                 # longest motor saturation, side by side
    python bench/bench_simulate.py --bodies      # every sample song: check's verdict (bodies) vs
                                                 # physics F1 and wrong keys (full contact)
    python bench/bench_simulate.py --agreement   # every sample song: kinematic vs physics F1
                                                 # (both contact models), notes that differ
    python bench/bench_simulate.py --notes       # pads contact, note by note: each note's
                                                 # share of the F1 difference and its cause,
                                                 # then each song's notes by cause
    python bench/bench_simulate.py --notes --contact full   # the same, full contact
    python bench/bench_simulate.py --catch-grid  # the default catch grid in physics, throw
                                                 # by throw (palm tilt, the ball at +150 ms)
    python bench/bench_simulate.py --catch-phases 10   # each feasible plan of that grid
                                                 # replayed with its ball arriving at 10
                                                 # phases of the physics' 1 ms step

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


# One replay in a fresh process whose ``planner`` is the tree in sys.argv[1] (the other
# side of --speed): the modules run_replay imports are imported before the clock starts.
_WORKER = r"""
import json, sys, time
sys.path.insert(0, sys.argv[1])
import mujoco
import planner.check, planner.planfile, planner.simulate.replay, planner.simulate.scores
from planner.simulate import simulate_trajectory
import planner
assert planner.__file__.startswith(sys.argv[1]), planner.__file__
t0, c0 = time.perf_counter(), time.process_time()
r = simulate_trajectory(sys.argv[2], sys.argv[3], contact=sys.argv[4])
wall, cpu = time.perf_counter() - t0, time.process_time() - c0
print(json.dumps(dict(sim_s=r.duration_s, wall_s=wall, cpu_s=cpu, loop_s=r.wall_s,
                      f1=r.play.f1, wrong=len(r.play.wrong_keys), hit=r.play.notes_hit,
                      notes=r.play.notes, sat_ms=1000 * max(m.saturated_s for m in r.motors))))
"""


def _replay_in(tree: Path, traj: Path, song: Path, contact: str) -> dict:
    import json
    import os
    import subprocess

    env = {**os.environ, "PYTHONPATH": str(tree)}
    out = subprocess.run([sys.executable, "-c", _WORKER, str(tree), str(traj), str(song),
                          contact],
                         cwd=str(tree), env=env, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def bench_speed_against(other: Path, reps: int, contact: str = "full") -> None:
    """Every sample song planned once (this tree's planner), then replayed (``contact``,
    full by default) by this tree and by ``other``, alternating, ``reps`` times each: the
    real-time factor (simulated s per wall s of ``simulate_trajectory``, its imports
    done; the CPU-time ratio beside it, less sensitive to a shared machine), median over
    the reps; the physics verdict of each (deterministic: the first rep's)."""
    trees = {"this": ROOT, "other": Path(other).resolve()}
    hand = planner.load_hand("default")
    songs = sorted((ROOT / "songs").glob("*.mid"))
    rows = {}
    with tempfile.TemporaryDirectory() as d:
        for song in songs:
            traj = Path(d) / f"{song.stem}.csv"
            planner.plan_song(planner.load_song(str(song)), hand, str(traj))
            runs = {k: [] for k in trees}
            for _ in range(reps):
                for k, tree in trees.items():
                    runs[k].append(_replay_in(tree, traj, song, contact))
            rows[song.stem] = runs
            print(f"{song.stem}: " + "; ".join(
                f"{k} {np.median([r['sim_s'] / r['wall_s'] for r in v]):.1f}x" for k, v in
                runs.items()), flush=True)
    print(f"\nthis = {trees['this']}, other = {trees['other']}; {reps} reps each, interleaved, "
          f"contact {contact}\n")
    print("| song | sim s | RTF other | RTF this | ratio | CPU-RTF other | CPU-RTF this | "
          "F1 other | F1 this | wrong other | wrong this | hit other | hit this | "
          "sat ms other | sat ms this |")
    print("|---|" + "---|" * 14)
    med = {"o": [], "t": [], "co": [], "ct": []}
    for name, runs in rows.items():
        o, t = runs["other"], runs["this"]
        rtf = lambda v, key: float(np.median([r["sim_s"] / r[key] for r in v]))
        ro, rt, co, ct = rtf(o, "wall_s"), rtf(t, "wall_s"), rtf(o, "cpu_s"), rtf(t, "cpu_s")
        for k, v in zip(("o", "t", "co", "ct"), (ro, rt, co, ct)):
            med[k].append(v)
        a, b = o[0], t[0]
        print(f"| {name} | {b['sim_s']:.2f} | {ro:.1f} | {rt:.1f} | {rt / ro:.2f} | {co:.1f} | "
              f"{ct:.1f} | {a['f1']:.4f} | {b['f1']:.4f} | {a['wrong']} | {b['wrong']} | "
              f"{a['hit']}/{a['notes']} | {b['hit']}/{b['notes']} | {a['sat_ms']:.0f} | "
              f"{b['sat_ms']:.0f} |")
    m = {k: float(np.median(v)) for k, v in med.items()}
    print(f"| **median** | | {m['o']:.1f} | {m['t']:.1f} | {m['t'] / m['o']:.2f} | "
          f"{m['co']:.1f} | {m['ct']:.1f} | | | | | | | | |")


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


def bench_bodies(hand_name: str = "default") -> None:
    """Every sample song: ``check``'s verdict (the body rule, spec section 2) beside the
    physics replay in full contact (frame F1, wrong keys), one plan each."""
    from planner.check import check_trajectory

    hand = planner.load_hand(hand_name)
    print("| song | check F1 (bodies) | wrong keys (check) | body bed hits "
          "| physics F1 (full) | wrong keys (physics) | wrong keys in check by: |")
    print("|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as d:
        for song in sorted((ROOT / "songs").glob("*.mid")):
            traj = Path(d) / f"{song.stem}.csv"
            planner.plan_song(planner.load_song(str(song)), hand, str(traj))
            p = check_trajectory(str(traj), str(song)).play
            full = simulate_trajectory(str(traj), str(song), contact="full")
            who: dict[str, int] = {}
            for w in p.wrong_presses:
                for ln in w.fingers:
                    who[ln] = who.get(ln, 0) + 1
            top = ", ".join(f"{k} {v}" for k, v in sorted(who.items(), key=lambda x: -x[1])[:3])
            print(f"| {song.stem} | {p.f1:.4f} | {len(p.wrong_presses)} | "
                  f"{len(p.body_bed_hits)} | {full.play.f1:.4f} | {len(full.play.wrong_keys)} | "
                  f"{top} |", flush=True)


def bench_notes(contact: str = "pads") -> None:
    from planner.simulate import run_replay
    from planner.simulate.compare import note_differences

    hand = planner.load_hand("default")
    summaries = []
    with tempfile.TemporaryDirectory() as d:
        for song in sorted((ROOT / "songs").glob("*.mid")):
            traj = Path(d) / f"{song.stem}.csv"
            planner.plan_song(planner.load_song(str(song)), hand, str(traj))
            r = run_replay(str(traj), str(song), contact=contact)
            diffs = note_differences(r)
            print(f"{song.stem}: kinematic F1 {r.report.kinematic_f1:.4f}, physics ({contact}) "
                  f"{r.report.play.f1:.4f}, {len(diffs)} notes or keys differ", flush=True)
            for x in diffs:
                what = f"note {x.note}" if x.note >= 0 else "wrong key"
                print(f"  {x.name:4s} @{x.onset_s:6.2f} s {what:9s} {x.lost_f1:+.4f}  {x.cause}; "
                      f"{'+'.join(x.fingers) or 'no finger'}, pad {x.pad_error_mm:.1f} mm off "
                      f"plan (dz {x.pad_dz_mm:+.1f})", flush=True)
            summaries.append(_by_kind(song.stem, r.report, diffs))
    print()
    for line in summaries:
        print(line)


def _by_kind(name: str, rep, diffs) -> str:
    """One markdown line: the song's differences by cause, note by note."""
    parts = []
    for kind in ("narrow", "wrong", "lifted", "timing"):
        xs = sorted((x for x in diffs if x.kind == kind), key=lambda x: x.onset_s)
        if xs:
            lost = sum(x.lost_f1 for x in xs)
            notes = ", ".join(f"{x.name}@{x.onset_s:.2f}"
                              + (f" ({'+'.join(x.fingers)})" if kind == "wrong" and x.fingers
                                 else "") for x in xs)
            planned = (f", {sum(x.plan_frames > 0 for x in xs)} with the plan's finger body on "
                       "the key" if kind == "wrong" and rep.contact == "full" else "")
            parts.append(f"**{kind}** {len(xs)} ({lost:.4f}{planned}): {notes}")
    return (f"* {name} (kinematic {rep.kinematic_f1:.4f}, physics {rep.play.f1:.4f}): "
            + ("; ".join(parts) or "no difference"))


def _catch_facts(r) -> str:
    """Why a catch is or is not held, from the plan and the physics: the palm's tilt
    from horizontal at the intercept (plan), the fingertips' smallest gap to the planned
    ball's surface in the last row (plan), the ball's distance from the palm centre 150 ms
    after the intercept and the last row it touches the hand (physics)."""
    rec, hand = r.record, r.hand
    meta = r.trajectory.metadata
    t_int = float(meta["intercept_t"])
    radius = float(r.scene.model.geom_size[r.scene.ball_geom][0])
    i = int(np.argmin(np.abs(rec.t_s - t_int)))
    T = hand.palm_pose(rec.q_ref[i])
    tilt = np.degrees(np.arccos(np.clip(T[2, 2], -1.0, 1.0)))
    Tend = hand.palm_pose(rec.q_ref[-1])
    ball_plan = Tend[:3, 3] + radius * Tend[:3, 2]
    gap = np.linalg.norm(hand.tip_positions(rec.q_ref[-1]) - ball_plan, axis=1) - radius
    j = int(np.argmin(np.abs(rec.t_s - (t_int + 0.15))))
    d150 = float(np.linalg.norm(rec.ball_m[j] - rec.palm_m[j]))
    touching = np.flatnonzero(rec.ball_contacts > 0)
    last = f"{rec.t_s[touching[-1]] - t_int:+.3f} s" if len(touching) else "never"
    return (f"palm tilt {tilt:.0f} deg, planned tips {gap.min() * 1000:.1f}-"
            f"{gap.max() * 1000:.1f} mm off the ball, ball {d150 * 1000:.0f} mm from the palm "
            f"centre at +150 ms, last touch {last} from the intercept")


def _grid_plans():
    """(angle deg, distance m, plan path) of each feasible plan of the default catch grid
    (angles 20-60 deg x distances 1-3 m, tests/test_catch.py's grid, height 0, tennis
    ball), planned into a temporary directory; the infeasible ones are named and skipped."""
    with tempfile.TemporaryDirectory() as d:
        for a in range(20, 61, 10):
            for dist in (1.0, 1.5, 2.0, 2.5, 3.0):
                path = Path(d) / f"c{a}_{dist}.csv"
                res = planner.plan_catch(float(a), dist, 0.0, "default", str(path))
                if not res.feasible:
                    print(f"{a} deg {dist} m: infeasible plan, not simulated", flush=True)
                    continue
                yield a, dist, path


def bench_catch_grid() -> None:
    """Angles 20-60 deg x distances 1-3 m (tests/test_catch.py's grid), height 0, tennis
    ball: each feasible plan in physics."""
    from planner.simulate import run_replay

    held = feasible = 0
    for a, dist, path in _grid_plans():
        r = run_replay(str(path))
        c = r.report.catch
        feasible += 1
        held += c.held
        print(f"{a} deg {dist} m: {'held' if c.held else 'NOT held'}, peak contact "
              f"{c.peak_contact_force_n:.1f} N, {c.end_distance_m * 1000:.1f} mm from "
              f"the palm centre at the end; {_catch_facts(r)}", flush=True)
    print(f"held {held} of {feasible} feasible plans")


def bench_catch_phases(n: int) -> None:
    """The default catch grid's feasible plans, each replayed ``n`` times with its ball
    launched k/n of one physics step later along its flight (``planner.simulate.phase``):
    the same rows, the ball's first contact at another depth into the palm (its rebound,
    0 to ~1/4 of its normal speed, is set by that phase). Per throw: held (H) or not (.)
    at each phase, and the ball's largest distance from the palm centre from +150 ms."""
    from planner.simulate import run_replay
    from planner.simulate.phase import ball_advanced
    from planner.simulate.scene import TIMESTEP_S
    from planner.trajfile import read_trajectory

    totals = np.zeros(n, dtype=int)
    feasible = 0
    for a, dist, path in _grid_plans():
        feasible += 1
        tr = read_trajectory(str(path))
        marks, far = [], []
        for k in range(n):
            r = run_replay(ball_advanced(tr, k / n * TIMESTEP_S))
            c, rec = r.report.catch, r.record
            after = rec.t_s >= c.held_from_s
            far.append(float(np.max(np.linalg.norm(rec.ball_m - rec.palm_m, axis=1)[after])))
            marks.append("H" if c.held else ".")
            totals[k] += c.held
        print(f"{a} deg {dist} m: {''.join(marks)}  held at {marks.count('H')} of {n} "
              f"phases; ball at most {min(far) * 1000:.0f}-{max(far) * 1000:.0f} mm "
              "from the palm centre from +150 ms", flush=True)
    print(f"held per phase (of {feasible}): {' '.join(str(x) for x in totals)}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--agreement", action="store_true",
                    help="kinematic vs physics F1 on every sample song")
    ap.add_argument("--notes", action="store_true",
                    help="pads contact: every note's share of the F1 difference")
    ap.add_argument("--bodies", action="store_true",
                    help="check's body rule vs physics (full contact) on every sample song")
    ap.add_argument("--hand", default="default", help="--bodies: the hand")
    ap.add_argument("--catch-grid", action="store_true", help="the default catch grid")
    ap.add_argument("--catch-phases", type=int, metavar="N", default=0,
                    help="the default catch grid replayed at N phases of the physics' step")
    ap.add_argument("--speed", action="store_true",
                    help="every sample song, this tree beside --against's, in one run")
    ap.add_argument("--against", type=Path, default=None, metavar="TREE",
                    help="--speed: the other tree (a worktree of the old code)")
    ap.add_argument("--reps", type=int, default=3, help="--speed: replays per song and tree")
    ap.add_argument("--contact", choices=("full", "pads"), default="pads",
                    help="--notes: the contact model (default pads); --speed: (default full)")
    a = ap.parse_args()
    sys.path.insert(0, str(ROOT / "bench"))
    if a.speed:
        bench_speed_against(a.against if a.against is not None else ROOT, a.reps,
                            a.contact if "--contact" in sys.argv else "full")
    elif a.agreement:
        bench_agreement()
    elif a.bodies:
        bench_bodies(a.hand)
    elif a.notes:
        bench_notes(a.contact)
    elif a.catch_grid:
        bench_catch_grid()
    elif a.catch_phases > 0:
        bench_catch_phases(a.catch_phases)
    else:
        bench_speed()


if __name__ == "__main__":
    main()
