"""The ``hand-trajectory`` version 1 file (interface spec, section 4).

``TrajectoryWriter`` streams rows as they are planned and flushes them, so a
reader can follow the file while it grows. A file is complete only with its
end marker. To a path, rows go to a temporary name beside it that is renamed
onto the path only after the end marker is written: an interrupted plan never
leaves a complete-looking file (nor a file at the path at all). To stdout
(``-``) the end marker is the signal.
"""

from __future__ import annotations

import json
import math
import os
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

import numpy as np

from planner.errors import InputError, PlannerError

FORMAT = "hand-trajectory"
VERSION = 1
_MAX_META_CHARS = 1 << 20  # a metadata line longer than this is not one (e.g. /dev/zero)


def _check_target(path: str | os.PathLike) -> None:
    """InputError before any work when ``path`` cannot name an output file."""
    if not os.fspath(path):
        raise InputError("cannot write '': empty output path")
    if os.path.isdir(path):
        raise InputError(f"cannot write {os.fspath(path)}: is a directory")


def _mkstemp_beside(path: Path) -> tuple[int, str]:
    """A temporary file beside ``path`` with the permissions a plain open() would give
    (mkstemp makes it 0600, which the rename would carry over to the published file)."""
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".part",
                               dir=str(path.parent) if str(path.parent) else ".")
    umask = os.umask(0)
    os.umask(umask)
    try:
        os.fchmod(fd, 0o666 & ~umask)
    except OSError:
        pass
    return fd, tmp


def write_text_atomic(path: str | os.PathLike, text: str) -> None:
    """Write ``text`` to ``path`` through a temporary file and a rename."""
    _check_target(path)
    path = Path(path)
    try:
        fd, tmp = _mkstemp_beside(path)
    except OSError as e:
        raise InputError(f"cannot write {path}: {e.strerror or e}") from None
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="\n") as f:
            f.write(text)
        os.replace(tmp, path)
    except OSError as e:
        _unlink(tmp)
        raise PlannerError(f"cannot write {path}: {e.strerror or e}") from None


def _unlink(p: str) -> None:
    try:
        os.unlink(p)
    except OSError:
        pass


class TrajectoryWriter:
    """Streams a trajectory: ``open`` writes metadata and header, ``row`` one setpoint, ``close`` the end."""

    def __init__(self, path: str, metadata: dict[str, Any], joint_names, motor_names) -> None:
        self.path = path
        self.rows = 0
        self._tmp: str | None = None
        self._last_t = -math.inf
        self.columns = ["t", *joint_names, *(f"motor.{m}" for m in motor_names)]
        if path == "-":
            self._f: IO[str] = sys.stdout
        else:
            _check_target(path)
            try:
                fd, self._tmp = _mkstemp_beside(Path(path))
            except OSError as e:
                raise InputError(f"cannot write {path}: {e.strerror or e}") from None
            self._f = os.fdopen(fd, "w", encoding="utf-8", newline="\n")
        meta = {"format": FORMAT, "version": VERSION, **metadata}
        self._write("# " + json.dumps(meta, sort_keys=False, separators=(", ", ": ")) + "\n")
        self._write(",".join(self.columns) + "\n")
        self._flush()

    def _write(self, s: str) -> None:
        try:
            self._f.write(s)
        except OSError as e:
            self.abort()
            raise PlannerError(f"cannot write {self.path}: {e.strerror or e}") from None

    def _flush(self) -> None:
        try:
            self._f.flush()
        except OSError as e:
            self.abort()
            raise PlannerError(f"cannot write {self.path}: {e.strerror or e}") from None

    def write_rows(self, t_s: np.ndarray, q: np.ndarray, q_motor: np.ndarray) -> None:
        """Append rows (times in s, joint positions, motor angles) and flush."""
        t_s = np.asarray(t_s, dtype=float)
        if len(t_s) == 0:
            return
        if not (t_s[0] > self._last_t and np.all(np.diff(t_s) > 0)):
            raise PlannerError(f"trajectory time not increasing near t={t_s[0]}")
        self._last_t = float(t_s[-1])
        arr = np.column_stack([t_s, q, q_motor])
        fmt = ",".join(["%.6f"] * arr.shape[1])
        self._write("\n".join([fmt % tuple(r) for r in arr.tolist()]) + "\n")
        self.rows += len(arr)
        self._flush()

    def close(self) -> None:
        """Write the end marker and publish the file."""
        self._write("# " + json.dumps({"end": True, "rows": self.rows}) + "\n")
        self._flush()
        if self._tmp is not None:
            try:
                self._f.close()
                os.replace(self._tmp, self.path)
            except OSError as e:
                self.abort()
                raise PlannerError(f"cannot write {self.path}: {e.strerror or e}") from None
            self._tmp = None

    def abort(self) -> None:
        """Drop a partial file (path output); nothing complete-looking stays behind."""
        if self._tmp is not None:
            try:
                self._f.close()
            except OSError:
                pass
            _unlink(self._tmp)
            self._tmp = None


