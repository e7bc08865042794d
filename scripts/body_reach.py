"""Where a hand's fingers can press a key as bodies, from one arm posture (a measurement).

For each mount (the rail's y and height over the keyboard) and wrist posture (flexion,
deviation) asked for, and each finger, counts the press points at which the finger's body
(``planner.play.fingerbody``: its pad sphere and segment capsules, the physics replay's
shapes) presses the key the way the physics replay's keys allow:

* the pad point at ``DEPTH_M`` below the key's top (the spec's key-down depth, 5 mm, plus
  the seed's 1 mm precision): the kinematic check's press;
* the body's lowest point over the key at most ``BED_EXCESS_M`` past the key bed (10 mm):
  a finger whose end reaches further is held up by the bed before its pad point is down;
* every other key pushed at most ``OTHER_KEY_M`` (half the key-down depth: it does not
  sound).

Press points: key D4 (a white key between two black keys) in front of the black keys
(y 6-48 mm, every 6 mm), C4 (a white key beside one black key) anywhere along it (y 6-138
mm, every 12 mm), C#4 (a black key) along its exposed length (y 66-138 mm, every 8 mm);
each at the finger's natural place over the key and 15 mm either side. Single-finger IK
(``planner.ik``), the arm held at the posture. Prints one line per posture: per finger,
the counts on D / C / C#.

    python scripts/body_reach.py --y=-0.40,-0.48 --z=0.17,0.10 --flex=0.1 --dev=-0.5,-0.1

(``--flex``/``--dev`` omitted: the atlas's fitted natural wrist). Measured and read in
docs/history/play-second-design.md, "One arm posture cannot press the white keys' front with
every finger".
"""

from __future__ import annotations

import argparse
import itertools
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from planner.hand.model import load_hand
from planner.ik import PressTarget
from planner.music import keyboard as kb
from planner.play.atlas import Atlas
from planner.play.fingerbody import FingerBodies

DEPTH_M = kb.DOWN_DEPTH_M + 0.001  # key-down depth (spec) + the seed's 1 mm precision
BED_EXCESS_M = 0.001  # the body past the key bed at most the seed's precision
OTHER_KEY_M = kb.DOWN_DEPTH_M / 2  # another key pushed at most half its key-down depth
KEYS = ((62, np.arange(0.006, 0.049, 0.006)), (60, np.arange(0.006, 0.139, 0.012)),
        (61, np.arange(0.066, 0.139, 0.008)))
SIDE_M = (-0.015, 0.0, 0.015)  # press places: the finger's natural place and either side


def reach(hand, flex: float | None, dev: float | None) -> dict[tuple[str, int], int]:
    """Per (finger, pitch) the press points whose body passes (see the module docstring)."""
    atlas, bodies = Atlas(hand), FingerBodies(hand)
    base = atlas.base.copy()
    for name, v in (("wrist_flex", flex), ("wrist_dev", dev)):
        if v is not None:
            base[hand.index[name]] = v
    base = hand.apply_couplings(base)
    tips = hand.tip_positions(base)
    out = {}
    for i, f in enumerate(hand.fingers):
        dx = float(tips[i, 0] - base[atlas.rail])
        for pitch, ys in KEYS:
            k, n = kb.key(pitch), 0
            for side, y in itertools.product(SIDE_M, ys):
                q0 = base.copy()
                q0[atlas.rail] = k.center_x_m - dx - side
                r = atlas.ik.solve_finger(PressTarget(
                    f, pitch, (k.center_x_m, float(y), k.top_z_m - DEPTH_M), (float(y), float(y))), q0)
                if not r.converged or not hand.within_limits(r.q):
                    continue
                pen = bodies.penetration(r.q, f, pitch)
                own = bodies.box_pitch == pitch
                n += bool(pen[own].max() <= BED_EXCESS_M and pen[~own].max() <= OTHER_KEY_M)
            out[(f, pitch)] = n
    return out


def _floats(s: str | None) -> list[float | None]:
    return [None] if not s else [float(v) for v in s.split(",")]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hand", default="default")
    ap.add_argument("--y", help="mount y values (m), comma-separated (default: the hand's)")
    ap.add_argument("--z", help="mount heights (m) over the white tops")
    ap.add_argument("--flex", help="wrist flexion values (rad)")
    ap.add_argument("--dev", help="wrist deviation values (rad)")
    a = ap.parse_args()
    hand0 = load_hand(a.hand)
    n = {p: len(SIDE_M) * len(ys) for p, ys in KEYS}
    print(f"press points per finger: D {n[62]}, C {n[60]}, C# {n[61]}")
    print("mount y, z (m) | wrist flex, dev (rad) | " + " ".join(f"{f:>8s}" for f in hand0.fingers))
    for y, z, flex, dev in itertools.product(_floats(a.y), _floats(a.z), _floats(a.flex), _floats(a.dev)):
        T = hand0.T_world_root.copy()
        T[1, 3] = T[1, 3] if y is None else y
        T[2, 3] = T[2, 3] if z is None else z
        hand = hand0.mounted(T)
        r = reach(hand, flex, dev)
        w = "fitted" if flex is None and dev is None else f"{flex}, {dev}"
        print(f"{T[1, 3]:.2f}, {T[2, 3]:.2f} | {w} | " + " ".join(
            f"{r[(f, 62)]:2d}/{r[(f, 60)]:2d}/{r[(f, 61)]:2d}" for f in hand.fingers), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
