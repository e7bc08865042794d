"""The two-hand ``hand-trajectory`` file, version 3: both hands' rows in one file
(``docs/user/two-hands.md``, ``docs/user/trajectory-file.md``).

The pair of hands is one robot (``planner.hand.pair.HandPair``): its columns are each
hand's joints and motors, prefixed ``left.`` / ``right.``; the file's ``hand`` is the pair's
name, its ``urdf_sha256`` the pair's URDF's hash and its ``T_world_root`` the identity
(the pair's root is the keyboard frame). Version 3 adds to the metadata ``hands`` (per
hand, in column order: ``prefix``, ``hand``, ``urdf_sha256`` of that hand's own URDF,
``T_world_root`` its mount) and to the end marker ``by_hand`` (per prefix, the indices of
the song's notes that hand plays: a claim, verified by ``check``).

``PairWriter`` streams one through the one trajectory writer (``TrajectoryWriter``: its
formatting, its guard on every row of each hand, its end marker); ``read_pair_plan``
(called by ``planner.planfile.read_plan`` for a version-3 file) reads one back as a
``PairPlan``: the pair rebuilt by its hands' names, every hash and column matched, and
each hand's own plan (``PlanFile``: its columns, unprefixed, with its hand's metadata), so
that what judges one hand judges each hand of a pair."""

from __future__ import annotations

import os
from collections import Counter
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from planner.errors import InputError, PlannerError
from planner.hand.pair import HandPair, check_pair, prefix
from planner.planfile import PlanFile, check_columns, plan_hand, plan_song_notes, start_pose
from planner.trajfile import PAIR_VERSION, Trajectory, TrajectoryWriter

if TYPE_CHECKING:
    from planner.hand.model import HandModel
    from planner.music.midi import Song

BY_HAND = "by_hand"  # the end marker's key: per prefix, the notes that hand plays
HANDS = "hands"  # the metadata's key: per hand, its prefix, name, hash and mount


def as_pair(hands: HandPair | Sequence[HandModel | str]) -> HandPair:
    """A ``HandPair`` of two hands given as models or names (a left hand, then a right)."""
    if isinstance(hands, HandPair):
        return hands
    from planner.hand.model import HandModel, load_hand

    return HandPair(tuple(h if isinstance(h, HandModel) else load_hand(h) for h in hands))


def hands_metadata(pair: HandPair) -> list[dict[str, Any]]:
    """The metadata's ``hands``: per hand (column order), prefix, name, hash, mount."""
    return [{"prefix": prefix(h), "hand": h.name, "urdf_sha256": h.urdf_sha256,
             "T_world_root": h.T_world_root.tolist()} for h in pair.hands]


def pair_metadata(pair: HandPair, metadata: Mapping[str, Any]) -> dict[str, Any]:
    """A version-3 file's metadata: ``metadata``'s ``task`` (a play unless given),
    ``rate_hz`` and other keys (the song's), with the pair's ``hand``, ``urdf_sha256``,
    ``T_world_root`` (the identity) and ``hands`` in place of any given (a one-hand
    plan's metadata may be given)."""
    own = ("version", "task", "hand", "urdf_sha256", "T_world_root", "rate_hz", HANDS)
    return {"version": PAIR_VERSION, "task": metadata.get("task", "play"), "hand": pair.name,
            "urdf_sha256": pair.urdf_sha256, "T_world_root": pair.T_world_root.tolist(),
            "rate_hz": metadata["rate_hz"], **{k: v for k, v in metadata.items() if k not in own},
            HANDS: hands_metadata(pair)}


def by_hand_claim(pair: HandPair, by_hand: Mapping[str, Sequence[int]]) -> dict[str, list[int]]:
    """The end marker's ``by_hand`` (per prefix, in column order, its notes sorted)."""
    if set(by_hand) != set(pair.prefixes):
        raise PlannerError(f"by_hand names {sorted(by_hand)}, the pair's hands are "
                           f"{list(pair.prefixes)}")
    return {p: sorted(int(i) for i in by_hand[p]) for p in pair.prefixes}


