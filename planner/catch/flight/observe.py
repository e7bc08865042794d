"""Camera observations of a thrown ball: reading them (``t,x,y,z`` CSV, catch frame),
fitting a flight to them with its uncertainty (``fit_observations``), and what that
uncertainty means where the ball meets the hand (``predict_intercept``). The flight
itself, vacuum or drag, is ``planner.catch.flight.path``."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np

from planner.catch.flight.path import (
    FD_STEP,
    GRAVITY_M_S2,
    MAX_LAUNCH_SPEED_M_S,
    MAX_OBS_RANGE_M,
    MAX_TIME_S,
    Ball,
    Flight,
    finite_float,
    get_ball,
    step_for,
)
from planner.errors import InputError, PlannerError, SolverError


@dataclass(frozen=True, eq=False)
class FitResult:
    """A flight fitted to camera observations.

    ``covariance``: 6x6 of [p0, v0] (m, m/s), from the residuals (noise estimated
    per axis). ``residual_rms``: rms of the N x 3 residual components, m.
    ``sigma_axis``: the per-axis noise estimate, m.
    """

    flight: Flight
    covariance: np.ndarray
    residual_rms: float
    sigma_axis: np.ndarray
    n_observations: int


def _check_observations(ts: Any, ps: Any, min_rows: int) -> tuple[np.ndarray, np.ndarray]:
    try:
        t = np.array(ts, dtype=float)
        p = np.array(ps, dtype=float)
    except (TypeError, ValueError):
        raise InputError("observations must be numbers: ts (N,) and ps (N, 3)") from None
    if t.ndim != 1 or p.shape != (t.size, 3):
        raise InputError(f"observations must be ts (N,) and ps (N, 3), got {t.shape} and {p.shape}")
    if t.size < min_rows:
        raise InputError(f"{t.size} observations, need at least {min_rows}")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(p))):
        raise InputError("observations must be finite (no NaN or inf)")
    if np.any(np.diff(t) <= 0):
        raise InputError("observation times must be strictly increasing")
    if np.any(np.abs(t) > MAX_TIME_S):
        i = int(np.argmax(np.abs(t) > MAX_TIME_S))
        raise InputError(f"observation {i + 1}: t = {t[i]:.6g} s is more than {MAX_TIME_S:g} s "
                         "from the launch")
    far = np.abs(p).max(axis=1) > MAX_OBS_RANGE_M  # (a norm of such values overflows)
    if np.any(far):
        i = int(np.argmax(far))
        raise InputError(f"observation {i + 1}: the ball {np.abs(p[i]).max():.6g} m off the "
                         f"launch point along an axis, farther than any throw reaches "
                         f"({MAX_OBS_RANGE_M:g} m)")
    return t, p


def _weighted_cov(J: np.ndarray, res: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Covariance of the parameters from J (3n x 6, rows t-major) and residuals (n, 3)."""
    sigma = np.sqrt(np.sum(res * res, axis=0) / max(n - 2, 1))
    w = 1.0 / np.maximum(sigma, 1e-12)
    Jw = J * np.tile(w, n)[:, None]
    return np.linalg.pinv(Jw.T @ Jw), sigma


def _fd_jacobian(fun, theta: np.ndarray) -> np.ndarray:
    cols = []
    for i in range(theta.size):
        e = np.zeros_like(theta)
        e[i] = FD_STEP
        cols.append((fun(theta + e) - fun(theta - e)) / (2.0 * FD_STEP))
    return np.stack(cols, axis=-1)


def fit_observations(
    ts: Any, ps: Any, ball: Ball | str | None = None, drag_per_m: float = 0.0
) -> FitResult:
    """Fit (p0, v0) at t = 0 to noisy positions ``ps`` (N, 3) seen at times ``ts`` (N,).

    k = 0: linear least squares of p = p0 + v0 t + g t^2 / 2 (N >= 3).
    k > 0: least squares on the drag model from the vacuum fit (N >= 6).
    """
    b = get_ball(ball)
    k = finite_float("drag_per_m", drag_per_m)
    if k < 0:
        raise InputError(f"drag_per_m must be >= 0, got {k}")
    t, p = _check_observations(ts, ps, 6 if k > 0 else 3)
    n = t.size
    A = np.stack([np.ones(n), t], axis=1)
    y = p - 0.5 * GRAVITY_M_S2 * (t * t)[:, None]
    coef, *_ = np.linalg.lstsq(A, y, rcond=None)  # (2, 3): rows p0, v0
    theta = np.concatenate([coef[0], coef[1]])
    speed = float(np.linalg.norm(theta[3:]))
    if speed > MAX_LAUNCH_SPEED_M_S:
        raise InputError(f"the observations move at {speed:.4g} m/s at t = 0, faster than any "
                         f"throw (at most {MAX_LAUNCH_SPEED_M_S:g} m/s)")
    if k == 0.0:
        res = y - A @ coef
        M = np.linalg.pinv(A.T @ A)
        sigma = np.sqrt(np.sum(res * res, axis=0) / max(n - 2, 1))
        cov = np.zeros((6, 6))
        for ax in range(3):
            idx = [ax, 3 + ax]
            cov[np.ix_(idx, idx)] = sigma[ax] ** 2 * M
        flight = Flight(theta[:3], theta[3:], b, 0.0)
    else:
        step = step_for(k, float(np.linalg.norm(theta[3:])))

        def resid(th: np.ndarray) -> np.ndarray:
            return (Flight(th[:3], th[3:], b, k, step_s=step).position(t) - p).ravel()

        from scipy.optimize import least_squares  # (only here: 0.25 s to import)

        try:
            sol = least_squares(
                resid,
                theta,
                jac=lambda th: _fd_jacobian(resid, th),
                method="lm",
                xtol=1e-12,
                ftol=1e-12,
                gtol=1e-12,
            )
        except PlannerError as exc:  # a trial state the drag model cannot run
            raise SolverError(f"drag fit failed: {exc}", problem=(t, p, k)) from exc
        if not sol.success:
            raise SolverError(f"drag fit failed: {sol.message}", problem=(t, p, k))
        theta = sol.x
        res = sol.fun.reshape(n, 3)
        cov, sigma = _weighted_cov(_fd_jacobian(resid, theta), res, n)
        flight = Flight(theta[:3], theta[3:], b, k, step_s=step)
    cov = 0.5 * (cov + cov.T)
    cov.setflags(write=False)
    sigma.setflags(write=False)
    rms = float(np.sqrt(np.mean(res * res)))
    return FitResult(flight, cov, rms, sigma, n)


