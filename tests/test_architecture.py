"""The shape of the house, read from the source with ``ast``: data flows one way.

Every ``import`` in ``src/tribopipe`` counts, at any depth: at module level, inside
functions and in ``if TYPE_CHECKING:`` blocks (a type-only import is still a dependency;
a cycle through one says a type lives in the wrong room). Importing ``a.b.c`` also runs the
packages ``a.b`` above it, so that counts as depending on them too.

A module or function named as text (``"tribopipe.export.fe_decks:write_abaqus"``, for
``importlib`` to import later) counts as an import of that module too, so a cycle through
such a name shows; and outside the CLI's lazy command table no function is named so.

The checks: no import cycle; no module imports one from a higher layer of :data:`LAYERS`;
click only under ``tribopipe.cli``, whose modules import only click and the standard
library at module level (so ``tribopipe --help`` stays light); no library module imports
the package's own modules inside a function (that is how cycles hide); no private name
(``_x``) imported from another module; every name imported from the module that defines
it (one import path per name; a package's ``__all__`` is the exception). A module's
length is no rule: a room holds one concept, whatever its length.
"""

from __future__ import annotations

import ast
import re
import sys
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"
PACKAGE = "tribopipe"

#: The import layers, bottom to top: a module may import its own layer and those below,
#: never one above. A module belongs to the layer of the longest name that prefixes it.
LAYERS: tuple[tuple[str, ...], ...] = (
    # the base: errors, escapes of outside text, validation of outside values, files on
    # disk, numbers from outside, units, the output folder
    ("tribopipe", "tribopipe.errors", "tribopipe.escape", "tribopipe.validate",
     "tribopipe.files", "tribopipe.numeric", "tribopipe.units", "tribopipe.layout",
     "tribopipe.rounding", "tribopipe.project", "tribopipe.materials",
     "tribopipe.reporting", "tribopipe.memory"),
    ("tribopipe.measurement",),
    ("tribopipe.physics",),
    ("tribopipe.config",),
    # raw exports in
    ("tribopipe.readers",),
    # the reduction method, one package (its docstring describes the method): the signal
    # filters and a run's uncertainty budget, the friction interval, the detection steps,
    # the reduction of one run
    ("tribopipe.reduction", "tribopipe.reduction.signals", "tribopipe.reduction.uncertainty",
     "tribopipe.reduction.manual"),
    ("tribopipe.reduction.intervals",),
    ("tribopipe.reduction.detection", "tribopipe.reduction.reciprocating",
     "tribopipe.reduction.parameters"),
    ("tribopipe.reduction.reduce",),
    # what a run is and its QC flags, decided once from its labels and its reduction,
    # before anything prints, plots or stores it
    ("tribopipe.labels",),
    ("tribopipe.figures",),
    # pure statistics over map rows: below the map, whose printed summary uses them
    ("tribopipe.stats",),
    ("tribopipe.frictionmap",),
    # one export to its runs, their files and their one landing in the map; a lab's
    # decisions applied to the map's rows (in that landing)
    ("tribopipe.pipeline", "tribopipe.review"),
    # many exports, incrementally; a package's evidence re-derived through the one route
    ("tribopipe.campaign", "tribopipe.evidence"),
    # the one rule for μ between measured conditions, below everything that reads it
    ("tribopipe.interpolation",),
    ("tribopipe.query", "tribopipe.query_text", "tribopipe.fit", "tribopipe.mastercurve"),
    ("tribopipe.export",),
    ("tribopipe.report", "tribopipe.hub"),
    ("tribopipe.cli", "tribopipe.__main__"),
)

#: own-module imports a library module may make inside a function, with the reason
#: (only to keep a heavy third-party package off the ``tribopipe --help`` path)
LAZY_IMPORTS_ALLOWED: dict[tuple[str, str], str] = {}


@dataclass(frozen=True)
class Import:
    """One import of one of the package's modules."""

    importer: str
    target: str
    line: int
    in_function: bool
    type_only: bool
    by_name: bool = False


