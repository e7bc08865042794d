"""Where `check`'s frames are lost, note by note, summed by cause: every song of a folder
planned and checked (the body rule's key replay, `check`'s own rows), and each note's
frames without its key down attributed to

* ``left out: <reason>`` (the plan's self-check names the note skipped: all its frames);
* ``late: <cause>`` (the frames before its key first goes down), the cause read from the
  rows around the press: the arm's reach axis moving (``posture``), else the rail moving
  (``rail``), else its own key still up from the note before on it (``repeat``), else the
  key held by another finger or link just before (``takeover``), else the pressing finger
  holding another key within ``LOOK_S`` before (``finger move``), else ``descent``;
* ``early: <cause>`` (the frames after its key last comes up, before the note's end): the
  reach axis moving between the key-up and the note's end (``posture``), else the rail
  (``rail``), else the next note on the same key starting within ``LOOK_S`` of the end
  (``repeat``: the key re-arms), else the finger pressing another key before the end
  (``finger move``), else ``other``;
* ``gap`` (frames up between the first and last frame down).

The frames of ``early: posture`` are split by the reach axis's move after the key-up
(``posture_phases``): before it starts (the lift, and the other fingers' lifts it waits
for), while it moves (the arm), after it is still (the descents onto the new keys, and a
note that would have sounded past them); printed below the table.

    python bench/frame_losses.py [--corpus DIR] [--tree DIR] [--hand NAME] [--only S,..]
        [--notes]

``--notes``: one line per note that loses frames. Precision is 1.0 on the corpus (no wrong
key), so the frames lost are the recall lost, in frames. Not a test: it prints what the
rows hold.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from collections import defaultdict
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "bench"))

from corpusargs import add_corpus_args, chosen_songs

LOOK_S = 0.1  # s: how far before a press (after a release) the rows are read for its cause
# (a finger's move between keys takes 30-155 ms on the default hand: design/play.md)
MOVE_EPS = 1e-6  # (m) a change of the rail or the reach axis between rows that is a move


def moving(q: np.ndarray, j: int | None, r0: int, r1: int) -> bool:
    """Whether joint ``j`` changes between rows ``r0`` and ``r1`` (inclusive)."""
    if j is None:
        return False
    r0, r1 = max(0, r0), min(len(q) - 1, r1)
    return r1 > r0 and float(np.ptp(q[r0:r1 + 1, j])) > MOVE_EPS


def late_cause(rp, q, arm, key, r_on, r_down, period_s) -> str:
    look = round(LOOK_S / period_s)
    rail, reach = arm
    if moving(q, reach, r_on - look, r_down):
        return "posture"
    if moving(q, rail, r_on - look, r_down):
        return "rail"
    if r_on > 0 and rp.down[r_on - 1, key]:
        return "repeat"
    who = int(rp.finger[r_down, key])
    before = rp.finger[max(0, r_on - look):r_on, key]
    if np.any((before >= 0) & (before != who)):
        return "takeover"
    held = rp.finger[max(0, r_on - look):r_down]
    if np.any(np.delete(held, key, axis=1) == who):
        return "finger move"
    return "descent"


def early_cause(rp, q, arm, key, r_up, r_end, next_on_s, t_end_s, period_s) -> str:
    look = round(LOOK_S / period_s)
    rail, reach = arm
    who = int(rp.finger[r_up - 1, key])
    if moving(q, reach, r_up - 1, r_end):
        return "posture"
    if moving(q, rail, r_up - 1, r_end):
        return "rail"
    if next_on_s is not None and next_on_s <= t_end_s + LOOK_S:
        return "repeat"
    after = rp.finger[r_up:min(len(q), r_end + look)]
    if np.any(np.delete(after, key, axis=1) == who):
        return "finger move"
    return "other"


POSTURE_PHASES = ("before the arm", "the arm moving", "after the arm")


def posture_phases(q: np.ndarray, reach: int, r_up: int) -> tuple[int, int]:
    """The reach axis's move after row ``r_up`` (a key's first row up): its first row
    away from where it was in the row before, and its first row at its end (still in the
    row after); rows before the first are ``POSTURE_PHASES[0]``, from the first to before
    the end ``[1]``, from the end on ``[2]``."""
    pos = q[:, reach]
    r0 = max(0, r_up - 1)
    away = np.flatnonzero(np.abs(pos[r0:] - pos[r0]) > MOVE_EPS)
    if not len(away):
        return len(q), len(q)
    first = r0 + int(away[0])
    still = np.flatnonzero(np.abs(np.diff(pos[first:])) <= MOVE_EPS)
    return first, first + int(still[0]) if len(still) else len(q)


def frame_weights(rp) -> np.ndarray:
    """Per row, the frame F1 a key up that should be down costs there: (1 - F1) shared
    by the row's keys missing (so the weights of a song sum to its frames times 1 - F1)."""
    from planner.check.criteria import frame_scores

    f1 = frame_scores(rp.expected, rp.down)[2]
    fn = np.sum(rp.expected & ~rp.down, axis=1)
    return np.divide(1.0 - f1, fn, out=np.zeros(len(f1)), where=fn > 0)


