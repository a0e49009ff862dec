"""``tribopipe map publish``: the friction map as a Frictionless Data Package.

A package is a folder::

    datapackage.json        the descriptor: every file with its size, SHA-256, licence and
                            sources; the tables with a Table Schema whose fields have units
    README.md               who, what, licence, how to cite, the columns
    CITATION.cff            Citation File Format 1.2.0 (the founding paper under references)
    explorer.html           the explorer page of the map (tribopipe explore)
    data/runs.csv           one row per run (the map's columns; every row names its lab)
    data/runs.parquet       the same rows as a friction map (query, explore, merge read it)
    data/groups.csv         the repeat statistics per condition group, numbered (``group``)
    data/groups.parquet     the same
    data/group_runs.csv     which runs each group holds: one row per (group, run), so that
                            no cell grows with the number of runs
    data/frictionmap.csv    the 7-column table of the founding paper's MATLAB app

:func:`publish_map` reads the map once, fills the ``lab`` of the rows that have none with the
publisher's lab, refuses a map whose rows fail
:func:`tribopipe.frictionmap.checks.validate_runs`, writes every file into a temporary folder
beside the target, checks the result with :func:`tribopipe.frictionmap.check_package` (so a
package tribopipe writes always validates) and only then renames it into place: a package
is never half-written. The descriptor is written here as plain JSON (see ``docs/DESIGN.md``
for why not through the ``frictionless`` library).
"""

from __future__ import annotations

import csv
import dataclasses
import io
import json
import math
import os
import re
import shutil
import tempfile
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO

from .. import __version__
from ..config import Settings
from ..errors import ExportError
from ..evidence import (
    INDEX_FIELDS,
    INDEX_PATH,
    INDEX_RESOURCE,
    SETTINGS_PATH,
    SETTINGS_RESOURCE,
    Evidence,
    gather_evidence,
    write_evidence,
)
from ..fit import fit_power_law
from ..frictionmap import RUN_COLUMNS, check_package
from ..frictionmap.checks import RowProblem, validate_runs
from ..frictionmap.datapackage import (
    DESCRIPTOR,
    FALSE,
    FRICTIONMAP_FIELDS,
    GROUP_ID,
    GROUP_RUNS_FIELDS,
    JOINED_COLUMNS,
    PROFILE,
    TRIBOPIPE_KEY,
    TRUE,
    file_digest,
    groups_fields,
    runs_fields,
    table_schema,
)
from ..frictionmap.package import (
    FRICTIONMAP_APP,
    GROUP_RUNS,
    GROUPS,
    GROUPS_PARQUET,
    RUNS,
    RUNS_PARQUET,
)
from ..frictionmap.profile import PROFILE_NAME, PROFILE_VERSION, profile_schema, schema_file
from ..frictionmap.published import FOUNDING_PAPER, PUBLISHED_LAB
from ..frictionmap.schema import (
    KIND,
    SCHEMA_NAME,
    SCHEMA_VERSION,
    SOURCE_PUBLISHED,
    columns_sha256,
)
from ..frictionmap.snapshot import MapSnapshot, MapSource
from ..frictionmap.store import MapCopyWriter, frame_of_table, load_map_table, stored_groups
from ..frictionmap.synthetic_rows import SYNTHETIC_MEANS, synthetic_count
from ..memory import return_free_memory
from ..query import pairs
from ..stats import (
    GROUP_INPUT_COLUMNS,
    LABS,
    OWN_LAB,
    finish_groups,
    group_statistics,
    run_ids_of,
    shown_columns,
)
from .citation import (
    CODE_LICENCE,
    Publisher,
    citation_cff,
    citation_text,
    founding_paper_text,
    package_readme,
)
from .explorer import EXPLORER_COLUMNS, explorer_parts
from .tables import frictionmap_csv, frictionmap_table

if TYPE_CHECKING:
    import pandas as pd

#: the explorer page's name in a package
EXPLORER = "explorer.html"
#: the most files of the explorer a package lists (each a resource; a package lists at
#: most 64): beyond, its pages carry more groups each, and then the runs travel in
#: the pages (:func:`~tribopipe.export.explorer.explorer_parts` ``max_files``)
EXPLORER_FILES_LIMIT = 40


