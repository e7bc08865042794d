"""Write each shipped hand's closed poses on the named balls (``planner.catch.plan.
closingtable``: ``closing.closed_pose``, with and without the fingers' bodies judged) to
where the catch planner loads them from (``planner/tables/closing-<URDF hash>.npz``).
Without it the planner solves a pose when it first needs it (12 fingertip IK solves:
0.08 s of CPU); the table holds exactly what the solver gives. Run from the repository
root after changing a hand, the IK or the closing:

    python scripts/make_closing.py [--hand NAME]
"""

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from planner.balls import BALLS
from planner.catch.plan.api import get_planner
from planner.catch.plan.closing import closed_pose
from planner.catch.plan.closingtable import key, save, table_path
from planner.errors import InputError
from planner.hand.spec import list_hands


def make(name: str) -> None:
    """The table of one hand (every named ball's radius, bodies judged and not)."""
    t0 = time.perf_counter()
    try:
        pl = get_planner(name)
    except InputError as e:  # (a hand the catch cannot mount)
        print(f"{name}: no catch planner ({e})")
        return
    poses = {}
    for r in sorted({b.radius_m for b in BALLS.values()}):
        for bodies in (True, False):
            poses[key(r, bodies)] = closed_pose(pl.hand, pl.ik, pl.joints, pl.wrist, r, bodies)
    path = table_path(pl.hand.urdf_sha256)
    path.parent.mkdir(parents=True, exist_ok=True)
    save(path, pl.hand, pl.joints, pl.wrist, poses)
    print(f"{path}: {len(poses)} closed poses of hand {name}, {time.perf_counter() - t0:.1f} s")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hand", default=None, help="one hand (default: every shipped hand)")
    a = ap.parse_args()
    for name in [a.hand] if a.hand else list_hands():
        make(name)
    return 0


if __name__ == "__main__":
    sys.exit(main())
