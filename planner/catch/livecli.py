"""``cli.py catch --live``: observations from standard input, one CSV line ``t,x,y,z``
each (the time since launch in s and the ball's centre in m, catch frame, spec section
5), read as they arrive and handed to a ``CatchSession``; an optional first line
``t,x,y,z`` (the header of an ``--observations`` file), blank lines and lines starting
with ``#`` are skipped. The summary goes to stderr (or ``--json`` to stdout) once the
session has ended.

A line that is not four numbers, a time not after the one before, a NaN: one line on
stderr naming the input line, exit 2, and the trajectory file removed (a stream, '-',
is left without its end marker, which every reader calls incomplete)."""

from __future__ import annotations

import json
import sys
from typing import IO

import numpy as np

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


def live_cli(args) -> int:
    """Plan the catch live; the summary (``planner.catch.summary``) once it has ended."""
    from planner.catch.plan.results import CatchResult
    from planner.catch.summary import catch_dict, format_summary

    for opt in ("angle", "observations"):
        if getattr(args, opt, None) is not None:
            raise InputError(f"--live takes the throw from the observations on stdin: "
                             f"--{opt} is not used with it")
    if getattr(args, "report", None) or getattr(args, "html", None):
        raise InputError("--report/--html are not available with --live")
    session = CatchSession(args.dist, args.height, args.hand, ball=args.ball, drag=args.drag,
                           rate_hz=args.rate, out_path=args.output)
    try:
        run_session(session, sys.stdin)
    except BaseException as e:
        session.abort(discard=isinstance(e, InputError))
        raise
    plan = session.plan
    res = CatchResult(plan, args.output, session.next_row, 0.0, 0.0)
    lat = np.array(session.latencies_s)
    p50, p99 = (float(x) for x in np.percentile(lat, [50, 99])) if lat.size else (0.0, 0.0)
    if getattr(args, "json", False):
        d = catch_dict(res)
        d["live"] = {"catch": session.outcome, "reason": session.reason,
                     "observations": session.fit.n, "latency_p50_s": p50,
                     "latency_p99_s": p99}
        sys.stdout.write(json.dumps(d) + "\n")
    else:
        sys.stderr.write(format_summary(res) + f"\n  live: {session.outcome}: "
                         f"{session.reason}\n  live: {lat.size} observations re-planned, "
                         f"latency to their rows p50 {1000 * p50:.2f} ms, p99 "
                         f"{1000 * p99:.2f} ms\n")
    return 1 if (args.strict and not plan.feasible) else 0
