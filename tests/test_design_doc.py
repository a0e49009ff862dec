"""docs/DESIGN.md cannot drift from the code: its layer table is the architecture test's
``LAYERS``, its module table names every module under ``src/tribopipe`` and no other,
and what it (and every other document) names in the code exists.

The checks read the Markdown as text: a table row is ``| first | second | ...``; names
in a cell are the spans in backticks.
"""

from __future__ import annotations

import ast
import builtins
import re
from pathlib import Path

from test_architecture import LAYERS, MODULES, SRC

REPO = Path(__file__).resolve().parents[1]
DESIGN = REPO / "docs" / "DESIGN.md"
#: the documents a user or a contributor reads (CLI.md is generated from --help)
DOCS = [DESIGN, *sorted(p for p in (REPO / "docs").glob("*.md") if p.name != "CLI.md"),
        REPO / "bench" / "README.md", REPO / "README.md"]
PACKAGE = "tribopipe"
TICKS = re.compile(r"`([^`\n]+)`")


def section(text: str, heading: str) -> str:
    """The text under ``## heading`` up to the next heading of that level."""
    start = text.index(f"\n## {heading}\n")
    end = text.find("\n## ", start + 1)
    return text[start: end if end != -1 else len(text)]


def table_rows(text: str) -> list[list[str]]:
    """The cells of every table row in ``text`` (header and rule rows left out)."""
    rule = re.compile(r"[-:| ]+")
    lines = [line.strip() for line in text.splitlines()]
    rows = []
    for k, line in enumerate(lines):
        if not line.startswith("|") or rule.fullmatch(line):
            continue
        if k + 1 < len(lines) and lines[k + 1].startswith("|") and rule.fullmatch(lines[k + 1]):
            continue  # a header
        rows.append([c.strip() for c in line.strip("|").split(" | ")])
    return rows


def documented_layers(text: str) -> list[tuple[str, ...]]:
    """DESIGN.md's layer table, bottom to top, as full module names."""
    layers = []
    for number, (index, modules, *_rest) in enumerate(table_rows(section(text, "Import layers"))):
        assert index == str(number), f"layer row {index!r} is not number {number}"
        names = [n.rstrip("/") for n in TICKS.findall(modules)]
        layers.append(tuple(n if n == PACKAGE else f"{PACKAGE}.{n}" for n in names))
    return layers


def documented_modules(text: str) -> list[str]:
    """The paths (below ``src/tribopipe``) in the first column of the module table."""
    return [TICKS.fullmatch(row[0]).group(1)  # type: ignore[union-attr]
            for row in table_rows(section(text, "Modules"))]


def top_level_names(module: str) -> set[str]:
    """What ``module`` defines or imports at its top level (also inside ``if``/``try``)."""
    tree = ast.parse(MODULES[module].read_text(encoding="utf-8"))
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            names.add(node.name)
        elif isinstance(node, ast.Assign | ast.AnnAssign):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            names |= {n.id for t in targets for n in ast.walk(t) if isinstance(n, ast.Name)}
        elif isinstance(node, ast.ImportFrom | ast.Import):
            names |= {(a.asname or a.name).split(".")[0] for a in node.names}
    return names


NAMES = {module: top_level_names(module) for module in MODULES}
EVERY_NAME = set().union(*NAMES.values())


def unresolved(reference: str, *, short: bool) -> str | None:
    """Why a dotted ``reference`` to the code does not resolve (None when it does): its
    longest module prefix must be a module and the next part a name defined there.
    ``short``: module names may leave out the ``tribopipe.`` prefix."""
    parts = reference.split(".")
    if parts[0] != PACKAGE:
        if not short:
            return None
        parts = [PACKAGE, *parts]
    for cut in range(len(parts), 0, -1):
        module = ".".join(parts[:cut])
        if module in MODULES:
            rest = parts[cut:]
            if rest and rest[0] not in NAMES[module]:
                return f"{module} defines no {rest[0]}"
            return None
    return None if not short else f"no module {'.'.join(parts[:2])}"


def test_the_layer_table_is_the_architecture_tests_layers() -> None:
    assert documented_layers(DESIGN.read_text(encoding="utf-8")) == [
        tuple(layer) for layer in LAYERS]


def test_the_module_table_names_every_module_and_no_other() -> None:
    listed = documented_modules(DESIGN.read_text(encoding="utf-8"))
    actual = sorted(p.relative_to(SRC / PACKAGE).as_posix() for p in MODULES.values())
    assert len(listed) == len(set(listed)), "a module is listed twice"
    assert sorted(set(listed) - set(actual)) == [], "listed but not in src/tribopipe"
    assert sorted(set(actual) - set(listed)) == [], "in src/tribopipe but not listed"


def test_what_the_design_names_in_the_code_exists() -> None:
    """A module path (``pipeline.reduce_export``, ``frictionmap.schema.COLUMNS``) resolves,
    and a class name (``RunVerdict``) is defined somewhere in the package."""
    text = DESIGN.read_text(encoding="utf-8")
    tops = {m.split(".")[1] for m in MODULES if m != PACKAGE}
    problems = []
    for span in TICKS.findall(text):
        if re.fullmatch(r"[\w/.-]+\.py", span):  # a file: below src/tribopipe or the repository
            if not ((SRC / PACKAGE / span).exists() or (REPO / span).exists()):
                problems.append(f"`{span}`: no such file")
            continue
        head = re.match(r"[A-Za-z_][\w.]*", span)
        if head is None:
            continue
        reference = head.group(0).rstrip(".")
        first = reference.split(".")[0]
        if first in tops or first == PACKAGE:
            why = unresolved(reference, short=True)
            if why is not None:
                problems.append(f"`{span}`: {why}")
        elif re.fullmatch(r"[A-Z][a-z]+[A-Z]\w*|[A-Z][a-z]+", first) and first not in EVERY_NAME:
            if first in dir(builtins) or first in {"NaN", "Infinity"}:
                continue
            problems.append(f"`{span}`: no class or name {first} in src/tribopipe")
    assert problems == []


