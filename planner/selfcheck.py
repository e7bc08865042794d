"""The planner's own verdict: the rows it wrote, replayed by the check's rules.

``SelfCheck`` takes every chunk of rows as the file holds them (rounded to its
decimals), finds the keys down with the check's kinematics and key-down rule (spec
section 2's bodies: ``planner.check.bodykeys``), and at the end scores them against the song with
the check's own ``SongScorer``, and audits the rows' limits with the check's own
``LimitAudit`` (motor torques with the hand's inertia, tendon tensions, speeds), both
block by block as the rows come.
The summary and the end marker's claims are that verdict, so ``check`` never finds
a note missed that the planner says it played, nor a wrong press or a limit
violation the planner did not name; ``Verdict.rejected`` says what ``check`` would
fail the plan for, and ``play`` exits 1 on it. (Memory: a block of rows, and per row
its time, its keys down as bits, the fingers holding them and its frame scores: about 50
bytes a row, 18 MB an hour of music at 100 Hz.)
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import Any

import numpy as np

from planner.check.bodykeys import bed_hits, bed_problem, body_keys, body_names
from planner.check.criteria import BODY_BED_DEPTH_M, DOWN_DEPTH_M, N_KEYS, tip_depths
from planner.check.episodes import EpisodeStream
from planner.check.keys import SongScore, SongScorer, frame_period, score_song
from planner.check.kinematics import Kinematics
from planner.check.limits import LimitAudit
from planner.check.results import BodyBedHit, LimitCheck
from planner.hand.bodies import collision_bodies
from planner.hand.model import HandModel
from planner.play.costs import Skip, SkipReason
from planner.trajfile import distinct_rows

BATCH_ROWS = 2000  # rows judged at once (20 s at 100 Hz: 0.7 MB of rows waiting at most)


@dataclass(frozen=True)
class Verdict:
    """What the rows do to the song: notes played, skipped (with reasons), late, and
    the check's full score."""

    notes: int
    skipped: tuple[Skip, ...]
    score: SongScore
    limits: tuple[LimitCheck, ...] = ()  # the check's limit audit of the rows
    bed_hits: tuple[BodyBedHit, ...] = ()  # bodies past a key's bed (check's rule)

    @property
    def played(self) -> int:
        return self.notes - len(self.skipped)

    @property
    def violations(self) -> tuple[LimitCheck, ...]:
        return tuple(lc for lc in self.limits if not lc.ok)

    @property
    def rejected(self) -> bool:
        """What ``check``'s default verdict fails: a wrong press, a body past a key's bed
        or a limit violation."""
        return bool(self.score.wrong_presses or self.bed_hits or self.violations)

    def problem_lines(self) -> list[str]:
        """The summary's lines for every key the replay finds down late and every wrong
        press."""
        out = [f"  late: t={lt.onset_s:.3f} s {lt.name} key down {lt.late_s * 1000:.0f} ms "
               "late (too fast for the motors)" for lt in self.score.late]
        out += [f"  WRONG PRESS: {w.start_s:.3f}-{w.end_s:.3f} s {w.name} by "
                f"{'+'.join(w.fingers) or '?'} (no note of that key sounds then)"
                for w in self.score.wrong_presses]
        out += [f"  BED: {line}" for line in bed_problem(self.bed_hits)]
        out += [f"  LIMIT: {lc.count} {lc.category.replace('_', ' ')} violations (worst "
                f"{lc.worst:.6g} vs {lc.limit:.6g} {lc.unit}, {lc.name} at {lc.time_s:.3f} s)"
                for lc in self.violations]
        return out

    def end_info(self) -> dict[str, Any]:
        """The end marker's claims (``check`` holds them against its replay)."""
        info: dict[str, Any] = {
            "notes": self.notes, "played": self.played,
            "left_out": [{"note": s.note, "reason": s.reason.value, "detail": s.detail}
                         for s in self.skipped]}
        if self.violations:  # (should one reach the end, the file says so)
            info["limit_violations"] = [
                {"category": lc.category, "count": lc.count, "worst": lc.worst,
                 "limit": lc.limit, "name": lc.name, "time_s": lc.time_s}
                for lc in self.violations]
        return info


