"""What ``planner.play.moves`` finds by forward kinematics, for every atlas entry and pair
of entries, found once per hand and shipped beside the atlas
(``planner/tables/moves-<URDF hash>.npz``, written by ``scripts/make_atlas.py``):

* the key crossings of every entry's descents (from high, hover, rise) and lifts (to
  the same), ``Moves._cross``;
* how much slower than its joints allow each of an entry's moves runs within the
  tendons' capacity (``Moves.entry_scale``, ``planner.play.tendonload``);
* the moments an entry's lift to crossing height, its rise from the waiting pose and
  its descent from crossing height pass the height that clears every key, by the front
  rule and by the black rule alone (``planner.play.highclear``, with that module's
  parameters beside them);
* for every pair of one finger's entries, whether its move across at crossing height
  is clear of the keys (``Moves.across``);
* for every pair of one finger's entries on one key (two places relative to the rail),
  whether the finger can hold the key down while the rail carries it from one to the
  other (``Moves.follow``);
* across play postures (a hand with several, ``planner.play.places``): for every pair of
  one finger's entries, one of another posture (``a``) and one of the table's own
  (``b``), whether its move across at crossing height is clear (the arm in ``b``'s
  posture, ``Places.move_gap_s``), the other postures' entries in their own tables'
  order (their keys kept beside, the matrix used only where they match); and the arm's
  move to each later posture at every step of the rail (``Places.arm_time_s``). (A
  finger holding its key from another posture's entry, ``Places.follow_clear``, is not
  here: the body rule's follow test of every such pair would take about half an hour
  a hand on two cores, measured on one key's 65 x 65 pairs, 16 s.)
* for a hand whose tendon bound has its sufficient test (``planner.play.tendonproof``):
  each finger's box of high poses and its bound (``TendonProof.box_gain``), and in
  posture 0's table each finger's cells over its hull of high poses in every posture
  (``TendonProof.hull_cells``), with the test's parameters (``proof_params``: a table
  made with others, or for another box, is not read for them).

A planner that meets a hand without a table finds each of these when first needed
(about 4 000 pairs a song, most of a cold plan's time: ``docs/history/play-second-design.md``).
The pair tests are the very tests of ``Moves`` on the very samples, evaluated for all
pairs at once with ``planner.hand.chain.FrameChain`` (the same rigid transforms as
Pinocchio's, to 2e-16 m); ``tests/test_play_moves.py`` checks them against
``Moves``' own forward kinematics. A table made with other parameters is not used.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from planner.hand.chain import FrameChain
from planner.ik import surfaces_under
from planner.music import keyboard as kb
from planner.play.atlas import (
    CLEARANCE_M,
    PATH_SAMPLES,
    STEP_M,
    TABLE_DIR,
    TIP_RADIUS_M,
    AtlasEntry,
)
from planner.play.follow import HOLD_MARGIN_M, paths_clear
from planner.play.tendonproof import BoxGain

ENDS = ("high", "hover", "rise")  # the poses a descent starts from and a lift ends at
# the move tests' parameters (``Moves`` and its table test the same):
HIGH_SAFE_Z_M = kb.BLACK_TOP_Z_M + CLEARANCE_M + TIP_RADIUS_M  # a tip this high clears every key
ACROSS_SAMPLES = (0.25, 0.5, 0.75)  # a move across at crossing height is checked here: both
# ends are at HIGH_Z_M, 4.5 mm above HIGH_SAFE_Z_M, and the tip's height along a straight
# joint-space move is smooth, lowest near its middle (the rows' replay checks every row)
# an entry's repeat as ``Moves.repeat_found`` finds it (NaN but the gap: no repeat)
REPEAT_COLUMNS = ("sigma", "s_c", "scale", "cross_s", "gap_s")
_BATCH = 60000  # configurations evaluated at once while the table is made


def table_path(urdf_sha256: str, posture: int = 0) -> Path:
    """Where the move table of a hand's atlas (of play posture ``posture``) is shipped
    (beside the atlas)."""
    return TABLE_DIR / f"moves-{urdf_sha256[:16]}{f'-p{posture}' if posture else ''}.npz"


class MoveTable:
    """The shipped answers (empty when there is no table for the hand, or it was made
    with other parameters); ``None`` from a lookup: not in the table."""

    def __init__(self, fingers: tuple[str, ...], natural_dx: dict[str, float],
                 posture: int = 0) -> None:
        self.fingers = fingers
        self.natural_dx = natural_dx
        self.posture = posture  # (the atlas's play posture: another's entries are not here)
        self.crossings: dict[tuple[str, int, int], np.ndarray] = {}
        self.scales: dict[tuple[str, int, int], np.ndarray] = {}  # (``SCALE_PAIRS``' order)
        # (``HighClear``'s moments, ``CLEAR_MOVES``' order, and the parameters they were
        # found with)
        self.clears: dict[tuple[str, int, int], list[float]] = {}
        self.clear_params: str | None = None
        self._index: dict[tuple[str, int, int], tuple[int, int]] = {}  # in finger, in key
        self._across: dict[str, np.ndarray] = {}
        self._follow: dict[tuple[str, int], np.ndarray] = {}
        self._keys: dict[int, tuple] = {}  # (entry, its ``key``) by the entry's id
        self.keys: list[tuple[str, int, int]] = []  # (the entries' keys, the table's order)
        # (across postures, by the other posture: its entries' keys, their places, and
        # the matrices by finger)
        self.cross_keys: dict[int, list[tuple[str, int, int]]] = {}
        self._x_index: dict[int, dict[tuple[str, int, int], tuple[int, int]]] = {}
        self._x_across: dict[tuple[str, int], np.ndarray] = {}
        # (the arm's moves to another posture: by it, the rail's steps of the first
        # duration and the durations, step by step: ``Places.arm_time_s``)
        self._x_arm: dict[int, tuple[int, list[float]]] = {}
        # (the tendon proof's gain of each finger's box of high poses, by finger: the box
        # and its gain, and the parameters they were made with)
        self.proofs: dict[str, tuple[np.ndarray, np.ndarray, BoxGain]] = {}
        self.proof_params: str | None = None
        # (and each finger's cells over its hull of high poses in every posture:
        # ``TendonProof.hull_cells``, in posture 0's table)
        self.proof_cells: dict[str, tuple[np.ndarray, np.ndarray, BoxGain]] = {}
        # (each entry's repeat, ``REPEAT_COLUMNS``, and the parameters it was found with)
        self.repeats: dict[tuple[str, int, int], tuple[float, ...]] = {}
        self.repeat_params: str | None = None

    def key(self, e: AtlasEntry) -> tuple[str, int, int]:
        got = self._keys.get(id(e))  # (by the entry, held: its id is not reused)
        if got is None or got[0] is not e:
            k = (e.finger, e.pitch_class, round((e.dx_m - self.natural_dx[e.finger]) / STEP_M))
            # (an entry of another posture: a key the table never holds)
            got = self._keys[id(e)] = (e, k if e.posture == self.posture else (*k, e.posture))
        return got[1]

    def crossing(self, e: AtlasEntry, column: int) -> float | None:
        row = self.crossings.get(self.key(e))
        return None if row is None else float(row[column])

    def clear_s(self, e: AtlasEntry, column: int, params: str) -> float | None:
        """``HighClear``'s moment of the entry's move ``column`` (``highclear.column``),
        None when the table was made with other ``params`` of its search or lacks it."""
        if params != self.clear_params:
            return None
        row = self.clears.get(self.key(e))
        return None if row is None else row[column]

    def repeat_row(self, e: AtlasEntry, params: str) -> tuple[float, ...] | None:
        """The entry's repeat (``REPEAT_COLUMNS``), None when the table was made with
        other ``params`` (``moves.REPEAT_PARAMS``) or lacks it."""
        return None if params != self.repeat_params else self.repeats.get(self.key(e))

    def tendon_scale(self, e: AtlasEntry, column: int) -> float | None:
        row = self.scales.get(self.key(e))
        return None if row is None else float(row[column])

    def across_clear(self, a: AtlasEntry, b: AtlasEntry) -> bool | None:
        if a.posture != self.posture:  # (from another posture's entry: ``cross_pair``)
            got = self._cross_pair(a, b)
            m = None if got is None else self._x_across.get((a.finger, a.posture))
            return None if m is None else bool(m[got[0][0], got[1][0]])
        ia, ib = self._index.get(self.key(a)), self._index.get(self.key(b))
        if ia is None or ib is None or a.finger not in self._across:
            return None
        return bool(self._across[a.finger][ia[0], ib[0]])

    def as_bytes(self) -> tuple[dict, dict]:
        """``across_clear`` of every finger's pairs and ``follow_clear`` of every finger's
        pairs on one key, as bytes (1: clear) with their row length: pair (i, j) at
        ``i * n + j`` by the entries' places (``index``), read without numpy by the
        programme's many questions."""
        return ({f: (m.tobytes(), len(m)) for f, m in self._across.items()},
                {k: (m.tobytes(), len(m)) for k, m in self._follow.items()})

    def index(self, e: AtlasEntry) -> tuple[int, int] | None:
        """The entry's places among its finger's entries and among its finger's on its
        key (None: not in the table)."""
        return self._index.get(self.key(e))

    def arm_s(self, other: int, steps: int) -> float | None:
        """The arm's move from this posture at rail 0 to posture ``other`` at ``steps`` of
        the rail (``Places.arm_move``'s duration; None: not in the table)."""
        got = self._x_arm.get(other)
        if got is None or not 0 <= steps - got[0] < len(got[1]):
            return None
        return got[1][steps - got[0]]

    def proof_gain(self, finger: str, lo: np.ndarray, hi: np.ndarray,
                   params: str) -> BoxGain | None:
        """The tendon proof's gain of the finger's box ``lo``-``hi`` (``TendonProof.box_gain``),
        None when the table was made with other ``params`` (``TendonProof.params``), for
        another box, or lacks it."""
        got = self.proofs.get(finger)
        if params != self.proof_params or got is None or not (
                np.array_equal(got[0], lo) and np.array_equal(got[1], hi)):
            return None
        return got[2]

    def _cross_pair(self, a: AtlasEntry, b: AtlasEntry):
        """The places of ``a`` (another posture's entry) among its posture's and of ``b``
        among this table's, or None."""
        index = self._x_index.get(a.posture)
        if index is None or b.posture != self.posture:
            return None
        ia, ib = index.get(self.key(a)[:3]), self._index.get(self.key(b))
        return None if ia is None or ib is None else (ia, ib)

    def follow_clear(self, a: AtlasEntry, b: AtlasEntry) -> bool | None:
        ia, ib = self._index.get(self.key(a)), self._index.get(self.key(b))
        m = self._follow.get((a.finger, a.pitch_class))
        if ia is None or ib is None or m is None or a.pitch_class != b.pitch_class:
            return None
        return bool(m[ia[1], ib[1]])

    # ------------------------------------------------------------------ file
    def load(self, path: Path, params: str) -> None:
        if not path.exists():
            return
        with np.load(path, allow_pickle=False) as z:
            if str(z["params"]) != params:
                return
            keys = [(self.fingers[int(f)], int(pc), int(k)) for f, pc, k in z["key"]]
            for key, row, sc in zip(keys, z["cross_s"], z["tendon_scale"]):
                self.crossings[key], self.scales[key] = row, sc
            self._index, self.keys = _indices(keys), keys
            if "clear_s" in z:  # (floats as Python's: the programme reads them as they are)
                self.clears = dict(zip(keys, z["clear_s"].tolist()))
                self.clear_params = str(z["clear_params"])
            if "repeat_params" in z:  # (floats as Python's, as ``repeat_found`` gives them)
                self.repeats = dict(zip(keys, map(tuple, z["repeat"].tolist())))
                self.repeat_params = str(z["repeat_params"])
            if "proof_params" in z:  # (the tendon proof's gains: ``proof_arrays``)
                self.proof_params = str(z["proof_params"])
                for f in self.fingers:
                    if f"proof_box_{f}" in z:
                        self.proofs[f] = _load_gain(z, f, "")
                    if f"proof_cells_box_{f}" in z:
                        self.proof_cells[f] = _load_gain(z, f, "cells_")
            for name in z.files:  # (across postures: ``make_table``'s ``others``)
                if name.startswith("xkey_"):
                    self._load_cross(z, int(name[5:]))
            for f in self.fingers:
                n = sum(k[0] == f for k in keys)
                if f"across_{f}" in z:
                    self._across[f] = _unpack(z[f"across_{f}"], n)
                for pc in range(12):
                    name = f"follow_{f}_{pc}"
                    if name in z:
                        m = sum(k[0] == f and k[1] == pc for k in keys)
                        self._follow[(f, pc)] = _unpack(z[name], m)


    def _load_cross(self, z, other: int) -> None:
        keys = [(self.fingers[int(f)], int(pc), int(k)) for f, pc, k in z[f"xkey_{other}"]]
        self.cross_keys[other], self._x_index[other] = keys, _indices(keys)
        if f"xarm_{other}" in z:
            self._x_arm[other] = (int(z[f"xarm_lo_{other}"]), z[f"xarm_{other}"].tolist())
        for f in self.fingers:
            n_a, n_b = (sum(k[0] == f for k in ks) for ks in (keys, self.keys))
            name = f"xacross_{f}_{other}"
            if name in z:
                self._x_across[(f, other)] = _unpack(z[name], n_a, n_b)

    def drop_cross(self, other: int) -> None:
        """Forget the pairs from posture ``other`` (its entries are not those the table
        was made with: ``Places`` compares the keys)."""
        self._x_index.pop(other, None)
        self._x_arm.pop(other, None)