@dataclass(frozen=True)
class Trajectory:
    """A trajectory read back: metadata, column names, times (s), joint and motor arrays."""

    metadata: dict[str, Any]
    joint_names: tuple[str, ...]
    motor_names: tuple[str, ...]
    t_s: np.ndarray
    q: np.ndarray
    q_motor: np.ndarray
    complete: bool


def read_trajectory(path: str, allow_incomplete: bool = False) -> Trajectory:
    """Read and validate a hand-trajectory v1 file; InputError (one line) on any defect."""
    try:
        with open(path, encoding="utf-8", newline="") as f:
            text = f.readline(_MAX_META_CHARS)  # bounded: an endless first line is refused
            if not text.startswith("# "):
                raise InputError(f"{path}: not a hand-trajectory file (no metadata line)")
            text += f.read()
    except FileNotFoundError:
        raise InputError(f"no such trajectory file: {path}") from None
    except (OSError, UnicodeDecodeError) as e:
        raise InputError(f"cannot read trajectory {path}: {e}") from None
    terminated = text.endswith("\n")
    lines = text.split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    if len(lines) < 2 or not lines[0].startswith("# "):
        raise InputError(f"{path}: not a hand-trajectory file (no metadata line)")
    try:
        meta = json.loads(lines[0][2:])
    except (json.JSONDecodeError, RecursionError):
        raise InputError(f"{path}: metadata line is not valid JSON") from None
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        raise InputError(f"{path}: not a hand-trajectory file (format is not {FORMAT!r})")
    if meta.get("version") != VERSION:
        raise InputError(f"{path}: unsupported version {meta.get('version')!r} (supported: {VERSION})")
    for key in ("task", "hand", "urdf_sha256", "T_world_root", "rate_hz"):
        if key not in meta:
            raise InputError(f"{path}: metadata lacks required key {key!r}")
    if meta["task"] not in ("play", "catch"):
        raise InputError(f"{path}: task must be 'play' or 'catch', got {meta['task']!r}")
    complete = False
    if lines[-1].startswith("# "):
        try:
            end = json.loads(lines[-1][2:])
        except (json.JSONDecodeError, RecursionError):
            end = None
        if isinstance(end, dict) and end.get("end") is True:
            complete = True
            body = lines[2:-1]
            if end.get("rows") != len(body):
                raise InputError(f"{path}: end marker says {end.get('rows')} rows, file has {len(body)}")
    if not complete:
        if not allow_incomplete:
            raise InputError(f"{path}: incomplete trajectory (no end marker); use --allow-incomplete to read it anyway")
        body = lines[2:]
        if body and (body[-1].startswith("#") or not terminated):
            body = body[:-1]  # a damaged end marker, or a row still being written
    header = lines[1].split(",")
    if not header or header[0] != "t":
        raise InputError(f"{path}: header must start with 't'")
    motor_cols = [c for c in header[1:] if c.startswith("motor.")]
    joint_cols = [c for c in header[1:] if not c.startswith("motor.")]
    if header[1:] != joint_cols + motor_cols:
        raise InputError(f"{path}: motor columns must follow the joint columns")
    if len(set(header)) != len(header):
        raise InputError(f"{path}: duplicate column names")
    if not body:
        raise InputError(f"{path}: no rows")
    try:
        arr = np.array([[float(x) for x in ln.split(",")] for ln in body], dtype=float)
    except ValueError:
        bad = next(i for i, ln in enumerate(body) if not _row_ok(ln, len(header)))
        raise InputError(f"{path}: row {bad + 1} is not {len(header)} numbers") from None
    if arr.ndim != 2 or arr.shape[1] != len(header):
        raise InputError(f"{path}: rows must have {len(header)} values")
    if not np.all(np.isfinite(arr)):
        i = int(np.argwhere(~np.isfinite(arr))[0, 0])
        raise InputError(f"{path}: row {i + 1} has a NaN or infinite value")
    t = arr[:, 0]
    if len(t) > 1 and not np.all(np.diff(t) > 0):
        i = int(np.argmax(~(np.diff(t) > 0)))
        raise InputError(f"{path}: time not strictly increasing at row {i + 2} (t={t[i + 1]:.6f})")
    nj = len(joint_cols)
    return Trajectory(meta, tuple(joint_cols), tuple(c[6:] for c in motor_cols), t,
                      arr[:, 1:1 + nj], arr[:, 1 + nj:], complete)


def _row_ok(line: str, n: int) -> bool:
    parts = line.split(",")
    if len(parts) != n:
        return False
    try:
        [float(x) for x in parts]
    except ValueError:
        return False
    return True
