"""A held key carried through a move of the arm: the body rule's follow test.

A finger holding a key down may stay on it while the arm moves (the rail, and the reach
axis when the move changes the play posture, ``planner.play.places``): the arm's joints
and the finger's on one straight time-optimal move, from its press pose over the key at
one place to its press pose over the same key at the other. With a ``[play]`` posture
(the atlas's body rule, spec section 2) the move is kept only when, at every sample
along it,

* the tip stays inside the key's footprint (shrunk by the pad's ``TIP_RADIUS_M``);
* the finger's body holds the key down: its deepest point inside the key's footprint
  column ``HOLD_MARGIN_M`` past the key-down depth (``check``'s body rule: a key is down
  while any body reaches 5 mm below its top there);
* its body is clear of every other key and of the key bed (``FingerBodies.clear_many``:
  the atlas's own body rule, ``planner.play.fingerbody``).

The samples are ``PATH_SAMPLES`` or more, at most ``FOLLOW_STEP_M`` of the arm's travel
apart. A hand without a ``[play]`` posture keeps the point rule (``Moves._follow``).
"""

from __future__ import annotations

import math

import numpy as np

from planner.check.criteria import BODY_BED_DEPTH_M, DOWN_DEPTH_M
from planner.music import keyboard as kb
from planner.music.keybodies import footprints
from planner.play.atlas import PATH_SAMPLES, TIP_RADIUS_M, Atlas, AtlasEntry
from planner.play.fingerbody import (
    AXIS_SAMPLES,
    MANY_CHUNK,
    OTHER_KEY_TOLERANCE_M,
    OWN_BED_MARGIN_M,
    FingerBodies,
)
from planner.play.fingerchain import FingerChain
from planner.play.halving import all_along

HOLD_MARGIN_M = 0.001  # a key held while the arm moves stays this far inside its down range
FOLLOW_STEP_M = 0.002  # a follow is tested every 2 mm of the arm's travel: a body sphere
# (radius 6.9 mm and more, ``planner.hand.bodies``) clear at two samples 2 mm apart can
# reach past them by at most the sagitta of a 2 mm chord, 0.07 mm, inside the body
# rule's 0.5 mm tolerance for another key (``fingerbody.OTHER_KEY_TOLERANCE_M``)
HOLD_PAST_S = 0.01  # a key held through a move of the arm comes up at least this long after
# it (a frame at 100 Hz: the key is seen down in the row after the move)
PAIR_CHUNK = 256  # pairs tested at once (bounded memory)
HIGH_MARGIN_M = 0.001  # a body point this far above every key's top reaches no key
# (``low_points``): 1 mm, far past the rounding of the distances measured (1e-16 m),
# within the 2-3 mm of any rule's threshold (0.5 mm tolerance, 5 mm down, 6 mm held)


def canonical_pitch(e: AtlasEntry) -> int:
    """The key an entry is solved on (``atlas.CANON_OCTAVE``: C4 .. B4)."""
    return 60 + e.pitch_class


def follow_ends(atlas_a: Atlas, atlas_b: Atlas, a: AtlasEntry, b: AtlasEntry
                ) -> tuple[np.ndarray, np.ndarray]:
    """The whole hand at the follow's ends (independent joints): each posture's natural
    hand, its rail at the key's centre less the entry's ``dx``, the finger pressing."""
    x = kb.key(canonical_pitch(a)).center_x_m
    js = atlas_a.hand.joint_slice(a.finger)
    qa, qb = atlas_a.base.copy(), atlas_b.base.copy()
    if atlas_a.rail is not None:
        qa[atlas_a.rail], qb[atlas_a.rail] = x - a.dx_m, x - b.dx_m
    qa[js], qb[js] = a.press, b.press
    return qa, qb


def samples(travel_m: float) -> int:
    """How many points along a follow whose arm travels ``travel_m`` are tested."""
    return max(PATH_SAMPLES, math.ceil(travel_m / FOLLOW_STEP_M) + 1)


