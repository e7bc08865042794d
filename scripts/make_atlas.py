"""Write a hand's atlas (``planner.play.atlas``: every finger's press, rise, hover and
crossing-height poses over every key, at every sampled place relative to the rail) to
where the planner loads it from (``planner/tables/atlas-<URDF hash>.npz``). Without it
the planner solves the entries it needs when it first needs them (single-finger IK,
about 1 ms a pose); the table saves that time and holds exactly what the solver gives.
Run from the repository root after changing a hand, the IK or the atlas:

    python scripts/make_atlas.py [--hand NAME]
"""

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from planner.hand.model import load_hand
from planner.play.atlas import Atlas, table_path


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hand", default="default")
    a = ap.parse_args()
    hand = load_hand(a.hand)
    path = table_path(hand.urdf_sha256)
    atlas = Atlas(hand)
    atlas._entries.clear()  # (solved afresh, not read back from an older table)
    t0 = time.perf_counter()
    n = atlas.solve_all()
    path.parent.mkdir(parents=True, exist_ok=True)
    atlas.save(path)
    print(f"{path}: {n} entries of {len(atlas._entries)} samples, {atlas.solves} IK solves, "
          f"{time.perf_counter() - t0:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
