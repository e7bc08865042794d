"""The PNG plots of a checked trajectory (``write_check_report``; see ``planner.report``)."""

from __future__ import annotations

import io
import math
import os
from collections.abc import Callable

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, Patch, Rectangle

from planner.check import (
    GRASP_TOL_M,
    GRASP_WINDOW_S,
    CheckReport,
    LimitCheck,
    ball_positions,
    key_contacts,
    key_episodes,
    pitch_name,
)
from planner.errors import InputError
from planner.hand.model import HandModel
from planner.hand.spec import FINGERS
from planner.music.keyboard import (
    DOWN_DEPTH_M,
    HIGHEST_PITCH,
    KEY_BED_DEPTH_M,
    KEY_DIP_M,
    LOWEST_PITCH,
    is_black,
)
from planner.output import write_file
from planner.report.context import (
    DPI,
    ERROR_COLOR,
    FINGER_COLORS,
    PictureContext,
    ball_centres,
    picture_context,
)

# ====================================================================== PNG plots


def write_check_report(report: CheckReport, out_dir: str,
                       on_progress: Callable[[int, int], None] | None = None) -> list[str]:
    """Write the PNG plots of ``report`` into ``out_dir`` (created if needed, never its parents).

    Returns the paths written, in a fixed order: the task's plots (play: piano
    roll, fingertip heights; catch: paths, closing timeline) then joint
    positions, joint speeds, motor angles, motor speeds. ``on_progress(done, total)``
    is called after each plot.
    """
    ctx = picture_context(report)
    if not os.path.isdir(out_dir):
        os.mkdir(out_dir)  # (the folder named, never its parents)
    figs: list[tuple[str, Callable[[], Figure]]] = []
    if report.play is not None:
        figs.append(("play_piano_roll.png", lambda: _fig_piano_roll(report)))
        figs.append(("play_fingertip_heights.png", lambda: _fig_tip_heights(report)))
    if report.catch is not None:
        figs.append(("catch_paths.png", lambda: _fig_catch_paths(report, ctx)))
        figs.append(("catch_closing.png", lambda: _fig_catch_closing(report, ctx)))
    figs.append(("joint_positions.png", lambda: _fig_joint_positions(report, ctx)))
    figs.append(("joint_speeds.png", lambda: _fig_joint_speeds(report, ctx)))
    figs.append(("motor_angles.png", lambda: _fig_motor_angles(report, ctx)))
    figs.append(("motor_speeds.png", lambda: _fig_motor_speeds(report, ctx)))
    paths = []
    for i, (name, draw) in enumerate(figs):
        path = os.path.join(out_dir, name)
        buf = io.BytesIO()
        draw().savefig(buf, format="png", dpi=DPI, metadata={"Software": None})
        write_file(path, buf.getvalue())
        paths.append(path)
        if on_progress is not None:
            on_progress(i + 1, len(figs))
    return paths


def plot_count(report: CheckReport) -> int:
    """How many plots ``write_check_report`` draws of ``report``."""
    return 4 + 2 * (report.play is not None) + 2 * (report.catch is not None)


def _limit(report: CheckReport, category: str) -> LimitCheck | None:
    return next((lc for lc in report.limits if lc.category == category), None)


def _limit_text(lc: LimitCheck | None) -> str:
    if lc is None:
        return ""
    verdict = "ok" if lc.ok else f"FAILED, {lc.count} samples beyond"
    return (f"{verdict}; worst {lc.name} {lc.worst:.4g} vs limit {lc.limit:.4g} {lc.unit} "
            f"at {lc.time_s:.2f} s")


def _title_file(report: CheckReport) -> str:
    return os.path.basename(report.trajectory)


def _finger_legend() -> list[Patch]:
    return [Patch(facecolor=c, label=f"{i + 1} {f}") for i, (f, c) in
            enumerate(zip(FINGERS, FINGER_COLORS))]


