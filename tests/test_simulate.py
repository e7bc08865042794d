"""The physics replay (planner.simulate): scene, keys, servos, a real plan, edited plans."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

import planner
from planner.check import check_trajectory, key_contacts
from planner.cli import main
from planner.hand.model import HandModel, load_hand
from planner.music import keyboard as kb
from planner.simulate import simulate_trajectory
from planner.simulate.keyboard import front_force_n, key_bodies, key_body
from planner.simulate.scene import build_scene
from planner.trajfile import read_trajectory, song_start_s
from tests.trajbuild import write_traj

SONG = "songs/twinkle.mid"


@pytest.fixture(scope="module")
def hand():
    return load_hand("default")


@pytest.fixture(scope="module")
def twinkle(tmp_path_factory, hand):
    path = tmp_path_factory.mktemp("sim") / "twinkle.csv"
    planner.plan_song(planner.load_song(SONG), hand, str(path))
    return path


def _write(path, tr, q, hand, end=None, t=None):
    """``tr`` with the rows ``q`` (at ``t``), written without the writer's guard: these
    files are made to fail in physics (a press cut short, rows out of the limits)."""
    write_traj(path, hand, tr.t_s if t is None else t, q,
               metadata={k: v for k, v in tr.metadata.items() if k not in ("format", "version")},
               end_info=end if end is not None else {k: v for k, v in tr.end.items()
                                                     if k not in ("end", "rows")})
    return path


def _random_kinematics(hand, scene, seed: int, n: int):
    """``n`` random configurations of ``hand`` (couplings applied) set in ``scene``, each
    with MuJoCo's kinematics done: (q, data)."""
    data = mujoco.MjData(scene.model)
    rng = np.random.default_rng(seed)
    for _ in range(n):
        q = hand.apply_couplings(rng.uniform(hand.lower, hand.upper))
        data.qpos[scene.hand_qpos] = q
        mujoco.mj_kinematics(scene.model, data)
        yield q, data


def test_scene_pad_points_are_the_urdf_pad_points(hand):
    scene = build_scene(hand, hand.T_world_root, keyboard=True)
    for q, data in _random_kinematics(hand, scene, seed=1, n=5):
        assert np.allclose(data.site_xpos[scene.tip_sites], hand.tip_positions(q), atol=1e-9)
    assert scene.model.nu == hand.n_motor and scene.model.neq == len(hand.couplings)
    assert len(scene.key_qpos) == 88


def test_servo_limits_are_the_motors_through_their_transmission(hand):
    scene = build_scene(hand, hand.T_world_root)
    m = hand.motor_names.index("index_pip")
    ratio = 2.2 + 1.5 * 0.667  # spool over PIP and DIP moment arms, DIP coupled
    assert scene.model.actuator_forcerange[m, 1] == pytest.approx(0.4 * ratio * 0.5, rel=1e-3)
    assert scene.model.actuator_forcerange[hand.motor_names.index("rail"), 1] == \
        pytest.approx(200.0)  # 2 N m through a 10 mm pulley



def test_reflected_rotor_inertia_is_each_motors_own():
    """The armature is the motor's rotor (the hand file's, seed 002's data sheets) times
    the transmission ratio squared: the AGH's end joints are 3564 B motors through a 20:1
    worm (34.9 g cm^2 x 400), its shafts 4490 B (130 g cm^2); the default hand's tendon
    motors 3564 B, its wrist 4490 B through 2:1. (The AGH's end joints once got the 4490
    B's rotor, 3.7x theirs, and its thumb fell behind its plan in physics.)"""
    from planner.simulate.actuators import servo_set

    agh = load_hand("agh")
    s = servo_set(agh)
    assert s.armature[agh.motor_names.index("thumb_end")] == pytest.approx(34.9e-7 * 20 ** 2)
    assert s.armature[agh.motor_names.index("shaft_near")] == pytest.approx(130e-7 * 20 ** 2)
    d = load_hand("default")
    s = servo_set(d)
    assert s.armature[d.motor_names.index("wrist_flex")] == pytest.approx(130e-7 * 2 ** 2)
    r = abs(d.motor_ratio(d.q_neutral)[d.motor_names.index("index_mcp")])
    assert s.armature[d.motor_names.index("index_mcp")] == pytest.approx(34.9e-7 * r ** 2)
    assert s.armature[d.motor_names.index("index_abd")] == 0.0  # servo: not documented


