"""A planned catch (``planner.catch.plan``) as the summary a user reads
(``format_summary``) and as one JSON object (``catch_dict``, ``catch --json``)."""

from __future__ import annotations

from typing import Any

import numpy as np

from planner.catch.plan.api import (
    ACTUATION_SEED_S,
    GRASP_WINDOW_S,
    PLAN_BUDGET_S,
    SIGNAL_S,
    CatchResult,
)
from planner.hand.tendon import TENDON_FORCE


def format_summary(res: CatchResult) -> str:
    p = res.plan
    ms = 1000.0
    lines = []
    thr = p.throw.to_dict() if p.throw is not None else {}
    ic = p.intercept
    lines.append(f"catch: {thr.get('ball')} ball thrown at {thr.get('angle_deg'):g} deg to "
                 f"({thr.get('dist_m'):g}, 0, {thr.get('height_m'):g}) m"
                 + (" with drag" if thr.get("drag") else " (vacuum)")
                 + f": launch speed {ic.launch_speed_m_s:.3f} m/s"
                 + (f", flight time {ic.flight_time_s:.3f} s" if ic.flight_time_s is not None
                    else ", never reaches x = dist"))
    ip = p.intercept.point_m
    lines.append(f"  intercept t = {p.intercept.t_s:.3f} s at ({ip[0]:.3f}, {ip[1]:.3f}, "
                 f"{ip[2]:.3f}) m, arrival {np.linalg.norm(ic.arrival_velocity):.2f} m/s, palm "
                 f"normal {p.intercept.misalignment_deg:.1f} deg off the ball's path, palm error "
                 f"{p.intercept.error_m * ms:.1f} mm")
    m = p.margins()
    tm = p.timing
    lines.append(f"  timeline: move from {tm.move_start_s * ms:.0f} ms (signal "
                 f"{SIGNAL_S * ms:.0f} + planning budget {PLAN_BUDGET_S * ms:.0f} ms"
                 + (f" after the last observation at {tm.t_info_s * ms:.0f} ms" if tm.t_info_s
                    else "") + f"), open pose at {m['ready_s'] * ms:.0f} ms, close start "
                 f"{tm.close_start_s * ms:.0f} ms (closing {tm.close_s * ms:.0f} ms; seed "
                 f"{ACTUATION_SEED_S[0] * ms:.0f}-{ACTUATION_SEED_S[1] * ms:.0f} ms)")
    g = (f"grasp at +{m['grasp_after_s'] * ms:.0f} ms ({', '.join(p.timing.grasp_fingers)}; "
         f"{m['grasp_slack_s'] * ms:.0f} ms to spare in the {GRASP_WINDOW_S * ms:.0f} ms window)"
         if p.timing.grasp_t is not None else "no grasp in the window")
    lines.append(f"  margins: open hand waits {m['wait_open_s'] * ms:.0f} ms, closing starts "
                 f"{m['close_lead_s'] * ms:.0f} ms before the ball, {g}; fingertips clear the "
                 f"ball by {p.timing.min_clearance_before_m * ms:.1f} mm before it")
    if p.forces.stop is not None:
        st, soft = p.forces.stop, p.forces.soft
        # (no stopping motion: the palm at rest, or turning with the wrist's turn already
        # under way when the ball lands, the roll rule's: a note says so)
        how = ("the palm not giving with the ball" if soft is None else
               f"the palm meeting it at {np.linalg.norm(soft.v_palm):.2f} m/s, "
               f"{np.linalg.norm(soft.v_rel):.2f} m/s relative, tilt "
               f"{np.degrees(soft.tilt_rad):+.0f} deg, at rest "
               f"{1000 * (soft.end_s - p.intercept.t_s):.0f} ms after")
        per = ", ".join(f"{m} {100 * x:.0f} %" for m, x in
                        sorted(zip(p.hand.motor_names, st.motor_headroom), key=lambda z: z[1])[:3])
        lines.append(f"  stopping (the rule's worst instant, {_cause(st)} at {st.time_s:.3f} s): "
                     f"{st.force_n:.1f} N ({how}); torque headroom "
                     f"{100 * st.headroom:.0f} % (least: {per})")
        c = p.forces.contact
        if c is not None:
            for name, ld in (("impact at contact", c.impact), ("riding the palm", c.riding)):
                if ld is not None:
                    lines.append(f"  {name}: {ld.force_n:.1f} N at {ld.time_s:.3f} s"
                                 + (f" ({ld.speed_m_s:.2f} m/s relative, over the pad's "
                                    f"{1000 * ld.distance_m:.0f} mm)" if ld.speed_m_s else "")
                                 + f"; headroom {_least(p, ld)}")
    for name, gr in (("holding", p.forces.hold),):
        if gr is not None:
            lines.append(f"  {name}: {np.linalg.norm(gr.total_force):.1f} N over "
                         f"{', '.join(c.name for c in gr.problem.contacts)}; torque headroom "
                         f"{100 * gr.headroom:.0f} % (limited by motor.{gr.limiting_motor}"
                         f"{_part(gr)})")
    if p.uncertainty:
        u = p.uncertainty
        lines.append(f"  intercept uncertainty (observations): sigma_t {u['sigma_t_s'] * ms:.1f}"
                     f" ms, sigma_y {u['sigma_y_m'] * ms:.1f} mm, sigma_z "
                     f"{u['sigma_z_m'] * ms:.1f} mm at x = {u['x_plane_m']:.3f} m")
    for n in p.notes:
        lines.append(f"  note: {n}")
    lines.append(f"  planning {res.planning_s * ms:.1f} ms (one-time setup "
                 f"{res.setup_s * ms:.0f} ms), {res.rows} rows "
                 f"({p.rows.t[-1]:.2f} s at {p.rate_hz:g} Hz) -> {res.out_path}")
    if p.feasible:
        lines.append("  feasible: yes")
    else:
        lines.append("  feasible: NO")
        for r in p.reasons:
            lines.append(f"  infeasible: {r}")
    return "\n".join(lines)


