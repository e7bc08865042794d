"""The tendon bound's sufficient test (planner.play.tendonproof): its bound of each
motor's torque is above the full computation's (``TendonLoad.terms``, the largest of
``|S| + |K| A + |C| W`` over the samples) on sampled moves across of every finger, in the
atlas's boxes and in a box around every finger's natural pose (the thumb, which plays no
key, among them); where it proves a move, the full computation's scale is 1; and a hand
with a weakened tendon is not proved where its moves need the tendon."""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace

import numpy as np
import pytest

from planner.hand.builders import load_hand_spec
from planner.hand.couplings import CouplingLaw
from planner.hand.model import HandModel, load_hand
from planner.play.atlas import Atlas, posture_count
from planner.play.moves import Moves
from planner.play.movetable import MoveTable, add_proofs, high_boxes, table_path
from planner.play.profile import straight_move
from planner.play.tendonload import TendonLoad, scale_for, speed_squared_bound
from planner.play.tendonproof import BOX_ROOM_RAD, GRID_CELLS


def _full(tl: TendonLoad, move, q_a, dq) -> tuple[np.ndarray, float]:
    """The full computation's largest ``|S| + |K| A + |C| W`` of each motor over the
    move's samples, and its scale (``scale_for`` of the same terms)."""
    static, K, C = tl.terms(q_a, dq)
    A, V = move.peak_acceleration, move.peak_speed
    W = speed_squared_bound(tl.samples, A, V)
    worst = np.max(np.abs(static[:, 0, :]) + np.abs(K) * A + np.abs(C) * W[:, None], axis=0)
    return worst, scale_for(static, K, C, W, A, tl.capacity_nm)


def _move(hand: HandModel, finger: str, base: np.ndarray, qa: np.ndarray, qb: np.ndarray):
    """The finger's straight move from ``qa`` to ``qb`` (the rest at ``base``) as
    ``Moves.finger_scale`` hands it to the bound: whole-hand start and difference."""
    js = hand.joint_slice(finger)
    move = straight_move(qa, qb, hand.velocity[js], np.array(hand.acceleration)[js],
                         np.array(hand.jerk)[js])
    q_a, dq = base.copy(), np.zeros(hand.n)
    q_a[js], dq[js] = qa, qb - qa
    return move, q_a, dq


@pytest.fixture(scope="module")
def default_moves():
    hand = load_hand("default")
    atlas = Atlas(hand)
    return hand, atlas, Moves(hand, atlas)


def test_the_bound_holds_on_the_atlas_moves_across(default_moves):
    """Forty random moves across (high pose to high pose of two entries) of each finger
    the default hand plays with: every motor's bound at or above the full computation's
    largest torque, every move proved (none is an ulp long here), the full scale 1."""
    hand, atlas, moves = default_moves
    tl = moves.tendons
    rng = np.random.default_rng(11)
    by_finger: dict[str, list] = {}
    for e in atlas.solved().values():
        by_finger.setdefault(e.finger, []).append(e)
    assert sorted(by_finger) == ["index", "middle", "pinky", "ring"]
    for finger, entries in by_finger.items():
        done = 0
        while done < 40:
            a, b = (entries[i] for i in rng.integers(len(entries), size=2))
            if np.max(np.abs(b.high - a.high)) < 1e-6:
                continue
            move, q_a, dq = _move(hand, finger, atlas.base, a.high, b.high)
            bound = tl.proof.bound_nm(q_a, dq, move.peak_acceleration, move.peak_speed)
            worst, scale = _full(tl, move, q_a, dq)
            assert bound is not None
            assert np.all(worst <= bound), (finger, worst, bound)
            assert tl.proof.proves(q_a, dq, move.peak_acceleration, move.peak_speed)
            assert scale == 1.0
            assert tl.time_scale(move, q_a, dq) == 1.0
            done += 1


