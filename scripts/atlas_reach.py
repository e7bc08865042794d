"""Which keys a hand's fingers press with their bodies clear, over mount and wrist postures
(a measurement: the atlas's own rule, for any hand, one-DOF fingers included).

``scripts/body_reach.py`` asks single-finger IK for a press point and judges its body;
a finger of one degree of freedom (the Mk5's, the AGH's middle and ring:
``planner.play.arc``) cannot be put on a point, it presses where its arc comes down. This
script instead builds the hand's atlas (``planner.play.atlas.Atlas``, the planner's) for
each posture asked for: the mount (the rail's height ``--z`` over the white tops and its
distance ``--y`` in front of the keys, the hand file's ``[mount]``; its roll kept), the
wrist's flexion and deviation (``--flex``, ``--dev``, degrees, the ``[play]`` posture's;
reach 0: these hands have no reach axis) and the press depth, and counts, per finger, the
atlas samples (``dx`` every ``--kstep`` mm over the atlas's span) whose entry it keeps:
every pose found within the limits, the tip's path and the finger's bodies clear of every
other key and of the bed (``planner.play.fingerbody``, spec section 2). Each kept press is
counted (if it holds ``--force``; ``weak``: the kept presses that do not, among them every
press whose motors cannot drive the key down its travel with the pad's friction,
``planner.play.force.press_capacity_n``) in its key class:

* ``Wf``: a white key pressed in front of the black keys (y < their front edge);
* ``Wb``: a white key pressed between the black keys;
* ``B``: a black key;

on the keys C4..E4 (pitch classes 0-4: two whites with one black neighbour, one between
two, two blacks). ``pcs``: how many of those five pitch classes any finger presses (5: with
the rail, every key of the keyboard has a finger). One line per posture, the best first:

    python scripts/atlas_reach.py --hand agh --z=0.20,0.25 --y=-0.40 --flex=0,20 --dev=0

Measured and read in docs/history/2026-12-06-hands-bodies.md.
"""

from __future__ import annotations

import argparse
import itertools
import math
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from planner.hand.model import load_hand
from planner.hand.spec import PlayPosture
from planner.music import keyboard as kb
from planner.play.atlas import SPAN_M, STEP_M, Atlas

PITCH_CLASSES = (0, 1, 2, 3, 4)  # C, C#, D, D#, E
CLASSES = ("Wf", "Wb", "B")


def reach(hand, kstep: int, force_n: float
          ) -> tuple[dict[tuple[str, str], int], set[int], int]:
    """Per (finger, class) the atlas samples kept that press ``force_n``; the pitch classes
    some finger presses so; how many samples were kept but press less."""
    atlas = Atlas(hand)
    out = {(f, c): 0 for f in hand.fingers for c in CLASSES}
    weak = 0
    pcs = set()
    n = round(SPAN_M / STEP_M)
    for f in hand.fingers:
        i = hand.fingers.index(f)
        for pc, k in itertools.product(PITCH_CLASSES, range(-n, n + 1, kstep)):
            e = atlas.entry_at(f, pc, k)
            if e is None:
                continue
            if e.max_force_n < force_n:
                weak += 1
                continue
            pitch = 12 * 5 + pc
            if kb.is_black(pitch):
                c = "B"
            else:
                y = hand.tip_positions(atlas.full_q(e, "press", atlas.rail_for(f, pitch, k)))[i, 1]
                c = "Wf" if y < kb.BLACK_Y0_M else "Wb"
            out[(f, c)] += 1
            pcs.add(pc)
    return out, pcs, weak


def _floats(s: str) -> list[float]:
    return [float(v) for v in s.split(",")]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hand", default="mk5")
    ap.add_argument("--z", default="", help="the rail's heights over the white tops (m; "
                    "default the hand file's)")
    ap.add_argument("--y", default="", help="the rail's y (m, - in front of the keys; "
                    "default the hand file's)")
    ap.add_argument("--flex", default="0", help="wrist flexions (deg; + bends the palm down)")
    ap.add_argument("--dev", default="0", help="wrist deviations (deg; + radial)")
    ap.add_argument("--depth", type=float, default=0.006, help="press depth below the top (m)")
    ap.add_argument("--force", type=float, default=1.5, help="count a press only if it holds "
                    "this key force (N; 1.5: velocity 80, every note of the sample songs)")
    ap.add_argument("--kstep", type=int, default=3, help="count every kstep-th sample of dx")
    a = ap.parse_args()
    hand0 = load_hand(a.hand)
    T0 = hand0.T_world_root
    zs = _floats(a.z) if a.z else [float(T0[2, 3])]
    ys = _floats(a.y) if a.y else [float(T0[1, 3])]
    rows = []
    for z, y, flex, dev in itertools.product(zs, ys, _floats(a.flex), _floats(a.dev)):
        T = T0.copy()
        T[1, 3], T[2, 3] = y, z
        hand = hand0.mounted(T)
        hand.spec = replace(hand.spec, play_posture=PlayPosture(
            (0.0,), math.radians(flex), math.radians(dev), a.depth))
        try:
            got, pcs, weak = reach(hand, a.kstep, a.force)
        except ValueError as exc:  # (a wrist outside its travel)
            print(f"z {z:.3f} y {y:+.3f} flex {flex:+.1f} dev {dev:+.1f}: {exc}", flush=True)
            continue
        total = sum(got.values())
        rows.append((len(pcs), total, z, y, flex, dev, got, weak))
        print(_line(rows[-1], hand0.fingers), flush=True)
    print(f"--- best first (samples of dx every {a.kstep} mm over +-{SPAN_M * 1e3:.0f} mm, "
          f"pitch classes {PITCH_CLASSES})")
    for row in sorted(rows, key=lambda r: (-r[0], -r[1]))[:15]:
        print(_line(row, hand0.fingers))
    return 0


def _line(row, fingers) -> str:
    npcs, total, z, y, flex, dev, got, weak = row
    return (f"z {z:.4f} y {y:+.3f} flex {flex:+5.1f} dev {dev:+5.1f}: pcs {npcs} total "
            f"{total:3d} | " + " ".join(f"{f} " + "/".join(str(got[(f, c)]) for c in CLASSES)
                                        for f in fingers) + f" | weak {weak}")


if __name__ == "__main__":
    np.seterr(all="ignore")
    sys.exit(main())
