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
from planner.hand.spec import HandSpec, hands_dir, list_hands
from planner.hand.units import check_hand_numbers

# kind -> (module, function) building a HandSpec from the parsed hand file
BUILDERS = {
    "tendon": ("planner.hand.builders.tendon", "build_tendon_hand"),
    "mk5": ("planner.hand.builders.mk5", "build_mk5_hand"),
    "agh": ("planner.hand.builders.agh", "build_agh_hand"),
}


def load_hand_spec(name_or_path: str) -> HandSpec:
    """Load a shipped hand by name, or a hand file by path (.toml)."""
    path = Path(name_or_path)
    if path.suffix != ".toml":
        path = hands_dir() / f"{name_or_path}.toml"
        if not path.is_file():
            raise InputError(
                f"unknown hand {name_or_path!r}; valid hands: {', '.join(list_hands())}"
            )
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as e:
        raise InputError(f"cannot read hand file {path}: {e.strerror or e}") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        raise InputError(f"malformed hand file {path.name}: {e}") from None
    try:
        check_hand_numbers(data)  # (every number in its unit's physical range, strings printable)
        return build_spec(data)
    except InputError as e:
        raise InputError(f"malformed hand file {path.name}: {e}") from None
    except (KeyError, TypeError, ValueError, IndexError, ZeroDivisionError, AttributeError) as e:
        raise InputError(f"malformed hand file {path.name}: bad or missing entry {e}") from None


def build_spec(data: dict[str, Any]) -> HandSpec:
    """Build the kinematic tree of a hand from its parsed TOML (its ``kind``'s builder)."""
    kind = data.get("kind", "tendon")
    if kind not in BUILDERS:
        raise InputError(f"unknown hand kind {kind!r}; valid kinds: {', '.join(BUILDERS)}")
    module, function = BUILDERS[kind]
    return getattr(importlib.import_module(module), function)(data)
