"""``check``: a trajectory replayed by kinematics and verified; the summary (or one JSON
object), the keys pressed as MIDI (``--played``), the pictures; 0 when it passes."""

from __future__ import annotations

import argparse
import json

from planner.cli.options import add_pictures, add_replay_options, draw_checked, song_options


def add_parser(sub) -> None:
    k = sub.add_parser("check", help="replay a trajectory and verify it")
    add_replay_options(k, "frame")
    k.add_argument("--played", metavar="OUT.mid", help="write the keys pressed as a MIDI file")
    add_pictures(k)


def run(a: argparse.Namespace) -> int:
    """The summary on stdout (or one JSON object with --json); 0 when the check passes,
    1 otherwise. ``--played OUT.mid`` writes the key-down episodes as notes (velocity
    64)."""
    from planner.check import check_trajectory

    report = check_trajectory(a.trajectory, a.song, allow_incomplete=a.allow_incomplete,
                              min_f1=a.min_f1, strict=a.strict, song_options=song_options(a),
                              hand_override=a.hand,
                              replay=bool(a.report or a.html))
    from planner.check.pairreport import PairReport

    pair = isinstance(report, PairReport)
    if a.played:
        from planner.music.midi import Note, write_notes_midi

        eps = report.play.played if report.play is not None else ()
        write_notes_midi([Note(e.pitch, e.start_s, e.end_s, 64) for e in eps], a.played)
    if (a.report or a.html) and pair:  # (each hand's pictures: planner.report.pair)
        from planner.report.pair import draw_pair_reports

        draw_pair_reports(a.trajectory, a.song, song_options(a), a.report, a.html,
                          enabled=not a.json)
    elif a.report or a.html:
        draw_checked(report, a.report, a.html, enabled=not a.json)
    print(json.dumps(report.to_dict()) if a.json else report.summary())
    return 0 if report.ok else 1