def drop_stale_cross(tables: list[MoveTable]) -> None:
    """Each posture's table (``tables[i]``) keeps its pairs across from posture ``p`` only
    where they were made with the entries ``tables[p]`` holds (their keys equal)."""
    for t in tables:
        for p, keys in list(t.cross_keys.items()):
            if p >= len(tables) or keys != tables[p].keys:
                t.drop_cross(p)


def _indices(keys) -> dict[tuple[str, int, int], tuple[int, int]]:
    """Each entry's place among its finger's entries and among its finger's on its key."""
    out, per_f, per_key = {}, {}, {}
    for f, pc, k in keys:
        out[(f, pc, k)] = (per_f.get(f, 0), per_key.get((f, pc), 0))
        per_f[f] = per_f.get(f, 0) + 1
        per_key[(f, pc)] = per_key.get((f, pc), 0) + 1
    return out


def _load_gain(z, finger: str, kind: str) -> tuple[np.ndarray, np.ndarray, BoxGain]:
    """A finger's box (or cells: ``kind``) and its gain as ``proof_arrays`` wrote them."""
    box = z[f"proof_{kind}box_{finger}"]
    n = box.shape[-1]
    mass, speed = z[f"proof_{kind}mass_{finger}"], z[f"proof_{kind}speed_{finger}"]
    return box[0], box[1], BoxGain(mass[0], mass[1], speed[0], speed[1],
                                   tuple((k, j) for k in range(n) for j in range(k, n)))