def paths_clear(atlas: Atlas, finger: str, pitch: int, QA: np.ndarray, QB: np.ndarray,
                arm: list[int]) -> np.ndarray:
    """Whether each straight move ``QA[i]`` -> ``QB[i]`` (whole hands, independent joints)
    passes the body rule's follow test on key ``pitch`` (the module docstring); ``arm``:
    the arm's joints (their travel sets the samples). (N,) bool."""
    bodies = atlas.bodies
    chain = finger_chain(bodies, finger)
    radii = bodies.radii(finger)
    d = (QB - QA)[:, arm]  # (the arm's travel, ``np.linalg.norm``'s: one or two joints'
    d *= d  # squares, their sum exact in any order)
    travel = np.sqrt(d[:, 0] + d[:, 1] if len(arm) == 2 else d.sum(axis=1))
    counts = [samples(float(t)) for t in travel]
    if len(counts) == 1:  # (one move: the programme's and the motion's question, asked
        # again by the motion of a move the programme asked: the answer of the same
        # numbers, ``ANSWERS`` of them kept per hand)
        memo = _answers(atlas)
        key = (finger, pitch, QA.tobytes(), QB.tobytes(), tuple(arm))
        got = memo.get(key)
        if got is None:
            if len(memo) >= ANSWERS:
                memo.clear()
            got = memo[key] = bool(_clear(atlas, chain, radii, pitch, QA, QB,
                                          _fractions(counts[0]))[0])
        return np.array([got])
    counts = np.array(counts)
    out = np.zeros(len(QA), dtype=bool)
    for n_s in sorted(set(counts.tolist())):
        idx = np.flatnonzero(counts == n_s)
        S = _fractions(n_s)
        for lo in range(0, len(idx), PAIR_CHUNK):
            sel = idx[lo:lo + PAIR_CHUNK]
            out[sel] = _clear(atlas, chain, radii, pitch, QA[sel], QB[sel], S)
    return out


def paths_clear_each(atlas: Atlas, finger: str, pitch: int, QA: np.ndarray, QB: np.ndarray,
                     arm: list[int]) -> np.ndarray:
    """``paths_clear`` of each move ``QA[i]`` -> ``QB[i]`` asked alone, (N,) bool, in one
    pass over every move's samples (each its own count: one stacked array, not one
    numpy call per move); each answer kept as ``paths_clear``'s one-move answer, which
    the motion asks again. A chain whose joints are not coordinate axes (its matrix
    products are BLAS calls whose rounding may depend on the array's shape) asks move by
    move. Every number of a move's samples is an elementwise operation on its own
    configuration (``FingerChain._carried``), and ``held_stacked``'s answer for one
    configuration does not depend on the others measured with it (``low_points``, the
    boxes and columns near: ``held_all``), so the answers are ``paths_clear``'s."""
    chain = finger_chain(atlas.bodies, finger)
    if not chain.axis_aligned:
        return np.array([bool(paths_clear(atlas, finger, pitch, QA[i:i + 1], QB[i:i + 1], arm)[0])
                         for i in range(len(QA))], dtype=bool)
    memo, arm_t = _answers(atlas), tuple(arm)
    keys = [(finger, pitch, QA[i].tobytes(), QB[i].tobytes(), arm_t) for i in range(len(QA))]
    out = np.array([bool(memo.get(k, False)) for k in keys], dtype=bool)
    todo = [i for i, k in enumerate(keys) if k not in memo]
    if todo:
        d = (QB[todo] - QA[todo])[:, arm]  # (``paths_clear``'s travel, operation by operation)
        d *= d
        travel = np.sqrt(d[:, 0] + d[:, 1] if len(arm) == 2 else d.sum(axis=1))
        got = _clear_each(atlas, chain, atlas.bodies.radii(finger), pitch, QA[todo], QB[todo],
                          [samples(float(t)) for t in travel])
        if len(memo) + len(todo) > ANSWERS:
            memo.clear()
        for i, g in zip(todo, got.tolist()):
            out[i] = memo[keys[i]] = g
    return out


def _clear_each(atlas: Atlas, chain: FingerChain, radii: np.ndarray, pitch: int,
                qa: np.ndarray, qb: np.ndarray, counts: list[int]) -> np.ndarray:
    """``_clear`` of each move with its own count of samples (``counts``), all moves'
    samples one array: ``qa + s (qb - qa)``, the tip test and ``held_stacked`` per
    configuration, each move's answers joined by ``np.logical_and.reduceat``."""
    hand, k = atlas.hand, kb.key(pitch)
    S = np.concatenate([_fractions(c) for c in counts])
    move = np.repeat(np.arange(len(qa)), counts)
    starts = np.cumsum([0, *counts[:-1]])
    Q = qa[move] + S[:, None] * (qb - qa)[move]
    tips, C = chain.carry_stacked(hand.apply_couplings(Q))
    x, y = tips[:, 0], tips[:, 1]
    inside = ((k.x_min_m + TIP_RADIUS_M <= x) & (x <= k.x_max_m - TIP_RADIUS_M)
              & (k.y_min_m + TIP_RADIUS_M <= y) & (y <= k.y_max_m - TIP_RADIUS_M))
    ok = np.logical_and.reduceat(inside, starts)
    if not ok.any():
        return ok
    held = np.zeros(len(S), dtype=bool)
    rows = np.flatnonzero(ok[move])  # (the samples of the moves whose tip stays inside)
    C = C[:, :, rows]
    held[rows] = np.concatenate([held_stacked(atlas.bodies, C[:, :, lo:lo + MANY_CHUNK], radii,
                                              pitch) for lo in range(0, C.shape[2], MANY_CHUNK)])
    return ok & np.logical_and.reduceat(held, starts)


