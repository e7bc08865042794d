"""Hand builders behind a registry: a hand file's ``kind`` names the module that builds
its ``HandSpec`` (``BUILDERS``); ``load_hand_spec`` reads a hand file and hands it to
its builder. ``planner.hand.spec`` (what a hand is) imports none of them.

The builders: ``tendon`` (the default hand), ``mk5`` (the Hand Mk5's leverism),
``agh`` (the AGH mechanical hand); ``common`` holds what they share, ``values`` the
hand file's value readers."""

from __future__ import annotations

import importlib
from pathlib import Path
from typing import Any

import tomllib

from planner.errors import InputError
from planner.hand.mirror import SIDES, mirror_spec
from planner.hand.spec import HandSpec, hands_dir, list_hands
from planner.hand.units import check_hand_numbers

# kind -> (module, function) building a HandSpec from the parsed hand file
BUILDERS = {
    "tendon": ("planner.hand.builders.tendon", "build_tendon_hand"),
    "mk5": ("planner.hand.builders.mk5", "build_mk5_hand"),
    "agh": ("planner.hand.builders.agh", "build_agh_hand"),
}


EXTENDS_DEPTH = 4  # hand files a chain of ``extends`` may pass through (a guard, no more)


def load_hand_spec(name_or_path: str) -> HandSpec:
    """Load a shipped hand by name, or a hand file by path (.toml)."""
    path = hand_path(name_or_path)
    try:
        data = read_hand_file(path)
        check_hand_numbers(data)  # (every number in its unit's physical range, strings printable)
        return build_spec(data)
    except InputError as e:
        raise InputError(f"malformed hand file {path.name}: {e}") from None
    except (KeyError, TypeError, ValueError, IndexError, ZeroDivisionError, AttributeError) as e:
        raise InputError(f"malformed hand file {path.name}: bad or missing entry {e}") from None


def hand_path(name_or_path: str, folder: Path | None = None) -> Path:
    """The file of a shipped hand's name, or a hand file's path (.toml; relative to
    ``folder`` when given: the folder of the file that names it)."""
    path = Path(name_or_path)
    if path.suffix == ".toml":
        return path if folder is None or path.is_absolute() else folder / path
    path = hands_dir() / f"{name_or_path}.toml"
    if not path.is_file():
        raise InputError(f"unknown hand {name_or_path!r}; valid hands: {', '.join(list_hands())}")
    return path


def read_hand_file(path: Path, depth: int = 0) -> dict[str, Any]:
    """A hand file's tables. ``extends = "NAME"`` (a shipped hand, or a hand file's path
    relative to this one's folder): that hand's tables with this file's merged over them
    (a table key by key, at every depth; any other value, a list of tables such as
    ``[[finger]]`` included, replaced whole), so that a variant of a hand (the shipped
    ``default-left``: ``side = "left"``) names only what differs and its numbers stay
    the other file's."""
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as e:
        raise InputError(f"cannot read hand file {path}: {e.strerror or e}") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        raise InputError(f"malformed hand file {path.name}: {e}") from None
    base = data.pop("extends", None)
    if base is None:
        return data
    if not isinstance(base, str) or not base:
        raise InputError(f"malformed hand file {path.name}: 'extends' must be a hand name "
                         "or a hand file's path")
    if depth >= EXTENDS_DEPTH:
        raise InputError(f"malformed hand file {path.name}: 'extends' chains more than "
                         f"{EXTENDS_DEPTH} files (a cycle?)")
    return merged(read_hand_file(hand_path(base, path.parent), depth + 1), data)


def merged(base: dict[str, Any], over: dict[str, Any]) -> dict[str, Any]:
    """``over``'s keys over ``base``'s: tables merged key by key, any other value replaced."""
    out = dict(base)
    for k, v in over.items():
        out[k] = merged(out[k], v) if isinstance(v, dict) and isinstance(out.get(k), dict) else v
    return out


def build_spec(data: dict[str, Any]) -> HandSpec:
    """Build the kinematic tree of a hand from its parsed TOML (its ``kind``'s builder), a
    right hand; ``side = "left"``: its mirror image (``planner.hand.mirror``)."""
    kind = data.get("kind", "tendon")
    if kind not in BUILDERS:
        raise InputError(f"unknown hand kind {kind!r}; valid kinds: {', '.join(BUILDERS)}")
    side = data.get("side", "right")
    if side not in SIDES:
        raise InputError(f"side must be one of {', '.join(map(repr, SIDES))}, got {side!r}")
    module, function = BUILDERS[kind]
    spec = getattr(importlib.import_module(module), function)(data)
    return mirror_spec(spec, side)
