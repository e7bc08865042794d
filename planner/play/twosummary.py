"""A two-hand plan as the summary a user reads (``format_two_summary``) and as one JSON
object (``two_plan_dict``, ``play --hands 2 --json``): per hand and together."""

from __future__ import annotations

import math
from collections import Counter

from planner.music.keyboard import pitch_name
from planner.play.force import press_force_n
from planner.play.hands import SIDES
from planner.play.summary import softer_notes, softer_words
from planner.play.twoplan import TwoHandPlan


def _song_s(notes) -> float:
    return max((n.offset_s for n in notes), default=0.0)


def hand_facts(plan: TwoHandPlan) -> list[dict]:
    """Per hand (left, right): its notes, played, left out, its own replay's frame F1
    (against its notes), the notes given to it against the file's parts."""
    out = []
    moved_to = Counter(plan.assignment.hand[m.note] for m in plan.assignment.moved)
    out_of = Counter(plan.assignment.hand[i] for i, _ in plan.left_out())
    for side, idx, p in zip(SIDES, plan.notes_of, plan.plans):
        v = p.verdict
        out.append({"hand": side, "notes": len(idx), "played": v.played,
                    "left_out": out_of.get(side, 0), "frame_f1": v.score.f1,
                    "given_from_other_part": moved_to.get(side, 0),
                    "wrong_presses": len(v.score.wrong_presses)})
    return out


def softer_of(notes, plan: TwoHandPlan, places_of: dict) -> list[tuple[int, str, float]]:
    """(song index, hand, force N) of the notes pressed with less force than their
    velocity asks (``summary.softer_notes`` on each hand's plan of its own notes, with
    that hand's places, ``places_of[side]``), by note."""
    out = []
    for side, idx, p in zip(SIDES, plan.planned_of or plan.notes_of, plan.plans):
        sub = [notes[i] for i in idx]
        out.extend((idx[n], side, f) for n, f in softer_notes(sub, p, places_of[side]))
    return sorted(out)


def format_two_summary(song_name: str, notes, plan: TwoHandPlan, out: str,
                       setup_s: float | None = None, places_of: dict | None = None) -> str:
    """The summary: counts and the file, timing, each hand's share and replay, the rail
    gap kept, the notes pressed softer than asked (with each hand's places,
    ``places_of``), then every note not played (its hand and reason)."""
    left_out = plan.left_out()
    song_s = _song_s(notes)
    rtf = song_s / plan.planning_s if plan.planning_s > 0 else math.inf
    rows = len(plan.rows.t_s)
    lines = [
        (f"{song_name}: {len(notes)} notes, {len(notes) - len(left_out)} played, "
         f"{len(left_out)} left out, two hands; {rows} rows "
         f"({rows * (plan.rows.t_s[1] - plan.rows.t_s[0]) if rows > 1 else 0.0:.2f} s) "
         f"-> {out}"),
        (f"planning {plan.planning_s * 1000:.0f} ms "
         + ("" if setup_s is None else f"(after the pair's set-up, {setup_s * 1000:.0f} ms) ")
         + f"for {song_s:.2f} s of music (real-time factor {rtf:.0f}x); "
         f"the {plan.first} hand planned first; the rails {plan.least_rail_gap_m * 1000:.0f} "
         f"mm apart at least (the bodies' farthest reach, {plan.gap.rail_gap_m * 1000:.0f} "
         "mm, kept where both may reach it)"),
        (f"hands ({plan.assignment.source.value}): "
         + "; ".join(f"{f['hand']} {f['notes']} notes, {f['played']} played, frame F1 "
                     f"{f['frame_f1']:.4f}" for f in hand_facts(plan))
         + f"; {len(plan.assignment.moved)} notes played by the other hand than their part's"),
    ]
    if places_of is not None:
        lines.extend(softer_words(notes, [(n, f) for n, _, f in
                                          softer_of(notes, plan, places_of)]))
    for i, s in left_out:
        n = notes[i]
        lines.append(f"  left out: t={n.onset_s:.3f} s {pitch_name(n.pitch)} (MIDI {n.pitch}, "
                     f"{plan.assignment.hand[i]} hand): {s.reason.value}: {s.detail}")
    for side, p in zip(SIDES, plan.plans):
        lines.extend(f"  {side}: {line.strip()}" for line in p.verdict.problem_lines())
    return "\n".join(lines)


def two_plan_dict(song_name: str, notes, plan: TwoHandPlan, out: str, setup_s: float,
                  places_of: dict | None = None) -> dict:
    """``play --hands 2 --json``: the summary's facts, one JSON object (a note is its
    index in the song, by onset then pitch, as in the end marker); ``softer``, the notes
    pressed with less force than asked, with each hand's places (else None)."""
    song_s = _song_s(notes)
    left_out = plan.left_out()
    softer = None if places_of is None else [
        {"note": n, "hand": side, "force_n": f, "asked_n": press_force_n(notes[n].velocity)}
        for n, side, f in softer_of(notes, plan, places_of)]
    return {
        "command": "play", "hands_planned": 2, "song": song_name, "notes": len(notes),
        "played": len(notes) - len(left_out),
        "left_out": [{"note": i, "hand": plan.assignment.hand[i],
                      "onset_s": float(notes[i].onset_s), "pitch": int(notes[i].pitch),
                      "name": pitch_name(notes[i].pitch), "reason": s.reason.value,
                      "detail": s.detail} for i, s in left_out],
        "hands": hand_facts(plan),
        "moved": [{"note": m.note, "to": plan.assignment.hand[m.note],
                   "reason": m.reason.value, "detail": m.detail}
                  for m in plan.assignment.moved],
        "hint": plan.assignment.source.value,
        "rail_gap_m": plan.gap.rail_gap_m, "least_rail_gap_m": plan.least_rail_gap_m,
        "first_hand": plan.first, "way": plan.way, "softer": softer,
        "tried": [{"way": w, "played_frames": fr} for w, fr in plan.tried],
        "rows": len(plan.rows.t_s), "trajectory": out, "song_s": song_s,
        "planning_s": plan.planning_s, "setup_s": setup_s,
        "realtime_factor": song_s / plan.planning_s if plan.planning_s > 0 else None,
    }