ANSWERS = 50_000  # one-move answers kept (``paths_clear``; about 0.6 kB each: a song
# asks 1,000-3,500 moves, a few per cent of them twice)
_ANSWERS: dict[tuple[int, int], tuple] = {}  # (``_answers``)


def _answers(atlas: Atlas) -> dict:
    """The one-move answers of ``atlas``' hand and bodies (``paths_clear``)."""
    key = (id(atlas.hand), id(atlas.bodies))
    got = _ANSWERS.get(key)
    if got is None or got[0] is not atlas.hand or got[1] is not atlas.bodies:
        got = _ANSWERS[key] = (atlas.hand, atlas.bodies, {})
    return got[2]


_FRACTIONS: dict[int, np.ndarray] = {}  # (``_fractions``)


def _fractions(n_s: int) -> np.ndarray:
    """``n_s`` points from 0 to 1 (``np.linspace``; made once per count, read-only)."""
    got = _FRACTIONS.get(n_s)
    if got is None:
        got = _FRACTIONS[n_s] = np.linspace(0.0, 1.0, n_s)
        got.flags.writeable = False
    return got


_CHAINS: dict[tuple[int, str], tuple[FingerBodies, FingerChain]] = {}  # (``finger_chain``)


def finger_chain(bodies: FingerBodies, finger: str) -> FingerChain:
    """The finger's ``FingerChain`` over ``bodies``' shapes (made once per hand)."""
    got = _CHAINS.get((id(bodies), finger))
    if got is None or got[0] is not bodies:
        got = _CHAINS[(id(bodies), finger)] = (bodies, FingerChain(
            bodies.hand, bodies.shapes[finger], finger, AXIS_SAMPLES))
    return got[1]


def _clear(atlas: Atlas, chain: FingerChain, radii: np.ndarray, pitch: int,
           qa: np.ndarray, qb: np.ndarray, S: np.ndarray) -> np.ndarray:
    hand, k = atlas.hand, kb.key(pitch)
    n, m = len(qa), len(S)
    Q = (qa[:, None, :] + S[None, :, None] * (qb - qa)[:, None, :]).reshape(n * m, -1)
    tips, C = chain.carry_stacked(hand.apply_couplings(Q))
    x, y = tips[:, 0], tips[:, 1]
    inside = ((k.x_min_m + TIP_RADIUS_M <= x) & (x <= k.x_max_m - TIP_RADIUS_M)
              & (k.y_min_m + TIP_RADIUS_M <= y) & (y <= k.y_max_m - TIP_RADIUS_M))
    ok = inside.reshape(n, m).all(axis=1)
    if not ok.any():
        return ok
    if not ok.all():
        C = C[:, :, np.repeat(ok, m)]
    held = np.concatenate([held_stacked(atlas.bodies, C[:, :, lo:lo + MANY_CHUNK], radii, pitch)
                           for lo in range(0, C.shape[2], MANY_CHUNK)])
    ok[ok] = held.reshape(-1, m).all(axis=1)
    return ok


def held_clear(bodies: FingerBodies, P: np.ndarray, r: np.ndarray, pitch: int) -> np.ndarray:
    """Whether each configuration's sphere-swept points ``P`` (K, m, 3), radii ``r``
    (m,), are clear of every key but ``pitch`` and of its bed and hold ``pitch`` down
    (``HOLD_MARGIN_M`` past the key-down depth in its footprint column): the booleans of
    ``FingerBodies.clear_many`` and its own-key depth, from the same numbers (the same
    boxes' penetrations, ``FingerBodies.boxes_clear``'s; every footprint column's depth
    in one array, not key by key: ``keybodies.key_depths``' elementwise arithmetic, its
    reductions exact), (K,) bool.

    The points are one array (coordinates, points, K), and every array made from it is
    (coordinates, points, boxes or columns, K): the same elementwise operations on the
    same numbers as ``boxes_clear``'s (K, points, boxes, 3) arrays, whose last axis of 2
    or 3 made numpy loop over a few elements at a time (an elementwise operation's
    result does not depend on the array's layout; a maximum, a minimum and a logical
    and are exact in any order)."""
    return held_stacked(bodies, np.ascontiguousarray(P.transpose(2, 1, 0)), r, pitch)


