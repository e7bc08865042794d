"""The check of a two-hand plan (a version-3 file, ``planner.pairfile.PairPlan``).

Each hand is judged as a one-hand file is, by its own model and by the same code
(``PlayJudge``, ``LimitAudit``, ``held_to_claims``, ``check_report``): its key-bed hits,
limits, couplings, motors and tendons, and its ``by_hand`` claim (every note the end
marker gives it, hit by its own bodies). The keys are one rule for both hands (spec
section 2: a key is down while any body of either hand holds it down): the song's frame
F1, its notes, wrong presses and the whole song's claims are judged on the keys of both.
Between the hands, every row's least distance (``planner.check.handgap``): a row closer
than ``HANDS_GAP_M`` is a collision. The rows are judged block by block (a file read as a
stream, or read whole)."""

from __future__ import annotations

import dataclasses
import os

import numpy as np

from planner.check import check_report, held_to_claims, play_problems
from planner.check.criteria import DOWN_DEPTH_M, N_KEYS
from planner.check.episodes import EpisodeStream
from planner.check.handgap import GapJudge
from planner.check.keys import PlayJudge, SongScorer, episodes_of, frame_period
from planner.check.kinematics import Kinematics
from planner.check.limits import LimitAudit
from planner.check.pairreport import PairReport
from planner.check.results import CheckReport, PlayResult
from planner.errors import InputError
from planner.hand.bodies import collision_bodies
from planner.pairfile import PairPlan
from planner.trajfile import song_start_s


class _Hand:
    """One hand's judges: its keys against its own notes, its limits."""

    def __init__(self, plan, notes, rate_hz: float) -> None:
        self.plan = plan
        self.kin = Kinematics(plan.hand, plan.T_world_root)
        self.bodies = collision_bodies(plan.hand.spec)
        self.notes = notes
        self.judge = PlayJudge(notes, rate_hz, self.bodies)
        self.audit = LimitAudit(plan.hand, self.kin, inertia=True)

    def add(self, t: np.ndarray, q: np.ndarray, qm: np.ndarray):
        from planner.check.bodykeys import body_keys

        tips, _ = self.kin.frames(q)
        keys = self.judge.add(t, tips, body_keys(self.kin, q, self.bodies))
        self.audit.add(t, q, qm, np.nan_to_num(keys.kc.tip_depth, nan=-1.0) >= DOWN_DEPTH_M)
        return keys


def own_notes(plan: PairPlan, notes) -> tuple[tuple[int, ...] | None, ...]:
    """Each hand's notes by its ``by_hand`` claim (song indices; None without a song or
    without the claim); InputError for an index past the song's notes."""
    if notes is None or plan.by_hand is None:
        return (None, None)
    for p, idx in plan.by_hand.items():
        if idx and max(idx) >= len(notes):
            raise InputError(f"{plan.path}: by_hand[{p!r}] names note {max(idx)}; the song has "
                             f"{len(notes)}")
    return tuple(plan.by_hand[p] for p in plan.pair.prefixes)