@dataclass(frozen=True)
class PublishedPackage:
    """What :func:`publish_map` wrote: the package folder, its number of runs and the
    files (paths relative to the folder)."""

    path: Path
    n_runs: int
    files: tuple[str, ...]
    #: what the evidence lacks (runs without a trace or raw export, unknown settings)
    notes: tuple[str, ...] = ()
    #: runs with a trace, and with a raw export, in ``evidence/``
    n_traces: int = 0
    n_raw: int = 0


# --------------------------------------------------------------------------- CSV


def package_cell(value: Any, kind: str) -> str:
    """One CSV cell of a value of map column kind ``kind``: missing as empty, floats by
    their shortest round-trip text, booleans ``true``/``false``, text as it is,
    CSV-quoted (the package's data are read back unchanged: not an escape)."""
    if value is None or (kind != "str" and _isna(value)):
        return ""
    if kind == "bool":
        return TRUE if bool(value) else FALSE
    if kind == "int":
        return str(int(value))
    if kind == "float":
        number = float(value)
        if math.isinf(number):
            raise ExportError(f"cannot publish an infinite number ({number})")
        return repr(number)
    return "" if _isna(value) else str(value)


def _isna(value: Any) -> bool:
    import pandas as pd

    try:
        return bool(pd.isna(value))
    except (TypeError, ValueError):
        return False


def table_csv(table: pd.DataFrame, kinds: Sequence[str]) -> str:
    """CSV text (``\\n`` line ends, UTF-8) of ``table`` with one map kind per column."""
    buf = io.StringIO()
    write_table_csv(buf, table, kinds)
    return buf.getvalue()


#: rows of a table written to CSV at a time (their cells are text only while written)
CSV_BATCH_ROWS = 8192


def write_table_csv(out: TextIO, table: pd.DataFrame, kinds: Sequence[str], *,
                    header: bool = True) -> None:
    """Write ``table`` as CSV to the text stream ``out`` (``\\n`` line ends), each column
    of its map kind written as :func:`package_cell` writes a value, column by column and
    :data:`CSV_BATCH_ROWS` rows at a time, so that the table is never held as text; with
    ``header`` (the default) its column names first (without: the next rows of a table
    written in batches)."""
    writer = csv.writer(out, lineterminator="\n")
    if header:
        writer.writerow([str(c) for c in table.columns])
    for start in range(0, len(table), CSV_BATCH_ROWS):
        part = table.iloc[start:start + CSV_BATCH_ROWS]
        columns = [_column_cells(part.iloc[:, j], kind) for j, kind in enumerate(kinds)]
        writer.writerows(zip(*columns, strict=True))


def _column_cells(column: pd.Series, kind: str) -> list[str]:
    """The CSV cells of one column of map kind ``kind`` (:func:`package_cell`, column-wise)."""
    import numpy as np

    missing = np.asarray(column.isna(), dtype=bool)
    if kind == "float":
        values = np.asarray(column, dtype=float)
        if np.isinf(values).any():
            number = float(values[np.isinf(values)][0])
            raise ExportError(f"cannot publish an infinite number ({number})")
        return ["" if m else repr(v) for v, m in zip(values.tolist(), missing, strict=True)]
    if kind == "int":
        return ["" if m else str(int(v)) for v, m in zip(column.tolist(), missing, strict=True)]
    if kind == "bool":
        return ["" if m else TRUE if v else FALSE
                for v, m in zip(column.tolist(), missing, strict=True)]
    return ["" if m else str(v) for v, m in zip(column.tolist(), missing, strict=True)]


def column_kind(series: pd.Series) -> str:
    """The map kind (str, float, int, bool) of a table column, from its dtype."""
    import pandas as pd

    dtype = series.dtype
    if pd.api.types.is_bool_dtype(dtype):
        return "bool"
    if pd.api.types.is_integer_dtype(dtype):
        return "int"
    if pd.api.types.is_float_dtype(dtype):
        return "float"
    return "str"


# --------------------------------------------------------------------------- the package


def package_runs_table(runs: pd.DataFrame, lab: str) -> pd.DataFrame:
    """The map's runs with every missing ``lab`` filled: the founding paper's authors for
    its published rows, ``lab`` for the others; empty texts other than ``flags`` missing
    (a new frame; :func:`package_column` of each column)."""
    return _package_frame(runs.loc[:, list(RUN_COLUMNS)], lab)


