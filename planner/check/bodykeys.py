"""The body rule (spec section 2, "Bodies"): the keys the hand's collision bodies press.

A key is down while any collision body of the hand (``planner.hand.bodies``) reaches at
least ``DOWN_DEPTH_M`` (5 mm) below its resting top inside its footprint; so pressed
where no note of it sounds, it is a wrong note, as with a point. No body may reach more
than ``criteria.BED_MARGIN_M`` (1 mm) below the key bed (10 mm dip) inside any
footprint: ``criteria.BODY_BED_DEPTH_M``, 11 mm below its top. The fingertip point rule (``criteria.key_contacts``) is the special case of
a body of zero size; every pad point is its pad sphere's bottom, so a key down by the
point rule is down by the bodies too.

One definition: ``check`` reports it (``check_trajectory``) and the planners'
self-checks call the same ``body_keys`` and ``judge_bodies``. The geometry (each body's
lowest point in each footprint, exact) is ``planner.music.keybodies``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from planner.check.criteria import (
    BODY_BED_DEPTH_M,
    DOWN_DEPTH_M,
    LOWEST_PITCH,
    N_KEYS,
    pitch_name,
)
from planner.check.episodes import EpisodeStream
from planner.check.keys import SongScorer, frame_period
from planner.check.kinematics import Kinematics
from planner.check.results import BodyBedHit, BodyResult
from planner.hand.bodies import Body, body_links, place
from planner.music.keybodies import column_depths
from planner.trajfile import distinct_rows


@dataclass(frozen=True)
class BodyKeys:
    """Per row and key: ``down`` (T, 88) by the body rule, ``depth_m`` (T, 88) how far
    below the key's top the deepest body reaches in its footprint (-inf, or less than
    ``DOWN_DEPTH_M``, where none reaches that deep), ``body`` (T, 88) that body (index
    into ``bodies``, -1 none)."""

    bodies: tuple[Body, ...]
    down: np.ndarray
    depth_m: np.ndarray
    body: np.ndarray


def body_keys(kin: Kinematics, Q: np.ndarray, bodies: tuple[Body, ...]) -> BodyKeys:
    """The body rule on every row of ``Q`` (joint rows), the hand's frames from ``kin``
    (a row equal to the one before it judged once)."""
    Q = np.atleast_2d(np.asarray(Q, dtype=float))
    new, of = distinct_rows(Q)
    poses = kin.link_poses(Q[new], body_links(bodies))
    depth, which = column_depths(place(bodies, poses), DOWN_DEPTH_M)
    depth, which = depth[of], which[of]
    return BodyKeys(bodies, depth >= DOWN_DEPTH_M, depth, which)


def _link_rows(bk: BodyKeys, links: tuple[str, ...]) -> np.ndarray:
    """(T, 88) index into ``links`` of the link whose body holds each key down, -1 none."""
    of_body = np.array([links.index(b.link) for b in bk.bodies] + [-1])
    return np.where(bk.down, of_body[bk.body], -1)


def bed_hits(t_s: np.ndarray, bk: BodyKeys) -> tuple[BodyBedHit, ...]:
    """Contiguous rows in which some body reaches past ``BODY_BED_DEPTH_M`` in a key's
    footprint, per key: the first row, the deepest reach and its body's link."""
    t_s = np.asarray(t_s, dtype=float)
    stream = EpisodeStream(bk.down.shape[1])
    stream.add(bk.depth_m > BODY_BED_DEPTH_M, t_s, bk.body, bk.depth_m)
    return _bed_hits(stream.finish(frame_period(t_s)), bk.bodies)


def _bed_hits(runs, bodies) -> tuple[BodyBedHit, ...]:
    out = []
    for r in runs:
        p = r.key + LOWEST_PITCH
        b = bodies[r.best_tag]
        out.append(BodyBedHit(r.start_s, r.start_row, r.end_s, p, pitch_name(p), b.link, b.name,
                              r.best))
    return tuple(out)


class BodyJudge:
    """The body rule's findings over rows given block by block (``add``: their times and
    ``BodyKeys``), then ``finish``: keys pressed, bed hits, and with ``notes`` the frame
    scores, the notes hit and the wrong presses (each with the links whose bodies held the
    key down). ``judge_bodies`` is one block."""

    def __init__(self, bodies: tuple[Body, ...], notes, rate_hz: float,
                 verdict: bool = False) -> None:
        self._bodies, self._notes, self._verdict = bodies, notes, verdict
        self._links = body_links(bodies)
        self._played = EpisodeStream(N_KEYS, keep=False)
        self._bed = EpisodeStream(N_KEYS)
        self._score = None if notes is None else SongScorer(notes, rate_hz, self._links)

    def add(self, t_s: np.ndarray, bk: BodyKeys) -> None:
        rows = _link_rows(bk, self._links)
        self._played.add(bk.down, t_s)
        self._bed.add(bk.depth_m > BODY_BED_DEPTH_M, t_s, bk.body, bk.depth_m)
        if self._score is not None:
            self._score.add(t_s, bk.down, rows)

    def finish(self, t_s: np.ndarray) -> BodyResult:
        """The findings; ``t_s``: every row's time."""
        period = frame_period(t_s)
        self._played.finish(period)
        played = self._played.count
        bed = _bed_hits(self._bed.finish(period), self._bodies)
        if self._score is None:
            return BodyResult(self._verdict, played, bed)
        notes, score = self._notes, self._score.finish(t_s)
        return BodyResult(self._verdict, played, bed, score.f1, score.precision, score.recall,
                          len(notes), len(notes) - len(score.missed), score.wrong_presses)


def judge_bodies(t_s: np.ndarray, bk: BodyKeys, notes, rate_hz: float,
                 verdict: bool = False) -> BodyResult:
    """The body rule's findings over rows at times ``t_s`` (``BodyJudge``, one block)."""
    t_s = np.asarray(t_s, dtype=float)
    judge = BodyJudge(bk.bodies, notes, rate_hz, verdict)
    judge.add(t_s, bk)
    return judge.finish(t_s)


def body_problems(res: BodyResult) -> list[str]:
    """The verdict's lines for the body rule (``check --bodies``)."""
    out = []
    if res.bed_hits:
        h = res.bed_hits[0]
        out.append(f"{len(res.bed_hits)} body key-bed hits (first: {h.link} on {h.name} at "
                   f"{h.time_s:.3f} s, {h.depth_m * 1000:.2f} mm below the top)")
    if res.wrong_presses:
        w = res.wrong_presses[0]
        out.append(f"{len(res.wrong_presses)} wrong presses by bodies (first: {w.name} at "
                   f"{w.start_s:.3f} s by {'+'.join(w.fingers)})")
    return out