def song_losses(rp, notes, skipped: dict, arm, show: bool, name: str) -> dict:
    """{cause: [notes, key-frames up, frames of F1 lost]} of one song's rows ``rp``
    (check's Replay)."""
    t, q = rp.t_s, rp.q
    w = frame_weights(rp)
    period_s = float(np.median(np.diff(t)))
    out: dict[str, list] = defaultdict(lambda: [0, 0, 0.0])
    next_on: dict[int, float | None] = {}
    by_key: dict[int, list[int]] = defaultdict(list)
    for i, n in enumerate(notes):
        by_key[n.pitch].append(i)
    for idx in by_key.values():
        for a, b in zip(idx, idx[1:] + [None]):
            next_on[a] = None if b is None else notes[b].onset_s
    for i, n in enumerate(notes):
        key = n.pitch - 21
        k0, k1 = (int(np.searchsorted(t, s, side="left")) for s in (n.onset_s, n.offset_s))
        up = ~rp.down[k0:k1, key]
        col = ~up
        parts: list[tuple[str, int, int]] = []  # (cause, first row, end row) of the note's
        if i in skipped:
            parts.append((f"left out: {skipped[i]}", k0, k1))
        elif not col.any():
            parts.append(("never down", k0, k1))
        else:
            first = int(np.argmax(col))
            last = len(col) - 1 - int(np.argmax(col[::-1]))
            if first:
                c = late_cause(rp, q, arm, key, k0, k0 + first, period_s)
                parts.append((f"late: {c}", k0, k0 + first))
            if last < len(col) - 1:
                c = early_cause(rp, q, arm, key, k0 + last + 1, k1 - 1, next_on[i],
                                n.offset_s, period_s)
                parts.append((f"early: {c}", k0 + last + 1, k1))
            parts.append(("gap", k0 + first, k0 + last + 1))
        shown = []
        for c, r0, r1 in parts:
            rows = np.arange(r0, r1)[up[r0 - k0:r1 - k0]]
            if not len(rows):
                continue
            out[c][0] += 1
            out[c][1] += len(rows)
            out[c][2] += float(w[rows].sum())
            if c == "early: posture":
                first, end = posture_phases(q, arm[1], r0)
                for phase, part in zip(POSTURE_PHASES, (rows[rows < first],
                                                        rows[(rows >= first) & (rows < end)],
                                                        rows[rows >= end])):
                    out[f"(posture: {phase})"][1] += len(part)
                    out[f"(posture: {phase})"][2] += float(w[part].sum())
            shown.append(f"{c} {len(rows)}")
        if show and shown:
            print(f"  {name} note {i} {n.pitch} {n.onset_s:.3f}-{n.offset_s:.3f}s "
                  f"({k1 - k0} frames): " + ", ".join(shown))
    out["(song frames)"][1] += len(t)
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_corpus_args(ap)
    ap.add_argument("--notes", action="store_true", help="one line per note losing frames")
    a = ap.parse_args()
    sys.path.insert(0, a.tree)
    from planner.check import check_trajectory
    from planner.hand.model import load_hand
    from planner.music.midi import load_song
    from planner.planfile import read_plan
    from planner.play import Planner, plan_song

    songs = chosen_songs(a)
    if not songs:
        return 2
    hand = load_hand(a.hand)
    pl = Planner(hand)
    arm = (hand.index.get("rail"), hand.index.get("reach"))
    total: dict[str, list] = defaultdict(lambda: [0, 0, 0.0])
    print(f"tree {a.tree}")
    with tempfile.TemporaryDirectory() as d:
        for p in songs:
            out = str(Path(d) / "o.csv")
            song = load_song(p)
            plan = plan_song(song, hand, out, planner=pl)
            rep = check_trajectory(out, str(p))
            skipped = {s.note: s.reason.value for s in plan.verdict.skipped}
            notes = read_plan(out).song_notes(song)  # (in the file's time)
            res = song_losses(rep.replay, notes, skipped, arm, a.notes, p.stem)
            lost = sum(v[2] for c, v in res.items() if not c.startswith("("))
            keyf = sum(v[1] for c, v in res.items() if not c.startswith("("))
            res["(expected)"][1] += round(plan.fingering.expected_loss_frames)
            print(f"{p.stem[:40]:40s} check F1 {rep.play.f1:.4f}  F1 frames lost {lost:6.1f}  "
                  f"key-frames {keyf} (programme {plan.fingering.expected_loss_frames:.0f})  "
                  + "  ".join(f"{c} {v[2]:.1f}" for c, v in
                              sorted(res.items(), key=lambda x: -x[1][2])
                              if not c.startswith("(")), flush=True)
            for c, v in res.items():
                total[c] = [x + y for x, y in zip(total[c], v)]
    lost = sum(v[2] for c, v in total.items() if not c.startswith("("))
    print(f"\n{'cause':28s} {'notes':>6s} {'key-frames':>10s} {'F1 frames':>9s} {'share':>6s}")
    for c, (k, f, fw) in sorted(total.items(), key=lambda x: -x[1][2]):
        if not c.startswith("("):
            print(f"{c:28s} {k:6d} {f:10d} {fw:9.1f} {fw / max(1e-9, lost):6.1%}")
    frames = total["(song frames)"][1]
    keyf = sum(v[1] for c, v in total.items() if not c.startswith("("))
    print(f"{'(key-frames lost)':28s} {'':6s} {keyf:10d}   the programme expected "
          f"{total['(expected)'][1]}")
    print(f"{'(all lost)':28s} {'':6s} {'':10s} {lost:9.1f}   of {frames} frames "
          f"(1 - F1 over the rows, all songs: {lost / max(1, frames):.4f})")
    for name in POSTURE_PHASES:
        _, f, fw = total[f"(posture: {name})"]
        print(f"{'early: posture, ' + name:34s} {f:10d} {fw:9.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
