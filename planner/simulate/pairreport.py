"""The physics replay's report of a two-hand plan (``planner.simulate.pair``): the keys
of both hands together, each hand's notes, motors and tracking, the contacts between the
hands; its verdict, summary and JSON form (``SimulateReport``'s conventions)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from planner.resultform import listing
from planner.simulate.report import Replay, effort_lines, play_lines
from planner.simulate.scores import JointTracking, MotorEffort, PhysicsPlay


@dataclass(frozen=True)
class HandPhysics:
    """One hand of the pair in the physics: the notes its ``by_hand`` claim gives it
    (None without a song or the claim) and how many of them sound, the wrong keys its own
    fingers pressed, its motors and its joints' tracking (names prefixed)."""

    prefix: str
    hand: str
    notes: int | None
    notes_hit: int | None
    wrong_keys: int
    motors: tuple[MotorEffort, ...]
    tracking: tuple[JointTracking, ...]


@dataclass(frozen=True)
class HandsTouch:
    """Rows ``row``.. (``start_s`` to ``end_s``) in which a geom of one hand touches one of
    the other in the physics: a collision between the hands (the first pair named)."""

    start_s: float
    row: int
    end_s: float
    rows: int
    left_geom: str
    right_geom: str


@dataclass(frozen=True)
class PairSimulateReport(Replay):
    play: PhysicsPlay
    hands: tuple[HandPhysics, HandPhysics]
    touches: tuple[HandsTouch, ...]
    kinematic_f1: float | None  # the kinematic check's F1 (both hands) of the same file
    problems: tuple[str, ...]

    @property
    def motors(self) -> tuple[MotorEffort, ...]:
        """Every motor of both hands (named ``motor.<prefix><name>``)."""
        return tuple(m for h in self.hands for m in h.motors)

    def to_dict(self) -> dict[str, Any]:
        d = self.json_head()
        for h, dh in zip(self.hands, d["hands"]):
            for m, dd in zip(h.motors, dh["motors"]):
                dd["ratio"] = m.ratio
        return d

    def summary(self, timing: bool = True) -> str:
        L = self.head_lines(timing, f"two hands {self.hand}")
        play_lines(L, self.play, self.song, self.kinematic_f1, " (either hand)")
        L.append(f"between the hands: {len(self.touches)} contacts in physics")
        listing(L, "contacts between the hands", self.touches, lambda c: (
            f"{c.start_s:8.3f}-{c.end_s:.3f} s (row {c.row}, {c.rows} rows)  {c.left_geom} "
            f"and {c.right_geom}"))
        for h in self.hands:
            notes = ("" if h.notes is None else
                     f": its notes (by_hand) {h.notes_hit}/{h.notes} sound")
            L.append(f"hand {h.prefix} {h.hand}{notes}, {h.wrong_keys} wrong keys by its "
                     "fingers")
            effort_lines(L, h.motors, h.tracking, "  ", (26, 24))
        return "\n".join(L)
