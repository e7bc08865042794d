"""What the check of a two-hand plan found (``planner.check.pair``): the keys of both hands
judged together, each hand's own report, the distance between the hands; its summary and
its JSON form."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from planner.check.handgap import HandsGap
from planner.check.results import CheckReport, PlayResult, limit_lines, play_lines
from planner.resultform import listing, plain


@dataclass(frozen=True)
class PairReport:
    """Everything the check of a two-hand plan found. ``play``: the keys of both hands
    against the whole song; ``hands``: each hand's own report (its keys against the notes
    its ``by_hand`` claim gives it, its limits), in the order of ``prefixes``; ``gap``:
    the distance between the hands. ``ok`` is the verdict; ``problems`` says why not
    (each hand's prefixed by it)."""

    trajectory: str
    song: str | None
    task: str
    hand: str
    urdf_sha256: str
    complete: bool
    rows: int
    duration_s: float
    rate_hz: float
    play: PlayResult
    prefixes: tuple[str, str]
    hands: tuple[CheckReport, CheckReport]
    gap: HandsGap
    min_f1: float | None
    problems: tuple[str, ...]
    song_start_s: float = 0.0

    @property
    def ok(self) -> bool:
        return not self.problems

    def to_dict(self) -> dict[str, Any]:
        """A JSON-serialisable dict: the pair's keys and gap, ``hands`` each hand's report
        (as ``CheckReport.to_dict``) with its ``prefix``."""
        d = plain({k: v for k, v in self.__dict__.items() if k != "hands"})
        d["ok"] = self.ok
        d["play"]["hit_rate"] = self.play.hit_rate
        d["gap"]["ok"] = self.gap.ok
        d["hands"] = [{"prefix": p, **r.to_dict()} for p, r in zip(self.prefixes, self.hands)]
        return d

    def summary(self) -> str:
        """A readable multi-line account, verdict first: both hands' keys, the gap
        between them, then each hand's own keys and limits."""
        L = [f"check {self.trajectory}: {'OK' if self.ok else 'FAILED'}"]
        L.extend(f"  - {p}" for p in self.problems)
        L.append(f"task {self.task}, two hands {self.hand} ("
                 + ", ".join(f"{p} {r.hand}" for p, r in zip(self.prefixes, self.hands))
                 + f"), {self.rows} rows, {self.duration_s:.3f} s at {self.rate_hz:g} Hz"
                 + ("" if self.complete else " (INCOMPLETE file: no end marker)"))
        play_lines(L, self.play, self.song, self.min_f1, "either hand's bodies")
        g = self.gap
        L.append(f"between the hands: least distance {g.least_m * 1000:.1f} mm ({g.left_body} "
                 f"and {g.right_body} at {g.time_s:.3f} s); a row closer than "
                 f"{g.limit_m * 1000:g} mm is a collision: {len(g.collisions)} "
                 f"({g.collision_rows} rows)")
        listing(L, "collisions between the hands", g.collisions, lambda c: (
            f"{c.start_s:8.3f}-{c.end_s:.3f} s (row {c.row}, {c.rows} rows)  {c.left_body} and "
            f"{c.right_body} {c.least_m * 1000:.1f} mm apart at {c.time_s:.3f} s"))
        for pre, r in zip(self.prefixes, self.hands):
            L.append(f"hand {pre} {r.hand}: {'OK' if r.ok else 'FAILED'}")
            p = r.play
            if p.notes is not None:
                L.append(f"  its notes (by_hand): {p.notes_hit}/{p.notes} hit by its own "
                         f"bodies, frame F1 {p.f1:.4f} on them alone")
                listing(L, "  notes it claims and misses", p.claim_mismatches, lambda c: (
                    f"{c.onset_s:8.3f} s  {c.name:4s} ({c.pitch})  note {c.note}"))
            M: list[str] = []
            limit_lines(M, r.limits, r.tendons)
            L.extend("  " + m for m in M)
        return "\n".join(L)