class SelfCheck:
    """Judges the rows written as they come: keys scored against the song and limits
    audited block by block (``SongScorer``, ``LimitAudit``); ``verdict`` finishes both."""

    def __init__(self, hand: HandModel, rate_hz: float) -> None:
        self._hand = hand
        self._kin = Kinematics(hand, hand.T_world_root)
        self._nj = hand.n
        self._rate_hz = rate_hz
        self._bodies = collision_bodies(hand.spec)
        self._names, self._of_body = body_names(self._bodies)
        self._bed = EpisodeStream(N_KEYS)
        self._audit = LimitAudit(hand, self._kin, inertia=True)
        self._t: list[np.ndarray] = []  # (every row's time: 8 bytes a row)
        self._blocks: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []  # (t, down, finger)
        self._scorer: SongScorer | None = None
        self._pending: list[np.ndarray] = []  # (rows not judged yet)
        self._pending_rows = 0
        self._rows = 0

    def add_rows(self, rows: np.ndarray) -> None:
        """Rows as written: (n, 1 + joints + motors), t first. They are judged
        ``BATCH_ROWS`` at a time (the planner writes a few dozen rows at once: the key
        rule's array work per call would cost more than the rows), the rest by
        ``verdict``."""
        if len(rows) == 0:
            return
        self._pending.append(np.array(rows, dtype=float))
        self._pending_rows += len(rows)
        if self._pending_rows >= BATCH_ROWS:
            self._judge()

    def _judge(self) -> None:
        if not self._pending:
            return
        rows = np.concatenate(self._pending)
        self._pending, self._pending_rows = [], 0
        nj = self._nj
        q = rows[:, 1:1 + nj]
        # (the rule is row by row: a row equal to the one before it, a hand holding still,
        # is judged once; about three rows in four on the corpus)
        new, of = distinct_rows(q)
        depth = tip_depths(self._kin.tips_of(q[new]))[1]
        bk = body_keys(self._kin, q, self._bodies)
        t = rows[:, 0].copy()
        down = bk.down
        finger = np.where(down, self._of_body[bk.body], -1).astype(np.int8)
        self._t.append(t)
        self._rows += len(t)
        self._bed.add(bk.depth_m > BODY_BED_DEPTH_M, t, bk.body, bk.depth_m)
        self._audit.add(t, q, rows[:, 1 + nj:],
                        (np.nan_to_num(depth, nan=-1.0) >= DOWN_DEPTH_M)[of])
        if self._scorer is not None:
            self._scorer.add(t, down, finger)
        else:  # (the song's notes come with the verdict: kept as bits till then)
            self._blocks.append((t, np.packbits(down, axis=1), finger[down]))

    def start_scoring(self, notes) -> None:
        """Score the rows against ``notes`` as they come (else they wait for ``verdict``,
        the keys down kept)."""
        self._scorer = SongScorer(notes, self._rate_hz, self._names)
        for t, bits, held in self._blocks:
            down = np.unpackbits(bits, axis=1, count=N_KEYS).astype(bool)
            finger = np.full(down.shape, -1, dtype=np.int8)
            finger[down] = held
            self._scorer.add(t, down, finger)
        self._blocks = []

    def verdict(self, notes, left_out: dict[int, tuple[enum.Enum, str]]) -> Verdict:
        """Score the rows against ``notes``; ``left_out`` are the planner's own skips
        (note index -> (reason, detail)). Every note the replay finds missed is skipped:
        with the planner's reason when it left the note out, else as ``MISSED``."""
        self._judge()
        if self._rows == 0:
            score = score_song(np.zeros(1), np.zeros((1, N_KEYS), dtype=bool), None, notes,
                               self._rate_hz, self._names)
        else:
            if self._scorer is None:
                self.start_scoring(notes)
            score = self._scorer.finish(np.concatenate(self._t))
        skipped = []
        for m in score.missed:
            if m.note in left_out:
                skipped.append(Skip(m.note, *left_out[m.note]))
            else:
                skipped.append(Skip(m.note, SkipReason.MISSED, f"replay: {m.reason}"))
        limits = tuple(self._audit.finish()[0]) if self._rows >= 2 else ()
        t_all = np.concatenate(self._t) if self._t else np.zeros(1)
        beds = bed_hits(self._bed.finish(frame_period(t_all)), self._bodies)
        return Verdict(len(notes), tuple(skipped), score, limits, beds)