def _package_frame(runs: pd.DataFrame, lab: str) -> pd.DataFrame:
    """:func:`package_column` of each column of ``runs`` (map rows of any of the map's
    columns, ``source`` among them): a new frame, the unchanged columns shared."""
    # a shallow copy: the columns not changed below stay shared (copy-on-write), so a
    # large map is not held twice
    out = runs.copy(deep=False)
    source = runs["source"]
    for name in runs.columns:
        column = out[name]
        filled = package_column(str(name), column, source, lab)
        if filled is not column:
            out[name] = filled
    return out


def _blank_labs(column: pd.Series) -> Any:
    """Where a ``lab`` column is missing or blank (a boolean array): the runs a package
    fills with a lab's name (:func:`package_column`), and that
    :func:`filled_group_rows` renames in the stored groups; one rule for both."""
    return (column.isna() | (column.astype(str).str.strip() == "")).to_numpy(dtype=bool)


def package_column(name: str, column: pd.Series, source: pd.Series, lab: str) -> pd.Series:
    """The map column ``name`` as a package holds it: a ``lab`` missing or blank filled
    with the founding paper's authors where ``source`` (the rows' ``source`` column) says
    published, with ``lab`` elsewhere; ``flags`` ``""`` where missing (a CSV cell cannot
    tell an empty text from a missing one: flags are ``""`` when there are none, never
    missing); every other empty text missing. A new Series, or ``column`` itself when
    nothing changes. One column at a time, so that the package's rows are made a batch
    or a column at a time (:func:`write_runs_files`)."""
    import numpy as np

    if name == "lab":
        missing = _blank_labs(column)
        if missing.any():
            published = np.asarray(source == SOURCE_PUBLISHED, dtype=bool)
            column = column.copy()
            column.loc[missing & published] = PUBLISHED_LAB
            column.loc[missing & ~published] = lab
    if name == "flags":
        return column.fillna("") if column.isna().any() else column
    if KIND[name] == "str":
        empty = (column == "").fillna(False).to_numpy(dtype=bool)
        if empty.any():
            column = column.copy()
            column.loc[empty] = None
    return column


def package_groups(groups: pd.DataFrame) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The group table of a package and its linking table, from
    :func:`tribopipe.stats.group_statistics` ``groups``: the groups numbered 1, 2, … in a
    first column ``group``, without the columns that join a group's runs into one cell
    (:data:`~tribopipe.frictionmap.datapackage.JOINED_COLUMNS`); and one row per (group,
    measurement id), in the groups' order and each group's own (new frames)."""
    import numpy as np
    import pandas as pd

    table = groups.drop(columns=[c for c in JOINED_COLUMNS if c in groups.columns])
    table.insert(0, GROUP_ID, np.arange(1, len(table) + 1, dtype="int64"))
    ids = [run_ids_of(cell) for cell in groups["run_ids"]]
    counts = np.fromiter((len(i) for i in ids), dtype="int64", count=len(ids))
    members = pd.DataFrame({
        GROUP_ID: np.repeat(np.arange(1, len(ids) + 1, dtype="int64"), counts),
        "measurement_id": pd.array([m for group in ids for m in group], dtype="str"),
    })
    return table, members


def _slug(text: str) -> str:
    return re.sub(r"[^a-z0-9]+", "-", text.casefold()).strip("-") or "lab"


def _sources(publisher: Publisher, year: int) -> list[dict[str, str]]:
    """The Data Package ``sources``: the lab's citation, the founding paper, tribopipe."""
    return [
        {"title": citation_text(publisher, year)},
        {"title": founding_paper_text(), "path": FOUNDING_PAPER["data"]},
        {"title": f"tribopipe {__version__} (reduction of the raw exports)"},
    ]


