"""A live catch: the plan re-made after every camera observation of the ball
(``cli.py catch --live``; ``CatchSession.observe(t_s, xyz)`` returns the new rows).

Time is the catch frame's (spec section 5): t = 0 when the ball leaves the launch
point, positions in metres from it. An observation seen at ``t`` can change the hand
from ``t_react = t + SIGNAL_S + PLAN_BUDGET_S`` on (the seed's 25 ms of signal
processing, the planning budget): every row up to then is written already, and after
each observation the rows are written up to ``t_react`` plus the last interval between
observations (the time the next observation can act from), so the hardware always has
the rows it is executing and a row, once written, never changes.

After each observation (``observe``):

1. Fit (``livefit.LiveFit``): the flight's state and its covariance from every
   observation so far (vacuum, or drag with the ball's k), once there are
   ``LiveFit.min_obs`` of them (before that there is no file: the hand rests, and the
   first rows are written from t = 0 with the first fit; those up to an earlier
   observation's ``t_react``, rest rows whatever the fit finds, formatted at that one).
2. Intercept (``livesearch.LiveSearch``): near the previous intercept time, the whole
   path searched from out of reach once per ``REACH_RETRY_S``; the pose confirmed by
   ``CatchPlanner.meet`` (placo, warm: the previous pose is the closed form's). The first
   fit's starts from the intercept of the flight fitted to the observations before it
   (``LiveFit.first_look``: with drag, the chord iteration the first fit would do, which
   it then continues by one step; its intercept searched along the whole path), both at
   the observation before the first fit, which plans nothing else, so that no
   observation carries the whole search or the fit's iteration together with the first
   plan.
3. Motion (``livemotion.LiveMotion``): until the hand moves, it waits while waiting for
   the next observation would not make it late (the open pose reached before the closing
   move must start, ``closing.close_start``), then starts the planner's move to the open
   pose; afterwards the arm is re-aimed at each new intercept pose from the state of the
   rows written, and the closing start is re-timed until it has begun.
4. Rows: only the ones not yet written are sampled, guarded and appended.

The session ends (``finish``; the end marker) when an observation can no longer act
before the ball reaches the palm (its ``t_react`` is past the planned intercept), or
when the observations end (``finish()`` at the end of the input: the rest of the rows
follow the last estimate). Then the rest of the plan is written, judged once and the end
marker written (``live.ending.LiveEnding``). The file's metadata holds the first fit's
(spec section 4 asks for one on the first line).

Steps 2-3 are ``live.replan.LiveReplan``'s (the re-plan of each estimate), the end
``LiveEnding``'s; the session keeps the observations, their fit and the rows written.

The latency of an observation (to its rows) is the fit, the intercept, the motion and the
new rows (``Written``: the rows and when they were flushed).
"""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from planner.catch.flight.livefit import LiveFit
from planner.catch.flight.path import Ball, Flight, finite_float, get_ball
from planner.catch.live.ending import LiveEnding
from planner.catch.live.motion import LiveMotion
from planner.catch.live.replan import LiveReplan
from planner.catch.live.search import LiveSearch
from planner.catch.live.stop import arm_offset
from planner.catch.live.stopper import LiveStopper
from planner.catch.live.turn import LiveTurn
from planner.catch.plan.arm import open_from
from planner.catch.plan.planner import PLAN_BUDGET_S, SIGNAL_S, CatchPlanner
from planner.catch.plan.results import CatchPlan, ThrowInfo, catch_metadata
from planner.catch.plan.softstop import SoftStop
from planner.errors import InputError
from planner.hand.model import HandModel
from planner.trajfile import FormattedRows, TrajectoryWriter, format_rows, joined_rows

if TYPE_CHECKING:
    from planner.catch.flight.dragfit import DragEstimate


class _Chunk(NamedTuple):
    """Rows sampled, guarded and formatted (``trajfile.format_rows``), to be written."""

    t: np.ndarray
    Q: np.ndarray
    rows: FormattedRows


