"""Where a run's labels come from: the manifest, the file name, the export's Test name.

Metadata resolution
-------------------
Each run needs ``pin``, ``disc``, ``normal_force_N`` (nominal, total) and ``temperature_C``
(nominal); ``repeat`` is optional. An export may hold several tests (a session), each
with its own runs, so metadata is resolved per test. The sources, consulted in this
order:

1. the manifest rows of the run (:func:`run_rows`): the row naming the file, the test
   and the friction interval (the optional ``interval`` column: the interval number as
   the export numbers it within its test, as ``reduce`` and ``runs.csv`` show it), the
   row naming the file and the interval with an empty ``test`` cell (that interval of
   every test: a file of one test with force or speed steps), then the row naming the
   file *and* the test (the manifest's optional ``test`` column holds the Test name as
   the export writes it) with an empty ``interval`` cell;
2. the manifest row naming the file with empty ``test`` and ``interval`` cells (it
   describes every test of the file);
3. the file-name pattern (:func:`~tribopipe.campaign.patterns.match_pattern` on the file
   stem; it describes every test of the file);
4. the test-name pattern on the Test name (``test_pattern``; the older
   ``use_export_names`` + ``export_pattern`` spell the same source).

Every source that gives a field must agree with the others (:func:`merge_metadata`:
names compared after the ``[names]`` aliases, ignoring case and surrounding blanks;
numbers compared exactly); the first source that gives a field defines its spelling. A
disagreement or a missing required field is an error *for that test only*: the other
tests of the file still land. In a file whose several tests hold friction runs, a test
described only by the file-level sources (2 and 3) fails too: those sources cannot tell
its tests apart, and the map would hold them under the same labels.
"""

from __future__ import annotations

import contextlib
import csv
import difflib
import functools
import io
import math
import sys
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import CampaignError, ConfigError, ReadError, ValidationError
from ..escape import csv_uncell
from ..files import read_regular
from ..labels import RunLabels
from ..materials import MaterialError, Resolved, Vocabulary
from ..readers.textio import decode, detect_delimiter
from ..reporting import NAMES as REPORTING_NAMES
from ..reporting import RunReport, from_export, parse_item
from ..validate import (
    FORCE_N,
    MAX_REPEAT,
    TEMPERATURE_C,
    check_count,
    check_name,
    check_number,
    text_problem,
)
from .patterns import LABEL_FIELDS, REQUIRED_FIELDS, parse_number

if TYPE_CHECKING:
    from .spec import Campaign

MANIFEST_COLUMNS: tuple[str, ...] = ("file", *LABEL_FIELDS)
#: the optional manifest column naming a test of a session export
TEST_COLUMN = "test"
#: the optional manifest column naming one friction interval (a force or speed step)
INTERVAL_COLUMN = "interval"


@dataclass(frozen=True)
class ManifestRow:
    """One manifest row: the label fields it gives (``None`` cells left out), its line,
    the file it names (as written, ``/`` separators), the test (``None``: the file's
    every test) and the friction interval (``None``: every interval of the test);
    ``problem`` is a bad value in it (an error for what it describes only)."""

    line: int
    fields: dict[str, Any]
    problem: str | None = None
    file: str = ""
    test: str | None = None
    interval: int | None = None

    def describes(self) -> str:
        """``line N (file)``, ``line N (file, test 'T')``, ``line N (file, interval I)``
        or ``line N (file, test 'T', interval I)``, for messages."""
        what = self.file if self.test is None else f"{self.file}, test {self.test!r}"
        if self.interval is not None:
            what += f", interval {self.interval}"
        return f"line {self.line} ({what})"