class PairWriter:
    """Streams a two-hand plan (version 3) into ``path`` ('-': stdout; None: in memory,
    ``text`` once closed): the constructor writes metadata and header (unless
    ``defer_header``), ``write_rows`` appends each hand's rows on their common clock
    (each hand's rows passed by its guard), ``close`` writes the end marker with the
    claims and ``by_hand``."""

    def __init__(self, path: str | None, hands: HandPair | Sequence[HandModel | str],
                 metadata: Mapping[str, Any],
                 on_rows: Callable[[np.ndarray], None] | None = None,
                 defer_header: bool = False) -> None:
        self.pair = as_pair(hands)
        self._writer = TrajectoryWriter(path, pair_metadata(self.pair, metadata), self.pair,
                                        on_rows=on_rows, defer_header=defer_header)

    @property
    def rows(self) -> int:
        return self._writer.rows

    @property
    def columns(self) -> list[str]:
        return self._writer.columns

    @property
    def text(self) -> str | None:
        return self._writer.text

    def add_metadata(self, **extra: Any) -> None:
        """Metadata known once planning has begun (``song_start_s``), before the first row."""
        self._writer.add_metadata(**extra)

    def write_rows(self, t_s: np.ndarray, q_left: np.ndarray, q_right: np.ndarray,
                   q_motor_left: np.ndarray | None = None,
                   q_motor_right: np.ndarray | None = None) -> np.ndarray:
        """Append rows at times ``t_s`` (s, the file's clock): each hand's joints (n, its
        joints) and motor angles (its model's of its joints unless given). Returns the
        rows as the file holds them, (n, columns)."""
        parts = [np.atleast_2d(np.asarray(q, dtype=float)) for q in (q_left, q_right)]
        for h, q in zip(self.pair.hands, parts):
            if q.shape != (len(np.atleast_1d(t_s)), h.n):
                raise PlannerError(f"{h.name}: rows of shape {q.shape}, want "
                                   f"({len(np.atleast_1d(t_s))}, {h.n})")
        motors = [h.motor_angles(q) if qm is None else np.atleast_2d(np.asarray(qm, float))
                  for h, q, qm in zip(self.pair.hands, parts, (q_motor_left, q_motor_right))]
        return self._writer.write_rows(t_s, np.concatenate(parts, axis=1),
                                       np.concatenate(motors, axis=1))

    def close(self, end_info: Mapping[str, Any] | None = None,
              by_hand: Mapping[str, Sequence[int]] | None = None) -> None:
        """The end marker: ``end_info``'s claims (``notes``, ``played``, ``left_out``:
        the whole song's), then ``by_hand`` (per prefix, the notes that hand plays)."""
        info = dict(end_info or {})
        if by_hand is not None:
            info[BY_HAND] = by_hand_claim(self.pair, by_hand)
        self._writer.close(info)

    def abort(self, discard: bool = False) -> None:
        """Stop without the end marker (the file stays visibly incomplete)."""
        self._writer.abort(discard)


def write_pair_file(path: str | None, hands: HandPair | Sequence[HandModel | str],
                    metadata: Mapping[str, Any], t_s: np.ndarray,
                    q: Sequence[np.ndarray], q_motor: Sequence[np.ndarray | None] = (None, None),
                    end_info: Mapping[str, Any] | None = None,
                    by_hand: Mapping[str, Sequence[int]] | None = None) -> str | None:
    """A whole two-hand file at once (``PairWriter``): ``q`` and ``q_motor`` the left
    hand's then the right hand's rows. Returns the text when ``path`` is None."""
    w = PairWriter(path, hands, metadata)
    w.write_rows(t_s, q[0], q[1], q_motor[0], q_motor[1])
    w.close(end_info, by_hand)
    return w.text


@dataclass(frozen=True)
class PairPlan:
    """A two-hand plan file read back: the file (``trajectory``, its prefixed columns),
    the pair, and each hand's own plan (``hands``: left, right; each its columns without
    prefix, its hand, its mount), with the end marker's ``by_hand`` (None when absent)."""

    trajectory: Trajectory
    path: str
    pair: HandPair
    hands: tuple[PlanFile, PlanFile]
    by_hand: dict[str, tuple[int, ...]] | None

    @property
    def metadata(self) -> dict[str, Any]:
        return self.trajectory.metadata

    @property
    def task(self) -> str:
        return self.trajectory.metadata["task"]

    @property
    def T_world_root(self) -> np.ndarray:
        return self.pair.T_world_root

    def song_notes(self, song: str | os.PathLike | Song, options: dict[str, Any] | None = None):
        """The whole song's notes in the file's time (``PlanFile.song_notes``)."""
        return plan_song_notes(self.metadata, self.path, song, options)


