"""Batch planning: every song of a folder planned and checked, in parallel, resumable.

``batch_plan(songs_dir, out_dir, workers=2)`` plans each ``*.mid`` of ``songs_dir`` into
``out_dir/<name>.csv``, replays it through the independent check, and records the
outcome in ``out_dir/<name>.json`` (written whole, after the check: a song whose record
is there, for the same song bytes and hand, with its trajectory complete, is done and
skipped by the next run). The summary of every song goes to ``out_dir/summary.csv`` and
``summary.json`` (those names are reserved: a song named ``summary.mid`` is recorded as
failed, its outputs never overwrite the summary's). Entries of ``songs_dir`` that are not
MIDI files (another suffix, a folder named ``x.mid``, a file without a MIDI header) are
skipped, each with a line (``on_skip``). A song whose planning fails, however, is
recorded as failed with its one-line reason and the batch goes on.

SIGINT, SIGTERM or SIGHUP (``KeyboardInterrupt``) stop the workers at once
(``planner.batchpool``), the summary of the songs done is written, and the
interrupt goes on to the command line (exit 128 + the signal's number).

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
from dataclasses import asdict, dataclass, replace
from functools import cache
from pathlib import Path

from planner.errors import InputError, PlannerError

RESERVED_STEMS = ("summary",)  # the summary's file names (summary.csv, summary.json)
MIDI_MAGIC = (b"MThd", b"RIFF")  # a standard MIDI file, or one wrapped in RIFF (RMID)
SUMMARY_FIELDS = ("song", "notes", "played", "infeasible", "frame_f1", "check_ok",
                  "planning_s", "realtime_factor", "trajectory", "error", "physics_f1",
                  "physics_wrong_keys", "physics_saturated_ms", "physics_ok",
                  "physics_saturated_motor", "physics_error")


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
    # with ``physics``: the MuJoCo replay's verdict (``planner.simulate``, full contact)
    physics_f1: float | None = None
    physics_wrong_keys: int | None = None
    physics_saturated_ms: float | None = None  # the longest run of a motor at its limit
    physics_ok: bool | None = None
    physics_saturated_motor: str | None = None  # the motor of that run ("" when none)
    physics_error: str = ""  # why the replay of a plan failed (the plan and check stand)


@dataclass(frozen=True)
class PhysicsTotals:
    """The physics replays of a batch together: how many plans were replayed (their
    verdict OK; the replays that failed to run), the mean and lowest F1 (its song; None
    when no replay ran), the wrong keys of all of them, the longest motor saturation of
    any (its song and motor: "" when none saturated)."""

    replayed: int
    ok: int
    failed: int
    mean_f1: float | None
    min_f1: float | None
    min_f1_song: str
    wrong_keys: int
    saturated_ms: float
    saturated_song: str
    saturated_motor: str

    def format(self) -> str:
        sat = (f"{self.saturated_ms:.0f} ms ({self.saturated_motor}, {self.saturated_song})"
               if self.saturated_ms > 0 else "0 ms")
        f1 = ("no F1" if self.mean_f1 is None else
              f"F1 mean {self.mean_f1:.4f}, lowest {self.min_f1:.4f} ({self.min_f1_song})")
        failed = f" ({self.failed} failed to run)" if self.failed else ""
        return (f"physics: {self.replayed} replayed{failed}, {self.ok} OK; {f1}; "
                f"{self.wrong_keys} wrong keys; longest motor saturation {sat}")


def physics_totals(results: tuple[SongResult, ...]) -> PhysicsTotals | None:
    """The ``PhysicsTotals`` of the plans replayed in physics, or whose replay failed
    (None: the batch replayed none)."""
    tried = [r for r in results if not r.error and (r.physics_f1 is not None
                                                    or r.physics_error)]
    if not tried:
        return None
    rs = [r for r in tried if r.physics_f1 is not None]
    low = min(rs, key=lambda r: r.physics_f1, default=None)
    sat = max(rs, key=lambda r: r.physics_saturated_ms, default=None)
    any_sat = sat is not None and sat.physics_saturated_ms > 0
    return PhysicsTotals(len(tried), sum(bool(r.physics_ok) for r in tried),
                         sum(bool(r.physics_error) for r in tried),
                         sum(r.physics_f1 for r in rs) / len(rs) if rs else None,
                         None if low is None else low.physics_f1,
                         "" if low is None else low.song,
                         sum(r.physics_wrong_keys for r in rs),
                         sat.physics_saturated_ms if any_sat else 0.0,
                         sat.song if any_sat else "",
                         (sat.physics_saturated_motor or "") if any_sat else "")


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
        """Every song has a plan its check passes (and its physics, when replayed)."""
        return not any(r.error or not r.check_ok or r.physics_ok is False
                       for r in self.results)

    @property
    def physics(self) -> PhysicsTotals | None:
        """The physics replays together (None: the batch replayed none)."""
        return physics_totals(self.results)

    def to_dict(self) -> dict:
        """``batch --json``: the counts, the physics totals (null without ``--physics``)
        and every song's result."""
        ph = self.physics
        return {"command": "batch", "ok": self.ok, "planned": self.planned,
                "skipped": self.skipped, "failed": self.failed,
                "physics": None if ph is None else asdict(ph),
                "songs": [asdict(r) for r in self.results]}

    def format(self, out_dir: str | os.PathLike) -> str:
        """The closing lines: the counts and where the summary is; the physics totals
        when the plans were replayed."""
        line = (f"{len(self.results)} songs: {self.planned} planned, {self.skipped} done "
                f"before, {self.failed} failed -> {Path(out_dir) / 'summary.csv'}")
        ph = self.physics
        return line if ph is None else f"{line}\n{ph.format()}"


