"""The ``hand-trajectory`` file, version 2 written, 1, 2 and 3 read (interface spec,
section 4; version 2 adds ``song_start_s``: the song's time 0 in the file's time; version 3
is two hands in one file, written by ``planner.pairfile`` through this writer).

``TrajectoryWriter`` streams rows into the named path itself as they are
planned, flushed per chunk, each row first passed by the hardware guard
(``planner.guard``: a row outside the hand's joint position or speed limits is refused,
so none reaches a file, a pipe or a plan kept in memory), so a reader can follow the file while it grows
(``planner.output``: a FIFO, a device or a symlink's target is written, never
replaced). The end marker is what says the file is complete: a plan that stops
early leaves a file without it, which every reader must call incomplete. The
end marker also carries the plan's own per-note claims (``end_info``), which
``check --strict`` holds against its replay.
"""

from __future__ import annotations

import io
import json
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from planner.errors import InputError, PlannerError
from planner.guard import guard_rows
from planner.output import open_stream, write_file

if TYPE_CHECKING:
    from planner.hand.model import HandModel

FORMAT = "hand-trajectory"
VERSION = 2  # written; read: READ_VERSIONS
PAIR_VERSION = 3  # two hands in one file (``planner.pairfile``)
READ_VERSIONS = (1, 2, PAIR_VERSION)  # 2 adds song_start_s and the end marker's claims; 3 two hands
_MAX_META_CHARS = 1 << 20  # a metadata line longer than this is not one (e.g. /dev/zero)


def distinct_rows(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Which rows differ from the row before them (the first always does: a hand holding
    still repeats its row), and each row's index among those: ``rows[new][of]`` is
    ``rows``. Row-by-row work (formatting, forward kinematics, the key-down rule) is done
    on ``rows[new]`` and spread back by ``of``."""
    new = np.ones(len(rows), dtype=bool)
    new[1:] = np.any(rows[1:] != rows[:-1], axis=1)
    return new, np.cumsum(new) - 1


AS_TEXT_ABS = 1e12  # values past this are read from their text (a time of 30,000 years)


def as_written(x: np.ndarray) -> np.ndarray:
    """What a file holds for each value of ``x``, ``float("%.6f" % v)``, bit for bit,
    without reading the text back (the writer hands its rows to a self-check): ``n``,
    ``x * 1e6`` rounded to an integer, is the text's digits (both round half to even)
    unless the product's own rounding could decide, within its float spacing of a half
    (those, and any value not finite or past ``AS_TEXT_ABS``, are read from their text);
    and ``n / 1e6`` is the double nearest the text's number, as reading it gives (both
    correctly rounded: ``n`` and 1e6 are exact)."""
    x = np.asarray(x, dtype=float)
    y = x * 1e6
    n = np.rint(y)
    out = n / 1e6
    with np.errstate(invalid="ignore"):
        odd = ~(np.abs(np.abs(y - n) - 0.5) > np.spacing(np.abs(y))) | ~(np.abs(x) < AS_TEXT_ABS)
    if odd.any():
        out[odd] = [float(f"{v:.6f}") for v in x[odd].tolist()]
    return out


class FormattedRows(NamedTuple):
    """Rows as a file's text (``text``: one line each) and as the file holds them
    (``written``: (n, columns), times and values rounded to its 6 decimals), with the
    joint positions they were made from (``q``, unrounded: what the guard judges)."""

    t_s: np.ndarray
    text: str
    written: np.ndarray
    q: np.ndarray


def format_rows(t_s: np.ndarray, q: np.ndarray, q_motor: np.ndarray) -> FormattedRows:
    """Rows (times in s, joint positions, motor angles) as ``TrajectoryWriter.append``
    writes them: a pure function of the rows, so that a live plan can format rows no
    estimate changes ahead of the observation that writes them."""
    t_s = np.asarray(t_s, dtype=float)
    q = np.asarray(q, dtype=float)
    if len(t_s) == 0:
        return FormattedRows(t_s, "", np.empty((0, 0)), q)
    if len(t_s) == 1:  # (a live observation's usual row: no repeats to look for)
        line = f"{float(t_s[0]):.6f}," + ",".join(["%.6f"] * (q.shape[1] + q_motor.shape[1])
                                                  ) % (*q[0].tolist(), *q_motor[0].tolist())
        return FormattedRows(t_s, line + "\n",
                             as_written(np.concatenate([t_s, q[0], q_motor[0]]))[None], q)
    if not np.all(np.diff(t_s) > 0):
        raise PlannerError(f"trajectory time not increasing near t={t_s[0]}")
    body = np.column_stack([q, q_motor])
    # a row whose setpoints equal the row's before is formatted (and read back) once
    new, of_row = distinct_rows(body)
    fmt = ",".join(["%.6f"] * body.shape[1])
    distinct = [fmt % tuple(r) for r in body[new].tolist()]
    of = of_row.tolist()
    times = [f"{t:.6f}" for t in t_s.tolist()]
    text = "\n".join([f"{a},{distinct[j]}" for a, j in zip(times, of)]) + "\n"
    # (the values as written, without reading the text back: ``as_written``)
    return FormattedRows(t_s, text, np.column_stack([as_written(t_s),
                                                     as_written(body[new])[of_row]]), q)


def joined_rows(parts: list[FormattedRows]) -> FormattedRows:
    """Successive rows formatted apart (``format_rows``), as one: the same text, values
    and rows, for one ``TrajectoryWriter.append`` (one guard over them all, whose speeds
    across the parts' seams are those the parts' own appends would judge)."""
    if len(parts) == 1:
        return parts[0]
    return FormattedRows(np.concatenate([p.t_s for p in parts]), "".join(p.text for p in parts),
                         np.concatenate([p.written for p in parts]),
                         np.concatenate([p.q for p in parts]))


def metadata_line(metadata: dict[str, Any]) -> str:
    """A file's first line: ``# `` and its metadata as JSON, format and version first."""
    meta = {"format": FORMAT, "version": VERSION, **metadata}
    return "# " + json.dumps(meta, sort_keys=False, separators=(", ", ": ")) + "\n"