def test_key_geometry_down_travel_and_down_weight():
    for k in key_bodies():  # the spec's key: 5 mm down sounds, the bed 10 mm down
        assert (k.down_m, k.dip_m) == (kb.DOWN_DEPTH_M, kb.KEY_DIP_M) == (0.005, 0.010)
        assert front_force_n(k, 0.0) == pytest.approx(0.5)
        assert front_force_n(k, k.dip_m) == pytest.approx(0.5 + 0.010 * 2.0 / 0.15 ** 2)
    c4, cs4 = key_body(60), key_body(61)
    front, back = c4.boxes  # C4's back part ends where C#4 begins
    assert 2 * front.half_m[0] == pytest.approx(kb.WHITE_WIDTH_M)
    assert 2 * back.half_m[0] == pytest.approx(kb.key(61).x_min_m - kb.key(60).x_min_m)
    assert cs4.boxes[0].center_m[2] + cs4.boxes[0].half_m[2] == pytest.approx(kb.BLACK_TOP_Z_M)
    # both stand on the key frame: the black key's sides wall the slot down to it
    for b in (front, back, cs4.boxes[0]):
        assert b.center_m[2] - b.half_m[2] == pytest.approx(-kb.WHITE_WIDTH_M)


def test_key_rests_up_and_returns_from_its_bed(hand):
    scene = build_scene(hand, hand.T_world_root, keyboard=True)
    model, data = scene.model, mujoco.MjData(scene.model)
    data.qpos[scene.hand_qpos] = hand.q_neutral
    k = 60 - 21
    adr = scene.key_qpos[k]
    mujoco.mj_forward(model, data)
    for _ in range(200):
        mujoco.mj_step(model, data)
    assert abs(data.qpos[adr]) < 1e-4  # held up by its preload
    data.qpos[adr] = key_body(60).dip_m
    steps = 0
    while data.qpos[adr] >= key_body(60).down_m:
        mujoco.mj_step(model, data)
        steps += 1
    # spring and critical damping bring it above the key-down travel in 10-40 ms
    assert 10 <= steps * model.opt.timestep * 1000 <= 40


