"""``play --hands 2``: a MIDI song planned on two hands into one two-hand file
(``planner.play.twohands``); the summary (stderr) or one JSON object (stdout), the exit
status."""

from __future__ import annotations

import argparse
import json
import os
import sys
import time


def run_two(a: argparse.Namespace, names: tuple[str, str]) -> int:
    """Plan both hands, write, summarise; 0, or 1 when a hand's own replay finds what
    ``check`` fails, or under ``--strict`` a note not played or late."""
    from planner.errors import InputError
    from planner.hand.model import load_hand
    from planner.music.midi import load_song
    from planner.play.twohands import PairPlanner, plan_two_hands
    from planner.play.twosummary import format_two_summary, two_plan_dict

    if a.track is not None or a.channel is not None:
        raise InputError("two hands play every part of the file: --track and --channel are "
                         "for one hand")
    song = load_song(a.song, transpose=a.transpose, every_part=True)
    left, right = (load_hand(n) for n in names)
    name = os.path.basename(a.song)
    out = a.output if a.output is not None else os.path.splitext(name)[0] + ".csv"
    t0 = time.perf_counter()  # (the pair's set-up, once per pair: timed apart from the song)
    pp = PairPlanner(left, right)
    setup_s = time.perf_counter() - t0
    plan = plan_two_hands(song, pp, out, a.rate, song_name=name)
    places_of = {s: p.places for s, p in pp.planners.items()}
    if a.json:
        sys.stdout.write(json.dumps(two_plan_dict(name, song.notes, plan, out, setup_s,
                                                  places_of)) + "\n")
    else:
        sys.stderr.write(format_two_summary(name, song.notes, plan, out, setup_s, places_of)
                         + "\n")
    if a.report or a.html:  # (each hand's pictures: ``planner.report.pair``)
        from planner.report.pair import draw_pair_reports, side_path

        draw_pair_reports(out, a.song, {"transpose": a.transpose}, a.report, a.html,
                          enabled=not a.json)
        if not a.json:
            sys.stderr.write(("" if not a.report else f"report -> {a.report} (left, right)\n")
                             + ("" if not a.html else "html -> " + ", ".join(
                                 side_path(a.html, s) for s in ("left", "right")) + "\n"))
    verdicts = [p.verdict for p in plan.plans]
    if any(v.rejected for v in verdicts):
        return 1
    if a.strict and any(v.skipped or v.score.late or v.score.wrong_presses for v in verdicts):
        return 1
    return 0
