"""Write the table of which two fingers can press which two keys at once
(``Planner.pair_table``) for a hand, where the planner loads it from
(``planner/tables/pairs-<URDF hash>.json``), with each finger's range at one hand position
(``Planner._finger_ranges``). Without it the planner works the same
answers out as the fingering asks for them (whole-hand IK, a few ms each); the table
only saves that time. Run from the repository root after changing a hand or the IK:

    python scripts/make_pair_table.py [--hand NAME]

``tests/test_play.py`` checks that the default hand's table is there, matches its URDF
and agrees with the IK on a sample of entries."""

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from planner.hand.model import load_hand
from planner.play.legacy import Planner, pair_table_path


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hand", default="default")
    a = ap.parse_args()
    hand = load_hand(a.hand)
    pl = Planner(hand)
    pl._pairs.clear()  # (worked out afresh, not read back from an older table)
    table = pl.pair_table()
    path = pair_table_path(hand.urdf_sha256)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(table, indent=1, sort_keys=True) + "\n")
    print(f"{path}: {sum(c != '-' for r in table['pairs'].values() for c in r)} pairs")
    return 0


if __name__ == "__main__":
    sys.exit(main())
