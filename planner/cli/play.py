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
    pl.add_argument("--hand", default=None, help="hand name or hand file (.toml; default: "
                                                  "the default hand)")
    pl.add_argument("--hands", default="1", metavar="1|2|LEFT,RIGHT",
                    help="1 (default): one hand; 2: both hands (default-left,default), or the "
                         "pair named, the left hand first: one two-hand file "
                         "(docs/user/two-hands.md)")
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
    pair = pair_names(a.hands, a.hand)
    if pair is not None:
        from planner.cli.playtwo import run_two

        return run_two(a, pair)
    song = load_song(a.song, track=a.track, channel=a.channel, transpose=a.transpose)
    hand = load_hand(a.hand or "default")
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
        sys.stdout.write(json.dumps(plan_dict(name, song.notes, plan, out, setup_s,
                                              planner.places)) + "\n")
    else:
        sys.stderr.write(format_summary(name, song.notes, plan, out, setup_s, planner.places)
                         + "\n")
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


DEFAULT_PAIR = ("default-left", "default")


def pair_names(hands: str, hand: str | None) -> tuple[str, str] | None:
    """``--hands``: None for one hand (``1``), the two hands' names for two (``2``: the
    default pair; ``LEFT,RIGHT``: named); InputError on anything else, or ``--hand``
    with two hands."""
    from planner.errors import InputError

    text = hands.strip()
    if text == "1":
        return None
    if text == "2":
        names = DEFAULT_PAIR
    elif text.count(",") == 1 and all(n.strip() for n in text.split(",")):
        left, right = (n.strip() for n in text.split(","))
        names = (left, right)
    else:
        raise InputError(f"--hands takes 1, 2 or two hands LEFT,RIGHT (the left one first), "
                         f"got {hands!r}")
    if hand is not None:
        raise InputError("--hand names one hand; with two, name the pair: --hands LEFT,RIGHT")
    return names