@dataclass(frozen=True)
class Manifest:
    """A manifest's rows, found by file (and test).

    ``get(file)`` is the row describing the whole file, ``get(file, test)`` the row of one
    of its tests, ``get(file, test, interval)`` the row of one friction interval;
    :meth:`for_file` finds them for a file of the campaign, by its path relative to the
    raw folder or by its name.
    """

    path: Path
    rows: tuple[ManifestRow, ...]

    def __len__(self) -> int:
        return len(self.rows)

    @property
    def name(self) -> str:
        """The manifest's file name."""
        return self.path.name

    def get(self, file: str, test: str | None = None,
            interval: int | None = None) -> ManifestRow | None:
        """The row for ``file`` (and ``test``, ``interval``; ``None``: the row with that
        cell empty)."""
        return self._index.get((file.replace("\\", "/"), _test_key(test), interval))

    def for_file(self, rel: str, name: str) -> tuple[ManifestRow | None,
                                                     tuple[ManifestRow, ...]]:
        """The rows naming a file of the campaign, by its relative path, else its name:
        the whole-file row (or ``None``) and the rows of its tests and intervals."""
        rows = self._by_file.get(rel) or self._by_file.get(name) or ()
        whole = next((r for r in rows if r.test is None and r.interval is None), None)
        return whole, tuple(r for r in rows if r is not whole)

    def near_miss(self, name: str) -> str | None:
        """The file a manifest row names that is closest to ``name`` (a row written
        without its ``.csv``, a typo), or ``None`` when no row is close."""
        names = list(self._by_file)
        stem = name.rsplit(".", 1)[0]
        if stem in names:
            return stem
        near = difflib.get_close_matches(name, names, n=1, cutoff=0.8)
        return near[0] if near else None

    @functools.cached_property
    def _index(self) -> dict[tuple[str, str | None, int | None], ManifestRow]:
        return {(r.file, r.test, r.interval): r for r in self.rows}

    @functools.cached_property
    def _by_file(self) -> dict[str, tuple[ManifestRow, ...]]:
        grouped: dict[str, list[ManifestRow]] = {}
        for r in self.rows:
            grouped.setdefault(r.file, []).append(r)
        return {k: tuple(v) for k, v in grouped.items()}


#: the largest manifest read [bytes]
MAX_MANIFEST_BYTES = 256 * 1024 * 1024


def run_rows(rows: Sequence[ManifestRow], test: str | None,
             interval: int | None) -> list[ManifestRow]:
    """The manifest rows (of one file's tests and intervals) that describe the run at
    ``test`` / ``interval``, most specific first: the row of that test and interval, the
    row of that interval with an empty test cell, the row of that test with an empty
    interval cell."""
    by_key = {(r.test, r.interval): r for r in rows}
    keys: list[tuple[str | None, int | None]] = (
        [(test, interval), (None, interval)] if interval is not None else [])
    keys.append((test, None))
    found = [by_key.get(key) for key in dict.fromkeys(keys) if key != (None, None)]
    return [r for r in found if r is not None]


def _test_key(test: str | None) -> str | None:
    """A Test name as matched: surrounding blanks ignored, an empty cell is ``None``."""
    if test is None:
        return None
    return test.strip() or None


def read_manifest(path: str | Path) -> Manifest:
    """Read a manifest CSV: one row per file, columns ``file, pin, disc, normal_force_N,
    temperature_C, repeat`` (empty cells mean unknown); a column named for a reporting
    item (:data:`tribopipe.reporting.ITEMS`: ``humidity_pct``, ``disc_Ra_um``,
    ``operator`` ...) gives that item, any other column is kept as the run's extra
    metadata (never dropped); with an
    optional ``test`` column, one row per test of a session export (the Test name as the
    export writes it; rows with the same file and different tests describe one export's
    tests, a row with an empty test cell the whole file); with an optional ``interval``
    column, one row per friction interval (a force or speed step within a test: the
    interval number, as ``reduce`` shows it; an empty cell: every interval).

    The encoding and the delimiter are detected as the readers detect them in an export
    (:mod:`tribopipe.readers.textio`): UTF-8 with or without BOM, UTF-16, cp1252; the
    header line decides between TAB, semicolon and comma (semicolon files may use a
    decimal comma). An unreadable file, a missing column, a bad interval number or a file
    (and test and interval) listed twice is a :class:`ConfigError` naming the manifest; a
    bad value (a name that is not one line of printable text, a number outside its
    physical range, a repeat that is not a whole number) is recorded as that row's
    ``problem``, one line naming the manifest, its line and column: an error for what the
    row describes only.
    """
    p = Path(path)
    try:
        raw = read_regular(p, max_bytes=MAX_MANIFEST_BYTES, what="a manifest (CSV)")
    except ReadError as exc:
        raise ConfigError(f"cannot read manifest: {exc.problem}", path=p) from None
    if not raw:
        raise ConfigError("manifest is empty", path=p, line=1)
    try:
        text = decode(raw, str(p)).text
    except ReadError as exc:
        raise ConfigError(f"cannot read manifest: {exc.problem}", path=p,
                          hint=exc.hint) from None
    delimiter = detect_delimiter(text.splitlines()[:1]) or ","
    with _no_cell_size_limit(len(text)):
        try:
            return _manifest_rows(p, text, delimiter)
        except csv.Error as exc:
            raise ConfigError(f"cannot split the manifest into cells: {exc}", path=p) from None