def _resource(name: str, path: str, size: int, digest: str, *, title: str, fmt: str,
              mediatype: str, licences: list[dict[str, str]], sources: list[dict[str, str]],
              schema: dict[str, Any] | None = None) -> dict[str, Any]:
    res: dict[str, Any] = {
        "name": name, "path": path, "title": title,
        "profile": "tabular-data-resource" if schema is not None else "data-resource",
        "format": fmt, "mediatype": mediatype, "bytes": size, "hash": digest,
        "licenses": licences, "sources": sources,
    }
    if fmt == "csv":
        res["encoding"] = "utf-8"
    if fmt == "parquet" or mediatype == "application/schema+json":
        # A Parquet file carries its own schema (the runs' with units in the metadata) and
        # the CSV resource beside it describes the same table; as a "file" the frictionless
        # tools check its size and hash rather than reading it through their Parquet plugin
        # (which takes NaN for a value and cannot count its bytes). A JSON Schema is a
        # "file" too: the frictionless tools would read it as a Table Schema.
        res["type"] = "file"
    if schema is not None:
        res["schema"] = schema
    return res


#: the run columns the package's tables, its explorer, its account and the evidence read
#: (every column travels into ``runs.csv`` and ``runs.parquet``, a batch at a time)
TABLE_COLUMNS: tuple[str, ...] = tuple(c for c in RUN_COLUMNS if c in {
    *GROUP_INPUT_COLUMNS, "source", "source_file", "file_hash", "config_hash", "method",
    "test", "result"})
#: rows of the map made into a DataFrame at a time while they are checked and written
PUBLISH_BATCH_ROWS = 16_384


def _batches(table: Any, lab: str) -> Iterator[tuple[int, pd.DataFrame]]:
    """The rows of the Arrow ``table`` of map rows
    (:func:`~tribopipe.frictionmap.store.load_map_table`) as the package holds them
    (:func:`package_runs_table`), :data:`PUBLISH_BATCH_ROWS` at a time, each with the
    position of its first row."""
    for start in range(0, table.num_rows, PUBLISH_BATCH_ROWS):
        rows = frame_of_table(table.slice(start, PUBLISH_BATCH_ROWS))
        yield start, package_runs_table(rows, lab)


def run_problems(table: Any, lab: str) -> list[RowProblem]:
    """Every problem of the package's rows of the Arrow ``table`` of map rows
    (:func:`~tribopipe.frictionmap.checks.validate_runs` with ``require_lab``), checked a
    batch at a time, rows counted from the table's first (each id is once in the table:
    its reader refuses a map that holds one twice)."""
    problems: list[RowProblem] = []
    for start, rows in _batches(table, lab):
        problems += [dataclasses.replace(p, row=p.row + start)
                     for p in validate_runs(rows, require_lab=True)]
    return problems


def write_runs_files(folder: Path, table: Any, lab: str) -> None:
    """Write ``data/runs.csv`` and ``data/runs.parquet`` of the package in ``folder`` from
    the Arrow ``table`` of map rows, a batch at a time (:data:`PUBLISH_BATCH_ROWS`): the
    rows are never one DataFrame, nor the CSV one text. The Parquet copy's checksum of
    its rows is computed a column at a time
    (:func:`~tribopipe.frictionmap.schema.columns_sha256`)."""
    (folder / "data").mkdir(exist_ok=True)
    n = table.num_rows
    source = frame_of_table(table, ["source"])["source"]
    digest = columns_sha256(n, lambda name: package_column(
        name, frame_of_table(table, [name])[name], source, lab))
    run_kinds = [KIND[c] for c in RUN_COLUMNS]
    sources = set(package_column("source", source, source, lab).dropna().astype(str))
    with open(folder / "data/runs.csv", "w", encoding="utf-8", newline="") as out, \
            MapCopyWriter(folder / "data/runs.parquet", n, sources, digest) as copy:
        for start, rows in _batches(table, lab):
            write_table_csv(out, rows, run_kinds, header=start == 0)
            copy.write(rows)
        copy.finish().chmod(0o644)  # a map is 0600


def package_group_table(source: MapSource, info: Mapping[str, Any], labs: pd.DataFrame,
                        runs: pd.DataFrame, lab: str) -> pd.DataFrame:
    """The group table of the package of the map ``source`` (whose metadata is ``info``):
    :func:`~tribopipe.stats.group_statistics` of its rows as the package holds them
    (``runs``, labs filled: :func:`package_runs_table`). A map folder's stored groups are
    finished instead (:func:`~tribopipe.stats.finish_groups`) where the filling of the
    labs leaves them the same (:func:`filled_group_rows`, from the map's own ``lab`` and
    ``source`` columns, ``labs``); else every row is grouped."""
    rows = stored_groups(source, info) if info.get("format") == "parts" else None
    filled = None if rows is None else filled_group_rows(rows, labs, lab)
    if filled is None:
        return group_statistics(runs)
    speed, method = shown_columns(filled)
    return finish_groups(filled, show_speed=speed, show_method=method)


