"""Keyboard surfaces and press targets of the IK module (planner/ik.py)."""

from planner.ik import exposed_range_x, press_target
from planner.music import keyboard as kb


def test_exposed_range_of_white_keys_lies_between_their_black_neighbours():
    lo, hi = exposed_range_x(62)  # D4: between C#4 and D#4
    assert lo == kb.key(61).x_max_m and hi == kb.key(63).x_min_m
    lo, hi = exposed_range_x(64)  # E4: no black key above
    assert lo == kb.key(63).x_max_m and hi == kb.key(64).x_max_m
    assert exposed_range_x(61) == (kb.key(61).x_min_m, kb.key(61).x_max_m)  # a black key: itself


def test_press_targets_are_on_their_keys_at_full_dip():
    for pitch in range(kb.LOWEST_PITCH, kb.HIGHEST_PITCH + 1):
        k = kb.key(pitch)
        for finger in ("thumb", "index"):
            t = press_target(finger, pitch)
            x, y, z = t.point_m
            assert k.x_min_m <= x <= k.x_max_m and z == k.top_z_m - kb.KEY_DIP_M
            assert k.y_min_m <= t.y_range_m[0] <= y <= t.y_range_m[1] <= k.y_max_m


def test_the_thumb_presses_every_black_key_within_its_reach(tmp_path):
    """The thumb is short: the IK (through the atlas, which solves with it) puts it on
    every black key from some hand position within 1 mm, pressing no nearer the key's
    front than 8 mm, wherever the rail lets it. (It once stopped 5 mm short on every
    one: its press range began 15 mm behind the front, out of its reach.) On the default
    hand without its play posture (the tip rule: its thumb has no body-clear press)."""
    from planner.ik import PRESS_TOL_M, THUMB_BLACK_EDGE_M
    from planner.play.atlas import SPAN_M, STEP_M, Atlas
    from tests.handfiles import fitted_text, load_text

    hand = load_text(tmp_path, fitted_text())
    atlas = Atlas(hand)
    rail = hand.joint_names.index("rail")
    f = hand.fingers.index("thumb")
    tried = 0
    for pitch in kb.ALL_PITCHES:
        x0 = kb.key(pitch).center_x_m - atlas.natural_dx["thumb"]
        if not kb.is_black(pitch) or not hand.lower[rail] + SPAN_M <= x0 <= hand.upper[rail] - SPAN_M:
            continue
        n = round(SPAN_M / STEP_M)
        found = [(x, e) for k in range(-n, n + 1)
                 if (e := atlas.entry("thumb", pitch, x := x0 + k * STEP_M)) is not None]
        assert found, pitch
        t = press_target("thumb", pitch)
        for x, e in found:
            tip = hand.tip_positions(atlas.full_q(e, "press", x))[f]
            assert abs(tip[0] - t.point_m[0]) <= PRESS_TOL_M + 1e-9
            assert abs(tip[2] - t.point_m[2]) <= PRESS_TOL_M + 1e-9
            assert tip[1] >= kb.BLACK_Y0_M + THUMB_BLACK_EDGE_M - 0.001
        tried += 1
    assert tried >= 30


def test_solve_palm_returns_a_start_that_meets_the_task_unchanged():
    """A warm start already within tolerance (the catch's closed form) takes no iteration
    and comes back as it went in; one 5 cm off along the rail is solved by iterating."""
    import numpy as np

    from planner.catch.plan.api import get_planner

    pl = get_planner("default")
    h, q = pl.hand, pl.q_rest.copy()
    T = h.palm_pose(q)
    point, n = T[:3, 3] + 0.03 * T[:3, 2], T[:3, 2]
    res = pl.ik.solve_palm(point, n, q, q, offset_m=0.03, max_iter=5)
    assert res.converged and res.iterations == 0
    np.testing.assert_array_equal(res.q, h.apply_couplings(np.clip(q, h.lower, h.upper)))
    moved = pl.ik.solve_palm(point + np.array([0.0, 0.05, 0.0]), n, q, q, offset_m=0.03,
                             max_iter=20)
    assert moved.iterations > 0 and moved.converged and moved.press_error_m < 0.001  # (rail)


def test_a_solve_that_cycles_ends_where_every_step_taken_ends():
    """``HandIK.solve`` stops stepping once a configuration comes back bit for bit (the
    steps then cycle): the catch's closing targets (the arm locked, the fingertips partly
    out of reach) cycle well before ``max_iter``, and the configuration, error and
    iterations returned are those of taking all ``max_iter`` steps one by one."""
    import numpy as np

    from planner.catch.plan.api import get_planner
    from planner.catch.plan.arm import zero_pose
    from planner.ik import HandIK, PressTarget

    pl = get_planner("default")
    h = pl.hand
    ik = HandIK(h)
    q0 = zero_pose(h)
    for i in pl.joints.flexion_idx:
        q0[i] = 0.5 * (h.lower[i] + h.upper[i])
    q0 = h.apply_couplings(np.clip(q0, h.lower, h.upper))
    centre = pl.wrist.pc0 + 0.0335 * pl.wrist.n0
    tips = h.tip_positions(q0)
    presses = [PressTarget(f, 0, tuple(p), (p[1], p[1]))  # 3.6 cm from the centre
               for f, p in zip(h.fingers, centre + 0.0365 * (tips - centre) /
                               np.linalg.norm(tips - centre, axis=1)[:, None])]
    for n in pl.joints.locked:
        ik.solver.mask_dof(n)
    steps = []
    solve_step = ik.solver.solve

    def counted(apply):
        steps.append(1)
        return solve_step(apply)

    ik.solver.solve = counted
    res = ik.solve(presses, q0, q0, hover=(), max_iter=150)
    assert len(steps) < 100 and res.iterations == 150 and not res.converged
    ik.solve(presses, q0, q0, hover=(), max_iter=0)  # the same tasks, at q0; no step
    for _ in range(150):  # every step, as before the shortcut
        for p in presses:
            y = float(np.clip(ik._tip(p.finger)[1], *p.y_range_m))
            ik._tasks[p.finger].target_world = np.array([p.point_m[0], y, p.point_m[2]])
        ik._set_hover(())
        solve_step(True)
        ik.robot.update_kinematics()
    q = h.apply_couplings(np.clip(ik.get_q(), h.lower, h.upper))
    assert q.tobytes() == res.q.tobytes()
    assert ik._press_error(presses, {f: ik._tip(f) for f in h.fingers}) == res.press_error_m


def test_an_infeasible_step_is_an_unconverged_solve_not_a_crash(tmp_path, capsys):
    """A hand file whose rail sits low and far back (0.10 m over the keys, 0.52 m in
    front): from its natural pose some presses' QP is infeasible even without the
    clearance half-spaces (placo raises RuntimeError). That is no pose for the atlas,
    not a traceback: every note is reported out of reach."""
    from tests.handfiles import remounted_play

    assert remounted_play(tmp_path, "[0.0, -0.52, 0.10]", (60, 62), fitted=True)[3] == 0
    err = capsys.readouterr().err
    assert "2 notes, 0 played, 2 infeasible" in err and err.count("out_of_reach") == 2
