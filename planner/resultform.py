"""How a result is written out, by ``check`` and ``simulate`` alike: as plain values JSON
takes (``plain``) and as a titled list in a summary (``listing``)."""

from __future__ import annotations

import enum
import math
from dataclasses import fields, is_dataclass
from typing import Any

import numpy as np


def listing(L: list[str], title: str, items, fmt, first: int = 10) -> None:
    """A summary's titled list: ``title (n):``, then the first ``first`` items, each
    ``fmt(item)`` on its own indented line, and how many more there are."""
    if not items:
        return
    L.append(f"{title} ({len(items)}):")
    L.extend("  " + fmt(x) for x in items[:first])
    if len(items) > first:
        L.append(f"  ... and {len(items) - first} more")


def missed_note_line(m) -> str:
    """A missed note's line in a summary (the check's and the physics' alike): its time,
    name, pitch, how much of it its key was down and why."""
    return (f"{m.onset_s:8.3f}-{m.offset_s:.3f} s  {m.name:4s} ({m.pitch})  "
            f"down {m.fraction_down:.0%}  {m.reason}")


def plain(x: Any) -> Any:
    """``x`` as JSON takes it: dataclasses as dicts, sequences and arrays as lists, NumPy
    scalars as Python's, an enum as its value, a non-finite float as None (null)."""
    if isinstance(x, enum.Enum):
        return x.value
    if is_dataclass(x) and not isinstance(x, type):
        return {f.name: plain(getattr(x, f.name)) for f in fields(x)}
    if isinstance(x, (list, tuple)):
        return [plain(v) for v in x]
    if isinstance(x, dict):
        return {str(k): plain(v) for k, v in x.items()}
    if isinstance(x, np.ndarray):
        return plain(x.tolist())
    if isinstance(x, (np.bool_, bool)):
        return bool(x)
    if isinstance(x, (np.integer, int)):
        return int(x)
    if isinstance(x, (np.floating, float)):
        v = float(x)
        return v if math.isfinite(v) else None
    return x
