"""The offline 3D animation of a checked trajectory (``write_html``; see ``planner.report``)."""

from __future__ import annotations

import base64
import html
import math
import os
import uuid
from pathlib import Path

import numpy as np

from planner.check import (
    CheckReport,
    ball_positions,
)
from planner.hand.spec import FINGERS
from planner.music.keyboard import (
    HIGHEST_PITCH,
    KEY_DIP_M,
    LOWEST_PITCH,
    key,
)
from planner.output import write_file
from planner.report.context import (
    CATCH_CAMERA_OFFSET_M,
    FINGER_COLORS,
    HTML_FPS,
    HTML_MAX_FRAMES,
    KEY_BODY_M,
    PLAY_CAMERA_OFFSET_M,
    TIP_SPHERE_M,
    ball_centres,
    picture_context,
)

# ====================================================================== HTML animation


class _SceneRecorder:
    """Stands in for meshcat's ``ViewerWindow``: records the commands a
    ``meshcat.Visualizer`` sends, in order, instead of sending them to a zmq
    server (which meshcat would start as a subprocess with a web server)."""

    def __init__(self) -> None:
        self.commands: list[bytes] = []
        self.animation: bytes | None = None

    def send(self, command) -> None:
        import umsgpack

        data = command.lower()
        packed = umsgpack.packb(data, force_float_precision="single")
        if data["type"] == "set_animation":
            self.animation = packed  # played last, once every object exists
        else:
            self.commands.append(packed)

    def close(self) -> None:  # nothing to stop
        pass

    def commands_b64(self) -> list[str]:
        cmds = self.commands + ([self.animation] if self.animation is not None else [])
        return [base64.b64encode(c).decode("ascii") for c in cmds]


def _uuid(*parts: str) -> str:
    return str(uuid.uuid5(uuid.NAMESPACE_URL, "hand-planner-report/" + "/".join(parts)))


def _mesh(geometry, material, path: str):
    import meshcat.geometry as g

    geometry.uuid = _uuid(path, "geometry")
    material.uuid = _uuid(path, "material")
    m = g.Mesh(geometry, material)
    m.uuid = _uuid(path, "object")
    return m


def _translation(p) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = p
    return T


def _frame_rows(t: np.ndarray) -> tuple[np.ndarray, float]:
    """Rows shown by the animation (nearest row to each frame time) and its fps."""
    dur = float(t[-1] - t[0])
    fps = HTML_FPS
    if dur * fps + 1 > HTML_MAX_FRAMES:
        fps = (HTML_MAX_FRAMES - 1) / dur
    n = math.floor(dur * fps + 1e-9) + 1
    times = t[0] + np.arange(n) / fps
    idx = np.clip(np.searchsorted(t, times), 0, len(t) - 1)
    prev = np.clip(idx - 1, 0, len(t) - 1)
    idx = np.where(np.abs(t[prev] - times) <= np.abs(t[idx] - times), prev, idx)
    return idx, fps


def _link_color(name: str) -> int:
    for f, c in zip(FINGERS, FINGER_COLORS):
        if name.startswith(f + "_"):
            return int(c[1:], 16)
    return 0x9a9a9a if name in ("palm", "wrist") else 0x6f6f6f


