"""Where output goes: the path the user named, and nothing else.

Two ways to write, one rule for both: a path is *written*, never replaced.

* ``open_stream(path)`` opens a text stream into ``path`` itself (``-``: stdout),
  for output that grows while it is planned (the trajectory file): a reader can
  follow it, and completeness is said by the content (the trajectory's end
  marker), not by the file's existence. A FIFO, a character device or a symlink's
  target is opened and written like any file; nothing is ever created beside it.
  What cannot be opened is refused at once (``InputError``, exit 2), before any
  planning.
* ``write_file(path, data)`` writes a finished artefact (URDF, MIDI, PNG, HTML).
  A regular file (or a new path) is written through a temporary file beside it and
  a rename, so it is complete or absent; a symlink is followed first, so the
  rename lands on its target and the link stays. Anything else that exists (FIFO,
  device) is written directly.
"""

from __future__ import annotations

import os
import stat
import sys
from typing import IO

from planner.errors import InputError, PlannerError

STDOUT = "-"


def _why(e: OSError) -> str:
    return e.strerror or str(e)


def _refuse_unnameable(path: str) -> None:
    if not path:
        raise InputError("cannot write '': empty output path")
    if os.path.isdir(path):
        raise InputError(f"cannot write {path}: is a directory")


def is_regular_target(path: str) -> bool:
    """True when ``path`` (a symlink followed) is a regular file or does not exist yet."""
    try:
        return stat.S_ISREG(os.stat(path).st_mode)
    except FileNotFoundError:
        return True


class OutputStream:
    """A text stream into the named path: ``write``, ``flush``, ``close``; ``discard``
    removes a regular file this stream created (for input found bad after opening)."""

    def __init__(self, path: str) -> None:
        self.path = path
        if path == STDOUT:
            self._f: IO[str] = sys.stdout
            self._created = False
            return
        _refuse_unnameable(path)
        self._created = not os.path.lexists(path)
        try:
            self._f = open(path, "w", encoding="utf-8", newline="\n")  # noqa: SIM115
        except OSError as e:
            raise InputError(f"cannot write {path}: {_why(e)}") from None

    def write(self, s: str) -> None:
        self._do(self._f.write, s)

    def flush(self) -> None:
        self._do(self._f.flush)

    def _do(self, fn, *a) -> None:
        try:
            fn(*a)
        except BrokenPipeError:
            raise  # a reader that went away: the CLI ends quietly (README, exit status)
        except OSError as e:
            raise PlannerError(f"cannot write {self.path}: {_why(e)}") from None

    def close(self) -> None:
        if self.path == STDOUT:
            self.flush()
            return
        f, self._f = self._f, None
        if f is not None:
            self._do(f.close)

    def discard(self) -> None:
        """Close quietly; a regular file this stream created is removed (nothing was
        complete in it). An existing file, a FIFO or a device is left as it is."""
        if self.path == STDOUT:
            return
        f, self._f = self._f, None
        if f is not None:
            try:
                f.close()
            except OSError:
                pass
        if self._created and is_regular_target(self.path):
            try:
                os.unlink(self.path)
            except OSError:
                pass


def open_stream(path: str) -> OutputStream:
    """A stream into ``path`` (``-``: stdout); InputError when it cannot be opened."""
    return OutputStream(os.fspath(path))


def write_file(path: str | os.PathLike, data: str | bytes) -> None:
    """Write a finished artefact to ``path`` (see the module docstring): complete or
    absent for a regular file, written in place for a FIFO or a device; a symlink's
    target is written and the link stays. InputError when it cannot be written."""
    path = os.fspath(path)
    _refuse_unnameable(path)
    raw = data.encode("utf-8") if isinstance(data, str) else bytes(data)
    target = os.path.realpath(path) if os.path.islink(path) else path
    try:
        if is_regular_target(target):
            _write_replacing(target, raw)
        else:
            with open(target, "wb") as f:
                f.write(raw)
    except OSError as e:
        raise InputError(f"cannot write {path}: {_why(e)}") from None