def _runs(values: np.ndarray) -> list[tuple[int, int, int]]:
    """(start, stop_exclusive, value) of the runs of equal values >= 0."""
    out = []
    n = len(values)
    i = 0
    while i < n:
        v = int(values[i])
        j = i + 1
        while j < n and values[j] == v:
            j += 1
        if v >= 0:
            out.append((i, j, v))
        i = j
    return out


# ---------------------------------------------------------------- play


def _song_notes(report: CheckReport) -> list[tuple[float, float, int]]:
    """(onset, offset, pitch) of the expected notes: the song's, else the
    ``expected`` array's episodes."""
    if report.song:
        try:
            from planner.music.midi import load_song, shift_notes

            notes = [(float(n.onset_s), float(n.offset_s), int(n.pitch)) for n in
                     shift_notes(load_song(report.song).notes, report.song_start_s)]
        except (InputError, OSError, ValueError):
            notes = None  # fall back on the replay's expected keys
        else:
            return notes
    rp = report.replay
    if rp.expected is None:
        return []
    return [(e.start_s, e.end_s, e.pitch) for e in key_episodes(rp.expected, rp.t_s)]


def _fig_piano_roll(report: CheckReport) -> Figure:
    rp, p = report.replay, report.play
    t = rp.t_s
    dt = float(np.median(np.diff(t))) if len(t) > 1 else 0.01
    t_end = np.append(t[1:], t[-1] + dt)
    notes = _song_notes(report)
    pitches = {n[2] for n in notes} | {e.pitch for e in p.played} | {m.pitch for m in p.missed}
    if not pitches:
        pitches = {60}
    lo = max(LOWEST_PITCH, min(pitches) - 2)
    hi = min(HIGHEST_PITCH, max(pitches) + 2)
    n_rows = hi - lo + 1
    dur = float(t_end[-1] - t[0])
    width = float(np.clip(4.0 + 1.1 * dur, 11.0, 26.0))
    height = float(np.clip(2.2 + 0.28 * n_rows, 4.5, 14.0))
    fig = Figure(figsize=(width, height), layout="constrained")
    ax = fig.add_subplot()
    for q in range(lo, hi + 1):
        if is_black(q):
            ax.axhspan(q - 0.5, q + 0.5, color="#ececec", zorder=0, lw=0)
    for on, off, q in notes:
        ax.add_patch(Rectangle((on, q - 0.42), off - on, 0.84, facecolor="#f4f4f4",
                               edgecolor="black", lw=1.0, zorder=1))
    # keys down, one bar per run of the same finger
    small_bar = 0.08 * dur / max(width, 1.0)  # below this a bar is too short for its number
    for k in np.flatnonzero(rp.down.any(axis=0)):
        q = int(k) + LOWEST_PITCH
        col = np.where(rp.down[:, k], rp.finger[:, k], -1)
        for a, b, f in _runs(col):
            x0, x1 = t[a], t_end[b - 1]
            finger = f < len(FINGER_COLORS)  # (else the palm, wrist, ...: ``rp.holders``)
            ax.add_patch(Rectangle((x0, q - 0.25), x1 - x0, 0.5, edgecolor="none", zorder=2,
                                   facecolor=FINGER_COLORS[f] if finger else ERROR_COLOR))
            if x1 - x0 >= small_bar:
                label = str(f + 1) if finger else rp.holders[f][:1].upper()
                ax.text(0.5 * (x0 + x1), q, label, ha="center", va="center",
                        fontsize=8, color="white", fontweight="bold", zorder=4)
    for w in p.wrong_presses:
        ax.add_patch(Rectangle((w.start_s, w.pitch - 0.34), w.end_s - w.start_s, 0.68,
                               facecolor="none", edgecolor=ERROR_COLOR, lw=2.0, zorder=3))
        ax.plot([w.start_s], [w.pitch + 0.34], marker="v", color=ERROR_COLOR, ms=7, zorder=5)
        who = "+".join(str(FINGERS.index(f) + 1) for f in w.fingers if f in FINGERS)
        ax.text(w.end_s + 0.02 * dur / max(width / 11.0, 1.0), w.pitch, f"wrong {who}".strip(),
                color=ERROR_COLOR, fontsize=8, va="center", ha="left", zorder=5)
    for m in p.missed:
        ax.add_patch(Rectangle((m.onset_s, m.pitch - 0.42), m.offset_s - m.onset_s, 0.84,
                               facecolor="none", edgecolor=ERROR_COLOR, lw=2.0, hatch="///",
                               zorder=3))
        ax.text(m.offset_s + 0.02 * dur / max(width / 11.0, 1.0), m.pitch, "missed",
                color=ERROR_COLOR, fontsize=8, va="center", ha="left", zorder=5)
    ax.set_xlim(min(0.0, float(t[0])), float(t_end[-1]))
    ax.set_ylim(lo - 0.5, hi + 0.5)
    step = 1 if n_rows <= 40 else 12
    ticks = [q for q in range(lo, hi + 1) if step == 1 or q % 12 == 0]
    ax.set_yticks(ticks, [f"{pitch_name(q)} ({q})" for q in ticks], fontsize=8)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("key (MIDI pitch)")
    ax.grid(axis="x", color="#cccccc", lw=0.5)
    scores = ""
    if p.f1 is not None:
        scores = (f"frame F1 {p.f1:.3f} (precision {p.precision:.3f}, recall {p.recall:.3f}), "
                  f"notes hit {p.notes_hit}/{p.notes}, ")
    ax.set_title(f"Piano roll - {_title_file(report)}"
                 + (f" vs {os.path.basename(report.song)}" if report.song else "")
                 + f"\n{scores}{len(p.wrong_presses)} wrong presses, {len(p.missed)} missed, "
                 f"{len(p.key_bed_hits)} key-bed hits", fontsize=11)
    handles = [Patch(facecolor="#f4f4f4", edgecolor="black", label="expected note"),
               *_finger_legend(),
               Patch(facecolor="none", edgecolor=ERROR_COLOR, hatch="///", label="missed note"),
               Patch(facecolor="none", edgecolor=ERROR_COLOR, lw=2, label="wrong press")]
    ax.legend(handles=handles, title="key down, by finger", loc="upper left",
              bbox_to_anchor=(1.005, 1.0), fontsize=8, title_fontsize=8, frameon=False)
    return fig