def read_pair_plan(tr: Trajectory, path: str, hand_override=None) -> PairPlan:
    """A version-3 ``Trajectory`` (read already) as a ``PairPlan``; InputError (one line,
    naming the file) on any mismatch: ``hands`` missing or malformed, a prefix not its
    hand's side, a hand unknown, a hash (a hand's or the pair's) or the columns not the
    rebuilt pair's, a mount not its hand's, ``by_hand`` malformed."""
    meta = tr.metadata
    if hand_override is not None:
        raise InputError(f"{path}: a two-hand file names its hands itself (no --hand)")
    if meta["task"] != "play":
        raise InputError(f"{path}: a two-hand file is a play, not a {meta['task']!r}")
    entries = meta.get(HANDS)
    if not isinstance(entries, list) or len(entries) != 2 or not all(
            isinstance(e, dict) for e in entries):
        raise InputError(f"{path}: a version-3 file's metadata must have 'hands': two objects "
                         "(prefix, hand, urdf_sha256, T_world_root), the left hand first")
    hands = tuple(_entry_hand(e, i, path) for i, e in enumerate(entries))
    try:
        check_pair(hands)
    except InputError as e:
        raise InputError(f"{path}: {e}") from None
    pair = HandPair(hands)
    for e, h, p in zip(entries, hands, pair.prefixes):
        if e["prefix"] != p:
            raise InputError(f"{path}: hand {h.name!r} ({h.side}) has prefix {e['prefix']!r}; "
                             f"a {h.side} hand's is {p!r}")
    if meta["hand"] != pair.name:
        raise InputError(f"{path}: metadata 'hand' is {meta['hand']!r}, its hands make the "
                         f"pair {pair.name!r}")
    if meta["urdf_sha256"] != pair.urdf_sha256:
        raise InputError(f"{path}: urdf_sha256 mismatch: the file was planned for "
                         f"{meta['urdf_sha256']!r}, the pair {pair.name!r} is "
                         f"{pair.urdf_sha256!r}")
    start_pose(meta, pair, path)  # (the pair's root is the keyboard frame: the identity)
    check_columns(tr, pair, path)
    parts = tuple(_hand_plan(tr, path, pair, i, e) for i, e in enumerate(entries))
    by_hand = _by_hand(tr.end, pair, path)
    return PairPlan(tr, path, pair, (parts[0], parts[1]), by_hand)


def _entry_hand(entry: dict[str, Any], i: int, path: str) -> HandModel:
    """The hand of ``hands[i]``, rebuilt by its name, its hash matched."""
    for key in ("prefix", "hand", "urdf_sha256", "T_world_root"):
        if key not in entry:
            raise InputError(f"{path}: hands[{i}] lacks {key!r}")
    hand = plan_hand(entry, path)
    if entry["urdf_sha256"] != hand.urdf_sha256:
        raise InputError(f"{path}: urdf_sha256 mismatch for {entry['prefix']!r}: the file was "
                         f"planned for {entry['urdf_sha256']!r}, hand {hand.name!r} is "
                         f"{hand.urdf_sha256!r}")
    return hand


def _hand_plan(tr: Trajectory, path: str, pair: HandPair, i: int,
               entry: dict[str, Any]) -> PlanFile:
    """Hand ``i``'s own plan: its columns without prefix, the file's metadata with its
    hand's name, hash and mount (which must be its hand's), the file's end (its rows)."""
    hand = pair.hands[i]
    meta = {**tr.metadata, "hand": hand.name, "urdf_sha256": hand.urdf_sha256,
            "T_world_root": entry["T_world_root"]}
    meta.pop(HANDS)
    T = start_pose(meta, hand, f"{path} ({entry['prefix']})")
    q, qm = pair.split(tr.q)[i], pair.split_motor(tr.q_motor)[i]
    end = {"end": True, "rows": len(tr.t_s)} if tr.complete else {}
    part = Trajectory(meta, tuple(hand.joint_names), tuple(hand.motor_names), tr.t_s, q, qm,
                      tr.complete, end)
    return PlanFile(part, path, hand, T)


def _by_hand(end: dict[str, Any], pair: HandPair, path: str
             ) -> dict[str, tuple[int, ...]] | None:
    """The end marker's ``by_hand``: per prefix, distinct note indices (>= 0)."""
    if BY_HAND not in end:
        return None
    raw = end[BY_HAND]
    if not isinstance(raw, dict) or set(raw) != set(pair.prefixes):
        raise InputError(f"{path}: the end marker's by_hand must name the notes of each hand "
                         f"({', '.join(pair.prefixes)}), got {raw!r:.80}")
    out: dict[str, tuple[int, ...]] = {}
    seen: list[int] = []
    for p in pair.prefixes:
        notes = raw[p]
        if not isinstance(notes, list) or not all(
                isinstance(i, int) and not isinstance(i, bool) and i >= 0 for i in notes):
            raise InputError(f"{path}: by_hand[{p!r}] must be a list of note indices (>= 0)")
        twice = sorted(i for i, k in Counter([*seen, *notes]).items() if k > 1)
        if twice:
            raise InputError(f"{path}: by_hand gives note {twice[0]} twice (a note is one "
                             "hand's)")
        seen.extend(notes)
        out[p] = tuple(notes)
    return out