@pytest.mark.parametrize("finger", ["thumb", "index", "middle", "ring", "pinky"])
def test_the_bound_holds_around_every_fingers_natural_pose(finger):
    """A box of 0.3 rad each way around the finger's natural pose (within its joint
    limits), thirty random moves within it at the joints' full speed: the bound at or
    above the full computation's largest torque on every motor."""
    hand = load_hand("default")
    atlas = Atlas(hand)
    tl = TendonLoad(hand)
    js = hand.joint_slice(finger)
    centre = atlas.base[js]
    lo = np.maximum(centre - 0.3, hand.lower[js])
    hi = np.minimum(centre + 0.3, hand.upper[js])
    coupled = hand.apply_couplings(np.stack((np.r_[atlas.base[:js[0]], lo, atlas.base[js[-1] + 1:]],
                                             np.r_[atlas.base[:js[0]], hi, atlas.base[js[-1] + 1:]])))
    tl.proof.add_box(finger, coupled[:, js].min(axis=0), coupled[:, js].max(axis=0))
    rng = np.random.default_rng(5)
    for _ in range(30):
        qa, qb = (lo + rng.random(len(js)) * (hi - lo) for _ in range(2))
        move, q_a, dq = _move(hand, finger, atlas.base, qa, qb)
        bound = tl.proof.bound_nm(q_a, dq, move.peak_acceleration, move.peak_speed)
        worst, scale = _full(tl, move, q_a, dq)
        assert bound is not None
        assert np.all(worst <= bound), (finger, worst, bound)
        if tl.proof.proves(q_a, dq, move.peak_acceleration, move.peak_speed):
            assert scale == 1.0


def test_a_move_outside_the_boxes_or_of_two_fingers_is_not_proved(default_moves):
    """A move with an end outside every box of its finger, and a move of two fingers at
    once, prove nothing (the full computation runs)."""
    hand, atlas, moves = default_moves
    tl = moves.tendons
    js = hand.joint_slice("index")
    e = next(e for e in atlas.solved().values() if e.finger == "index")
    far = e.high.copy()
    far[1] = hand.upper[js][1]  # (the knuckle bent to its stop: no high pose is)
    move, q_a, dq = _move(hand, "index", atlas.base, e.high, far)
    assert tl.proof.bound_nm(q_a, dq, move.peak_acceleration, move.peak_speed) is None
    dq2 = dq.copy()
    dq2[hand.joint_slice("middle")[1]] = 0.01
    assert tl.proof.bound_nm(q_a, dq2, move.peak_acceleration, move.peak_speed) is None


def _weak_hand() -> HandModel:
    """The default hand with its middle finger's knuckle tendon at 9 N of its 40 N."""
    spec = load_hand_spec("default")
    return HandModel(dataclasses.replace(spec, actuators=tuple(
        dataclasses.replace(a, tendon_force_n=9.0)
        if a.name == "middle_mcp" else a for a in spec.actuators)))


def test_a_weakened_tendon_is_not_proved(default_moves):
    """The default hand with its middle finger's knuckle tendon at 9 N of its 40 N (its
    capacity between the finger's load held still and its load moving) and the default
    hand's boxes: the full computation slows some of that finger's moves across, and no
    move of that finger is proved; nor the index finger's, which the full computation does
    not slow (the test asks every tendon motor's static bound within its share, the middle
    finger's too: on the safe side)."""
    _, atlas, moves = default_moves
    weak = _weak_hand()
    tl = TendonLoad(weak)
    for finger, boxes in moves.tendons.proof.boxes.items():
        tl.proof.boxes[finger].extend(boxes)
    rng = np.random.default_rng(2)
    entries = {f: [e for e in atlas.solved().values() if e.finger == f]
               for f in ("middle", "index")}
    slowed = unslowed = 0
    for _ in range(40):
        a, b = (entries["middle"][i] for i in rng.integers(len(entries["middle"]), size=2))
        move, q_a, dq = _move(weak, "middle", atlas.base, a.high, b.high)
        is_proved = tl.proof.proves(q_a, dq, move.peak_acceleration, move.peak_speed)
        assert not is_proved
        slowed += _full(tl, move, q_a, dq)[1] > 1.0
        a, b = (entries["index"][i] for i in rng.integers(len(entries["index"]), size=2))
        if np.max(np.abs(b.high - a.high)) >= 1e-6:
            move, q_a, dq = _move(weak, "index", atlas.base, a.high, b.high)
            assert not tl.proof.proves(q_a, dq, move.peak_acceleration, move.peak_speed)
            unslowed += _full(tl, move, q_a, dq)[1] == 1.0
    assert slowed > 0
    assert unslowed > 0