def _fig_tip_heights(report: CheckReport) -> Figure:
    rp = report.replay
    t = rp.t_s
    kc = key_contacts(rp.tips)
    over = kc.tip_key >= 0
    h_mm = np.where(over, -kc.tip_depth, rp.tips[..., 2]) * 1000.0  # (T, 5)
    top = float(np.clip(np.nanmax(h_mm) + 5.0, 20.0, 60.0))
    dur = float(t[-1] - t[0]) if len(t) > 1 else 1.0
    fig = Figure(figsize=(float(np.clip(4.0 + 1.1 * dur, 11.0, 26.0)), 11.0),
                 layout="constrained")
    axs = fig.subplots(len(FINGERS), 1, sharex=True)
    lines = ((0.0, "#888888", "-", "key top (rest)"),
             (-DOWN_DEPTH_M * 1000, "#ff7f0e", "--", f"key down ({-DOWN_DEPTH_M * 1000:g} mm)"),
             (-KEY_DIP_M * 1000, "#2ca02c", "--", f"full dip ({-KEY_DIP_M * 1000:g} mm)"),
             (-KEY_BED_DEPTH_M * 1000, ERROR_COLOR, "--",
              f"key bed ({-KEY_BED_DEPTH_M * 1000:g} mm)"))
    pressing = over & (np.nan_to_num(kc.tip_depth, nan=-1.0) >= DOWN_DEPTH_M)
    wrong = None if rp.expected is None else rp.down & ~rp.expected  # (T, 88)
    for f, ax in enumerate(axs):
        for y, c, ls, _ in lines:
            ax.axhline(y, color=c, ls=ls, lw=1.0, zorder=1)
        key_id = np.where(pressing[:, f], kc.tip_key[:, f], -1)
        for a, b, k in _runs(key_id):
            bad = wrong is not None and bool(wrong[a:b, k].any())
            ax.axvspan(t[a], t[min(b, len(t) - 1)], color=ERROR_COLOR if bad else FINGER_COLORS[f],
                       alpha=0.15, lw=0)
            ax.text(t[a], top - 1.0, pitch_name(k + LOWEST_PITCH) + (" wrong" if bad else ""),
                    fontsize=7, va="top", ha="left",
                    color=ERROR_COLOR if bad else FINGER_COLORS[f])
        # over a key: solid; between keys / off the keyboard (height above z = 0): dotted
        ax.plot(t, np.where(over[:, f], h_mm[:, f], np.nan), color=FINGER_COLORS[f], lw=1.3)
        off = ~over[:, f]
        off_ext = off | np.r_[off[1:], False] | np.r_[False, off[:-1]]  # joins the solid line
        ax.plot(t, np.where(off_ext, h_mm[:, f], np.nan), color=FINGER_COLORS[f], lw=1.0,
                ls=":")
        deep = h_mm[:, f] < -KEY_BED_DEPTH_M * 1000
        if deep.any():
            ax.plot(t[deep], h_mm[deep, f], "x", color=ERROR_COLOR, ms=5)
        ax.set_ylim(-16.0, top)
        above = float(np.mean(h_mm[:, f] > top))
        if above > 0:
            ax.text(0.995, 0.97, f"{above:.0%} of the time above {top:.0f} mm "
                    f"(max {np.max(h_mm[:, f]):.0f} mm)", transform=ax.transAxes, ha="right",
                    va="top", fontsize=8, color="#555555",
                    bbox={"facecolor": "white", "edgecolor": "none", "alpha": 0.8})
        ax.set_ylabel(f"{f + 1} {FINGERS[f]}\nheight (mm)", fontsize=9)
        ax.grid(axis="x", color="#dddddd", lw=0.5)
    axs[-1].set_xlabel("time (s)")
    handles = [Line2D([], [], color=c, ls=ls, label=lab) for _, c, ls, lab in lines]
    handles += [Line2D([], [], color="black", lw=1.3, label="over a key"),
                Line2D([], [], color="black", lw=1.0, ls=":", label="over no key (vs z = 0)"),
                Patch(facecolor="#999999", alpha=0.3, label="holding a key down"),
                Patch(facecolor=ERROR_COLOR, alpha=0.3, label="... a wrong one")]
    axs[0].legend(handles=handles, loc="upper left", bbox_to_anchor=(1.005, 1.0), fontsize=8,
                  frameon=False)
    fig.suptitle(f"Fingertip height above the resting top of the key below - "
                 f"{_title_file(report)} (clipped at {top:.0f} mm)", fontsize=11)
    return fig


