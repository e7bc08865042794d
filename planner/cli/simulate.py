"""``simulate``: a trajectory replayed in MuJoCo physics and scored; the summary (or one
JSON object), the pictures (``--video``, ``--html``); 0 when the physics passes it."""

from __future__ import annotations

import argparse
import json

from planner.cli.options import add_replay_options, song_options


def add_parser(sub) -> None:
    sm = sub.add_parser("simulate", help="replay a trajectory in MuJoCo physics and score it",
                        epilog="needs MuJoCo: pip install -e \".[physics]\"")
    add_replay_options(sm, "physics")
    sm.add_argument("--contact", choices=("full", "pads"), default="full",
                    help="collision shapes: full (finger segments, palm, pads; default) or pads "
                         "(only the pad points, the kinematic check's contact model)")
    sm.add_argument("--video", metavar="FILE.mp4",
                    help="write an mp4 of the run: the plan beside the physics")
    sm.add_argument("--html", metavar="FILE",
                    help="write the run's frames as an offline HTML page (play, scrub)")


def run(a: argparse.Namespace) -> int:
    from planner.errors import InputError
    from planner.simulate import run_replay
    from planner.simulate.pictures import prepare, write_pictures

    if a.min_f1 is not None and not 0.0 <= a.min_f1 <= 1.0:
        raise InputError(f"--min-f1 must be within 0..1, got {a.min_f1}")
    prepare(a.video, a.html)
    replay = run_replay(a.trajectory, a.song, contact=a.contact, min_f1=a.min_f1,
                        strict=a.strict, allow_incomplete=a.allow_incomplete,
                        song_options=song_options(a), hand_override=a.hand)
    if (a.video or a.html) and not hasattr(replay.hand, "urdf"):
        raise InputError(f"{a.trajectory}: --video and --html draw a one-hand plan; this "
                         "file has two hands (no pictures of two yet)")
    write_pictures(replay, a.video, a.html, progress=not a.json)
    report = replay.report
    if a.json:
        d = report.to_dict()
        d["video"], d["html"] = a.video, a.html
        print(json.dumps(d))
    else:
        print(report.summary())
    return 0 if report.ok else 1