@contextlib.contextmanager
def _no_cell_size_limit(size: int) -> Iterator[None]:
    """Let the csv module read cells up to ``size`` characters (its default stops at
    131,072 with an error for the whole file); a cell that long is then refused as a
    value, for its row only."""
    before = csv.field_size_limit()
    csv.field_size_limit(min(max(before, size + 1), sys.maxsize))
    try:
        yield
    finally:
        csv.field_size_limit(before)


def _cell_value(name: str, raw: str) -> Any:
    """A manifest cell as the label field or reporting item ``name`` holds it;
    :class:`ValidationError` saying what was expected otherwise."""
    if name in REPORTING_NAMES:
        return parse_item(name, raw)
    if name in ("pin", "disc"):
        return check_name(raw, name)
    try:
        number = parse_number(raw)
    except ValueError:
        kind = "a whole number" if name == "repeat" else "a number"
        raise ValidationError(f"{name}: expected {kind}, got {raw[:40]!r}") from None
    if name == "repeat":
        if not number.is_integer():
            raise ValidationError(f"repeat: expected a whole number, got {raw[:40]!r}")
        return check_count(int(number), "repeat", high=MAX_REPEAT)
    bounds = FORCE_N if name == "normal_force_N" else TEMPERATURE_C
    return check_number(number, bounds, name)


def _manifest_rows(p: Path, text: str, delimiter: str) -> Manifest:
    """The rows of a manifest's text (see :func:`read_manifest`)."""
    reader = csv.reader(io.StringIO(text, newline=""), delimiter=delimiter)
    try:
        header = [h.strip() for h in next(reader)]
    except StopIteration:
        raise ConfigError("manifest is empty", path=p, line=1) from None
    missing = [c for c in MANIFEST_COLUMNS if c not in header]
    if missing:
        raise ConfigError(
            f"manifest lacks column(s) {', '.join(missing)}; expected "
            f"{', '.join(MANIFEST_COLUMNS)} (more allowed)",
            path=p, line=1,
        )
    index = {name: header.index(name) for name in MANIFEST_COLUMNS}
    # reporting items become their map columns; any other column is kept as extra metadata
    known = {*MANIFEST_COLUMNS, TEST_COLUMN, INTERVAL_COLUMN}
    for i, name in enumerate(header):
        if name in REPORTING_NAMES:
            index.setdefault(name, i)
    extra_index = {name: i for i, name in enumerate(header)
                   if name and name not in known and name not in REPORTING_NAMES}
    test_index = header.index(TEST_COLUMN) if TEST_COLUMN in header else None
    interval_index = header.index(INTERVAL_COLUMN) if INTERVAL_COLUMN in header else None
    rows: dict[tuple[str, str | None, int | None], ManifestRow] = {}
    for lineno, cells in enumerate(reader, start=2):
        if not any(c.strip() for c in cells):
            continue
        cells = cells + [""] * (len(header) - len(cells))
        # a template we wrote keeps a name starting with =, +, - or @ text for a spreadsheet
        file = csv_uncell(cells[index["file"]].strip())
        if not file:
            raise ConfigError("empty 'file' cell", path=p, line=lineno, column="file")
        if len(file) > 4096 or not file.isprintable():
            raise ConfigError("the 'file' cell is not a file name (one printable line)",
                              path=p, line=lineno, column="file")
        test = None if test_index is None else _test_key(cells[test_index])
        problem = None
        interval = None
        interval_text = "" if interval_index is None else cells[interval_index].strip()
        if interval_text:
            try:
                number = parse_number(interval_text)
                if not number.is_integer() or number < 1:
                    raise ValueError
                interval = int(number)
            except ValueError:
                raise ConfigError(
                    f"{interval_text!r} is not an interval number (a whole number from 1, "
                    "as reduce and runs.csv show it)",
                    path=p, line=lineno, column=INTERVAL_COLUMN) from None
        key = (file.replace("\\", "/"), test, interval)
        if key in rows:
            what = f"file {file!r}" + ("" if test is None else f" with test {test!r}") + (
                "" if interval is None else f" and interval {interval}")
            raise ConfigError(
                f"{what} listed twice (first on line {rows[key].line})",
                path=p, line=lineno,
                column=INTERVAL_COLUMN if interval is not None else
                "file" if test is None else TEST_COLUMN,
            )
        fields: dict[str, Any] = {}
        for name, i in extra_index.items():
            raw = csv_uncell(cells[i].strip())
            if raw:
                if text_problem(raw, max_chars=300) is None:
                    fields[EXTRA_PREFIX + name] = raw
                elif problem is None:
                    problem = str(ValidationError("expected one line of printable text",
                                                  path=p, line=lineno, column=name))
        for name in [*LABEL_FIELDS, *(n for n in REPORTING_NAMES if n in index)]:
            raw = csv_uncell(cells[index[name]].strip())
            if not raw:
                continue
            try:
                fields[name] = _cell_value(name, raw)
            except ValidationError as exc:
                if problem is None:
                    problem = str(ValidationError(exc.problem, path=p, line=lineno,
                                                  column=name))
        rows[key] = ManifestRow(line=lineno, fields=fields, problem=problem, file=key[0],
                                test=test, interval=interval)
    return Manifest(path=p, rows=tuple(rows.values()))