def _gains_equal(a, b) -> bool:
    return (a.pairs == b.pairs and all(
        np.array_equal(getattr(a, k), getattr(b, k)) and getattr(a, k).dtype == getattr(b, k).dtype
        for k in ("mass", "mass_radius", "speed", "speed_radius")))


@pytest.mark.parametrize("name", ["default", "default-left"])
def test_the_shipped_gains_are_those_worked_out(name):
    """Every play posture's move table ships the tendon proof's gain of each finger's box
    of high poses (``MoveTable.proof_gain``): bit for bit the gain ``box_gain`` works out
    now, and the very gain the proof reads (no box of a finger that plays goes without)."""
    hand = load_hand(name)
    for posture in range(posture_count(hand)):
        moves = Moves(hand, Atlas(hand, posture=posture))
        proof = moves.tendons.proof
        boxes = moves.high_boxes()
        assert sorted(boxes) == ["index", "middle", "pinky", "ring"]
        for f, (lo, hi) in boxes.items():
            shipped = moves.table.proof_gain(f, lo, hi, proof.params())
            assert shipped is not None
            assert _gains_equal(shipped, proof.box_gain(f, lo, hi))
            # (the box as the proof holds it, and the gain it reads for it: the shipped one)
            i = next(i for i, (l0, h0) in enumerate(proof.boxes[f])
                     if np.array_equal(l0, lo - BOX_ROOM_RAD) and np.array_equal(h0, hi + BOX_ROOM_RAD))
            assert _gains_equal(proof.gains[(f, i)], shipped)


def test_gains_of_other_parameters_or_another_box_are_not_read(tmp_path):
    """A table made with other proof parameters (its ``proof_params``) is not read, nor
    its gain for a box an ulp wider; a table without the proof's arrays gives none; and
    ``add_proofs`` writes into such a table the very arrays the shipped one holds (the
    cells over every posture's among them)."""
    hand = load_hand("default")
    moves = Moves(hand, Atlas(hand))
    proof, f = moves.tendons.proof, "middle"
    lo, hi = moves.high_boxes()[f]
    path = table_path(hand.urdf_sha256)
    assert moves.table.proof_gain(f, lo, hi, proof.params()) is not None
    assert moves.table.proof_gain(f, lo, hi, proof.params().replace('"grid_points": 4',
                                                                    '"grid_points": 5')) is None
    assert moves.table.proof_gain(f, lo, np.nextafter(hi, np.inf), proof.params()) is None
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files}
    other = tmp_path / "other.npz"
    np.savez(other, **{**arrays, "proof_params": np.array(proof.params().replace(
        '"curvature": 64.0', '"curvature": 32.0'))})
    bare = tmp_path / "bare.npz"
    np.savez(bare, **{k: v for k, v in arrays.items() if not k.startswith("proof_")})
    for p in (other, bare):
        table = MoveTable(hand.fingers, moves.atlas.natural_dx)
        table.load(p, moves.params())
        assert len(table.crossings) == len(moves.table.crossings)  # (the rest is read)
        assert table.proof_gain(f, lo, hi, proof.params()) is None
    assert add_proofs(moves, bare, [Atlas(hand, posture=p) for p in range(1, posture_count(hand))])
    with np.load(bare) as z:
        assert sorted(k for k in z.files if k.startswith("proof_")) == \
            sorted(k for k in arrays if k.startswith("proof_"))
        for k in z.files:
            assert np.array_equal(z[k], arrays[k])