def _unpack(bits: np.ndarray, n: int, m: int | None = None) -> np.ndarray:
    m = n if m is None else m
    return np.unpackbits(bits, count=n * m).astype(bool).reshape(n, m)


# ---------------------------------------------------------------------- making it
def table_entries(atlas) -> tuple[list, list[AtlasEntry]]:
    """An atlas's (solved in full) entries' keys and entries, in a table's order."""
    hand, solved = atlas.hand, atlas.solved()
    order = sorted(solved, key=lambda k: (hand.fingers.index(k[0]), k[1], k[2]))
    return order, [solved[k] for k in order]


def make_table(moves, path: Path, params: str, others=(), high=None) -> int:
    """Find every answer for ``moves``' atlas (solved in full) and write the table;
    ``others``: the hand's other play postures' atlases (solved in full) and the arm's
    moves to each (the rail's first step and the
    durations step by step, ``Places.arm_time_s``; or None), for the pairs across
    postures; ``high``: a ``HighClear`` that searches every moment (none shipped), and
    its parameters (``highclear.params``), or None. Returns the number of
    entries. The tendon proof's gains and the entries' repeats go into the table after
    (``add_proofs``, ``add_repeats``)."""
    atlas, hand = moves.atlas, moves.hand
    order, entries = table_entries(atlas)
    arrays: dict[str, np.ndarray] = {
        "key": np.array([(hand.fingers.index(f), pc, k) for f, pc, k in order],
                        dtype=np.int16).reshape(-1, 3),
        "cross_s": np.array([[moves.descend(e, p).cross_s for p in ENDS]
                             + [moves.lift(e, p).cross_s for p in ENDS] for e in entries]
                            ).reshape(-1, 6),
        "tendon_scale": np.array([[moves.entry_scale(e, c) for c in range(4)]
                                  for e in entries]).reshape(-1, 4),
        "params": np.array(params)}
    if high is not None:  # (``HighClear``'s moments of every entry, and its parameters)
        high, clear_params = high
        rows = [high.clear_row(e, moves) for e in entries]
        arrays["clear_s"] = np.array(rows).reshape(len(rows), len(rows[0]) if rows else 0)
        arrays["clear_params"] = np.array(clear_params)
    for f in hand.fingers:
        mine = [e for e in entries if e.finger == f]
        arrays[f"across_{f}"] = np.packbits(_across_matrix(moves, f, mine))
        if atlas.rail is None:
            continue
        for pc in range(12):
            on_key = [e for e in mine if e.pitch_class == pc]
            if on_key:
                arrays[f"follow_{f}_{pc}"] = np.packbits(_follow_matrix(moves, f, pc, on_key))
    for other, arm_s in others:
        arrays.update(_cross_arrays(moves, entries, other))
        if arm_s is not None:  # (the arm's moves to the other posture, every step)
            lo, durations = arm_s
            arrays[f"xarm_lo_{other.posture_index}"] = np.array(lo)
            arrays[f"xarm_{other.posture_index}"] = np.array(durations, dtype=float)
    with open(path, "wb") as fh:
        np.savez_compressed(fh, **arrays)
    return len(entries)


