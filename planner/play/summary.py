"""A played song's plan as the summary a user reads (``format_summary``) and as one
JSON object (``plan_dict``, ``play --json``).

The summary is the plan's own replay (``PlayPlan.verdict``: the check's rules): every
note it calls played the check finds hit, every other note is named with its reason.
"""

from __future__ import annotations

import math

from planner.music.keyboard import pitch_name
from planner.play.force import press_force_n, pressed_force_n
from planner.play.stream import PlayPlan


def _timing(notes, plan: PlayPlan) -> tuple[float, float | None, int]:
    """(seconds of music, real-time factor (None without a planning time), hand
    positions used): the facts both the summary and ``--json`` give."""
    song_s = max((n.offset_s for n in notes), default=0.0)
    rtf = song_s / plan.planning_s if plan.planning_s > 0 else None
    return song_s, rtf, len({(a.rail_m, a.posture) for a in plan.fingering.assignments})


def part_lines(plan: PlayPlan) -> list[str]:
    """Which part of a file of several the hand played, and why (none for one part)."""
    return [] if plan.part is None else [f"part: {plan.part.reason}"]


def softer_notes(notes, plan: PlayPlan, places) -> list[tuple[int, float]]:
    """(note, force N) of the notes played with less force than their velocity asks
    (``planner.play.force.pressed_force_n``: the pose that presses them holds less), by
    note."""
    out = []
    for a in plan.fingering.assignments:
        asked = press_force_n(notes[a.note].velocity)
        e = places.atlases[a.posture].entry(a.finger, notes[a.note].pitch, a.rail_m)  # (as
        # the motion reads it: ``Motion.entry``)
        if e is not None and pressed_force_n(asked, e.max_force_n) < asked:
            out.append((a.note, pressed_force_n(asked, e.max_force_n)))
    return out


def softer_line(notes, plan: PlayPlan, places) -> list[str]:
    """The summary's line on the notes pressed softer than asked (none when there are
    none)."""
    return softer_words(notes, softer_notes(notes, plan, places))


def softer_words(notes, soft: list[tuple[int, float]]) -> list[str]:
    """The line on the notes ``soft`` ((note, force N), ``softer_notes``) pressed softer
    than their velocity asks; none when there are none."""
    if not soft:
        return []
    asked = max(press_force_n(notes[n].velocity) for n, _ in soft)
    return [(f"softer: {len(soft)} note{'' if len(soft) == 1 else 's'} pressed with "
             f"{min(f for _, f in soft):.2f}-{max(f for _, f in soft):.2f} N, less than "
             f"their velocity asks (up to {asked:.2f} N): their fingers' poses hold no more")]


def format_summary(song_name: str, notes, plan: PlayPlan, out: str,
                   setup_s: float | None = None, places=None) -> str:
    """The summary: counts and the file, timing (after the hand's set-up, ``setup_s``,
    given apart), the notes pressed softer than asked (with the hand's ``places``), then
    every note not played (with its reason), every late key and every wrong press the
    replay finds."""
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
    if places is not None:
        lines.extend(softer_line(notes, plan, places))
    for s in v.skipped:
        n = notes[s.note]
        lines.append(f"  infeasible: t={n.onset_s:.3f} s {pitch_name(n.pitch)} (MIDI {n.pitch}): "
                     f"{s.reason.value}: {s.detail}")
    lines.extend(v.problem_lines())
    return "\n".join(lines)


def plan_dict(song_name: str, notes, plan: PlayPlan, out: str, setup_s: float,
              places=None) -> dict:
    """``play --json``: the summary's facts, one JSON object (units in the names; a note
    is its index in the song, by onset then pitch, as in the end marker); ``softer``, the
    notes pressed with less force than asked, with the hand's ``places`` (else None)."""
    v = plan.verdict
    song_s, rtf, rails = _timing(notes, plan)
    softer = None if places is None else [
        {"note": n, "force_n": f, "asked_n": press_force_n(notes[n].velocity)}
        for n, f in softer_notes(notes, plan, places)]
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
        "part": None if plan.part is None else plan.part.to_dict(), "softer": softer,
    }
