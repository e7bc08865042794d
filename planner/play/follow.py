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

from planner.hand.chain import FrameChain
from planner.music import keyboard as kb
from planner.play.atlas import PATH_SAMPLES, TIP_RADIUS_M, Atlas, AtlasEntry

HOLD_MARGIN_M = 0.001  # a key held while the arm moves stays this far inside its down range
FOLLOW_STEP_M = 0.002  # a follow is tested every 2 mm of the arm's travel: a body sphere
# (radius 6.9 mm and more, ``planner.hand.bodies``) clear at two samples 2 mm apart can
# reach past them by at most the sagitta of a 2 mm chord, 0.07 mm, inside the body
# rule's 0.5 mm tolerance for another key (``fingerbody.OTHER_KEY_TOLERANCE_M``)
HOLD_PAST_S = 0.01  # a key held through a move of the arm comes up at least this long after
# it (a frame at 100 Hz: the key is seen down in the row after the move)
PAIR_CHUNK = 256  # pairs tested at once (bounded memory)


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
    chain = bodies.tip_chain(finger)
    radii = bodies.radii(finger)
    travel = np.linalg.norm((QB - QA)[:, arm], axis=1)
    counts = np.array([samples(float(t)) for t in travel])
    out = np.zeros(len(QA), dtype=bool)
    for n_s in sorted(set(counts.tolist())):
        idx = np.flatnonzero(counts == n_s)
        S = np.linspace(0.0, 1.0, n_s)
        for lo in range(0, len(idx), PAIR_CHUNK):
            sel = idx[lo:lo + PAIR_CHUNK]
            out[sel] = _clear(atlas, chain, radii, finger, pitch, QA[sel], QB[sel], S)
    return out


def _clear(atlas: Atlas, chain: FrameChain, radii: np.ndarray, finger: str, pitch: int,
           qa: np.ndarray, qb: np.ndarray, S: np.ndarray) -> np.ndarray:
    hand, k = atlas.hand, kb.key(pitch)
    n, m = len(qa), len(S)
    Q = (qa[:, None, :] + S[None, :, None] * (qb - qa)[:, None, :]).reshape(n * m, -1)
    Q = hand.apply_couplings(Q)
    x, y, _ = chain.positions(Q).T
    inside = ((k.x_min_m + TIP_RADIUS_M <= x) & (x <= k.x_max_m - TIP_RADIUS_M)
              & (k.y_min_m + TIP_RADIUS_M <= y) & (y <= k.y_max_m - TIP_RADIUS_M))
    ok = inside.reshape(n, m).all(axis=1)
    if not ok.any():
        return ok
    rows = np.repeat(ok, m)
    clear, depth = atlas.bodies.clear_many(atlas.bodies.points_many(Q[rows], finger), radii,
                                           pitch)
    held = clear & (depth >= kb.DOWN_DEPTH_M + HOLD_MARGIN_M)
    ok[ok] = held.reshape(-1, m).all(axis=1)
    return ok