def high_boxes(hand, atlas) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """The box (least, greatest) of each finger's high poses in the atlas (its joints,
    couplings applied), for the tendon bound's proof: a move across between two of them
    stays in it (a straight line, the couplings elementwise and linear)."""
    highs: dict[str, list[np.ndarray]] = {}
    for e in atlas.solved().values():
        highs.setdefault(e.finger, []).append(e.high)
    out = {}
    for f, poses in highs.items():
        js = hand.joint_slice(f)
        Q = np.repeat(atlas.base[None, :], len(poses), axis=0)
        Q[:, js] = poses
        Q = hand.apply_couplings(Q)[:, js]
        out[f] = (Q.min(axis=0), Q.max(axis=0))
    return out


def proof_arrays(moves, others=()) -> dict[str, np.ndarray]:
    """The tendon proof's gain of each finger's box of high poses (``Moves.high_boxes``,
    ``TendonProof.box_gain``: found as a plan finds it) and the proof's parameters; with
    ``others`` (the other play postures' atlases, in posture 0's table) also each finger's
    cells over the hull of its boxes in every posture (``TendonProof.hull_cells``); none
    for a hand without the proof."""
    proof = moves.tendons.proof
    if proof is None:
        return {}
    out = {"proof_params": np.array(proof.params())}
    boxes = moves.high_boxes()
    for f, (lo, hi) in boxes.items():
        _put_gain(out, f, "", (lo, hi, proof.box_gain(f, lo, hi)))
    theirs = [high_boxes(moves.hand, a) for a in others]
    for f, (lo, hi) in boxes.items() if theirs else ():
        los, his = [lo, *(b[f][0] for b in theirs if f in b)], [hi, *(b[f][1] for b in theirs if f in b)]
        cells = proof.hull_cells(f, np.min(los, axis=0), np.max(his, axis=0))
        _put_gain(out, f, "cells_", cells)
    return out


