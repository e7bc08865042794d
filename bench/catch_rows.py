"""A catch file's replay beside the check's ball-on-palm model, row by row (not a test): where
the physics' ball is and where ``planner.check.ballpalm.BallOnPalm`` (the roll rule's model,
``planner.check.ballroll``) puts it, both in the palm's frame from the palm target (palm
centre + radius along the normal; the replay's ball in the replayed palm, the model's in the
rows' palm), the hand's contacts with the ball and which fingers touch it. Then the
fingertips of the rows about the planned ball at the grasp and at the end.

    python bench/catch_rows.py FILE.json [--from T_S]

Columns: x (towards the palm's +x), y (towards the wrist: the roll rule's axis), z (off the
palm) in mm; ``con``: the hand's geoms touching the ball; the fingers thumb..pinky touching
it (1) or not (.); ``n.z``, ``y.z``: the rows' palm normal and +y against the world's up.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from planner.balls import file_inertia_ratio
from planner.check.ball import STOP_DIFF_S, ball_params, ball_positions, judged_source
from planner.check.ballpalm import BallOnPalm
from planner.check.ballstop import PALM_MU
from planner.check.kinematics import Kinematics
from planner.errors import InputError
from planner.hand.spec import FINGERS
from planner.planfile import read_plan


def in_palm(P: np.ndarray, r: float, p: np.ndarray) -> np.ndarray:
    """``p`` (world) in the palm frame ``P`` from its palm target (m)."""
    return P[:3, :3].T @ (np.asarray(p, dtype=float) - (P[:3, 3] + r * P[:3, 2]))


def mm(v: np.ndarray) -> str:
    return " ".join(f"{1000 * x:7.1f}" for x in v)


def rows_table(path: str, t_from_s: float | None) -> list[str]:
    """The table's lines (module docstring) of the catch file ``path``."""
    from planner.simulate import run_replay

    plan = read_plan(path)
    if plan.task != "catch":
        raise InputError(f"{path}: not a catch file (task {plan.task})")
    rp = run_replay(path)
    rec, tr = rp.record, rp.trajectory
    kin = Kinematics(plan.hand, plan.T_world_root)
    tips, P_ref = kin.frames(tr.q)
    _, P_sim = kin.frames(rec.q_sim)
    meta = judged_source(tr, path)
    b = ball_params(meta, path)
    r, ti, t = float(b["radius"]), float(meta["intercept_t"]), tr.t_s
    h = STOP_DIFF_S
    fl = ball_positions(b["p0"], b["v0"], b["drag"], [ti - h, ti + h])
    model = BallOnPalm(r, file_inertia_ratio(meta), PALM_MU)
    k0 = int(np.flatnonzero(t > ti)[0])
    model.land(P_ref, t, k0 - 1, ti, (fl[1] - fl[0]) / (2 * h))
    start = k0 if t_from_s is None else int(np.searchsorted(t, t_from_s))
    out = [f"{path}: landing {ti:.3f} s, ball radius {1000 * r:.1f} mm",
           "  t_s   |  replay x y z (mm)     |  model x y z (mm)      | con fingers | n.z    y.z"]
    for k in range(k0, len(t)):
        model.step_to(P_ref, t, k)
        if k < start:
            continue
        sim = in_palm(P_sim[k], r, rec.ball_m[k])
        mod = in_palm(P_ref[k], r, model.p)
        touch = "".join("1" if f else "." for f in rec.ball_fingers[k])
        out.append(f"{t[k]:.3f} | {mm(sim)} | {mm(mod)} | {int(rec.ball_contacts[k]):3d} {touch:>7}"
                   f" | {P_ref[k][2, 2]:6.3f} {P_ref[k][2, 1]:6.3f}")
    out.append(f"peak contact force {float(np.max(rec.ball_force_n)):.1f} N at "
               f"{float(t[int(np.argmax(rec.ball_force_n))]):.3f} s")
    for k in (min(k0 + 4, len(t) - 1), len(t) - 1):
        out.append(f"fingertips of the rows at {t[k]:.3f} s (x y z mm from the palm target; "
                   "mm beyond the ball's surface):")
        for f, name in enumerate(FINGERS[:tips.shape[1]]):
            rel = in_palm(P_ref[k], r, tips[k, f])
            out.append(f"  {name:7s} {mm(rel)}  {1000 * (np.linalg.norm(rel) - r):6.1f}")
    return out


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description="A catch's replay beside the check's ball model.")
    ap.add_argument("file", help="a catch file (cli.py catch -o FILE)")
    ap.add_argument("--from", dest="t_from", type=float, default=None,
                    help="first row's time (s; default: the first row after the landing)")
    a = ap.parse_args(argv)
    try:
        lines = rows_table(a.file, a.t_from)
    except (InputError, OSError, ValueError) as e:
        print(f"catch_rows: {e}", file=sys.stderr)
        return 2
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
