"""Only what can touch within a row collides: MuJoCo's collision search narrowed row by row.

MuJoCo's broad phase builds and sorts the bounding box of every collidable body at every
step (sweep and prune; docs: Computation, "Collision detection"), then filters the pairs
by ``contype``/``conaffinity``: with the 88 keys and the hand's 24 bodies, a third of a
step's time, though a hand spans a dozen keys and its forearm, wrist and carriages are
never over the keyboard. At each row the replay takes out of that search (``contype``
and ``conaffinity`` 0, on the geoms and their body, as ``NearKeys.apply`` does):

* every key whose footprint lies more than ``REACH_MARGIN_M`` along the keyboard (world
  x) from every collision shape of the hand (their bounding boxes), and
* every body of the hand whose shapes' bounding boxes, grown by ``REACH_MARGIN_M``, do
  not meet the keyboard's box (every key's, the travel to its bed included).

No contact can be lost, so the physics is the same to the bit (tests/test_simulate_speed.py):
a contact needs a hand shape to overlap a key, and a shape more than the margin away at
the row's start would have to move faster than ``REACH_MARGIN_M`` per row to close it.

``REACH_MARGIN_M``: 0.10 m per 10 ms row is 10 m/s; the hand file's fastest axes together
(the rail 3 m/s, the wrist's deviation 8 rad/s at the fingertips' ~0.2 m, a finger's
splay 20 rad/s at its ~0.1 m) make about 7 m/s. The replay measures the motion: a row over
which a shape's box moved more than half the margin (5 m/s) is counted
(``SimRecord.reach_overruns``) and fails the replay's verdict.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

REACH_MARGIN_M = 0.10  # see the module docstring: 10 m/s over a 10 ms row


@dataclass(frozen=True)
class NearKeys:
    """What the row-by-row selection reads and writes (looked up once per scene)."""

    hand_geoms: np.ndarray  # (h,) the hand's colliding geoms
    hand_half: np.ndarray  # (h, 3) their bounding boxes' half sizes, geom frame
    hand_center: np.ndarray  # (h, 3) their bounding boxes' centres, geom frame
    hand_body_of: np.ndarray  # (h,) index into hand_bodies of each geom's body
    hand_bodies: np.ndarray  # (b,) the hand's bodies with colliding geoms
    hand_body_geoms: tuple[np.ndarray, ...]  # per hand body, its colliding geoms
    hand_contype: int
    hand_conaffinity: int
    key_lo_m: np.ndarray  # (88,) each key's lowest world x (its boxes')
    key_hi_m: np.ndarray  # (88,) its highest
    board_lo_m: np.ndarray  # (3,) the keyboard's box, every key down to its bed
    board_hi_m: np.ndarray  # (3,)
    key_geoms: tuple[np.ndarray, ...]  # per key, its geoms
    key_bodies: np.ndarray  # (88,) body of each key
    key_contype: int
    key_conaffinity: int
    margin_m: float


def near_keys(model, data, key_geom_key: np.ndarray, hand_geoms: np.ndarray,
              key_travel_m: float, margin_m: float = REACH_MARGIN_M) -> NearKeys:
    """The selection for a scene whose keys are the geoms with ``key_geom_key >= 0``
    (their key's index) sliding straight down at most ``key_travel_m``, and whose hand
    collides through ``hand_geoms``; ``data``: any state of it (the keys' boxes are
    taken where they are: at rest)."""
    keys = np.flatnonzero(key_geom_key >= 0)
    n = int(key_geom_key.max()) + 1
    lo_k, hi_k = boxes(data, keys, model.geom_aabb[keys, :3], model.geom_aabb[keys, 3:])
    lo = np.full(n, np.inf)
    hi = np.full(n, -np.inf)
    np.minimum.at(lo, key_geom_key[keys], lo_k[:, 0])
    np.maximum.at(hi, key_geom_key[keys], hi_k[:, 0])
    board_lo, board_hi = lo_k.min(axis=0), hi_k.max(axis=0)
    board_lo[2] -= key_travel_m
    per_key = tuple(keys[key_geom_key[keys] == k] for k in range(n))
    bodies = np.array([int(model.geom_bodyid[g[0]]) for g in per_key])
    hand_geoms = np.asarray(hand_geoms, dtype=int)
    hand_bodies, body_of = np.unique(model.geom_bodyid[hand_geoms], return_inverse=True)
    per_body = tuple(hand_geoms[body_of == b] for b in range(len(hand_bodies)))
    g0, h0 = int(keys[0]), int(hand_geoms[0])
    return NearKeys(hand_geoms, np.array(model.geom_aabb[hand_geoms, 3:]),
                    np.array(model.geom_aabb[hand_geoms, :3]), body_of, hand_bodies, per_body,
                    int(model.geom_contype[h0]), int(model.geom_conaffinity[h0]), lo, hi,
                    board_lo, board_hi, per_key, bodies, int(model.geom_contype[g0]),
                    int(model.geom_conaffinity[g0]), margin_m)


def boxes(data, geoms: np.ndarray, center: np.ndarray, half: np.ndarray):
    """World bounding boxes (lo, hi), each (k, 3), of boxes of local ``center`` and
    ``half`` sizes carried by ``geoms`` (MuJoCo's ``geom_aabb``, in the geom's frame)."""
    R = data.geom_xmat[geoms].reshape(-1, 3, 3)
    c = data.geom_xpos[geoms] + np.einsum("kij,kj->ki", R, center)
    h = np.einsum("kij,kj->ki", np.abs(R), half)
    return c - h, c + h


@dataclass(frozen=True)
class Selection:
    """One row's selection: which keys and which hand bodies collide, and the hand's
    shapes' boxes it was made from (to measure the motion over the row)."""

    keys: np.ndarray  # (88,) bool
    bodies: np.ndarray  # (b,) bool, the hand's bodies with colliding geoms
    lo_m: np.ndarray  # (h, 3) the hand's shapes' boxes at the row's start
    hi_m: np.ndarray


def select(nk: NearKeys, data) -> Selection:
    """The keys and hand bodies that may touch within a row from this state."""
    lo, hi = boxes(data, nk.hand_geoms, nk.hand_center, nk.hand_half)
    m = nk.margin_m
    keys = (nk.key_hi_m >= lo[:, 0].min() - m) & (nk.key_lo_m <= hi[:, 0].max() + m)
    near = np.all((hi + m >= nk.board_lo_m) & (lo - m <= nk.board_hi_m), axis=1)
    bodies = np.zeros(len(nk.hand_bodies), dtype=bool)
    bodies[nk.hand_body_of[near]] = True
    return Selection(keys, bodies, lo, hi)


def moved_m(prev: Selection, now: Selection) -> float:
    """The most any side of a hand shape's box moved between two selections (m)."""
    return float(max(np.abs(now.lo_m - prev.lo_m).max(), np.abs(now.hi_m - prev.hi_m).max()))


def apply(nk: NearKeys, model, now: Selection | None, was: Selection | None) -> None:
    """Make what ``now`` selects collide and the rest not, changing only what differs
    from ``was`` (None: nothing set yet). ``now`` None: everything collides again."""
    keys = np.ones(len(nk.key_bodies), dtype=bool) if now is None else now.keys
    bodies = np.ones(len(nk.hand_bodies), dtype=bool) if now is None else now.bodies
    old_k = None if was is None else was.keys
    old_b = None if was is None else was.bodies
    for k in _changed(keys, old_k):
        on = bool(keys[k])
        _set(model, nk.key_geoms[k], int(nk.key_bodies[k]), nk.key_contype if on else 0,
             nk.key_conaffinity if on else 0)
    for b in _changed(bodies, old_b):
        on = bool(bodies[b])
        _set(model, nk.hand_body_geoms[b], int(nk.hand_bodies[b]),
             nk.hand_contype if on else 0, nk.hand_conaffinity if on else 0)


def _changed(now: np.ndarray, was: np.ndarray | None) -> np.ndarray:
    return np.arange(len(now)) if was is None else np.flatnonzero(now != was)


def _set(model, geoms: np.ndarray, body: int, contype: int, conaffinity: int) -> None:
    model.geom_contype[geoms] = contype
    model.geom_conaffinity[geoms] = conaffinity
    model.body_contype[body] = contype
    model.body_conaffinity[body] = conaffinity
