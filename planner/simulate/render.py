"""Frames of a physics replay, drawn by MuJoCo's offscreen renderer: each frame is the
plan (left: the rows as the kinematic check replays them, keys down by the pads' depth,
the ball on its planned flight and then on the palm) beside the physics (right: the
simulated hand, keys and ball), seen by the same camera at the same time.

Keys are tinted by what they do: green down for a note of the song, red down where no
note sounds (a wrong key, or a key still rising after its note), amber a note's key
left up. The camera of a play follows the hand along the keyboard (the pads' mean x,
smoothed over ``CAMERA_SMOOTH_S``) from behind the keys (``PLAY_CAMERA_OFFSET_M``, the
kinematic 3D view's camera); a catch's looks at the palm at the intercept from the side
of the flight (``CATCH_CAMERA_OFFSET_M``).

MuJoCo picks its OpenGL backend when it is first imported (``MUJOCO_GL``): the CLI sets
``egl`` (headless, no display needed) when it is unset. No rendering context: an
``InputError`` that says so.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from planner.errors import InputError
from planner.report.context import CATCH_CAMERA_OFFSET_M, HTML_FPS, PLAY_CAMERA_OFFSET_M

PANEL_W_PX, PANEL_H_PX = 480, 360  # one panel (plan or physics); a frame is two side by side
PICTURE_FPS = HTML_FPS  # the kinematic 3D view's frame rate
MAX_FRAMES = 1500  # a longer run is shown at a lower frame rate (60 s at 25 fps)
CAMERA_SMOOTH_S = 1.0  # the play camera's x: the pads' mean over this window
PLAY_LOOKAT_YZ_M = (0.08, 0.03)  # the play camera looks at the keys' middle, 3 cm up
SOUNDING_RGBA = (0.25, 0.75, 0.35, 1.0)
WRONG_RGBA = (0.85, 0.15, 0.15, 1.0)
SILENT_NOTE_RGBA = (0.95, 0.7, 0.2, 1.0)


@dataclass(frozen=True)
class Frames:
    """What is drawn: the rows shown (indices into the replay's rows), at ``fps``."""

    rows: np.ndarray
    fps: float
    t_s: np.ndarray


def frame_rows(t_s: np.ndarray, fps: float = PICTURE_FPS,
               max_frames: int = MAX_FRAMES) -> Frames:
    """One row every 1/fps seconds (the nearest row), at most ``max_frames`` rows."""
    t = np.asarray(t_s, dtype=float)
    dur = float(t[-1] - t[0]) if len(t) else 0.0
    if dur * fps + 1 > max_frames:
        fps = (max_frames - 1) / dur
    n = int(np.floor(dur * fps + 1e-9)) + 1
    want = t[0] + np.arange(n) / fps
    hi = np.clip(np.searchsorted(t, want), 0, len(t) - 1)
    lo = np.clip(hi - 1, 0, len(t) - 1)
    rows = np.where(np.abs(t[lo] - want) <= np.abs(t[hi] - want), lo, hi)
    return Frames(rows, float(fps), t[rows])


def _camera(mujoco, lookat, offset) -> object:
    """A free camera at ``lookat + offset`` looking at ``lookat`` (world frame)."""
    o = np.asarray(offset, dtype=float)
    d = float(np.linalg.norm(o))
    cam = mujoco.MjvCamera()
    cam.type = mujoco.mjtCamera.mjCAMERA_FREE
    cam.lookat[:] = lookat
    cam.distance = d
    cam.azimuth = float(np.degrees(np.arctan2(-o[1], -o[0])))
    cam.elevation = float(np.degrees(np.arcsin(-o[2] / d)))
    return cam


def _lookats(replay, frames: Frames) -> np.ndarray:
    rec = replay.record
    if replay.report.task == "play":
        x = rec.tips_m[:, :, 0].mean(axis=1)
        dt = float(np.median(np.diff(rec.t_s))) if len(rec.t_s) > 1 else 0.01
        w = max(1, round(CAMERA_SMOOTH_S / dt))
        pad = np.pad(x, (w // 2, w - 1 - w // 2), mode="edge")
        xs = np.convolve(pad, np.ones(w) / w, mode="valid")
        return np.array([(xs[r], *PLAY_LOOKAT_YZ_M) for r in frames.rows])
    i = int(np.argmin(np.abs(rec.t_s - float(replay.trajectory.metadata["intercept_t"]))))
    return np.repeat(rec.palm_m[i][None], len(frames.rows), axis=0)


def _planned_ball(replay, data, mujoco, scene, t: float) -> np.ndarray:
    """The ball as the kinematic check has it: its flight before the intercept, on the
    palm (palm centre + radius along the palm's normal) from it on."""
    from planner.check.ball import ball_params, ball_positions

    meta = replay.trajectory.metadata
    b = ball_params(meta, replay.report.trajectory)
    if t < float(meta["intercept_t"]):
        return ball_positions(b["p0"], b["v0"], float(b["drag"]), [t])[0]
    R = np.asarray(data.site_xmat[scene.palm_site]).reshape(3, 3)
    return np.asarray(data.site_xpos[scene.palm_site]) + float(b["radius"]) * R[:, 2]


def _set_state(scene, data, mujoco, q, key_dip, ball) -> None:
    data.qpos[scene.hand_qpos] = q
    if len(scene.key_qpos):
        data.qpos[scene.key_qpos] = key_dip
    mujoco.mj_kinematics(scene.model, data)
    if scene.ball_body >= 0 and ball is not None:
        adr = scene.model.jnt_qposadr[scene.model.body_jntadr[scene.ball_body]]
        data.qpos[adr:adr + 3] = ball(data) if callable(ball) else ball
        data.qpos[adr + 3:adr + 7] = (1.0, 0.0, 0.0, 0.0)
        mujoco.mj_kinematics(scene.model, data)


class _KeyTint:
    """Key colours from what each key does (see the module docstring)."""

    def __init__(self, scene) -> None:
        self.model = scene.model
        self.geoms = [np.flatnonzero(scene.key_geom_key == k) for k in range(88)]
        self.rest = np.array(scene.model.geom_rgba)

    def apply(self, down: np.ndarray | None, expected: np.ndarray | None) -> None:
        self.model.geom_rgba[:] = self.rest
        if down is None:
            return
        for k in range(88):
            exp = expected is not None and expected[k]
            if down[k]:
                self.model.geom_rgba[self.geoms[k]] = SOUNDING_RGBA if exp or expected is None \
                    else WRONG_RGBA
            elif exp:
                self.model.geom_rgba[self.geoms[k]] = SILENT_NOTE_RGBA

    def restore(self) -> None:
        self.model.geom_rgba[:] = self.rest


def _key_states(replay):
    """(planned key travel, planned down, physics down, expected) per row; Nones for a
    catch (expected None without a song)."""
    if replay.report.task != "play":
        return None, None, None, None
    from planner.check.criteria import expected_keys, key_contacts
    from planner.simulate.keyboard import planned_key_travel
    from planner.simulate.scores import key_down

    planned_tips = np.array([replay.hand.tip_positions(q) for q in replay.record.q_ref])
    kc = key_contacts(planned_tips)
    expected = None if replay.notes is None else expected_keys(replay.notes, replay.record.t_s)
    return planned_key_travel(kc), kc.down, key_down(replay.record), expected


def _label(img: np.ndarray, lines: list[str]) -> np.ndarray:
    from PIL import Image, ImageDraw

    im = Image.fromarray(img)
    draw = ImageDraw.Draw(im)
    for i, line in enumerate(lines):
        draw.text((8, 6 + 13 * i), line, fill=(255, 255, 255))
    return np.asarray(im)


def _renderer(mujoco, model):
    model.vis.global_.offwidth = max(int(model.vis.global_.offwidth), PANEL_W_PX)
    model.vis.global_.offheight = max(int(model.vis.global_.offheight), PANEL_H_PX)
    model.vis.headlight.ambient[:] = 0.35
    model.vis.headlight.diffuse[:] = 0.6
    import warnings

    try:
        with warnings.catch_warnings():  # (glfw warns on stderr before it fails)
            warnings.simplefilter("ignore")
            r = mujoco.Renderer(model, PANEL_H_PX, PANEL_W_PX)
    except (RuntimeError, ImportError, OSError, mujoco.FatalError) as e:  # no GL context
        raise InputError(f"cannot render offscreen (MUJOCO_GL={_gl_name()}): "
                         f"{str(e).splitlines()[0] if str(e) else type(e).__name__}; "
                         "set MUJOCO_GL to egl, osmesa or glfw") from None
    r.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = False
    r.scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = False
    return r


def _gl_name() -> str:
    import os

    return os.environ.get("MUJOCO_GL", "") or "unset"


def render_frames(replay, frames: Frames) -> Iterator[np.ndarray]:
    """The frames (H, 2 W, 3) uint8 of ``replay`` (a ``run_replay`` result with its
    scene) at ``frames``: plan on the left, physics on the right."""
    from planner.simulate.scene import require_mujoco

    mujoco = require_mujoco()
    scene, rec = replay.scene, replay.record
    renderer = _renderer(mujoco, scene.model)
    plan, phys = mujoco.MjData(scene.model), mujoco.MjData(scene.model)
    tint = _KeyTint(scene)
    travel, plan_down, phys_down, expected = _key_states(replay)
    catch = replay.report.task == "catch"
    offset = CATCH_CAMERA_OFFSET_M if catch else PLAY_CAMERA_OFFSET_M
    what = f"physics (MuJoCo, contact {replay.report.contact})"
    try:
        for lookat, r in zip(_lookats(replay, frames), frames.rows):
            cam = _camera(mujoco, lookat, offset)
            t = float(rec.t_s[r])
            exp = None if expected is None else expected[r]
            _set_state(scene, plan, mujoco, rec.q_ref[r], None if travel is None else travel[r],
                       (lambda d, t=t: _planned_ball(replay, d, mujoco, scene, t)) if catch
                       else None)
            _set_state(scene, phys, mujoco, rec.q_sim[r], rec.key_dip_m[r],
                       rec.ball_m[r] if catch else None)
            panels = []
            for data, down, name in ((plan, plan_down, "plan (kinematic check)"),
                                     (phys, phys_down, what)):
                tint.apply(None if down is None else down[r], exp)
                renderer.update_scene(data, camera=cam)
                panels.append(_label(renderer.render(), [name, f"t = {t:.2f} s"]))
            yield np.concatenate(panels, axis=1)
    finally:
        tint.restore()
        renderer.close()