def write_html(report: CheckReport, out_file: str) -> str:
    """Write a self-contained HTML animation of the replayed plan; returns ``out_file``.

    meshcat's viewer script is inlined and the scene is encoded in the page,
    so the file works offline; no server is started.
    """
    import meshcat
    import meshcat.geometry as g
    from meshcat.animation import Animation

    ctx = picture_context(report)
    rp = report.replay
    hand = ctx.hand.mounted(ctx.T_world_root)  # own Pinocchio data, the file's root pose
    rec = _SceneRecorder()
    vis = meshcat.Visualizer(window=rec)
    rows, fps = _frame_rows(rp.t_s)

    # the hand: one node per link (animated world pose) holding its box or tip sphere
    links = []
    for link in ctx.hand.spec.links:
        if link.name.endswith("_tip"):
            path = f"hand/{link.name}"
            geom = _mesh(g.Sphere(TIP_SPHERE_M),
                         g.MeshPhongMaterial(color=_link_color(link.name)), path)
            vis[path].set_object(geom)
            links.append(link.name)
        elif link.mass_kg > 0:
            path = f"hand/{link.name}/box"
            vis[path].set_object(_mesh(g.Box(list(link.size_m)),
                                       g.MeshPhongMaterial(color=_link_color(link.name)), path))
            vis[path].set_transform(_translation(link.com_m))
            links.append(link.name)
    # the rail (static)
    if "rail" in ctx.hand.joint_names:
        i = ctx.hand.index["rail"]
        lo, hi = float(ctx.hand.lower[i]), float(ctx.hand.upper[i])
        if np.isfinite(lo) and np.isfinite(hi):
            vis["rail"].set_object(_mesh(g.Box([hi - lo, 0.012, 0.012]),
                                         g.MeshPhongMaterial(color=0x444444), "rail"))
            vis["rail"].set_transform(ctx.T_world_root @ _translation([0.5 * (lo + hi), 0, 0]))

    anim = Animation(default_framerate=fps)
    poses = {name: [] for name in links}
    for r in rows:
        for name in links:
            poses[name].append(hand.frame_pose(rp.q[r], name))
    for i in range(len(rows)):
        with anim.at_frame(vis, i) as frame:
            for name in links:
                frame[f"hand/{name}"].set_transform(poses[name][i])

    if report.play is not None:
        _keyboard(vis, anim, rp, rows)
        target = np.array([float(np.mean(rp.tips[rows, :, 0])), 0.08, 0.03])
        offset = np.array(PLAY_CAMERA_OFFSET_M)
        vis["/Grid"].set_property("visible", False)
        vis["/Axes"].set_property("visible", False)
    else:
        centres = ball_centres(report, ctx)
        if centres is not None:
            _ball(vis, anim, report, ctx, centres, rows)
        i_row = int(np.argmin(np.abs(rp.t_s - report.catch.intercept_t)))
        target = rp.palm[i_row, :3, 3].copy()
        offset = np.array(CATCH_CAMERA_OFFSET_M)
    # meshcat's orbit controls look at the world origin whatever the camera node's pose:
    # the scene (and the grid) is shifted instead, so that ``target`` sits at the origin
    vis.set_transform(_translation(-target))
    vis["/Grid"].set_transform(_translation(-target))
    vis["/Axes"].set_transform(_translation(-target))
    # the camera sits in meshcat's y-up "rotated" frame: world (x, y, z) -> (x, z, -y)
    vis["/Cameras/default/rotated/<object>"].set_property(
        "position", [float(offset[0]), float(offset[2]), float(-offset[1])])
    vis.set_animation(anim, play=True, repetitions=1000)

    text = _page(report, rec, fps, len(rows))
    write_file(out_file, text)
    return out_file


def _keyboard(vis, anim, rp, rows: np.ndarray) -> None:
    """88 key boxes; a key held down moves down by the depth of the body pressing it
    (<= dip; the body rule's ``Replay.key_depth_m``)."""
    import meshcat.geometry as g

    depth = np.where(rp.down, np.clip(rp.key_depth_m, 0.0, KEY_DIP_M), 0.0)  # (T, 88)
    vis["keyboard/bed"].set_object(_mesh(
        g.Box([key(HIGHEST_PITCH).x_max_m - key(LOWEST_PITCH).x_min_m + 0.02, 0.17, 0.01]),
        g.MeshPhongMaterial(color=0x2b2b2b), "keyboard/bed"))
    x_mid = 0.5 * (key(HIGHEST_PITCH).x_max_m + key(LOWEST_PITCH).x_min_m)
    vis["keyboard/bed"].set_transform(_translation([x_mid, 0.075, -KEY_BODY_M - 0.005]))
    for p in range(LOWEST_PITCH, HIGHEST_PITCH + 1):
        k = key(p)
        path = f"keyboard/{p}"
        size = [k.x_max_m - k.x_min_m, k.y_max_m - k.y_min_m, KEY_BODY_M]
        color = 0x151515 if k.black else 0xf7f7f2
        vis[f"{path}/box"].set_object(_mesh(g.Box(size), g.MeshPhongMaterial(color=color),
                                            f"{path}/box"))
        vis[f"{path}/box"].set_transform(_translation([0, 0, -0.5 * KEY_BODY_M]))
        centre = [k.center_x_m, 0.5 * (k.y_min_m + k.y_max_m), k.top_z_m]
        vis[path].set_transform(_translation(centre))
        col = p - LOWEST_PITCH
        dip = depth[:, col]  # (T,)
        if not np.any(dip[rows] > 0):
            continue
        for i, r in enumerate(rows):
            with anim.at_frame(vis, i) as frame:
                frame[path].set_property("position", "vector3",
                                         [centre[0], centre[1], centre[2] - float(dip[r])])


