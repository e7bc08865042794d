"""A package's names imported on first use (a module ``__getattr__``, PEP 562), so that
importing the package stays light: ``planner``'s public API, ``planner.play``'s."""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import Any


def lazy_names(package: str, api: dict[str, str]) -> Callable[[str], Any]:
    """The ``__getattr__`` of ``package``: ``name`` taken from its module ``api[name]``,
    imported on first use; AttributeError for any other name."""

    def __getattr__(name: str) -> Any:
        if name in api:
            return getattr(importlib.import_module(api[name]), name)
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    return __getattr__