@pytest.mark.parametrize("name", ["default", "default-left"])
def test_the_shipped_cells_are_those_worked_out(name):
    """Posture 0's move table ships each finger's cells over the hull of its high poses in
    every posture (``MoveTable.proof_cells``): their corners and gains bit for bit what
    ``hull_cells`` works out now over the postures' boxes, and the proof holds them."""
    hand = load_hand(name)
    atlases = [Atlas(hand, posture=p) for p in range(posture_count(hand))]
    moves = Moves(hand, atlases[0])
    proof = moves.tendons.proof
    boxes = [high_boxes(hand, a) for a in atlases]
    assert sorted(moves.table.proof_cells) == ["index", "middle", "pinky", "ring"]
    for f, (lo, hi, gain) in moves.table.proof_cells.items():
        want = proof.hull_cells(f, np.min([b[f][0] for b in boxes], axis=0),
                                np.max([b[f][1] for b in boxes], axis=0))
        assert np.array_equal(lo, want[0]) and np.array_equal(hi, want[1])
        assert len(lo) == GRID_CELLS ** (len(lo[0]) - 1)
        assert _gains_equal(gain, want[2])
        assert proof.cells[f][0] is lo and proof.cells[f][2][0] is gain.mass


def test_the_cells_bound_holds_on_moves_across_postures():
    """Moves across from another posture's entry (its high pose, the rest of the hand at
    this posture's: ``Moves.finger_scale``' question), twenty of each finger and pair of
    postures: no box holds both ends, the cells' bound is at or above the full
    computation's largest torque on every motor, and every such move is proved (scale 1);
    without the cells none is bounded."""
    hand = load_hand("default")
    atlases = [Atlas(hand, posture=p) for p in range(posture_count(hand))]
    moves = [Moves(hand, a) for a in atlases]
    tl = moves[0].tendons
    bare = TendonLoad(hand)
    for f in ("index", "middle", "ring", "pinky"):
        for box in tl.proof.boxes[f]:
            bare.proof.boxes[f].append(box)
    rng = np.random.default_rng(3)
    proved = 0
    for p, q in ((0, 1), (1, 0), (0, 2), (2, 1)):
        for f in ("index", "middle", "ring", "pinky"):
            mine = [e for e in atlases[p].solved().values() if e.finger == f]
            theirs = [e for e in atlases[q].solved().values() if e.finger == f]
            for _ in range(20):
                a, b = mine[rng.integers(len(mine))], theirs[rng.integers(len(theirs))]
                move, q_a, dq = _move(hand, f, atlases[q].base, a.high, b.high)
                A, V = move.peak_acceleration, move.peak_speed
                points = hand.apply_couplings(np.stack((q_a, q_a + dq)))[:, hand.joint_slice(f)]
                if tl.proof.gain(f, points) is not None:
                    continue  # (both ends in one posture's box: not this test's)
                bound = tl.proof.bound_nm(q_a, dq, A, V)
                worst, scale = _full(tl, move, q_a, dq)
                assert bound is not None
                assert np.all(worst <= bound), (f, p, q, worst, bound)
                assert bare.proof.bound_nm(q_a, dq, A, V) is None
                if tl.proof.proves(q_a, dq, A, V):
                    assert scale == 1.0
                    proved += 1
    assert proved > 100


def test_the_box_bound_is_at_least_each_moves_own(default_moves):
    """Forty random moves across of each finger (posture 0: its own box is the first
    that holds its moves): the box's bound (``BoxBound.bound_nm``) at or above the move's
    own (``TendonProof.bound_nm``) on every motor, so a move the box proves the move's
    own bound proves; most moves proved by the box."""
    hand, atlas, moves = default_moves
    proof = moves.tendons.proof
    rng = np.random.default_rng(17)
    proved = 0
    for finger, fb in moves.across_proof.boxes.items():
        box = proof.box_bound(finger, fb.lo, fb.hi, fb.most - fb.least)
        entries = list(fb.by_id.values())
        for _ in range(40):
            a, b = (entries[i] for i in rng.integers(len(entries), size=2))
            move, q_a, dq = _move(hand, finger, atlas.base, a.high, b.high)
            A, V = move.peak_acceleration, move.peak_speed
            own = proof.bound_nm(q_a, dq, A, V)
            # (the same sums in another order: equal but for their last bits)
            assert np.all(box.bound_nm(move.dq, A, V) >= own * (1.0 - 1e-12)), finger
            if box.proves(move.dq, A, V):
                proved += 1
                assert proof.proves(q_a, dq, A, V)
    assert proved >= 150  # (of 160)


