"""The independent replay check: what does a trajectory file really do?

``check_trajectory(path, song)`` reads a ``hand-trajectory`` v1 file (spec
section 4), rebuilds the hand it names, replays every row through forward
kinematics and reports

* **play**: which keys go down in every frame (spec section 2's body rule,
  ``bodykeys``: any collision body of the hand inside a key's footprint -- for a
  white key minus the black keys' rectangles -- at least ``DOWN_DEPTH_M`` below the
  key's resting top; a fingertip point is the bottom of its pad sphere, so the point
  rule is the special case), key-bed hits (a fingertip in a footprint more than
  ``KEY_BED_DEPTH_M`` below that top, a body more than ``BODY_BED_DEPTH_M``), and
  with a song: frame-level precision / recall / F1 (RoboPianist's
  metric), note-level hits, missed notes and wrong presses;
* **catch**: the ball's flight (integrated here), where it meets the palm,
  fingertips touching it early and the grasp after the intercept;
* **both**: a limit audit (joint positions, speeds, accelerations, motor
  speeds, motor columns against the joints, motor torque (with the hand's inertia on a
  play), couplings, tendon
  tensions).

The package: ``criteria`` (the rules, imported by the planners' self-checks
too), ``kinematics`` (its own Pinocchio model), ``keys`` (play), ``ball``
(catch), ``limits`` (the audit), ``worst`` and ``episodes`` (a category's worst and the
keys' runs merged across blocks of rows: a play file is judged as a stream unless its
per-row arrays are asked for), ``results`` (frozen results, summary, JSON).

The file contract (``planner.trajfile``): rows at ``rate_hz`` from t = 0 (within
``ROW_TIME_TOL_S``), no gap, at least two rows; a damaged file is bad input (exit
2) with the first bad row named. With a song, the file's metadata must name as
many notes as the song has (with its ``track``, ``channel`` and ``transpose``,
which the check reads from the metadata unless given).

The verdict fails on key-bed hits, wrong presses, limit violations, a failed
catch, F1 under ``min_f1``, and on any claim of the plan's end marker the replay
contradicts (``planner.check.claims``): its ``notes`` and ``played`` counts, and
every note's outcome (``left_out``: the notes it says it left out, every other
note it says it played). A claim of the wrong type is bad input. ``strict`` also fails it on any missed
or late note.

A two-hand file (version 3, ``planner.pairfile``) is judged by ``planner.check.pair``:
each hand by the code that judges one, the keys of both together, and the distance
between the hands (``planner.check.handgap``); its report is a ``PairReport``.

Independence: this package shares only the hand model, the keyboard geometry,
the trajectory and plan-file readers (``planner.trajfile``, ``planner.planfile``,
``planner.pairfile``), the MIDI reader and the results' plain form (``planner.resultform``) with the planner. It never imports
``planner.play``, ``planner.ik``, ``planner.trajectory``, ``planner.catch`` or
``planner.selfcheck`` (the planners' side), and it runs its own copy of the Pinocchio
model (so it never touches the shared hand's data, and can put the root where
the file's metadata says).

Choices (each one a named constant below):

* Times. The song's clock is the trajectory's clock (t = 0 in both). A note
  sounds in frame ``t`` when ``onset_s <= t < offset_s``.
* Frame F1 (``frame_scores``) over the song's frames (``song_frames``: rows
  missing at the end count as frames with nothing pressed, rows after the last
  note are not scored): per frame, a binary classification over the 88
  keys scored like ``sklearn.metrics.precision_recall_fscore_support(...,
  average="binary", zero_division=1)``: precision = tp/(tp+fp), recall =
  tp/(tp+fn), F1 = 2 tp/(2 tp+fp+fn), each 1 when its denominator is 0 -- so
  a frame with nothing expected and nothing pressed scores 1, and a frame with
  only false positives or only misses scores 0. The three are averaged over
  the song's frames.
* Note hits: a note is hit when its key is down in at least
  ``NOTE_HIT_FRACTION`` (50 %) of the frames in ``[onset, offset)``; a note
  with no frame inside that interval (shorter than a frame period, or
  after the trajectory's end) cannot be hit and is listed as missed with the
  reason.
* Wrong presses: a key down in a frame where no note of that key sounds,
  grouped into contiguous episodes per key. An episode runs from its first
  frame's time to the time of the frame after its last one (one median frame
  period past the last row at the end of the file), and lists every finger
  that held the key down during it.
* Speeds and accelerations are first and second differences of consecutive
  rows (non-uniform steps handled). For a trajectory whose continuous speed
  and acceleration respect the limits, the differences do too (they are
  averages of the continuous quantity), so they are a sound test. Tolerances
  are 1 % of the limit plus the effect of the file's 6-decimal rounding
  (``1e-6/dt`` for speeds, ``2e-6/dt^2`` for second differences: 0.02 rad/s^2
  at 100 Hz). The speed is reported at the later row of its pair, the
  acceleration at the middle row of its triple.
* Motor torque: gravity (with the file's ``T_world_root`` orientation) plus,
  for play, a nominal ``KEY_FORCE_N`` = 0.5 N upward on every fingertip that
  holds a key down (the planner may press harder) and the torques that move
  the hand through its rows (RNEA on central differences of the rows: the
  rail carrying the hand sideways loads the wrist), and for a catch, after the
  intercept, the ball's weight on the palm centre (the arm's own inertia is not
  counted there) -- mapped to the motors with ``HandModel.motor_torques`` and
  compared with ``motor_peak_torque`` (1 %).
* Motor columns must equal ``HandModel.motor_angles(q)`` of the row's joints
  within ``MOTOR_TOL_RAD`` (1e-5 rad) plus the rounding of the file (half a
  unit of the 6th decimal on the motor value and on each joint, weighted by
  the motor's sensitivity to it: 100 rad/m for the rail's belt). Couplings
  likewise within ``COUPLING_TOL_RAD`` plus rounding.
* Catch: the ball flies from ``p0, v0`` at t = 0 (acceleration g - k|v|v,
  closed form when k = 0, else RK4 with steps of at most 1 ms). At
  ``intercept_t`` (joint rows interpolated linearly in time) its centre must
  lie within ``INTERCEPT_TOL_M`` (15 mm) of ``palm_center + radius * n`` (n the
  palm frame's +z). Before ``intercept_t`` no fingertip may be closer than the
  radius to the ball's centre. From ``intercept_t`` on the ball is taken to
  be held: its centre is ``palm_center + radius * n`` of each row. Within
  ``GRASP_WINDOW_S`` (150 ms) after ``intercept_t`` some row must have at least
  ``GRASP_MIN_TIPS`` (3) fingertips, the thumb among them, within
  ``radius + GRASP_TOL_M`` (10 mm) of the ball's centre, and every later row
  must keep that grasp (the catch holds to the end of the file).
* ``T_world_root``: the FK uses the metadata's pose. For ``play`` it must equal
  the hand's mount (the keyboard frame is defined by that mount) within
  ``planner.planfile.T_TOL``; for ``catch`` the catch frame has its origin at the launch point,
  so the hand may be mounted anywhere in it -- the pose is only required to be
  a rigid transform.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any

import numpy as np

from planner.check.ball import ball_params, ball_positions, catch_audit
from planner.check.bodykeys import bed_problem, body_keys, body_names
from planner.check.claims import (
    ClaimKey,
    CountMismatch,
    PlayClaims,
    count_mismatches,
    left_out_notes,
    read_claims,
)
from planner.check.criteria import (
    DOWN_DEPTH_M,
    GRASP_MIN_TIPS,
    GRASP_TOL_M,
    GRASP_WINDOW_S,
    INTERCEPT_TOL_M,
    KEY_BED_DEPTH_M,
    LATE_S,
    NOTE_HIT_FRACTION,
    KeyContacts,
    expected_keys,
    frame_f1,
    frame_scores,
    key_contacts,
    pitch_name,
    song_frames,
)
from planner.check.keys import PlayJudge, key_episodes, play_replay
from planner.check.kinematics import Kinematics, fk_frames, keys_down
from planner.check.limits import LimitAudit, limit_audit
from planner.check.results import (
    CatchResult,
    CheckReport,
    ClaimMismatch,
    KeyBedHit,
    KeyEpisode,
    LateNote,
    LimitCheck,
    MissedNote,
    PlayResult,
    Replay,
    TendonLoad,
    TipTouch,
)
from planner.errors import InputError
from planner.hand.bodies import collision_bodies
from planner.hand.model import HandModel
from planner.pairfile import PairPlan
from planner.planfile import read_plan
from planner.trajfile import (
    NotStreamable,
    Trajectory,
    is_num,
    song_start_s,
    stream_trajectory,
)

if TYPE_CHECKING:
    from planner.check.pairreport import PairReport
    from planner.music.midi import Song

__all__ = [
    "DOWN_DEPTH_M",
    "GRASP_MIN_TIPS",
    "GRASP_TOL_M",
    "GRASP_WINDOW_S",
    "INTERCEPT_TOL_M",
    "KEY_BED_DEPTH_M",
    "LATE_S",
    "NOTE_HIT_FRACTION",
    "CatchResult",
    "CheckReport",
    "ClaimKey",
    "ClaimMismatch",
    "CountMismatch",
    "KeyBedHit",
    "KeyContacts",
    "KeyEpisode",
    "LateNote",
    "LimitCheck",
    "MissedNote",
    "PlayClaims",
    "PlayResult",
    "Replay",
    "TendonLoad",
    "TipTouch",
    "ball_params",
    "ball_positions",
    "catch_audit",
    "check_play",
    "check_trajectory",
    "count_mismatches",
    "expected_keys",
    "fk_frames",
    "frame_f1",
    "frame_scores",
    "is_num",
    "key_contacts",
    "key_episodes",
    "keys_down",
    "left_out_notes",
    "pitch_name",
    "read_claims",
    "song_frames",
]

def _claim_mismatches(notes, missed_notes: set[int], left_out: set[int]) -> list[ClaimMismatch]:
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
    ``simulate`` reports beside its physics. None for a catch file."""
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
                else _claim_mismatches(notes, missed, claims.left_out))
    return dataclasses.replace(play, claims=True, claim_mismatches=tuple(per_note),
                               count_mismatches=tuple(count_mismatches(claims, len(notes),
                                                                       len(missed))))