def filled_group_rows(rows: pd.DataFrame, labs: pd.DataFrame, lab: str) -> pd.DataFrame | None:
    """The stored group rows ``rows`` (:func:`~tribopipe.stats.group_rows` of a map's
    runs) as the runs give them once their missing labs are filled
    (:func:`package_column`), or ``None`` where that is not a renaming of the stored
    rows: ``labs`` are the map's own ``lab`` and ``source`` columns. The stored rows
    name a run without a lab :data:`~tribopipe.stats.OWN_LAB`; they stay exact when every
    run without a lab is filled with one same name, no run names itself ``(own lab)``
    and no group holds runs with and without a lab: then a group of runs without a lab
    is a group of that one lab, and nothing but its ``labs`` cell changes."""
    given = labs["lab"]
    blank = _blank_labs(given)
    if not blank.any():
        return rows
    if (given == OWN_LAB).any():
        return None
    published = (labs["source"] == SOURCE_PUBLISHED).to_numpy(dtype=bool)[blank]
    fills = {PUBLISHED_LAB if p else lab for p in published.tolist()}
    if len(fills) != 1 or rows.empty:
        return None if len(fills) != 1 else rows
    cells = rows[LABS].astype(str)
    own = (cells == OWN_LAB).to_numpy(dtype=bool)
    with_own = cells.str.split(";").map(lambda names: OWN_LAB in names).to_numpy(dtype=bool)
    if (with_own & ~own).any():
        return None
    out = rows.copy()
    out.loc[own, LABS] = fills.pop()
    return out


def explorer_runs(runs: pd.DataFrame) -> pd.DataFrame:
    """The runs the explorer page shows of the package's rows ``runs``: the included
    ones, the :data:`EXPLORER_COLUMNS`, each text column a column of Python texts that
    holds each distinct text once (the page's writer makes an object of every cell: a
    text repeated in 10⁵ rows is then one object, not 10⁵). A new frame."""
    import numpy as np
    import pandas as pd

    included = runs.loc[~runs["excluded"].astype(bool), list(EXPLORER_COLUMNS)]
    out = {}
    for name in EXPLORER_COLUMNS:
        column = included[name]
        if KIND[name] == "str":
            codes, uniques = pd.factorize(column)
            texts = np.array([*uniques.tolist(), None], dtype=object)
            out[name] = pd.Series(texts[codes], dtype=object)
        else:
            out[name] = column.reset_index(drop=True)
    return pd.DataFrame(out, index=pd.RangeIndex(len(included)))