def module_name(path: Path) -> str:
    parts = list(path.relative_to(SRC).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


MODULES: dict[str, Path] = {module_name(p): p for p in sorted((SRC / PACKAGE).rglob("*.py"))}


def is_package(name: str) -> bool:
    return MODULES[name].name == "__init__.py"


def _is_type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def _walk(node: ast.AST, in_function: bool = False,
          type_only: bool = False) -> Iterator[tuple[ast.AST, bool, bool]]:
    for child in ast.iter_child_nodes(node):
        yield child, in_function, type_only
        yield from _walk(
            child,
            in_function or isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda),
            type_only or (isinstance(child, ast.If) and _is_type_checking(child)),
        )


def _resolve(importer: str, node: ast.ImportFrom) -> str:
    if not node.level:
        return node.module or ""
    base = importer.split(".")
    if not is_package(importer):
        base = base[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


#: a module, or a name in it, written as text for importlib: ``tribopipe.x.y:name``
NAMED = re.compile(r"(tribopipe(?:\.\w+)*):\w+")


def _named_module(text: str) -> str | None:
    """The package module a ``"module:name"`` text names (its longest known prefix)."""
    match = NAMED.fullmatch(text)
    if match is None:
        return None
    parts = match.group(1).split(".")
    for cut in range(len(parts), 0, -1):
        if ".".join(parts[:cut]) in MODULES:
            return ".".join(parts[:cut])
    return None


def _import_by_name(node: ast.AST) -> str | None:
    """The text of ``importlib.import_module("...")`` / ``__import__("...")`` (None for any
    other node; ``"?"`` when the argument is not a constant text)."""
    if not isinstance(node, ast.Call):
        return None
    func = node.func
    called = (func.attr if isinstance(func, ast.Attribute) else
              func.id if isinstance(func, ast.Name) else "")
    if called not in {"import_module", "__import__"}:
        return None
    arg = node.args[0] if node.args else None
    return arg.value if isinstance(arg, ast.Constant) and isinstance(arg.value, str) else "?"


def imports_of(name: str) -> list[Import]:
    """Every import of a package module by module ``name`` (own ancestors excluded),
    references by name (``"module:function"`` texts, ``importlib`` calls) included."""
    tree = ast.parse(MODULES[name].read_text(encoding="utf-8"))
    found: list[Import] = []
    for node, in_function, type_only in _walk(tree):
        targets: list[str] = []
        by_name = False
        dynamic = _import_by_name(node)
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            named = _named_module(node.value)
            targets, by_name = ([named] if named else []), True
        elif dynamic is not None and dynamic in MODULES:
            targets, by_name = [dynamic], True
        elif isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = _resolve(name, node)
            for alias in node.names:
                sub = f"{base}.{alias.name}"
                targets.append(sub if sub in MODULES else base)
        for target in targets:
            if target != PACKAGE and not target.startswith(PACKAGE + "."):
                continue
            # importing a.b.c runs a and a.b first: depending on them, unless they are
            # the importer's own packages (already running when it is imported)
            parts = target.split(".")
            for k in range(1, len(parts) + 1):
                dep = ".".join(parts[:k])
                if dep in MODULES and dep != name and not name.startswith(dep + "."):
                    found.append(Import(name, dep, node.lineno, in_function, type_only,
                                        by_name))
    return list(dict.fromkeys(found))  # one per target and line


GRAPH: dict[str, list[Import]] = {name: imports_of(name) for name in MODULES}


def layer_of(name: str) -> int:
    best, best_len = None, -1
    for index, members in enumerate(LAYERS):
        for prefix in members:
            if (name == prefix or name.startswith(prefix + ".")) and len(prefix) > best_len:
                best, best_len = index, len(prefix)
    assert best is not None, f"{name} is in no layer of LAYERS: add it"
    return best


def cycles() -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for imp in GRAPH[v]:
            w = imp.target
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(GRAPH):
        if v not in index:
            visit(v)
    return found


def _where(imp: Import) -> str:
    kind = (" (by name)" if imp.by_name else " (type-only)" if imp.type_only
            else " (in a function)" if imp.in_function else "")
    where = f"{MODULES[imp.importer].relative_to(SRC)}:{imp.line}"
    return f"{where}: {imp.importer} -> {imp.target}{kind}"


# ----------------------------------------------------------------------------- the checks


def test_the_graph_sees_every_kind_of_import() -> None:
    """The checks below are only as good as this walk: it must see imports in functions,
    under TYPE_CHECKING, relative and absolute, of packages and of their modules."""
    route = {(i.target, i.in_function, i.type_only) for i in GRAPH["tribopipe.pipeline.route"]}
    assert ("tribopipe.reduction.reduce", False, False) in route
    assert ("tribopipe.config", False, True) in route  # under TYPE_CHECKING
    assert ("tribopipe.frictionmap.records", False, False) in route
    assert ("tribopipe.frictionmap", False, False) in route  # its package runs first
    assert ("tribopipe.pipeline.runs", False, False) in route  # relative, in its package
    readers = {i.target for i in GRAPH["tribopipe.readers"]}
    assert {"tribopipe.readers.plaincsv", "tribopipe.readers.textio"} <= readers
    cli_reduce = {(i.target, i.in_function) for i in GRAPH["tribopipe.cli.reduce"]}
    assert ("tribopipe.pipeline.route", True) in cli_reduce
    # a package's own modules do not depend on the package they are in
    assert "tribopipe.frictionmap" not in {i.target for i in GRAPH["tribopipe.frictionmap.store"]}
    # a module named as text for importlib (the CLI's lazy command table) is an import
    cli = {(i.target, i.by_name) for i in GRAPH["tribopipe.cli"]}
    assert ("tribopipe.cli.reduce", True) in cli


def test_there_is_no_import_cycle() -> None:
    found = cycles()
    details = []
    for component in found:
        inside = set(component)
        details += [_where(i) for m in component for i in GRAPH[m] if i.target in inside]
    assert not found, "import cycles:\n" + "\n".join(details)


def _dynamic_imports(name: str) -> Iterator[int]:
    """The lines of module ``name`` that import a module whose name is only known at run
    time (``importlib.import_module(x)``)."""
    tree = ast.parse(MODULES[name].read_text(encoding="utf-8"))
    for node, _, _ in _walk(tree):
        if _import_by_name(node) == "?":
            yield node.lineno  # type: ignore[attr-defined]


def test_no_function_is_named_as_text() -> None:
    """A function named as text (``"module:function"``, imported by ``importlib`` when it
    is called) hides its import from the graph and its signature from mypy: a library
    module holds the function itself (the simulator registry holds its writers). The
    CLI's lazy command table is the exception: it keeps numpy and friends off the path
    of ``--help``, and its names are the CLI's own modules."""
    offenders = [_where(i) for imports in GRAPH.values() for i in imports
                 if i.by_name and not i.importer.startswith("tribopipe.cli")]
    offenders += [f"{MODULES[name].relative_to(SRC)}:{line}: an import by a name known "
                  "only at run time"
                  for name in MODULES if not name.startswith("tribopipe.cli")
                  for line in _dynamic_imports(name)]
    assert not offenders, "functions or modules named as text:\n" + "\n".join(offenders)


def test_no_module_imports_from_a_higher_layer() -> None:
    upward = [
        f"{_where(i)}: layer {layer_of(i.importer)} imports layer {layer_of(i.target)}"
        for imports in GRAPH.values() for i in imports
        if layer_of(i.target) > layer_of(i.importer)
    ]
    assert not upward, "imports against the data flow:\n" + "\n".join(upward)


def test_every_module_has_a_layer() -> None:
    for name in MODULES:
        layer_of(name)


def _third_party_imports(name: str) -> Iterator[tuple[str, int, bool, bool]]:
    tree = ast.parse(MODULES[name].read_text(encoding="utf-8"))
    for node, in_function, type_only in _walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name.split(".")[0], node.lineno, in_function, type_only
        elif isinstance(node, ast.ImportFrom) and not node.level and node.module:
            yield node.module.split(".")[0], node.lineno, in_function, type_only


def test_only_the_cli_imports_click() -> None:
    offenders = [
        f"{MODULES[name].relative_to(SRC)}:{line}"
        for name in MODULES if not (name == "tribopipe.cli" or name.startswith("tribopipe.cli."))
        for top, line, _, _ in _third_party_imports(name) if top == "click"
    ]
    assert not offenders, "library modules importing click: " + ", ".join(offenders)


def test_cli_modules_import_only_click_and_the_standard_library_at_module_level() -> None:
    """What ``tribopipe --help`` loads: the CLI modules' module-level imports."""
    allowed = set(sys.stdlib_module_names) | {"click", "__future__"}
    offenders = []
    for name in MODULES:
        if not name.startswith("tribopipe.cli"):
            continue
        for top, line, in_function, type_only in _third_party_imports(name):
            if not in_function and not type_only and top not in allowed:
                offenders.append(f"{MODULES[name].relative_to(SRC)}:{line}: {top}")
        for imp in GRAPH[name]:
            light = imp.target == PACKAGE or imp.target.startswith("tribopipe.cli")
            if not imp.in_function and not imp.type_only and not light:
                offenders.append(_where(imp))
    assert not offenders, "heavy imports on the --help path:\n" + "\n".join(offenders)


def test_library_modules_import_their_own_package_at_the_top() -> None:
    """An import inside a function is how a cycle hides; the CLI's are the exception
    (they keep numpy, pandas and friends off the --help path)."""
    lazy = [
        _where(i) for imports in GRAPH.values() for i in imports
        if i.in_function and not i.importer.startswith("tribopipe.cli")
        and (i.importer, i.target) not in LAZY_IMPORTS_ALLOWED
    ]
    assert not lazy, "own-module imports inside library functions:\n" + "\n".join(lazy)


def _top_level_names(name: str) -> tuple[set[str], set[str] | None]:
    """What module ``name`` defines at its top level (functions, classes, assignments, also
    inside top-level ``if``/``try`` blocks), and its ``__all__`` when it has one."""
    tree = ast.parse(MODULES[name].read_text(encoding="utf-8"))
    defined: set[str] = set()
    listed: set[str] | None = None
    body = list(tree.body)
    while body:
        node = body.pop(0)
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            defined.add(node.name)
        elif isinstance(node, ast.Assign | ast.AnnAssign | ast.AugAssign):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for target in targets:
                defined |= {n.id for n in ast.walk(target) if isinstance(n, ast.Name)}
            if isinstance(node, ast.Assign) and any(
                    isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets):
                listed = {e.value for e in getattr(node.value, "elts", [])
                          if isinstance(e, ast.Constant)}
        elif isinstance(node, ast.If) and not _is_type_checking(node):
            body += node.body + node.orelse
        elif isinstance(node, ast.Try):
            body += node.body + [n for h in node.handlers for n in h.body] + node.orelse
    return defined, listed


def _named_imports(name: str) -> Iterator[tuple[str, str, int]]:
    """(module, imported name, line) of every ``from <own module> import <name>`` in
    module ``name`` that imports a name, not a module."""
    tree = ast.parse(MODULES[name].read_text(encoding="utf-8"))
    for node, _, _ in _walk(tree):
        if isinstance(node, ast.ImportFrom):
            base = _resolve(name, node)
            if base in MODULES and base != name:
                for alias in node.names:
                    if f"{base}.{alias.name}" not in MODULES and alias.name != "*":
                        yield base, alias.name, node.lineno


def test_no_private_name_is_imported_across_modules() -> None:
    """A ``_name`` is its module's own business: a name another module needs is public in
    its home module (or the code moves to where it is used)."""
    offenders = [
        f"{MODULES[name].relative_to(SRC)}:{line}: {target}.{imported}"
        for name in MODULES for target, imported, line in _named_imports(name)
        if imported.startswith("_") and not imported.startswith("__")
    ]
    assert not offenders, "private names imported from another module:\n" + "\n".join(offenders)


def test_every_name_is_imported_from_the_module_that_defines_it() -> None:
    """One import path per name: no module passes on a name it imported (a package's
    ``__all__`` is its deliberate, short exception)."""
    tops = {name: _top_level_names(name) for name in MODULES}
    offenders = []
    for name in MODULES:
        for target, imported, line in _named_imports(name):
            defined, listed = tops[target]
            if imported in defined or (listed is not None and imported in listed):
                continue
            offenders.append(f"{MODULES[name].relative_to(SRC)}:{line}: {imported} "
                             f"imported from {target}, which does not define it")
    assert not offenders, "names imported from a module that only passes them on:\n" + \
        "\n".join(offenders)


def test_the_checks_catch_what_they_are_for(tmp_path: Path) -> None:
    """Each rule fails on a small house built to break it (so a pass above means something)."""
    global MODULES, GRAPH, SRC
    saved = MODULES, GRAPH, SRC
    pkg = tmp_path / "tribopipe"
    (pkg / "cli").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "errors.py").write_text("_hidden = 1\n")
    (pkg / "layout.py").write_text("from .errors import _hidden\n")
    (pkg / "config.py").write_text("from typing import TYPE_CHECKING\n"
                                   "if TYPE_CHECKING:\n    from .reduction.reduce import X\n")
    (pkg / "reduction").mkdir()
    (pkg / "reduction" / "__init__.py").write_text("")
    (pkg / "reduction" / "reduce.py").write_text("import click\nfrom ..config import Y\n"
                                   "def f():\n    from ..report import Z\n")
    (pkg / "report.py").write_text("x = 1\nWRITER = 'tribopipe.hub:write'\n")
    (pkg / "hub.py").write_text("from .report import x\ndef write():\n    return x\n")
    (pkg / "files.py").write_text("import importlib\n"
                                  "def load(n):\n    return importlib.import_module(n)\n")
    (pkg / "cli" / "__init__.py").write_text("import numpy\nfrom ..report import W\n")
    try:
        SRC = tmp_path
        MODULES = {module_name(p): p for p in sorted(pkg.rglob("*.py"))}
        GRAPH = {name: imports_of(name) for name in MODULES}
        assert sorted(cycles()) == [["tribopipe.config", "tribopipe.reduction.reduce"],
                                    ["tribopipe.hub", "tribopipe.report"]]
        with pytest.raises(AssertionError, match=r"config.py:3: .*\(type-only\)"):
            test_there_is_no_import_cycle()
        with pytest.raises(AssertionError, match=r"report.py:2: .*report -> tribopipe\.hub "
                                                 r"\(by name\)"):
            test_there_is_no_import_cycle()
        with pytest.raises(AssertionError, match=r"report -> tribopipe\.hub \(by name\)"
                                                 r"(.|\n)*files\.py:3: an import by a name"):
            test_no_function_is_named_as_text()
        reduce_layer = layer_of("tribopipe.reduction.reduce")
        report_layer = layer_of("tribopipe.report")
        upward = f"layer {reduce_layer} imports layer {report_layer}"
        with pytest.raises(AssertionError, match=upward):
            test_no_module_imports_from_a_higher_layer()
        with pytest.raises(AssertionError, match=r"reduce\.py:1"):
            test_only_the_cli_imports_click()
        with pytest.raises(AssertionError, match=r"numpy(.|\n)*cli -> tribopipe\.report"):
            test_cli_modules_import_only_click_and_the_standard_library_at_module_level()
        with pytest.raises(AssertionError, match=r"reduce -> tribopipe\.report \(in a"):
            test_library_modules_import_their_own_package_at_the_top()
        with pytest.raises(AssertionError, match=r"layout\.py:1: tribopipe\.errors\._hidden"):
            test_no_private_name_is_imported_across_modules()
        with pytest.raises(AssertionError, match=r"reduce\.py:2: Y imported from tribopipe\.con"):
            test_every_name_is_imported_from_the_module_that_defines_it()
    finally:
        MODULES, GRAPH, SRC = saved