def format_song_line(r: SongResult) -> str:
    """One song's line as it finishes: counts, F1, the check (or why it failed)."""
    if r.error:
        msg = f"failed: {r.error}"
    else:
        msg = (f"{r.played}/{r.notes} played, frame F1 {r.frame_f1:.4f}, check "
               f"{'OK' if r.check_ok else 'FAILED'}"
               + (" (done before)" if r.skipped else f", {r.realtime_factor:.0f}x"))
        if r.physics_error:
            msg += f"; physics FAILED: {r.physics_error}"
        elif r.physics_f1 is not None:
            msg += (f"; physics F1 {r.physics_f1:.4f}, {r.physics_wrong_keys} wrong keys, "
                    f"longest motor saturation {r.physics_saturated_ms:.0f} ms"
                    + (f" ({r.physics_saturated_motor})" if r.physics_saturated_motor else "")
                    + ", "
                    f"{'OK' if r.physics_ok else 'FAILED'}")
    return f"{r.song}: {msg}"


def batch_plan(songs_dir: str | os.PathLike, out_dir: str | os.PathLike, workers: int = 2,
               hand: str = "default", address: str | None = None,
               on_result: Callable[[SongResult], None] | None = None,
               on_progress: Callable[[int, int], None] | None = None,
               on_skip: Callable[[str, str], None] | None = None,
               physics: bool = False) -> BatchSummary:
    """Plan and check every song of ``songs_dir`` into ``out_dir`` (see the module
    docstring); ``on_result`` is called as each song finishes (or is found done), then
    ``on_progress(songs done, songs)``; ``on_skip(entry, why)`` for an entry that is
    not a MIDI file. ``physics``: every plan is also replayed in MuJoCo (full contact,
    ``planner.simulate``: the ``physics`` extra), its F1, wrong keys and motor
    saturation recorded; a record without them is not done for such a batch."""
    if physics:
        from planner.simulate.scene import require_mujoco

        require_mujoco()  # (the clear message before any song)
    if not Path(songs_dir).is_dir():
        raise InputError(f"{songs_dir}: no such folder")
    songs = midi_files(Path(songs_dir), on_skip)
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
        done = _reserved(s, hand) or _done(s, out, hand, physics)
        if done is None:
            todo.append(s)
        else:
            record(s, done)
    try:
        for s, r in _run(todo, out, hand, workers, address, physics):
            record(s, r)
    except KeyboardInterrupt:  # (the workers are stopped: the summary of what is done)
        for s in todo:  # (a worker writes its record before this process hears of it)
            if s not in results and (late := _done(s, out, hand, physics)) is not None:
                results[s] = replace(late, skipped=False)  # (done by this run)
        _write_summary(BatchSummary(tuple(results[s] for s in songs if s in results)), out)
        raise
    summary = BatchSummary(tuple(results[s] for s in songs))
    _write_summary(summary, out)
    return summary