def build_package(rows: list[pd.DataFrame], groups: pd.DataFrame, publisher: Publisher,
                  folder: Path, *, date: str, evidence: Evidence | None = None) -> list[str]:
    """Write the package into ``folder``, where :func:`write_runs_files` has written the
    runs already: ``rows`` is a list that holds the package's rows (labs filled;
    :data:`TABLE_COLUMNS` suffice), which it empties, so that it holds them alone and
    lets them go once its tables are written (the explorer page is written from
    :func:`explorer_runs` of them); ``groups`` their group table
    (:func:`package_group_table`), ``evidence`` (:mod:`tribopipe.evidence`) when given.
    Returns the files written (relative paths), the descriptor last."""
    runs = rows.pop()
    year = int(date[:4])
    group_table, group_runs = package_groups(groups)
    fits = fit_power_law(runs)
    data_licence = [publisher.licence_entry()]
    sources = _sources(publisher, year)
    group_kinds = [column_kind(group_table[c]) for c in group_table.columns]
    files: list[str] = []
    resources = []

    def add(name: str, path: str, data: bytes | None, **meta: Any) -> None:
        """Describe the file ``path`` (written here from ``data``, or already written
        when ``data`` is ``None``), its size and SHA-256 read back in blocks."""
        if data is not None:
            (folder / path).write_bytes(data)
        size, digest = file_digest(folder / path, 1 << 62)
        files.append(path)
        resources.append(_resource(name, path, size, digest, sources=sources,
                                   licences=meta.pop("licences", data_licence), **meta))

    def write_csv(path: str, table: pd.DataFrame, kinds: Sequence[str]) -> None:
        with open(folder / path, "w", encoding="utf-8", newline="") as out:
            write_table_csv(out, table, kinds)

    runs_schema = table_schema(runs_fields(), primary_key="measurement_id")
    add(RUNS, "data/runs.csv", None,
        title="Runs: one row per friction run", fmt="csv", mediatype="text/csv",
        schema=runs_schema)
    add(RUNS_PARQUET, "data/runs.parquet", None,
        title="Runs as a tribopipe friction map (Parquet, schema in its metadata)",
        fmt="parquet", mediatype="application/vnd.apache.parquet")
    groups_schema = table_schema(groups_fields(list(zip(group_table.columns, group_kinds,
                                                        strict=True))), primary_key=GROUP_ID)
    add(GROUPS, "data/groups.csv", table_csv(group_table, group_kinds).encode(),
        title="Repeat statistics per condition group", fmt="csv", mediatype="text/csv",
        schema=groups_schema)
    buf = io.BytesIO()
    group_table.to_parquet(buf, index=False)
    add(GROUPS_PARQUET, "data/groups.parquet", buf.getvalue(),
        title="Repeat statistics per condition group (Parquet)", fmt="parquet",
        mediatype="application/vnd.apache.parquet")
    write_csv("data/group_runs.csv", group_runs, ["int", "str"])
    add(GROUP_RUNS, "data/group_runs.csv", None,
        title="The runs of each condition group: one row per group and run", fmt="csv",
        mediatype="text/csv",
        schema=table_schema(GROUP_RUNS_FIELDS, primary_key="measurement_id",
                            foreign_keys={GROUP_ID: (GROUPS, GROUP_ID),
                                          "measurement_id": (RUNS, "measurement_id")}))
    add(FRICTIONMAP_APP, "data/frictionmap.csv",
        frictionmap_csv(frictionmap_table(runs)).encode(),
        title="The included runs in the 7-column table of the founding paper's MATLAB app",
        fmt="csv", mediatype="text/csv", schema=table_schema(FRICTIONMAP_FIELDS))
    if evidence is not None:
        index, settings_json = write_evidence(folder, evidence)
        add(INDEX_RESOURCE, INDEX_PATH, index,
            title="Evidence: each run's reduced trace and raw export, with their SHA-256, "
                  "settings and method (files under evidence/)",
            fmt="csv", mediatype="text/csv", schema=table_schema(list(INDEX_FIELDS)))
        add(SETTINGS_RESOURCE, SETTINGS_PATH, settings_json,
            title="The settings that reduced the runs, by config hash (method, instrument, "
                  "reduction parameters)", fmt="json", mediatype="application/json")
    (folder / "profile").mkdir()
    add("profile-schema", schema_file(),
        (json.dumps(profile_schema(), indent=2, ensure_ascii=False) + "\n").encode(),
        title=f"JSON Schema of this package's descriptor (package profile version "
              f"{PROFILE_VERSION})", fmt="json", mediatype="application/schema+json")
    page_licences = [*data_licence, {"name": CODE_LICENCE[0], "title": CODE_LICENCE[1],
                                     "path": CODE_LICENCE[2]}]
    n_runs = len(runs)
    n_excluded = int(runs["excluded"].astype(bool).sum())
    n_published = int((runs["source"] == SOURCE_PUBLISHED).sum())
    pair_list = pairs(runs)
    labs = sorted(set(runs["lab"].dropna().astype(str)))
    shown = explorer_runs(runs)
    del runs  # the page is written from the runs it shows
    return_free_memory()
    # each file is a resource of its own (a package lists at most 64), written as it is
    # made: one page held at a time
    page_files = explorer_parts(shown, EXPLORER, groups=groups, fits=fits,
                                     title=publisher.package_title, source=publisher.lab,
                                     max_files=EXPLORER_FILES_LIMIT)
    for path, text in page_files:
        (folder / path).parent.mkdir(parents=True, exist_ok=True)
        if path == EXPLORER:
            add("explorer", path, text.encode(), title="Explorer page (open in a browser)",
                fmt="html", mediatype="text/html", licences=page_licences)
            continue
        html = path.endswith(".html")
        add("explorer-" + re.sub(r"[^a-z0-9]+", "-", path.lower().removesuffix(
            ".html").removesuffix(".js")).strip("-"), path, text.encode(),
            title="A page of the explorer (one pin's pairs)" if html
            else "The runs of one pair of the explorer, loaded when the pair is shown",
            fmt="html" if html else "js",
            mediatype="text/html" if html else "text/javascript", licences=page_licences)
    del page_files, shown
    add("citation", "CITATION.cff",
        citation_cff(publisher, date=date, n_runs=n_runs, pairs=pair_list).encode(),
        title="How to cite (Citation File Format 1.2.0)", fmt="cff",
        mediatype="application/x-yaml")
    listing = [(r["path"], r["title"]) for r in resources]
    listing += [("README.md", "this account"), (DESCRIPTOR, "the Data Package descriptor")]
    readme = package_readme(
        publisher, date=date, n_runs=n_runs, n_excluded=n_excluded, n_published=n_published,
        pairs=pair_list, files=listing, fields=runs_fields())
    add("readme", "README.md", readme.encode(), title="About this package", fmt="md",
        mediatype="text/markdown")
    descriptor = {
        "profile": PROFILE,
        "name": f"{_slug(publisher.lab)}-friction-map",
        "title": publisher.package_title,
        "description": (f"Friction map: {n_runs} runs of {len(pair_list)} contact pairs, "
                        "μ_S and μ_K by contact pressure and temperature, with repeat "
                        "statistics and provenance. Written by tribopipe."),
        "created": f"{date}T00:00:00Z" if len(date) == 10 else date,
        "version": date,
        "licenses": data_licence,
        "contributors": [{
            "title": publisher.contact or publisher.lab, "role": "publisher",
            "organization": publisher.lab,
            **({"email": publisher.email} if publisher.email else {}),
        }],
        "sources": sources,
        "keywords": ["friction", "tribology", "coefficient of friction", "soft robotics"],
        "citation": citation_text(publisher, year),
        TRIBOPIPE_KEY: {
            "profile": PROFILE_NAME, "profile_version": PROFILE_VERSION,
            "schema": SCHEMA_NAME, "schema_version": SCHEMA_VERSION, "lab": publisher.lab,
            "tribopipe_version": __version__, "n_runs": n_runs, "labs": labs,
        },
        "resources": resources,
    }
    text = json.dumps(descriptor, ensure_ascii=False, indent=2) + "\n"
    (folder / DESCRIPTOR).write_text(text, encoding="utf-8")
    return [*files, DESCRIPTOR]