def header_line(joint_names, motor_names) -> str:
    """The column header: ``t``, the joints, ``motor.<name>`` of each motor."""
    return ",".join(["t", *joint_names, *(f"motor.{m}" for m in motor_names)]) + "\n"


def end_line(rows: int, end_info: dict[str, Any] | None = None) -> str:
    """The end marker: ``# {"end": true, "rows": n, ...end_info}``."""
    end = {"end": True, "rows": rows, **(end_info or {})}
    return "# " + json.dumps(end, separators=(", ", ": ")) + "\n"


class TrajectoryWriter:
    """Streams a trajectory of ``hand`` (a ``HandModel``, or a ``HandPair``: two hands'
    prefixed columns and limits, ``planner.pairfile``): the constructor opens the path and
    writes metadata and header (the hand's joints and motors), ``write_rows`` appends setpoints,
    each passed by the hand's guard first (``planner.guard``: a row out of the joint
    position or speed limits raises SolverError and is not written), ``close`` writes the
    end marker."""

    def __init__(self, path: str | None, metadata: dict[str, Any], hand: HandModel,
                 on_rows: Callable[[np.ndarray], None] | None = None,
                 defer_header: bool = False) -> None:
        """``on_rows`` is given every chunk of rows as the file holds them (a self-check).
        ``path`` None: the text is kept in memory (``text`` once closed). ``defer_header``:
        metadata and header are written with the first rows (``add_metadata`` first)."""
        self.path = path
        self.hand = hand
        self._on_rows = on_rows
        self.rows = 0
        self._last_t = -math.inf
        self._last_q: np.ndarray | None = None  # the last row written, for its speed
        self.columns = header_line(hand.joint_names, hand.motor_names)[:-1].split(",")
        self._out = io.StringIO() if path is None else open_stream(path)
        self.text: str | None = None
        self._meta: dict[str, Any] | None = dict(metadata)
        if not defer_header:
            self._start()

    def add_metadata(self, **extra: Any) -> None:
        """Metadata known only once planning has begun (``song_start_s``), added before
        the first row (a writer made with ``defer_header``)."""
        if self._meta is None:
            raise PlannerError("the trajectory's metadata is written already")
        self._meta.update(extra)

    def _start(self) -> None:
        """Metadata and header, once."""
        if self._meta is None:
            return
        meta, self._meta = self._meta, None
        self._out.write(metadata_line(meta))
        self._out.write(header_line(self.hand.joint_names, self.hand.motor_names))
        self._out.flush()

    def write_rows(self, t_s: np.ndarray, q: np.ndarray,
                   q_motor: np.ndarray | None = None) -> np.ndarray:
        """Append rows (times in s, joint positions, motor angles: the hand's of ``q``
        unless given) and flush. Returns the rows as the file holds them (rounded to its
        6 decimals), (n, columns)."""
        if q_motor is None:
            q_motor = self.hand.motor_angles(np.asarray(q, dtype=float))
        return self.append(format_rows(t_s, q, q_motor))

    def append(self, rows: FormattedRows) -> np.ndarray:
        """Append rows formatted ahead (``format_rows``) and flush; returns them as the
        file holds them."""
        if len(rows.t_s) == 0:
            return np.empty((0, len(self.columns)))
        self._start()
        if not rows.t_s[0] > self._last_t:
            raise PlannerError(f"trajectory time not increasing near t={rows.t_s[0]}")
        self._guard(rows)
        self._last_t, self._last_q = float(rows.t_s[-1]), rows.q[-1].copy()
        self._out.write(rows.text)
        self.rows += len(rows.t_s)
        self._out.flush()
        if self._on_rows is not None:
            self._on_rows(rows.written)
        return rows.written

    def _guard(self, rows: FormattedRows) -> None:
        """The hardware guard on ``rows`` (their speeds from the last row written on)."""
        t = rows.t_s if self._last_q is None else np.r_[self._last_t, rows.t_s]
        guard_rows(self.hand, rows.q, self._last_q, np.diff(t)[:, None] if len(t) > 1 else 1.0)

    def close(self, end_info: dict[str, Any] | None = None) -> None:
        """Write the end marker (with ``end_info``'s keys after ``end`` and ``rows``)."""
        self._start()
        self._out.write(end_line(self.rows, end_info))
        if self.path is None:
            self.text = self._out.getvalue()
        self._out.close()

    def abort(self, discard: bool = False) -> None:
        """Stop without the end marker: the file stays visibly incomplete. ``discard``
        (the input was found bad after opening) removes a regular file it created."""
        if discard and self.path is not None:
            self._out.discard()
            return
        try:
            self._out.close()
        except (PlannerError, BrokenPipeError):
            pass


