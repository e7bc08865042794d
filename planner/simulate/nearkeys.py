"""Only the keys the hand can reach within a row collide: MuJoCo's collision search
narrowed row by row.

MuJoCo's broad phase builds and sorts the bounding box of every collidable body at every
step (sweep and prune; docs: Computation, "Collision detection") before it filters the
pairs by ``contype``/``conaffinity``: with the 88 keys, a quarter of a step's work,
though a hand spans a dozen keys. At each row the replay takes out of that search every
key whose footprint lies more than ``REACH_MARGIN_M`` along the keyboard (world x) from
the hand's collision shapes (``hand_half_x_m``: their x half-extent about their centre in
any pose): the key's geoms and its body get ``contype`` and ``conaffinity`` 0
(``apply``).

No contact can be lost, so the physics is the same to the bit (tests/test_simulate_speed.py):
a contact needs a hand shape to overlap a key, and a key more than the margin from the
hand's span at the row's start is out of reach unless the hand moves faster than
``REACH_MARGIN_M`` per row. ``REACH_MARGIN_M``: 0.10 m per 10 ms row is 10 m/s; the hand
file's fastest axes together (the rail 3 m/s, the wrist's deviation 8 rad/s at the
fingertips' ~0.2 m, a finger's splay 20 rad/s at its ~0.1 m) make about 7 m/s. The
replay measures the motion: a row over whose 10 ms the hand's span moved more than half
the margin (5 m/s) is counted (``SimRecord.reach_overruns``) and fails the replay's
verdict.
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass

import numpy as np

REACH_MARGIN_M = 0.10  # see the module docstring: 10 m/s over a 10 ms row


@dataclass(frozen=True)
class NearKeys:
    """What the row-by-row selection reads and writes (looked up once per scene)."""

    hand_geoms: np.ndarray  # (h,) the hand's colliding geoms
    hand_half_x_m: np.ndarray  # (h,) their x half-extent about geom_xpos (hand_half_x_m)
    key_lo_m: list[float]  # (88,) each key's lowest world x (its boxes'), rising with pitch
    key_hi_m: list[float]  # (88,) its highest, rising with pitch
    key_geoms: tuple[np.ndarray, ...]  # per key, its geoms
    key_bodies: np.ndarray  # (88,) body of each key
    contype: int  # the keys' own
    conaffinity: int
    margin_m: float


def near_keys(model, data, key_geom_key: np.ndarray, hand_geoms: np.ndarray,
              margin_m: float | None = None) -> NearKeys:
    """The selection for a scene whose keys are the geoms with ``key_geom_key >= 0``
    (their key's index, keys in pitch order) and whose hand collides through
    ``hand_geoms``; ``data``: any state of it (a key slides straight down: its x-extent
    is where its boxes are). ``margin_m``: ``REACH_MARGIN_M`` unless given."""
    margin_m = REACH_MARGIN_M if margin_m is None else margin_m
    keys = np.flatnonzero(key_geom_key >= 0)
    n = int(key_geom_key.max()) + 1
    R = data.geom_xmat[keys].reshape(-1, 3, 3)
    cx = data.geom_xpos[keys, 0] + np.einsum("kj,kj->k", R[:, 0], model.geom_aabb[keys, :3])
    hx = np.einsum("kj,kj->k", np.abs(R[:, 0]), model.geom_aabb[keys, 3:])
    lo = np.full(n, np.inf)
    hi = np.full(n, -np.inf)
    np.minimum.at(lo, key_geom_key[keys], cx - hx)
    np.maximum.at(hi, key_geom_key[keys], cx + hx)
    if np.any(np.diff(lo) < 0) or np.any(np.diff(hi) < 0):
        raise ValueError("the keys' x-extents must rise with pitch")
    per_key = tuple(keys[key_geom_key[keys] == k] for k in range(n))
    g0 = int(keys[0])
    hand_geoms = np.asarray(hand_geoms, dtype=int)
    return NearKeys(hand_geoms, hand_half_x_m(model, data, hand_geoms),
                    [float(v) for v in lo], [float(v) for v in hi], per_key,
                    np.array([int(model.geom_bodyid[g[0]]) for g in per_key]),
                    int(model.geom_contype[g0]), int(model.geom_conaffinity[g0]), margin_m)


def hand_half_x_m(model, data, geoms: np.ndarray) -> np.ndarray:
    """(h,) how far each geom reaches along world x from its centre, in every pose: a
    geom that only slides (no hinge between it and the world: the carriages, the
    forearm) keeps its orientation, so its bounding box's x half-extent; any other its
    bounding sphere's radius (``geom_rbound``)."""
    import mujoco

    slide = int(mujoco.mjtJoint.mjJNT_SLIDE)
    out = np.array(model.geom_rbound[geoms], dtype=float)
    for i, g in enumerate(geoms):
        b, turns = int(model.geom_bodyid[g]), False
        while b > 0:
            adr, num = int(model.body_jntadr[b]), int(model.body_jntnum[b])
            turns |= any(int(model.jnt_type[j]) != slide for j in range(adr, adr + num))
            b = int(model.body_parentid[b])
        if not turns:
            R = data.geom_xmat[g].reshape(3, 3)
            aabb = model.geom_aabb[g]
            out[i] = float(abs(R[0] @ aabb[:3]) + np.abs(R[0]) @ aabb[3:])
    return out


def hand_span_m(nk: NearKeys, data) -> tuple[float, float]:
    """The hand's collision shapes' extent along world x (m)."""
    x = data.geom_xpos[nk.hand_geoms, 0]
    return float((x - nk.hand_half_x_m).min()), float((x + nk.hand_half_x_m).max())


def reachable(nk: NearKeys, span: tuple[float, float]) -> tuple[int, int]:
    """The keys ``[first, end)`` within ``margin_m`` of the hand's ``span`` along x."""
    first = bisect.bisect_left(nk.key_hi_m, span[0] - nk.margin_m)
    end = bisect.bisect_right(nk.key_lo_m, span[1] + nk.margin_m)
    return first, max(first, end)


def moved_m(prev: tuple[float, float], now: tuple[float, float]) -> float:
    """How far either end of the hand's span moved between two rows (m)."""
    return max(abs(now[0] - prev[0]), abs(now[1] - prev[1]))


def apply(nk: NearKeys, model, now: tuple[int, int] | None,
          was: tuple[int, int] | None) -> None:
    """Make the keys ``now`` (``[first, end)``; None: all of them) collide and the others
    not, changing only the keys whose state differs from ``was`` (None: not set yet,
    every key colliding as built)."""
    n = len(nk.key_bodies)
    a0, a1 = (0, n) if now is None else now
    b0, b1 = (0, n) if was is None else was
    if (a0, a1) == (b0, b1):
        return
    for k in range(min(a0, b0), max(a1, b1)):
        on, on_before = a0 <= k < a1, b0 <= k < b1
        if on != on_before:
            ct, ca = (nk.contype, nk.conaffinity) if on else (0, 0)
            model.geom_contype[nk.key_geoms[k]] = ct
            model.geom_conaffinity[nk.key_geoms[k]] = ca
            model.body_contype[nk.key_bodies[k]] = ct
            model.body_conaffinity[nk.key_bodies[k]] = ca