def _write_replacing(path: str, raw: bytes) -> None:
    import tempfile  # (here: its import, ~4 ms of CPU, is not on every command's start)

    folder, base = os.path.split(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{base}.", suffix=".part", dir=folder or ".")
    try:
        umask = os.umask(0)
        os.umask(umask)
        os.fchmod(fd, 0o666 & ~umask)  # as open() would create it (mkstemp makes 0600)
        with os.fdopen(fd, "wb") as f:
            f.write(raw)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


# ---------------------------------------------------------------- checked before planning

# (the options naming an artefact: a file, or a folder the command fills)
FILE_OPTIONS = ("output", "html", "urdf", "played", "video")
DIR_OPTIONS = ("report",)


def check_file_target(path: str, option: str) -> None:
    """Refuse now (``InputError``) a file path the artefact could not be written to
    later: empty, a folder, in a folder that does not exist (none is ever created) or
    cannot be written. An existing FIFO, device or symlink's target is not opened."""
    if path == STDOUT and option in ("output", "urdf"):
        return
    _refuse_unnameable(path)
    if os.path.lexists(path):
        target = os.path.realpath(path)
        if is_regular_target(target):
            _probe(lambda: open(target, "ab").close(), path)  # (appends nothing)
        return
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise InputError(f"cannot write {path}: no folder {folder} (none is created)")
    _probe(lambda: os.unlink(_temp_in(folder)), path)


def check_dir_target(path: str, option: str) -> None:
    """Refuse now a folder path for ``--report``: an existing file, a folder that
    cannot be written, or a new folder whose parent does not exist or cannot be
    written (the folder named is the only one ever created)."""
    if not path:
        raise InputError(f"--{option}: empty folder path")
    if os.path.lexists(path) and not os.path.isdir(path):
        raise InputError(f"cannot write into {path}: not a folder")
    if os.path.isdir(path):
        _probe(lambda: os.unlink(_temp_in(path)), f"into {path}")
        return
    parent = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(parent):
        raise InputError(f"cannot make folder {path}: no folder {parent} (none is created)")
    import tempfile

    _probe(lambda: os.rmdir(tempfile.mkdtemp(prefix=".probe.", dir=parent)),
           f"{path} (cannot make a folder in {parent})")


PROBE_TRIES = 100  # names a probe tries in a folder before it gives up (as ``tempfile``'s
# ``TMP_MAX`` bounds ``mkstemp``'s): only leftovers of earlier probes of the same name clash


def _temp_in(folder: str) -> str:
    """A new empty file in ``folder`` (created exclusively, mode 0600, as
    ``tempfile.mkstemp`` makes one; named by this process and a count, without importing
    ``tempfile``: a command probing its output path before it plans does not load it)."""
    for k in range(PROBE_TRIES):
        tmp = os.path.join(folder, f".probe.{os.getpid()}.{k}.part")
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o600)
        except FileExistsError:
            continue
        os.close(fd)
        return tmp
    raise FileExistsError(f"no free probe name in {folder}")


def _probe(fn, what: str) -> None:
    try:
        fn()
    except OSError as e:
        raise InputError(f"cannot write {what}: {_why(e)}") from None


# ---------------------------------------------------------------- closed stdout / stderr


def reopen_closed_stdio() -> frozenset[str]:
    """A standard stream the shell closed (``>&-``, ``2>&-``: Python then has None
    there) is put on /dev/null, so that nothing fails on it; returns the names of those
    closed ("stdout", "stderr")."""
    closed = set()
    for name in ("stdout", "stderr"):
        if getattr(sys, name) is None:
            setattr(sys, name, open(os.devnull, "w", encoding="utf-8"))  # noqa: SIM115
            closed.add(name)
    return frozenset(closed)