ROW_TIME_TOL_S = 1e-6  # a row's t vs k / rate_hz: one unit of the 6 decimals written
MIN_ROWS = 2  # one row has no duration: no speed, no time to play anything


@dataclass(frozen=True)
class Trajectory:
    """A trajectory read back: metadata, column names, times (s), joint and motor
    arrays; ``end`` is the end marker's object (empty when incomplete)."""

    metadata: dict[str, Any]
    joint_names: tuple[str, ...]
    motor_names: tuple[str, ...]
    t_s: np.ndarray
    q: np.ndarray
    q_motor: np.ndarray
    complete: bool
    end: dict[str, Any] = field(default_factory=dict)


class KeptText:
    """A plan made in memory (``text``, None when it went into a file): its file read
    back (``trajectory``) or written whole (``write``). ``PlayPlan`` and ``CatchResult``
    have it."""

    text: str | None

    @property
    def trajectory(self) -> Trajectory:
        """The plan as read back from its file (times, joint and motor arrays)."""
        if self.text is None:
            raise PlannerError("the plan was written to a file: read it with read_trajectory")
        return parse_trajectory(self.text)

    def write(self, path: str) -> None:
        """Write a plan made in memory to ``path`` (whole: ``planner.output``), the same
        bytes as planning into it."""
        if self.text is None:
            raise PlannerError("the plan was written to a file already")
        write_file(path, self.text)


