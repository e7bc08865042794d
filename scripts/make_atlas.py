"""Write a hand's atlas (``planner.play.atlas``: every finger's press, rise, hover and
crossing-height poses over every key, at every sampled place relative to the rail) to
where the planner loads it from (``planner/tables/atlas-<URDF hash>.npz``). Without it
the planner solves the entries it needs when it first needs them (single-finger IK,
about 1 ms a pose); the table saves that time and holds exactly what the solver gives.
It also writes the hand's move table (``planner.play.movetable``: every entry's key
crossings, the moments its lifts and descents are clear above every key, which pairs
of entries a finger moves between clear of the keys, which it can hold a key down
between while the rail moves: ``planner/tables/moves-<URDF hash>.npz``; with several play postures also the moves across from another posture's
entries and the arm's moves between postures at every step of the rail), which the
planner would otherwise find by forward kinematics when it first needs them. Run from
the repository root after changing a hand, the IK, the atlas or the moves:

    python scripts/make_atlas.py [--hand NAME] [--only PART,...]

It makes its parts in this order (``PARTS``), each by one function whether it is made
with the rest or alone; ``--only`` names the parts to make (default: all), the others
are read as shipped:

* ``atlas``: every play posture's atlas, solved afresh (else the shipped one is read);
* ``moves``: each posture's move table of its atlas's entries (``movetable.make_table``;
  a fresh table holds no proofs nor repeats: these two parts are made with it);
* ``proofs``: into each move table, the tendon proof's gains of each finger's box of high
  poses (``planner.play.tendonproof``; posture 0's: also the cells over every posture's;
  ``movetable.add_proofs``);
* ``repeats``: into each move table, each entry's repeat (``Moves.repeat_found``;
  ``movetable.add_repeats``, the table's own crossings read back);
* ``follows``: the hand's follow table (``planner.play.followtable``: the follow test's
  answers on the rail's grid, for a hand with a rail and the atlas's body rule), of the
  atlas and move tables as shipped by then.

A name not among them: one line on stderr, exit 2.
"""

import argparse
import math
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from planner.hand.model import load_hand
from planner.play import followtable, highclear
from planner.play.atlas import Atlas, posture_count, table_path
from planner.play.moves import Moves
from planner.play.movetable import MoveTable, add_proofs, add_repeats, make_table
from planner.play.movetable import table_path as moves_path
from planner.play.places import RAIL_STEP_M, Places

PARTS = ("atlas", "moves", "proofs", "repeats", "follows")  # (in the order they are made)


def parts_named(text: str) -> tuple[str, ...]:
    """The parts ``--only`` names (comma-separated), in ``PARTS``' order, with the proofs
    and repeats of a fresh move table; ValueError for a name not among ``PARTS``."""
    named = {n.strip() for n in text.split(",")}
    unknown = sorted(named - set(PARTS))
    if unknown:
        raise ValueError(f"--only: unknown part {unknown[0]!r} (parts: {','.join(PARTS)})")
    if "moves" in named:
        named |= {"proofs", "repeats"}
    return tuple(n for n in PARTS if n in named)


def make(hand, posture: int, fresh: bool) -> Atlas:
    """The atlas of one play posture of ``hand``, solved in full: afresh and written when
    ``fresh``, else the shipped one."""
    path = table_path(hand.urdf_sha256, posture)
    atlas = Atlas(hand, posture=posture)
    t0 = time.perf_counter()
    if fresh:
        atlas.forget()  # (solved afresh, not read back from an older table)
    n = atlas.solve_all()
    if fresh:
        path.parent.mkdir(parents=True, exist_ok=True)
        atlas.save(path)
        print(f"{path}: {n} entries of {atlas.asked()} samples, {atlas.solves} IK "
              f"solves, {time.perf_counter() - t0:.1f} s")
    return atlas


