"""The follow test's answers on the rail's grid, shipped: whether a finger holding a key
follows it through a move of the arm from one place to another (``Places.follow_path_clear``:
``planner.play.follow``'s body rule on the very move the motion makes, the rail on the
``RAIL_STEP_M`` grid at both ends), for every finger, key and pair of places from which
the finger has an entry on the key and whose entries the move table lets follow
(``Places.follow_clear``: the programme asks the path of no other pair).

With several play postures it holds too, for every pair of one finger's entries on one
key in two postures met on that grid, the follow across postures: whether its path is
clear and how long it takes (``Places.follow_clear``, ``Places.follow_s``: each asked of
a pair of entries, found by forward kinematics and the arm's timing when first asked).

And whether each of those entries' press poses, with the rail there, keeps the finger's
body clear of the other keys (``Places.presses_clear``, asked of every place of a key a
finger may press: the first window's programme asks hundreds), for the fingers whose
chain ``follow.FingerChain`` carries by elementwise operations alone (the answer of a
place does not depend on the others asked with it).

The programme asks a few thousand of these a song (``ArmCosts._follow_path``), each
about 0.3 ms of forward kinematics and box tests; the table answers them by a look-up.
It holds the answers the code gives (``make_table`` asks ``follow.paths_clear_each``,
which answers as ``paths_clear``: the same moves, the same numbers), and it is used only
where it was made with the same hand, parameters and entries (``params``: the move
tables' parameters of every posture, the follow test's constants, and a digest of every
posture's base configuration and its entries' press poses). A question outside it
(another rail, another pair) is answered by forward kinematics, as without a table.

    python scripts/make_atlas.py --only follows   (or with the atlas and its move tables)
"""

from __future__ import annotations

import bisect
import hashlib
import json
import math
from pathlib import Path

import numpy as np

from planner.music import keyboard as kb
from planner.play import follow
from planner.play.armmoves import RAIL_STEP_M
from planner.play.atlas import TABLE_DIR

VERSION = 3  # the table's layout and what it answers (a table of another is not used)
_PLACE_BITS = 20  # a place's bits in a row's code (places lie within +-2^19: a few
# postures times ``PLACE_STRIDE``)


def table_path(urdf_sha256: str) -> Path:
    """Where a hand's follow table is shipped (beside its atlas and move tables)."""
    return TABLE_DIR / f"follows-{urdf_sha256[:16]}.npz"


def code(finger_i: int, pitch: int, place_a: int, place_b: int) -> int:
    """A row's key as one int: the finger's index, the key, the two places."""
    half = 1 << (_PLACE_BITS - 1)
    return ((((finger_i << 7) | pitch) << _PLACE_BITS | (place_a + half)) << _PLACE_BITS
            | (place_b + half))


def cross_code(finger_i: int, pitch_class: int, posture_a: int, k_a: int, posture_b: int,
               k_b: int) -> int:
    """A pair across postures as one int: the finger's index, the pitch class, each
    entry's posture and sample (``Atlas.entry_at``'s ``k``, within +-2^7)."""
    return ((((((finger_i << 4) | pitch_class) << 4 | posture_a) << 8 | (k_a + 128)) << 4
             | posture_b) << 8) | (k_b + 128)


def params(places) -> str:
    """What the answers depend on besides the hand's URDF (its table's name): each
    posture's move-table parameters (the atlas's, the body rule's, the follow step), the
    rail's grid, the follow test's constants, and a digest of each posture's base
    configuration and of its entries (keys and press poses)."""
    h = hashlib.sha256()
    for atlas in places.atlases:
        h.update(np.ascontiguousarray(atlas.base, dtype=float).tobytes())
        solved = atlas.solved()
        for key in sorted(solved, key=lambda k: (places.hand.fingers.index(k[0]), k[1], k[2])):
            h.update(repr(key).encode())
            h.update(np.ascontiguousarray(solved[key].press, dtype=float).tobytes())
    return json.dumps({"version": VERSION, "moves": [m.params() for m in places.moves],
                       "rail_step_m": RAIL_STEP_M, "arm": places.arm,
                       "follow": [follow.HOLD_MARGIN_M, follow.FOLLOW_STEP_M,
                                  follow.HIGH_MARGIN_M],
                       "entries": h.hexdigest()}, sort_keys=True)