def read_trajectory(path: str, allow_incomplete: bool = False) -> Trajectory:
    """Read and validate a hand-trajectory v1 file; InputError (one line) on any defect,
    the first bad row named: rows must be at ``rate_hz`` from t = 0 (within
    ``ROW_TIME_TOL_S``), with no gap, at least ``MIN_ROWS`` of them."""
    return parse_trajectory(_read_text(path), path, allow_incomplete)


def parse_trajectory(text: str, path: str = "<memory>",
                     allow_incomplete: bool = False) -> Trajectory:
    """``read_trajectory`` of a file's text (``path`` names it in messages)."""
    terminated = text.endswith("\n")
    lines = text.split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    if len(lines) < 2 or not lines[0].startswith("# "):
        raise InputError(f"{path}: not a hand-trajectory file (no metadata line)")
    if lines[0].endswith("\r") or lines[1].endswith("\r"):
        raise InputError(f"{path}: its lines end in CR LF (a Windows editor?); the format's "
                         "line ends are LF alone (spec section 4)")
    meta = _metadata(lines[0], path)
    end = _end_marker(lines[-1])
    if end is not None:
        body = lines[2:-1]
        if end.get("rows") != len(body):
            raise InputError(f"{path}: end marker says {end.get('rows')} rows, file has {len(body)}")
    else:
        if not allow_incomplete:
            raise InputError(f"{path}: incomplete trajectory (no end marker); "
                             "use --allow-incomplete to read it anyway")
        body = lines[2:]
        if body and (body[-1].startswith("#") or not terminated):
            body = body[:-1]  # a damaged end marker, or a row still being written
    joint_cols, motor_cols = _header(lines[1], path)
    arr = _rows(body, 1 + len(joint_cols) + len(motor_cols), path)
    _check_clock(arr[:, 0], float(meta["rate_hz"]), path)
    nj = len(joint_cols)
    return Trajectory(meta, tuple(joint_cols), tuple(c[6:] for c in motor_cols), arr[:, 0],
                      arr[:, 1:1 + nj], arr[:, 1 + nj:], end is not None, end or {})


def _read_text(path: str) -> str:
    try:
        with open(path, encoding="utf-8", newline="") as f:
            text = f.readline(_MAX_META_CHARS)  # bounded: an endless first line is refused
            if not text.startswith("# "):
                raise InputError(f"{path}: not a hand-trajectory file (no metadata line)")
            return text + f.read()
    except FileNotFoundError:
        raise InputError(f"no such trajectory file: {path}") from None
    except (OSError, UnicodeDecodeError) as e:
        raise InputError(f"cannot read trajectory {path}: {e}") from None


def _metadata(line: str, path: str) -> dict[str, Any]:
    try:
        meta = json.loads(line[2:])
    except (json.JSONDecodeError, RecursionError):
        raise InputError(f"{path}: metadata line is not valid JSON") from None
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        raise InputError(f"{path}: not a hand-trajectory file (format is not {FORMAT!r})")
    version = meta.get("version")
    if isinstance(version, bool) or version not in READ_VERSIONS:
        raise InputError(f"{path}: unsupported version {version!r} (supported: 1, 2, 3)")
    for key in ("task", "hand", "urdf_sha256", "T_world_root", "rate_hz"):
        if key not in meta:
            raise InputError(f"{path}: metadata lacks required key {key!r}")
    if meta["task"] not in ("play", "catch"):
        raise InputError(f"{path}: task must be 'play' or 'catch', got {meta['task']!r}")
    if version == PAIR_VERSION and (meta["task"] != "play" or "hands" not in meta):
        raise InputError(f"{path}: a version-3 file is a play of two hands: its metadata "
                         "must have 'hands' and task 'play'")
    rate = meta["rate_hz"]
    if not is_num(rate) or not math.isfinite(rate) or not rate > 0:
        raise InputError(f"{path}: rate_hz must be a positive number, got {rate!r}")
    start = meta.get("song_start_s", 0.0)
    if not is_num(start) or not math.isfinite(start) or start < 0 or (start and version < 2):
        raise InputError(f"{path}: song_start_s must be a number >= 0 (format version 2), "
                         f"got {start!r}")
    return meta


