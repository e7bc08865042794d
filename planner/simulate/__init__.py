"""The physics replay: a trajectory run in MuJoCo, scored from the physics.

``simulate_trajectory(path, song)`` reads a ``hand-trajectory`` v1 file as ``check``
does (the same reader, hand, URDF hash, columns and ``T_world_root`` rules), builds the
scene (``scene``: the hand from its URDF, ``keyboard``: 88 keys, or the catch's
ball; ``actuators``: a torque-limited position servo per motor, couplings as equality
constraints), runs it (``replay``) and scores it (``scores``), with the kinematic
check's F1 of the same file beside the physics F1. The modules: ``hand_mjcf`` (URDF ->
MJCF), ``keyboard``, ``actuators``, ``scene``, ``replay`` (with ``nearkeys``: only the
keys the hand can reach collide, and ``sampling``: what a row reads), ``scores``,
``report``, ``compare``; the pictures (``--video``, ``--html``): ``render``, ``video``, ``page``,
``pictures``.

Verdict (``SimulateReport.ok``): fails on wrong keys, on notes the plan's end marker
claims played that the physics misses, on a motor saturated longer than
``scores.SATURATION_MAX_S``, on a catch not held, on F1 under ``min_f1``, on a diverged
simulation, on a hand faster than ``nearkeys``' margin allows; ``strict``
also on any missed or late note. MuJoCo is an optional dependency
(``pip install -e ".[physics]"``); without it the command says so (exit 2).
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any

from planner.lazy import lazy_dir, lazy_names

if TYPE_CHECKING:
    from planner.simulate.verdict import Replay

__all__ = ["Replay", "physics_problems", "record_problems", "run_replay", "simulate_trajectory"]
_VERDICT = {n: "planner.simulate.verdict" for n in ("Replay", "physics_problems",
                                                     "record_problems")}
__getattr__ = lazy_names(__name__, _VERDICT)  # (imported on first use: the package is
# loaded for its ``keyboard`` module by every hand's finger bodies, a live catch's too)
__dir__ = lazy_dir(globals(), _VERDICT)


def simulate_trajectory(traj_path, song_path=None, *, contact: str = "full",
                        min_f1: float | None = None, strict: bool = False,
                        allow_incomplete: bool = False,
                        song_options: dict[str, Any] | None = None, hand_override=None):
    """Replay ``traj_path`` in MuJoCo and score it (see the package docstring).
    ``hand_override``: as ``check_trajectory``'s (a hand name, hand file or HandModel in
    place of the file's hand name; its URDF hash must match the file's)."""
    return run_replay(traj_path, song_path, contact=contact, min_f1=min_f1, strict=strict,
                      allow_incomplete=allow_incomplete, song_options=song_options,
                      hand_override=hand_override).report


def run_replay(traj_path, song_path=None, *, contact: str = "full",
               min_f1: float | None = None, strict: bool = False,
               allow_incomplete: bool = False,
               song_options: dict[str, Any] | None = None, hand_override=None) -> Replay:
    """``simulate_trajectory`` keeping the record (for pictures and comparisons)."""
    from planner.check import check_play, check_trajectory
    from planner.check.claims import left_out_notes
    from planner.planfile import read_plan
    from planner.simulate.replay import simulate
    from planner.simulate.report import SimulateReport
    from planner.simulate.scene import Ball, build_scene, require_mujoco
    from planner.simulate.scores import motor_efforts, score_catch, score_play, tracking
    from planner.simulate.verdict import Replay, physics_problems, record_problems

    require_mujoco()  # the clear message before any work
    plan = read_plan(traj_path, allow_incomplete=allow_incomplete, hand_override=hand_override)
    from planner.pairfile import PairPlan

    if isinstance(plan, PairPlan):  # (a two-hand file: planner.simulate.pair)
        from planner.simulate.pair import run_pair_replay

        return run_pair_replay(plan, song_path, contact=contact, min_f1=min_f1, strict=strict,
                               song_options=song_options)
    tr, name, hand, T = plan.trajectory, plan.path, plan.hand, plan.T_world_root
    # the kinematic check validates the file (hand, hash, columns, pose, song) and gives
    # the F1 to compare with (a play file's key replay: its limit audit is not needed)
    meta = tr.metadata
    task = meta["task"]
    kw = {"allow_incomplete": allow_incomplete, "song_options": song_options,
          "hand_override": hand_override}
    kin_play = (check_play(tr, song_path, **kw) if task == "play"
                else check_trajectory(tr, song_path, **kw).play)
    ball = None
    if task == "catch":
        from planner.balls import file_inertia_ratio
        from planner.check.ball import ball_params, judged_source

        meta = judged_source(tr, name)  # (a live file: its last estimate, as the check's)
        b = ball_params(meta, name)
        ball = Ball(tuple(b["p0"]), tuple(b["v0"]), float(b["radius"]), float(b["mass"]),
                    float(b["drag"]), file_inertia_ratio(meta))
        hand = hand.mounted(T)
    scene = build_scene(hand, T, keyboard=task == "play", ball=ball, contact=contact)
    rec = simulate(scene, hand, tr.t_s, tr.q, ball=ball)
    notes = None if song_path is None else plan.song_notes(song_path, song_options)
    play = catch = None
    claims: list = []
    if task == "play":
        play = score_play(rec, notes, float(meta["rate_hz"]))
        if notes is not None:
            left = left_out_notes(tr.end, len(notes), name) or set()
            claims = [m for m in play.missed if m.note not in left]
    else:
        catch = score_catch(rec, float(meta["intercept_t"]), ball.radius_m)
    motors = motor_efforts(rec, hand)
    problems = record_problems(rec) + physics_problems(play, motors, catch, min_f1, strict,
                                                       claims)
    song_name = None if song_path is None else (
        os.fspath(song_path) if isinstance(song_path, (str, os.PathLike)) else song_path.source)
    report = SimulateReport(
        trajectory=os.fspath(name), song=song_name, task=task, hand=hand.name, contact=contact,
        rows=len(tr.t_s), duration_s=float(tr.t_s[-1] - tr.t_s[0]), wall_s=rec.wall_s,
        play=play, catch=catch, motors=motors, tracking=tracking(rec, hand),
        kinematic_f1=None if kin_play is None else kin_play.f1, problems=tuple(problems))
    return Replay(report, rec, hand, tr, None if notes is None else tuple(notes), scene)
