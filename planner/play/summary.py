"""``cli.py play`` on the second planner: the summary a user reads, and the exit status.

The summary is the plan's own replay (``PlayPlan.verdict``: the check's rules): every
note it calls played the check finds hit, every other note is named with its reason.
"""

from __future__ import annotations

import json
import math
import os
import sys
import time

from planner.errors import InputError
from planner.hand.model import load_hand
from planner.music.midi import load_song, pitch_name
from planner.play.stream import Planner, PlayPlan, plan_song
from planner.progress import progress_bar


def _timing(notes, plan: PlayPlan) -> tuple[float, float | None, int]:
    """(seconds of music, real-time factor (None without a planning time), hand
    positions used): the facts both the summary and ``--json`` give."""
    song_s = max((n.offset_s for n in notes), default=0.0)
    rtf = song_s / plan.planning_s if plan.planning_s > 0 else None
    return song_s, rtf, len({a.rail_m for a in plan.fingering.assignments})


def part_lines(plan: PlayPlan) -> list[str]:
    """Which part of a file of several the hand played, and why (none for one part)."""
    return [] if plan.part is None else [f"part: {plan.part.reason}"]


def format_summary(song_name: str, notes, plan: PlayPlan, out: str,
                   setup_s: float | None = None) -> str:
    """The summary: counts and the file, timing (after the hand's set-up, ``setup_s``,
    given apart), then every note not played (with its reason), every late key and every
    wrong press the replay finds."""
    v = plan.verdict
    song_s, rtf, rails = _timing(notes, plan)
    rtf = math.inf if rtf is None else rtf
    lines = [(f"{song_name}: {v.notes} notes, {v.played} played, {len(v.skipped)} infeasible; "
             f"{plan.rows} rows ({plan.duration_s:.2f} s) -> {out}"),
             (f"planning {plan.planning_s * 1000:.0f} ms "
              + ("" if setup_s is None else f"(after the hand's set-up, {setup_s * 1000:.0f} ms) ")
              + f"for {song_s:.2f} s of music "
             f"(real-time factor {rtf:.0f}x), first row after {plan.first_row_s * 1000:.0f} ms, "
             f"{rails} hand position{'' if rails == 1 else 's'}, frame F1 {v.score.f1:.4f}")]
    lines.extend(part_lines(plan))
    for s in v.skipped:
        n = notes[s.note]
        lines.append(f"  infeasible: t={n.onset_s:.3f} s {pitch_name(n.pitch)} (MIDI {n.pitch}): "
                     f"{s.reason.value}: {s.detail}")
    lines.extend(v.problem_lines())
    return "\n".join(lines)


def plan_dict(song_name: str, notes, plan: PlayPlan, out: str, setup_s: float) -> dict:
    """``play --json``: the summary's facts, one JSON object (units in the names; a note
    is its index in the song, by onset then pitch, as in the end marker)."""
    v = plan.verdict
    song_s, rtf, rails = _timing(notes, plan)
    return {
        "command": "play", "song": song_name, "notes": v.notes, "played": v.played,
        "left_out": [{"note": s.note, "onset_s": float(notes[s.note].onset_s),
                      "pitch": int(notes[s.note].pitch), "name": pitch_name(notes[s.note].pitch),
                      "reason": s.reason.value, "detail": s.detail} for s in v.skipped],
        "late": [{"note": lt.note, "onset_s": lt.onset_s, "pitch": lt.pitch,
                  "late_s": lt.late_s} for lt in v.score.late],
        "wrong_presses": [{"start_s": w.start_s, "end_s": w.end_s, "name": w.name,
                           "fingers": list(w.fingers)} for w in v.score.wrong_presses],
        "frame_f1": v.score.f1, "rows": plan.rows, "duration_s": plan.duration_s,
        "trajectory": out, "song_s": song_s, "planning_s": plan.planning_s,
        "first_row_s": plan.first_row_s, "setup_s": setup_s,
        "realtime_factor": rtf, "hand_positions": rails,
        "part": None if plan.part is None else plan.part.to_dict(),
    }


def play_cli(a) -> int:
    """Plan, write, summarise; 0, or 1 under ``--strict`` when a note is not played, late
    or a key is pressed wrongly."""
    if (a.report or a.html) and a.output == "-":
        raise InputError("--report and --html need a trajectory file (-o PATH), not stdout")
    song = load_song(a.song, track=a.track, channel=a.channel, transpose=a.transpose)
    hand = load_hand(a.hand)
    name = os.path.basename(a.song)
    # (by default into the current directory, never beside the song: it may be read-only)
    out = a.output if a.output is not None else os.path.splitext(name)[0] + ".csv"
    as_json = getattr(a, "json", False)
    t0 = time.perf_counter()  # (the hand's set-up, once per hand: timed apart from the song)
    planner = Planner(hand)
    setup_s = time.perf_counter() - t0
    with progress_bar("note", enabled=not as_json) as bar:
        plan = plan_song(song, hand, out, a.rate, song_name=name, planner=planner,
                         on_progress=bar.update)
    if as_json:
        sys.stdout.write(json.dumps(plan_dict(name, song.notes, plan, out, setup_s)) + "\n")
    else:
        sys.stderr.write(format_summary(name, song.notes, plan, out, setup_s) + "\n")
    if a.report or a.html:
        write_reports(out, a.song, a.report, a.html, enabled=not as_json)
        if not as_json:
            sys.stderr.write("".join(f"{what} -> {path}\n" for what, path in
                                     (("report", a.report), ("html", a.html)) if path))
    score = plan.verdict.score
    if a.strict and (plan.verdict.skipped or score.late or score.wrong_presses):
        return 1
    return 0


def write_reports(traj_path: str, song_path: str, report_dir: str | None,
                  html_path: str | None, enabled: bool = True) -> None:
    """``--report DIR`` and ``--html FILE`` of a written plan: the independent check's
    replay of it, plotted and animated (with a progress bar on a terminal)."""
    from planner.check import check_trajectory
    from planner.report import draw_reports

    draw_reports(check_trajectory(traj_path, song_path), report_dir, html_path, enabled)
