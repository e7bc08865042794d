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

from planner.check.criteria import BODY_BED_DEPTH_M, DOWN_DEPTH_M, LOWEST_PITCH, pitch_name
from planner.check.keys import key_episodes, score_song
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
    deep = bk.depth_m > BODY_BED_DEPTH_M
    out = []
    for ep in key_episodes(deep, t_s):
        k = ep.pitch - LOWEST_PITCH
        rows = np.flatnonzero(deep[:, k] & (t_s >= ep.start_s) & (t_s < ep.end_s))
        worst = rows[np.argmax(bk.depth_m[rows, k])]
        b = bk.bodies[int(bk.body[worst, k])]
        out.append(BodyBedHit(float(t_s[rows[0]]), int(rows[0]), ep.end_s, ep.pitch,
                              pitch_name(ep.pitch), b.link, b.name,
                              float(bk.depth_m[worst, k])))
    return tuple(out)


def judge_bodies(t_s: np.ndarray, bk: BodyKeys, notes, rate_hz: float,
                 verdict: bool = False) -> BodyResult:
    """The body rule's findings over rows at times ``t_s``: keys pressed, bed hits, and
    with ``notes`` the frame scores, the notes hit and the wrong presses (each with the
    links whose bodies held the key down). ``verdict``: whether they decide the check."""
    t_s = np.asarray(t_s, dtype=float)
    links = body_links(bk.bodies)
    rows = _link_rows(bk, links)
    played = key_episodes(bk.down, t_s, rows, links)
    bed = bed_hits(t_s, bk)
    if notes is None:
        return BodyResult(verdict, len(played), bed)
    score = score_song(t_s, bk.down, rows, notes, rate_hz, links)
    return BodyResult(verdict, len(played), bed, score.f1, score.precision, score.recall,
                      len(notes), len(notes) - len(score.missed), score.wrong_presses)


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