def _ball(vis, anim, report, ctx, centres: np.ndarray, rows: np.ndarray) -> None:
    import meshcat.geometry as g

    c = report.catch
    vis["ball"].set_object(_mesh(g.Sphere(c.radius_m), g.MeshPhongMaterial(color=0xd8e83a),
                                 "ball"))
    tf = np.linspace(0.0, c.intercept_t, 200)
    path = ball_positions(ctx.ball["p0"], ctx.ball["v0"], ctx.ball["drag"], tf)
    line = g.Line(g.PointsGeometry(path.T.astype(np.float32)),
                  g.LineBasicMaterial(color=0xe6a700))
    line.geometry.uuid = _uuid("ball_path", "geometry")
    line.material.uuid = _uuid("ball_path", "material")
    line.uuid = _uuid("ball_path", "object")
    vis["ball_path"].set_object(line)
    mark = _mesh(g.Sphere(0.006), g.MeshPhongMaterial(color=0xd62728), "intercept")
    vis["intercept"].set_object(mark)
    vis["intercept"].set_transform(_translation(c.ball_at_intercept))
    for i, r in enumerate(rows):
        with anim.at_frame(vis, i) as frame:
            frame["ball"].set_transform(_translation(centres[r]))


def _page(report: CheckReport, rec: _SceneRecorder, fps: float, n_frames: int) -> str:
    import meshcat

    js = (Path(meshcat.__file__).parent / "viewer" / "dist" / "main.min.js").read_text(
        encoding="utf-8")
    cmds = ",\n".join(f'"{b}"' for b in rec.commands_b64())
    lines = [f"{report.task}: {os.path.basename(report.trajectory)}"
             + (f" + {os.path.basename(report.song)}" if report.song else ""),
             (f"{report.rows} rows, {report.duration_s:.2f} s; animation {n_frames} frames "
              f"at {fps:.3g} fps"),
             f"check: {'OK' if report.ok else 'FAILED'}"]
    if report.play is not None and report.play.f1 is not None:
        p = report.play
        lines.append(f"frame F1 {p.f1:.3f}, notes hit {p.notes_hit}/{p.notes}, "
                     f"{len(p.wrong_presses)} wrong presses")
    if report.catch is not None:
        c = report.catch
        err = "n/a" if c.intercept_error_m is None else f"{c.intercept_error_m * 1000:.1f} mm"
        lines.append(f"intercept at {c.intercept_t:.3f} s, error {err}; "
                     + ("grasp held" if c.grasp_held else "no held grasp"))
    info = "<br>".join(html.escape(s) for s in lines)
    return f"""<!DOCTYPE html>
<html>
<head>
<meta charset="utf-8">
<title>{html.escape(report.task)} - {html.escape(os.path.basename(report.trajectory))}</title>
<style>
body {{ margin: 0; }}
#meshcat-pane {{ width: 100vw; height: 100vh; overflow: hidden; }}
#info {{ position: absolute; left: 8px; top: 8px; padding: 6px 8px; font: 13px sans-serif;
        color: #fff; background: rgba(0, 0, 0, 0.45); border-radius: 4px; }}
</style>
</head>
<body>
<div id="meshcat-pane"></div>
<div id="info">{info}</div>
<script>
{js}
</script>
<script>
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
var sceneCommands = [
{cmds}
];
for (var i = 0; i < sceneCommands.length; i++) {{
    var s = atob(sceneCommands[i]);
    var bytes = new Uint8Array(s.length);
    for (var j = 0; j < s.length; j++) bytes[j] = s.charCodeAt(j);
    viewer.handle_command_bytearray(bytes);
}}
</script>
</body>
</html>
"""