def held_coords(bodies: FingerBodies, X: np.ndarray, Y: np.ndarray, Z: np.ndarray,
                r: np.ndarray, pitch: int) -> np.ndarray:
    """``held_clear`` of points whose coordinates are ``X``, ``Y``, ``Z`` (m, K each):
    (K,) bool (``held_stacked``)."""
    return held_stacked(bodies, np.stack((X, Y, Z)), r, pitch)


def held_stacked(bodies: FingerBodies, C: np.ndarray, r: np.ndarray, pitch: int
                 ) -> np.ndarray:
    """``held_clear`` of points whose coordinates are ``C`` (3, m, K): (K,) bool;
    ``held_all``'s answer from the points low enough to matter (``low_points``: two
    thirds of a finger's points are far above every key)."""
    keep = low_points(bodies, C[2], r, pitch)
    if keep is None:
        return held_all(bodies, C, r, pitch)
    if not keep.any():  # (no point reaches down to a key top: none holds the key)
        return np.zeros(C.shape[2], dtype=bool)
    return held_all(bodies, C[:, keep], r[keep], pitch)


def low_points(bodies: FingerBodies, Z: np.ndarray, r: np.ndarray, pitch: int
               ) -> np.ndarray | None:
    """Which points (rows of ``Z``, (m, K); radii ``r``) come within ``HIGH_MARGIN_M``
    of the highest top of the boxes and footprint columns ``held_all`` measures, in any
    configuration; None when all do. A point that stays above that, its sphere's lowest
    point more than ``HIGH_MARGIN_M`` over every top, changes none of its answers: its
    penetration of any box is below -1 mm (every allowance is >= 0), its depth in any
    column below -1 mm (the rules ask depths against 5, 6 and 11 mm), and a column's
    depth it does not set stays below 0 or is the same number."""
    ceiling = _boxes(bodies, pitch)[3]
    keep = (Z.min(axis=1) - r) <= ceiling
    return None if keep.all() else keep


def held_coords_all(bodies: FingerBodies, X: np.ndarray, Y: np.ndarray, Z: np.ndarray,
                    r: np.ndarray, pitch: int) -> np.ndarray:
    """``held_all`` of points whose coordinates are ``X``, ``Y``, ``Z`` (m, K each)."""
    return held_all(bodies, np.stack((X, Y, Z)), r, pitch)


def held_all(bodies: FingerBodies, C: np.ndarray, r: np.ndarray, pitch: int) -> np.ndarray:
    """``held_clear`` of points whose coordinates are ``C`` (3, m, K), every point
    measured: (K,) bool. (Its reductions are numpy's along the first axis, over rows of
    many numbers (boxes or columns times configurations): exact, as any order of a
    minimum, a maximum or a logical and, and there twice as fast as
    ``planner.play.halving``'s, which wins where the rows are two or three numbers.)"""
    # (``boxes_clear``: the points' bounds grown by the largest radius and the tolerance,
    # the boxes near them, each one's deepest penetration within its allowance)
    reach = float(r.max()) + OTHER_KEY_TOLERANCE_M
    p_lo = C.min(axis=(1, 2)) - reach
    p_hi = C.max(axis=(1, 2)) + reach
    lo, hi, allowed, _ = _boxes(bodies, pitch)
    near = all_along((lo <= p_hi) & (hi >= p_lo), 1)
    ok = (box_penetration_stacked(C, r, lo[near], hi[near]) <= allowed[near, None]).all(axis=0)
    fp, (not_mine, own_lo, own_hi, own_top, lo_grown, hi_grown) = footprints(), _columns(pitch)
    near = (fp.lo <= p_hi[:2]) & (fp.hi >= p_lo[:2])
    other = near[:, 0] & near[:, 1] & not_mine
    # (the other keys' footprints near, grown by the tolerance; the key's own as they are)
    cols_lo = np.concatenate([lo_grown[other], own_lo])
    cols_hi = np.concatenate([hi_grown[other], own_hi])
    top = np.concatenate([fp.top_m[other], own_top])
    dxy = _outside(C[:2], cols_lo, cols_hi)  # (2, m, columns, K)
    d = np.sqrt(dxy[0] + dxy[1])
    r2 = (r * r)[:, None, None] - d * d
    low = np.where(r2 >= 0.0, C[2][:, None, :] - np.sqrt(np.maximum(r2, 0.0)), np.inf)
    depth = top[:, None] + -low.min(axis=0)  # (columns, K)
    n_other = len(cols_lo) - len(own_lo)
    if n_other:
        ok &= (depth[:n_other] < DOWN_DEPTH_M).all(axis=0)
    own_depth = depth[n_other:].max(axis=0)
    return ok & (own_depth <= BODY_BED_DEPTH_M) & (own_depth >= kb.DOWN_DEPTH_M + HOLD_MARGIN_M)


