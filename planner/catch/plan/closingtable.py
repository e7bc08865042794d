"""The closed hand on a ball, shipped: ``closing.closed_pose`` (12 fingertip IK solves,
the fingers' bodies kept clear by bisection: 0.08 s of CPU, 0.3-0.6 s on a loaded
machine) per hand and ball radius, in ``planner/tables/closing-<URDF hash>.npz``, made
by ``scripts/make_closing.py`` for the shipped hands and the named balls (``BALLS``).
The rest of the closing move (``closing.closing_from``: the table of the move in the
palm frame, the grasp condition, the fingers' bodies along it) is computed from the
shipped pose, as from a solved one.

A pose is used only where the table was made with the same parameters (``params``: the
hand's URDF and its whole hand file, the reference wrist, the closing's constants,
``VERSION``): a hand, a mount or a constant changed since leaves the table unused, and
the pose is solved as before. A clean checkout without the file solves it (the table is
a cache, never needed). ``tests/test_closingtable.py`` holds the shipped poses equal to
the solver's, bit for bit.
"""

from __future__ import annotations

import hashlib
import json
from functools import lru_cache
from pathlib import Path

import numpy as np

from planner.catch.plan.arm import CatchJoints, zero_pose
from planner.catch.plan.closing import closed_pose_constants
from planner.catch.plan.intercept import Wrist
from planner.hand.model import HandModel

TABLE_DIR = Path(__file__).parents[2] / "tables"  # (beside the play atlas's tables)
VERSION = 2  # the closed pose's algorithm (``closing.closed_pose``, ``HandIK.solve``): one
# up when it changes, so that no table made by the older one is read (2: solved within the
# planner's limits, ``HandModel.within_margins``)
RADIUS_DIGITS = 9  # a ball's radius keyed to 1 nm (``CatchPlanner.closing``'s own key)


def table_path(urdf_sha256: str) -> Path:
    """Where the closed poses of a hand's URDF are shipped."""
    return TABLE_DIR / f"closing-{urdf_sha256[:16]}.npz"


def _rounded(x) -> list[float]:
    return [round(float(v), 12) for v in np.asarray(x, dtype=float).ravel()]


def params(hand: HandModel, joints: CatchJoints, wrist: Wrist) -> str:
    """What a closed pose depends on besides the ball: the hand (its URDF and its hand
    file, couplings and limits included; the limits the planner keeps), the arm's and fingers' roles, the reference
    wrist, the closing's constants and the algorithm's version."""
    spec = hashlib.sha256(repr(hand.spec).encode()).hexdigest()
    return json.dumps({
        "version": VERSION, "urdf_sha256": hand.urdf_sha256, "spec_sha256": spec,
        "q0": _rounded(zero_pose(hand)), "lower": _rounded(hand.lower),
        "upper": _rounded(hand.upper), "pc0": _rounded(wrist.pc0), "n0": _rounded(wrist.n0),
        "b0": _rounded(wrist.b0), "arm": [int(i) for i in joints.arm],
        "flexion": [int(i) for i in joints.flexion_idx], "locked": list(joints.locked),
        "constants": list(closed_pose_constants())}, sort_keys=True)


def key(radius_m: float, bodies: bool) -> tuple[float, bool]:
    return round(float(radius_m), RADIUS_DIGITS), bool(bodies)


@lru_cache(maxsize=8)
def _entries(path: Path, want: str) -> dict[tuple[float, bool], np.ndarray]:
    """The poses of the table at ``path`` made with parameters ``want`` (none otherwise)."""
    if not path.exists():
        return {}
    with np.load(path, allow_pickle=False) as z:
        if str(z["params"]) != want:
            return {}
        return {key(r, b): q.copy() for r, b, q in zip(z["radius_m"], z["bodies"], z["q"])}


def shipped_closed_pose(hand: HandModel, joints: CatchJoints, wrist: Wrist, radius_m: float,
                        bodies: bool) -> np.ndarray | None:
    """The shipped closed pose for this hand and ball (None: not shipped, or made with
    other parameters)."""
    q = _entries(table_path(hand.urdf_sha256), params(hand, joints, wrist)).get(
        key(radius_m, bodies))
    return None if q is None else q.copy()


def save(path: Path, hand: HandModel, joints: CatchJoints, wrist: Wrist,
         poses: dict[tuple[float, bool], np.ndarray]) -> None:
    """Write ``poses`` ((radius, bodies) -> closed pose) with this hand's parameters."""
    keys = sorted(poses)
    with open(path, "wb") as fh:
        np.savez_compressed(fh, params=np.array(params(hand, joints, wrist)),
                            radius_m=np.array([k[0] for k in keys]),
                            bodies=np.array([k[1] for k in keys], dtype=bool),
                            q=np.array([poses[k] for k in keys]))
    _entries.cache_clear()