def _same(field_name: str, a: Any, b: Any, campaign: Campaign) -> bool:
    if field_name in ("pin", "disc"):
        return campaign.alias(str(a)).casefold() == campaign.alias(str(b)).casefold()
    if isinstance(a, str) or isinstance(b, str):
        return str(a).strip() == str(b).strip()
    return math.isclose(float(a), float(b), rel_tol=1e-9, abs_tol=1e-9)


#: the key prefix of a manifest column tribopipe does not know, in a row's fields
EXTRA_PREFIX = "extra:"


def resolve_material(campaign: Campaign, name: str, what: str, file: str) -> Resolved:
    """A pin or disc name as a campaign gives it: its ``[names]`` alias, then resolved
    through the campaign's materials vocabulary (:mod:`tribopipe.materials`);
    :class:`CampaignError` naming the file, with a did-you-mean, otherwise."""
    full = campaign.alias(name)
    try:
        resolved = _resolved_name(campaign, full, what)
    except (MaterialError, ValidationError) as exc:
        raise CampaignError(exc.problem, path=file, hint=exc.hint) from None
    return Resolved(resolved, name.strip())


#: names resolved, by (the vocabulary's id, name, what) → (that vocabulary, canonical name)
_RESOLVED: dict[tuple[int, str, str], tuple[Vocabulary, str]] = {}


def _resolved_name(campaign: Campaign, full: str, what: str) -> str:
    """The canonical name of ``full`` in the campaign's vocabulary, each name resolved
    once per vocabulary (a campaign repeats a few names over thousands of files; the
    vocabulary is known by identity, as hashing it would walk every material); raises
    as :meth:`~tribopipe.materials.Vocabulary.resolve` does (a refusal is not kept)."""
    vocabulary = campaign.vocabulary
    key = (id(vocabulary), full, what)
    kept = _RESOLVED.get(key)
    if kept is not None and kept[0] is vocabulary:
        return kept[1]
    name = vocabulary.resolve(full, what).name
    if len(_RESOLVED) >= 4096:
        _RESOLVED.clear()
    _RESOLVED[key] = (vocabulary, name)
    return name


