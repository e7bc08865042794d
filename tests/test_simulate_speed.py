"""The physics replay's speed-ups change nothing they should not: the transmission
computed once per distinct pose is the hand's own bit for bit, and the keys that sleep at
rest move as the awake keys do (speed itself: bench/bench_simulate.py --speed, never here)."""

from __future__ import annotations

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

import planner
from planner.hand.model import load_hand
from planner.simulate import simulate_trajectory
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
        for m, d in enumerate(hand.motor_map.drive):
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


# --- the collision selection, the rows' samples, the reference and the motor efforts ---


@pytest.fixture(scope="module")
def short(tmp_path_factory):
    """A short plan (three notes) and its song."""
    from planner.music.midi import Note, write_notes_midi

    d = tmp_path_factory.mktemp("short")
    song = d / "s.mid"
    write_notes_midi([Note(60, 0.5, 0.9, 80), Note(64, 1.0, 1.4, 80), Note(67, 1.5, 2.0, 80)],
                     str(song))
    path = d / "s.csv"
    planner.plan_song(planner.load_song(str(song)), load_hand("default"), str(path))
    return path, song


def _record_arrays(rec):
    import dataclasses

    return {f.name: getattr(rec, f.name) for f in dataclasses.fields(rec)
            if isinstance(getattr(rec, f.name), np.ndarray)}


def test_selection_changes_nothing_to_the_bit(short, monkeypatch):
    """The replay with the collision search narrowed row by row equals the replay where
    every key and hand shape collides at every step, every array to the bit; the
    scene's model is left as it was built."""
    from planner.simulate import replay
    from planner.trajfile import read_trajectory

    hand = load_hand("default")
    tr = read_trajectory(str(short[0]))
    scene = build_scene(hand, hand.T_world_root, keyboard=True)
    built = (np.array(scene.model.geom_contype), np.array(scene.model.body_conaffinity))
    narrowed = replay.simulate(scene, hand, tr.t_s, tr.q)
    assert np.array_equal(scene.model.geom_contype, built[0])
    assert np.array_equal(scene.model.body_conaffinity, built[1])
    monkeypatch.setattr(replay, "_near", lambda scene, data: None)
    every = replay.simulate(scene, hand, tr.t_s, tr.q)
    a, b = _record_arrays(narrowed), _record_arrays(every)
    for name in a:
        assert np.array_equal(a[name], b[name], equal_nan=a[name].dtype.kind == "f"), name
    assert (narrowed.key_dip_m.max(axis=0) > 0.005).sum() >= 3  # the keys were played
    assert narrowed.reach_overruns == 0


def test_selection_keeps_every_key_a_hand_shape_comes_near(short):
    """At every row of a real plan, every key with a geom within half the margin of a
    hand geom (MuJoCo's own distance, mj_geomDistance) is among the selected keys, and
    the selection leaves most keys out."""
    from planner.simulate import nearkeys, replay
    from planner.trajfile import read_trajectory

    hand = load_hand("default")
    tr = read_trajectory(str(short[0]))
    scene = build_scene(hand, hand.T_world_root, keyboard=True)
    m = scene.model
    data = mujoco.MjData(m)
    nk = replay._near(scene, data)
    reach = 0.5 * nk.margin_m
    keys = np.flatnonzero(scene.key_geom_key >= 0)
    out = []
    for row in tr.q[::20]:
        data.qpos[scene.hand_qpos] = row
        mujoco.mj_forward(m, data)
        first, end = nearkeys.reachable(nk, nearkeys.hand_span_m(nk, data))
        out.append(88 - (end - first))
        for h in nk.hand_geoms:
            for g in keys:
                if mujoco.mj_geomDistance(m, data, int(h), int(g), reach, None) < reach:
                    assert first <= scene.key_geom_key[g] < end, (m.geom(h).name,
                                                                  m.geom(g).name)
    assert min(out) >= 40


def test_overrun_of_the_margin_fails_the_replay(short, monkeypatch):
    """A hand moving more than half the margin within a row is counted and fails the
    verdict (a margin of 0.1 mm: every move overruns it)."""
    from planner.simulate import nearkeys

    monkeypatch.setattr(nearkeys, "REACH_MARGIN_M", 1e-4)
    rep = simulate_trajectory(str(short[0]), str(short[1]))
    assert not rep.ok
    assert "within a row" in rep.problems[0]


def test_servo_motor_torques_are_the_hands_own_bit_for_bit():
    rng = np.random.default_rng(5)
    for name in ("default", "mk5", "agh"):
        hand = load_hand(name)
        drive = np.array(hand.motor_map.drive)
        q = np.array([hand.apply_couplings(rng.uniform(hand.lower, hand.upper))
                      for _ in range(50)])
        force = rng.normal(size=(50, hand.n_motor))
        force[::7] = 0.0
        force[3, 0] = -0.0
        tau = np.zeros(hand.n)
        want = np.empty_like(force)
        for k in range(50):
            tau[drive] = force[k]
            want[k] = hand.motor_torques(q[k], tau)
        got = Transmission(hand).servo_motor_torques(q, force, drive)
        assert got.tobytes() == want.tobytes(), name


def test_reference_once_per_distinct_row():
    """Rows repeated (a held pose) are computed once, with the numbers of every row."""
    from planner.simulate.actuators import reference

    hand = load_hand("default")
    rng = np.random.default_rng(2)
    q0 = hand.apply_couplings(rng.uniform(hand.lower, hand.upper))
    q1 = hand.apply_couplings(rng.uniform(hand.lower, hand.upper))
    q = np.array([q0] * 6 + [q1] * 6 + [q0] * 6)
    t = np.arange(len(q)) * 0.01
    calls = []

    def gravity(row, qd, qdd):
        calls.append(1)
        return hand.gravity_torques(row) + 0.1 * qdd

    ref = reference(hand, q, t, gravity)
    qd = np.gradient(q, t, axis=0)
    qdd = np.gradient(qd, t, axis=0)
    keys = {q[i].tobytes() + qd[i].tobytes() + qdd[i].tobytes() for i in range(len(q))}
    assert len(calls) == len(keys) < len(q)
    tr = Transmission(hand)
    for i in range(len(q)):
        cols, _ = tr.at(q[i])
        tau = gravity(q[i], qd[i], qdd[i])
        assert np.array_equal(ref.feedforward_nm[i], [float(c @ tau) for c in cols])


def test_check_play_is_the_checks_play(short):
    from planner.check import check_play, check_trajectory

    a = check_play(str(short[0]), str(short[1]))
    b = check_trajectory(str(short[0]), str(short[1])).play
    assert a == b