# ---------------------------------------------------------------- catch


def _fig_catch_paths(report: CheckReport, ctx: PictureContext) -> Figure:
    rp, c = report.replay, report.catch
    t = rp.t_s
    palm = rp.palm[:, :3, 3]
    fig = Figure(figsize=(14.0, 10.5), layout="constrained")
    axs = fig.subplots(2, 2)
    flight = None
    if ctx.ball is not None:
        tf = np.linspace(0.0, c.intercept_t, 300)
        flight = ball_positions(ctx.ball["p0"], ctx.ball["v0"], ctx.ball["drag"], tf)
    held = ball_centres(report, ctx)
    after = t >= c.intercept_t
    b_i = np.array(c.ball_at_intercept)
    target = np.array(c.palm_target)
    i_row = int(np.argmin(np.abs(t - c.intercept_t)))
    zoom = 0.15 + c.radius_m
    for row, zoomed in enumerate((False, True)):
        for col, (j, name) in enumerate(((2, "side view (x-z)"), (1, "top view (x-y)"))):
            ax = axs[row, col]
            if flight is not None:
                ax.plot(flight[:, 0], flight[:, j], color="#e6a700", lw=1.8,
                        label="ball centre, flight")
                ax.plot(*flight[0, [0, j]], "o", color="#e6a700", ms=6, label="launch")
            if held is not None and after.any():
                ax.plot(held[after, 0], held[after, j], color="#e6a700", lw=1.5, ls=":",
                        label="ball centre, held")
            ax.plot(palm[:, 0], palm[:, j], color="#1f77b4", lw=1.6, label="palm centre")
            ax.plot(palm[0, 0], palm[0, j], "s", color="#1f77b4", ms=5, label="palm at t=0")
            ax.plot(palm[i_row, 0], palm[i_row, j], "D", color="#1f77b4", ms=5,
                    label="palm at intercept")
            n = rp.palm[i_row, :3, 2]
            L = 2.0 * c.radius_m
            ax.annotate("", xy=(palm[i_row, 0] + L * n[0], palm[i_row, j] + L * n[j]),
                        xytext=(palm[i_row, 0], palm[i_row, j]),
                        arrowprops={"arrowstyle": "->", "color": "#1f77b4"})
            ax.add_patch(Circle((b_i[0], b_i[j]), c.radius_m, facecolor="#ffe680", alpha=0.5,
                                edgecolor="#e6a700"))
            ax.plot(b_i[0], b_i[j], "*", color=ERROR_COLOR if not c.intercept_ok else "black",
                    ms=13, label=f"ball at intercept (t={c.intercept_t:.3f} s)")
            if np.all(np.isfinite(target)):
                ax.plot(target[0], target[j], "x", color=ERROR_COLOR, ms=9, mew=2,
                        label="palm target (centre + r n)")
            if zoomed:
                tips = rp.tips[i_row]
                for f in range(len(FINGERS)):
                    ax.plot(tips[f, 0], tips[f, j], "o", color=FINGER_COLORS[f], ms=5,
                            label=f"{FINGERS[f]} tip at intercept")
                ax.set_xlim(b_i[0] - zoom, b_i[0] + zoom)
                ax.set_ylim(b_i[j] - zoom, b_i[j] + zoom)
            ax.set_aspect("equal", adjustable="datalim" if not zoomed else "box")
            ax.set_xlabel("x (m)")
            ax.set_ylabel(("z" if j == 2 else "y") + " (m)")
            ax.set_title(("zoom on the intercept, " if zoomed else "") + name, fontsize=10)
            ax.grid(color="#dddddd", lw=0.5)
    axs[0, 1].legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8, frameon=False)
    axs[1, 1].legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8, frameon=False)
    err = "n/a" if c.intercept_error_m is None else f"{c.intercept_error_m * 1000:.1f} mm"
    fig.suptitle(f"Catch - {_title_file(report)}: ball and palm paths (catch frame); "
                 f"intercept error {err}, {'OK' if c.ok else 'FAILED'}", fontsize=11)
    return fig