class FollowTable:
    """The shipped answers of one hand (``load``; empty when none fits)."""

    def __init__(self) -> None:
        self._codes: list[int] = []
        self._answers = b""
        self._xcodes: list[int] = []  # (the pairs across postures, ``cross``)
        self._xclear = b""
        self._xs: list[float] = []
        self._pcodes: list[int] = []  # (the press poses, ``press``)
        self._pclear = b""

    def __len__(self) -> int:
        return len(self._codes)

    def load(self, path: Path, want: str) -> bool:
        """Read ``path`` if it was made with parameters ``want``; whether it was."""
        if not path.exists():
            return False
        with np.load(path, allow_pickle=False) as z:
            if str(z["params"]) != want:
                return False
            self._codes = z["code"].tolist()
            self._answers = np.unpackbits(z["answer"], count=len(self._codes)).tobytes()
            self._xcodes = z["xcode"].tolist()
            self._xclear = np.unpackbits(z["xclear"], count=len(self._xcodes)).tobytes()
            self._xs = z["xfollow_s"].tolist()  # (floats as Python's, as they were found)
            self._pcodes = z["pcode"].tolist()
            self._pclear = np.unpackbits(z["pclear"], count=len(self._pcodes)).tobytes()
        return True

    def get(self, finger_i: int, pitch: int, place_a: int, place_b: int) -> bool | None:
        """The answer of that row; None when the table has none."""
        c = code(finger_i, pitch, place_a, place_b)
        i = bisect.bisect_left(self._codes, c)
        if i < len(self._codes) and self._codes[i] == c:
            return self._answers[i] == 1
        return None


    def cross(self, finger_i: int, pitch_class: int, posture_a: int, k_a: int,
              posture_b: int, k_b: int) -> tuple[bool, float] | None:
        """The follow across postures of that pair: whether its path is clear and its
        time; None when the table has none."""
        c = cross_code(finger_i, pitch_class, posture_a, k_a, posture_b, k_b)
        i = bisect.bisect_left(self._xcodes, c)
        if i < len(self._xcodes) and self._xcodes[i] == c:
            return self._xclear[i] == 1, self._xs[i]
        return None


    def press(self, finger_i: int, pitch: int, place: int) -> bool | None:
        """Whether the finger's press pose on the key from ``place`` is clear of the
        other keys; None when the table has none."""
        c = code(finger_i, pitch, place, place)
        i = bisect.bisect_left(self._pcodes, c)
        if i < len(self._pcodes) and self._pcodes[i] == c:
            return self._pclear[i] == 1
        return None


def ends(places, finger: str, pitch: int) -> list[tuple[int, object]]:
    """The places of the rail's grid from which ``finger`` has an entry on key ``pitch``
    (within ``REACH_M`` of its natural place over it, and the rail's travel), with those
    entries: (place, entry), posture by posture."""
    hand, r = places.hand, places.rail
    lo = max(math.ceil(hand.plan_lower[r] / RAIL_STEP_M),
             math.ceil((kb.key(pitch).center_x_m - places.natural_dx[finger] - REACH_M)
                       / RAIL_STEP_M))
    hi = min(math.floor(hand.plan_upper[r] / RAIL_STEP_M),
             math.floor((kb.key(pitch).center_x_m - places.natural_dx[finger] + REACH_M)
                        / RAIL_STEP_M))
    return [(q, e) for p in range(places.postures) for i in range(lo, hi + 1)
            if (e := places.entry(finger, pitch, q := places.place(p, i))) is not None]


