"""Two hands against one, per piece of a two-hand corpus, in one run: each piece planned by
one hand (``play``'s default: the upper part) and by two (``play --hands 2``), each plan
checked (frame F1 against the whole song, both parts: what a listener hears; the one-hand
plan also against its own part, ``1h own``, as ``check`` judges it) and replayed
in MuJoCo (full contact; ``--no-physics`` to skip): check F1, physics F1, wrong keys,
collisions between the hands (check's bodies, physics' contacts), notes per hand, notes
left out (and, after the table, every note left out by its hand and reason), the way
kept (``way``: ``R``/``L`` the right or left hand first (``Rs``/``Ls``: its room settled), ``RA`` the right hand alone, the
left one given what it leaves out; ``+``: then the first hand planned again with what the
second left out), the planning's real-time factor (after set-up; one ``Planner`` / ``PairPlanner``
for every piece, as ``batch`` plans).

    python bench/two_hands.py [--corpus DIR] [--only S] [--no-physics]

Not a test: it prints what this machine measures.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from collections import Counter
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RATE_HZ = 100.0  # plan_two_hands' default rate (frames of music: a note's length at it)


WAY_CODES = {"right first": "R", "left first": "L", "right alone": "RA",
             "right first settled": "Rs", "left first settled": "Ls"}


def way_code(way: str) -> str:
    """The kept way's short name (the module docstring)."""
    return WAY_CODES.get(way.removesuffix(" back"), way) + ("+" if way.endswith(" back") else "")


def set_up():
    """The one-hand ``Planner`` and the ``PairPlanner`` (one each for every piece), timed."""
    from planner.hand.model import load_hand
    from planner.play import Planner
    from planner.play.twohands import PairPlanner

    t0 = time.perf_counter()
    one = Planner(load_hand("default"))
    one_setup = time.perf_counter() - t0
    t0 = time.perf_counter()
    pp = PairPlanner(load_hand("default-left"), load_hand("default"))
    two_setup = time.perf_counter() - t0
    print(f"set-up: one hand {one_setup:.1f} s, two hands {two_setup:.1f} s; rail gap "
          f"{pp.gap.rail_gap_m * 1000:.1f} mm, key gap {pp.gap.key_gap_m * 1000:.1f} mm")
    return one, pp


def one_hand_row(p: Path, whole, one, d: str, simulate) -> dict:
    """The piece's upper part planned by one hand, checked against its part and against
    the whole song, replayed against the whole song."""
    from planner.check import check_trajectory
    from planner.music.midi import load_song
    from planner.play import plan_song
    from planner.trajfile import read_trajectory

    upper = load_song(p)
    out1 = str(Path(d) / "one.csv")
    plan1 = plan_song(upper, one.hand, out1, planner=one)
    own1 = check_trajectory(out1, upper).play.f1  # (against its part)
    # (against every part, what is heard: the same rows, the whole song's count)
    tr1 = read_trajectory(out1)
    tr1 = replace(tr1, metadata={**tr1.metadata, "notes": len(whole.notes)})
    chk1 = check_trajectory(tr1, whole)
    ph1 = simulate(tr1, whole) if simulate is not None else None
    return {"own1": own1, "chk1": chk1.play.f1,
            "phy1": ph1.play.f1 if ph1 else float("nan"),
            "wr1": len(ph1.play.wrong_keys) if ph1 else 0,
            "rtf1": max(n.offset_s for n in upper.notes) / plan1.planning_s}


def two_hand_row(p: Path, whole, pp, d: str, simulate, reasons: Counter, lost: Counter) -> dict:
    """The whole piece planned by two hands, checked and replayed; ``reasons`` and
    ``lost`` count its notes left out and their frames by hand and reason."""
    from planner.check import check_trajectory
    from planner.play.twohands import plan_two_hands

    out2 = str(Path(d) / "two.csv")
    plan2 = plan_two_hands(whole, pp, out2, song_name=p.name)
    chk2 = check_trajectory(out2, whole)
    ph2 = simulate(out2, whole) if simulate is not None else None
    for i, s in plan2.left_out():
        reasons[(plan2.assignment.hand[i], s.reason.value)] += 1
        lost[(plan2.assignment.hand[i], s.reason.value)] += round(whole.notes[i].duration_s
                                                                  * RATE_HZ)
    return {"chk2": chk2.play.f1, "phy2": ph2.play.f1 if ph2 else float("nan"),
            "wr2": len(ph2.play.wrong_keys) if ph2 else 0,
            "coll": chk2.gap.collision_rows + (len(ph2.touches) if ph2 else 0),
            "L": len(plan2.notes_of[0]), "R": len(plan2.notes_of[1]),
            "out": len(plan2.left_out()),
            "rtf2": max(n.offset_s for n in whole.notes) / plan2.planning_s,
            "gap": chk2.gap.least_m * 1000, "ok": chk2.ok, "way": way_code(plan2.way)}


