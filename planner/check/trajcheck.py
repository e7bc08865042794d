"""The replay check's entry points (``planner.check``'s package docstring): a trajectory
file read whole or as a stream, judged by the package's rules, its report."""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any

import numpy as np

from planner.check.ball import catch_audit
from planner.check.bodykeys import body_keys, body_names
from planner.check.criteria import DOWN_DEPTH_M
from planner.check.keys import PlayJudge, play_replay
from planner.check.kinematics import Kinematics
from planner.check.limits import LimitAudit, limit_audit
from planner.check.results import CheckReport, PlayResult, Replay
from planner.check.verdict import check_report, held_to_claims, play_problems
from planner.errors import InputError
from planner.hand.bodies import collision_bodies
from planner.hand.model import HandModel
from planner.pairfile import PairPlan
from planner.planfile import read_plan
from planner.trajfile import NotStreamable, Trajectory, stream_trajectory

if TYPE_CHECKING:
    from planner.check.pairreport import PairReport
    from planner.music.midi import Song


def check_trajectory(traj_path: str | Trajectory, song_path: str | Song | None = None, *,
                     allow_incomplete: bool = False, min_f1: float | None = None,
                     hand_override: str | HandModel | None = None, strict: bool = False,
                     song_options: dict[str, Any] | None = None,
                     replay: bool = True) -> CheckReport | PairReport:
    """Replay ``traj_path`` and audit it (see the package docstring).

    ``traj_path``: a file, or a ``Trajectory`` already read (a plan made in memory).
    ``song_path``: a MIDI file (play only), or a ``Song`` read already, for F1, note hits
    and wrong presses, read with ``song_options`` (``track``, ``channel``, ``transpose``;
    each defaults to the file's metadata). ``min_f1``: the verdict also requires frame F1 >= this (needs a
    song). ``strict``: the verdict also fails on any missed or late note.
    ``hand_override``: a hand name / hand file or a HandModel to use instead of
    metadata["hand"] (its URDF hash must still match the file's).
    ``replay``: keep the per-row arrays (``CheckReport.replay``, for pictures); without
    them a play file is read and judged as a stream, block by block (memory bounded by
    the block, not the song; the same report).
    Raises InputError when the file cannot be replayed: damaged or incomplete (unless
    allowed), unknown hand, URDF hash or column mismatch, bad T_world_root, bad
    catch metadata, a song other than the plan's.
    """
    kw = {"allow_incomplete": allow_incomplete, "min_f1": min_f1,
          "hand_override": hand_override, "strict": strict, "song_options": song_options}
    if not replay and isinstance(traj_path, (str, os.PathLike)):
        try:
            return _check_streamed(os.fspath(traj_path), song_path, **kw)
        except (NotStreamable, InputError):
            pass  # (read whole: a catch, or bad input, named as read_trajectory names it)
    return _check_whole(traj_path, song_path, **kw)


def plan_notes(plan, song_path, min_f1: float | None, song_options):
    """The checks of the options against the plan, and the song's notes (None)."""
    if min_f1 is not None and not (0.0 <= min_f1 <= 1.0):
        raise InputError(f"--min-f1 must be within 0..1, got {min_f1}")
    task = plan.task
    if song_path is not None and task != "play":
        raise InputError(f"a song was given but {plan.path} is a {task} trajectory")
    if min_f1 is not None and song_path is None:
        raise InputError("--min-f1 needs a song")
    return None if song_path is None else plan.song_notes(song_path, song_options)


def _check_whole(traj_path, song_path, *, allow_incomplete, min_f1, hand_override, strict,
                 song_options) -> CheckReport | PairReport:
    """``check_trajectory`` of a file read whole (its replay arrays kept)."""
    plan = read_plan(traj_path, allow_incomplete=allow_incomplete,
                     hand_override=hand_override)
    notes = plan_notes(plan, song_path, min_f1, song_options)
    if isinstance(plan, PairPlan):
        return _check_pair(plan, None, notes, song_path, min_f1, strict)
    tr, traj_path, hand = plan.trajectory, plan.path, plan.hand
    task = plan.task
    kin = Kinematics(hand, plan.T_world_root)
    tips, palm = kin.frames(tr.q)
    problems: list[str] = []
    play = catch = None
    replay_kw: dict[str, Any] = {}
    pressing = ball_load = None
    if task == "play":
        play, keys, exp, bk, shapes = _play_whole(plan, kin, tips, notes)
        pressing = np.nan_to_num(keys.kc.tip_depth, nan=-1.0) >= DOWN_DEPTH_M
        replay_kw = {"down": keys.down, "finger": keys.holder, "expected": exp,
                     "holders": body_names(shapes)[0], "key_depth_m": bk.depth_m}
        problems.extend(play_problems(play, min_f1, strict))
    else:
        catch, ball_load = catch_audit(tr, kin, tips, palm, traj_path)
        problems.extend(catch.problems)
    limits, tendons = limit_audit(hand, kin, tr, pressing, ball_load, inertia=task == "play")
    return check_report(plan, song_path, tr.t_s, limits, tendons, play, catch, min_f1, problems,
                   Replay(tr.t_s, tr.q, tips, palm, **replay_kw))