def _put_gain(out: dict, finger: str, kind: str, got) -> None:
    """A finger's box (or cells) and gain into ``out`` (``_load_gain`` reads them)."""
    if got is None or got[2] is None:
        return
    lo, hi, gain = got
    out[f"proof_{kind}box_{finger}"] = np.array([lo, hi])
    out[f"proof_{kind}mass_{finger}"] = np.array([gain.mass, gain.mass_radius])
    out[f"proof_{kind}speed_{finger}"] = np.array([gain.speed, gain.speed_radius])


def add_proofs(moves, path: Path, others=()) -> bool:
    """Write ``proof_arrays`` into the move table at ``path`` (its other arrays as they
    are; none of an older proof's kept; a hand without the proof: left as it is, False)."""
    proofs = proof_arrays(moves, others)
    if not proofs:
        return False
    with np.load(path, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files if not k.startswith("proof_")}
    arrays.update(proofs)
    with open(path, "wb") as fh:
        np.savez_compressed(fh, **arrays)
    return True


def repeat_arrays(moves, entries: list[AtlasEntry]) -> dict[str, np.ndarray]:
    """Each entry's repeat as ``moves`` finds it (``Moves.repeat_found``) and the
    parameters it was found with (``moves.repeat_params``: ``moves.REPEAT_PARAMS``)."""
    rows = np.array([moves.repeat_found(e) for e in entries], dtype=float)
    return {"repeat": rows.reshape(-1, len(REPEAT_COLUMNS)),
            "repeat_params": np.array(moves.repeat_params)}


