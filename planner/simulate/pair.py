"""The physics replay of a two-hand plan (a version-3 file, ``planner.pairfile.PairPlan``).

One MuJoCo scene: the keyboard once, both hands (``scene.build_parts``: each hand's bodies,
servos and couplings as for one hand, every name prefixed ``left.``/``right.``), each
hand's geoms colliding with the keys and with the other hand's geoms, not its own
(``scene.pair_bits``). The same replay (``replay.simulate``: each hand's servo reference
from its own rows and its own inverse dynamics) and the same scores: the keys of both
hands against the whole song (``scores.score_play``), each hand's motors and tracking by
its own model (``scores.motor_efforts``, ``tracking`` on its columns), the notes of its
``by_hand`` claim that sound. A contact between the hands is a collision: counted, named
(the first two geoms of each run of rows) and a problem."""

from __future__ import annotations

import dataclasses
import os

import numpy as np

from planner.pairfile import PairPlan
from planner.simulate.pairreport import HandPhysics, HandsTouch, PairSimulateReport


def _hand_record(rec, i: int, plan: PairPlan, finger_cut: list[int]):
    """Hand ``i``'s part of the record: its joints, servos, fingers (its own indices)."""
    n0, m0 = plan.hands[0].hand.n, plan.hands[0].hand.n_motor
    j = slice(0, n0) if i == 0 else slice(n0, None)
    m = slice(0, m0) if i == 0 else slice(m0, None)
    a, b = finger_cut[i], finger_cut[i + 1]
    kf = rec.key_finger
    mine = (kf >= a) & (kf < b)
    return dataclasses.replace(rec, q_ref=rec.q_ref[:, j], q_sim=rec.q_sim[:, j],
                               servo_demand=rec.servo_demand[:, m],
                               servo_force=rec.servo_force[:, m],
                               force_limit=rec.force_limit[:, m],
                               key_finger=np.where(mine, kf - a, -1).astype(np.int8),
                               ball_fingers=rec.ball_fingers[:, a:b])


def _touches(rec, scene) -> tuple[HandsTouch, ...]:
    """Runs of rows with a contact between the hands."""
    rows: dict[int, tuple[int, int]] = {}
    for k, g1, g2 in rec.hand_contacts:
        rows.setdefault(k, (g1, g2))
    out: list[HandsTouch] = []
    t = rec.t_s
    period = float(np.median(np.diff(t))) if len(t) > 1 else 0.01
    ks = sorted(rows)
    start = 0
    for n in range(1, len(ks) + 1):
        if n == len(ks) or ks[n] != ks[n - 1] + 1:
            first, last = ks[start], ks[n - 1]
            g1, g2 = rows[first]
            end = float(t[last + 1]) if last + 1 < len(t) else float(t[last]) + period
            out.append(HandsTouch(float(t[first]), first, end, last - first + 1,
                                  scene.model.geom(g1).name, scene.model.geom(g2).name))
            start = n
    return tuple(out)


def _hand_physics(rec, i: int, plan: PairPlan, finger_cut, play, notes) -> HandPhysics:
    from planner.simulate.scores import motor_efforts, tracking

    part, pre = plan.hands[i], plan.pair.prefixes[i]
    hand = part.hand
    rh = _hand_record(rec, i, plan, finger_cut)
    motors = tuple(dataclasses.replace(m, name=f"motor.{pre}{m.name[6:]}")
                   for m in motor_efforts(rh, hand))
    joints = tuple(dataclasses.replace(j, name=pre + j.name) for j in tracking(rh, hand))
    wrong = sum(any(f.startswith(pre) for f in w.fingers) for w in play.wrong_keys)
    own = None if notes is None or plan.by_hand is None else plan.by_hand[pre]
    missed = {m.note for m in play.missed}
    hit = None if own is None else sum(k not in missed for k in own)
    return HandPhysics(pre, hand.name, None if own is None else len(own), hit, wrong, motors,
                       joints)


def run_pair_replay(plan: PairPlan, song_path=None, *, contact: str = "full",
                    min_f1: float | None = None, strict: bool = False,
                    song_options=None):
    """``run_replay`` of a two-hand plan (see the module docstring)."""
    from planner.check import check_play
    from planner.check.claims import left_out_notes
    from planner.simulate import Replay, physics_problems, record_problems
    from planner.simulate.replay import simulate
    from planner.simulate.scene import build_parts, pair_parts
    from planner.simulate.scores import score_play

    tr, name = plan.trajectory, plan.path
    hands = tuple(p.hand for p in plan.hands)
    kin_play = check_play(tr, song_path, song_options=song_options)
    parts = pair_parts(hands, tuple(p.T_world_root for p in plan.hands), plan.pair.prefixes)
    scene = build_parts(plan.pair.name, parts, keyboard=True, contact=contact)
    rec = simulate(scene, hands, tr.t_s, tr.q)
    notes = None if song_path is None else plan.song_notes(song_path, song_options)
    names = tuple(pre + f for h, pre in zip(hands, plan.pair.prefixes) for f in h.fingers)
    finger_cut = [0, len(hands[0].fingers), len(names)]
    play = score_play(rec, notes, float(tr.metadata["rate_hz"]), names)
    claims: list = []
    if notes is not None:
        left = left_out_notes(tr.end, len(notes), name) or set()
        claims = [m for m in play.missed if m.note not in left]
    per_hand = tuple(_hand_physics(rec, i, plan, finger_cut, play, notes) for i in (0, 1))
    touches = _touches(rec, scene)
    problems = record_problems(rec) + physics_problems(
        play, [m for h in per_hand for m in h.motors], None, min_f1, strict, claims)
    if touches:
        c = touches[0]
        problems.append(f"{len(touches)} contacts between the hands in physics (first: "
                        f"{c.left_geom} and {c.right_geom} at {c.start_s:.3f} s, {c.rows} "
                        "rows)")
    song_name = None if song_path is None else (
        os.fspath(song_path) if isinstance(song_path, (str, os.PathLike)) else song_path.source)
    report = PairSimulateReport(
        trajectory=os.fspath(name), song=song_name, task=plan.task, hand=plan.pair.name,
        contact=contact, rows=len(tr.t_s), duration_s=float(tr.t_s[-1] - tr.t_s[0]),
        wall_s=rec.wall_s, play=play, hands=per_hand, touches=touches,
        kinematic_f1=None if kin_play is None else kin_play.f1, problems=tuple(problems))
    return Replay(report, rec, hands, tr, None if notes is None else tuple(notes), scene)
