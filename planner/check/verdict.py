"""The verdict's parts shared by the check of one hand's file and of two hands'
(``planner.check.pair``): the lines of a play's problems, the end marker's claims held
against a replay, and the report made of the findings."""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from planner.check.bodykeys import bed_problem
from planner.check.claims import PlayClaims, count_mismatches, read_claims
from planner.check.criteria import LATE_S, pitch_name
from planner.check.results import CheckReport, ClaimMismatch, PlayResult, Replay
from planner.trajfile import song_start_s


def claim_mismatches(notes, missed_notes: set[int], left_out: set[int]) -> list[ClaimMismatch]:
    out = []
    for i, n in enumerate(notes):
        missed = i in missed_notes
        claimed_out = i in left_out
        if missed != claimed_out:
            out.append(ClaimMismatch(i, float(n.onset_s), int(n.pitch), pitch_name(n.pitch),
                                     "left out" if claimed_out else "played",
                                     "hit" if claimed_out else "missed"))
    return out


def play_problems(play: PlayResult, min_f1: float | None, strict: bool) -> list[str]:
    problems = []
    if play.key_bed_hits:
        h = play.key_bed_hits[0]
        problems.append(f"{len(play.key_bed_hits)} key-bed hits (first: {h.finger} on {h.name}"
                        f" at {h.time_s:.3f} s, {h.depth_m * 1000:.2f} mm deep)")
    problems.extend(bed_problem(play.body_bed_hits))
    if play.wrong_presses:
        w = play.wrong_presses[0]
        problems.append(f"{len(play.wrong_presses)} wrong presses (first: {w.name} at "
                        f"{w.start_s:.3f} s by {'+'.join(w.fingers) or '?'})")
    if play.claim_mismatches:
        c = play.claim_mismatches[0]
        problems.append(f"{len(play.claim_mismatches)} notes the plan claims otherwise than the "
                        f"replay finds (first: {c.name} at {c.onset_s:.3f} s, claimed {c.claimed},"
                        f" {c.found})")
    for c in play.count_mismatches:
        problems.append(f"the end marker claims {c.key.value} = {c.claimed}, the replay finds "
                        f"{c.found} ({c.detail})")
    if min_f1 is not None and play.f1 < min_f1:
        problems.append(f"frame F1 {play.f1:.4f} < {min_f1:g}")
    if strict and play.missed:
        m = play.missed[0]
        problems.append(f"{len(play.missed)} notes missed (first: {m.name} at {m.onset_s:.3f} s:"
                        f" {m.reason})")
    if strict and play.late:
        n = play.late[0]
        problems.append(f"{len(play.late)} notes late by more than {LATE_S * 1000:g} ms (first: "
                        f"{n.name} at {n.onset_s:.3f} s, {n.late_s * 1000:.0f} ms)")
    return problems


def check_report(plan, song_path, t_s: np.ndarray, limits, tendons, play, catch, min_f1,
            problems: list[str], replay: Replay | None) -> CheckReport:
    """The report: the limits' problems after the task's."""
    for lc in limits:
        if not lc.ok:
            problems.append(f"{lc.count} {lc.category.replace('_', ' ')} violations (worst "
                            f"{lc.worst:.6g} vs {lc.limit:.6g} {lc.unit}, {lc.name} at "
                            f"{lc.time_s:.3f} s)")
    meta, hand = plan.metadata, plan.hand
    return CheckReport(
        trajectory=os.fspath(plan.path),
        song=None if song_path is None else (song_path.source if not isinstance(
            song_path, (str, os.PathLike)) else os.fspath(song_path)),
        task=plan.task, hand=hand.name, urdf_sha256=hand.urdf_sha256,
        complete=plan.trajectory.complete, rows=len(t_s), duration_s=float(t_s[-1] - t_s[0]),
        rate_hz=float(meta["rate_hz"]), limits=tuple(limits), play=play, catch=catch,
        min_f1=min_f1, problems=tuple(problems), replay=replay, tendons=tendons,
        song_start_s=song_start_s(meta))


def held_to_claims(play: PlayResult, notes, end: dict[str, Any], path: str) -> PlayResult:
    """``play`` with the end marker's claims held against it: every count and every
    note's outcome (types are checked without a song too)."""
    import dataclasses

    claims = read_claims(end, None if notes is None else len(notes), path)
    if notes is None or claims == PlayClaims(None, None, None):
        return play
    missed = {m.note for m in play.missed}
    per_note = ([] if claims.left_out is None
                else claim_mismatches(notes, missed, claims.left_out))
    return dataclasses.replace(play, claims=True, claim_mismatches=tuple(per_note),
                               count_mismatches=tuple(count_mismatches(claims, len(notes),
                                                                       len(missed))))
