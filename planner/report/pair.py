"""Pictures of a checked two-hand plan (a version-3 file): each hand's own pictures.

Each hand of the pair is replayed as the one-hand plan it is (``planner.pairfile``'s
``PairPlan.hands``: its columns without prefix, its hand, its mount) against the notes
its end marker's ``by_hand`` gives it (the whole song when the claim is absent), by the
one-hand check with its replay arrays, and drawn by the one-hand pictures: ``--report
DIR`` writes ``DIR/left/`` and ``DIR/right/`` (``write_check_report``'s files), ``--html
FILE`` writes ``FILE`` with the hand's side before its extension (``pair.left.html``,
``pair.right.html``). The verdict is the pair's check (``planner.check.pair``); these
pictures show each hand's keys against its own notes, its fingertips, joints and motors.
"""

from __future__ import annotations

import os
from dataclasses import replace
from typing import Any

from planner.check import check_trajectory
from planner.check.pair import own_notes
from planner.check.results import CheckReport
from planner.music.midi import Song, load_song
from planner.pairfile import PairPlan, read_pair_plan
from planner.trajfile import read_trajectory

ONE_HAND_VERSION = 2  # (each hand's part is judged as a one-hand file, format version 2)


def hand_reports(path: str, song: str | os.PathLike | None,
                 options: dict[str, Any] | None = None) -> tuple[tuple[str, CheckReport], ...]:
    """Per hand of the two-hand plan ``path`` (left, right): its side and its one-hand
    check with the replay arrays, against its own notes of ``song`` (None: no song)."""
    plan: PairPlan = read_pair_plan(read_trajectory(path), path)
    whole = None
    if song is not None:
        opts = options or {}
        whole = load_song(song, transpose=bool(opts.get("transpose")
                                               or plan.metadata.get("transpose")),
                          every_part=True)
        plan.song_notes(whole)  # (the note count the file was planned for, or InputError)
    own = own_notes(plan, None if whole is None else whole.notes)
    out = []
    for part, idx, pre in zip(plan.hands, own, plan.pair.prefixes):
        tr = part.trajectory
        sub: Song | None = None
        meta = {**tr.metadata, "version": ONE_HAND_VERSION}
        if whole is not None:
            notes = whole.notes if idx is None else tuple(whole.notes[i] for i in idx)
            sub = replace(whole, notes=notes, part=None)
            meta["notes"] = len(notes)
        rep = check_trajectory(replace(tr, metadata=meta), sub, replay=True)
        # (no song path: the pictures draw the hand's own notes, its replay's expected
        # keys, not the file's parts read again)
        out.append((part.hand.side, replace(rep, trajectory=f"{path} ({pre[:-1]})",
                                            song=None)))
    return tuple(out)


def side_path(html_path: str, side: str) -> str:
    """``FILE`` with the hand's side before its extension (``a.html`` -> ``a.left.html``)."""
    stem, ext = os.path.splitext(html_path)
    return f"{stem}.{side}{ext or '.html'}"


def draw_pair_reports(path: str, song, options: dict[str, Any] | None,
                      report_dir: str | None, html_path: str | None,
                      enabled: bool = True) -> list[str]:
    """``check --report DIR`` / ``--html FILE`` of a two-hand plan (module docstring);
    returns the paths written."""
    from planner.report import draw_reports
    from planner.report.plots import write_check_report

    written: list[str] = []
    if report_dir and not os.path.isdir(report_dir):
        os.mkdir(report_dir)  # (the folder named, never its parents; each hand's in it)
    for side, rep in hand_reports(path, song, options):
        if report_dir:
            d = os.path.join(report_dir, side)
            written.extend(write_check_report(rep, d))
        if html_path:
            out = side_path(html_path, side)
            draw_reports(rep, None, out, enabled)
            written.append(out)
    return written
