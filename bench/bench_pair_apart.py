"""Two-hand files made without a two-hand planner, to measure what ``check`` and
``simulate`` find in them: each track of a two-hand MIDI file (corpus2h: track 0 the right
hand, track 1 the left) planned alone by the one-hand planner, the left on ``default-left``
and the right on ``default``, each from a rest pose of its own on the rail (``REST_RAIL_M``:
the one-hand planner's rest is at middle C, where two hands would overlap), and the two
plans written as one version-3 file by ``planner.pairfile.PairWriter`` on a common clock
(the later start sets it; each hand holds its first row before its own start and its last
row after its end). Neither plan knows the other hand: this is the baseline a two-hand
planner is measured against, not a plan to play.

    python bench/bench_pair_apart.py OUT_DIR SONG.mid [SONG.mid ...] [--no-physics]

Per song one JSON line: rows; check's frame F1 (both hands), notes hit, wrong presses, each
hand's notes hit by its own bodies, the least distance between the hands, the collisions
and their rows, the check's time; and the physics' (full contact) F1, wrong keys, contacts
between the hands, each hand's notes that sound, the replay's time. Not a test: it prints
what this machine measures.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

RATE_HZ = 100.0
REST_RAIL_M = {"left": -0.35, "right": 0.35}  # each hand's rest on the rail (m), apart
TRACKS = {"left": 1, "right": 0}  # corpus2h's tracks (its README)


def write_pair(song_path: Path, out: Path, hands, planners) -> Path:
    """The song's two tracks planned apart and written as one two-hand file."""
    from planner.music.midi import load_song
    from planner.pairfile import PairWriter
    from planner.play.stream import plan_song
    from planner.trajfile import song_start_s

    whole = load_song(song_path, every_part=True)
    index = {(n.pitch, round(n.onset_s, 6)): i for i, n in enumerate(whole.notes)}
    trs, notes_of = [], []
    for hand, planner in zip(hands, planners):
        part = load_song(song_path, track=TRACKS[hand.side])
        trs.append(plan_song(part, hand, planner=planner).trajectory)
        notes_of.append([index[(n.pitch, round(n.onset_s, 6))] for n in part.notes])
    start = max(song_start_s(tr.metadata) for tr in trs)
    lead = [round((start - song_start_s(tr.metadata)) * RATE_HZ) for tr in trs]
    rows = max(len(tr.t_s) + k for tr, k in zip(trs, lead))
    qs = []
    for tr, k in zip(trs, lead):
        q = np.concatenate([np.repeat(tr.q[:1], k, axis=0), tr.q])
        qs.append(np.concatenate([q, np.repeat(q[-1:], rows - len(q), axis=0)]))
    left_out = sorted((ix[x["note"]], x) for tr, ix in zip(trs, notes_of)
                      for x in tr.end.get("left_out", []))
    out_idx = {i for i, _ in left_out}
    path = out / f"{song_path.stem}.csv"
    w = PairWriter(str(path), hands, {
        "task": "play", "rate_hz": RATE_HZ, "song": song_path.name, "notes": len(whole.notes),
        "track": None, "channel": None, "transpose": False, "song_start_s": start})
    w.write_rows(np.arange(rows) / RATE_HZ, qs[0], qs[1])
    w.close({"notes": len(whole.notes), "played": len(whole.notes) - len(out_idx),
             "left_out": [{**x, "note": i} for i, x in left_out]},
            {f"{h.side}.": sorted(set(ix) - out_idx) for h, ix in zip(hands, notes_of)})
    return path


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out")
    ap.add_argument("songs", nargs="+")
    ap.add_argument("--no-physics", action="store_true")
    a = ap.parse_args(argv)
    from planner.check import check_trajectory
    from planner.hand.model import load_hand
    from planner.play.stream import Planner

    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    hands = (load_hand("default-left"), load_hand("default"))
    planners = []
    for h in hands:
        p = Planner(h)
        p.rest_q = p.rest_q.copy()
        p.rest_q[h.joint_names.index("rail")] = REST_RAIL_M[h.side]
        planners.append(p)
    for song in map(Path, a.songs):
        path = write_pair(song, out, hands, planners)
        t0 = time.perf_counter()
        rep = check_trajectory(str(path), str(song), replay=False)
        row = {"song": song.stem, "rows": rep.rows, "check_f1": round(rep.play.f1, 4),
               "hit": f"{rep.play.notes_hit}/{rep.play.notes}",
               "wrong": len(rep.play.wrong_presses),
               "hit_per_hand": [f"{h.play.notes_hit}/{h.play.notes}" for h in rep.hands],
               "least_mm": round(rep.gap.least_m * 1000, 1),
               "collisions": len(rep.gap.collisions), "collision_rows": rep.gap.collision_rows,
               "check_s": round(time.perf_counter() - t0, 2)}
        if not a.no_physics:
            from planner.simulate import simulate_trajectory

            t0 = time.perf_counter()
            sim = simulate_trajectory(str(path), str(song))
            row.update(physics_f1=round(sim.play.f1, 4), physics_wrong=len(sim.play.wrong_keys),
                       touches=len(sim.touches),
                       sound_per_hand=[f"{h.notes_hit}/{h.notes}" for h in sim.hands],
                       simulate_s=round(time.perf_counter() - t0, 1))
        print(json.dumps(row), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