def check_pair_plan(plan: PairPlan, blocks, notes, song, *, min_f1: float | None,
                    strict: bool) -> PairReport:
    """Judge ``plan``'s rows (``blocks``: (t_s, q, q_motor) of the file's columns, in
    order) against ``notes`` (the whole song's in the file's time, or None)."""
    rate_hz = float(plan.metadata["rate_hz"])
    own = own_notes(plan, notes)
    hands = [_Hand(p, None if idx is None else [notes[i] for i in idx], rate_hz)
             for p, idx in zip(plan.hands, own)]
    names = tuple(pre + n for h, pre in zip(hands, plan.pair.prefixes) for n in h.judge.names)
    offset = len(hands[0].judge.names)
    together = None if notes is None else SongScorer(notes, rate_hz, names)
    played = EpisodeStream(N_KEYS)
    gap = GapJudge(tuple(h.kin for h in hands), tuple(h.bodies for h in hands),
                   plan.pair.prefixes)
    times = []
    for t, q, qm in blocks:
        qs, qms = plan.pair.split(q), plan.pair.split_motor(qm)
        (kl, kr) = (h.add(t, a, b) for h, a, b in zip(hands, qs, qms))
        down = kl.down | kr.down
        holder = np.where(kl.down, kl.holder, np.where(kr.down, kr.holder + offset, -1))
        played.add(down, t, holder.astype(np.int16))
        if together is not None:
            together.add(t, down, holder)
        gap.add(t, *qs)
        times.append(t)
    t_s = np.concatenate(times)
    period = frame_period(t_s)
    per_hand = [_hand_report(plan, h, pre, idx, song, t_s)
                for h, pre, idx in zip(hands, plan.pair.prefixes, own)]
    play = _together(plan, per_hand, episodes_of(played.finish(period), names), together,
                     notes, t_s)
    hands_gap = gap.finish(float(t_s[-1]) + period)
    problems = play_problems(dataclasses.replace(play, key_bed_hits=(), body_bed_hits=()),
                             min_f1, strict)
    if hands_gap.collisions:
        c = min(hands_gap.collisions, key=lambda c: c.least_m)
        problems.append(f"{len(hands_gap.collisions)} collisions between the hands: "
                        f"{hands_gap.collision_rows} rows closer than "
                        f"{hands_gap.limit_m * 1000:g} mm (closest: {c.left_body} and "
                        f"{c.right_body} {c.least_m * 1000:.1f} mm apart at {c.time_s:.3f} s)")
    for pre, rep in zip(plan.pair.prefixes, per_hand):
        problems.extend(f"{pre} {p}" for p in rep.problems)
    meta = plan.metadata
    return PairReport(
        trajectory=os.fspath(plan.path), song=_song_name(song), task=plan.task,
        hand=plan.pair.name, urdf_sha256=plan.pair.urdf_sha256,
        complete=plan.trajectory.complete, rows=len(t_s),
        duration_s=float(t_s[-1] - t_s[0]), rate_hz=rate_hz, play=play,
        prefixes=plan.pair.prefixes, hands=(per_hand[0], per_hand[1]), gap=hands_gap,
        min_f1=min_f1, problems=tuple(problems), song_start_s=song_start_s(meta))


def _song_name(song) -> str | None:
    if song is None:
        return None
    return os.fspath(song) if isinstance(song, (str, os.PathLike)) else song.source


def _hand_report(plan: PairPlan, h: _Hand, pre: str, idx, song, t_s) -> CheckReport:
    """One hand's report: its keys against its own notes, its ``by_hand`` claim held
    against them (every note it names, hit by this hand), its limits."""
    result = h.judge.finish(t_s)
    if idx is not None:
        claim = {"played": len(idx), "left_out": []}
        result = _to_song(held_to_claims(result, h.notes, claim, plan.path), idx)
    limits, tendons = h.audit.finish()
    problems = play_problems(dataclasses.replace(result, wrong_presses=()), None, False)
    return check_report(h.plan, song, t_s, limits, tendons, result, None, None, problems, None)


def _to_song(play: PlayResult, idx: tuple[int, ...]) -> PlayResult:
    """A hand's result with its notes named by their indices in the whole song."""
    def named(xs):
        return tuple(dataclasses.replace(x, note=idx[x.note]) for x in xs)

    return dataclasses.replace(play, missed=named(play.missed), late=named(play.late),
                               claim_mismatches=named(play.claim_mismatches))


def _together(plan: PairPlan, per_hand: list[CheckReport], played, scorer, notes,
              t_s) -> PlayResult:
    """The keys of both hands as one result (the key-bed hits of each, named with its
    prefix), scored against the whole song and held to the whole song's claims."""
    bed, body_bed = [], []
    for pre, rep in zip(plan.pair.prefixes, per_hand):
        bed += [dataclasses.replace(b, finger=pre + b.finger) for b in rep.play.key_bed_hits]
        body_bed += [dataclasses.replace(b, link=pre + b.link, body=pre + b.body)
                     for b in rep.play.body_bed_hits]
    bed.sort(key=lambda b: b.time_s)
    body_bed.sort(key=lambda b: b.time_s)
    if scorer is None:
        return PlayResult(len(t_s), tuple(played), tuple(bed), body_bed_hits=tuple(body_bed))
    s = scorer.finish(t_s)
    play = PlayResult(len(t_s), tuple(played), tuple(bed), f1=s.f1, precision=s.precision,
                      recall=s.recall, notes=len(notes), notes_hit=len(notes) - len(s.missed),
                      missed=s.missed, wrong_presses=s.wrong_presses, late=s.late,
                      song_frames=s.song_frames, body_bed_hits=tuple(body_bed))
    end = {k: v for k, v in plan.trajectory.end.items() if k != "by_hand"}
    return held_to_claims(play, notes, end, plan.path)

