"""The shape of ``planner/``'s imports (issue 33): no import cycle between its modules,
and no private (underscore) name taken from another of its modules.

Both read the source with ``ast``: every ``import`` and ``from ... import`` counts,
at module level and inside functions alike (a deferred import is still a dependency);
those under ``if TYPE_CHECKING:`` do not (they never run)."""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "planner"

PRIVATE_EXEMPT: tuple[str, ...] = ()  # (none: the catch package's went with its rearrangement)


def _modules() -> dict[str, Path]:
    out = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


MODULES = _modules()


def _type_checking_only(tree: ast.AST) -> set[int]:
    """The ids of the nodes under ``if TYPE_CHECKING:`` (or ``typing.TYPE_CHECKING``)."""
    skip: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If):
            t = node.test
            if ((isinstance(t, ast.Name) and t.id == "TYPE_CHECKING")
                    or (isinstance(t, ast.Attribute) and t.attr == "TYPE_CHECKING")):
                for child in node.body:
                    skip.update(id(n) for n in ast.walk(child))
    return skip


def _resolve(module: str, node: ast.ImportFrom) -> str | None:
    """The absolute module a ``from`` import names (relative ones resolved)."""
    if node.level == 0:
        return node.module
    base = module.split(".")
    if MODULES[module].name != "__init__.py":
        base = base[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def _imports(module: str) -> list[tuple[str, str | None, int]]:
    """(imported module, name taken from it or None, line) of every import that runs."""
    tree = ast.parse(MODULES[module].read_text(encoding="utf-8"))
    skip = _type_checking_only(tree)
    out = []
    for node in ast.walk(tree):
        if id(node) in skip:
            continue
        if isinstance(node, ast.Import):
            out.extend((a.name, None, node.lineno) for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            source = _resolve(module, node)
            for a in node.names:
                sub = f"{source}.{a.name}"
                if sub in MODULES:  # ``from planner.x import y``, y a module
                    out.append((sub, None, node.lineno))
                else:
                    out.append((source, a.name, node.lineno))
    return out


def _graph() -> dict[str, set[str]]:
    return {m: {t for t, _, _ in _imports(m) if t in MODULES and t != m} for m in MODULES}


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_the_import_graph_of_planner_has_no_cycle():
    graph = _graph()
    cycles = _cycles(graph)
    assert not cycles, "import cycles: " + "; ".join(
        " <-> ".join(c) + " (" + ", ".join(f"{a} -> {b}" for a in c for b in sorted(graph[a])
                              if b in c) + ")" for c in cycles)


def test_the_cycle_finder_finds_a_cycle():
    """The test above can fail: a two-module loop and a three-module one are found, a
    chain is not."""
    g = {"a": {"b"}, "b": {"a"}, "c": {"d"}, "d": {"e"}, "e": {"c"}, "f": {"a"}}
    assert _cycles(g) == [["a", "b"], ["c", "d", "e"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []


def _exempt(module: str) -> bool:
    return any(module == p or module.startswith(p + ".") for p in PRIVATE_EXEMPT)


def test_no_private_name_is_imported_from_another_module():
    bad = []
    for module in MODULES:
        if _exempt(module):
            continue
        for source, name, line in _imports(module):
            if (name is not None and name.startswith("_") and not name.startswith("__")
                    and source.split(".")[0] == "planner" and source != module
                    and not _exempt(source)):
                bad.append(f"{MODULES[module].relative_to(PACKAGE.parent)}:{line}: "
                           f"{name} from {source}")
    assert not bad, "private names imported across modules:\n" + "\n".join(bad)


def test_every_import_of_planner_names_a_module_that_exists():
    """The graph above is only as good as its names: every ``planner...`` import
    resolves to a module of the package (a misspelt one would leave an edge out)."""
    missing = sorted({(m, t) for m in MODULES for t, _, _ in _imports(m)
                      if t.split(".")[0] == "planner" and t not in MODULES})
    assert not missing, missing
