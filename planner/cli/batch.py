"""``batch``: every song of a folder planned and checked (``planner.batch``); a line per
song as it finishes under a progress bar (or one JSON object), the summary files; 0
when every song has a plan its check passes."""

from __future__ import annotations

import argparse
import json
import sys


def add_parser(sub) -> None:
    b = sub.add_parser("batch", help="plan and check every song of a folder (resumable)")
    b.add_argument("songs", help="folder of MIDI files (*.mid)")
    b.add_argument("out", help="folder for the trajectories, per-song records and summary")
    b.add_argument("--workers", type=int, default=2, help="local worker processes (default 2)")
    b.add_argument("--hand", default="default", help="hand name or hand file (.toml)")
    b.add_argument("--address", default=None,
                   help="run on a Ray cluster at this address ('local': a local Ray)")
    b.add_argument("--physics", action="store_true",
                   help="replay every plan in MuJoCo too (full contact; the physics extra): "
                        "physics F1, wrong keys and motor saturation in the summary")
    b.add_argument("--json", action="store_true", help="one JSON object on stdout")


def run(a: argparse.Namespace) -> int:
    from planner.batch import batch_plan, format_song_line
    from planner.progress import progress_bar

    with progress_bar("song", enabled=not a.json) as bar:
        summary = batch_plan(a.songs, a.out, workers=a.workers, hand=a.hand,
                             address=a.address, physics=a.physics,
                             on_result=None if a.json else (
                                 lambda r: bar.write(format_song_line(r))),
                             on_progress=bar.update,
                             on_skip=None if a.json else (
                                 lambda e, why: bar.write(f"{e}: skipped ({why})")))
    if a.json:
        sys.stdout.write(json.dumps(summary.to_dict()) + "\n")
    else:
        sys.stderr.write(summary.format(a.out) + "\n")
    return 0 if summary.ok else 1
