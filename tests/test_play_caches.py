"""The play planner's shortcuts that must not change a plan: each gives the
straightforward computation's numbers to the bit (plans stay byte-identical; the
bytes of whole plans: bench/play_bytes.py)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from planner.hand.model import load_hand
from planner.hand.tendon import actuator_capacity
from planner.play.atlas import PATH_SAMPLES
from planner.play.places import Places
from planner.play.railcap import RAIL_TORQUE_SHARE, path_acceleration_cap


def straight_cap(hand, postures, dq) -> float:
    """``path_acceleration_cap`` as first written: every posture's motor torques."""
    m = hand.pin_model
    data = m.createData()
    cap = RAIL_TORQUE_SHARE * actuator_capacity(hand).torque_nm
    vi = hand.pin_v_idx
    best = np.inf
    for q in postures:
        qp, v = hand.pin_q(q), np.zeros(m.nv)
        unit = np.zeros(m.nv)
        unit[vi] = dq
        tau_g = pin.rnea(m, data, qp, v, np.zeros(m.nv))[vi]
        tau_1 = pin.rnea(m, data, qp, v, unit)[vi] - tau_g
        g, k = hand.motor_torques(q, tau_g), hand.motor_torques(q, tau_1)
        room = cap - np.abs(g)
        with np.errstate(divide="ignore"):
            best = min(best, float(np.min(np.where(np.abs(k) > 1e-12, room / np.abs(k),
                                                   np.inf))))
    return best


@pytest.fixture(scope="module")
def places() -> Places:
    return Places(load_hand("default"))


def test_arm_lines_cap_is_the_straight_one(places) -> None:
    """The arm's lines (``Places.arm_move``: rail and reach, the rest at a posture's
    natural hand), every pair of postures and rail moves up to a metre."""
    h, cols = places.hand, places.arm
    assert len(cols) == 2
    for pa in range(places.postures):
        for pb in range(places.postures):
            for dist in (0.0, 0.006, 0.042, 0.3, 1.0):
                qa = np.array([0.0, places.reach_m(pa)])
                dq = np.array([dist, places.reach_m(pb)]) - qa
                full = np.zeros(h.n)
                full[cols] = dq
                line = []
                for s in np.linspace(0.0, 1.0, PATH_SAMPLES):
                    q = places.atlases[pa].base.copy()
                    q[cols] = qa + s * dq
                    line.append(h.apply_couplings(q))
                assert path_acceleration_cap(h, line, full) == straight_cap(h, line, full)


@pytest.mark.parametrize("name", ["default", "mk5", "agh"])
def test_whole_hand_lines_cap_is_the_straight_one(name: str) -> None:
    """Lines on which every joint moves (no posture repeats), and a line of one pose
    repeated (every posture after the first skipped)."""
    h = load_hand(name)
    rng = np.random.default_rng(3)
    lo, hi = np.clip(h.plan_lower, -1, 1), np.clip(h.plan_upper, -1, 1)
    for _ in range(20):
        qa, qb = rng.uniform(lo, hi), rng.uniform(lo, hi)
        dq = qb - qa
        line = [h.apply_couplings(qa + s * dq) for s in np.linspace(0, 1, PATH_SAMPLES)]
        assert path_acceleration_cap(h, line, dq) == straight_cap(h, line, dq)
        same = [h.apply_couplings(qa)] * 4
        assert path_acceleration_cap(h, same, dq) == straight_cap(h, same, dq)


def test_distance_and_arm_time_are_the_straight_ones(places) -> None:
    """``Places.distance_m`` (read from a list of reaches) and ``arm_time_s`` (memoised
    by the pair of places) against their definitions, both orders of every pair (a
    move and its reverse take the same time: found within one posture by the rail's
    steps, across postures from the lower posture, the rail's steps signed)."""
    ps = [places.place(p, r) for p in range(places.postures) for r in (-40, -3, 0, 1, 7, 60)]
    for a in ps:
        for b in ps:
            pa, pb = places.posture_of(a), places.posture_of(b)
            ra, rb = places.rail_i(a), places.rail_i(b)
            reach_a, reach_b = places.reach_m(pa), places.reach_m(pb)
            assert places.distance_m(a, b) == abs(ra - rb) * 0.006 + abs(reach_a - reach_b)
            lo, hi, steps = ((pa, pb, rb - ra) if pa < pb else (pb, pa, ra - rb)
                             if pa > pb else (pa, pa, abs(rb - ra)))
            want = places.arm_move((0.0, places.reach_m(lo)),
                                   (steps * 0.006, places.reach_m(hi)))
            assert places.arm_time_s(a, b) == want.duration_s


def test_arm_move_line_is_the_samples_one_by_one(places, monkeypatch) -> None:
    """``Places.arm_move`` (``ArmMoves.arm_move``) builds its line's samples as one array: the rows it hands
    ``path_acceleration_cap`` are the samples built one by one."""
    import planner.play.armmoves as pp

    h, cols = places.hand, places.arm
    got = []
    monkeypatch.setattr(pp, "path_acceleration_cap",
                        lambda hand, line, dq: got.append(np.array(line)) or 1.0)
    a, b = (0.0, places.reach_m(0)), (0.138, places.reach_m(places.postures - 1))
    places.arm_move(a, b)
    qa, dq = np.array(a), np.array(b) - np.array(a)
    want = []
    for s in np.linspace(0.0, 1.0, PATH_SAMPLES):
        q = places.atlas.base.copy()
        q[cols] = qa + s * dq
        want.append(h.apply_couplings(q))
    assert len(got) == 1 and np.array_equal(got[0], np.array(want))


def test_an_arm_moves_tendon_factor_kept_is_the_one_found_again(monkeypatch) -> None:
    """``ArmMoves.tendon_slowed`` keeps each move's factor by the move, its joints, its
    posture and the fingers pressing: planning ``leaps.mid`` and ``fast.mid`` (arms
    carrying fingers that hold keys), every answer, the kept ones among them, is the
    factor ``time_scale`` finds afresh, and the move it slows is the same."""
    from planner.music.midi import load_song
    from planner.play.armmoves import ArmMoves
    from planner.play.stream import Planner, plan_song
    from planner.play.tendonload import hand_load, slowed

    hand = load_hand("default")
    plain = ArmMoves.tendon_slowed
    seen, kept = [], []

    def checked(self, move, posture, cols, pressing):
        key = (posture, cols.tobytes(), move.q_a.tobytes(), move.dq.tobytes(),
               move.duration_s, move.ta_s, move.tj_s, pressing)
        kept.append(key in seen)
        seen.append(key)
        got = plain(self, move, posture, cols, pressing)
        q_a, dq = self.atlases[posture].base.copy(), np.zeros(hand.n)
        q_a[cols], dq[cols] = move.q_a, move.dq
        want = slowed(move, hand_load(hand).time_scale(move, q_a, dq, pressing))
        assert (got.duration_s, got.ta_s, got.tj_s) == (want.duration_s, want.ta_s, want.tj_s)
        assert np.array_equal(got.q_a, want.q_a) and np.array_equal(got.dq, want.dq)
        return got

    monkeypatch.setattr(ArmMoves, "tendon_slowed", checked)
    planner = Planner(hand)
    for song in ("leaps.mid", "fast.mid"):
        plan_song(load_song(str(Path(__file__).resolve().parents[1] / "songs" / song)), hand,
                  None, planner=planner)
    assert any(kept) and not all(kept), (len(kept), sum(kept))
