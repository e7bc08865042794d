"""A package's names imported on first use (a module ``__getattr__`` and ``__dir__``,
PEP 562), so that importing the package stays light: ``planner``'s public API,
``planner.play``'s. Editors and type checkers see the names through the package's own
``if TYPE_CHECKING:`` imports; ``dir(package)`` lists them."""

from __future__ import annotations

import importlib
from collections.abc import Callable, Iterable
from typing import Any


def lazy_names(package: str, api: dict[str, str]) -> Callable[[str], Any]:
    """The ``__getattr__`` of ``package``: ``name`` taken from its module ``api[name]``,
    imported on first use (and kept in the package, so the next use is a plain
    attribute); AttributeError for any other name."""

    def __getattr__(name: str) -> Any:
        if name in api:
            value = getattr(importlib.import_module(api[name]), name)
            setattr(importlib.import_module(package), name, value)
            return value
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    return __getattr__


def lazy_dir(namespace: dict[str, Any], api: Iterable[str]) -> Callable[[], list[str]]:
    """The ``__dir__`` of a package whose module namespace is ``namespace`` (its
    ``globals()``): the names it holds and the lazy ones, sorted."""

    def __dir__() -> list[str]:
        return sorted(set(namespace) | set(api))

    return __dir__
