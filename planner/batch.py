"""Batch planning: every song of a folder planned and checked, in parallel, resumable.

``batch_plan(songs_dir, out_dir, workers=2)`` plans each ``*.mid`` of ``songs_dir`` into
``out_dir/<name>.csv``, replays it through the independent check, and records the
outcome in ``out_dir/<name>.json`` (written whole, after the check: a song whose record
is there, for the same song bytes and hand, with its trajectory complete, is done and
skipped by the next run). The summary of every song goes to ``out_dir/summary.csv`` and
``summary.json``.

Workers are local processes (each builds its planner once and plans song after song);
with ``address`` the songs go to a Ray cluster instead (the ``batch`` extra; one task a
song). Results are returned in the songs' order, whatever order they finish in.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import os
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict, dataclass
from functools import cache
from pathlib import Path

from planner.errors import InputError, PlannerError

SUMMARY_FIELDS = ("song", "notes", "played", "infeasible", "frame_f1", "check_ok",
                  "planning_s", "realtime_factor", "trajectory", "error")


@dataclass(frozen=True)
class SongResult:
    """One song's outcome (``error``: why it has no plan, else empty)."""

    song: str
    notes: int
    played: int
    infeasible: int
    frame_f1: float
    check_ok: bool
    planning_s: float
    realtime_factor: float
    trajectory: str
    error: str = ""
    song_sha256: str = ""
    hand: str = ""
    skipped: bool = False  # done by an earlier run (this run only read its record)


@dataclass(frozen=True)
class BatchSummary:
    results: tuple[SongResult, ...]

    @property
    def planned(self) -> int:
        return sum(not r.skipped and not r.error for r in self.results)

    @property
    def skipped(self) -> int:
        return sum(r.skipped for r in self.results)

    @property
    def failed(self) -> int:
        return sum(bool(r.error) for r in self.results)

    @property
    def ok(self) -> bool:
        """Every song has a plan its check passes."""
        return not any(r.error or not r.check_ok for r in self.results)

    def to_dict(self) -> dict:
        """``batch --json``: the counts and every song's result."""
        return {"command": "batch", "planned": self.planned, "skipped": self.skipped,
                "failed": self.failed, "songs": [asdict(r) for r in self.results]}

    def format(self, out_dir: str | os.PathLike) -> str:
        """The closing line: the counts and where the summary is."""
        return (f"{len(self.results)} songs: {self.planned} planned, {self.skipped} done "
                f"before, {self.failed} failed -> {Path(out_dir) / 'summary.csv'}")


def format_song_line(r: SongResult) -> str:
    """One song's line as it finishes: counts, F1, the check (or why it failed)."""
    if r.error:
        msg = f"failed: {r.error}"
    else:
        msg = (f"{r.played}/{r.notes} played, frame F1 {r.frame_f1:.4f}, check "
               f"{'OK' if r.check_ok else 'FAILED'}"
               + (" (done before)" if r.skipped else f", {r.realtime_factor:.0f}x"))
    return f"{r.song}: {msg}"


def batch_plan(songs_dir: str | os.PathLike, out_dir: str | os.PathLike, workers: int = 2,
               hand: str = "default", address: str | None = None,
               on_result: Callable[[SongResult], None] | None = None,
               on_progress: Callable[[int, int], None] | None = None) -> BatchSummary:
    """Plan and check every song of ``songs_dir`` into ``out_dir`` (see the module
    docstring); ``on_result`` is called as each song finishes (or is found done), then
    ``on_progress(songs done, songs)``."""
    if not Path(songs_dir).is_dir():
        raise InputError(f"{songs_dir}: no such folder")
    songs = sorted(Path(songs_dir).glob("*.mid"))
    if not songs:
        raise InputError(f"{songs_dir}: no MIDI files (*.mid) in it")
    if not isinstance(workers, int) or workers < 1:
        raise InputError(f"--workers must be a positive whole number, got {workers}")
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise InputError(f"cannot create {out}: {e.strerror}") from None
    results: dict[Path, SongResult] = {}

    def record(s: Path, r: SongResult) -> None:
        results[s] = r
        if on_result:
            on_result(r)
        if on_progress:
            on_progress(len(results), len(songs))

    todo = []
    for s in songs:
        done = _done(s, out, hand)
        if done is None:
            todo.append(s)
        else:
            record(s, done)
    for s, r in _run(todo, out, hand, workers, address):
        record(s, r)
    summary = BatchSummary(tuple(results[s] for s in songs))
    _write_summary(summary, out)
    return summary