def _fig_catch_closing(report: CheckReport, ctx: PictureContext) -> Figure:
    rp, c = report.replay, report.catch
    t = rp.t_s
    fig = Figure(figsize=(12.0, 6.0), layout="constrained")
    ax = fig.add_subplot()
    centres = ball_centres(report, ctx)
    t0 = max(float(t[0]), c.intercept_t - 0.3)
    r_mm = c.radius_m * 1000
    ymax = r_mm + 150.0
    if centres is not None:
        d = np.linalg.norm(rp.tips - centres[:, None, :], axis=-1) * 1000
        shown = t >= t0
        if shown.any():
            ymax = float(np.clip(np.max(d[shown]) * 1.05, r_mm + 40.0, max(6 * r_mm, 300.0)))
        for f in range(len(FINGERS)):
            ax.plot(t, d[:, f], color=FINGER_COLORS[f], lw=1.5, label=f"{f + 1} {FINGERS[f]}")
    else:
        ax.text(0.5, 0.5, "ball parameters unavailable (trajectory file not readable)",
                transform=ax.transAxes, ha="center")
    ax.axhline(r_mm, color="black", lw=1.2, label=f"ball radius ({r_mm:g} mm)")
    ax.axhline(r_mm + GRASP_TOL_M * 1000, color="black", ls="--", lw=1.2,
               label=f"radius + {GRASP_TOL_M * 1000:g} mm (grasp)")
    ax.axvline(c.intercept_t, color="#555555", lw=1.2,
               label=f"intercept_t = {c.intercept_t:.3f} s")
    ax.axvline(c.intercept_t + GRASP_WINDOW_S, color="#555555", ls="--", lw=1.2,
               label=f"intercept_t + {GRASP_WINDOW_S * 1000:g} ms")
    ax.axvspan(c.intercept_t, c.intercept_t + GRASP_WINDOW_S, color="#999999", alpha=0.12, lw=0)
    if c.grasp_time_s is not None:
        ax.axvline(c.grasp_time_s, color="black", ls="-.", lw=1.5,
                   label=f"grasp closed ({c.grasp_time_s:.3f} s, {'+'.join(c.grasp_fingers)})")
    if c.early_touches:
        et = c.early_touches
        ax.plot([e.time_s for e in et], [e.distance_m * 1000 for e in et], "x",
                color=ERROR_COLOR, ms=7, mew=2, label=f"early touches ({len(et)})")
    ax.set_xlim(t0, float(t[-1]))
    ax.set_ylim(0.0, ymax)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("fingertip to ball centre (mm)")
    ax.grid(color="#dddddd", lw=0.5)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    verdict = "grasp held" if c.grasp_held else ("grasp NOT held" if c.grasp_time_s else
                                                  "no grasp")
    ax.set_title(f"Closing around the ball - {_title_file(report)}: {verdict}; ball on the palm "
                 f"from intercept_t (centre = palm_center + r n)", fontsize=11)
    return fig


