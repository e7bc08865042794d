"""Where a hand's fingers press keys as bodies from one arm posture (a measurement).

For each arm posture asked for (the rail's height over the keys, the reach axis, the
wrist's flexion; deviation 0) and each finger, counts the presses whose body passes the
atlas's body rule (``planner.play.fingerbody.FingerBodies.clear``: the finger's
collision bodies, spec section 3, reach no other key by more than 0.5 mm and their own
pressed key no more than 2 mm past its bed), the pad point ``--depth`` below the key's
top (single-finger IK, ``planner.ik``; the arm held at the posture):

* ``W``: keys D4 and E4 in front of the black keys (y 4-50 mm: the only place a finger
  end wider than 13.5 mm fits on a white key between two black keys);
* ``B``: keys C#4 and D#4 along their exposed length;

each at the finger's natural place over the key and 8 mm either side (6 presses a
class). Prints one line per posture, the best first:

    python scripts/body_reach.py --z=0.05,0.08 --reach=-0.175,-0.125 --flex=-0.2,0

Measured and read in docs/history/2026-12-06-play-posture.md (the default hand's
``[play]`` posture was chosen with it).
"""

from __future__ import annotations

import argparse
import itertools
import sys
from dataclasses import replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from planner.hand.model import load_hand
from planner.hand.spec import PlayPosture
from planner.ik import FRONT_Y_MAX_M, PressTarget
from planner.music import keyboard as kb
from planner.play.atlas import Atlas
from planner.play.fingerbody import FingerBodies

CLASSES = (("W", (62, 64)), ("B", (61, 63)))
SIDE_M = (-0.008, 0.0, 0.008)  # press places: the finger's natural place and either side


def target(finger: str, pitch: int, depth_m: float) -> PressTarget:
    k = kb.key(pitch)
    z = k.top_z_m - depth_m
    if k.black:
        return PressTarget(finger, pitch, (k.center_x_m, kb.BLACK_Y0_M + 0.02, z),
                           (kb.BLACK_Y0_M + 0.008, kb.BLACK_Y1_M - 0.025))
    return PressTarget(finger, pitch, (k.center_x_m, 0.03, z), (0.004, FRONT_Y_MAX_M))


def reach(hand, depth_m: float) -> dict[tuple[str, str], int]:
    """Per (finger, class) the presses whose body passes (see the module docstring)."""
    atlas, bodies = Atlas(hand), FingerBodies(hand)
    base, rail = atlas.base, atlas.rail
    out = {}
    for i, f in enumerate(hand.fingers):
        dx = float(hand.tip_positions(base)[i, 0] - base[rail])
        for name, pitches in CLASSES:
            n = 0
            for pitch, side in itertools.product(pitches, SIDE_M):
                q0 = base.copy()
                q0[rail] = kb.key(pitch).center_x_m - dx - side
                r = atlas.ik.solve_finger(target(f, pitch, depth_m), q0)
                n += bool(r.converged and hand.within_plan_limits(r.q)
                          and bodies.clear(r.q, f, pitch))
            out[(f, name)] = n
    return out


def _floats(s: str) -> list[float]:
    return [float(v) for v in s.split(",")]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hand", default="default")
    ap.add_argument("--z", default="0.05", help="the rail's heights over the white tops (m)")
    ap.add_argument("--reach", default="-0.175", help="reach axis positions (m)")
    ap.add_argument("--flex", default="-0.2", help="wrist flexions (rad; + bends the palm down)")
    ap.add_argument("--depth", type=float, default=0.007, help="press depth below the top (m)")
    a = ap.parse_args()
    hand0 = load_hand(a.hand)
    rows = []
    for z, r, flex in itertools.product(_floats(a.z), _floats(a.reach), _floats(a.flex)):
        T = hand0.T_world_root.copy()
        T[2, 3] = z
        hand = hand0.mounted(T)
        hand.spec = replace(hand.spec, play_posture=PlayPosture(r, flex, 0.0, a.depth))
        got = reach(hand, a.depth)
        rows.append((sum(got.values()), z, r, flex, got))
    n = len(SIDE_M) * 2
    print(f"presses per finger and class: {n} (W: white keys' front, B: black keys)")
    for total, z, r, flex, got in sorted(rows, key=lambda row: -row[0]):
        print(f"z {z:.3f} m, reach {r:+.3f} m, wrist {flex:+.2f} rad: {total:3d} | " + " ".join(
            f"{f} W{got[(f, 'W')]} B{got[(f, 'B')]}" for f in hand0.fingers), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
