"""The friction map's schema: the one table of row rules, and the validated DataFrame
form of the rows.

:data:`COLUMNS` is the contract of a map row, one :class:`Column` per column: name, kind,
unit, meaning, physical range (with its reason) and whether it is required. Everything
else is derived from it: :data:`RUN_COLUMNS`, :data:`KIND`, :data:`BOUNDS`,
:data:`REQUIRED`, :data:`NAME_COLUMNS`; the store's row check (:func:`check_runs`), the
package validator (:func:`tribopipe.frictionmap.checks.validate_runs`) and the
``datapackage.json`` field constraints
(:func:`tribopipe.frictionmap.datapackage.runs_fields`). :func:`records_frame` turns
record dicts into a map DataFrame with the schema's dtypes and row rules,
:func:`frame_records` turns it back. The schema is written with units into every map's
Parquet metadata (:mod:`tribopipe.frictionmap.store`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, fields, replace
from datetime import UTC, datetime
from typing import TYPE_CHECKING, Any

from ..config import DEFAULT_TEST_METHOD, TEST_METHODS
from ..errors import MapError, RowError
from ..escape import printable
from ..reporting import EXTRA_COLUMN
from ..reporting import ITEMS as REPORTING_ITEMS
from ..validate import (
    FORCE_N,
    MAX_REPEAT,
    MU,
    PRESSURE_KPA,
    SLIDING_SPEED_MM_S,
    TEMPERATURE_C,
    Range,
    file_name_problem,
    name_problem,
    text_problem,
)

if TYPE_CHECKING:
    import pandas as pd

#: Parquet key-value metadata key holding the schema and provenance (JSON).
META_KEY = b"tribopipe.frictionmap"
SCHEMA_NAME = "tribopipe.frictionmap"
SCHEMA_VERSION = 6

#: ``source`` of runs reduced by tribopipe (imported rows name their origin instead).
SOURCE_REDUCED = "reduced"
#: ``source`` of the founding paper's published map.
SOURCE_PUBLISHED = "published:Berthold2023"
#: ``Column.required``: the column is filled in every row
ALWAYS = "always"
#: ``Column.required``: filled in every row tribopipe reduced (``source`` is
#: :data:`SOURCE_REDUCED`); an imported row may lack it
IN_REDUCED_ROWS = "reduced"
#: ``Column.required``: filled in every row of a published data package (a map's own rows
#: may leave it missing)
IN_PACKAGES = "package"

_DISTANCE = Range(0.0, 1e9, "mm")
_SPREAD = Range(0.0, 1e3)


@dataclass(frozen=True)
class Column:
    """One column of a map row and its rules.

    ``kind`` is ``"str"``, ``"float"``, ``"int"`` (nullable) or ``"bool"``; ``unit`` is
    ``""`` for none. ``bounds`` is the physical range of a number (``None``: a float need
    only be finite); ``reason`` says why; ``choices`` the values a text column may hold.
    ``required`` is ``""`` (may be missing),
    :data:`ALWAYS`, :data:`IN_REDUCED_ROWS` or :data:`IN_PACKAGES`. A text column
    required :data:`ALWAYS` is a name (one printable line of at most 200 characters, not
    blank); every other text is one printable line.
    """

    name: str
    kind: str
    unit: str
    meaning: str
    bounds: Range | None = None
    reason: str = ""
    required: str = ""
    #: the values a text column may hold (``()``: any one printable line)
    choices: tuple[str, ...] = ()


_CONTACT = "a run in contact presses the pins on the disc"
_COLD = "nothing is colder than absolute zero"
_RATIO = "a coefficient of friction is a ratio of magnitudes"
_ALONG = "sliding distance from the start of sliding"

#: The one table of row rules: every map row keeps them, on its way into the map and on
#: every read; a published package's ``datapackage.json`` states them as constraints.
COLUMNS: tuple[Column, ...] = (
    Column("measurement_id", "str", "", "hash of the raw file content + interval (or import "
           "origin)", required=ALWAYS),
    Column("source", "str", "", "'reduced' or the origin of an imported row", required=ALWAYS),
    Column("lab", "str", "", "laboratory that measured the run (missing: the map's own lab)",
           required=IN_PACKAGES),
    Column("pin", "str", "", "pin material", required=ALWAYS),
    Column("disc", "str", "", "disc material", required=ALWAYS),
    Column("normal_force_N", "float", "N", "nominal total normal force", FORCE_N, _CONTACT,
           ALWAYS),
    Column("pressure_kPa", "float", "kPa", "nominal contact pressure per pin", PRESSURE_KPA,
           "a run in contact has a positive contact pressure", ALWAYS),
    Column("normal_force_measured_N", "float", "N", "measured mean normal force", FORCE_N,
           _CONTACT),
    Column("pressure_measured_kPa", "float", "kPa", "measured mean contact pressure per pin",
           PRESSURE_KPA, "a run in contact has a positive contact pressure"),
    Column("temperature_C", "float", "°C", "nominal temperature", TEMPERATURE_C, _COLD),
    Column("temperature_measured_C", "float", "°C", "measured mean temperature",
           TEMPERATURE_C, _COLD),
    Column("sliding_speed_mm_s", "float", "mm/s", "measured sliding speed",
           SLIDING_SPEED_MM_S, "a friction run slides"),
    Column("nominal_speed_mm_s", "float", "mm/s", "nominal sliding speed (the interval's "
           "set point; missing in rows older than schema version 5: the founding speed)",
           SLIDING_SPEED_MM_S, "a friction run slides"),
    Column("repeat", "int", "", "repeat number within the condition",
           Range(0, MAX_REPEAT), "repeat numbers count up from 0 or 1"),
    Column("mu_s", "float", "", "static coefficient of friction", MU, _RATIO,
           IN_REDUCED_ROWS),
    Column("mu_k", "float", "", "kinetic coefficient of friction", MU, _RATIO, ALWAYS),
    Column("u_mu_s", "float", "", "standard uncertainty of μ_S (GUM, k = 1)", _SPREAD,
           "a standard uncertainty is not negative"),
    Column("u_mu_k", "float", "", "standard uncertainty of μ_K (GUM, k = 1)", _SPREAD,
           "a standard uncertainty is not negative"),
    Column("mu_s_distance_mm", "float", "mm", "sliding distance at the static peak",
           _DISTANCE, _ALONG),
    # times are on the export's own clock, which may start anywhere: finite only
    Column("mu_s_time_s", "float", "s", "time of the static peak"),
    Column("mu_k_window_start_mm", "float", "mm", "start of the kinetic plateau window",
           _DISTANCE, _ALONG),
    Column("mu_k_window_end_mm", "float", "mm", "end of the kinetic plateau window",
           _DISTANCE, _ALONG),
    Column("mu_k_window_start_s", "float", "s", "start of the kinetic plateau window"),
    Column("mu_k_window_end_s", "float", "s", "end of the kinetic plateau window"),
    Column("plateau_std", "float", "", "standard deviation of μ in the plateau window",
           _SPREAD, "a standard deviation is not negative"),
    Column("plateau_drift_per_mm", "float", "1/mm", "slope of μ over the plateau window"),
    Column("flags", "str", "", "QC flags, ';'-joined"),
    Column("method", "str", "", "reduction method (or 'published'/'imported')"),
    Column("test_method", "str", "", "instrument kind and test method: "
           + ", ".join(f"'{m}'" for m in TEST_METHODS) + " (missing in rows older than "
           f"schema version 6: '{DEFAULT_TEST_METHOD}')", choices=TEST_METHODS),
    Column("source_file", "str", "", "name of the raw or imported file"),
    Column("file_hash", "str", "", "SHA-256 of that file"),
    Column("test", "str", "", "Test name in the export the run came from (as the export "
           "writes it)"),
    Column("result", "str", "", "result of that test the run came from"),
    Column("interval", "int", "", "interval of the export the run came from",
           Range(0, 1_000_000_000), "interval numbers count up from 0 or 1"),
    Column("config_hash", "str", "", "hash of instrument + reduction settings"),
    Column("tribopipe_version", "str", "", "version that wrote the row"),
    Column("reduced_at", "str", "", "UTC time of reduction or import (ISO 8601)"),
    Column("excluded", "bool", "", "left out of the statistics", required=ALWAYS),
    Column("exclusion_reason", "str", "", "why it was excluded"),
    Column("review", "str", "", "a reviewer's decision on the run: 'accept' (its QC flags "
           "do not count against its group), 'exclude' or 'window' (μ_K, and μ_S where a "
           "peak was given, re-read where the reviewer chose); missing: not reviewed"),
    Column("review_by", "str", "", "who reviewed the run"),
    Column("review_date", "str", "", "when the run was reviewed (as the decisions file says)"),
    Column("review_reason", "str", "", "why the reviewer decided so"),
    Column("review_kinetic_from_mm", "float", "mm", "start of the μ_K window the reviewer "
           "gave", _DISTANCE, _ALONG),
    Column("review_kinetic_to_mm", "float", "mm", "end of the μ_K window the reviewer gave",
           _DISTANCE, _ALONG),
    Column("review_static_peak_mm", "float", "mm", "the static peak position the reviewer "
           "gave", _DISTANCE, _ALONG),
    Column("auto_mu_s", "float", "", "μ_S as the reduction found it (reviewed rows)", MU,
           _RATIO),
    Column("auto_mu_k", "float", "", "μ_K as the reduction found it (reviewed rows)", MU,
           _RATIO),
    Column("auto_u_mu_s", "float", "", "u(μ_S) as the reduction found it (reviewed rows)",
           _SPREAD, "a standard uncertainty is not negative"),
    Column("auto_u_mu_k", "float", "", "u(μ_K) as the reduction found it (reviewed rows)",
           _SPREAD, "a standard uncertainty is not negative"),
    Column("auto_mu_s_distance_mm", "float", "mm", "the reduction's static peak position "
           "(reviewed rows)", _DISTANCE, _ALONG),
    Column("auto_mu_k_window_start_mm", "float", "mm", "start of the reduction's μ_K window "
           "(reviewed rows)", _DISTANCE, _ALONG),
    Column("auto_mu_k_window_end_mm", "float", "mm", "end of the reduction's μ_K window "
           "(reviewed rows)", _DISTANCE, _ALONG),
    Column("pin_as_given", "str", "", "the pin's name as it came in (a pattern, manifest, "
           "option or merged map), before the materials vocabulary resolved it"),
    Column("disc_as_given", "str", "", "the disc's name as it came in, before the materials "
           "vocabulary resolved it"),
    *(Column(item.name, item.kind, item.unit, item.meaning, item.bounds,
             "a physical range" if item.bounds is not None else "")
      for item in REPORTING_ITEMS),
    Column(EXTRA_COLUMN, "str", "", "metadata columns tribopipe does not know, as a JSON "
           "object of text values"),
)

#: the columns a review sets (:mod:`tribopipe.review`); the ``auto_`` ones keep the
#: reduction's own values beside the reviewed ones
REVIEW_COLUMNS: tuple[str, ...] = (
    "review", "review_by", "review_date", "review_reason", "review_kinetic_from_mm",
    "review_kinetic_to_mm", "review_static_peak_mm", "auto_mu_s", "auto_mu_k",
    "auto_u_mu_s", "auto_u_mu_k", "auto_mu_s_distance_mm", "auto_mu_k_window_start_mm",
    "auto_mu_k_window_end_mm")

RUN_COLUMNS: tuple[str, ...] = tuple(c.name for c in COLUMNS)
#: Columns added after schema version 1, with the version that added them: a map written
#: before that version lacks them and reads with them missing, and a record built by older
#: code may leave them out.
ADDED_IN_VERSION: dict[str, int] = {"lab": 2, "u_mu_s": 3, "u_mu_k": 3, "test": 4, "result": 4,
                                    "nominal_speed_mm_s": 5, "test_method": 6,
                                    **{c: 6 for c in REVIEW_COLUMNS},
                                    "pin_as_given": 6, "disc_as_given": 6,
                                    EXTRA_COLUMN: 6,
                                    **{item.name: 6 for item in REPORTING_ITEMS}}
#: the values each text column with a closed vocabulary may hold
CHOICES: dict[str, tuple[str, ...]] = {c.name: c.choices for c in COLUMNS if c.choices}
#: the kind of each column: ``"str"``, ``"float"``, ``"int"`` or ``"bool"``
KIND: dict[str, str] = {c.name: c.kind for c in COLUMNS}
#: the physical range of each bounded number column; a float column not listed need only
#: be finite (or missing)
BOUNDS: dict[str, Range] = {c.name: c.bounds for c in COLUMNS if c.bounds is not None}
#: number and truth columns that may not be missing in any row
REQUIRED: frozenset[str] = frozenset(
    c.name for c in COLUMNS if c.required == ALWAYS and c.kind != "str")
#: the text columns that name something (required in every row: one printable line,
#: at most 200 characters, not blank)
NAME_COLUMNS: tuple[str, ...] = tuple(
    c.name for c in COLUMNS if c.required == ALWAYS and c.kind == "str")
#: Columns that say where a row came from, not what was measured: two rows with the same
#: id that differ only here are the same run (a renamed file, a later import). ``test`` and
#: ``result`` are part of what the id hashes, so they can differ only where one row lacks
#: them (a row of a map older than schema version 4).
PROVENANCE_COLUMNS: frozenset[str] = frozenset(
    {"lab", "source_file", "file_hash", "test", "result", "tribopipe_version", "reduced_at",
     "excluded", "exclusion_reason", "pin_as_given", "disc_as_given"}
)
CONTENT_COLUMNS: tuple[str, ...] = tuple(c for c in RUN_COLUMNS if c not in PROVENANCE_COLUMNS)
#: The content columns :data:`ADDED_IN_VERSION` a later schema: a row written before the
#: column existed lacks it, so where the older of two rows of one run lacks it, that is no
#: difference of the run (the store compares rows with this rule). The review's columns
#: are not among them: missing there means "not reviewed", and a review that fills them
#: changes the row.
ADDED_LATER_CONTENT: frozenset[str] = frozenset(c for c in ADDED_IN_VERSION
                                                if c in CONTENT_COLUMNS
                                                and c not in REVIEW_COLUMNS)


@dataclass(frozen=True, kw_only=True)
class MapRow:
    """One map row, typed: one field per column of :data:`COLUMNS`, in its order, of its
    kind (``str``, ``float``, ``int``, ``bool``); a column not required in every row
    (:data:`ALWAYS`) may be ``None`` (missing). A misspelt column is a type error.

    The fields are held to :data:`COLUMNS` when this module is imported
    (:func:`_check_row_type`), so the table of row rules stays the one place a column is
    declared. Build one from a mapping with :meth:`from_mapping`, from a map DataFrame
    with :func:`frame_rows`; :func:`records_frame` turns rows into a map DataFrame. A row
    built by :func:`checked_row` has kept the row rules and is not checked again; a copy
    changed with :func:`dataclasses.replace` is checked again.
    """

    measurement_id: str
    source: str
    lab: str | None = None
    pin: str
    disc: str
    normal_force_N: float
    pressure_kPa: float
    normal_force_measured_N: float | None = None
    pressure_measured_kPa: float | None = None
    temperature_C: float | None = None
    temperature_measured_C: float | None = None
    sliding_speed_mm_s: float | None = None
    nominal_speed_mm_s: float | None = None
    repeat: int | None = None
    mu_s: float | None = None
    mu_k: float
    u_mu_s: float | None = None
    u_mu_k: float | None = None
    mu_s_distance_mm: float | None = None
    mu_s_time_s: float | None = None
    mu_k_window_start_mm: float | None = None
    mu_k_window_end_mm: float | None = None
    mu_k_window_start_s: float | None = None
    mu_k_window_end_s: float | None = None
    plateau_std: float | None = None
    plateau_drift_per_mm: float | None = None
    flags: str | None = None
    method: str | None = None
    test_method: str | None = None
    source_file: str | None = None
    file_hash: str | None = None
    test: str | None = None
    result: str | None = None
    interval: int | None = None
    config_hash: str | None = None
    tribopipe_version: str | None = None
    reduced_at: str | None = None
    excluded: bool = False
    exclusion_reason: str | None = None
    review: str | None = None
    review_by: str | None = None
    review_date: str | None = None
    review_reason: str | None = None
    review_kinetic_from_mm: float | None = None
    review_kinetic_to_mm: float | None = None
    review_static_peak_mm: float | None = None
    auto_mu_s: float | None = None
    auto_mu_k: float | None = None
    auto_u_mu_s: float | None = None
    auto_u_mu_k: float | None = None
    auto_mu_s_distance_mm: float | None = None
    auto_mu_k_window_start_mm: float | None = None
    auto_mu_k_window_end_mm: float | None = None
    pin_as_given: str | None = None
    disc_as_given: str | None = None
    humidity_pct: float | None = None
    disc_Ra_um: float | None = None
    surface_finish: str | None = None
    specimen_batch: str | None = None
    specimen_cure: str | None = None
    conditioning_h: float | None = None
    instrument: str | None = None
    instrument_serial: str | None = None
    software_version: str | None = None
    operator: str | None = None
    measured_on: str | None = None
    extra_metadata: str | None = None
    #: set by :func:`checked_row` only: the row kept the row rules when it was built
    checked: bool = field(default=False, init=False, compare=False, repr=False)

    @classmethod
    def from_mapping(cls, values: Mapping[str, Any], *, where: str = "record") -> MapRow:
        """The row of a mapping keyed by :data:`RUN_COLUMNS` (missing values ``None`` or
        NaN; the columns :data:`ADDED_IN_VERSION` may be left out). Raises
        :class:`MapError` naming the column when one is absent, unknown or of the wrong
        kind; the row rules are not checked here (:func:`checked_row` does)."""
        unknown = [k for k in values if k not in KIND]
        if unknown:
            raise MapError(f"{where} has unknown column(s) "
                           f"{', '.join(printable(str(k))[:40] for k in unknown[:5])}",
                           hint="build rows with tribopipe.frictionmap.make_record")
        absent = [c for c in RUN_COLUMNS if c not in values and c not in ADDED_IN_VERSION]
        if absent:
            raise MapError(f"{where} lacks column(s) {', '.join(absent)}",
                           hint="build rows with tribopipe.frictionmap.make_record")
        typed: dict[str, Any] = {}
        for name in RUN_COLUMNS:
            value = values.get(name)
            try:
                typed[name] = _typed(value, KIND[name])
            except (TypeError, ValueError, OverflowError):
                raise MapError(f"{where}: expected {KIND[name]} values, got {value!r}",
                               column=name) from None
        return cls(**typed)

    def as_dict(self) -> dict[str, Any]:
        """The row as a dict keyed by :data:`RUN_COLUMNS` (missing values ``None``), for
        writers of outside formats (JSON, CSV)."""
        return {name: getattr(self, name) for name in RUN_COLUMNS}


#: the annotation each kind of column has in :class:`MapRow`
_ROW_TYPE = {"str": "str", "float": "float", "int": "int", "bool": "bool"}


def _check_row_type() -> None:
    """Hold :class:`MapRow` to :data:`COLUMNS`: the same columns in the same order, each
    of its kind, ``None`` allowed exactly where the column is not required in every row
    (a ``bool`` is never missing)."""
    row_fields = [f for f in fields(MapRow) if f.init]
    names = tuple(f.name for f in row_fields)
    if names != RUN_COLUMNS:
        raise AssertionError(f"MapRow's fields {names} differ from COLUMNS {RUN_COLUMNS}")
    for f, column in zip(row_fields, COLUMNS, strict=True):
        expected = _ROW_TYPE[column.kind]
        if column.required != ALWAYS and column.kind != "bool":
            expected += " | None"
        if f.type != expected:
            raise AssertionError(f"MapRow.{f.name} is {f.type}, COLUMNS says {expected}")


_check_row_type()


def utc_now() -> str:
    return datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ")


def empty_map() -> pd.DataFrame:
    """A map with no runs: the :data:`RUN_COLUMNS` with their dtypes."""
    return records_frame([])


def is_missing(value: Any) -> bool:
    if value is None:
        return True
    try:
        import pandas as pd

        return bool(pd.isna(value))
    except (TypeError, ValueError):
        return False


def checked_row(record: MapRow | Mapping[str, Any], *, where: str = "record") -> MapRow:
    """``record`` as a :class:`MapRow` checked against the row rules
    (:func:`check_runs`; a :class:`MapError` naming the column otherwise), marked so that
    :func:`records_frame` does not check it again."""
    row = record if isinstance(record, MapRow) else MapRow.from_mapping(record, where=where)
    check_runs(unvalidated_frame([row], where=where), where)
    if not row.checked:
        row = replace(row)
        object.__setattr__(row, "checked", True)
    return row


def records_frame(records: Sequence[MapRow | Mapping[str, Any]], *,
                  where: str = "record") -> pd.DataFrame:
    """Validate map rows and return them as a map DataFrame (schema dtypes, in order).

    A row is a :class:`MapRow` or a mapping keyed by :data:`RUN_COLUMNS` (rows from
    outside: those of :data:`ADDED_IN_VERSION` may be left out: missing) with a value of
    its kind (a ``bool`` is no number, text is no ``bool``). Every row must keep the rules
    of :func:`check_runs` (not checked again when every row is a :class:`MapRow` built by
    :func:`checked_row`). Raises :class:`MapError` naming the row and column otherwise;
    nothing is written on error.
    """
    frame = unvalidated_frame(records, where=where)
    if records and all(isinstance(r, MapRow) and r.checked for r in records):
        return frame  # each kept the rules when it was built (checked_row)
    return check_runs(frame, where)


def unvalidated_frame(
    records: Sequence[MapRow | Mapping[str, Any]], *, where: str = "record"
) -> pd.DataFrame:
    """:func:`records_frame` without its row rules: the schema's columns and dtypes only
    (a value of the wrong kind is still a :class:`MapError`). For checks that want to see
    every problem of the rows (:func:`tribopipe.frictionmap.checks.validate_runs`) rather
    than the first."""
    import pandas as pd

    columns: dict[str, Any] = {}
    for i, rec in enumerate(records):
        if isinstance(rec, MapRow):
            continue
        absent = [c for c in RUN_COLUMNS if c not in rec and c not in ADDED_IN_VERSION]
        if absent:
            raise MapError(
                f"{where} {i + 1} lacks column(s) {', '.join(absent)}",
                hint="build records with tribopipe.frictionmap.make_record",
            )
    for name in RUN_COLUMNS:
        kind = KIND[name]
        values = [getattr(rec, name) if isinstance(rec, MapRow) else rec.get(name)
                  for rec in records]
        try:
            columns[name] = _column(values, kind)
        except (TypeError, ValueError, OverflowError) as exc:
            bad = next((i for i, v in enumerate(values) if not _ok(v, kind)), None)
            if bad is None:
                raise MapError(f"expected {kind} values, got {exc!r}", column=name) from None
            raise RowError(f"expected {kind} values, got {values[bad]!r}", row=f"{where} {bad + 1}",
                           column=name) from None
    return pd.DataFrame(columns, columns=list(RUN_COLUMNS), index=pd.RangeIndex(len(records)))


#: the text columns that hold a file's own name, kept raw
#: (:func:`~tribopipe.validate.file_name_problem`)
FILE_NAME_COLUMNS: tuple[str, ...] = ("source_file",)


def _row_error(frame: pd.DataFrame, where: str, i: int, column: str, problem: str) -> RowError:
    ident = frame["measurement_id"].iloc[i]
    label = f" ({printable(str(ident))[:40]})" if isinstance(ident, str) else ""
    return RowError(problem, row=f"{where} {i + 1}{label}", column=column)


def check_runs(frame: pd.DataFrame, where: str = "row") -> pd.DataFrame:
    """Check the rows of a map DataFrame (schema dtypes) against :data:`COLUMNS` and return
    it unchanged, or raise :class:`MapError` naming the first bad row (``where`` and its
    number, its id), the column and what was expected.

    The rules every map row keeps, wherever it comes from (a reduction, an import, another
    lab's map, a file on disk):

    * :data:`NAME_COLUMNS` are names (one printable line of at most 200 characters, not
      blank); :data:`FILE_NAME_COLUMNS` hold a file's own name (any text without NUL or a
      lone surrogate) or are missing; every other text is one printable line or missing;
    * floats finite or missing (never ±inf); numbers inside their :data:`BOUNDS` (force > 0,
      temperature above −273.15 °C, 0 ≤ μ ≤ 10 ...; ``repeat`` and ``interval`` whole
      numbers); :data:`REQUIRED` never missing, and the columns required
      :data:`IN_REDUCED_ROWS` (``mu_s``) missing only in imported rows.
    """
    import numpy as np

    reduced = (frame["source"] == SOURCE_REDUCED).to_numpy(dtype=bool)
    for column in COLUMNS:
        name, kind, bounds = column.name, column.kind, column.bounds
        if kind == "str":
            found = _first_text_problem(frame[name], column)
            if found is not None:
                raise _row_error(frame, where, found[0], name, f"{name}: {found[1]}")
        elif kind == "float":
            values = frame[name].to_numpy(dtype=float)
            present = ~np.isnan(values)
            if bounds is None:
                bad = present & ~np.isfinite(values)
                expected = "a finite number or missing"
            else:
                low = values > bounds.low if bounds.low_open else values >= bounds.low
                bad = present & ~(low & (values <= bounds.high))
                expected = f"a number {bounds.describe()}"
            if column.required == ALWAYS:
                bad |= ~present
            if bad.any():
                i = int(np.flatnonzero(bad)[0])
                raise _row_error(frame, where, i, name,
                                 f"{name} is {float(values[i])!r}, expected {expected}")
            if column.required == IN_REDUCED_ROWS and (reduced & ~present).any():
                i = int(np.flatnonzero(reduced & ~present)[0])
                raise _row_error(frame, where, i, name,
                                 f"{name} is missing; only imported rows may lack {name}")
        elif kind == "int" and bounds is not None:
            values_i = frame[name]
            bad_i = values_i.notna() & ((values_i < bounds.low) | (values_i > bounds.high))
            if bad_i.any():
                i = int(np.flatnonzero(bad_i.to_numpy(dtype=bool))[0])
                raise _row_error(frame, where, i, name, f"{name} is {values_i.iloc[i]}, "
                                 f"expected a whole number from {bounds.low:.0f} to "
                                 f"{bounds.high:.0f}")
    return frame


def _text_problem(value: Any, column: Column) -> str | None:
    """Why the present text ``value`` breaks the rules of the text ``column`` (a name, a
    file's own name, one line of text; one of its choices), or ``None``."""
    name = column.name
    checker = (name_problem if name in NAME_COLUMNS else
               file_name_problem if name in FILE_NAME_COLUMNS else text_problem)
    problem = checker(value)
    if problem is None and column.choices and value not in column.choices:
        problem = (f"{printable(str(value))[:60]!r} is not one of "
                   + ", ".join(repr(c) for c in column.choices))
    return problem


def _first_text_problem(values: pd.Series, column: Column) -> tuple[int, str] | None:
    """The first row (position) of the text column ``values`` that breaks the rules of
    ``column``, with its problem; ``None`` when none does. A column of text (pandas'
    ``str`` dtype: every present value a ``str``) is checked once per distinct value;
    any other column value by value, as it comes."""
    import numpy as np
    import pandas as pd

    is_name = column.name in NAME_COLUMNS
    if values.dtype == "str":
        codes, uniques = pd.factorize(values)
        problems = {u: p for u, text in enumerate(uniques.tolist())
                    if (p := _text_problem(text, column)) is not None}
        bad = np.isin(codes, list(problems)) if problems else np.zeros(len(codes), bool)
        if is_name:
            bad |= codes < 0
        if not bad.any():
            return None
        i = int(np.flatnonzero(bad)[0])
        code = int(codes[i])
        return i, "missing, expected a name" if code < 0 else problems[code]
    for i, value in enumerate(values.tolist()):
        missing = value is None or (isinstance(value, float) and value != value)
        if missing and not is_name:
            continue
        problem = "missing, expected a name" if missing else _text_problem(value, column)
        if problem is not None:
            return i, problem
    return None


def content_sha256(frame: pd.DataFrame, version: int = SCHEMA_VERSION) -> str:
    """SHA-256 (hex) of a map's content: the :data:`RUN_COLUMNS` of schema ``version``
    (those :data:`ADDED_IN_VERSION` later are left out) of every row, in order, in a
    canonical byte form (floats as little-endian IEEE 754 with one NaN, whole numbers as
    int64 with a missing-mask, booleans as bytes, text as JSON with ``null``), so the same
    rows give the same digest however they were stored or read back. Stored in the map's
    Parquet metadata and checked on every read against the version the map was written
    in (:mod:`tribopipe.frictionmap.store`), so a map still verifies after a schema
    upgrade adds columns.
    """
    return columns_sha256(len(frame), lambda name: frame[name], version)


def columns_sha256(n_rows: int, column_of: Callable[[str], pd.Series],
                   version: int = SCHEMA_VERSION) -> str:
    """:func:`content_sha256` of ``n_rows`` rows given a column at a time: ``column_of``
    gives the column of a name (all ``n_rows`` cells), asked once per column in the
    schema's order, so that a caller that holds the rows in another form (an Arrow
    table) never builds them as one DataFrame."""
    import hashlib

    import numpy as np

    digest = hashlib.sha256(f"tribopipe.frictionmap rows={n_rows}".encode())
    for name in RUN_COLUMNS:
        if ADDED_IN_VERSION.get(name, 1) > version:
            continue
        kind = KIND[name]
        column = column_of(name)
        if len(column) != n_rows:
            raise ValueError(f"column {name} holds {len(column)} cells, not {n_rows}")
        if kind == "float":
            values = column.to_numpy(dtype="float64")
            data = np.where(np.isnan(values), np.nan, values).astype("<f8").tobytes()
        elif kind == "int":
            ints = column.astype("Int64")
            mask = ints.isna()
            data = (np.asarray(mask, dtype="u1").tobytes()
                    + ints.fillna(0).to_numpy(dtype="int64").astype("<i8").tobytes())
        elif kind == "bool":
            data = np.asarray(column, dtype=bool).astype("u1").tobytes()
        else:
            pieces = _json_pieces(column)
            size = 2 + sum(len(p) for p in pieces) + 2 * max(0, len(pieces) - 1)
            digest.update(f"|{name}:{kind}:{size}|[".encode())
            for k, piece in enumerate(pieces):
                if k:
                    digest.update(b", ")
                digest.update(piece)
            digest.update(b"]")
            continue
        digest.update(f"|{name}:{kind}:{len(data)}|".encode())
        digest.update(data)
    return digest.hexdigest()


#: cells of a text column turned into Python texts at a time by :func:`columns_sha256`
HASH_BATCH_ROWS = 8192


def _json_pieces(column: pd.Series) -> list[bytes]:
    """The JSON text (UTF-8, ``ensure_ascii=False``) of the list of a text column's cells
    (:func:`_texts`) without its brackets, in pieces of :data:`HASH_BATCH_ROWS` cells:
    joined by ``", "`` and bracketed they are ``json.dumps`` of the whole list, which is
    never built (for a column of 10⁵ long texts: tens of MB twice over)."""
    import json

    pieces = []
    for start in range(0, len(column), HASH_BATCH_ROWS):
        texts = _texts(column.iloc[start:start + HASH_BATCH_ROWS])
        pieces.append(json.dumps(texts, ensure_ascii=False)[1:-1].encode("utf-8",
                                                                          "surrogatepass"))
    return pieces


def _texts(column: pd.Series) -> list[str | None]:
    """The cells of a text column as :func:`content_sha256` hashes them: ``None`` where
    missing, else the text (a column of pandas' ``str`` dtype as it is, any other value
    by value)."""
    import numpy as np

    if column.dtype != "str":
        return [None if is_missing(v) else str(v) for v in column.tolist()]
    texts: list[str | None] = column.tolist()
    for i in np.flatnonzero(np.asarray(column.isna(), dtype=bool)).tolist():
        texts[i] = None
    return texts


def _ok(value: Any, kind: str) -> bool:
    try:
        _column([value], kind)
    except (TypeError, ValueError, OverflowError):
        return False
    return True


def _column(values: list[Any], kind: str) -> Any:
    import numpy as np
    import pandas as pd

    if kind == "float":
        out = []
        for v in values:
            if is_missing(v):
                out.append(np.nan)
            elif isinstance(v, bool | str):
                raise TypeError(f"not a number: {v!r}")
            else:
                out.append(float(v))
        return np.asarray(out, dtype="float64")
    if kind == "int":
        out_i: list[Any] = []
        for v in values:
            if is_missing(v):
                out_i.append(pd.NA)
            elif isinstance(v, bool | str) or float(v) != int(float(v)):
                raise TypeError(f"not a whole number: {v!r}")
            else:
                out_i.append(int(v))
        return pd.array(out_i, dtype="Int64")
    if kind == "bool":
        out_b = []
        for v in values:
            if isinstance(v, bool | np.bool_):
                out_b.append(bool(v))
            else:
                raise TypeError(f"not true/false: {v!r}")
        return np.asarray(out_b, dtype=bool)
    out_s: list[Any] = []
    for v in values:
        if is_missing(v):
            out_s.append(None)
        elif isinstance(v, str):
            out_s.append(v)
        else:
            raise TypeError(f"not text: {v!r}")
    return pd.array(out_s, dtype="str")


def _typed(value: Any, kind: str) -> Any:
    """One value of a column of ``kind`` as :class:`MapRow` holds it (missing: ``None``);
    raises ``TypeError`` or ``ValueError`` for a value of another kind."""
    import numpy as np

    if kind == "bool":
        if isinstance(value, bool | np.bool_):
            return bool(value)
        raise TypeError(f"not true/false: {value!r}")
    if is_missing(value):
        return None
    if kind == "str":
        if isinstance(value, str):
            return str(value)
        raise TypeError(f"not text: {value!r}")
    if isinstance(value, bool | str | np.bool_):
        raise TypeError(f"not a number: {value!r}")
    if kind == "int":
        if float(value) != int(float(value)):
            raise TypeError(f"not a whole number: {value!r}")
        return int(value)
    return float(value)


def frame_rows(runs: pd.DataFrame) -> list[MapRow]:
    """The rows of a map DataFrame (schema dtypes) as :class:`MapRow` (missing values as
    ``None``), not checked again."""
    kinds = [KIND[c] for c in RUN_COLUMNS]
    out = []
    for row in runs.loc[:, list(RUN_COLUMNS)].itertuples(index=False, name=None):
        out.append(MapRow(**{c: _typed(v, k) for c, k, v in zip(RUN_COLUMNS, kinds, row,
                                                                  strict=True)}))
    return out


def frame_records(runs: pd.DataFrame) -> list[dict[str, Any]]:
    """The rows of a map DataFrame as dicts (missing values as ``None``), for writers of
    outside formats."""
    out = []
    for row in runs.loc[:, list(RUN_COLUMNS)].itertuples(index=False, name=None):
        pairs = zip(RUN_COLUMNS, row, strict=True)
        out.append({c: (None if is_missing(v) else v) for c, v in pairs})
    return out