def add_repeats(moves, path: Path) -> int:
    """Write ``repeat_arrays`` of the table's entries into the move table at ``path`` (its
    other arrays as they are; ``moves`` reads that table: the crossings it ships are those
    found); the number of entries."""
    order, entries = table_entries(moves.atlas)
    with np.load(path, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files if not k.startswith("repeat")}
    fingers = moves.hand.fingers
    if [(fingers[int(f)], int(pc), int(k)) for f, pc, k in arrays["key"]] != order:
        raise ValueError(f"{path}: not the move table of this atlas's entries")
    arrays.update(repeat_arrays(moves, entries))
    with open(path, "wb") as fh:
        np.savez_compressed(fh, **arrays)
    return len(entries)


def _cross_arrays(moves, entries: list[AtlasEntry], other) -> dict:
    """The pairs from the entries of ``other`` (another posture's atlas) to ``entries``
    (``moves``' own): ``Moves.across``' test at this posture's natural pose, with the
    other posture's keys."""
    hand, p = moves.hand, other.posture_index
    order, theirs = table_entries(other)
    out = {f"xkey_{p}": np.array([(hand.fingers.index(f), pc, k) for f, pc, k in order],
                                 dtype=np.int16).reshape(-1, 3)}
    S = np.array(ACROSS_SAMPLES)
    for f in hand.fingers:
        mine, yours = [e for e in entries if e.finger == f], [e for e in theirs if e.finger == f]
        if not mine or not yours:
            continue
        A = np.array([e.high for e in yours] + [e.high for e in mine])
        z = _pair_tips(moves, f, moves.js[f], A, S, len(yours))[:, 2]
        out[f"xacross_{f}_{p}"] = np.packbits(
            (z >= HIGH_SAFE_Z_M).reshape(-1, len(S)).all(axis=1))
    return out


