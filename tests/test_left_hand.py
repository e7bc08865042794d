"""The left hand (``default-left``) plays one-hand songs: its tables are the right hand's
mirrored, its fingering is mirrored (the pinky on the bass side), and its plans pass
``check`` and physics as the right hand's do (measured side by side:
docs/history/2026-12-06-left-hand.md)."""

from __future__ import annotations

import numpy as np
import pytest

import planner
from planner.check import check_trajectory
from planner.hand.bodies import collision_bodies
from planner.hand.model import load_hand
from planner.hand.spec import FINGERS
from planner.play.atlas import Atlas, posture_count
from planner.play.atlas import table_path as atlas_path
from planner.play.movetable import table_path as moves_path

RIGHT, LEFT = "default", "default-left"


def mirrored_pitch_class(pc: int) -> int:
    """The keyboard is its own mirror image about D: C <-> E, C# <-> D#, F <-> B, ..."""
    return (4 - pc) % 12


@pytest.fixture(scope="module")
def pair():
    return load_hand(RIGHT), load_hand(LEFT)


def _by_key(z) -> dict[tuple[int, int, int], int]:
    return {tuple(k): i for i, k in enumerate(z["key"].tolist())}


@pytest.mark.parametrize("posture", range(3))
def test_the_left_atlas_is_the_right_atlas_mirrored(pair, posture) -> None:
    """Every sample (finger f, pitch class c, offset k from the finger's natural place) of
    the left hand's shipped table is the right hand's (f, mirrored c, -k): the same joints
    to rounding, the same force bound, the same refusals by the body rule."""
    right, left = pair
    assert posture_count(left) == posture_count(right) == 3
    with np.load(atlas_path(right.urdf_sha256, posture)) as zr, \
            np.load(atlas_path(left.urdf_sha256, posture)) as zl:
        kr = _by_key(zr)
        assert len(kr) == len(zl["key"]) > 5000
        n_entries = 0
        for i, (f, pc, k) in enumerate(zl["key"].tolist()):
            j = kr[(f, mirrored_pitch_class(pc), -k)]
            assert zl["body_refused"][i] == zr["body_refused"][j]
            assert np.isnan(zl["max_force_n"][i]) == np.isnan(zr["max_force_n"][j])
            if np.isnan(zl["max_force_n"][i]):
                continue
            n_entries += 1
            some = (left.fingers[f], pc, k)
            assert abs(zl["max_force_n"][i] - zr["max_force_n"][j]) < 1e-9
            for pose in ("press", "rise", "hover", "high"):
                assert np.nanmax(np.abs(zl[pose][i] - zr[pose][j])) < 1e-12
        assert n_entries > 500
    # (and the planner loads it: an entry read is not solved again)
    atlas = Atlas(left, posture=posture)
    assert atlas.entry_at(*some) is not None and atlas.solves == 0


@pytest.mark.parametrize("posture", range(3))
def test_the_left_move_table_is_the_right_one_mirrored(pair, posture) -> None:
    right, left = pair
    with np.load(moves_path(right.urdf_sha256, posture)) as zr, \
            np.load(moves_path(left.urdf_sha256, posture)) as zl:
        kr = _by_key(zr)
        for i, (f, pc, k) in enumerate(zl["key"].tolist()):
            j = kr[(f, mirrored_pitch_class(pc), -k)]
            a, b = zl["cross_s"][i], zr["cross_s"][j]
            assert np.array_equal(np.isnan(a), np.isnan(b))
            assert np.nanmax(np.abs(a - b), initial=0.0) < 1e-9
        for name in zl.files:
            if name.startswith("across_"):
                assert zl[name].shape == zr[name].shape, name
            elif name.startswith("follow_"):
                finger, pc = name.rsplit("_", 1)
                other = f"{finger}_{mirrored_pitch_class(int(pc))}"
                assert zl[name].shape == zr[other].shape, name


def _plan(song: str, hand, path):
    plan = planner.plan_song(planner.load_song(song), hand, str(path))
    return plan, check_trajectory(str(path), song)


@pytest.mark.parametrize("song", ["songs/twinkle.mid", "songs/scale.mid", "songs/leaps.mid"])
def test_the_left_hand_plays_as_well_as_the_right(pair, tmp_path, song) -> None:
    """Measured: check's frame F1 1.0 / 1.0 (twinkle), 0.9751 / 0.9859 (scale), 0.9931 /
    0.9931 (leaps), right / left, no wrong key."""
    right, left = pair
    got = {}
    for hand in (right, left):
        plan, rep = _plan(song, hand, tmp_path / f"{hand.name}.csv")
        assert rep.ok, rep.problems
        assert not rep.play.wrong_presses
        assert rep.play.f1 == pytest.approx(plan.verdict.score.f1, abs=1e-9)
        got[hand.name] = rep
    assert got[LEFT].play.f1 >= got[RIGHT].play.f1 - 0.01
    assert got[LEFT].play.notes_hit == got[RIGHT].play.notes_hit