def _cause(ld) -> str:
    """What a stopping load is: the pad's impact or the ball riding the palm."""
    return "impact" if ld.speed_m_s > 0 else "riding the palm"


def _least(p, ld, n: int = 3) -> str:
    """The ``n`` motors closest to their capacity at a load, with their headroom."""
    per = sorted(zip(p.hand.motor_names, ld.motor_headroom), key=lambda z: z[1])[:n]
    return ", ".join(f"{m} {100 * x:.0f} %" for m, x in per)


def _load_dict(p, ld) -> dict[str, Any] | None:
    """One ball load (``catch --json``): force, when, relative speed, every motor's
    headroom."""
    if ld is None:
        return None
    return {"force_n": float(ld.force_n), "time_s": float(ld.time_s),
            "relative_speed_m_s": float(ld.speed_m_s), "limiting_motor": ld.motor,
            "torque_headroom": float(ld.headroom),
            "motor_headroom": dict(zip(p.hand.motor_names, map(float, ld.motor_headroom)))}


def _part(gr) -> str:
    """', its tendon force' when the motor's tendon, not its torque, sets the headroom."""
    return f", its {gr.limiting_part}" if gr.limiting_part == TENDON_FORCE else ""


def _grasp_dict(gr) -> dict[str, Any] | None:
    if gr is None:
        return None
    return {"force_n": float(np.linalg.norm(gr.total_force)),
            "contacts": [c.name for c in gr.problem.contacts],
            "torque_headroom": float(gr.headroom), "limiting_motor": gr.limiting_motor,
            "limiting_part": gr.limiting_part}


def _stop_dict(p) -> dict[str, Any] | None:
    st, soft = p.forces.stop, p.forces.soft
    if st is None:
        return None
    return {"force_n": float(st.force_n), "torque_headroom": float(st.headroom),
            "limiting_motor": st.motor, "limiting_part": st.limiting_part,
            "motor_headroom": dict(zip(p.hand.motor_names, map(float, st.motor_headroom))),
            "cone_margin_n": st.cone_margin_n,
            # when the palm meets the ball (the summary's "... m/s relative"); None without
            # a stopping motion, as in the summary
            "palm_speed_m_s": None if soft is None else float(np.linalg.norm(soft.v_palm)),
            "relative_speed_m_s": None if soft is None else float(np.linalg.norm(soft.v_rel)),
            "tilt_deg": None if soft is None else float(np.degrees(soft.tilt_rad)),
            # the moment the force and headroom above are judged at (the check's worst row)
            "worst_t_s": float(st.time_s), "worst_relative_speed_m_s": float(st.speed_m_s),
            "worst_is": _cause(st)}


def catch_dict(res: CatchResult) -> dict[str, Any]:
    """``catch --json``: the summary's facts, one JSON object (units in the names)."""
    p = res.plan
    m = p.margins()
    return {
        "command": "catch", "feasible": bool(p.feasible),
        "reasons": [r.detail for r in p.reasons],
        "reason_kinds": [k.value for k in p.reason_kinds],
        "throw": p.throw.to_dict() if p.throw is not None else {},
        "launch_speed_m_s": float(p.intercept.launch_speed_m_s),
        "flight_time_s": (None if p.intercept.flight_time_s is None
                          else float(p.intercept.flight_time_s)),
        "intercept_t_s": float(p.intercept.t_s),
        "intercept_point_m": [float(x) for x in p.intercept.point_m],
        "arrival_speed_m_s": float(np.linalg.norm(p.intercept.arrival_velocity)),
        "palm_misalignment_deg": float(p.intercept.misalignment_deg),
        "intercept_error_m": float(p.intercept.error_m),
        "move_start_s": float(p.timing.move_start_s),
        "close_start_s": float(p.timing.close_start_s),
        "close_s": float(p.timing.close_s),
        "grasp_t_s": None if p.timing.grasp_t is None else float(p.timing.grasp_t),
        "grasp_fingers": list(p.timing.grasp_fingers), "margins_s": {k: float(v) for k, v in m.items()},
        "min_clearance_before_m": float(p.timing.min_clearance_before_m),
        "stopping": _stop_dict(p), "holding": _grasp_dict(p.forces.hold),
        "impact": None if p.forces.contact is None else _load_dict(p, p.forces.contact.impact),
        "riding": None if p.forces.contact is None else _load_dict(p, p.forces.contact.riding),
        "uncertainty": None if not p.uncertainty else {k: float(v) for k, v in
                                                       p.uncertainty.items()},
        "notes": list(p.notes), "rows": int(res.rows), "rate_hz": float(p.rate_hz),
        "duration_s": float(p.rows.t[-1]), "trajectory": res.out_path,
        "planning_s": float(res.planning_s), "setup_s": float(res.setup_s),
    }
