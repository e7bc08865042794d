"""A plan file read for a replay: its rows and metadata (``planner.trajfile``), the hand
it names, rebuilt and matched to the file (URDF hash, columns), the pose of the hand's
root it starts from (``T_world_root``), the song's notes as the plan read them, and the
notes its end marker says it left out. ``check`` and ``simulate`` both read plans so.

Every mismatch is an ``InputError`` naming the file (exit 2)."""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from planner.errors import InputError
from planner.hand.model import HandModel, load_hand
from planner.trajfile import PAIR_VERSION, Trajectory, is_num, read_trajectory, song_start_s

if TYPE_CHECKING:
    from planner.hand.pair import HandPair
    from planner.music.midi import Song
    from planner.pairfile import PairPlan

T_TOL = 1e-9  # metadata T_world_root vs the hand's mount (play)
MEMORY = "<memory>"  # the name of a plan read already (``PlayPlan.trajectory``)


@dataclass(frozen=True)
class PlanFile:
    """A plan file with its hand and its start pose, checked against each other."""

    trajectory: Trajectory
    path: str  # the file, or MEMORY
    hand: HandModel
    T_world_root: np.ndarray

    @property
    def metadata(self) -> dict[str, Any]:
        return self.trajectory.metadata

    @property
    def task(self) -> str:
        return self.trajectory.metadata["task"]

    def song_notes(self, song: str | os.PathLike | Song, options: dict[str, Any] | None = None):
        """The song's notes in the file's time (``plan_song_notes``)."""
        return plan_song_notes(self.metadata, self.path, song, options)


def plan_song_notes(meta: dict[str, Any], path: str, song: str | os.PathLike | Song,
                    options: dict[str, Any] | None = None):
    """The song's notes in the file's time (shifted by its ``song_start_s``, format
    version 2 on), read with the options the plan was made with (the file's metadata
    ``meta``) unless given; InputError when the file names another number of notes."""
    from planner.music.midi import Song, load_song, shift_notes

    options = options or {}
    opts = {k: (options.get(k) if options.get(k) is not None else meta.get(k))
            for k in ("track", "channel", "transpose")}
    if isinstance(song, Song):  # (read already, with the options its reader chose)
        notes = song.notes
    else:
        notes = load_song(song, track=opts["track"], channel=opts["channel"],
                          transpose=bool(opts["transpose"])).notes
    want = meta.get("notes")
    if is_num(want) and int(want) != len(notes):
        given = (", ".join(f"{k}={v}" for k, v in opts.items() if v not in (None, False))
                 or "none")
        raise InputError(f"{path}: planned for a song of {int(want)} notes, {song} "
                         f"has {len(notes)} (another song, or other --track/--channel/"
                         f"--transpose; options used: {given})")
    return shift_notes(notes, song_start_s(meta))


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
        from planner.pairfile import read_pair_plan

        return read_pair_plan(tr, os.fspath(path), hand_override)
    hand = plan_hand(meta, path, hand_override)
    if meta["urdf_sha256"] != hand.urdf_sha256:
        raise InputError(f"{path}: urdf_sha256 mismatch: the file was planned for "
                         f"{meta['urdf_sha256']!r}, hand {hand.name!r} is {hand.urdf_sha256!r}")
    check_columns(tr, hand, path)
    return PlanFile(tr, path, hand, start_pose(meta, hand, path))


def plan_hand(meta: dict[str, Any], path: str, hand_override=None) -> HandModel:
    """The hand the metadata names (or ``hand_override``), rebuilt."""
    if isinstance(hand_override, HandModel):
        return hand_override
    name = hand_override if hand_override is not None else meta["hand"]
    if not isinstance(name, str) or not name:
        raise InputError(f"{path}: metadata 'hand' must be a hand name, got {name!r}")
    try:
        return load_hand(name)
    except InputError as e:
        raise InputError(f"{path}: cannot rebuild hand {name!r}: {e}") from None


def check_columns(tr: Trajectory, hand: HandModel | HandPair, path: str) -> None:
    """The file's joint and motor columns are ``hand``'s (names and order), or InputError
    naming what is missing, extra or out of order."""
    for what, have, want in (("joint", tr.joint_names, hand.joint_names),
                             ("motor", tr.motor_names, hand.motor_names)):
        if tuple(have) == tuple(want):
            continue
        pre = "motor." if what == "motor" else ""
        missing = [pre + n for n in want if n not in have]
        extra = [pre + n for n in have if n not in want]
        parts = []
        if missing:
            parts.append("missing " + ", ".join(missing))
        if extra:
            parts.append("extra " + ", ".join(extra))
        if not parts:
            parts.append(f"order differs from the hand's ({', '.join(pre + n for n in want)})")
        raise InputError(f"{path}: {what} columns do not match hand {hand.name!r}: "
                         + "; ".join(parts))


def start_pose(meta: dict[str, Any], hand: HandModel | HandPair, path: str) -> np.ndarray:
    """The metadata's ``T_world_root``, a rigid transform; for a play, the hand's mount
    (the keyboard frame is defined by it)."""
    raw = meta["T_world_root"]
    try:
        T = np.array(raw, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{path}: T_world_root must be a 4x4 list of numbers") from None
    if T.shape != (4, 4) or not np.all(np.isfinite(T)):
        raise InputError(f"{path}: T_world_root must be a 4x4 list of finite numbers")
    R = T[:3, :3]
    if (not np.allclose(T[3], [0, 0, 0, 1], atol=1e-9)
            or not np.allclose(R.T @ R, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0):
        raise InputError(f"{path}: T_world_root is not a rigid transform")
    if meta["task"] == "play":
        diff = float(np.max(np.abs(T - hand.T_world_root)))
        if diff > T_TOL:
            raise InputError(f"{path}: T_world_root differs from hand {hand.name!r}'s mount by "
                             f"{diff:.3g} (the keyboard frame is that mount)")
    return T
