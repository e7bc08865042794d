"""Pictures of a checked trajectory: PNG plots and an offline 3D animation.

Modules: ``context`` (what every picture needs: the hand, the file's metadata, the
motors, the ball), ``plots`` (the PNG plots), ``html`` (the animation).

Two entry points, both fed with a ``CheckReport`` from
``planner.check.check_trajectory`` (they use its ``replay`` arrays, so the
pictures show what the independent replay found, not what the planner meant):

* ``write_check_report(report, out_dir) -> list[str]`` writes PNG plots
  (matplotlib, Agg canvas, fixed file names) and returns their paths:

  - ``play_piano_roll.png``: expected notes as boxes (pitch vs time), the keys
    really down as bars coloured and numbered by finger (1 thumb .. 5 pinky),
    missed notes and wrong presses in red;
  - ``play_fingertip_heights.png``: each fingertip's height above the resting
    top of the key under it, with the key-down threshold (-5 mm), the full dip
    (-10 mm) and the key bed (-12 mm);
  - ``catch_paths.png``: ball and palm paths, side (x-z) and top (x-y) views,
    whole flight and a zoom on the intercept;
  - ``catch_closing.png``: fingertip distances to the ball's centre against
    time, with the radius, radius + 10 mm, ``intercept_t`` and the 150 ms
    grasp window;
  - ``joint_positions.png``, ``joint_speeds.png``: one panel per joint against
    its limits (dashed);
  - ``motor_angles.png``, ``motor_speeds.png``: motor shaft angles, and motor
    speeds as a fraction of each motor's speed limit.

* ``write_html(report, out_file) -> str`` writes one self-contained HTML page
  (meshcat's viewer script inlined, no network access needed) that animates
  the hand over the plan: a box per hand link, spheres for the fingertips,
  the 88 keys (going down under the fingers) for ``play``, the ball and its
  path for ``catch``.

The animation is built with ``meshcat.Visualizer`` on an in-memory window
(``_SceneRecorder``) instead of meshcat's zmq/websocket server: no process is
started and no socket opened. The page is byte-identical for the same input
(object UUIDs are derived from the scene paths).

Motor angles are ``HandModel.motor_angles`` of the replayed joints (the check
verifies that the file's motor columns equal them within 1e-5 rad).
"""

from planner.report.html import write_html
from planner.report.plots import plot_count, write_check_report

__all__ = ["draw_reports", "write_check_report", "write_html"]


def draw_reports(report, report_dir: str | None, html_path: str | None,
                 enabled: bool = True) -> None:
    """``--report DIR`` (the plots) and ``--html FILE`` (the animation) of a checked
    trajectory, with a progress bar over the pictures on a terminal (``enabled``)."""
    from planner.progress import progress_bar

    total = (plot_count(report) if report_dir else 0) + (1 if html_path else 0)
    with progress_bar("picture", enabled) as bar:
        bar.update(0, total)
        done = 0
        if report_dir:
            write_check_report(report, report_dir, lambda i, _n: bar.update(i, total))
            done = plot_count(report)
        if html_path:
            write_html(report, html_path)
            bar.update(done + 1, total)