def test_the_box_bound_proves_nothing_of_a_weakened_tendon(default_moves):
    """The weakened middle knuckle of ``test_a_weakened_tendon_is_not_proved``: the box
    proves none of the middle finger's moves across."""
    _, atlas, moves = default_moves
    weak = _weak_hand()
    tl = TendonLoad(weak)
    fb = moves.across_proof.boxes["middle"]
    tl.proof.add_box("middle", fb.lo, fb.hi)
    box = tl.proof.box_bound("middle", fb.lo, fb.hi, fb.most - fb.least)
    entries = list(fb.by_id.values())
    rng = np.random.default_rng(3)
    for _ in range(30):
        a, b = (entries[i] for i in rng.integers(len(entries), size=2))
        move, _, _ = _move(weak, "middle", atlas.base, a.high, b.high)
        assert not box.proves(move.dq, move.peak_acceleration, move.peak_speed)


def test_a_coupling_out_of_the_finger_gives_no_box_bound(default_moves):
    """The default hand's proof with one more coupling, the index finger's first joint
    driven by the middle finger's (a move of the one moves the other: ``bound_nm``
    proves none of their moves): no ``BoxBound`` for either finger; without it, one."""
    hand, _, moves = default_moves
    js_m, js_i = hand.joint_slice("middle"), hand.joint_slice("index")
    tl = TendonLoad(hand)
    tied = CouplingLaw(dep=int(js_i[0]), src=int(js_m[0]), kind="linear", ratio=0.5)
    for finger in ("middle", "index"):
        fb = moves.across_proof.boxes[finger]
        lo, hi, reach = fb.lo, fb.hi, fb.most - fb.least
        tl.proof.add_box(finger, lo, hi)
        assert tl.proof.box_bound(finger, lo, hi, reach) is not None
        tl.proof.hand = SimpleNamespace(couplings=(*hand.couplings, tied))
        assert tl.proof.box_bound(finger, lo, hi, reach) is None
        tl.proof.hand = hand


def test_the_stretched_box_bound_holds_on_moves_across_postures():
    """Moves across from another posture's entry into this posture's box, twenty of each
    finger and pair of postures, those of them that no box holds both ends of: the bound over the box
    stretched to the first entry's high pose (``AcrossProof``, the cells it meets) at or
    above the move's own (the cells' that the move's ends' box meets) on every motor but
    for the sums' rounding; where it proves a move, the full computation's scale is 1."""
    hand = load_hand("default")
    atlases = [Atlas(hand, posture=p) for p in range(posture_count(hand))]
    moves = [Moves(hand, a) for a in atlases]
    proof = moves[0].tendons.proof
    rng = np.random.default_rng(4)
    proved = tried = 0
    for p, q in ((0, 1), (1, 0), (0, 2), (2, 1)):
        across = moves[q].across_proof
        for f in ("index", "middle", "ring", "pinky"):
            mine = [e for e in atlases[p].solved().values() if e.finger == f]
            theirs = list(across.boxes[f].by_id.values())
            for _ in range(20):
                a, b = mine[rng.integers(len(mine))], theirs[rng.integers(len(theirs))]
                move, q_a, dq = _move(hand, f, atlases[q].base, a.high, b.high)
                A, V = move.peak_acceleration, move.peak_speed
                points = hand.apply_couplings(np.stack((q_a, q_a + dq)))[:, hand.joint_slice(f)]
                if proof.gain(f, points) is not None:
                    continue  # (both ends in one posture's box: the first test's)
                box = across._stretched(a, across.boxes[f])
                assert box is not None
                assert np.all(box.bound_nm(move.dq, A, V)
                              >= proof.bound_nm(q_a, dq, A, V) * (1.0 - 1e-12)), (f, p, q)
                tried += 1
                if across.proves(a, b, move):
                    assert _full(moves[q].tendons, move, q_a, dq)[1] == 1.0
                    proved += 1
    assert tried > 100
    assert proved > tried // 2
