"""``play``: a MIDI song planned into a trajectory; the summary a user reads (stderr) or
one JSON object (stdout), the pictures of the checked plan, and the exit status."""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

from planner.cli.options import add_pictures, draw_checked


def add_parser(sub) -> None:
    pl = sub.add_parser("play", help="plan a MIDI song")
    pl.add_argument("song", help="MIDI file")
    pl.add_argument("-o", "--output", default=None,
                    help="trajectory CSV ('-' for stdout; default: SONG.csv in the current "
                         "directory)")
    pl.add_argument("--hand", default="default", help="hand name or hand file (.toml)")
    pl.add_argument("--rate", type=float, default=100.0, help="setpoint rate, Hz (default 100)")
    pl.add_argument("--track", type=int, default=None, help="only this track (0-based)")
    pl.add_argument("--channel", type=int, default=None, help="only this channel (0-15)")
    pl.add_argument("--transpose", action="store_true", help="move notes outside A0-C8 by octaves")
    pl.add_argument("--strict", action="store_true",
                    help="exit 1 if any note is not played, late, or a key is pressed wrongly")
    add_pictures(pl)
    pl.add_argument("--json", action="store_true",
                    help="the summary as one JSON object on stdout (needs -o FILE)")


def run(a: argparse.Namespace) -> int:
    """Plan, write, summarise; 0, or 1 when the plan's own replay finds what ``check``
    fails (a wrong press, a limit violation), or under ``--strict`` a note not played or
    late."""
    from planner.errors import InputError
    from planner.hand.model import load_hand
    from planner.music.midi import load_song
    from planner.play.stream import Planner, plan_song
    from planner.play.summary import format_summary, plan_dict
    from planner.progress import progress_bar

    if (a.report or a.html) and a.output == "-":
        raise InputError("--report and --html need a trajectory file (-o PATH), not stdout")
    song = load_song(a.song, track=a.track, channel=a.channel, transpose=a.transpose)
    hand = load_hand(a.hand)
    name = os.path.basename(a.song)
    # (by default into the current directory, never beside the song: it may be read-only)
    out = a.output if a.output is not None else os.path.splitext(name)[0] + ".csv"
    t0 = time.perf_counter()  # (the hand's set-up, once per hand: timed apart from the song)
    planner = Planner(hand)
    setup_s = time.perf_counter() - t0
    with progress_bar("note", enabled=not a.json) as bar:
        plan = plan_song(song, hand, out, a.rate, song_name=name, planner=planner,
                         on_progress=bar.update)
    if a.json:
        sys.stdout.write(json.dumps(plan_dict(name, song.notes, plan, out, setup_s)) + "\n")
    else:
        sys.stderr.write(format_summary(name, song.notes, plan, out, setup_s) + "\n")
    if a.report or a.html:
        from planner.check import check_trajectory

        draw_checked(check_trajectory(out, a.song), a.report, a.html, enabled=not a.json)
        if not a.json:
            sys.stderr.write("".join(f"{what} -> {path}\n" for what, path in
                                     (("report", a.report), ("html", a.html)) if path))
    score = plan.verdict.score
    if plan.verdict.rejected:  # (a wrong press or a limit violation: check fails the plan)
        return 1
    if a.strict and (plan.verdict.skipped or score.late or score.wrong_presses):
        return 1
    return 0
