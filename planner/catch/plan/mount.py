"""Where the hand sits for a catch: the rail base (URDF root) relative to the nominal catch
point, from the hand file's ``[catch]`` section or computed (``default_mount``; see
``planner.catch.plan.api`` for the geometry)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import tomllib

from planner.catch.plan.arm import zero_pose
from planner.errors import InputError
from planner.hand.model import HandModel
from planner.hand.spec import hands_dir, rpy_matrix

DESIGN_DESCENT_DEG = 36.0  # default mount: the palm faces a ball descending at this angle
DESIGN_DEV_DEG = 10.0  # ... with the wrist deviated this much (room for the path's curvature)


@dataclass(frozen=True)
class CatchMount:
    """Pose of the rail base (URDF root) relative to the nominal catch point.

    ``offset_m``: root origin minus the catch point, catch-frame axes (m);
    ``rpy_deg``: URDF roll-pitch-yaw of the root in the catch frame (deg)."""

    offset_m: tuple[float, float, float]
    rpy_deg: tuple[float, float, float]
    source: str

    @property
    def rotation(self) -> np.ndarray:
        return rpy_matrix(tuple(math.radians(a) for a in self.rpy_deg))

    def T_ref(self) -> np.ndarray:
        """Root pose in the reference frame (catch point at the origin)."""
        T = np.eye(4)
        T[:3, :3] = self.rotation
        T[:3, 3] = self.offset_m
        return T

    def T_world_root(self, catch_point: np.ndarray) -> np.ndarray:
        T = self.T_ref()
        T[:3, 3] += np.asarray(catch_point, dtype=float)
        return T


def _hand_file(name_or_path: str) -> Path | None:
    p = Path(name_or_path)
    if p.suffix == ".toml":
        return p if p.is_file() else None
    f = hands_dir() / f"{name_or_path}.toml"
    return f if f.is_file() else None


def _vec3(d: dict[str, Any], key: str, where: str) -> tuple[float, float, float]:
    v = d.get(key)
    if (not isinstance(v, list) or len(v) != 3 or not all(
            isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)
            for x in v)):
        raise InputError(f"{where}: [catch] {key} must be a list of 3 finite numbers")
    return (float(v[0]), float(v[1]), float(v[2]))


def mount_from_file(path: Path) -> CatchMount | None:
    """The ``[catch]`` section of a hand file (``offset_m``, ``rpy_deg``), or None."""
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as e:
        raise InputError(f"cannot read hand file {path}: {e}") from None
    sec = data.get("catch")
    if sec is None:
        return None
    if not isinstance(sec, dict):
        raise InputError(f"{path.name}: [catch] must be a table")
    return CatchMount(_vec3(sec, "offset_m", path.name), _vec3(sec, "rpy_deg", path.name),
                      f"{path.name} [catch]")


def default_mount(hand: HandModel, descent_deg: float = DESIGN_DESCENT_DEG,
                  dev_deg: float = DESIGN_DEV_DEG) -> CatchMount:
    """The mount described in the module docstring, computed from the hand's geometry.

    Orientation: root x across the throw (+y of the catch frame), the palm normal at
    zero flexion = (-cos a, 0, sin a), a = ``descent_deg``: rpy = (90 + a, 0, 90).
    Position: the catch point C lies in the plane through the wrist axis that is
    parallel to the palm, at cos(``dev_deg``) times the palm centre's distance from
    the axis: a ball descending at ``descent_deg`` then lands on the palm centre with
    the wrist deviated by ``dev_deg``, which leaves deviation to spare both ways
    (towards 0 for the path's curvature, towards the limit for other angles)."""
    rpy = (90.0 + descent_deg, 0.0, 90.0)
    R = rpy_matrix(tuple(math.radians(a) for a in rpy))
    h = hand.mounted(np.eye(4))
    q0 = zero_pose(h)
    P = h.palm_pose(q0)
    pc, n = P[:3, 3], P[:3, 2]
    W = h.frame_pose(q0, "wrist_flex")[:3, 3]
    g = pc - W
    g_p = g - float(g @ n) * n
    c_root = W + math.cos(math.radians(dev_deg)) * g_p
    off = -R @ c_root
    return CatchMount((float(off[0]), float(off[1]), float(off[2])), rpy,
                      f"default (palm faces a {descent_deg:g} deg descent)")


def catch_mount(hand: HandModel, source: str | None = None) -> CatchMount:
    """The ``[catch]`` mount of the hand file ``source`` (a name or a .toml path;
    default: the shipped file named like the hand), else ``default_mount``."""
    f = _hand_file(source if source is not None else hand.name)
    m = mount_from_file(f) if f is not None else None
    return m if m is not None else default_mount(hand)