def midi_files(folder: Path, on_skip: Callable[[str, str], None] | None) -> list[Path]:
    """The MIDI files of ``folder`` (``*.mid`` regular files that start as one), by name;
    every other entry is told to ``on_skip`` with why."""
    out = []
    for p in sorted(folder.iterdir()):
        why = None
        if p.suffix.lower() != ".mid":
            why = "not a .mid file"
        elif not p.is_file():
            why = "not a regular file (a folder?)"
        else:
            try:
                with open(p, "rb") as f:
                    if f.read(4) not in MIDI_MAGIC:
                        why = "not a MIDI file (no MThd header)"
            except OSError as e:
                why = f"cannot read it: {e.strerror or e}"
        if why is None:
            out.append(p)
        elif on_skip:
            on_skip(p.name, why)
    return out


def _failed(song: Path, hand: str, why: str) -> SongResult:
    return SongResult(song=song.name, notes=0, played=0, infeasible=0, frame_f1=0.0,
                      check_ok=False, planning_s=0.0, realtime_factor=0.0,
                      trajectory=f"{song.stem}.csv", error=why, hand=hand)


def _reserved(song: Path, hand: str) -> SongResult | None:
    """A failed result for a song whose outputs would be the summary's files."""
    if song.stem.lower() not in RESERVED_STEMS:
        return None
    r = _failed(song, hand, f"its outputs ({song.stem}.csv, {song.stem}.json) would be the "
                            "batch summary's files: rename the song")
    return SongResult(**{**asdict(r), "trajectory": ""})


def _run(songs: list[Path], out: Path, hand: str, workers: int, address: str | None,
         physics: bool):
    """(song, result) as they finish."""
    if not songs:
        return
    if address is not None:
        yield from _run_ray(songs, out, hand, address, physics)
        return
    if workers == 1:
        for s in songs:
            yield s, plan_one(str(s), str(out), hand, physics)
        return
    from planner.batchpool import Failed, WorkerPool

    with WorkerPool(_plan_task, min(workers, len(songs))) as pool:
        for (s, *_), r in pool.run([(s, out, hand, physics) for s in songs]):
            yield s, (_failed(s, hand, r.reason) if isinstance(r, Failed) else r)


def _plan_task(task: tuple[Path, Path, str, bool]) -> SongResult:
    song, out, hand, physics = task
    return plan_one(str(song), str(out), hand, physics)


def _run_ray(songs: list[Path], out: Path, hand: str, address: str, physics: bool):
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
    pending = {task.remote(str(s), str(out), hand, physics): s for s in songs}
    try:
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=1)
            for ref in ready:
                s = pending.pop(ref)
                try:
                    r = ray.get(ref)
                except Exception as e:  # noqa: BLE001 -- (a task that died: this song failed)
                    r = _failed(s, hand, f"{type(e).__name__}: "
                                         f"{(str(e).strip().splitlines() or [''])[0]}"[:500])
                yield s, r
    finally:  # (done, or interrupted: no task of this batch keeps running)
        for ref in pending:
            ray.cancel(ref, force=True)


