"""The palm's pad, one definition (``planner.hand.pad``): the hand file's ``[palm]
pad_give_m`` and ``pad_speed_m_s``, read by the catch planner, by ``check``'s ball stop and
by ``simulate``'s palm-ball contact."""

from dataclasses import replace

import numpy as np
import pytest

from planner.errors import InputError
from planner.hand.builders import load_hand_spec
from planner.hand.model import HandModel, load_hand
from planner.hand.pad import ASSUMED_PAD_GIVE_M, PalmPad, palm_pad

BALL_RADIUS_M, BALL_MASS_KG = 0.0335, 0.057  # a tennis ball (``planner.balls``)


def _padded(tmp_path, give_m: float, name: str = "padded"):
    """A hand file: the default hand with another pad give."""
    path = tmp_path / f"{name}.toml"
    path.write_text(f'extends = "default"\nname = "{name}"\n[palm]\npad_give_m = {give_m}\n')
    return path


def test_the_hand_files_name_the_pad(tmp_path):
    """Every shipped hand declares its pad (default-left by its ``extends``); a file without
    one has none (the planner's and check's give then ``ASSUMED_PAD_GIVE_M``); a give
    without its rated speed, or a number not positive, is refused."""
    for name in ("default", "default-left", "agh", "mk5"):
        h = load_hand(name)
        assert h.palm_pad == PalmPad(0.02, 8.0) and h.pad_give_m == 0.02, name
    assert palm_pad({"palm": {"length_m": 0.1}}) is None
    bare = HandModel(replace(load_hand_spec("default"), palm_pad=None))
    assert bare.palm_pad is None and bare.pad_give_m == ASSUMED_PAD_GIVE_M
    assert load_hand(str(_padded(tmp_path, 0.01))).pad_give_m == 0.01
    for palm in ({"pad_give_m": 0.02}, {"pad_give_m": 0.0, "pad_speed_m_s": 8.0},
                 {"pad_give_m": 0.02, "pad_speed_m_s": "fast"}):
        with pytest.raises(InputError, match="palm.pad_"):
            palm_pad({"palm": palm})
    assert PalmPad(0.02, 8.0).contact_time_s() == pytest.approx(np.e * 0.02 / 8.0)


def test_the_planner_and_the_check_stop_the_ball_over_the_hand_files_pad(tmp_path):
    """A hand whose pad gives 10 mm: the planner's file states it, its impact is the pad
    rule's m v^2 / 2d over 10 mm (twice the default pad's at the same speed), and ``check``
    judges a file planned for the default hand's 20 mm against this hand's pad."""
    from planner.catch.plan.api import get_planner, plan_throw, write_plan
    from planner.check import check_trajectory
    from planner.trajfile import read_trajectory

    soft = _padded(tmp_path, 0.01, "soft10")
    pl = get_planner(str(soft))
    assert pl.hand.pad_give_m == 0.01 and pl.base_hand.pad_give_m == 0.01
    p = plan_throw(30.0, 1.5, 0.0, planner=pl)
    out = tmp_path / "c10.csv"
    write_plan(p, str(out))
    assert read_trajectory(str(out)).metadata["catch"]["stop_distance_m"] == 0.01
    v = p.forces.contact.impact.speed_m_s
    assert p.forces.contact.impact.force_n == pytest.approx(BALL_MASS_KG * v * v / (2 * 0.01),
                                                            rel=0.1)
    p20 = plan_throw(30.0, 1.5, 0.0, planner=get_planner("default"))
    f20 = tmp_path / "c20.csv"
    write_plan(p20, str(f20))
    assert check_trajectory(str(f20)).ok
    hand10 = HandModel(replace(load_hand_spec("default"), palm_pad=PalmPad(0.01, 8.0)))
    rep = check_trajectory(str(f20), hand_override=hand10)  # (its URDF the default's)
    assert any("the plan stops the ball over 20 mm; the hand's pad gives 10 mm" in s
               for s in rep.problems), rep.problems


def _deepest_mm(hand: HandModel, speed_m_s: float) -> float:
    """A ball thrown at the still palm along its normal at ``speed_m_s``: how deep (mm) the
    replay's contact lets it into the palm over 60 ms (the hand held by its servos)."""
    import mujoco

    from planner.simulate.scene import Ball, build_scene

    scene = build_scene(hand, hand.T_world_root, ball=Ball((0.0, 0.0, 5.0), (0.0, 0.0, 0.0),
                                                           BALL_RADIUS_M, BALL_MASS_KG, 0.0, 0.4))
    m = scene.model
    d = mujoco.MjData(m)
    d.qpos[scene.hand_qpos] = hand.q_neutral
    d.ctrl[:] = hand.q_neutral[scene.servos.drive]
    mujoco.mj_forward(m, d)
    c, n = d.site_xpos[scene.palm_site].copy(), d.site_xmat[scene.palm_site].reshape(3, 3)[:, 2]
    adr = m.jnt_qposadr[m.joint("ball_free").id]
    d.qpos[adr:adr + 3] = c + (BALL_RADIUS_M + 0.002) * n
    d.qvel[m.jnt_dofadr[m.joint("ball_free").id]:][:3] = -speed_m_s * n
    deepest = 0.0
    for _ in range(60):
        mujoco.mj_step(m, d)
        c = d.site_xpos[scene.palm_site]
        n = d.site_xmat[scene.palm_site].reshape(3, 3)[:, 2]
        deepest = max(deepest, BALL_RADIUS_M - float((d.xpos[scene.ball_body] - c) @ n))
    return 1000 * deepest


def test_the_replays_palm_is_the_hand_files_pad():
    """The replay's palm-ball contact is the declared pad: a ball at the pad's rated speed
    sinks about its give into the palm (the arm's own give adds little), at half the speed
    about half of it (measured: 19.2 mm at 8 m/s, 8.8 mm at 4 m/s); a hand without a pad
    keeps the rigid palm (6.0 mm at 8 m/s), and a scene without a ball has no pair."""
    pytest.importorskip("mujoco")
    h = load_hand("default")
    deep = _deepest_mm(h, 8.0)
    assert 15.0 < deep < 25.0, deep
    assert 0.35 < _deepest_mm(h, 4.0) / deep < 0.65
    bare = HandModel(replace(h.spec, palm_pad=None))
    assert _deepest_mm(bare, 8.0) < 10.0  # (measured: 6.0 mm rigid, 19.2 mm on the pad)
    from planner.simulate.scene import build_scene

    assert build_scene(h, h.T_world_root).model.npair == 0  # (no ball: a play's scene)