def print_row(r: dict) -> None:
    print(f"{r['piece'][:22]:22s} {r['notes']:5d} | {r['own1']:6.4f} {r['chk1']:6.4f} {r['phy1']:6.4f} "
          f"{r['wr1']:3d} {r['rtf1']:4.0f}x | {r['chk2']:6.4f} {r['phy2']:6.4f} "
          f"{r['wr2']:3d} {r['coll']:4d} {r['L']:4d} {r['R']:4d} {r['out']:4d} "
          f"{r['rtf2']:4.0f}x {r['gap']:6.1f} {r['way']:>3s} "
          f"{'ok' if r['ok'] else 'FAIL'}",
          flush=True)


def print_summary(rows: list[dict], reasons: Counter, lost: Counter) -> None:
    """The means (RTF: medians), the notes left out by hand and reason, the lowest F1."""
    def mean(k):
        return statistics.mean(r[k] for r in rows)

    print(f"{'(mean; RTF median)':22s} {'':5s} | {mean('own1'):6.4f} {mean('chk1'):6.4f} {mean('phy1'):6.4f} "
          f"{sum(r['wr1'] for r in rows):3d} "
          f"{statistics.median(r['rtf1'] for r in rows):4.0f}x | {mean('chk2'):6.4f} "
          f"{mean('phy2'):6.4f} {sum(r['wr2'] for r in rows):3d} "
          f"{sum(r['coll'] for r in rows):4d} {'':4s} {'':4s} "
          f"{sum(r['out'] for r in rows):4d} "
          f"{statistics.median(r['rtf2'] for r in rows):4.0f}x")
    print("left out (two hands), by hand and reason: " + ", ".join(
        f"{h} {why} {k}" for (h, why), k in sorted(reasons.items(), key=lambda x: -x[1])))
    print("their frames of music (at 100 Hz): " + ", ".join(
        f"{h} {why} {k}" for (h, why), k in sorted(lost.items(), key=lambda x: -x[1])))
    print(f"lowest physics F1: one hand {min(r['phy1'] for r in rows):.4f}, two hands "
          f"{min(r['phy2'] for r in rows):.4f}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--corpus", default="/work/shared/corpus2h")
    ap.add_argument("--only", default=None, help="only pieces whose name holds this")
    ap.add_argument("--no-physics", action="store_true")
    a = ap.parse_args()
    sys.path.insert(0, str(ROOT))
    from planner.music.midi import load_song

    simulate = None
    if not a.no_physics:
        from planner.simulate import simulate_trajectory as simulate
    songs = sorted(Path(a.corpus).glob("*.mid"))
    if a.only:
        songs = [s for s in songs if a.only in s.stem]
    one, pp = set_up()
    print(f"{'piece':22s} {'notes':>5s} | {'1h own':>6s} {'1h chk':>6s} {'1h phy':>6s} {'wr':>3s} "
          f"{'RTF':>5s} | {'2h chk':>6s} {'2h phy':>6s} {'wr':>3s} {'coll':>4s} "
          f"{'L':>4s} {'R':>4s} {'out':>4s} {'RTF':>5s} {'gap mm':>6s} way check")
    rows = []
    reasons: Counter = Counter()
    lost: Counter = Counter()
    with tempfile.TemporaryDirectory() as d:
        for p in songs:
            whole = load_song(p, every_part=True)
            r = {"piece": p.stem, "notes": len(whole.notes),
                 **one_hand_row(p, whole, one, d, simulate),
                 **two_hand_row(p, whole, pp, d, simulate, reasons, lost)}
            rows.append(r)
            print_row(r)
    if rows:
        print_summary(rows, reasons, lost)
    return 0


if __name__ == "__main__":
    sys.exit(main())
