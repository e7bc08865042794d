"""What the physics replay finds: keys from the keys' own joints, scored by the check's
rules (``planner.check.keys.score_song``: frame F1 over the song's frames, notes hit,
late, keys down where no note sounds), the servos' effort against their motors' limits,
tracking error per joint, and for a catch whether the ball stays in the hand.

* A key sounds while it is ``KeyBody.down_m`` (the spec's 5 mm) or more down.
* Wrong keys: key-down episodes outside that key's notes that do not touch one of its
  notes. An episode that continues a note of its key (the key still rising after the
  note's end, or down a frame before its onset) is an overhang: it costs F1 frames but
  is the right key.
* Motor effort: what the control law asked of each motor (``SimRecord.servo_demand``,
  as motor torque through ``HandModel.motor_torques``) against its peak torque. A motor
  is saturated while the demand exceeds the peak; a saturation that lasts longer than
  ``SATURATION_MAX_S`` is a problem -- except for a finger's motors while that finger
  touches a key (a finger pushing a key into its bed stalls its motors, as a pianist's
  finger presses into the bed; the key then is down, which is what is scored) or the
  ball (a position servo closing on a rigid ball stalls at its torque: the grip's force
  is then the motor's peak, and whether it holds is what is scored).
* Catch: the ball is held when, from ``intercept_t + GRASP_WINDOW_S`` to the end, it
  stays within ``radius + GRASP_TOL_M`` of the palm centre (criteria) and the hand touches
  it (a contact pushing on it at some physics step) within the last ``REST_WINDOW_S``: a
  ball at rest in the hand may be seen without contact at one step (a resting contact
  flickers at the solver's scale), a ball the hand no longer supports falls out of the
  grasp's tolerance within that window.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from planner.check.criteria import GRASP_TOL_M, GRASP_WINDOW_S, LATE_S
from planner.check.keys import key_episodes, score_song
from planner.check.kinematics import G
from planner.check.results import KeyEpisode, LateNote, MissedNote
from planner.hand.model import HandModel
from planner.hand.spec import FINGERS
from planner.simulate.keyboard import key_bodies
from planner.simulate.replay import SimRecord

SATURATION_MAX_S = LATE_S  # a motor short of torque for longer than a late note's 20 ms
# The window over which a held ball must be touched: the time a ball without support takes
# to fall the grasp's tolerance from rest, sqrt(2 GRASP_TOL_M / g) (45 ms for 10 mm).
REST_WINDOW_S = math.sqrt(2.0 * GRASP_TOL_M / G)


@dataclass(frozen=True)
class MotorEffort:
    """One motor: peak demanded torque (N m) against its limit, and its saturation."""

    name: str
    peak_demand_nm: float
    limit_nm: float
    saturated_s: float  # longest run at the limit (outside key contact for finger motors)
    at_s: float  # where that run starts (or the peak, without one)

    @property
    def ratio(self) -> float:
        return self.peak_demand_nm / self.limit_nm


@dataclass(frozen=True)
class JointTracking:
    name: str
    max_error: float  # rad (m for a rig axis: the rail, the reach)
    rms_error: float
    at_s: float
    unit: str = "rad"  # "m" for a rig axis (a prismatic joint)


@dataclass(frozen=True)
class PhysicsPlay:
    f1: float | None
    precision: float | None
    recall: float | None
    notes: int | None
    notes_hit: int | None
    missed: tuple[MissedNote, ...]
    late: tuple[LateNote, ...]
    wrong_keys: tuple[KeyEpisode, ...]
    overhangs: tuple[KeyEpisode, ...]
    played: tuple[KeyEpisode, ...]
    song_frames: int | None


@dataclass(frozen=True)
class PhysicsCatch:
    held: bool
    held_from_s: float  # the time from which it must stay
    end_distance_m: float  # ball centre to palm centre at the end
    peak_contact_force_n: float
    contacts_at_end: int
    left_at_s: float | None = None  # the first row after held_from_s beyond the grasp
    last_touch_s: float | None = None  # the end of the last row interval the hand touched it
    end_s: float | None = None  # the last row's time

    @property
    def why_not(self) -> str:
        """Why the ball is not held ('' when it is)."""
        if self.held:
            return ""
        if self.end_s is not None and self.end_s < self.held_from_s:
            return f"the rows end at {self.end_s:.3f} s, before {self.held_from_s:.3f} s"
        if self.left_at_s is not None:
            return (f"it left the hand at {self.left_at_s:.3f} s "
                    f"({self.end_distance_m * 1000:.1f} mm from the palm centre at the end)")
        if self.last_touch_s is None:
            return "the hand never touched it"
        return (f"the hand last touched it at {self.last_touch_s:.3f} s, more than "
                f"{REST_WINDOW_S * 1000:.0f} ms before the end")


def key_down(rec: SimRecord) -> np.ndarray:
    """(T, 88) bool: each key down by its key-down travel or more."""
    down_m = np.array([k.down_m for k in key_bodies()])
    return rec.key_dip_m >= down_m


def _split_overhangs(episodes, down: np.ndarray, expected: np.ndarray, t_s: np.ndarray):
    """Wrong-press episodes that continue a note of their key (overhangs) and the rest."""
    idx = {float(t): i for i, t in enumerate(t_s)}
    wrong, over = [], []
    for e in episodes:
        k = e.pitch - 21
        a = idx.get(e.start_s, int(np.searchsorted(t_s, e.start_s)))
        b = int(np.searchsorted(t_s, e.end_s - 1e-9, side="left"))  # one past the last
        before = a > 0 and down[a - 1, k] and expected[a - 1, k]
        after = b < len(t_s) and down[b, k] and expected[b, k]
        (over if before or after else wrong).append(e)
    return tuple(wrong), tuple(over)


def score_play(rec: SimRecord, notes, rate_hz: float,
               names: tuple[str, ...] = FINGERS) -> PhysicsPlay:
    """The keys of a replay against ``notes``; ``names``: the fingers ``key_finger``
    indexes (two hands: each hand's, prefixed)."""
    from planner.check.criteria import expected_keys

    down = key_down(rec)
    played = tuple(key_episodes(down, rec.t_s, rec.key_finger, names))
    if notes is None:
        return PhysicsPlay(None, None, None, None, None, (), (), (), (), played, None)
    s = score_song(rec.t_s, down, rec.key_finger, notes, rate_hz, names)
    wrong, over = _split_overhangs(s.wrong_presses, down, expected_keys(notes, rec.t_s),
                                   rec.t_s)
    return PhysicsPlay(s.f1, s.precision, s.recall, len(notes), len(notes) - len(s.missed),
                       s.missed, s.late, wrong, over, played, s.song_frames)


def _longest_run(mask: np.ndarray) -> tuple[int, int]:
    """(length, start) of the longest run of True in ``mask``."""
    best, start, run, run_start = 0, 0, 0, 0
    for i, m in enumerate(mask):
        if m:
            if run == 0:
                run_start = i
            run += 1
            if run > best:
                best, start = run, run_start
        else:
            run = 0
    return best, start


def motor_efforts(rec: SimRecord, hand: HandModel) -> tuple[MotorEffort, ...]:
    T = len(rec.t_s)
    from planner.simulate.actuators import Transmission

    drive = np.array(hand.motor_map.drive)
    tr = Transmission(hand)  # (hand.motor_torques, once per distinct transmission)
    demand = tr.servo_motor_torques(rec.q_sim, rec.servo_demand, drive)
    finger_of = {}
    for f, name in enumerate(hand.fingers):
        for j in hand.joint_slice(name):
            finger_of[int(j)] = f
    touching = np.zeros((T, len(hand.fingers)), dtype=bool)
    for f in range(len(hand.fingers)):
        touching[:, f] = (rec.key_finger == f).any(axis=1) | rec.ball_fingers[:, f]
    dt = float(np.median(np.diff(rec.t_s))) if T > 1 else 0.01
    out = []
    for m, name in enumerate(hand.motor_names):
        limit = float(hand.motor_peak_torque[m])
        over = np.abs(demand[:, m]) > limit * (1 + 1e-9)
        f = finger_of.get(int(drive[m]))
        if f is not None:
            over &= ~touching[:, f]
        run, start = _longest_run(over)
        peak = int(np.argmax(np.abs(demand[:, m])))
        out.append(MotorEffort(f"motor.{name}", float(np.abs(demand[peak, m])), limit,
                               run * dt, float(rec.t_s[start if run else peak])))
    return tuple(out)


def tracking(rec: SimRecord, hand: HandModel) -> tuple[JointTracking, ...]:
    err = np.abs(rec.q_sim - rec.q_ref)
    worst = err.argmax(axis=0)
    return tuple(JointTracking(n, float(err[worst[i], i]), float(np.sqrt(np.mean(err[:, i] ** 2))),
                               float(rec.t_s[worst[i]]), "m" if n in hand.rig_joints else "rad")
                 for i, n in enumerate(hand.joint_names))


def score_catch(rec: SimRecord, intercept_t: float, radius_m: float) -> PhysicsCatch:
    """Whether the ball stays in the hand (module docstring): within the grasp's reach of
    the palm at every row from ``intercept_t + GRASP_WINDOW_S``, touched within the last
    ``REST_WINDOW_S`` (a row's force is the peak over the physics steps since the row
    before: the window judges the contact over its steps, not at one sample)."""
    dist = np.linalg.norm(rec.ball_m - rec.palm_m, axis=1)
    t0 = intercept_t + GRASP_WINDOW_S
    after = rec.t_s >= t0
    # a ball inside the hand: its centre within reach of the palm and touching the hand
    near = dist <= radius_m * 2 + GRASP_TOL_M
    out = np.flatnonzero(after & ~near)
    touched = np.flatnonzero((rec.ball_force_n > 0.0) | (rec.ball_contacts > 0))
    last_touch = float(rec.t_s[touched[-1]]) if len(touched) else None
    rests = last_touch is not None and last_touch > float(rec.t_s[-1]) - REST_WINDOW_S
    held = bool(after.any() and not len(out) and rests)
    return PhysicsCatch(held, t0, float(dist[-1]), float(np.max(rec.ball_force_n)),
                        int(rec.ball_contacts[-1]),
                        float(rec.t_s[out[0]]) if len(out) else None, last_touch,
                        float(rec.t_s[-1]))