class Written(NamedTuple):
    """Rows written to the file (as it holds them, (n, columns); none: (0, 0)), and when
    they were flushed: ``perf_counter`` and ``thread_time`` then (NaN: none written), the
    point an observation's latency is measured to."""

    rows: np.ndarray
    at_s: float = math.nan
    cpu_at_s: float = math.nan


NOTHING = Written(np.empty((0, 0)))


class CatchSession:
    """One throw, planned live: ``observe`` each observation, ``finish`` at the end of
    the input. ``out_path``: a file, '-' (stdout) or None (in memory: ``text``)."""

    def __init__(self, dist_m: float, height_m: float = 0.0,
                 hand: HandModel | str = "default", ball: Ball | str = "tennis",
                 drag: bool = False, rate_hz: float = 100.0, out_path: str | None = None,
                 planner: CatchPlanner | None = None, soft_stop: bool = True) -> None:
        from planner.catch.plan.api import get_planner, validate_live

        d, hgt, rate = validate_live(dist_m, height_m, rate_hz)
        self.ball = get_ball(ball)
        self.drag = bool(drag)
        self.pl = planner or get_planner(hand)
        self.closing = self.pl.closing(self.ball.radius_m)
        self.C = np.array([d, 0.0, hgt])
        self.rate_hz, self.dt = rate, 1.0 / rate
        if out_path is not None and out_path != "-":
            parent = Path(out_path).parent
            if not parent.is_dir():
                raise InputError(f"cannot write {out_path}: no such directory {parent}")
        self.out_path = out_path
        self.latencies_s: list[float] = []  # per observation: to its rows written
        self.cpu_s: list[float] = []  # ... and the CPU time of this thread in it (the
        # latency less the time the machine ran other work)
        self.fit = LiveFit(self.ball, self.ball.drag_per_m if drag else 0.0)
        h, j = self.pl.hand, self.pl.joints
        q_open = open_from(h, j, self.pl.q_zero, self.closing.q_closed)
        self.motion = LiveMotion(h, j.arm, self.pl.q_rest, q_open, self.closing.q_closed,
                                 self.pl.dyn)
        self.writer: TrajectoryWriter | None = None
        self._T_root = self.pl.mount.T_world_root(self.C).tolist()  # (the file's metadata)
        self._t: list[np.ndarray] = []
        self._q: list[np.ndarray] = []
        self._ahead: list[_Chunk] = []  # rows formatted before the file is opened
        self.next_row = 0
        self.pose = self.flight = None
        self.t_i: float | None = None
        self._search = LiveSearch(self.pl.wrist, self.C, self.ball.radius_m)  # (step 2)
        # default: docs/history/live-catch.md, issue 31)
        self.first: dict[str, Any] | None = None  # the first plan's flight and intercept
        self.ending = LiveEnding(self)  # the end (outcome, plan, the wrist's turn)
        self.stopper = LiveStopper(self.pl, self.motion, self.ball, self.C, self.dt, self.drag,
                                   soft_stop)  # the soft stop (``live.stopper``)
        self.replanner = LiveReplan(self.pl, self.closing, self.C, self.dt, self.ball.radius_m,
                                    self.motion, self.stopper, self._search)  # (steps 2-3)

    # ------------------------------------------------------------ observations
    @property
    def stop(self) -> SoftStop | None:
        """The arm's stopping motion (``live.stopper``): of the newest estimate, fixed
        (``stop_fixed``) once the rows reach its ramp."""
        return self.stopper.stop

    @property
    def stop_fixed(self) -> bool:
        return self.stopper.fixed

    @property
    def fallbacks(self) -> int:
        """Soft stops given up for the palm at rest (``LiveStopper.fix``)."""
        return self.stopper.fallbacks

    @property
    def done(self) -> bool:
        return self.outcome is not None

    @property
    def outcome(self) -> str | None:
        """``"held"`` or ``"given_up"`` once ended (the end marker's), None before."""
        return self.ending.outcome

    @property
    def reason(self) -> str:
        return self.ending.reason

    @property
    def plan(self) -> CatchPlan | None:
        """The final plan, judged (at the end)."""
        return self.ending.plan

    @property
    def turn(self) -> LiveTurn | None:
        """The wrist's turn that holds the ball (at the end)."""
        return self.ending.turn

    @property
    def uncertainty(self) -> dict[str, float] | None:
        return self.ending.uncertainty

    @property
    def drag_estimate(self) -> DragEstimate | None:
        """(drag: at the end)"""
        return self.ending.drag_estimate

    @property
    def written_to_s(self) -> float:
        """Time of the last row written (-inf before any)."""
        return (self.next_row - 1) * self.dt if self.next_row else -math.inf

    @property
    def text(self) -> str | None:
        """The file's text, for a session kept in memory, once finished."""
        return None if self.writer is None else self.writer.text

    def observe(self, t_s: Any, xyz: Any) -> np.ndarray:
        """One observation: the ball's centre ``xyz`` (m, catch frame) at ``t_s`` (s from
        the launch). Refits, re-plans and writes the rows the plan adds; returns them as
        the file holds them, (n, columns) (none before the first fit, nor after the end).
        InputError (one line) on an observation that cannot follow the ones before."""
        if self.done:
            return np.empty((0, 0))
        t0, c0 = time.perf_counter(), time.thread_time()
        w = self._observe(t_s, xyz)
        wrote = len(w.rows) > 0
        self.latencies_s.append((w.at_s if wrote else time.perf_counter()) - t0)
        self.cpu_s.append((w.cpu_at_s if wrote else time.thread_time()) - c0)
        return w.rows

    def _observe(self, t_s: Any, xyz: Any) -> Written:
        t = finite_float("t", t_s)
        p = _point(xyz)
        period = t - self.fit.times[-1] if self.fit.n else 0.0
        fit = self.fit.add(t, p)
        if fit is None:
            if self.fit.n == 1 and self.stopper.soft and not self.motion.moving:
                self.stopper.start_early(t + SIGNAL_S + PLAN_BUDGET_S)
            if self.fit.n == self.fit.min_obs - 1:  # the observation before the first fit
                look = self.fit.first_look()
                tilt = None if look is None else self.stopper.look(look)
                if tilt is not None:
                    self._search.tilt = tilt
                self._search.look(look)
            # the hand rests at least until this observation could act: those rows
            # formatted here, written with the first fit's
            chunk = self._format(t + SIGNAL_S + PLAN_BUDGET_S)
            self._ahead += [chunk] if chunk else []
            return NOTHING
        t_react = t + SIGNAL_S + PLAN_BUDGET_S
        t_b = max(self.written_to_s, t_react)
        if self.t_i is not None and t_b >= self.t_i and self.pose.ic.reason is None:  # too
            # late to act before the ball (an estimate out of reach has no such time: a
            # first fit of a few noisy observations may put its nearest point in the past)
            return self.ending.finish(f"the observation at t = {t:.3f} s acts after the "
                                      "intercept", t_react + period)
        old_seg = self.motion.seg
        self.pose = self.replanner.replan(fit.flight, t, t_b, period,
                                          self.last_row_s(t_react + period), self.pose, self.t_i)
        self.flight, self.t_i = fit.flight, self.pose.t_i
        if self.writer is None:
            self._open()
        written = self.write_to(t_react + period, t_b, old_seg)
        self.ending.warm()  # (after the rows: the wrist's turn ahead, once the stop is fixed)
        return written

    def finish(self) -> np.ndarray:
        """The end of the observations: the rest of the plan follows the last estimate
        (InputError when there were too few to fit a flight)."""
        if self.done:
            return np.empty((0, 0))
        if self.flight is None:
            raise InputError(f"{self.fit.n} observation{'' if self.fit.n == 1 else 's'} of the "
                             f"ball: at least {self.fit.min_obs} are needed to fit its flight")
        last = float(self.fit.times[-1])
        return self.ending.finish(f"the observations ended at t = {last:.3f} s").rows

    def abort(self, discard: bool = False) -> None:
        """Stop without the end marker (the file stays visibly incomplete)."""
        if self.writer is not None:
            self.writer.abort(discard=discard)

    # ------------------------------------------------------------ rows
    def _open(self) -> None:
        ball = self.flight.to_metadata()
        self.first = {"ball": dict(ball), "intercept_t": float(self.t_i),
                      "observations": self.fit.n}
        meta = catch_metadata(self.pl.base_hand, self._T_root, self.rate_hz, self.flight,
                              self.t_i, {"live": True, "throw": self.throw_info().to_dict(),
                                         "catch_point": [float(x) for x in self.C],
                                         "stop_distance_m": self.pl.base_hand.pad_give_m,
                                         "observations": self.fit.n})
        h = self.pl.base_hand
        self.writer = TrajectoryWriter(self.out_path, meta, h)

    def throw_info(self) -> ThrowInfo:
        """The throw the current estimate describes."""
        return live_throw(self.flight, self.C, self.ball, self.drag, self.fit.n)

    @property
    def closings_computed(self) -> int:
        """Re-plans' closing starts computed (``close_start``; the rest deferred)."""
        return self.replanner.closings.computed

    @property
    def formatted_rows(self) -> int:
        """Rows written or formatted ahead (the index of the next row to format)."""
        return self.next_row + sum(len(c.t) for c in self._ahead)

    def written_rows(self) -> tuple[np.ndarray, np.ndarray]:
        """The times and joint rows written so far, (n,) and (n, joints)."""
        return np.concatenate(self._t), np.concatenate(self._q)

    def last_row_s(self, t_end_s: float) -> float:
        """The time of the last row ``write_to(t_end_s)`` writes."""
        return math.floor(t_end_s / self.dt + 1e-9) * self.dt

    def _format(self, t_end_s: float, t_b: float = -math.inf, old_seg=None) -> _Chunk | None:
        """The rows after those written (and formatted ahead) up to ``t_end_s`` (those up
        to ``t_b`` on the arm's move ``old_seg``, from before this re-plan), guarded and
        formatted, not written (None: no row)."""
        first = self.formatted_rows
        n = math.floor(t_end_s / self.dt + 1e-9) + 1
        if n <= first:
            return None
        t = np.arange(first, n) * self.dt
        Q = self.motion.rows(t, old_seg, t_b)  # (the writer guards them as it writes them)
        sp = self.stopper
        off = arm_offset(sp.stop if sp.fixed else None, t, self.pl.hand.n)
        if off is not None:
            Q = Q + off
        if self.turn is not None:
            Q = Q + self.turn.offset(t)
        return _Chunk(t, Q, format_rows(t, Q, self.pl.hand.motor_angles(Q)))

    def write_to(self, t_end_s: float, t_b: float = -math.inf, old_seg=None) -> Written:
        """The rows formatted ahead and the rest up to ``t_end_s`` (``_format``), written;
        returns them as written, and when."""
        chunks = self._ahead + [c for c in (self._format(t_end_s, t_b, old_seg),) if c]
        self._ahead = []
        if not chunks:
            return NOTHING
        out = self.writer.append(joined_rows([c.rows for c in chunks]))  # (the rows
        # formatted ahead and the new ones: one guard, one flush)
        at_s, cpu_at_s = time.perf_counter(), time.thread_time()
        for c in chunks:
            self._t.append(c.t)
            self._q.append(c.Q)
            self.next_row += len(c.t)
        return Written(out, at_s, cpu_at_s)


def _point(xyz: Any) -> np.ndarray:
    try:
        p = np.array(xyz, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise InputError(f"an observation's position must be 3 numbers, got {xyz!r}") from None
    if p.shape != (3,):
        raise InputError(f"an observation's position must be 3 numbers, got {p.size}")
    return p


def live_throw(flight: Flight, C: np.ndarray, ball: Ball, drag: bool, n_obs: int) -> ThrowInfo:
    """The throw a live estimate ``flight`` describes (its launch angle, the catch point
    ``C``, the ball, drag, ``n_obs`` observations)."""
    v = flight.v0
    return ThrowInfo(math.degrees(math.atan2(float(v[2]), math.hypot(v[0], v[1]))),
                     float(C[0]), float(C[2]), ball.name, drag, n_obs, live=True)
