"""Why a hand's atlas has no entry where it has none: per play posture and finger, the
atlas samples (``dx`` every ``--kstep`` mm over the atlas's span, every pitch class) by
the rule that refuses them (``planner.play.atlassolve.Refusal``: no pose, the limits, the
tip's path, the pad facing up, the bodies), each solved again by the atlas's own steps
(``EntrySolver.refusal``), white and black keys apart; for the samples the body rule
refuses, the median and least depth any body reaches below another key's top inside
that key's footprint column (a key sounds from 5 mm) and into another key's box (the rule
allows 0.5 mm), and the column depth again with the pad sphere's centre over the press
point (``centred``); and the farthest the finger's tip reaches into the keyboard (y, mm: its
joints sampled uniformly within the planning limits, the arm in the posture; the white
keys' front is at 0, the black keys' at 60 mm).

    python bench/atlas_refusals.py [--hand default] [--fingers thumb,index] [--kstep 3]

Not a test: it prints what the atlas's rules decide (docs/history/2026-12-06-play-quality2.md).
"""

from __future__ import annotations

import argparse
import sys
from collections import Counter
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from planner.errors import InputError
from planner.hand.model import load_hand
from planner.music import keyboard as kb
from planner.play.atlas import SPAN_M, STEP_M, Atlas, posture_count
from planner.play.atlassolve import BODY_REFUSALS

WORKSPACE_SAMPLES = 20000  # joint configurations drawn per finger (seeded: same output)


def tip_reach_y_m(atlas: Atlas, finger: str, rng: np.random.Generator) -> float:
    """The farthest y the finger's tip reaches with its joints anywhere in their planning
    limits, the rest of the hand at the atlas's natural hand."""
    h = atlas.hand
    js = h.joint_slice(finger)
    lo, hi = h.plan_lower[js], h.plan_upper[js]
    i = h.fingers.index(finger)
    best = -np.inf
    for u in rng.random((WORKSPACE_SAMPLES, len(lo))):
        q = atlas.base.copy()
        q[js] = lo + u * (hi - lo)
        best = max(best, float(h.tip_positions(h.apply_couplings(q))[i, 1]))
    return best


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--hand", default="default")
    ap.add_argument("--fingers", default="", help="comma-separated (default: every finger)")
    ap.add_argument("--kstep", type=int, default=3, help="every this many grid samples (mm)")
    a = ap.parse_args(argv)
    try:
        hand = load_hand(a.hand)
    except (InputError, OSError, ValueError) as e:
        print(f"atlas_refusals: {e}", file=sys.stderr)
        return 2
    fingers = a.fingers.split(",") if a.fingers else list(hand.fingers)
    if a.kstep < 1 or any(f not in hand.fingers for f in fingers):
        print(f"atlas_refusals: fingers must be among {', '.join(hand.fingers)}, kstep >= 1",
              file=sys.stderr)
        return 2
    n = round(SPAN_M / STEP_M)
    rng = np.random.default_rng(0)
    print("posture finger key  samples  entry  reach limits tip_path pad_up body"
          "  column_mm(med/min)  box_mm(med/min)  centred_mm(med/min)  tip_y_max_mm")
    for posture in range(posture_count(hand)):
        atlas = Atlas(hand, posture=posture)
        for f in fingers:
            y_max = 1000 * tip_reach_y_m(atlas, f, rng)
            for black in (False, True):
                count: Counter = Counter()
                column, box, centred = [], [], []
                for pc in range(12):
                    if kb.is_black(60 + pc) is not black:
                        continue
                    for k in range(-n, n + 1, a.kstep):
                        v = atlas.refusal(f, pc, k)
                        if v is None:
                            continue
                        count[v.refusal.value if v.refusal else "entry"] += 1
                        if v.refusal not in BODY_REFUSALS:
                            continue
                        if not np.isnan(v.other_column_m):
                            column.append(1000 * v.other_column_m)
                            box.append(1000 * v.other_box_m)
                        if not np.isnan(v.centred_column_m):
                            centred.append(1000 * v.centred_column_m)
                cells = [count[c] for c in ("entry", "reach", "limits", "tip_path", "pad_up",
                                            "body")]
                depth = "  ".join(f"{np.median(d):6.1f}/{min(d):5.1f}" if d else f"{'-':>12}"
                                  for d in (column, box, centred))
                print(f"{posture:7d} {f:6s} {'B' if black else 'W':3s} {sum(count.values()):8d}"
                      f" {cells[0]:6d} {cells[1]:6d} {cells[2]:6d} {cells[3]:8d} {cells[4]:6d}"
                      f" {cells[5]:4d}  {depth}  {y_max:12.1f}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