def test_no_document_names_a_module_or_file_that_is_gone() -> None:
    """``tribopipe.x.y`` references and ``src/tribopipe/...`` paths in the documents lead
    to code that exists (a renamed module leaves no stale pointer behind)."""
    problems = []
    for doc in DOCS:
        text = doc.read_text(encoding="utf-8")
        for reference in re.findall(r"\btribopipe(?:\.[A-Za-z_]\w*)+", text):
            why = unresolved(reference, short=False)
            if why is not None:
                problems.append(f"{doc.relative_to(REPO)}: {reference}: {why}")
        for path in re.findall(r"\bsrc/tribopipe/[\w/.-]*\w", text):
            if not (REPO / path).exists():
                problems.append(f"{doc.relative_to(REPO)}: {path} does not exist")
    assert problems == []


def test_the_parsers_read_what_they_are_for() -> None:
    """The table readers above on a small page (so a pass means something)."""
    page = ("# t\n\n## Import layers\n\n| layer | modules | why |\n|---|---|---|\n"
            "| 0 | `tribopipe`, `errors` | base |\n| 1 | `readers/` | in |\n\n"
            "## Modules\n\n| module | concept |\n|---|---|\n| `errors.py` | e |\n"
            "| `readers/textio.py` | t |\n\n## Next\n| `x.py` | not a module row |\n")
    assert documented_layers(page) == [("tribopipe", "tribopipe.errors"),
                                       ("tribopipe.readers",)]
    assert documented_modules(page) == ["errors.py", "readers/textio.py"]
    assert unresolved("tribopipe.pipeline.reduce_export", short=False) is None
    assert unresolved("tribopipe.pipeline.no_such_thing", short=False) is not None
    assert unresolved("frictionmap.schema.COLUMNS", short=True) is None
    assert unresolved("intervals.SAMPLE_LIMITS", short=True) is not None


def test_the_method_pages_flags_are_the_codes_flags() -> None:
    """docs/method.md's table of flags names every flag a run can carry, and no other:
    the reduction's (``reduction.reduce.FLAGS``) and those its labels add
    (``labels.FLAG_*``)."""
    from tribopipe import labels
    from tribopipe.reduction.reduce import FLAGS

    text = (REPO / "docs" / "method.md").read_text(encoding="utf-8")
    listed = [TICKS.fullmatch(row[0]).group(1)  # type: ignore[union-attr]
              for row in table_rows(section(text, "Flags"))]
    from_labels = [v for k, v in vars(labels).items() if k.startswith("FLAG_")]
    assert sorted(listed) == sorted({*FLAGS, *from_labels})
    reduction = [row for row in table_rows(section(text, "Flags")) if row[1] == "the reduction"]
    assert sorted(TICKS.fullmatch(r[0]).group(1) for r in reduction) == sorted(FLAGS)  # type: ignore[union-attr]


def test_no_docstring_points_to_a_name_that_is_gone() -> None:
    """Every Sphinx-style reference to the package in ``src/`` (``:func:`tribopipe.x.f```,
    ``:class:`~.cells.RowCells```) names a module, and a name that module defines."""
    problems = []
    for module, path in MODULES.items():
        text = path.read_text(encoding="utf-8")
        for role, target in re.findall(r":(func|class|mod|data|meth|attr):`~?([^`]+)`", text):
            if target.startswith("."):
                package = module if path.name == "__init__.py" else module.rsplit(".", 1)[0]
                target = f"{package}.{target.lstrip('.')}"
            elif not target.startswith(PACKAGE + "."):
                continue
            why = (None if target in MODULES else f"no module {target}") if role == "mod" \
                else unresolved(target, short=False)
            if why is not None:
                problems.append(f"{path.relative_to(SRC)}: :{role}:`{target}`: {why}")
    assert problems == []


def test_the_schema_version_the_docs_name_is_the_codes() -> None:
    """docs/DESIGN.md and docs/map.md name the schema version the code writes and the
    version each later column came in (read from ``schema.SCHEMA_VERSION`` and
    ``ADDED_IN_VERSION``, never a number copied here)."""
    import re

    from tribopipe.frictionmap.schema import ADDED_IN_VERSION, REVIEW_COLUMNS, SCHEMA_VERSION

    design = (REPO / "docs" / "DESIGN.md").read_text(encoding="utf-8")
    guide = (REPO / "docs" / "map.md").read_text(encoding="utf-8")
    assert re.findall(r"`SCHEMA_VERSION`, now (\d+)", design) == [str(SCHEMA_VERSION)]
    assert re.findall(r"has a version\s+\(now (\d+)", guide) == [str(SCHEMA_VERSION)]
    named = {c: v for c, v in ADDED_IN_VERSION.items() if c not in REVIEW_COLUMNS}
    added = design[design.index("with the version that added it"):]
    added = added[:added.index("): a map of an")]
    for column, version in named.items():
        said = re.search(rf"`{column}`[^;]*?: (\d+)", added)
        assert said is not None and int(said.group(1)) == version, column
        assert re.search(rf"version {version} (?:(?!version)[^;)])*`{column}`", guide), column
    assert f"the review columns: {ADDED_IN_VERSION[REVIEW_COLUMNS[0]]}" in added
