"""The physics replay's verdict lines and its result with what it was made from
(``Replay``), shared by one hand's replay (``planner.simulate``) and two hands'
(``planner.simulate.pair``)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any


def physics_problems(play, motors, catch, min_f1, strict, claims) -> list[str]:
    """The verdict's lines of a replay's keys, motors and catch (see the docstring)."""
    out = []
    if play is not None:
        if play.wrong_keys:
            w = play.wrong_keys[0]
            out.append(f"{len(play.wrong_keys)} wrong keys in physics (first: {w.name} at "
                       f"{w.start_s:.3f} s, {'+'.join(w.fingers) or 'no finger'})")
        if claims:
            m = claims[0]
            out.append(f"{len(claims)} notes the plan claims played are missed in physics "
                       f"(first: {m.name} at {m.onset_s:.3f} s: {m.reason})")
        if min_f1 is not None and play.f1 is not None and play.f1 < min_f1:
            out.append(f"physics frame F1 {play.f1:.4f} < {min_f1:g}")
        if strict and play.missed:
            out.append(f"{len(play.missed)} notes missed in physics")
        if strict and play.late:
            out.append(f"{len(play.late)} notes late in physics")
    from planner.simulate.scores import SATURATION_MAX_S

    for m in motors:
        if m.saturated_s > SATURATION_MAX_S:
            out.append(f"{m.name} short of torque for {m.saturated_s * 1000:.0f} ms from "
                       f"{m.at_s:.3f} s (asked {m.peak_demand_nm:.3f} N m at peak, gives "
                       f"{m.limit_nm:.3f})")
    if catch is not None and not catch.held:
        out.append(f"ball not held in physics: {catch.why_not}")
    return out


def record_problems(rec) -> list[str]:
    """The verdict's lines of the replay itself: a diverged simulation, a hand faster than
    the collision selection's margin."""
    out = []
    if rec.unstable_at_s is not None:
        out.append(f"the simulation diverged near {rec.unstable_at_s:.3f} s (MuJoCo "
                   "reset its state: forces beyond what the solver can resolve)")
    if rec.reach_overruns:
        from planner.simulate.nearkeys import REACH_MARGIN_M

        out.append(f"the hand moved more than {500 * REACH_MARGIN_M:.0f} mm within a "
                   f"row {rec.reach_overruns} times: the replay's collision selection "
                   "may have missed a contact")
    return out


@dataclass(frozen=True)
class Replay:
    """A replay's report with what it was made from: the record (every row's simulated
    state), the hand (mounted as the file says), the trajectory, the song's notes, the
    scene it ran in."""

    report: Any  # SimulateReport
    record: Any  # replay.SimRecord
    hand: Any  # HandModel
    trajectory: Any  # trajfile.Trajectory
    notes: tuple | None
    scene: Any = None  # scene.Scene