def is_num(v: Any) -> bool:
    """A JSON number of the file (an int or a float, not a bool)."""
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def song_start_s(metadata: dict[str, Any]) -> float:
    """The file time at which the song's time 0 falls (version 2; 0 when absent): every
    reader shifts the song by it."""
    return float(metadata.get("song_start_s", 0.0))


def _end_marker(line: str) -> dict[str, Any] | None:
    if not line.startswith("# "):
        return None
    try:
        end = json.loads(line[2:])
    except (json.JSONDecodeError, RecursionError):
        return None
    return end if isinstance(end, dict) and end.get("end") is True else None


def _header(line: str, path: str) -> tuple[list[str], list[str]]:
    header = line.split(",")
    if not header or header[0] != "t":
        raise InputError(f"{path}: header must start with 't'")
    motor_cols = [c for c in header[1:] if c.startswith("motor.")]
    joint_cols = [c for c in header[1:] if not c.startswith("motor.")]
    if header[1:] != joint_cols + motor_cols:
        raise InputError(f"{path}: motor columns must follow the joint columns")
    if len(set(header)) != len(header):
        raise InputError(f"{path}: duplicate column names")
    return joint_cols, motor_cols


def _rows(body: list[str], n: int, path: str) -> np.ndarray:
    if len(body) < MIN_ROWS:
        raise InputError(f"{path}: {len(body)} row{'' if len(body) == 1 else 's'}; a trajectory "
                         f"has at least {MIN_ROWS}")
    try:
        arr = np.array([[float(x) for x in ln.split(",")] for ln in body], dtype=float)
    except ValueError:
        bad = next(i for i, ln in enumerate(body) if not _row_ok(ln, n))
        raise InputError(f"{path}: row {bad + 1} is not {n} numbers") from None
    if arr.ndim != 2 or arr.shape[1] != n:
        raise InputError(f"{path}: rows must have {n} values")
    if not np.all(np.isfinite(arr)):
        i = int(np.argwhere(~np.isfinite(arr))[0, 0])
        raise InputError(f"{path}: row {i + 1} has a NaN or infinite value")
    return arr


def _check_clock(t: np.ndarray, rate_hz: float, path: str) -> None:
    """Row k (1-based k + 1) at t = k / rate_hz: strictly increasing, no gap, no offset."""
    if len(t) > 1 and not np.all(np.diff(t) > 0):
        i = int(np.argmax(~(np.diff(t) > 0)))
        raise InputError(f"{path}: time not strictly increasing at row {i + 2} (t={t[i + 1]:.6f})")
    err = np.abs(t - np.arange(len(t)) / rate_hz)
    if np.any(err > ROW_TIME_TOL_S):
        i = int(np.argmax(err > ROW_TIME_TOL_S))
        raise InputError(f"{path}: row {i + 1} is at t={t[i]:.6f} s, not {i / rate_hz:.6f} s "
                         f"(rows are at rate_hz = {rate_hz:g} from t = 0)")


def _row_ok(line: str, n: int) -> bool:
    parts = line.split(",")
    if len(parts) != n:
        return False
    try:
        [float(x) for x in parts]
    except ValueError:
        return False
    return True


SCAN_BYTES = 1 << 20  # the pre-pass reads the file in pieces this large
STREAM_ROWS = 1024  # rows a streamed file yields at once (the rules' arrays of a block: ~15 MB)


class NotStreamable(Exception):
    """A file ``stream_trajectory`` leaves to ``read_trajectory``: not a regular file,
    not ASCII, or with any defect (whose message ``read_trajectory`` gives)."""


