"""The plan's claims in its end marker (spec section 4, version 2), read and typed.

A claim is something ``check`` verifies against its replay, never something that
changes how the rows are judged. ``read_claims`` refuses a claim of the wrong type
(``InputError``, the one line naming the key: ``"played": "14"`` is not a count);
``count_mismatches`` lists every count the replay contradicts.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import Any

from planner.errors import InputError


class ClaimKey(enum.Enum):
    """The end marker's keys that state what a play does."""

    NOTES = "notes"
    PLAYED = "played"
    LEFT_OUT = "left_out"


@dataclass(frozen=True)
class PlayClaims:
    """What the end marker says (None: the key is absent)."""

    notes: int | None
    played: int | None
    left_out: frozenset[int] | None


@dataclass(frozen=True)
class CountMismatch:
    """A count of the end marker that the replay contradicts."""

    key: ClaimKey
    claimed: int
    found: int
    detail: str


def _count(end: dict[str, Any], key: ClaimKey, path: str) -> int | None:
    raw = end.get(key.value)
    if raw is None and key.value not in end:
        return None
    if isinstance(raw, bool) or not isinstance(raw, int) or raw < 0:
        raise InputError(f"{path}: end marker's {key.value!r} must be a count (an integer "
                         f">= 0), got {raw!r}")
    return raw


def _left_out(end: dict[str, Any], n_notes: int | None, path: str) -> frozenset[int] | None:
    if ClaimKey.LEFT_OUT.value not in end:
        return None
    raw = end[ClaimKey.LEFT_OUT.value]

    def note_ok(x) -> bool:
        i = x.get("note") if isinstance(x, dict) else None
        return (isinstance(i, int) and not isinstance(i, bool) and i >= 0
                and (n_notes is None or i < n_notes)
                and all(isinstance(x.get(k, ""), str) for k in ("reason", "detail")))

    if not isinstance(raw, list) or not all(note_ok(x) for x in raw):
        raise InputError(f"{path}: end marker's 'left_out' is not a list of notes of the song "
                         "({\"note\": index, \"reason\": text, \"detail\": text})")
    notes = [x["note"] for x in raw]
    if len(set(notes)) != len(notes):
        raise InputError(f"{path}: end marker's 'left_out' names a note twice")
    return frozenset(notes)


def read_claims(end: dict[str, Any], n_notes: int | None, path: str) -> PlayClaims:
    """The end marker's play claims, typed (``n_notes``: the song's, None without one).
    InputError naming the key when one is of the wrong type."""
    return PlayClaims(_count(end, ClaimKey.NOTES, path), _count(end, ClaimKey.PLAYED, path),
                      _left_out(end, n_notes, path))


def left_out_notes(end: dict[str, Any], n_notes: int, path: str) -> frozenset[int] | None:
    """The notes the end marker says the plan left out (None: it states none)."""
    return read_claims(end, n_notes, path).left_out


def count_mismatches(claims: PlayClaims, n_notes: int, n_missed: int) -> list[CountMismatch]:
    """Every count claim the replay of a song of ``n_notes`` (``n_missed`` missed)
    contradicts (each note of ``left_out`` is held against the replay apart)."""
    out = []
    if claims.notes is not None and claims.notes != n_notes:
        out.append(CountMismatch(ClaimKey.NOTES, claims.notes, n_notes,
                                 "the song has another number of notes"))
    if claims.played is not None and claims.played != n_notes - n_missed:
        out.append(CountMismatch(ClaimKey.PLAYED, claims.played, n_notes - n_missed,
                                 "the replay finds another number of notes hit"))
    return out