def domain(places, fingers=None, pitches=None) -> list[tuple[int, int, list]]:
    """The rows a table holds, by finger and key: (finger index, pitch, [(place a, entry
    a, place b, entry b), ...]) for every pair of places of the rail's travel (within
    ``Costs.rails``' 5 cm of the key) from which the finger has an entry on the key and
    whose entries may follow (``Places.follow_clear``); of ``fingers`` and ``pitches``
    only when given."""
    out = []
    for fi, f in enumerate(places.hand.fingers):
        if fingers is not None and f not in fingers:
            continue
        for pitch in kb.ALL_PITCHES if pitches is None else pitches:
            on = ends(places, f, pitch)
            pairs = [(qa, a, qb, b) for qa, a in on for qb, b in on if places.follow_clear(a, b)]
            if pairs:
                out.append((fi, pitch, pairs))
    return out


def cross_pairs(places) -> dict[int, tuple]:
    """Every pair of one finger's entries on one key in two postures that ``ends`` meets
    (by ``cross_code``): the entries."""
    out = {}
    for fi, f in enumerate(places.hand.fingers):
        for pitch in kb.ALL_PITCHES:
            on = [e for _, e in ends(places, f, pitch)]
            for a in on:
                for b in on:
                    if a.posture != b.posture:
                        out[cross_code(fi, a.pitch_class, a.posture, places.sample_of(a),
                                       b.posture, places.sample_of(b))] = (a, b)
    return out


REACH_M = 0.05  # the places of a key a table covers: this far from the finger's natural
# place over it (``Costs.rails``' span; the atlas's entries reach ``SPAN_M``, 45 mm)


def answer_pairs(places, finger_i: int, pitch: int, pairs: list) -> np.ndarray:
    """The follow test of ``domain``'s ``pairs`` of one finger and key, by forward
    kinematics (``follow.paths_clear_each``: ``Places.follow_path_clear``'s moves)."""
    QA, QB = zip(*[places.follow_ends_on_rail(a, b, places.rail_m(qa), places.rail_m(qb))
                   for qa, a, qb, b in pairs])
    return follow.paths_clear_each(places.atlas, places.hand.fingers[finger_i], pitch,
                                   np.array(QA), np.array(QB), places.arm)


def make_table(places, path: Path) -> int:
    """Find every answer of ``domain(places)`` (``follow.paths_clear_each``, key by key)
    and write the table; returns its rows."""
    places.follows = FollowTable()  # (found afresh, not read back)
    codes, answers = [], []
    for fi, pitch, pairs in domain(places):
        codes += [code(fi, pitch, qa, qb) for qa, _, qb, _ in pairs]
        answers += answer_pairs(places, fi, pitch, pairs).tolist()
    cross = cross_pairs(places)
    xcodes = sorted(cross)
    xclear = [places.follow_clear(*cross[c]) for c in xcodes]
    xs = [places.follow_s(*cross[c]) for c in xcodes]
    pcodes, pclear = [], []
    for fi, f in enumerate(places.hand.fingers):
        if not follow.finger_chain(places.atlas.bodies, f).axis_aligned:
            continue
        for pitch in kb.ALL_PITCHES:
            on = [q for q, _ in ends(places, f, pitch)]
            pcodes += [code(fi, pitch, q, q) for q in on]
            pclear += places.presses_clear(f, pitch, on)
    order = np.argsort(codes, kind="stable")
    porder = np.argsort(pcodes, kind="stable")
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(path, params=np.array(params(places)),
                        code=np.array(codes, dtype=np.int64)[order],
                        answer=np.packbits(np.array(answers, dtype=bool)[order]),
                        xcode=np.array(xcodes, dtype=np.int64),
                        xclear=np.packbits(np.array(xclear, dtype=bool)),
                        xfollow_s=np.array(xs, dtype=float),
                        pcode=np.array(pcodes, dtype=np.int64)[porder],
                        pclear=np.packbits(np.array(pclear, dtype=bool)[porder]))
    return len(codes) + len(xcodes) + len(pcodes)