# ---------------------------------------------------------------- joints and motors


def _grid(n: int, ncols: int = 6) -> tuple[int, int]:
    ncols = min(ncols, max(n, 1))
    return math.ceil(n / ncols), ncols


def _small_multiples(title: str, names, t: np.ndarray, Y: np.ndarray, lo, hi, ylabels,
                     xlim: tuple[float, float], band: bool = False) -> Figure:
    """One panel per column of ``Y`` with dashed lines at ``lo``/``hi`` (None: no line);
    samples beyond them are marked in red."""
    n = Y.shape[1]
    rows, cols = _grid(n)
    w, h = 3.1 * cols, 2.3 * rows + 0.9
    fig = Figure(figsize=(w, h))
    # fixed margins in inches (a layout engine costs seconds with this many panels)
    fig.subplots_adjust(left=0.75 / w, right=1 - 0.15 / w, bottom=0.5 / h, top=1 - 0.85 / h,
                        wspace=0.32, hspace=0.42)
    axs = np.atleast_1d(fig.subplots(rows, cols, sharex=True, squeeze=False)).ravel()
    for i in range(n):
        ax = axs[i]
        y = Y[:, i]
        ax.plot(t, y, color="#1f77b4", lw=1.1)
        bad = np.zeros(len(y), dtype=bool)
        for b, is_hi in ((lo[i], False), (hi[i], True)):
            if b is None or not np.isfinite(b):
                continue
            ax.axhline(b, color="#d62728" if band else "#444444", ls="--", lw=1.0)
            bad |= (y > b + 1e-9 * max(1.0, abs(b))) if is_hi else (y < b - 1e-9 * max(1.0, abs(b)))
        if bad.any():
            ax.plot(t[bad], y[bad], ".", color=ERROR_COLOR, ms=3)
        ax.set_title(names[i], fontsize=9, color=ERROR_COLOR if bad.any() else "black")
        ax.set_ylabel(ylabels[i], fontsize=8)
        ax.tick_params(labelsize=7)
        ax.grid(color="#eeeeee", lw=0.5)
        ax.set_xlim(xlim)
    for ax in axs[n:]:
        ax.set_visible(False)
    for ax in axs[max(0, n - cols):n]:
        ax.set_xlabel("time (s)", fontsize=8)
        ax.xaxis.set_tick_params(labelbottom=True)
    fig.suptitle(title, fontsize=11)
    return fig


