"""The physics replay's report: frozen, its verdict, summary and JSON form (the shape
conventions of ``check``: ``ok``, ``problems``, the task's section, SI units)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from planner.resultform import listing, missed_note_line, plain
from planner.simulate.scores import JointTracking, MotorEffort, PhysicsCatch, PhysicsPlay


@dataclass(frozen=True)
class Replay:
    """What every physics replay's report opens with (one hand's, ``SimulateReport``; a
    pair's, ``planner.simulate.pairreport``): the file, the song, the task, the hand, the
    contact model, the rows replayed and how long they took. A report adds its own
    fields after these and ends with ``problems`` (its verdict: ``ok`` when there are
    none)."""

    trajectory: str
    song: str | None
    task: str
    hand: str
    contact: str
    rows: int
    duration_s: float
    wall_s: float

    @property
    def ok(self) -> bool:
        return not self.problems  # type: ignore[attr-defined]

    @property
    def realtime_factor(self) -> float:
        return self.duration_s / self.wall_s if self.wall_s > 0 else float("inf")

    def json_head(self) -> dict[str, Any]:
        """The report as JSON takes it, with the command, the verdict and the real-time
        factor."""
        d = plain(self)
        d["command"] = "simulate"
        d["ok"] = self.ok
        d["realtime_factor"] = self.realtime_factor
        return d

    def head_lines(self, timing: bool, hands: str) -> list[str]:
        """The summary's first lines: the verdict, the problems, what was replayed
        (``hands``: "hand NAME" or "two hands NAME"); ``timing`` False leaves out the wall
        time."""
        L = [f"simulate {self.trajectory}: {'OK' if self.ok else 'FAILED'}"]
        L.extend(f"  - {p}" for p in self.problems)  # type: ignore[attr-defined]
        took = (f" in {self.wall_s:.2f} s ({self.realtime_factor:.1f}x real time)" if timing
                else "")
        L.append(f"task {self.task}, {hands}, contact {self.contact}, {self.rows} rows, "
                 f"{self.duration_s:.3f} s simulated{took}")
        return L


@dataclass(frozen=True)
class SimulateReport(Replay):
    play: PhysicsPlay | None
    catch: PhysicsCatch | None
    motors: tuple[MotorEffort, ...]
    tracking: tuple[JointTracking, ...]
    kinematic_f1: float | None  # the kinematic check's F1 of the same file and song
    problems: tuple[str, ...]

    def to_dict(self) -> dict[str, Any]:
        d = self.json_head()
        for m, dd in zip(self.motors, d["motors"]):
            dd["ratio"] = m.ratio
        return d

    def summary(self, timing: bool = True) -> str:
        """The report as text; ``timing`` False leaves out the wall time (a picture's
        page: the same bytes for the same input)."""
        L = self.head_lines(timing, f"hand {self.hand}")
        p = self.play
        if p is not None:
            play_lines(L, p, self.song, self.kinematic_f1)
        c = self.catch
        if c is not None:
            lt = "never" if c.last_touch_s is None else f"{c.last_touch_s:.3f} s"
            L.append(f"catch: ball {'HELD' if c.held else 'NOT held'} from {c.held_from_s:.3f} s "
                     f"to the end ({c.end_distance_m * 1000:.1f} mm from the palm centre at the "
                     f"end, {c.contacts_at_end} contacts, last touched at {lt}); peak contact "
                     f"force {c.peak_contact_force_n:.1f} N")
        effort_lines(L, self.motors, self.tracking)
        return "\n".join(L)


def play_lines(L: list[str], p: PhysicsPlay, song: str | None, kinematic_f1: float | None,
               keys_note: str = "") -> None:
    """Append a replay's key lines to the summary ``L``: the key presses, the song's
    physics scores beside the kinematic F1, the wrong keys and the missed notes (one
    hand's replay, or both hands' with ``keys_note``)."""
    L.append(f"keys: {len(p.played)} key presses in physics{keys_note}")
    if p.f1 is not None:
        kin = "" if kinematic_f1 is None else f"; kinematic F1 {kinematic_f1:.4f}"
        L.append(f"song {song}: physics frame F1 {p.f1:.4f} over {p.song_frames} "
                 f"frames (precision {p.precision:.4f}, recall {p.recall:.4f}){kin}; "
                 f"notes hit {p.notes_hit}/{p.notes}, {len(p.late)} late, "
                 f"{len(p.wrong_keys)} wrong keys, {len(p.overhangs)} overhangs")
    listing(L, "wrong keys", p.wrong_keys, lambda w: (
        f"{w.start_s:8.3f}-{w.end_s:.3f} s  {w.name:4s} ({w.pitch})  "
        f"{'+'.join(w.fingers) or 'no finger (the key returning)'}"))
    listing(L, "missed notes", p.missed, missed_note_line)


def effort_lines(L: list[str], motors: tuple[MotorEffort, ...],
                 tracking: tuple[JointTracking, ...], indent: str = "",
                 name_width: tuple[int, int] = (22, 18)) -> None:
    """Append a hand's motor and tracking lines to the summary ``L``: each motor's peak
    demand beside its limit and its longest saturation, each joint's tracking error (mm
    for a rig axis, deg for the others), headed at ``indent``, the names padded to
    ``name_width`` (motors, joints)."""
    mw, jw = name_width
    L.append(f"{indent}motors (peak demand / limit, longest saturation):")
    for m in motors:
        L.append(f"{indent}  {m.name:{mw}s} {m.peak_demand_nm:8.3f} / {m.limit_nm:.3f} N m "
                 f"({m.ratio:5.2f})  {m.saturated_s * 1000:5.0f} ms at {m.at_s:.3f} s")
    L.append(f"{indent}tracking error per joint (max, rms):")
    for j in tracking:
        unit = "mm" if j.unit == "m" else "deg"
        f = 1000.0 if unit == "mm" else 57.29577951308232
        L.append(f"{indent}  {j.name:{jw}s} {j.max_error * f:8.2f} {unit}  rms "
                 f"{j.rms_error * f:6.2f}  worst at {j.at_s:.3f} s")
