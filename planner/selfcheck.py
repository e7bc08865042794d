"""The planner's own verdict: the rows it wrote, replayed by the check's rules.

``SelfCheck`` takes every chunk of rows as the file holds them (rounded to its
decimals), finds the keys down with the check's kinematics and key-down rule
(``planner.check.criteria``), and at the end scores them against the song with
the check's own ``score_song``, and audits the rows' limits with the check's own
``limit_audit`` (motor torques with the hand's inertia, tendon tensions, speeds).
The summary and the end marker's claims are that verdict, so ``check`` never finds
a note missed that the planner says it played, nor a wrong press or a limit
violation the planner did not name; ``Verdict.rejected`` says what ``check`` would
fail the plan for, and ``play`` exits 1 on it. (The audit keeps the rows until the
end: 350 bytes a row, 125 MB an hour of music at 100 Hz.)
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import Any

import numpy as np

from planner.check.criteria import DOWN_DEPTH_M, key_contacts
from planner.check.keys import SongScore, score_song
from planner.check.kinematics import Kinematics
from planner.check.limits import limit_audit
from planner.check.results import LimitCheck
from planner.hand.model import HandModel
from planner.play.costs import Skip, SkipReason
from planner.trajfile import Trajectory, distinct_rows

BATCH_ROWS = 2000  # rows judged at once (20 s at 100 Hz: 0.7 MB of rows waiting at most)


@dataclass(frozen=True)
class Verdict:
    """What the rows do to the song: notes played, skipped (with reasons), late, and
    the check's full score."""

    notes: int
    skipped: tuple[Skip, ...]
    score: SongScore
    limits: tuple[LimitCheck, ...] = ()  # the check's limit audit of the rows

    @property
    def played(self) -> int:
        return self.notes - len(self.skipped)

    @property
    def violations(self) -> tuple[LimitCheck, ...]:
        return tuple(lc for lc in self.limits if not lc.ok)

    @property
    def rejected(self) -> bool:
        """What ``check``'s default verdict fails: a wrong press or a limit violation."""
        return bool(self.score.wrong_presses or self.violations)

    def problem_lines(self) -> list[str]:
        """The summary's lines for every key the replay finds down late and every wrong
        press."""
        out = [f"  late: t={lt.onset_s:.3f} s {lt.name} key down {lt.late_s * 1000:.0f} ms "
               "late (too fast for the motors)" for lt in self.score.late]
        out += [f"  WRONG PRESS: {w.start_s:.3f}-{w.end_s:.3f} s {w.name} by "
                f"{'+'.join(w.fingers) or '?'} (no note of that key sounds then)"
                for w in self.score.wrong_presses]
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
    """Collects the key states of the rows written; ``verdict`` scores them."""

    def __init__(self, hand: HandModel, rate_hz: float) -> None:
        self._hand = hand
        self._kin = Kinematics(hand, hand.T_world_root)
        self._nj = hand.n
        self._rows: list[np.ndarray] = []  # (every row as written, for the limit audit)
        self._pressing: list[np.ndarray] = []
        self._rate_hz = rate_hz
        self._t: list[np.ndarray] = []
        self._down: list[np.ndarray] = []
        self._finger: list[np.ndarray] = []
        self._pending: list[np.ndarray] = []  # (rows not judged yet, t and joints)
        self._pending_rows = 0

    def add_rows(self, rows: np.ndarray) -> None:
        """Rows as written: (n, 1 + joints + motors), t first. They are judged
        ``BATCH_ROWS`` at a time (the planner writes a few dozen rows at once: the key
        rule's array work per call would cost more than the rows), the rest by
        ``verdict``."""
        if len(rows) == 0:
            return
        self._pending.append(rows[:, :1 + self._nj])
        self._rows.append(np.array(rows, dtype=float))
        self._pending_rows += len(rows)
        if self._pending_rows >= BATCH_ROWS:
            self._judge()

    def _judge(self) -> None:
        if not self._pending:
            return
        rows = np.concatenate(self._pending)
        self._pending, self._pending_rows = [], 0
        q = rows[:, 1:1 + self._nj]
        # (the rule is row by row: a row equal to the one before it, a hand holding still,
        # is judged once; about three rows in four on the corpus)
        new, of = distinct_rows(q)
        tips, _ = self._kin.frames_of(q[new])
        kc = key_contacts(tips)
        self._t.append(rows[:, 0].copy())
        self._down.append(kc.down[of])
        self._finger.append(kc.finger[of])
        self._pressing.append((np.nan_to_num(kc.tip_depth, nan=-1.0) >= DOWN_DEPTH_M)[of])

    def verdict(self, notes, left_out: dict[int, tuple[enum.Enum, str]]) -> Verdict:
        """Score the rows against ``notes``; ``left_out`` are the planner's own skips
        (note index -> (reason, detail)). Every note the replay finds missed is skipped:
        with the planner's reason when it left the note out, else as ``MISSED``."""
        self._judge()
        t = np.concatenate(self._t) if self._t else np.zeros(1)
        down = np.concatenate(self._down) if self._down else np.zeros((1, 88), dtype=bool)
        finger = np.concatenate(self._finger) if self._finger else None
        score = score_song(t, down, finger, notes, self._rate_hz)
        skipped = []
        for m in score.missed:
            if m.note in left_out:
                skipped.append(Skip(m.note, *left_out[m.note]))
            else:
                skipped.append(Skip(m.note, SkipReason.MISSED, f"replay: {m.reason}"))
        return Verdict(len(notes), tuple(skipped), score, self._limits())

    def _limits(self) -> tuple[LimitCheck, ...]:
        """The check's limit audit of every row written (as ``check`` runs it on a play:
        the keys pushing back on the pressing tips, the hand's inertia)."""
        if sum(len(r) for r in self._rows) < 2:
            return ()
        rows = np.concatenate(self._rows)
        h, nj = self._hand, self._nj
        tr = Trajectory({}, h.joint_names, h.motor_names, rows[:, 0], rows[:, 1:1 + nj],
                        rows[:, 1 + nj:], True)
        limits, _ = limit_audit(h, self._kin, tr, np.concatenate(self._pressing), None,
                                inertia=True)
        return tuple(limits)