def predict_intercept(
    fit: FitResult, x_plane: float
) -> tuple[float, np.ndarray, np.ndarray, float]:
    """Where and when the fitted ball crosses the plane x = x_plane, with uncertainty.

    Returns (t, p, cov_p, sigma_t): p (3,) with p[0] = x_plane, cov_p (3, 3)
    (its x row and column are 0: the plane is given), sigma_t in s. The
    uncertainty is the fit covariance propagated through a central-difference
    Jacobian of (t, p) with respect to [p0, v0].
    """
    x = finite_float("x_plane", x_plane)
    fl = fit.flight

    def crossing(th: np.ndarray) -> np.ndarray:
        f = replace(fl, p0=th[:3], v0=th[3:])
        tc = f.time_at_x(x)
        pc = f.position(tc)
        return np.array([tc, x, pc[1], pc[2]])

    theta = np.concatenate([fl.p0, fl.v0])
    c0 = crossing(theta)
    J = _fd_jacobian(crossing, theta)
    C = J @ fit.covariance @ J.T
    cov_p = 0.5 * (C[1:, 1:] + C[1:, 1:].T)
    return float(c0[0]), c0[1:].copy(), cov_p, float(math.sqrt(max(C[0, 0], 0.0)))


def load_observations_csv(
    path: str | PathLike[str], *, min_rows: int = 3
) -> tuple[np.ndarray, np.ndarray]:
    """Read camera observations: header ``t,x,y,z`` then one row per frame.

    Returns (ts (N,), ps (N, 3)). Needs ``min_rows`` rows (3 for a vacuum fit,
    pass 6 for a drag fit), times strictly increasing, every value finite.
    InputError with one line on any problem.
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputError(f"{p}: observation file not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{p}: cannot read observation file ({exc})") from None
    lines = [(i, ln) for i, ln in enumerate(text.splitlines(), 1) if ln.strip()]
    if not lines:
        raise InputError(f"{p}: empty file, expected a header t,x,y,z")
    lineno, head = lines[0]
    header = [c.strip().lower() for c in _cells(p, lineno, head)]
    if header != ["t", "x", "y", "z"]:
        raise InputError(f"{p}: line {lineno}: header must be t,x,y,z, got {head.strip()!r}")
    rows = []
    for lineno, ln in lines[1:]:
        cells = _cells(p, lineno, ln)
        if len(cells) != 4:
            raise InputError(f"{p}: line {lineno}: expected 4 values t,x,y,z, got {len(cells)}")
        vals = []
        for name, c in zip("txyz", cells):
            try:
                v = float(c)
            except ValueError:
                raise InputError(
                    f"{p}: line {lineno}: {name} = {c.strip()!r} is not a number"
                ) from None
            if not math.isfinite(v):
                raise InputError(f"{p}: line {lineno}: {name} = {c.strip()!r} is not finite")
            vals.append(v)
        if rows and vals[0] <= rows[-1][0]:
            raise InputError(
                f"{p}: line {lineno}: time {vals[0]:g} is not after the previous {rows[-1][0]:g}"
            )
        rows.append(vals)
    if len(rows) < min_rows:
        raise InputError(f"{p}: {len(rows)} observation rows, need at least {min_rows}")
    arr = np.array(rows, dtype=float)
    return arr[:, 0].copy(), arr[:, 1:].copy()


def _cells(path: Path, lineno: int, line: str) -> list[str]:
    """One CSV line's fields; InputError (one line) on what the csv module refuses (a
    field over its 131,072-character limit, a stray quote)."""
    import csv  # (a file's reader only: a live session, which fits this module's
    # ``FitResult``s, does not load it)

    try:
        return next(csv.reader([line]))
    except csv.Error as e:
        raise InputError(f"{path}: line {lineno}: not a CSV line of t,x,y,z ({e})") from None