def test_the_left_hand_fingers_a_scale_from_its_pinky_up(pair, tmp_path) -> None:
    """The scale C4..C5 and back: the right hand starts it with a finger nearer its thumb
    than the one that reaches the top, the left hand (its thumb on the treble side) the
    other way round."""
    for hand in pair:
        _, rep = _plan("songs/scale.mid", hand, tmp_path / f"{hand.name}.csv")
        played = rep.play.played
        low = FINGERS.index(min(played, key=lambda p: p.pitch).fingers[0])
        high = FINGERS.index(max(played, key=lambda p: p.pitch).fingers[0])
        assert (low < high) if hand.side == "right" else (low > high), hand.name


def test_the_left_hand_plays_in_physics(pair, tmp_path) -> None:
    """Full contact: measured physics F1 0.9979 (right) and 0.9959 (left) on twinkle."""
    pytest.importorskip("mujoco")
    from planner.simulate import simulate_trajectory

    f1 = {}
    for hand in pair:
        path = tmp_path / f"{hand.name}.csv"
        _plan("songs/twinkle.mid", hand, path)
        rep = simulate_trajectory(str(path), "songs/twinkle.mid")
        assert rep.ok, rep.problems
        assert not rep.play.wrong_keys
        f1[hand.name] = rep.play.f1
    assert f1[LEFT] >= 0.98 and f1[LEFT] >= f1[RIGHT] - 0.01


def test_the_left_hand_alone_reaches_the_bass_and_the_treble(pair, tmp_path) -> None:
    """Its rail's travel is the right hand's (one rail, a second carriage): from A0, the
    lowest key, through the low half of the keyboard, to C8, the highest."""
    from tests.midibytes import notes_track, smf

    pitches = [21, 22, 24, 28, 31, 35, 38, 41, 45, 48, 52, 55, 59, 62, 108]
    song = tmp_path / "bass.mid"
    song.write_bytes(smf(notes_track([(p, i * 960, i * 960 + 480, 80)
                                      for i, p in enumerate(pitches)])))
    plan, rep = _plan(str(song), pair[1], tmp_path / "bass.csv")
    assert plan.verdict.played == plan.verdict.notes == len(pitches)
    assert rep.ok and rep.play.notes_hit == len(pitches) and not rep.play.wrong_presses


def test_the_left_hands_physics_scene_is_the_right_ones_mirrored(pair) -> None:
    """The MuJoCo scene of each hand with the keyboard: every geom of the left hand where
    the right hand's is, reflected through the carriage's plane, with the same shape and
    size; the same servos (gains, the damping set from the compiled inertia)."""
    mujoco = pytest.importorskip("mujoco")
    from planner.simulate.scene import build_scene

    right = pair[0]
    scenes = [build_scene(h, h.T_world_root, keyboard=True) for h in pair]
    names = {b.name for b in collision_bodies(right.spec)}
    assert all(scenes[0].model.geom(n) is not None for n in names)
    for s in (1, 2):
        q = right.apply_couplings(np.random.default_rng(s).uniform(right.lower, right.upper))
        plane_x = right.frame_pose(q, "carriage")[0, 3]
        geoms = []
        for hand, sc in zip(pair, scenes):
            data = mujoco.MjData(sc.model)
            data.qpos[sc.hand_qpos] = q
            mujoco.mj_kinematics(sc.model, data)
            out = set()
            for g in range(sc.model.ngeom):
                p = data.geom_xpos[g].copy()
                if hand is right and sc.model.geom(g).name in names:  # (the hand's, not a key's)
                    p[0] = 2 * plane_x - p[0]
                out.add((int(sc.model.geom_type[g]), tuple(np.round(sc.model.geom_size[g], 9)),
                         tuple(np.round(p, 9))))
            geoms.append(out)
        assert len(geoms[0]) > 88 and geoms[0] == geoms[1]
    m_r, m_l = (sc.model for sc in scenes)
    assert np.array_equal(m_r.actuator_gainprm, m_l.actuator_gainprm)
    assert np.allclose(m_r.actuator_biasprm, m_l.actuator_biasprm, rtol=1e-9, atol=0)