def _song_sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _done(song: Path, out: Path, hand: str, physics: bool = False) -> SongResult | None:
    """The recorded result of ``song`` when it is done for these bytes and this hand
    (and replayed in physics, when ``physics``)."""
    rec = out / f"{song.stem}.json"
    try:
        d = json.loads(rec.read_text(encoding="utf-8"))
        r = SongResult(**{k: d[k] for k in SongResult.__dataclass_fields__ if k != "skipped"})
    except (OSError, ValueError, KeyError, TypeError):
        return None
    if r.error or r.song_sha256 != _song_sha256(song) or r.hand != hand:
        return None
    if physics and (r.physics_f1 is None or r.physics_error):
        return None  # (not replayed, or the replay failed: again)
    from planner.trajfile import read_trajectory

    try:
        if not read_trajectory(str(out / r.trajectory)).complete:
            return None
    except (InputError, OSError):
        return None
    return SongResult(**{**asdict(r), "skipped": True})


def plan_one(song_path: str, out_dir: str, hand_name: str, physics: bool = False) -> SongResult:
    """Plan and check one song (in a worker: its planner is built once per process);
    ``physics``: replay it in MuJoCo too (``physics_verdict``)."""
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
        rep = check_trajectory(traj_path, song_path, replay=False)
        song_s = max((n.offset_s for n in parsed.notes), default=0.0)
        r = SongResult(notes=plan.verdict.notes, played=plan.verdict.played,
                       infeasible=len(plan.verdict.skipped), frame_f1=float(rep.play.f1),
                       check_ok=bool(rep.ok), planning_s=float(plan.planning_s),
                       realtime_factor=float(song_s / plan.planning_s), **base,
                       **(_physics_fields(traj_path, song_path) if physics else {}))
    except (InputError, PlannerError) as e:
        r = SongResult(notes=0, played=0, infeasible=0, frame_f1=0.0, check_ok=False,
                       planning_s=0.0, realtime_factor=0.0, error=str(e), **base)
    except Exception as e:  # noqa: BLE001 -- a planner bug fails this song, not the batch
        first = (str(e).strip().splitlines() or [""])[0]
        r = SongResult(notes=0, played=0, infeasible=0, frame_f1=0.0, check_ok=False,
                       planning_s=0.0, realtime_factor=0.0,
                       error=f"{type(e).__name__}: {first}"[:500], **base)
    record = {k: v for k, v in asdict(r).items() if k != "skipped"}
    write_file(Path(out_dir) / f"{song.stem}.json", json.dumps(record, indent=1) + "\n")
    return r


def _physics_fields(traj_path: str, song_path: str) -> dict:
    """``physics_verdict``; a replay that fails (bad input to MuJoCo, a bug) fails the
    song's physics with its one-line reason, keeping its plan and check."""
    try:
        return physics_verdict(traj_path, song_path)
    except Exception as e:  # noqa: BLE001 -- (the replay's failure, not the plan's)
        first = (str(e).strip().splitlines() or [""])[0]
        return {"physics_ok": False, "physics_error": f"{type(e).__name__}: {first}"[:500]}


def physics_verdict(traj_path: str, song_path: str) -> dict:
    """A plan's physics replay (full contact) as a ``SongResult``'s physics fields."""
    from planner.simulate import simulate_trajectory

    rep = simulate_trajectory(traj_path, song_path)
    play = rep.play
    worst = max(rep.motors, key=lambda m: m.saturated_s, default=None)
    sat_s = 0.0 if worst is None else worst.saturated_s
    return {"physics_f1": None if play.f1 is None else float(play.f1),
            "physics_wrong_keys": len(play.wrong_keys),
            "physics_saturated_ms": 1000.0 * sat_s,
            "physics_ok": bool(rep.ok),
            "physics_saturated_motor": worst.name if sat_s > 0 else ""}


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
    ph = summary.physics
    write_file(out / "summary.json", json.dumps(
        {"songs": rows, "physics": None if ph is None else asdict(ph)}, indent=1) + "\n")
