"""The arm's stopping motion of one catch as a profile in time (``SoftStop``), made by
``planner.catch.plan.stopping.stop_profile``: every arm joint through the intercept pose
q_i along q_j(t) = q_i,j + qd_j sigma_j(t), sigma_j a time-like scalar whose speed rises
from rest (min-jerk), holds the contact share from one row before the intercept, rises to
1 over the recoil, holds 1 and falls to rest (min-jerk).

One ramp time for every joint (``ramp_in_s``, ``ramp_out_s``): the palm target moves along
one line through the intercept. Per-joint ramps (``ramps_in_s``, ``ramps_out_s``, set by
``planner.catch.plan.ramps``): each joint ramps in and out in its own time, the same
speeds from one row before the intercept to the ramp-out's start (where the ball meets
the palm and the pad stops it, every sigma_j is the same); a joint with a short range (the
rig's reach axis) ramps quickly, one whose motor is loaded (the wrist flexion) slowly.
``ramp_in_s``/``ramp_out_s`` are then the longest of them (the profile's start and end).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def ramp_integral(u: np.ndarray) -> np.ndarray:
    """The integral over [0, u] of the min-jerk rise (10 s^3 - 15 s^4 + 6 s^5), u clipped to
    [0, 1]: 2.5 u^4 - 3 u^5 + u^6 (1/2 at u = 1)."""
    u = np.clip(u, 0.0, 1.0)
    return u ** 4 * (2.5 - 3.0 * u + u * u)


def stop_knots(c, t_i: float, row_s: float, ramp_in_s, recoil_s: float, hold_s: float,
               ramp_out_s) -> tuple:
    """A ``SoftStop``'s sigma at the ramp-in's start and end, the recoil's end, the hold's
    end, the end; and the time the hold ends (its fields: the contact share ``c``, ...;
    floats, or arrays of every joint's): one definition, for a stop and for the numbers of
    one not made (``live.stopper``'s bisection of a slower stop)."""
    t4 = t_i + recoil_s + hold_s
    s2 = -c * row_s
    s1 = s2 - 0.5 * c * ramp_in_s
    s3 = 0.5 * recoil_s * (1.0 + c)
    s4 = s3 + hold_s
    return s1, s2, s3, s4, s4 + 0.5 * ramp_out_s, t4


@dataclass(frozen=True)
class SoftStop:
    """The arm's stopping motion of one catch (see the module docstring): its speed factor
    sigma' rises (min-jerk, ``ramp_in_s``) to ``contact_share`` one row before the
    intercept, holds it to the intercept, rises linearly to 1 over ``recoil_s`` (the hand
    recoiling under the ball's push), holds 1 for ``hold_s``, falls to rest (min-jerk,
    ``ramp_out_s``). The arm's speeds at factor 1 are ``qd``. ``ramps_in_s`` and
    ``ramps_out_s`` (one per arm joint, or None: every joint the common ones): per-joint
    ramps, ``ramp_in_s`` and ``ramp_out_s`` then their longest."""

    tilt_rad: float
    arm: tuple[int, ...]  # the arm joints' indices (hand order)
    qd: np.ndarray  # their speeds at factor 1 (after the recoil)
    contact_share: float  # the speed factor when the palm meets the ball
    t_i: float
    row_s: float  # one row interval: the contact speed is held this long before the ball
    ramp_in_s: float
    recoil_s: float
    hold_s: float
    ramp_out_s: float
    pad_s: float  # how long the pad takes to stop the ball relative to the palm
    v_palm: np.ndarray  # palm target velocity at the intercept (m/s)
    v_rel: np.ndarray  # the ball's velocity relative to it (m/s)
    force_n: np.ndarray  # the pad's force on the ball (N)
    motor_ratio: np.ndarray  # |torque| / capacity of every motor while the pad stops it
    cone_margin_n: float
    ramps_in_s: np.ndarray | None = None  # per arm joint (``arm`` order), or None
    ramps_out_s: np.ndarray | None = None
    shares: np.ndarray | None = None  # per arm joint contact shares (or None: every joint's
    # ``contact_share``): a joint whose acceleration limit cannot take the recoil from
    # ``contact_share`` in ``recoil_s`` meets the ball nearer its full speed

    @property
    def per_joint(self) -> bool:
        """Whether the joints ramp (or recoil) each in its own way."""
        return self.ramps_in_s is not None or self.ramps_out_s is not None \
            or self.shares is not None

    @property
    def qd_c(self) -> np.ndarray:
        """The arm's speeds when the palm meets the ball."""
        return (self.contact_share if self.shares is None else self.shares) * self.qd

    @property
    def start_s(self) -> float:
        """When the arm starts its ramp (it holds its pre-catch pose until then)."""
        return self.t_i - self.row_s - self.ramp_in_s

    @property
    def end_s(self) -> float:
        """When the arm is at rest with the ball."""
        return self.t_i + self.recoil_s + self.hold_s + self.ramp_out_s

    def joint_ramps(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Every arm joint's ramp-in and ramp-out times (s) and contact share, ``arm``
        order."""
        k = len(self.arm)
        rin = np.full(k, self.ramp_in_s) if self.ramps_in_s is None else self.ramps_in_s
        rout = np.full(k, self.ramp_out_s) if self.ramps_out_s is None else self.ramps_out_s
        c = np.full(k, self.contact_share) if self.shares is None else self.shares
        return (np.asarray(rin, dtype=float), np.asarray(rout, dtype=float),
                np.asarray(c, dtype=float))

    def ramp_out_of(self, c: int) -> float:
        """The ramp-out time of the arm's ``c``-th joint."""
        return float(self.joint_ramps()[1][c])

    def knots(self) -> tuple[float, float, float, float, float, float]:
        """sigma at the ramp-in's start and end, the recoil's end, the hold's end, the end;
        and the time the hold ends, of the common ramps (``stop_knots``)."""
        return self._knots(self.ramp_in_s, self.ramp_out_s, self.contact_share)

    def _knots(self, ramp_in_s, ramp_out_s, c) -> tuple:
        """``stop_knots`` for ramps of these durations and the contact share ``c`` (floats,
        or arrays of every joint's)."""
        return stop_knots(c, self.t_i, self.row_s, ramp_in_s, self.recoil_s, self.hold_s,
                          ramp_out_s)

    def _profile(self, t: np.ndarray, ramp_in_s: float, ramp_out_s: float, c: float
                 ) -> np.ndarray:
        """The time-like scalar at ``t`` of a joint with these ramps and contact share ``c``
        (0 at the intercept)."""
        ti = self.t_i
        s1, _, s3, s4, _, t4 = self._knots(ramp_in_s, ramp_out_s, c)
        start = ti - self.row_s - ramp_in_s
        out = np.full(t.shape, s1)
        if ramp_in_s > 0:
            u = (t - start) / ramp_in_s
            out = np.where(t > start, s1 + c * ramp_in_s * ramp_integral(u), out)
        tau = t - ti
        out = np.where(t > ti - self.row_s, np.minimum(tau, 0.0) * c, out)
        if self.recoil_s > 0:
            w = np.clip(tau, 0.0, self.recoil_s)
            out = np.where(t > ti, c * w + (1.0 - c) * w * w / (2.0 * self.recoil_s), out)
        out = np.where(t > ti + self.recoil_s, s3 + np.minimum(t - ti - self.recoil_s,
                                                                self.hold_s), out)
        if ramp_out_s > 0:
            u = np.clip((t - t4) / ramp_out_s, 0.0, 1.0)
            out = np.where(t > t4, s4 + ramp_out_s * (u - ramp_integral(u)), out)
        return out

    def sigma(self, t_s: np.ndarray) -> np.ndarray:
        """The profile's time-like scalar at ``t_s`` (0 at the intercept), the common ramps'."""
        return self._profile(np.atleast_1d(np.asarray(t_s, dtype=float)), self.ramp_in_s,
                             self.ramp_out_s, self.contact_share)

    def sigmas(self, t_s: np.ndarray) -> np.ndarray:
        """(T, k) every arm joint's time-like scalar at ``t_s``."""
        t = np.atleast_1d(np.asarray(t_s, dtype=float))
        if not self.per_joint:
            return np.tile(self.sigma(t)[:, None], (1, len(self.arm)))
        return np.column_stack([self._profile(t, float(a), float(b), float(c))
                                for a, b, c in zip(*self.joint_ramps())])

    def offset(self, t_s: np.ndarray, n: int) -> np.ndarray:
        """(T, n) joint offsets from the intercept pose (only the arm joints move)."""
        t = np.atleast_1d(t_s)
        out = np.zeros((len(t), n))
        if not self.per_joint:
            out[:, list(self.arm)] = np.outer(self.sigma(t), self.qd)
        else:
            out[:, list(self.arm)] = self.sigmas(t) * self.qd
        return out

    @property
    def first_offset(self) -> np.ndarray:
        """Every arm joint's offset from the intercept pose where its ramp-in starts."""
        return self.qd * self._knots(*self.joint_ramps())[0]

    @property
    def last_offset(self) -> np.ndarray:
        """... and where its ramp-out ends (at rest)."""
        return self.qd * self._knots(*self.joint_ramps())[4]
