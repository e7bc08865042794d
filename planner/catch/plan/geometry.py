"""Small vector helpers of the catch planner (plain numpy, fast on small arrays)."""

from __future__ import annotations

import math

import numpy as np


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product of (..., 3) arrays (np.cross is slow for small arrays)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def rot(axis: np.ndarray, ang: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate vectors ``v`` (N, 3) by angles ``ang`` (N,) about unit ``axis`` (Rodrigues)."""
    c = np.cos(ang)[:, None]
    s = np.sin(ang)[:, None]
    kv = cross(np.broadcast_to(axis, v.shape), v)
    return v * c + kv * s + np.outer(v @ axis, axis) * (1.0 - c)


def interp_row(t: np.ndarray, Q: np.ndarray, ti: float) -> np.ndarray:
    """Rows ``Q`` at times ``t`` interpolated linearly at ``ti`` (clamped to the ends)."""
    k = int(np.searchsorted(t, ti, side="right")) - 1
    if k < 0:
        return Q[0].copy()
    if k >= len(t) - 1:
        return Q[-1].copy()
    w = (ti - t[k]) / (t[k + 1] - t[k])
    return (1.0 - w) * Q[k] + w * Q[k + 1]


def rot1(axis: np.ndarray, ang: float, v: np.ndarray) -> np.ndarray:
    """``rot`` of one vector by one angle (plain float arithmetic: no array overhead)."""
    ex, ey, ez = axis.tolist()
    vx, vy, vz = v.tolist()
    c, s = math.cos(ang), math.sin(ang)
    kx, ky, kz = ey * vz - ez * vy, ez * vx - ex * vz, ex * vy - ey * vx
    d = vx * ex + vy * ey + vz * ez
    return np.array([vx * c + kx * s + d * ex * (1.0 - c), vy * c + ky * s + d * ey * (1.0 - c),
                     vz * c + kz * s + d * ez * (1.0 - c)])


def unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)



def bracketed_secant(f, ta: float, tb: float, fa: float, fb: float, iters: int = 12):
    """Root of a smooth function on the bracket [ta, tb] (fa > 0 >= fb): secant steps kept
    inside the shrinking bracket, bisection when a step leaves it. ``f(t)`` returns a
    tuple whose last item is the value; returns (t, f(t)) of the last iterate."""
    t0, f0, t1, f1 = ta, fa, tb, fb
    tm, out = 0.5 * (ta + tb), None
    for _ in range(iters):
        tm = t1 - f1 * (t1 - t0) / (f1 - f0) if f1 != f0 else 0.5 * (ta + tb)
        if not ta < tm < tb:
            tm = 0.5 * (ta + tb)
        out = f(tm)
        fm = out[-1]
        if fm > 0:
            ta = tm
        else:
            tb = tm
        t0, f0, t1, f1 = t1, f1, tm, fm
        if abs(fm) < 1e-8 or tb - ta < 1e-9:
            break
    return tm, out