def publish_map(map_path: MapSource, out_dir: str | os.PathLike[str],
                publisher: Publisher, *, overwrite: bool = False,
                date: str | None = None, allow_synthetic: bool = False,
                evidence: bool = True, traces_dir: str | os.PathLike[str] | None = None,
                with_raw: bool = False, raw_dirs: Sequence[str | os.PathLike[str]] = (),
                settings: Sequence[Settings] = ()) -> PublishedPackage:
    """Write the map at ``map_path`` as a data package in the folder ``out_dir`` (see the
    module docstring). ``date`` (``YYYY-MM-DD``, default today, UTC) is the release date.

    Raises :class:`ExportError` for an empty map, rows that fail the checks (the first
    named, the rest counted), a bad publisher, or an ``out_dir`` that exists and is not
    empty — unless it is a package and ``overwrite`` is given; and for a map with rows
    flagged synthetic (:mod:`tribopipe.frictionmap.synthetic_rows`) unless
    ``allow_synthetic`` is given (they are never a lab's measurements).

    With ``evidence`` (the default) the package carries each reduced run's trace, found
    under ``traces_dir`` (default: ``traces/`` beside the map), and with ``with_raw`` its
    raw export, found by name and SHA-256 under ``raw_dirs``; the settings that reduced
    them are those of ``settings`` (and the defaults) whose config hash the rows name
    (:mod:`tribopipe.evidence`). What cannot be found is in the result's ``notes``.
    """
    publisher = publisher.checked()
    date = date or datetime.now(UTC).strftime("%Y-%m-%d")
    if not re.fullmatch(r"\d{4}-\d{2}-\d{2}", date):
        raise ExportError(f"release date {date!r}, expected YYYY-MM-DD")
    target = Path(out_dir)
    _check_target(target, overwrite)
    table, info = _map_table(map_path)
    n_runs = table.num_rows
    if n_runs == 0:
        raise ExportError("the friction map is empty or absent; nothing to publish",
                          path=map_path)
    own_labs = frame_of_table(table, ["lab", "source"])
    runs = _package_frame(frame_of_table(table, TABLE_COLUMNS), publisher.lab)
    n_synthetic = synthetic_count(runs)
    if n_synthetic and not allow_synthetic:
        raise ExportError(
            f"{n_synthetic} of {n_runs} runs are {SYNTHETIC_MEANS}; they cannot be "
            "published as a lab's measurements",
            path=map_path,
            hint="publish a map of your own runs, or pass --allow-synthetic for a "
                 "package of demo data",
        )
    problems = run_problems(table, publisher.lab)
    if problems:
        more = f" (and {len(problems) - 1} more)" if len(problems) > 1 else ""
        raise ExportError(f"{problems[0].line('map')}{more}; fix or exclude the run before "
                          "publishing", path=map_path)
    found = None
    if evidence:
        traces = Path(traces_dir) if traces_dir is not None else Path(map_path).parent / "traces"
        found = gather_evidence(runs, traces_dir=traces,
                                raw_dirs=[Path(p) for p in raw_dirs], settings=settings,
                                with_raw=with_raw)
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent))
    try:
        tmp.chmod(0o755)  # mkdtemp's 0700 would make the published folder private
        write_runs_files(tmp, table, publisher.lab)
        del table  # every column of every run is written: the tables need TABLE_COLUMNS
        groups = package_group_table(map_path, info, own_labs, runs, publisher.lab)
        del own_labs
        return_free_memory()
        rows = [runs]
        del runs  # build_package holds them alone, and lets them go when it can
        files = build_package(rows, groups, publisher, tmp, date=date, evidence=found)
        del groups
        return_free_memory()  # what writing held, before the check reads it all again
        check = check_package(tmp, keep_runs=False)  # the verdict, not the runs
        if not check.ok:  # a package we write must validate: a bug, said plainly
            raise ExportError("the package written does not validate: "
                              + "; ".join(check.lines()[:3]))
        _swap_into_place(tmp, target)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    if found is None:
        return PublishedPackage(target, n_runs, tuple(files))
    return PublishedPackage(target, n_runs, tuple(files), found.notes,
                            sum(f.trace is not None for f in found.files),
                            sum(f.raw is not None for f in found.files))