def _outside(C: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """How far each point's coordinates ``C`` (c, m, K) are outside each box [lo, hi]
    (B, c or more: its first c), squared, coordinate by coordinate: (c, m, B, K),
    ``max(lo - w, w - hi, 0)`` squared."""
    c = len(C)
    W = C[:, :, None, :]
    lo_, hi_ = lo[:, :c].T[:, None, :, None], hi[:, :c].T[:, None, :, None]
    d = np.maximum(np.maximum(lo_ - W, W - hi_), 0.0)
    d *= d
    return d


def box_penetration(X: np.ndarray, Y: np.ndarray, Z: np.ndarray, r: np.ndarray,
                    lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """``fingerbody.many_box_penetration`` of points whose coordinates are ``X``, ``Y``,
    ``Z`` (m, K each), radii ``r`` (m,), boxes [lo, hi] (B, 3): (B, K), the same numbers
    (``box_penetration_stacked``)."""
    return box_penetration_stacked(np.stack((X, Y, Z)), r, lo, hi)


def box_penetration_stacked(C: np.ndarray, r: np.ndarray, lo: np.ndarray, hi: np.ndarray
                            ) -> np.ndarray:
    """``box_penetration`` of points whose coordinates are ``C`` (3, m, K): (B, K), its
    sum of three squares in ``many_box_penetration``'s order, (x + y) + z, its maximum
    exact."""
    d = _outside(C, lo, hi)
    dd = d[0] + d[1]
    dd += d[2]
    return (r[:, None, None] - np.sqrt(dd)).max(axis=0)


_BOXES: dict[tuple[int, int | None], tuple] = {}  # (``_boxes``)


def _boxes(bodies: FingerBodies, pitch: int | None) -> tuple[np.ndarray, ...]:
    """The keys' boxes with key ``pitch`` pressed (``FingerBodies.pressed_boxes``: lo,
    hi), each one's allowed penetration (``FingerBodies.boxes_clear``'s: the pressed
    key's ``OWN_BED_MARGIN_M``, another's ``OTHER_KEY_TOLERANCE_M``) and ``low_points``'
    ceiling (the highest top of a box or a footprint column, ``HIGH_MARGIN_M`` over it),
    once per key."""
    key = (id(bodies), pitch)
    got = _BOXES.get(key)
    if got is None or got[0] is not bodies:
        own, lo, hi = bodies.pressed_boxes(pitch)
        ceiling = max(float(hi[:, 2].max()), float(footprints().top_m.max())) + HIGH_MARGIN_M
        got = _BOXES[key] = (bodies, lo, hi, np.where(own, OWN_BED_MARGIN_M,
                                                      OTHER_KEY_TOLERANCE_M), ceiling)
    return got[1:]


_COLUMNS: dict[int, tuple[np.ndarray, ...]] = {}  # (``_columns``)


def _columns(pitch: int) -> tuple[np.ndarray, ...]:
    """The footprint columns ``held_clear`` measures for key ``pitch`` (made once per
    key): which rectangles are another key's, the key's own rectangles (lo, hi, top) as
    they are, and every rectangle grown by ``OTHER_KEY_TOLERANCE_M`` (lo, hi)."""
    got = _COLUMNS.get(pitch)
    if got is None:
        fp = footprints()
        mine = fp.key == pitch - kb.LOWEST_PITCH
        got = _COLUMNS[pitch] = (~mine, fp.lo[mine] - 0.0, fp.hi[mine] + 0.0, fp.top_m[mine],
                                 fp.lo - OTHER_KEY_TOLERANCE_M, fp.hi + OTHER_KEY_TOLERANCE_M)
    return got