def _pair_tips(moves, finger: str, cols: np.ndarray, A: np.ndarray, S: np.ndarray,
               split: int | None = None) -> np.ndarray:
    """The finger's tip positions (n * n * len(S), 3) along the straight move between
    every pair (i, j) of the rows of ``A`` (values of the joints ``cols``, the rest of
    the hand at the atlas's natural posture), at each path parameter of ``S``: row
    (i * n + j) * len(S) + s. ``split``: only the pairs from the first ``split`` rows to
    the others (row (i * (n - split) + j) * len(S) + s)."""
    n = len(A)
    if split is None:
        I, J = np.divmod(np.arange(n * n), n)
    else:
        I, J = np.divmod(np.arange(split * (n - split)), n - split)
        J = J + split
    chain = FrameChain(moves.hand, f"{finger}_tip")
    base = moves.atlas.base
    out = np.empty((len(I) * len(S), 3))
    for lo in range(0, len(out), _BATCH):
        hi = min(len(out), lo + _BATCH)
        pair, s = np.divmod(np.arange(lo, hi), len(S))
        Q = np.repeat(base[None, :], hi - lo, axis=0)
        a, b = A[I[pair]], A[J[pair]]
        Q[:, cols] = a + S[s][:, None] * (b - a)
        out[lo:hi] = chain.positions(moves.hand.apply_couplings(Q))
    return out


def _across_matrix(moves, finger: str, E: list[AtlasEntry]) -> np.ndarray:
    """``Moves.across``' test for every pair (i, j) of ``E``: the tip at least
    ``HIGH_SAFE_Z_M`` high at each of ``ACROSS_SAMPLES`` along high_i -> high_j."""
    S = np.array(ACROSS_SAMPLES)
    z = _pair_tips(moves, finger, moves.js[finger], np.array([e.high for e in E]), S)[:, 2]
    n = len(E)
    return (z >= HIGH_SAFE_Z_M).reshape(n * n, len(S)).all(axis=1).reshape(n, n)


def _follow_matrix(moves, finger: str, pc: int, E: list[AtlasEntry]) -> np.ndarray:
    """``Moves._follow``'s test for every pair (i, j) of ``E`` (one finger, one key): with
    the atlas's body rule, ``planner.play.follow.paths_clear``; else the tip inside the
    key's footprint with the key down (within ``HOLD_MARGIN_M``) at each of
    ``PATH_SAMPLES`` along the joint rail + finger move, off the black keys beside a
    white one."""
    k = kb.key(60 + pc)
    cols = np.r_[moves.atlas.rail, moves.js[finger]]
    A = np.array([np.r_[k.center_x_m - e.dx_m, e.press] for e in E])  # rail, finger joints
    n, S = len(E), np.linspace(0.0, 1.0, PATH_SAMPLES)
    if moves.atlas.bodies is not None:  # (the body rule: ``planner.play.follow``)
        Q = np.repeat(moves.atlas.base[None, :], n, axis=0)
        Q[:, cols] = A
        I, J = np.divmod(np.arange(n * n), n)
        return paths_clear(moves.atlas, finger, k.pitch, Q[I], Q[J],
                           [moves.atlas.rail]).reshape(n, n)
    tips = _pair_tips(moves, finger, cols, A, S)
    x, y, z = tips[:, 0], tips[:, 1], tips[:, 2]
    depth = k.top_z_m - z
    ok = ((k.x_min_m + TIP_RADIUS_M <= x) & (x <= k.x_max_m - TIP_RADIUS_M)
          & (k.y_min_m + TIP_RADIUS_M <= y) & (y <= k.y_max_m - TIP_RADIUS_M)
          & (kb.DOWN_DEPTH_M + HOLD_MARGIN_M <= depth)
          & (depth <= kb.KEY_BED_DEPTH_M - HOLD_MARGIN_M))
    if k.black is False:
        ok &= ~(surfaces_under(x, y, TIP_RADIUS_M) > k.top_z_m)
    return ok.reshape(n * n, len(S)).all(axis=1).reshape(n, n)