@dataclass(frozen=True)
class TrajectoryStream:
    """A regular trajectory file read as a stream: ``head`` is its metadata, columns and
    end marker (no rows: empty arrays), ``rows`` its count; ``blocks`` yields the rows,
    (t_s, q, q_motor), ``STREAM_ROWS`` at a time, each checked as ``read_trajectory``
    checks them (any defect: ``NotStreamable``)."""

    head: Trajectory
    path: str
    rows: int
    rate_hz: float

    def blocks(self, block_rows: int | None = None):
        block_rows = block_rows or STREAM_ROWS
        nj, nm = len(self.head.joint_names), len(self.head.motor_names)
        n, done, t_prev = 1 + nj + nm, 0, -math.inf
        with open(self.path, encoding="ascii", newline="\n") as f:
            f.readline()
            f.readline()
            while done < self.rows:
                lines = [f.readline() for _ in range(min(block_rows, self.rows - done))]
                try:
                    arr = np.array([[float(x) for x in ln.rstrip("\n").split(",")]
                                    for ln in lines], dtype=float)
                except ValueError:
                    raise NotStreamable("a row is not numbers") from None
                if arr.ndim != 2 or arr.shape[1] != n or not np.all(np.isfinite(arr)):
                    raise NotStreamable("a row is not numbers")
                t = arr[:, 0].copy()  # (kept by a reader: not a view of the block)
                k = np.arange(done, done + len(t))
                if (not t[0] > t_prev or not np.all(np.diff(t) > 0)
                        or np.any(np.abs(t - k / self.rate_hz) > ROW_TIME_TOL_S)):
                    raise NotStreamable("rows off the clock")
                t_prev, done = float(t[-1]), done + len(t)
                yield t, arr[:, 1:1 + nj], arr[:, 1 + nj:]


def _scan(path: str) -> tuple[int, bool, int]:
    """Lines (as ``text.split("\\n")`` without a last empty one), whether the text ends in
    a line end, and where its last line starts; NotStreamable unless a regular ASCII file."""
    import os
    import stat

    try:
        if not stat.S_ISREG(os.stat(path).st_mode):
            raise NotStreamable("not a regular file")
        ends, size, last_end, before = 0, 0, -1, -1  # (the last two line ends)
        with open(path, "rb") as f:
            while piece := f.read(SCAN_BYTES):
                if not piece.isascii():
                    raise NotStreamable("not ASCII")
                ends += piece.count(b"\n")
                j1 = piece.rfind(b"\n")
                if j1 >= 0:
                    j0 = piece.rfind(b"\n", 0, j1)
                    before = size + j0 if j0 >= 0 else last_end
                    last_end = size + j1
                size += len(piece)
    except OSError:
        raise NotStreamable("cannot read") from None
    terminated = size > 0 and last_end == size - 1
    return (ends + (0 if terminated or size == 0 else 1), terminated,
            (before if terminated else last_end) + 1)


def stream_trajectory(path: str, allow_incomplete: bool = False) -> TrajectoryStream:
    """``path`` read as a stream (``TrajectoryStream``): its first two lines and its last
    now, its rows as they are read; NotStreamable for any file ``read_trajectory`` would
    refuse or that is not a regular ASCII file (``read_trajectory`` then names why)."""
    lines, terminated, last_start = _scan(path)
    if lines < 3:
        raise NotStreamable("too short")
    with open(path, "rb") as f:
        first, header = f.readline()[:-1].decode(), f.readline()[:-1].decode()
        f.seek(last_start)
        last = f.read().decode()
    last = last[:-1] if terminated else last
    if not first.startswith("# ") or first.endswith("\r") or header.endswith("\r"):
        raise NotStreamable("not a trajectory's first lines")
    try:
        meta = _metadata(first, path)
        joint_cols, motor_cols = _header(header, path)
    except InputError:
        raise NotStreamable("bad metadata or header") from None
    end = _end_marker(last)
    body = lines - 2
    if end is not None:
        body -= 1
        if end.get("rows") != body:
            raise NotStreamable("row count")
    elif not allow_incomplete:
        raise NotStreamable("incomplete")
    elif body and (last.startswith("#") or not terminated):
        body -= 1
    if body < MIN_ROWS:
        raise NotStreamable("too few rows")
    nj = len(joint_cols)
    head = Trajectory(meta, tuple(joint_cols), tuple(c[6:] for c in motor_cols), np.zeros(0),
                      np.zeros((0, nj)), np.zeros((0, len(motor_cols))), end is not None,
                      end or {})
    return TrajectoryStream(head, path, body, float(meta["rate_hz"]))