def _xlim(t: np.ndarray) -> tuple[float, float]:
    return (float(t[0]), float(t[-1])) if t[-1] > t[0] else (float(t[0]) - 0.5, float(t[0]) + 0.5)


def _is_prismatic(hand: HandModel, name: str) -> bool:
    try:
        return hand.spec.joint(name).kind == "prismatic"
    except KeyError:
        return False


def _fig_joint_positions(report: CheckReport, ctx: PictureContext) -> Figure:
    hand, rp = ctx.hand, report.replay
    pris = [_is_prismatic(hand, n) for n in hand.joint_names]
    scale = np.array([1.0 if p else 180.0 / math.pi for p in pris])
    Y = rp.q * scale
    lo = [v * s if np.isfinite(v) else None for v, s in zip(hand.lower, scale)]
    hi = [v * s if np.isfinite(v) else None for v, s in zip(hand.upper, scale)]
    units = ["m" if p else "deg" for p in pris]
    return _small_multiples(
        f"Joint positions and limits (dashed) - {_title_file(report)}\n"
        f"joint_position: {_limit_text(_limit(report, 'joint_position'))}",
        hand.joint_names, rp.t_s, Y, lo, hi, units, _xlim(rp.t_s))


def _speeds(t: np.ndarray, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """First differences, reported at the later row of each pair (as the check does)."""
    if len(t) < 2:
        return t, np.zeros_like(X)
    return t[1:], np.diff(X, axis=0) / np.diff(t)[:, None]


def _fig_joint_speeds(report: CheckReport, ctx: PictureContext) -> Figure:
    hand, rp = ctx.hand, report.replay
    ts, V = _speeds(rp.t_s, rp.q)
    pris = [_is_prismatic(hand, n) for n in hand.joint_names]
    units = ["m/s" if p else "rad/s" for p in pris]
    return _small_multiples(
        f"Joint speeds and speed limits (dashed) - {_title_file(report)}\n"
        f"joint_velocity: {_limit_text(_limit(report, 'joint_velocity'))}",
        hand.joint_names, ts, V, list(-hand.velocity), list(hand.velocity), units,
        _xlim(rp.t_s), band=True)


def _fig_motor_angles(report: CheckReport, ctx: PictureContext) -> Figure:
    hand, rp = ctx.hand, report.replay
    names = [f"motor.{m}" for m in hand.motor_names]
    return _small_multiples(
        f"Motor shaft angles - {_title_file(report)} (motors have no position limit)\n"
        f"motor_consistency: {_limit_text(_limit(report, 'motor_consistency'))}",
        names, rp.t_s, ctx.q_motor, [None] * len(names), [None] * len(names),
        ["rad"] * len(names), _xlim(rp.t_s))


def _fig_motor_speeds(report: CheckReport, ctx: PictureContext) -> Figure:
    hand, rp = ctx.hand, report.replay
    ts, V = _speeds(rp.t_s, ctx.q_motor)
    frac = V / hand.motor_speed
    names = [f"motor.{m} ({s:g} rad/s)" for m, s in zip(hand.motor_names, hand.motor_speed)]
    n = len(names)
    fig = _small_multiples(
        f"Motor speeds as a fraction of each motor's speed limit (dashed: +/-1) - "
        f"{_title_file(report)}\nmotor_velocity: {_limit_text(_limit(report, 'motor_velocity'))}",
        names, ts, frac, [-1.0] * n, [1.0] * n, ["speed / limit"] * n, _xlim(rp.t_s),
        band=True)
    for ax, y in zip(fig.axes, frac.T):
        m = max(1.1, float(np.max(np.abs(y))) * 1.05 if y.size else 1.1)
        ax.set_ylim(-m, m)
    return fig