def material_problems(campaign: Campaign,
                      named: Sequence[tuple[str, str, str]]) -> list[str]:
    """One line per pin or disc name of ``named`` (``(what, name, where)``) that the
    campaign's vocabulary cannot resolve, with a did-you-mean and where it is used (the
    first place and how many more), in the order first met."""
    seen: dict[tuple[str, str], list[str]] = {}
    problems: dict[tuple[str, str], str] = {}
    for what, name, where in named:
        key = (what, name.strip())
        if key not in problems:
            full = campaign.alias(name)
            problem = campaign.vocabulary.problem(full, what) if full.strip() else None
            if problem is None:
                problems[key] = ""
                continue
            problems[key] = problem if full == name.strip() else \
                f"{problem} (from {name.strip()!r} by [names])"
        if problems[key]:
            seen.setdefault(key, []).append(where)
    lines = []
    for key, places in seen.items():
        more = f" and {len(places) - 1} more" if len(places) > 1 else ""
        lines.append(f"{problems[key]} [in {places[0]}{more}]")
    return lines


def merge_metadata(
    file: str, sources: Sequence[tuple[str, Mapping[str, Any]]], campaign: Campaign
) -> dict[str, Any]:
    """Merge the label fields of several sources (in priority order) for one file.

    Names get their ``[names]`` alias; the first source giving a field defines its value.
    Raises :class:`CampaignError` naming the file, the field and both sources when two
    sources disagree.
    """
    merged: dict[str, Any] = {}
    origin: dict[str, str] = {}
    for source, fields in sources:
        for key, value in fields.items():
            if value is None:
                continue
            if key in ("pin", "disc"):
                given = str(value).strip()
                value = resolve_material(campaign, given, key, file).name
                merged.setdefault(sys.intern(f"{key}_as_given"), given)
            if key in merged:
                if not _same(key, merged[key], value, campaign):
                    raise CampaignError(
                        f"contradictory {key}: {origin[key]} says {merged[key]!r}, "
                        f"{source} says {value!r}",
                        path=file,
                        hint="fix the manifest, the file name or the Test name",
                    )
                continue
            merged[key] = value
            origin[key] = source
    return merged


def run_report(merged: Mapping[str, Any], defaults: RunReport | None = None,
               header: Mapping[str, str] | None = None) -> RunReport:
    """A run's reporting items: those of its merged metadata (the manifest), else the
    campaign's ``[metadata]`` (``defaults``), else what its export's header says
    (``header``, :func:`tribopipe.reporting.from_export`); the manifest's unknown columns
    as extra metadata."""
    values = {k: v for k, v in merged.items() if k in REPORTING_NAMES}
    extra = {k[len(EXTRA_PREFIX):]: str(v) for k, v in merged.items()
             if k.startswith(EXTRA_PREFIX)}
    report = RunReport.of(values, extra)
    if defaults is not None:
        report = report.over(defaults)
    if header:
        report = report.over(RunReport.of(from_export(header)))
    return report


def labels_from(file: str, merged: Mapping[str, Any], *, hints: Sequence[str] = (),
                report: RunReport | None = None) -> RunLabels:
    """Build :class:`RunLabels` from merged fields (with the run's reporting items,
    ``report``: default :func:`run_report` of ``merged``); :class:`CampaignError` when a
    required field (pin, disc, normal_force_N, temperature_C) is missing."""
    missing = [f for f in REQUIRED_FIELDS if merged.get(f) is None]
    if missing:
        hint = "; ".join(hints) if hints else (
            "give it in the manifest, the file-name pattern or the test-name pattern")
        raise CampaignError(f"metadata missing: {', '.join(missing)}", path=file, hint=hint)
    try:
        return RunLabels(
            pin=str(merged["pin"]),
            disc=str(merged["disc"]),
            normal_force_N=float(merged["normal_force_N"]),
            temperature_C=float(merged["temperature_C"]),
            repeat=None if merged.get("repeat") is None else merged["repeat"],
            pin_as_given=merged.get("pin_as_given"),
            disc_as_given=merged.get("disc_as_given"),
            report=report if report is not None else run_report(merged),
        )
    except ValidationError as exc:
        raise CampaignError(exc.problem, path=file) from None
