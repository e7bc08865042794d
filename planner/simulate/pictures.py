"""``simulate --video FILE.mp4`` and ``--html FILE``: the replay's frames (``render``:
the plan beside the physics) drawn once, as an mp4 (``video``) and a self-contained
page (``page``) from the same pass. Both are written only after the whole run has been
drawn, by ``planner.output.write_file``.

``prepare(video, html)`` is called before the simulation: a missing encoder or an
output path that cannot be written is refused at once (``InputError``, exit 2), and
MuJoCo's OpenGL backend is set to ``egl`` (headless) when ``MUJOCO_GL`` is unset and
MuJoCo not yet imported.
"""

from __future__ import annotations

import os
import sys

from planner.errors import InputError


def _check_path(path: str, option: str) -> None:
    if not path:
        raise InputError(f"{option}: empty output path")
    if os.path.isdir(path):
        raise InputError(f"cannot write {path}: is a directory")
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.lexists(path) and not os.path.isdir(folder):
        raise InputError(f"cannot write {path}: no folder {folder}")


def prepare(video: str | None, html: str | None) -> None:
    """Refuse now what would fail after the simulation (see the module docstring)."""
    if video is not None:
        _check_path(video, "--video")
        from planner.simulate.video import require

        require()
    if html is not None:
        _check_path(html, "--html")
    if (video or html) and "mujoco" not in sys.modules and not os.environ.get("MUJOCO_GL"):
        os.environ["MUJOCO_GL"] = "egl"


def write_pictures(replay, video: str | None, html: str | None,
                   progress: bool = True) -> list[str]:
    """Draw ``replay`` (a ``run_replay`` result) and write the mp4 and/or the page;
    returns the paths written."""
    if not (video or html):
        return []
    from planner.output import write_file
    from planner.progress import progress_bar
    from planner.simulate.page import frame_jpeg, page_html
    from planner.simulate.render import frame_rows, render_frames

    frames = frame_rows(replay.record.t_s)
    jpegs: list[bytes] = []

    def drawn():
        with progress_bar("frame", progress) as bar:
            for i, img in enumerate(render_frames(replay, frames)):
                if html:
                    jpegs.append(frame_jpeg(img))
                bar.update(i + 1, len(frames.rows))
                yield img

    out = []
    if video:
        from planner.simulate.video import encode_mp4

        data = encode_mp4(drawn(), frames.fps)
    else:
        for _ in drawn():
            pass
    if video:
        write_file(video, data)
        out.append(video)
    if html:
        r = replay.report
        title = f"simulate {os.path.basename(r.trajectory)}" + (
            f" + {os.path.basename(r.song)}" if r.song else "")
        write_file(html, page_html(title, r.summary(timing=False), jpegs, frames.t_s, frames.fps))
        out.append(html)
    return out