def _run(songs: list[Path], out: Path, hand: str, workers: int, address: str | None):
    """(song, result) as they finish."""
    if not songs:
        return
    if address is not None:
        yield from _run_ray(songs, out, hand, address)
        return
    if workers == 1:
        for s in songs:
            yield s, plan_one(str(s), str(out), hand)
        return
    with ProcessPoolExecutor(max_workers=min(workers, len(songs))) as pool:
        futures = {pool.submit(plan_one, str(s), str(out), hand): s for s in songs}
        for f in as_completed(futures):
            yield futures[f], f.result()


def _run_ray(songs: list[Path], out: Path, hand: str, address: str):
    try:
        import ray
    except ImportError:
        raise InputError('--address needs Ray: pip install -e ".[batch]" (or ray)') from None
    try:
        ray.init(address=None if address == "local" else address, ignore_reinit_error=True,
                 log_to_driver=False)
    except (ConnectionError, ValueError, RuntimeError) as e:
        first = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        raise InputError(f"--address {address}: cannot join the Ray cluster ({first}); a "
                         "cluster started with token authentication (Ray >= 2.52) needs "
                         "RAY_AUTH_MODE=token and its token (ray get-auth-token)") from None
    task = ray.remote(plan_one)
    pending = {task.remote(str(s), str(out), hand): s for s in songs}
    while pending:
        ready, _ = ray.wait(list(pending), num_returns=1)
        for ref in ready:
            yield pending.pop(ref), ray.get(ref)


def _song_sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _done(song: Path, out: Path, hand: str) -> SongResult | None:
    """The recorded result of ``song`` when it is done for these bytes and this hand."""
    rec = out / f"{song.stem}.json"
    try:
        d = json.loads(rec.read_text(encoding="utf-8"))
        r = SongResult(**{k: d[k] for k in SongResult.__dataclass_fields__ if k != "skipped"})
    except (OSError, ValueError, KeyError, TypeError):
        return None
    if r.error or r.song_sha256 != _song_sha256(song) or r.hand != hand:
        return None
    from planner.trajfile import read_trajectory

    try:
        if not read_trajectory(str(out / r.trajectory)).complete:
            return None
    except (InputError, OSError):
        return None
    return SongResult(**{**asdict(r), "skipped": True})


def plan_one(song_path: str, out_dir: str, hand_name: str) -> SongResult:
    """Plan and check one song (in a worker: its planner is built once per process)."""
    from planner.check import check_trajectory
    from planner.music.midi import load_song
    from planner.output import write_file
    from planner.play import plan_song

    song = Path(song_path)
    traj = f"{song.stem}.csv"
    traj_path = str(Path(out_dir) / traj)
    base = {"song": song.name, "song_sha256": _song_sha256(song), "hand": hand_name,
            "trajectory": traj}
    try:
        parsed = load_song(song_path)
        planner = _planner(hand_name)
        plan = plan_song(parsed, planner.hand, traj_path, song_name=song.name,
                         planner=planner)
        rep = check_trajectory(traj_path, song_path)
        song_s = max((n.offset_s for n in parsed.notes), default=0.0)
        r = SongResult(notes=plan.verdict.notes, played=plan.verdict.played,
                       infeasible=len(plan.verdict.skipped), frame_f1=float(rep.play.f1),
                       check_ok=bool(rep.ok), planning_s=float(plan.planning_s),
                       realtime_factor=float(song_s / plan.planning_s), **base)
    except (InputError, PlannerError) as e:
        r = SongResult(notes=0, played=0, infeasible=0, frame_f1=0.0, check_ok=False,
                       planning_s=0.0, realtime_factor=0.0, error=str(e), **base)
    record = {k: v for k, v in asdict(r).items() if k != "skipped"}
    write_file(Path(out_dir) / f"{song.stem}.json", json.dumps(record, indent=1) + "\n")
    return r


@cache
def _planner(hand_name: str):
    """The worker's planner for a hand, built on its first song."""
    from planner.hand.model import load_hand
    from planner.play import Planner

    return Planner(load_hand(hand_name))


def _write_summary(summary: BatchSummary, out: Path) -> None:
    from planner.output import write_file

    rows = [{k: getattr(r, k) for k in SUMMARY_FIELDS} for r in summary.results]
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=SUMMARY_FIELDS, lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    write_file(out / "summary.csv", buf.getvalue())
    write_file(out / "summary.json", json.dumps({"songs": rows}, indent=1) + "\n")