def test_real_plan_in_physics(twinkle, capsys):
    # (full contact, the verdict: the keys go down under the bodies the plan is timed to;
    # a press shifted across its key puts the pad's body, not its point, at 5 mm, so the
    # pads-only model no longer presses every key: twinkle 0.7451 by the pad points)
    rep = simulate_trajectory(str(twinkle), SONG)
    assert rep.ok, rep.problems
    assert rep.play.f1 >= 0.99 and not rep.play.wrong_keys
    assert rep.play.notes_hit == rep.play.notes == 14
    assert rep.kinematic_f1 == pytest.approx(1.0, abs=1e-4)
    track = {j.name: j for j in rep.tracking}
    assert track["rail"].max_error < 0.002  # m
    # the rig's axes in m (their lines in mm), the others in rad (deg)
    assert {n for n, j in track.items() if j.unit == "m"} == {"rail", "reach"}
    assert {j.unit for n, j in track.items() if n not in ("rail", "reach")} == {"rad"}
    lines = {ln.split()[0]: ln for ln in rep.summary().splitlines()
             if ln.startswith("  ") and ln.split()[0] in track}
    assert " mm " in lines["reach"] and " mm " in lines["rail"] and " deg " in lines["wrist_flex"]
    rc = main(["simulate", str(twinkle), SONG, "--contact", "pads", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert {j["name"]: j["unit"] for j in out["tracking"]}["reach"] == "m"
    assert out["command"] == "simulate" and out["play"]["notes"] == 14
    assert set(out) >= {"play", "motors", "tracking", "problems", "kinematic_f1",
                        "realtime_factor"}
    assert rc == (0 if out["ok"] else 1)


def test_coupling_holds_in_physics(twinkle, hand):
    from planner.simulate.replay import simulate

    tr = read_trajectory(str(twinkle))
    scene = build_scene(hand, hand.T_world_root, keyboard=True, contact="pads")
    rec = simulate(scene, hand, tr.t_s[:200], tr.q[:200])
    err = hand.coupling_errors(rec.q_sim)
    # the equality constraint (as stiff as a contact): 1 deg at worst, while a pad pushes
    # its key into the bed, well under 0.1 deg on average
    assert np.max(np.abs(err)) < 0.025 and np.sqrt(np.mean(err ** 2)) < 2e-3


def test_wrist_beyond_its_motor_is_caught_by_the_physics_and_the_check(twinkle, hand,
                                                                     tmp_path):
    """The wrist swung sideways at its speed and acceleration limits: within every
    kinematic limit, beyond what its motor gives to the hand's inertia. The physics finds
    the motor short of torque; so does ``check`` since it counts the hand's inertia on a
    play (before, it judged static torques and passed this plan)."""
    tr = read_trajectory(str(twinkle))
    i = hand.index["wrist_dev"]
    q = np.repeat(tr.q[:1], 150, axis=0)  # the first pose held (no key down after 10 ms)
    q[:, hand.index["index_mcp_flex"]] = q[0, hand.index["middle_mcp_flex"]]
    q[:, hand.index["index_pip"]] = q[0, hand.index["middle_pip"]]
    q = hand.apply_couplings(q)
    t = np.arange(len(q)) / 100.0
    v, a = 0.97 * hand.velocity[i], 0.97 * hand.acceleration[i]
    w = a / v
    amp = v / w
    # (speed v and acceleration a at most, about a pose the swing keeps within the wrist's
    # planning limits: the rest pose's deviation, +15 deg, is within 11.8 deg of its stop)
    mid = np.clip(q[0, i], hand.plan_lower[i] + amp, hand.plan_upper[i] - amp)
    q[:, i] = mid - amp * np.sin(w * t)
    tr2 = read_trajectory(str(_write(tmp_path / "wrist.csv", tr, q, hand, end={}, t=t)))
    kin = check_trajectory(tr2)
    assert all(lc.count == 0 for lc in kin.limits if lc.category != "motor_torque")
    torque = next(lc for lc in kin.limits if lc.category == "motor_torque")
    assert not kin.ok and torque.name == "motor.wrist_dev" and torque.worst > torque.limit
    rep = simulate_trajectory(tr2, contact="pads")
    assert not rep.ok
    assert any("motor.wrist_dev short of torque" in p for p in rep.problems)
    wd = next(m for m in rep.motors if m.name == "motor.wrist_dev")
    assert wd.ratio > 1.0 and wd.saturated_s > 0.02
    rc = main(["simulate", str(tmp_path / "wrist.csv"), "--contact", "pads"])
    assert rc == 1


def test_shallow_press_misses_in_physics(twinkle, hand, tmp_path):
    """Note 2 (G4, ring) pressed only 1.5 mm below the key's top: short of the key-down
    travel (5 mm), the note the plan claims played is missed in physics (exit 1)."""
    tr = read_trajectory(str(twinkle))
    tips = np.array([hand.tip_positions(r) for r in tr.q])
    kc = key_contacts(tips)
    f = 3  # ring
    k = 67 - 21
    rows = np.flatnonzero((kc.tip_key[:, f] == k) & (kc.tip_depth[:, f] > 0.0015))
    assert len(rows) > 20
    hover = tr.q[rows[0] - 1]
    js = hand.joint_slice("ring")
    q = tr.q.copy()
    for r in rows:
        lo, hi = 0.0, 1.0
        for _ in range(40):  # the blend of hover -> press that puts the pad 1.5 mm down
            mid = 0.5 * (lo + hi)
            qq = q[r].copy()
            qq[js] = hover[js] + mid * (tr.q[r, js] - hover[js])
            depth = -hand.tip_positions(qq)[f, 2]  # (a white key's top is z = 0)
            lo, hi = (mid, hi) if depth < 0.0015 else (lo, mid)
        q[r, js] = hover[js] + lo * (tr.q[r, js] - hover[js])
    path = _write(tmp_path / "shallow.csv", tr, q, hand)
    rep = simulate_trajectory(str(path), SONG, contact="pads")
    assert any(m.pitch == 67 and m.note == 2 for m in rep.play.missed)
    assert not rep.ok and any("claims played are missed" in p for p in rep.problems)


def test_a_repeated_key_rises_between_its_presses(tmp_path):
    """Chords' F4 at 2.40 s and again at 3.60 s: between them the plan lifts the finger's
    body to ``REARM_M`` (0.5 mm) above the 5 mm key-down travel; the spec's key follows it
    up past that travel (the first, hinged key model kept its front 5.6 mm down there:
    the second note never sounded) and sounds again at 3.60 s."""
    song = "songs/chords.mid"
    path = tmp_path / "chords.csv"
    planner.plan_song(planner.load_song(song), load_hand("default"), str(path))
    from planner.simulate import run_replay

    r = run_replay(str(path), song)  # (full contact: the finger's body presses)
    rec, k = r.record, 65 - 21
    t = rec.t_s - song_start_s(read_trajectory(str(path)).metadata)  # (the song's time)
    between = (t > 3.40) & (t < 3.60)
    assert np.any(rec.key_dip_m[between, k] < key_body(65).down_m)
    assert np.all(rec.key_dip_m[(t >= 3.61) & (t < 3.9), k] >= key_body(65).down_m)
    assert not any(m.pitch == 65 and abs(m.onset_s - 3.6) < 1e-6
                   for m in (*r.report.play.missed, *r.report.play.late))


def test_legato_repeats_sound_every_note_in_physics(tmp_path):
    """Eight legato quavers on one key (C5, 200 ms each, each ending where the next
    starts): every repeat is one bounce (``Moves.repeat``), its key up 10-11 ms in the rows;
    the check sees it up in at most 2 rows of each junction (3 with the lift and descent
    from rest to the atlas's rise pose before). In the physics replay (full contact) the
    key is up between every two notes and down again for each (8 key-downs): 8 notes
    hit, none late, no wrong key, the key up at most 3 rows at each junction."""
    from planner.music.midi import Note, Song
    from planner.simulate import run_replay

    notes = tuple(Note(72, round(0.5 + 0.2 * i, 9), round(0.7 + 0.2 * i, 9), 80)
                  for i in range(8))
    song = Song(notes, notes[-1].offset_s, source="repeats.mid")
    path = tmp_path / "repeats.csv"
    planner.plan_song(song, load_hand("default"), str(path))
    kin = check_trajectory(str(path), song)
    assert kin.ok and kin.play.notes_hit == 8, kin.summary()
    r = run_replay(str(path), song)
    play = r.report.play
    assert play.notes_hit == 8 and not play.late and not play.missed and not play.wrong_keys
    assert sum(ep.pitch == 72 for ep in play.played) == 8  # (each note its own key-down)
    k, rec = 72 - 21, r.record
    t = rec.t_s - song_start_s(read_trajectory(str(path)).metadata)
    down_phys = rec.key_dip_m[:, k] >= key_body(72).down_m
    down_kin = kin.replay.down[:, k]
    for n in notes[1:]:
        near = (t > n.onset_s - 0.06) & (t < n.onset_s + 0.06)
        assert 1 <= np.sum(~down_kin[near]) <= 2
        assert 1 <= np.sum(~down_phys[near]) <= 3


def test_missing_mujoco_is_one_line_exit_2(twinkle, monkeypatch, capsys):
    import builtins

    real = builtins.__import__

    def no_mujoco(name, *a, **k):
        if name == "mujoco":
            raise ImportError("no mujoco")
        return real(name, *a, **k)

    monkeypatch.setattr(builtins, "__import__", no_mujoco)
    rc = main(["simulate", str(twinkle)])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1 and "pip install" in err


def test_bad_input_exit_2(tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    bad.write_text("not a trajectory\n")
    assert main(["simulate", str(bad)]) == 2
    assert capsys.readouterr().err.count("\n") == 1


# ------------------------------------------------------------------ catch


@pytest.fixture(scope="module")
def catch30(tmp_path_factory):
    path = tmp_path_factory.mktemp("simcatch") / "c30.csv"
    res = planner.plan_catch(30.0, 1.5, 0.0, "default", str(path))
    assert res.feasible
    return path


def test_scene_palm_centre_and_palm_box(hand):
    """The palm site is the URDF's palm_center (it was on the mount: an empty body is a
    falsy Element); the palm and forearm collide as their boxes, not as capsules."""
    scene = build_scene(hand, hand.T_world_root)
    for q, data in _random_kinematics(hand, scene, seed=2, n=3):
        T = hand.palm_pose(q)
        assert np.allclose(data.site_xpos[scene.palm_site], T[:3, 3], atol=1e-9)
        assert np.allclose(data.site_xmat[scene.palm_site].reshape(3, 3), T[:3, :3], atol=1e-9)
    for name in ("palm_box", "forearm_box"):
        assert scene.model.geom(name).type == mujoco.mjtGeom.mjGEOM_BOX
    assert 2 * scene.model.geom("palm_box").size[0] == pytest.approx(5.25 * 0.0254)  # palm width


def test_the_physics_ball_has_the_file_balls_inertia(catch30, hand):
    """The spec's ``ball`` has radius and mass, not inertia: ``file_inertia_ratio`` takes the
    ball the plan names when radius and mass are that ball's (the seed's: a tennis ball's
    shell, 0.61), else the default ball's; the physics ball is given it (MuJoCo's geom would
    make it a solid sphere, 0.4, and it rolls further on the palm)."""
    from planner.balls import BALLS, file_inertia_ratio
    from planner.simulate.scene import Ball as SimBall

    meta = read_trajectory(str(catch30)).metadata
    seed = BALLS["seed"]  # the default ball (get_ball(None))
    assert meta["catch"]["throw"]["ball"] == "tennis"
    assert file_inertia_ratio(meta) == BALLS["tennis"].inertia_ratio == 0.61
    base = {"ball": {"radius": BALLS["baseball"].radius_m, "mass": BALLS["baseball"].mass_kg},
            "catch": {"throw": {"ball": "baseball"}}}
    assert file_inertia_ratio(base) == 0.4
    base["ball"]["mass"] = 0.2  # not the named ball's mass: the default ball's inertia
    assert file_inertia_ratio(base) == seed.inertia_ratio
    assert file_inertia_ratio({}) == seed.inertia_ratio
    ball = SimBall((0.0, 0.0, 1.0), (0.0, 0.0, 0.0), seed.radius_m, seed.mass_kg, 0.0, 0.61)
    model = build_scene(hand, hand.T_world_root, ball=ball).model
    body = model.body("ball")
    assert body.mass[0] == pytest.approx(seed.mass_kg)
    assert np.allclose(body.inertia, 0.61 * seed.mass_kg * seed.radius_m ** 2, rtol=1e-9)


def test_catch_in_physics_held_motors_within_peak(catch30, capsys):
    """The 30 deg / 1.5 m catch is held in physics: the contact speeds leave the ball no
    roll along the palm, the wrist turns the closed hand so that the palm's downhill points
    5 deg into the fingers (``planner.catch.plan.holdturn.hold_turn``); the servos stay within
    their motors, never saturated; the impact is taken by the palm's pad (the hand file's,
    ``planner.hand.pad``): on the same hand with a rigid palm the ball stops within a few 1 ms
    steps (a force far above the one the plan spreads over 2 cm of pad: measured 195 N),
    on the pad at less than half of that (measured 56.8 N: a critically damped pad's first
    push 2 m v / tau at 3.5 m/s). (Before the hold: not held, 76 mm from the palm centre at
    the end.)"""
    rep = simulate_trajectory(str(catch30))
    assert rep.task == "catch" and rep.catch is not None
    assert all(m.ratio < 1.0 and m.saturated_s == 0.0 for m in rep.motors), \
        [(m.name, m.ratio) for m in rep.motors]
    ball = rep.catch
    rigid = HandModel(replace(load_hand("default").spec, palm_pad=None))
    hard = simulate_trajectory(str(catch30), hand_override=rigid).catch
    assert hard.peak_contact_force_n > 0.057 * 4.05 / 0.004  # stopped within 4 ms
    assert ball.peak_contact_force_n < 0.5 * hard.peak_contact_force_n
    assert ball.held and ball.end_distance_m < 2 * 0.0335 + 0.010 and ball.contacts_at_end >= 1
    assert rep.problems == ()
    assert main(["simulate", str(catch30), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["catch"]["held"] is True and out["ok"] is True


def test_closing_fingers_do_not_press_the_ball_in_physics(tmp_path):
    """40 deg / 2.0 m: the closed fingers' bodies (pad spheres, segments) are planned
    ``BODY_CLEAR_M`` outside the ball, so no finger's servo presses the rigid ball and no
    motor is ever short of torque. (With the fingertips' closing alone the middle and ring
    pads were 3.4-3.6 mm inside the ball: ``motor.ring_mcp`` short of torque for 20 ms,
    0.49 of 0.40 N m, middle MCP/PIP 10 ms.)"""
    path = tmp_path / "c40.csv"
    assert planner.plan_catch(40.0, 2.0, 0.0, "default", str(path)).feasible
    rep = simulate_trajectory(str(path))
    assert rep.catch is not None and rep.catch.held
    assert all(m.saturated_s == 0.0 for m in rep.motors), \
        [(m.name, m.peak_demand_nm, m.saturated_s) for m in rep.motors if m.saturated_s]
    assert rep.problems == ()


def test_ball_advanced_is_the_same_flight_later(catch30, tmp_path):
    """``phase.ball_advanced``: the same rows, the ball at every time where the file's
    would be dt later (without drag and with it); a negative dt is refused."""
    from planner.check.ball import ball_params, ball_positions
    from planner.errors import InputError
    from planner.simulate.phase import ball_advanced

    tr = read_trajectory(str(catch30))
    t = np.linspace(0.0, 0.6, 13)
    for drag in (0.0, 0.5):
        meta = {**tr.metadata, "ball": {**tr.metadata["ball"], "drag": drag}}
        base = ball_params(meta, "x")
        for dt in (0.0, 0.37e-3, 0.9e-3):
            adv = ball_advanced(replace(tr, metadata=meta), dt)
            b = ball_params(adv.metadata, "x")
            assert np.array_equal(adv.q, tr.q) and np.array_equal(adv.t_s, tr.t_s)
            assert np.allclose(ball_positions(b["p0"], b["v0"], drag, t),
                               ball_positions(base["p0"], base["v0"], drag, t + dt),
                               atol=1e-9 if drag == 0.0 else 1e-7)
    with pytest.raises(InputError):
        ball_advanced(tr, -1e-4)


def test_held_catch_whatever_the_contact_phase(catch30):
    """The 30 deg / 1.5 m plan is held whatever the sub-step phase at which its ball meets
    the near-rigid palm: launched 0, 1/4, 1/2, 3/4 of a physics step later along its flight,
    its first contact is 0-3.5 mm deep and its rebound off the palm 0-0.9 m/s (250/s x that
    depth: ``planner.simulate.phase``), and the ball is held at every one."""
    from planner.simulate import run_replay
    from planner.simulate.phase import ball_advanced
    from planner.simulate.scene import TIMESTEP_S

    tr = read_trajectory(str(catch30))
    for k in range(4):
        r = run_replay(ball_advanced(tr, 0.25 * k * TIMESTEP_S))
        assert r.report.catch.held, (k, r.report.catch)
        assert r.report.problems == (), (k, r.report.problems)


def _ball_in_closed_hand(catch30, tmp_path, wrist_m: float, tilt_to_wrist_deg=None):
    """The catch file's last pose (the closed hand after the wrist's turn) held 0.6 s, the
    ball at rest on the palm centre moved ``wrist_m`` along the palm towards the wrist (the
    palm's +y); ``tilt_to_wrist_deg``: the wrist flexion instead set so that the palm's
    downhill points that far towards the wrist (as the palm met the ball: 30-73 deg)."""
    from planner.catch.plan.api import get_planner
    from planner.catch.plan.holdturn import best_flex

    tr = read_trajectory(str(catch30))
    hand = load_hand("default")
    T = np.array(tr.metadata["T_world_root"])
    q_hold = tr.q[-1].copy()
    if tilt_to_wrist_deg is not None:
        pl = get_planner("default")
        i = pl.joints.i_flex
        f = best_flex(pl.hand, q_hold, i, np.linspace(hand.lower[i], hand.upper[i], 400),
                       np.sin(np.radians(tilt_to_wrist_deg)))
        q_hold[i] = f
    scene = build_scene(hand, T)
    data = mujoco.MjData(scene.model)
    data.qpos[scene.hand_qpos] = q_hold
    mujoco.mj_kinematics(scene.model, data)
    R = data.site_xmat[scene.palm_site].reshape(3, 3)
    r = tr.metadata["ball"]["radius"]
    p0 = data.site_xpos[scene.palm_site] + r * R[:, 2] + wrist_m * R[:, 1]
    meta = {k: v for k, v in tr.metadata.items() if k not in ("format", "version")}
    meta["ball"] = {**meta["ball"], "p0": [float(v) for v in p0], "v0": [0.0, 0.0, 0.0]}
    meta["intercept_t"] = 0.0
    n = 61
    q = np.repeat(q_hold[None], n, axis=0)
    path = tmp_path / f"rest_{wrist_m}_{tilt_to_wrist_deg}.csv"
    # (unguarded: q_hold is a row as the file holds it, rounded to 6 decimals, which may
    # lie a fraction of a micro-radian past a limit the planner's own row met)
    write_traj(path, hand, np.arange(n) / 100.0, q, metadata=meta, end_info={})
    return simulate_trajectory(str(path)).catch


def test_ball_at_rest_in_the_held_pose_rolls_into_the_fingers(catch30, tmp_path):
    """What holds the ball is the closed fingers' cage with the palm's downhill into it: in
    the plan's last pose a ball placed at rest on the palm centre, or 10 mm towards the
    wrist (where it has rolled by the time the fingers close), rolls into the fingers and
    stays; the same closed hand with the palm's downhill 30 deg towards the wrist (as the
    palm meets the ball) lets the ball 10 mm towards the wrist touch no finger: it rolls
    off the open wrist side and leaves the hand."""
    at = _ball_in_closed_hand(catch30, tmp_path, 0.0)
    assert at.held and at.contacts_at_end >= 2 and at.end_distance_m < 0.0335 + 0.010
    wrist = _ball_in_closed_hand(catch30, tmp_path, 0.010)
    assert wrist.held and wrist.contacts_at_end >= 2
    tilted = _ball_in_closed_hand(catch30, tmp_path, 0.010, tilt_to_wrist_deg=30.0)
    assert not tilted.held and tilted.end_distance_m > 0.1


def test_note_differences_add_up_to_the_f1_difference(twinkle):
    """compare.note_differences: the notes' shares sum to kinematic F1 - physics F1; in
    pads contact twinkle's difference is key timing only (late onsets, keys returning),
    no wrong key (since the rows start from rest, there is none: physics F1 = kinematic)."""
    from planner.simulate import run_replay
    from planner.simulate.compare import note_differences

    r = run_replay(str(twinkle), SONG, contact="pads")
    diffs = note_differences(r)
    total = r.report.kinematic_f1 - r.report.play.f1
    assert total >= 0 and sum(d.lost_f1 for d in diffs) == pytest.approx(total, abs=1e-12)
    assert all(d.note >= 0 for d in diffs)  # every difference belongs to a note
    assert all(d.onset_frames + d.release_frames + d.middle_frames > 0 for d in diffs)


def test_full_contact_finds_no_press_narrower_than_the_finger(twinkle):
    """Full contact: twinkle's white keys are pressed in front of the black keys (before
    session 37 its G4 at 1.20 s was pressed by the ring 127 mm back, between F#4 and G#4
    where G4 is 13.5 mm wide, with a finger end 21.4 mm wide: 'narrow', its black
    neighbours sounding as wrong keys). Today no difference is 'narrow' and no key sounds
    wrongly; what physics loses against the check is each note's own timing."""
    from planner.simulate import run_replay
    from planner.simulate.compare import note_differences

    r = run_replay(str(twinkle), SONG, contact="full")
    diffs = note_differences(r)
    total = r.report.kinematic_f1 - r.report.play.f1
    assert sum(d.lost_f1 for d in diffs) == pytest.approx(total, abs=1e-12)
    assert not any(d.kind in ("narrow", "wrong") for d in diffs)
    assert not r.report.play.wrong_keys and r.report.play.f1 >= 0.98


def test_a_four_finger_hand_replays(tmp_path):
    """The agh hand has four fingers: its play and catch files replay (the record's pad
    points, the fingers touching keys and the motors' fingers are the hand's own, not five:
    the replay raised IndexError / KeyError 'pinky' before)."""
    song = tmp_path / "s.mid"
    from planner.music.midi import Note, write_notes_midi

    write_notes_midi([Note(60 + 2 * i, 0.5 * i, 0.5 * i + 0.4, 80) for i in range(4)], str(song))
    play = tmp_path / "p.csv"
    assert main(["play", str(song), "--hand", "agh", "-o", str(play)]) == 0
    rep = simulate_trajectory(str(play), str(song))
    assert rep.task == "play" and rep.song is not None
    # its index presses white keys with its body clear (hands/agh.toml): the keys it
    # plays go down in physics as in the kinematic check, no wrong key
    assert len(rep.play.played) > 0 and not rep.play.wrong_keys
    assert abs(rep.play.f1 - rep.kinematic_f1) <= 0.05
    assert [m.name for m in rep.motors] == [f"motor.{m}" for m in load_hand("agh").motor_names]
    assert not any("pinky" in m.name for m in rep.motors)
    catch = tmp_path / "c.csv"
    assert planner.plan_catch(30.0, 1.5, 0.0, "agh", str(catch)).feasible
    from planner.simulate import run_replay

    r = run_replay(str(catch))
    rep = r.report
    assert rep.catch is not None and rep.catch.peak_contact_force_n > 0
    # held; its end motors stall on the ball as they grip it (a 20:1 worm's servo gives
    # its peak 0.4 mm into the ball at the tip), which is the grip, not a motor short of
    # torque: the fingers touching the ball are recorded and their motors excepted (its
    # index end motor was reported short for 380 ms before)
    assert rep.catch.held and rep.ok, rep.problems
    after = r.record.t_s > float(r.trajectory.metadata["intercept_t"]) + 0.15
    assert r.record.ball_fingers.shape == (len(r.record.t_s), 4)
    # the thumb holds the ball to the end (the index, its body as wide as the seed's
    # finger, is closed 1.5 mm clear of the ball by the catch planner: it does not touch)
    thumb = r.hand.fingers.index("thumb")
    assert r.record.ball_fingers[after, thumb].all()
