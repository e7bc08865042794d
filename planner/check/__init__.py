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
per-row arrays are asked for), ``results`` (frozen results, summary, JSON),
``trajcheck`` (``check_trajectory`` and ``check_play``: a file read and judged). The
package imports its names on first use (``planner.lazy``): a planner importing one rule
(``kinematics``, ``ballstop``) does not load the others.

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
  ``planner.planhand.T_TOL``; for ``catch`` the catch frame has its origin at the launch point,
  so the hand may be mounted anywhere in it -- the pose is only required to be
  a rigid transform.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from planner.lazy import lazy_dir, lazy_names

if TYPE_CHECKING:
    from planner.check.ball import (
        ball_params,
        ball_positions,
        catch_audit,
    )
    from planner.check.bodykeys import (  # noqa: F401
        body_keys,
        body_names,
    )
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
    from planner.check.keys import (  # noqa: F401
        PlayJudge,
        key_episodes,
        play_replay,
    )
    from planner.check.kinematics import (  # noqa: F401
        Kinematics,
        fk_frames,
        keys_down,
    )
    from planner.check.limits import (  # noqa: F401
        LimitAudit,
        limit_audit,
    )
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
    from planner.check.trajcheck import (  # noqa: F401
        check_play,
        check_trajectory,
        plan_notes,
    )
    from planner.check.verdict import (  # noqa: F401
        check_report,
        held_to_claims,
        play_problems,
    )
    from planner.trajfile import (  # noqa: F401
        NotStreamable,
        Trajectory,
        is_num,
        stream_trajectory,
    )

_API = {
    "CatchResult": "planner.check.results",
    "CheckReport": "planner.check.results",
    "ClaimKey": "planner.check.claims",
    "ClaimMismatch": "planner.check.results",
    "CountMismatch": "planner.check.claims",
    "DOWN_DEPTH_M": "planner.check.criteria",
    "GRASP_MIN_TIPS": "planner.check.criteria",
    "GRASP_TOL_M": "planner.check.criteria",
    "GRASP_WINDOW_S": "planner.check.criteria",
    "INTERCEPT_TOL_M": "planner.check.criteria",
    "KEY_BED_DEPTH_M": "planner.check.criteria",
    "KeyBedHit": "planner.check.results",
    "KeyContacts": "planner.check.criteria",
    "KeyEpisode": "planner.check.results",
    "Kinematics": "planner.check.kinematics",
    "LATE_S": "planner.check.criteria",
    "LateNote": "planner.check.results",
    "LimitAudit": "planner.check.limits",
    "LimitCheck": "planner.check.results",
    "MissedNote": "planner.check.results",
    "NOTE_HIT_FRACTION": "planner.check.criteria",
    "NotStreamable": "planner.trajfile",
    "PlayClaims": "planner.check.claims",
    "PlayJudge": "planner.check.keys",
    "PlayResult": "planner.check.results",
    "Replay": "planner.check.results",
    "TendonLoad": "planner.check.results",
    "TipTouch": "planner.check.results",
    "Trajectory": "planner.trajfile",
    "ball_params": "planner.check.ball",
    "ball_positions": "planner.check.ball",
    "body_keys": "planner.check.bodykeys",
    "body_names": "planner.check.bodykeys",
    "catch_audit": "planner.check.ball",
    "check_play": "planner.check.trajcheck",
    "check_report": "planner.check.verdict",
    "check_trajectory": "planner.check.trajcheck",
    "count_mismatches": "planner.check.claims",
    "expected_keys": "planner.check.criteria",
    "fk_frames": "planner.check.kinematics",
    "frame_f1": "planner.check.criteria",
    "frame_scores": "planner.check.criteria",
    "held_to_claims": "planner.check.verdict",
    "is_num": "planner.trajfile",
    "key_contacts": "planner.check.criteria",
    "key_episodes": "planner.check.keys",
    "keys_down": "planner.check.kinematics",
    "left_out_notes": "planner.check.claims",
    "limit_audit": "planner.check.limits",
    "pitch_name": "planner.check.criteria",
    "plan_notes": "planner.check.trajcheck",
    "play_problems": "planner.check.verdict",
    "play_replay": "planner.check.keys",
    "read_claims": "planner.check.claims",
    "song_frames": "planner.check.criteria",
    "stream_trajectory": "planner.trajfile",
}

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

__getattr__ = lazy_names(__name__, _API)
__dir__ = lazy_dir(globals(), _API)