def _map_table(source: MapSource) -> tuple[Any, Mapping[str, Any]]:
    """The rows of the map ``source`` as one Arrow table and its metadata: a path is read
    as :func:`~tribopipe.frictionmap.store.load_map_table` reads it (never as one
    DataFrame); a snapshot a command opened already gives its rows (every column)."""
    import pyarrow as pa

    if isinstance(source, MapSnapshot):
        source.require(RUN_COLUMNS)
        return pa.Table.from_pandas(source.runs, preserve_index=False), source.info
    return load_map_table(source)


def _check_target(target: Path, overwrite: bool) -> None:
    if target.is_symlink() or (target.exists() and not target.is_dir()):
        raise ExportError("exists and is not a folder", path=target)
    if target.is_dir() and any(target.iterdir()):
        if not (target / DESCRIPTOR).is_file():
            raise ExportError("folder exists and is not empty (and not a package); refusing "
                              "to write into it", path=target, hint="pass a new folder")
        if not overwrite:
            raise ExportError("holds a package already", path=target,
                              hint="pass --overwrite to replace it")


def _swap_into_place(tmp: Path, target: Path) -> None:
    """Rename the finished package ``tmp`` to ``target``; an old package there is moved
    aside first and removed after."""
    old = None
    if target.exists():
        old = target.with_name(f".{target.name}.old.{os.getpid()}")
        os.replace(target, old)
    try:
        os.replace(tmp, target)
    except OSError as exc:
        if old is not None:
            os.replace(old, target)
        raise ExportError(f"cannot write the package ({exc.strerror or exc})",
                          path=target) from None
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)
