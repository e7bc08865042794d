"""A plan file read for a replay: its rows and metadata (``planner.trajfile``), the hand
it names, rebuilt and matched to the file (``planner.planhand``: URDF hash, columns, the
pose of the hand's root, the song's notes as the plan read them); a two-hand file
(version 3) each of its hands so (``planner.pairfile``). ``check`` and ``simulate`` both
read plans so.

Every mismatch is an ``InputError`` naming the file (exit 2)."""

from __future__ import annotations

import os

from planner.errors import InputError
from planner.hand.model import HandModel
from planner.pairfile import PairPlan, read_pair_plan
from planner.planhand import MEMORY, PlanFile, check_columns, plan_hand, start_pose
from planner.trajfile import PAIR_VERSION, Trajectory, read_trajectory

__all__ = ["MEMORY", "PairPlan", "PlanFile", "read_plan"]


def read_plan(traj: str | os.PathLike | Trajectory, *, allow_incomplete: bool = False,
              hand_override: str | HandModel | None = None, name: str | None = None
              ) -> PlanFile | PairPlan:
    """Read ``traj`` (a file, or a ``Trajectory`` read already: ``name`` its file, or
    MEMORY) and rebuild its hand (``hand_override``: a hand name, hand file or HandModel
    in place of the file's hand name; its URDF hash must still match the file's). A
    two-hand file (version 3) is a ``planner.pairfile.PairPlan``: both hands rebuilt by
    their names (no override)."""
    if isinstance(traj, Trajectory):
        tr, path = traj, MEMORY if name is None else name
    else:
        tr, path = read_trajectory(traj, allow_incomplete=allow_incomplete), traj
    meta = tr.metadata
    if meta["version"] == PAIR_VERSION:
        return read_pair_plan(tr, os.fspath(path), hand_override)
    hand = plan_hand(meta, path, hand_override)
    if meta["urdf_sha256"] != hand.urdf_sha256:
        raise InputError(f"{path}: urdf_sha256 mismatch: the file was planned for "
                         f"{meta['urdf_sha256']!r}, hand {hand.name!r} is {hand.urdf_sha256!r}")
    check_columns(tr, hand, path)
    return PlanFile(tr, path, hand, start_pose(meta, hand, path))
