"""The live catch's stop table kept between runs (opt-in): ``StopTable.make`` (15 throws
through the catch point, each the planned catch's tilt search and stopping motion: ~0.1 s
of CPU, the largest step of ``catch --live``'s set-up after the imports) is a function of
the hand, the catch point, the ball, drag and the rows' interval, and of the code. A rig is
set up once at a distance, and its sessions repeat their ``--dist`` and ``--height``:
with ``HAND_PLANNER_CACHE=DIR`` in the environment a table is written to ``DIR`` when it
is made and read back, the same numbers to the bit (npz keeps every float64), by the next
session with the same key. Without the variable nothing is written or read (a clean clone,
the tests). The key (``table_key``) is a hash of every parameter the table reads and of the
source of the whole ``planner`` package (``code_sha256``: any change of the code makes a
new key; old files are left, never read), numpy's version beside it. A file that cannot
be read or written is ignored: the table is made as without the cache.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import zipfile
from functools import lru_cache
from pathlib import Path

import numpy as np

from planner.catch.plan.softstop import SoftStop

CACHE_ENV = "HAND_PLANNER_CACHE"  # a directory: the stop tables kept between runs
PACKAGE_DIR = Path(__file__).parents[2]  # planner/
_ARRAYS = ("qd", "v_palm", "v_rel", "force_n", "motor_ratio")
_PER_JOINT = ("ramps_in_s", "ramps_out_s", "shares")  # (None in every live stop: the
# planned catch's per-joint stops, ``planner.catch.plan.ramps``, are not kept)
_SCALARS = tuple(f.name for f in dataclasses.fields(SoftStop)
                 if f.name not in ("arm", *_ARRAYS, *_PER_JOINT))


def cache_dir() -> Path | None:
    """The cache's directory (``HAND_PLANNER_CACHE``), None when it is not set."""
    d = os.environ.get(CACHE_ENV, "")
    return Path(d) if d else None


@lru_cache(maxsize=1)
def code_sha256() -> str:
    """A hash of every source file of the ``planner`` package (paths and contents)."""
    h = hashlib.sha256()
    for p in sorted(PACKAGE_DIR.rglob("*.py")):
        h.update(str(p.relative_to(PACKAGE_DIR)).encode())
        h.update(p.read_bytes())
    return h.hexdigest()


def table_key(pl, C: np.ndarray, ball, drag: bool, row_s: float) -> str:
    """The key of the stop table of planner ``pl`` at catch point ``C``."""
    hand = pl.hand
    params = {"code": code_sha256(), "numpy": np.__version__, "urdf": hand.urdf_sha256,
              "spec": hashlib.sha256(repr(hand.spec).encode()).hexdigest(),
              "mount": repr(pl.mount), "C": [float(x).hex() for x in C],
              "ball": repr(ball), "drag": bool(drag), "row_s": float(row_s).hex()}
    return hashlib.sha256(json.dumps(params, sort_keys=True).encode()).hexdigest()


def table_path(directory: Path, key: str) -> Path:
    return directory / f"live-stop-{key[:32]}.npz"


def load(path: Path):
    """The parts of a kept table (angles, tilts, stops, prior), None when it cannot be
    read."""
    try:
        with np.load(path, allow_pickle=False) as z:  # (each array read from the file
            a = {n: z[n] for n in ("arm", "angles_deg", "tilts_rad", "prior", *_SCALARS,
                                   *_ARRAYS)}  # once: ``z[n]`` parses it again each time)
    except (OSError, EOFError, KeyError, ValueError, zipfile.BadZipFile):
        return None
    arm = tuple(int(i) for i in a["arm"])
    scalars = {n: a[n].tolist() for n in _SCALARS}  # (Python floats: float(x) of each)
    try:
        stops = tuple(SoftStop(**{n: scalars[n][k] for n in _SCALARS},
                               **{n: a[n][k].copy() for n in _ARRAYS}, arm=arm)
                      for k in range(len(a["angles_deg"])))
    except (IndexError, TypeError, ValueError):
        return None
    return a["angles_deg"], a["tilts_rad"], stops, a["prior"]


def save(path: Path, angles_deg: np.ndarray, tilts_rad: np.ndarray,
         stops: tuple[SoftStop, ...], prior: np.ndarray) -> None:
    """Write a table (atomically: a reader sees the whole file or none); ignored when the
    directory cannot be written."""
    if not stops or any(s.per_joint for s in stops):
        return
    arm = np.array(stops[0].arm, dtype=int)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with open(tmp, "wb") as fh:
            np.savez(fh, angles_deg=angles_deg, tilts_rad=tilts_rad, prior=prior, arm=arm,
                     **{n: np.array([getattr(s, n) for s in stops], dtype=float)
                        for n in _SCALARS},
                     **{n: np.array([getattr(s, n) for s in stops]) for n in _ARRAYS})
        os.replace(tmp, path)
    except OSError:
        tmp.unlink(missing_ok=True)
