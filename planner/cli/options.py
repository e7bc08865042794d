"""Options more than one command takes, and what they share in running them."""

from __future__ import annotations

import argparse
from typing import Any

from planner.errors import InputError
from planner.output import (
    DIR_OPTIONS,
    FILE_OPTIONS,
    STDOUT,
    check_dir_target,
    check_file_target,
)


def add_pictures(parser) -> None:
    """``--report DIR`` and ``--html FILE`` (play, catch, check: the checked plan drawn)."""
    parser.add_argument("--report", metavar="DIR", help="write PNG plots here")
    parser.add_argument("--html", metavar="FILE", help="write a 3D animation (HTML)")


def add_replay_options(parser, what: str) -> None:
    """The options ``check`` and ``simulate`` share: how to read the file and the song,
    what fails, the output."""
    parser.add_argument("trajectory", help="hand-trajectory v1 file")
    parser.add_argument("song", nargs="?", default=None, help="the MIDI file it was planned from")
    parser.add_argument("--allow-incomplete", action="store_true",
                        help="replay a file without its end marker (still being written, or cut)")
    parser.add_argument("--min-f1", type=float, default=None, help=f"fail under this {what} F1")
    parser.add_argument("--strict", action="store_true",
                        help="fail on any missed or late note, not only wrong ones")
    parser.add_argument("--track", type=int, default=None,
                        help="read only this track of the song (default: as the plan was made)")
    parser.add_argument("--channel", type=int, default=None,
                        help="read only this channel (default: as the plan was made)")
    parser.add_argument("--transpose", action="store_true",
                        help="move notes outside A0-C8 by octaves (default: as the plan was made)")
    parser.add_argument("--json", action="store_true", help="one JSON object on stdout")
    parser.add_argument("--hand", default=None,
                        help="the hand name or hand file (.toml) the plan was made with "
                             "(default: the file's hand, by name)")


def song_options(args: argparse.Namespace) -> dict[str, Any]:
    """``--track``, ``--channel``, ``--transpose`` of a replay (None: as the plan was made)."""
    return {"track": args.track, "channel": args.channel,
            "transpose": True if args.transpose else None}


def draw_checked(report, report_dir: str | None, html_path: str | None,
                 enabled: bool) -> None:
    """``--report DIR`` and ``--html FILE``: a check's replay plotted and animated (with a
    progress bar on a terminal when ``enabled``)."""
    from planner.report import draw_reports

    draw_reports(report, report_dir, html_path, enabled)


def check_artefacts(args) -> None:
    """Every output path a command's options name (``FILE_OPTIONS``, ``DIR_OPTIONS``),
    checked before any planning with the rules of ``check_file_target`` and
    ``check_dir_target``."""
    for option in FILE_OPTIONS:
        path = getattr(args, option, None)
        if isinstance(path, str):
            check_file_target(path, option)
    for option in DIR_OPTIONS:
        path = getattr(args, option, None)
        if isinstance(path, str):
            check_dir_target(path, option)


def refuse_closed_stdout(args, closed: frozenset[str]) -> None:
    """InputError when stdout was closed and the command's output goes there (``-o -``,
    ``--urdf -``, ``--json``, or ``hand``'s description)."""
    if "stdout" not in closed:
        return
    to_stdout = (getattr(args, "output", None) == STDOUT or getattr(args, "urdf", None) == STDOUT
                 or getattr(args, "json", False)
                 or (args.command == "hand" and not getattr(args, "urdf", None)))
    if to_stdout:
        raise InputError("standard output is closed: the output has nowhere to go "
                         "(name a file, or leave stdout open)")