def make_moves(hand, atlases: list[Atlas], posture: int, places: Places | None) -> None:
    """The move table of one play posture, with the pairs from every other posture's
    entries and the arm's moves to the postures after it (``Places.arm_time_s``, every
    step of the rail's travel; ``places``: the hand's, None with one posture)."""
    t1 = time.perf_counter()
    atlas = atlases[posture]
    moves = Moves(hand, atlas)
    # (found afresh, not read back)
    moves.table = MoveTable(hand.fingers, atlas.natural_dx, posture)
    out = moves_path(hand.urdf_sha256, posture)
    n = make_table(moves, out, moves.params(),
                   [(a, None if places is None or i < posture else _arm_s(places, posture, i))
                    for i, a in enumerate(atlases) if i != posture],
                   (highclear.HighClear(hand, atlases), highclear.params()))
    print(f"{out}: the moves of {n} entries, {time.perf_counter() - t1:.1f} s")


def _arm_s(places: Places, posture: int, other: int) -> tuple[int, list[float]]:
    """The arm's move from ``posture`` at rail 0 to ``other`` at every step of the rail
    that its travel allows (``Places.arm_time_s``' question): the first step and the
    durations."""
    r = places.rail
    lo = math.ceil(places.hand.plan_lower[r] / RAIL_STEP_M)
    hi = math.floor(places.hand.plan_upper[r] / RAIL_STEP_M)
    steps = range(lo - hi, hi - lo + 1)
    return steps[0], [places.arm_move((0.0, places.reach_m(posture)),
                                      (s * RAIL_STEP_M, places.reach_m(other))).duration_s
                      for s in steps]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hand", default="default")
    ap.add_argument("--only", default=",".join(PARTS),
                    help="the parts to make, comma-separated (default: all, "
                         f"{','.join(PARTS)}); the others are read as shipped")
    a = ap.parse_args(argv)
    try:
        parts = parts_named(a.only)
    except ValueError as err:
        print(err, file=sys.stderr)
        return 2
    hand = load_hand(a.hand)
    atlases = [] if parts == ("follows",) else [
        make(hand, i, "atlas" in parts) for i in range(posture_count(hand))]
    if "moves" in parts:
        places = Places(hand) if len(atlases) > 1 and atlases[0].rail is not None else None
        for i in range(len(atlases)):
            make_moves(hand, atlases, i, places)
    for i in range(len(atlases) if "proofs" in parts else 0):
        make_proofs(hand, atlases, i)
    for atlas in atlases if "repeats" in parts else ():
        make_repeats(hand, atlas)
    if "follows" in parts:
        make_follows(hand)
    return 0


def make_proofs(hand, atlases: list[Atlas], posture: int) -> None:
    """The tendon proof's gains of one play posture's shipped atlas (posture 0's table:
    also the cells over every posture's), into its shipped move table
    (``movetable.add_proofs``)."""
    t0 = time.perf_counter()
    out = moves_path(hand.urdf_sha256, posture)
    if not out.exists():
        print(f"{out}: no move table", file=sys.stderr)
        return
    others = [a for i, a in enumerate(atlases) if i != posture] if posture == 0 else []
    if add_proofs(Moves(hand, atlases[posture]), out, others):
        print(f"{out}: the tendon proof's gains, {time.perf_counter() - t0:.1f} s")


def make_repeats(hand, atlas: Atlas) -> None:
    """Each entry's repeat of one play posture's shipped atlas, into its shipped move
    table (``movetable.add_repeats``)."""
    t0 = time.perf_counter()
    out = moves_path(hand.urdf_sha256, atlas.posture_index)
    if not out.exists():
        print(f"{out}: no move table", file=sys.stderr)
        return
    n = add_repeats(Moves(hand, atlas), out)
    print(f"{out}: the repeats of {n} entries, {time.perf_counter() - t0:.1f} s")


def make_follows(hand) -> None:
    """The hand's follow table, of the shipped atlas and move tables (none without a
    rail or the body rule)."""
    t0 = time.perf_counter()
    places = Places(hand)
    if places.rail is None or places.atlas.bodies is None:
        return
    out = followtable.table_path(hand.urdf_sha256)
    n = followtable.make_table(places, out)
    print(f"{out}: {n} follows, {time.perf_counter() - t0:.1f} s")


if __name__ == "__main__":
    sys.exit(main())
