"""The physics replay's speed-ups change nothing they should not: the transmission
computed once per distinct pose is the hand's own bit for bit, and the keys that sleep at
rest move as the awake keys do (speed itself: bench/bench_simulate.py --speed, never here)."""

from __future__ import annotations

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

import planner
from planner.hand.model import load_hand
from planner.simulate.actuators import Transmission
from planner.simulate.scene import KEY_SLEEP_TOLERANCE_M_S, build_scene


@pytest.mark.parametrize("name", ["default", "mk5", "agh"])
def test_transmission_is_the_hands_own_bit_for_bit(name):
    hand = load_hand(name)
    tr = Transmission(hand)
    rng = np.random.default_rng(3)
    col = {int(j): k for k, j in enumerate(hand.independent)}
    for _ in range(20):
        q = hand.apply_couplings(rng.uniform(hand.lower, hand.upper))
        tau = rng.normal(size=hand.n)
        cols, ratio = tr.at(q)
        S = hand.dq_dindependent(q)
        assert np.array_equal(ratio, hand.motor_ratio(q))
        for m, d in enumerate(hand._drive):
            assert np.array_equal(cols[m], S[:, col[int(d)]])
        assert np.array_equal(tr.motor_torques(q, tau), hand.motor_torques(q, tau))


def test_keys_sleep_only_at_rest():
    hand = load_hand("default")
    scene = build_scene(hand, hand.T_world_root, keyboard=True)
    m = scene.model
    assert m.opt.enableflags & int(mujoco.mjtEnableBit.mjENBL_SLEEP)
    assert m.opt.sleep_tolerance == KEY_SLEEP_TOLERANCE_M_S
    allowed = int(mujoco.mjtSleepPolicy.mjSLEEP_ALLOWED)
    key_trees = {int(m.body_treeid[m.body(f"key_{p}").id]) for p in range(21, 109)}
    assert all(int(m.tree_sleep_policy[t]) == allowed for t in key_trees)
    hand_tree = int(m.dof_treeid[scene.hand_dof[0]])
    assert int(m.tree_sleep_policy[hand_tree]) != allowed  # driven: never asleep
    catch = build_scene(hand, hand.T_world_root, keyboard=False)
    assert not catch.model.opt.enableflags & int(mujoco.mjtEnableBit.mjENBL_SLEEP)


def test_sleeping_keys_move_as_awake_keys(tmp_path):
    """A short song replayed with and without sleep: every key's travel and every joint
    within 1 um / 10 urad of the awake replay (MuJoCo's default 1 mm/s tolerance froze
    settling keys and moved twinkle's F1 by 0.02)."""
    from planner.music.midi import Note, write_notes_midi
    from planner.simulate.replay import simulate
    from planner.trajfile import read_trajectory

    song = tmp_path / "s.mid"
    write_notes_midi([Note(60, 0.5, 0.9, 80), Note(62, 1.0, 1.4, 80), Note(64, 1.5, 2.0, 80)],
                     str(song))
    hand = load_hand("default")
    path = tmp_path / "s.csv"
    planner.plan_song(planner.load_song(str(song)), hand, str(path))
    tr = read_trajectory(str(path))
    recs = []
    for sleep in (True, False):
        scene = build_scene(hand, hand.T_world_root, keyboard=True)
        if not sleep:
            scene.model.opt.enableflags &= ~int(mujoco.mjtEnableBit.mjENBL_SLEEP)
        recs.append(simulate(scene, hand, tr.t_s, tr.q))
    a, b = recs
    assert np.abs(a.key_dip_m - b.key_dip_m).max() < 1e-6
    assert np.abs(a.q_sim - b.q_sim).max() < 1e-5
    assert (a.key_dip_m.max(axis=0) > 0.005).sum() >= 3  # the keys were played