def _play_whole(plan, kin: Kinematics, tips: np.ndarray, notes):
    """A play file's key replay by the body rule, its claims held against it: (play,
    keys, expected, body keys, shapes)."""
    tr = plan.trajectory
    shapes = collision_bodies(plan.hand.spec)
    bk = body_keys(kin, tr.q, shapes)
    play, keys, exp = play_replay(tr, tips, bk, shapes, notes)
    return held_to_claims(play, notes, tr.end, plan.path), keys, exp, bk, shapes


def check_play(traj_path: str | Trajectory, song_path: str | Song | None = None, *,
               allow_incomplete: bool = False, hand_override: str | HandModel | None = None,
               song_options: dict[str, Any] | None = None) -> PlayResult | None:
    """``check_trajectory(...).play`` without the limit audit (the same reading, the
    same errors on bad input, the same key replay and claims): the kinematic verdict
    ``simulate`` reports beside its physics. None for a catch file; for a two-hand file,
    the keys of both hands (``PairReport.play``, its whole check made)."""
    plan = read_plan(traj_path, allow_incomplete=allow_incomplete,
                     hand_override=hand_override)
    notes = plan_notes(plan, song_path, None, song_options)
    if isinstance(plan, PairPlan):
        return _check_pair(plan, None, notes, song_path, None, False).play
    if plan.task != "play":
        return None
    kin = Kinematics(plan.hand, plan.T_world_root)
    tips, _ = kin.frames(plan.trajectory.q)
    return _play_whole(plan, kin, tips, notes)[0]


def _check_streamed(path: str, song_path, *, allow_incomplete, min_f1, hand_override, strict,
                    song_options) -> CheckReport | PairReport:
    """``check_trajectory`` of a play file read as a stream: every rule judges the rows
    block by block (``PlayJudge``, ``LimitAudit``); kept per row only its time and what
    the song's notes need (bits). NotStreamable: read it whole."""
    stream = stream_trajectory(path, allow_incomplete)
    if stream.head.metadata["task"] != "play":
        raise NotStreamable("a catch")
    plan = read_plan(stream.head, hand_override=hand_override, name=path)
    notes = plan_notes(plan, song_path, min_f1, song_options)
    if isinstance(plan, PairPlan):
        return _check_pair(plan, stream, notes, song_path, min_f1, strict)
    hand, rate_hz = plan.hand, stream.rate_hz
    kin = Kinematics(hand, plan.T_world_root)
    shapes = collision_bodies(hand.spec)
    judge = PlayJudge(notes, rate_hz, shapes)
    audit = LimitAudit(hand, kin, inertia=True)
    times = []
    for t, q, qm in stream.blocks():
        tips, _ = kin.frames(q)
        keys = judge.add(t, tips, body_keys(kin, q, shapes))
        audit.add(t, q, qm, np.nan_to_num(keys.kc.tip_depth, nan=-1.0) >= DOWN_DEPTH_M)
        times.append(t)
    t_s = np.concatenate(times)
    play = held_to_claims(judge.finish(t_s), notes, stream.head.end, path)
    problems = play_problems(play, min_f1, strict)
    limits, tendons = audit.finish()
    return check_report(plan, song_path, t_s, limits, tendons, play, None, min_f1, problems, None)


def _check_pair(plan: PairPlan, stream, notes, song_path, min_f1, strict) -> PairReport:
    """A two-hand plan's check (``planner.check.pair``): its rows from ``stream`` (a
    ``TrajectoryStream``) or, None, the file read whole."""
    from planner.check.pair import check_pair_plan

    tr = plan.trajectory
    blocks = [(tr.t_s, tr.q, tr.q_motor)] if stream is None else stream.blocks()
    return check_pair_plan(plan, blocks, notes, song_path, min_f1=min_f1, strict=strict)
