"""What the check found: frozen results, their summary and their JSON form."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from planner.check.ballroll import ROLL_ROOM_M
from planner.check.claims import CountMismatch
from planner.check.criteria import BODY_BED_DEPTH_M, INTERCEPT_TOL_M, KEY_BED_DEPTH_M
from planner.resultform import listing, missed_note_line, plain


@dataclass(frozen=True)
class LimitCheck:
    """One audited quantity: how many samples exceed their limit and the worst one.

    ``worst`` is the sample with the largest value relative to its limit (for
    positions: the largest excess beyond a bound; when nothing is violated,
    the closest approach), ``limit`` its limit, ``name`` the joint or motor,
    ``time_s`` the row's time. ``count`` counts (row, joint) samples.
    """

    category: str
    count: int
    worst: float
    limit: float
    name: str
    time_s: float
    unit: str

    @property
    def ok(self) -> bool:
        return self.count == 0


@dataclass(frozen=True)
class TendonLoad:
    """One tendon over the replay: its worst tension at the spool (``worst_n``, N, at
    ``time_s``) against its design force (``limit_n``); ``count`` rows beyond it (1 %)."""

    name: str
    count: int
    worst_n: float
    limit_n: float
    time_s: float

    @property
    def ok(self) -> bool:
        return self.count == 0


@dataclass(frozen=True)
class KeyEpisode:
    """A key held down over contiguous frames: [start_s, end_s), by these fingers."""

    pitch: int
    name: str
    start_s: float
    end_s: float
    fingers: tuple[str, ...]


@dataclass(frozen=True)
class KeyBedHit:
    """A fingertip more than KEY_BED_DEPTH_M below the top of the key it is over."""

    time_s: float
    finger: str
    pitch: int
    name: str
    depth_m: float


@dataclass(frozen=True)
class BodyBedHit:
    """Rows ``row``.. (from ``time_s`` to ``end_s``) in which a collision body reaches
    more than 1 mm past the key bed in a key's footprint (spec section 2): the deepest
    reach (``depth_m`` below the key's top) and its body."""

    time_s: float
    row: int
    end_s: float
    pitch: int
    name: str
    link: str
    body: str
    depth_m: float


@dataclass(frozen=True)
class MissedNote:
    onset_s: float
    offset_s: float
    pitch: int
    name: str
    fraction_down: float  # of the note's frames
    reason: str
    note: int = -1  # its index in the song


@dataclass(frozen=True)
class LateNote:
    """A note hit, but whose key first went down ``late_s`` after its onset (> LATE_S)."""

    onset_s: float
    pitch: int
    name: str
    late_s: float
    note: int = -1  # its index in the song


@dataclass(frozen=True)
class ClaimMismatch:
    """A note whose outcome the plan's end marker states otherwise than the replay finds:
    ``claimed`` is "played" or "left out", ``found`` "missed" or "hit"."""

    note: int
    onset_s: float
    pitch: int
    name: str
    claimed: str
    found: str


@dataclass(frozen=True)
class PlayResult:
    """Keys, notes and the frame metrics of a play trajectory.

    ``f1``/``precision``/``recall`` and the note counts are None without a song.
    ``played`` are all key-down episodes (what the trajectory plays). The scores are
    over the song's frames (``song_frames``, criteria); ``claim_mismatches`` holds the
    notes the plan's end marker claims otherwise than the replay finds.
    """

    frames: int
    played: tuple[KeyEpisode, ...]
    key_bed_hits: tuple[KeyBedHit, ...]
    f1: float | None = None
    precision: float | None = None
    recall: float | None = None
    notes: int | None = None
    notes_hit: int | None = None
    missed: tuple[MissedNote, ...] = ()
    wrong_presses: tuple[KeyEpisode, ...] = ()
    late: tuple[LateNote, ...] = ()
    song_frames: int | None = None  # the frames F1 is computed over
    claims: bool = False  # the file's end marker states per-note outcomes
    claim_mismatches: tuple[ClaimMismatch, ...] = ()
    count_mismatches: tuple[CountMismatch, ...] = ()  # the marker's counts the replay contradicts
    body_bed_hits: tuple[BodyBedHit, ...] = ()  # a body more than 1 mm past a key's bed

    @property
    def hit_rate(self) -> float | None:
        if self.notes is None:
            return None
        return 1.0 if self.notes == 0 else self.notes_hit / self.notes


@dataclass(frozen=True)
class TipTouch:
    time_s: float
    finger: str
    distance_m: float  # tip to ball centre


@dataclass(frozen=True)
class BallLoad:
    """The ball's load on the hand in one phase of a catch (``stop``: decelerated from its
    speed relative to the palm over the planned stopping distance; ``hold``: riding the
    palm, at the worst row): the force the hand applies (N), where the rows need it, and
    the motor closest to its capacity (``planner.hand.tendon.actuator_capacity``)."""

    phase: str
    time_s: float
    force_n: float
    speed_m_s: float  # stop: the ball's speed relative to the palm; hold: 0
    distance_m: float  # stop: the stopping distance; hold: 0
    motor: str
    torque_nm: float
    capacity_nm: float
    limiting_part: str
    motor_headroom: tuple[float, ...] = ()  # 1 - |torque| / capacity of every motor (worst)
    cone_margin_n: float | None = None  # mu F_n - |F_t| on the palm before the grasp (least;
    # None: the fingers hold the ball throughout)

    @property
    def headroom(self) -> float:
        """1 - |torque| / capacity of the motor closest to its capacity."""
        return 1.0 - abs(self.torque_nm) / self.capacity_nm


@dataclass(frozen=True)
class CatchResult:
    """The catch audit; ``ok`` when the ball meets the palm, nothing touches it
    early, and the grasp closes within the window and holds."""

    intercept_t: float
    radius_m: float
    ball_at_intercept: tuple[float, float, float]
    palm_target: tuple[float, float, float]  # palm_center + radius * normal
    intercept_error_m: float | None
    intercept_ok: bool
    early_touches: tuple[TipTouch, ...]
    grasp_time_s: float | None
    grasp_fingers: tuple[str, ...]
    grasp_held: bool
    min_tip_distance_after_m: float | None
    problems: tuple[str, ...]
    loads: tuple[BallLoad, ...] = ()  # stopping and holding the ball: force and motors
    live: dict[str, Any] | None = None  # a live plan's end marker: outcome, reason
    roll_m: float | None = None  # the landed ball's largest roll towards the wrist on the
    # rows (``planner.check.ballroll``; None when the intercept is outside the rows)

    @property
    def ok(self) -> bool:
        return not self.problems


@dataclass(frozen=True)
class Replay:
    """Per-row arrays of the replay (not serialised), for plots and animations.

    ``tips`` (T, 5, 3) world fingertip points in ``FINGERS`` order; ``palm``
    (T, 4, 4) world palm_center poses; ``down`` (T, 88) the keys down by the body rule,
    ``finger`` (T, 88) who holds each (an index into ``holders``: the fingers, then the
    other links, ``planner.check.bodykeys.body_names``; -1 none); ``key_depth_m`` (T, 88)
    how deep the bodies push each key where they hold it down (``BodyKeys.depth_m``);
    ``expected`` (T, 88) bool or None without a song.
    """

    t_s: np.ndarray
    q: np.ndarray
    tips: np.ndarray
    palm: np.ndarray
    down: np.ndarray | None = None
    finger: np.ndarray | None = None
    expected: np.ndarray | None = None
    holders: tuple[str, ...] = ()
    key_depth_m: np.ndarray | None = None


@dataclass(frozen=True)
class CheckReport:
    """Everything the check found. ``ok`` is the verdict; ``problems`` says why not."""

    trajectory: str
    song: str | None
    task: str
    hand: str
    urdf_sha256: str
    complete: bool
    rows: int
    duration_s: float
    rate_hz: float
    limits: tuple[LimitCheck, ...]
    play: PlayResult | None
    catch: CatchResult | None
    min_f1: float | None
    problems: tuple[str, ...]
    replay: Replay | None = field(default=None, compare=False, repr=False)
    tendons: tuple[TendonLoad, ...] = ()  # the worst tension of every tendon
    song_start_s: float = 0.0  # the song's time 0 in the file's time (format version 2)

    @property
    def ok(self) -> bool:
        return not self.problems

    def to_dict(self) -> dict[str, Any]:
        """A JSON-serialisable dict (the replay arrays are left out)."""
        d = plain(self)
        d.pop("replay", None)
        d["ok"] = self.ok
        if self.play is not None:
            d["play"]["hit_rate"] = self.play.hit_rate
        if self.catch is not None:
            d["catch"]["ok"] = self.catch.ok
            for ld, dd in zip(self.catch.loads, d["catch"]["loads"]):
                dd["headroom"] = ld.headroom
        for lc, dd in zip(self.limits, d["limits"]):
            dd["ok"] = lc.ok
        for tl, dd in zip(self.tendons, d["tendons"]):
            dd["ok"] = tl.ok
        return d

    def summary(self) -> str:
        """A readable multi-line account, verdict first."""
        L = [f"check {self.trajectory}: {'OK' if self.ok else 'FAILED'}"]
        for p in self.problems:
            L.append(f"  - {p}")
        L.append(f"task {self.task}, hand {self.hand}, {self.rows} rows, "
                 f"{self.duration_s:.3f} s at {self.rate_hz:g} Hz"
                 + ("" if self.complete else " (INCOMPLETE file: no end marker)"))
        if self.play is not None:
            play_lines(L, self.play, self.song, self.min_f1)
        if self.catch is not None:
            c = self.catch
            err = "n/a" if c.intercept_error_m is None else f"{c.intercept_error_m * 1000:.1f} mm"
            L.append(f"catch at t={c.intercept_t:.3f} s: ball {err} from palm target "
                     f"(max {INTERCEPT_TOL_M * 1000:g} mm); "
                     + (f"grasp at {c.grasp_time_s:.3f} s by {'+'.join(c.grasp_fingers)}"
                        + ("" if c.grasp_held else ", NOT held")
                        if c.grasp_time_s is not None else "no grasp"))
            for ld in c.loads:
                what = (f"{ld.speed_m_s:.2f} m/s relative to the palm over "
                        f"{1000 * ld.distance_m:g} mm" if ld.distance_m > 0 else
                        "riding the palm as it slows" if ld.phase == "stop" else "on the palm")
                L.append(f"  {ld.phase}: {ld.force_n:.1f} N at {ld.time_s:.3f} s ({what}): "
                         f"motor.{ld.motor} {abs(ld.torque_nm):.3f} of {ld.capacity_nm:.3f} N m "
                         f"({ld.limiting_part}), headroom {100 * ld.headroom:.0f} %")
            if c.roll_m is not None:
                L.append(f"  roll: the ball rolls at most {1000 * c.roll_m:.1f} mm towards the "
                         f"wrist on the palm (room {1000 * ROLL_ROOM_M:g} mm)")
            if c.live:
                L.append(f"  live plan: {c.live.get('catch')}: {c.live.get('reason')}")
            listing(L, "early touches", c.early_touches, lambda e: (
                f"{e.time_s:8.3f} s  {e.finger:6s} {e.distance_m * 1000:.1f} mm from the centre"))
        limit_lines(L, self.limits, self.tendons)
        return "\n".join(L)


def play_lines(L: list[str], p: PlayResult, song: str | None, min_f1: float | None,
               by: str = "the hand's bodies") -> None:
    """A summary's lines of a play's keys (held down ``by``): presses, the song's scores,
    the listings."""
    L.append(f"keys (by {by}, spec section 2): {len(p.played)} key presses, "
             f"{len(p.key_bed_hits) + len(p.body_bed_hits)} key-bed hits")
    if p.f1 is not None:
        L.append(f"song {song}: frame F1 {p.f1:.4f} over its {p.song_frames} frames "
                 f"(precision {p.precision:.4f}, recall {p.recall:.4f}); notes hit "
                 f"{p.notes_hit}/{p.notes}, {len(p.late)} late"
                 + (f"; required F1 >= {min_f1:g}" if min_f1 is not None else ""))
    listing(L, "wrong presses", p.wrong_presses, lambda w: (
        f"{w.start_s:8.3f}-{w.end_s:.3f} s  {w.name:4s} ({w.pitch})  "
        f"{'+'.join(w.fingers) or '?'}"))
    listing(L, "missed notes", p.missed, missed_note_line)
    listing(L, "late notes", p.late, lambda n: (
        f"{n.onset_s:8.3f} s  {n.name:4s} ({n.pitch})  key down {n.late_s * 1000:.0f} ms "
        "after the onset"))
    listing(L, "claims the replay contradicts", p.claim_mismatches, lambda c: (
        f"{c.onset_s:8.3f} s  {c.name:4s} ({c.pitch})  note {c.note}: the plan says "
        f"{c.claimed}, the replay finds it {c.found}"))
    listing(L, "counts the replay contradicts", p.count_mismatches, lambda c: (
        f"{c.key.value}: the plan says {c.claimed}, the replay finds {c.found}"))
    listing(L, "key-bed hits", p.key_bed_hits, lambda h: (
        f"{h.time_s:8.3f} s  {h.finger:6s} {h.name:4s} ({h.pitch})  "
        f"{h.depth_m * 1000:.2f} mm below the top (max {KEY_BED_DEPTH_M * 1000:g})"))
    listing(L, "body key-bed hits", p.body_bed_hits, lambda h: (
        f"{h.time_s:8.3f}-{h.end_s:.3f} s (row {h.row})  {h.name:4s} ({h.pitch})  "
        f"{h.body} {h.depth_m * 1000:.2f} mm below the top (max "
        f"{BODY_BED_DEPTH_M * 1000:g})"))


def limit_lines(L: list[str], limits, tendons) -> None:
    """A summary's lines of the limit audit and the tendons."""
    L.append("limits (count, worst / limit, where):")
    for lc in limits:
        L.append(f"  {lc.category:18s} {'ok  ' if lc.ok else 'FAIL'} {lc.count:6d}  "
                 f"{lc.worst:.6g} / {lc.limit:.6g} {lc.unit}  {lc.name} at {lc.time_s:.3f} s")
    if tendons:
        L.append("tendons (count, worst tension at the spool / design force, when):")
        for tl in tendons:
            L.append(f"  {tl.name:20s} {'ok  ' if tl.ok else 'FAIL'} {tl.count:6d}  "
                     f"{tl.worst_n:.4g} / {tl.limit_n:.4g} N at {tl.time_s:.3f} s")
