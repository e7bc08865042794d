"""``cli.py catch --live``: observations from standard input, one CSV line ``t,x,y,z``
each (the time since launch in s and the ball's centre in m, catch frame, spec section
5), read as they arrive and handed to a ``CatchSession`` (``run_session``); an optional
first line ``t,x,y,z`` (the header of an ``--observations`` file), blank lines and lines
starting with ``#`` are skipped. The command (``planner.cli.catch``) prints the summary once the
session has ended.

A line that is not four numbers, a time not after the one before, a NaN: one line on
stderr naming the input line, exit 2, and the trajectory file removed (a stream, '-',
is left without its end marker, which every reader calls incomplete)."""

from __future__ import annotations

from typing import IO

from planner.catch.live.session import CatchSession
from planner.errors import InputError

HEADER = ("t", "x", "y", "z")


def parse_line(line: str, lineno: int) -> tuple[float, tuple[float, float, float]] | None:
    """One input line: (t, (x, y, z)), or None for a line to skip; InputError otherwise."""
    text = line.strip()
    if not text or text.startswith("#"):
        return None
    cells = [c.strip() for c in text.split(",")]
    if lineno == 1 and tuple(c.lower() for c in cells) == HEADER:
        return None
    if len(cells) != 4:
        raise InputError(f"stdin line {lineno}: expected 4 values t,x,y,z, got {len(cells)}")
    vals = []
    for name, c in zip("txyz", cells):
        try:
            vals.append(float(c))
        except ValueError:
            raise InputError(f"stdin line {lineno}: {name} = {c!r} is not a number") from None
    return vals[0], (vals[1], vals[2], vals[3])


def run_session(session: CatchSession, stream: IO[str]) -> int:
    """Feed ``stream``'s lines to ``session`` until it ends or the input does; returns
    the number of lines read. InputError names the line."""
    lineno = 0
    for lineno, line in enumerate(iter(stream.readline, ""), 1):
        obs = parse_line(line, lineno)
        if obs is None:
            continue
        try:
            session.observe(*obs)
        except InputError as e:
            raise InputError(f"stdin line {lineno}: {e}") from None
        if session.done:
            return lineno
    session.finish()
    return lineno
