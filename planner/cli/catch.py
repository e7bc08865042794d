"""``catch``: a throw planned into a catch (once, from the throw or from observations),
or live from observations read on stdin (``--live``); the summary (stderr) or one JSON
object (stdout), the pictures of the checked plan, and the exit status."""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import sys

from planner.cli.options import add_pictures, draw_checked


def add_parser(sub) -> None:
    c = sub.add_parser("catch", help="plan a catch of a thrown ball")
    c.add_argument("--angle", type=float, default=None,
                   help="launch angle above horizontal, deg (required unless --live or "
                        "--observations)")
    c.add_argument("--dist", type=float, required=True, help="horizontal distance to the hand, m")
    c.add_argument("--height", type=float, default=0.0, help="hand height above the launch point, m")
    c.add_argument("--ball", default="tennis", help="ball: tennis, baseball, golf, seed")
    c.add_argument("--drag", action="store_true", help="model quadratic air drag")
    c.add_argument("--observations", metavar="CSV", help="fit the flight to t,x,y,z observations")
    c.add_argument("--live", action="store_true",
                   help="re-plan after each t,x,y,z observation read from stdin as it arrives")
    c.add_argument("-o", "--output", default="catch.csv",
                   help="trajectory CSV ('-' for stdout; default catch.csv)")
    c.add_argument("--hand", default="default", help="hand name or hand file (.toml)")
    c.add_argument("--rate", type=float, default=100.0, help="setpoint rate, Hz (default 100)")
    c.add_argument("--strict", action="store_true", help="exit 1 if the catch is infeasible")
    add_pictures(c)
    c.add_argument("--json", action="store_true",
                   help="the summary as one JSON object on stdout (needs -o FILE)")


def run(a: argparse.Namespace) -> int:
    """Plan, write, print the summary on stderr; exit status.

    ``--report DIR`` / ``--html FILE``: the written plan is replayed by the
    independent check and drawn by ``planner.report``; both need a file output (not
    ``-``)."""
    from planner.errors import InputError

    if a.live:
        return run_live(a)
    if a.angle is None and a.observations is None:
        raise InputError("catch needs --angle or --observations (or --live, which takes the "
                         "throw from the observations on stdin)")
    if a.report or a.html:
        for mod in ("planner.report", "planner.check"):
            if importlib.util.find_spec(mod) is None:
                raise InputError(f"--report/--html need {mod}, which is not installed")
        if a.output == "-":
            raise InputError("--report/--html need a trajectory file (-o FILE), not stdout")
    from planner.catch import plan_catch
    from planner.catch.summary import catch_dict, format_summary

    res = plan_catch(a.angle, a.dist, a.height, a.hand, a.output, ball=a.ball, drag=a.drag,
                     observations=a.observations, rate_hz=a.rate, strict=False)
    if a.json:
        sys.stdout.write(json.dumps(catch_dict(res)) + "\n")
    else:
        sys.stderr.write(format_summary(res) + "\n")
    if a.report or a.html:
        from planner.check import check_trajectory

        draw_checked(check_trajectory(a.output, hand_override=a.hand), a.report, a.html,
                     enabled=not a.json)
    return 1 if (a.strict and not res.feasible) else 0


LIVE_BLAS_THREADS = "1"  # OpenBLAS's threads for ``catch --live``: its matrices are at most
# the hand's joints square (3-variable QPs, 6-joint Jacobians), which OpenBLAS multiplies on
# one thread whatever it is allowed; with the default (a thread per core) it only starts
# and parks the others: 0.017 s of CPU of the start before the first observation, 0.035 s
# over the process (this 2-core machine, 9 alternated runs; docs/history/2026-12-07-ready.md)


def one_blas_thread() -> None:
    """OpenBLAS kept to ``LIVE_BLAS_THREADS`` unless the user set its thread count: read
    when numpy is first imported, so only where it has not been yet (a program that runs
    ``main`` after its own numpy keeps its own)."""
    if "numpy" not in sys.modules:
        os.environ.setdefault("OPENBLAS_NUM_THREADS", LIVE_BLAS_THREADS)


def run_live(a: argparse.Namespace) -> int:
    """``catch --live``: observations from stdin (``planner.catch.livecli``) handed to a
    ``CatchSession``; the summary once it has ended."""
    one_blas_thread()
    import numpy as np

    from planner.catch.live.session import CatchSession
    from planner.catch.livecli import run_session
    from planner.catch.plan.results import CatchResult
    from planner.catch.summary import catch_dict, format_summary
    from planner.errors import InputError

    for opt in ("angle", "observations"):
        if getattr(a, opt) is not None:
            raise InputError(f"--live takes the throw from the observations on stdin: "
                             f"--{opt} is not used with it")
    if a.report or a.html:
        raise InputError("--report/--html are not available with --live")
    session = CatchSession(a.dist, a.height, a.hand, ball=a.ball, drag=a.drag,
                           rate_hz=a.rate, out_path=a.output)
    try:
        run_session(session, sys.stdin)
    except BaseException as e:
        session.abort(discard=isinstance(e, InputError))
        raise
    plan = session.plan
    res = CatchResult(plan, a.output, session.next_row, 0.0, 0.0)
    lat = np.array(session.latencies_s)
    p50, p99 = (float(x) for x in np.percentile(lat, [50, 99])) if lat.size else (0.0, 0.0)
    if a.json:
        d = catch_dict(res)
        d["live"] = {"catch": session.outcome, "reason": session.reason,
                     "observations": session.fit.n, "latency_p50_s": p50,
                     "latency_p99_s": p99}
        sys.stdout.write(json.dumps(d) + "\n")
    else:
        sys.stderr.write(format_summary(res) + f"\n  live: {session.outcome}: "
                         f"{session.reason}\n  live: {lat.size} observations re-planned, "
                         f"latency to their rows p50 {1000 * p50:.2f} ms, p99 "
                         f"{1000 * p99:.2f} ms\n")
    return 1 if (a.strict and not plan.feasible) else 0
