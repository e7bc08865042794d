"""The body rule (spec section 2, "Bodies"): the keys the hand's collision bodies press.

A key is down while any collision body of the hand (``planner.hand.bodies``) reaches at
least ``DOWN_DEPTH_M`` (5 mm) below its resting top inside its footprint; so pressed
where no note of it sounds, it is a wrong note, as with a point. No body may reach more
than ``criteria.BED_MARGIN_M`` (1 mm) below the key bed (10 mm dip) inside any
footprint: ``criteria.BODY_BED_DEPTH_M``, 11 mm below its top. The fingertip point rule (``criteria.key_contacts``) is the special case of
a body of zero size; every pad point is its pad sphere's bottom, so a key down by the
point rule is down by the bodies too.

One definition: ``check``'s key-down rule (``planner.check.keys.PlayJudge``) and the
planner's self-check (``planner.selfcheck``) call the same ``body_keys``. The geometry (each body's
lowest point in each footprint, exact) is ``planner.music.keybodies``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from planner.check.criteria import DOWN_DEPTH_M, LOWEST_PITCH, pitch_name
from planner.check.kinematics import Kinematics
from planner.check.results import BodyBedHit
from planner.hand.bodies import Body, body_links, place
from planner.hand.spec import FINGERS
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


def body_names(bodies: tuple[Body, ...]) -> tuple[tuple[str, ...], np.ndarray]:
    """Who holds a key down by the body rule, by name: the fingers (``FINGERS``, a
    finger's every segment and its pad) and then each other link (palm, wrist, forearm,
    carriage) by its own name; and each body's index into those names (-1 appended: a
    row where no body holds the key)."""
    others = tuple(dict.fromkeys(b.link for b in bodies if b.finger is None))
    names = FINGERS + others
    of_body = np.array([FINGERS.index(b.finger) if b.finger is not None
                        else names.index(b.link) for b in bodies] + [-1], dtype=np.int16)
    return names, of_body


def bed_hits(runs, bodies: tuple[Body, ...]) -> tuple[BodyBedHit, ...]:
    """The runs of rows in which a body reaches past ``BODY_BED_DEPTH_M`` in a key's
    footprint (an ``EpisodeStream`` of ``BodyKeys.depth_m > BODY_BED_DEPTH_M`` tagged by
    body, valued by depth): the first row, the deepest reach and its body's link."""
    out = []
    for r in runs:
        p = r.key + LOWEST_PITCH
        b = bodies[r.best_tag]
        out.append(BodyBedHit(r.start_s, r.start_row, r.end_s, p, pitch_name(p), b.link, b.name,
                              r.best))
    return tuple(out)


def bed_problem(hits: tuple[BodyBedHit, ...]) -> list[str]:
    """The verdict's line for the bodies' key-bed hits (none: no line)."""
    if not hits:
        return []
    h = hits[0]
    line = (f"{len(hits)} body key-bed hits (first: {h.link} on {h.name} at {h.time_s:.3f} s, "
            f"{h.depth_m * 1000:.2f} mm below the top)")
    return [line]
