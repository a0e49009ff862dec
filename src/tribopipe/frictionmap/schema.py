"""The friction map's schema: its run columns with kinds, units and meanings, and the
validated DataFrame form of its rows.

:data:`RUN_COLUMNS` (from ``_SCHEMA``: name, kind, unit, meaning) is the contract of a map
row; :func:`records_frame` turns record dicts into a map DataFrame with the schema's dtypes
and row rules, :func:`frame_records` turns it back. The schema is written with units into
every map's Parquet metadata (:mod:`tribopipe.frictionmap.store`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from datetime import UTC, datetime
from typing import TYPE_CHECKING, Any

from ..errors import MapError
from ..escape import printable
from ..validate import (
    FORCE_N,
    MAX_REPEAT,
    MU,
    PRESSURE_KPA,
    SLIDING_SPEED_MM_S,
    TEMPERATURE_C,
    Range,
    name_problem,
    text_problem,
)

if TYPE_CHECKING:
    import pandas as pd

#: Parquet key-value metadata key holding the schema and provenance (JSON).
META_KEY = b"tribopipe.frictionmap"
SCHEMA_NAME = "tribopipe.frictionmap"
SCHEMA_VERSION = 4

#: ``source`` of runs reduced by tribopipe (imported rows name their origin instead).
SOURCE_REDUCED = "reduced"
#: ``source`` of the founding paper's published map.
SOURCE_PUBLISHED = "published:Berthold2023"
# (name, kind, unit or "", meaning); kinds: str, float, int (nullable), bool.
_SCHEMA: tuple[tuple[str, str, str, str], ...] = (
    ("measurement_id", "str", "", "hash of the raw file content + interval (or import origin)"),
    ("source", "str", "", "'reduced' or the origin of an imported row"),
    ("lab", "str", "", "laboratory that measured the run (missing: the map's own lab)"),
    ("pin", "str", "", "pin material"),
    ("disc", "str", "", "disc material"),
    ("normal_force_N", "float", "N", "nominal total normal force"),
    ("pressure_kPa", "float", "kPa", "nominal contact pressure per pin"),
    ("normal_force_measured_N", "float", "N", "measured mean normal force"),
    ("pressure_measured_kPa", "float", "kPa", "measured mean contact pressure per pin"),
    ("temperature_C", "float", "°C", "nominal temperature"),
    ("temperature_measured_C", "float", "°C", "measured mean temperature"),
    ("sliding_speed_mm_s", "float", "mm/s", "measured sliding speed"),
    ("repeat", "int", "", "repeat number within the condition"),
    ("mu_s", "float", "", "static coefficient of friction"),
    ("mu_k", "float", "", "kinetic coefficient of friction"),
    ("u_mu_s", "float", "", "standard uncertainty of μ_S (GUM, k = 1)"),
    ("u_mu_k", "float", "", "standard uncertainty of μ_K (GUM, k = 1)"),
    ("mu_s_distance_mm", "float", "mm", "sliding distance at the static peak"),
    ("mu_s_time_s", "float", "s", "time of the static peak"),
    ("mu_k_window_start_mm", "float", "mm", "start of the kinetic plateau window"),
    ("mu_k_window_end_mm", "float", "mm", "end of the kinetic plateau window"),
    ("mu_k_window_start_s", "float", "s", "start of the kinetic plateau window"),
    ("mu_k_window_end_s", "float", "s", "end of the kinetic plateau window"),
    ("plateau_std", "float", "", "standard deviation of μ in the plateau window"),
    ("plateau_drift_per_mm", "float", "1/mm", "slope of μ over the plateau window"),
    ("flags", "str", "", "QC flags, ';'-joined"),
    ("method", "str", "", "reduction method (or 'published'/'imported')"),
    ("source_file", "str", "", "name of the raw or imported file"),
    ("file_hash", "str", "", "SHA-256 of that file"),
    ("test", "str", "", "Test name in the export the run came from (as the export writes it)"),
    ("result", "str", "", "result of that test the run came from"),
    ("interval", "int", "", "interval of the export the run came from"),
    ("config_hash", "str", "", "hash of instrument + reduction settings"),
    ("tribopipe_version", "str", "", "version that wrote the row"),
    ("reduced_at", "str", "", "UTC time of reduction or import (ISO 8601)"),
    ("excluded", "bool", "", "left out of the statistics"),
    ("exclusion_reason", "str", "", "why it was excluded"),
)

RUN_COLUMNS: tuple[str, ...] = tuple(name for name, *_ in _SCHEMA)
#: Columns added after schema version 1, with the version that added them: a map written
#: before that version lacks them and reads with them missing, and a record built by older
#: code may leave them out.
ADDED_IN_VERSION: dict[str, int] = {"lab": 2, "u_mu_s": 3, "u_mu_k": 3, "test": 4, "result": 4}
_KIND: dict[str, str] = {name: kind for name, kind, *_ in _SCHEMA}
#: Columns that say where a row came from, not what was measured: two rows with the same
#: id that differ only here are the same run (a renamed file, a later import). ``test`` and
#: ``result`` are part of what the id hashes, so they can differ only where one row lacks
#: them (a row of a map older than schema version 4).
PROVENANCE_COLUMNS: frozenset[str] = frozenset(
    {"lab", "source_file", "file_hash", "test", "result", "tribopipe_version", "reduced_at",
     "excluded", "exclusion_reason"}
)
_CONTENT_COLUMNS: tuple[str, ...] = tuple(c for c in RUN_COLUMNS if c not in PROVENANCE_COLUMNS)


def _now() -> str:
    return datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ")


def empty_map() -> pd.DataFrame:
    """A map with no runs: the :data:`RUN_COLUMNS` with their dtypes."""
    return records_frame([])


def _missing(value: Any) -> bool:
    if value is None:
        return True
    try:
        import pandas as pd

        return bool(pd.isna(value))
    except (TypeError, ValueError):
        return False


def records_frame(records: Sequence[Mapping[str, Any]], *, where: str = "record") -> pd.DataFrame:
    """Validate run records and return them as a map DataFrame (schema dtypes, in order).

    Every record needs every column of :data:`RUN_COLUMNS` (those of
    :data:`ADDED_IN_VERSION` may be left out: missing) with a value of its kind (a
    ``bool`` is no number, text is no ``bool``) that keeps the rules of
    :func:`check_runs`. Raises :class:`MapError` naming the record and column otherwise;
    nothing is written on error.
    """
    return check_runs(unvalidated_frame(records, where=where), where)


def unvalidated_frame(
    records: Sequence[Mapping[str, Any]], *, where: str = "record"
) -> pd.DataFrame:
    """:func:`records_frame` without its row rules: the schema's columns and dtypes only
    (a value of the wrong kind is still a :class:`MapError`). For checks that want to see
    every problem of the rows (:func:`tribopipe.frictionmap.checks.validate_runs`) rather
    than the first."""
    import pandas as pd

    columns: dict[str, Any] = {}
    for i, rec in enumerate(records):
        absent = [c for c in RUN_COLUMNS if c not in rec and c not in ADDED_IN_VERSION]
        if absent:
            raise MapError(
                f"{where} {i + 1} lacks column(s) {', '.join(absent)}",
                hint="build records with tribopipe.frictionmap.make_record",
            )
    for name in RUN_COLUMNS:
        kind = _KIND[name]
        values = [rec.get(name) for rec in records]
        try:
            columns[name] = _column(values, kind)
        except (TypeError, ValueError, OverflowError) as exc:
            bad = next((i for i, v in enumerate(values) if not _ok(v, kind)), None)
            row = "" if bad is None else f"{where} {bad + 1}: "
            raise MapError(
                f"{row}expected {kind} values, got {values[bad] if bad is not None else exc!r}",
                column=name,
            ) from None
    return pd.DataFrame(columns, columns=list(RUN_COLUMNS), index=pd.RangeIndex(len(records)))


#: the text columns that name something (one printable line, ≤ 200 characters, not blank)
NAME_COLUMNS: tuple[str, ...] = ("measurement_id", "source", "pin", "disc")
#: the physical range of each float column; columns not listed need only be finite (or
#: missing). ``REQUIRED`` columns may not be missing in any row.
COLUMN_RANGES: dict[str, Range] = {
    "normal_force_N": FORCE_N,
    "pressure_kPa": PRESSURE_KPA,
    "normal_force_measured_N": FORCE_N,
    "pressure_measured_kPa": PRESSURE_KPA,
    "temperature_C": TEMPERATURE_C,
    "temperature_measured_C": TEMPERATURE_C,
    "sliding_speed_mm_s": SLIDING_SPEED_MM_S,
    "mu_s": MU,
    "mu_k": MU,
    "mu_s_distance_mm": Range(0.0, 1e9, "mm"),
    "mu_k_window_start_mm": Range(0.0, 1e9, "mm"),
    "mu_k_window_end_mm": Range(0.0, 1e9, "mm"),
    "plateau_std": Range(0.0, 1e3),
    "u_mu_s": Range(0.0, 1e3),
    "u_mu_k": Range(0.0, 1e3),
}
REQUIRED: frozenset[str] = frozenset({"normal_force_N", "pressure_kPa", "mu_k"})
#: the whole-number columns and their bounds
COUNT_RANGES: dict[str, tuple[int, int]] = {"repeat": (0, MAX_REPEAT),
                                            "interval": (0, 1_000_000_000)}


def _row_error(frame: pd.DataFrame, where: str, i: int, column: str, problem: str) -> MapError:
    ident = frame["measurement_id"].iloc[i]
    label = f" ({printable(str(ident))[:40]})" if isinstance(ident, str) else ""
    return MapError(f"{where} {i + 1}{label}: {problem}", column=column)


def check_runs(frame: pd.DataFrame, where: str = "row") -> pd.DataFrame:
    """Check the rows of a map DataFrame (schema dtypes) and return it unchanged, or raise
    :class:`MapError` naming the first bad row (``where`` and its number, its id), the
    column and what was expected.

    The rules every map row keeps, wherever it comes from (a reduction, an import, another
    lab's map, a file on disk):

    * ``measurement_id``, ``source``, ``pin``, ``disc``: names (one printable line of at
      most 200 characters, not blank); every other text: one printable line or missing;
    * floats finite or missing (never ±inf); inside the physical ranges of
      :data:`COLUMN_RANGES` (force > 0, temperature above −273.15 °C, 0 ≤ μ ≤ 10 ...);
      :data:`REQUIRED` never missing; ``mu_s`` missing only in imported rows;
    * ``repeat`` and ``interval`` whole numbers in :data:`COUNT_RANGES` or missing.
    """
    import numpy as np

    for name in RUN_COLUMNS:
        kind = _KIND[name]
        if kind == "str":
            checker = name_problem if name in NAME_COLUMNS else text_problem
            for i, value in enumerate(frame[name].tolist()):
                missing = value is None or (isinstance(value, float) and value != value)
                if missing and name not in NAME_COLUMNS:
                    continue
                problem = "missing, expected a name" if missing else checker(value)
                if problem is not None:
                    raise _row_error(frame, where, i, name, f"{name}: {problem}")
        elif kind == "float":
            values = frame[name].to_numpy(dtype=float)
            bounds = COLUMN_RANGES.get(name)
            present = ~np.isnan(values)
            if bounds is None:
                bad = present & ~np.isfinite(values)
                expected = "a finite number or missing"
            else:
                low = values > bounds.low if bounds.low_open else values >= bounds.low
                bad = present & ~(low & (values <= bounds.high))
                expected = f"a number {bounds.describe()}"
            if name in REQUIRED:
                bad |= ~present
            if bad.any():
                i = int(np.flatnonzero(bad)[0])
                raise _row_error(frame, where, i, name,
                                 f"{name} is {float(values[i])!r}, expected {expected}")
        elif kind == "int":
            low_i, high_i = COUNT_RANGES[name]
            values_i = frame[name]
            bad_i = values_i.notna() & ((values_i < low_i) | (values_i > high_i))
            if bad_i.any():
                i = int(np.flatnonzero(bad_i.to_numpy(dtype=bool))[0])
                raise _row_error(frame, where, i, name, f"{name} is {values_i.iloc[i]}, "
                                 f"expected a whole number from {low_i} to {high_i}")
    bad_s = ~np.isfinite(frame["mu_s"].to_numpy()) & (frame["source"] == SOURCE_REDUCED).to_numpy()
    if bad_s.any():
        i = int(np.flatnonzero(bad_s)[0])
        raise MapError(
            f"{where} {i + 1} ({frame['measurement_id'].iloc[i]}): mu_s is missing; only "
            "imported rows may lack mu_s",
            column="mu_s",
        )
    return frame


def content_sha256(frame: pd.DataFrame, version: int = SCHEMA_VERSION) -> str:
    """SHA-256 (hex) of a map's content: the :data:`RUN_COLUMNS` of schema ``version``
    (those :data:`ADDED_IN_VERSION` later are left out) of every row, in order, in a
    canonical byte form (floats as little-endian IEEE 754 with one NaN, whole numbers as
    int64 with a missing-mask, booleans as bytes, text as JSON with ``null``), so the same
    rows give the same digest however they were stored or read back. Stored in the map's
    Parquet metadata and checked on every read against the version the map was written
    in (:mod:`tribopipe.frictionmap.mapfile`), so a map still verifies after a schema
    upgrade adds columns.
    """
    import hashlib
    import json

    import numpy as np
    import pandas as pd

    digest = hashlib.sha256(f"tribopipe.frictionmap rows={len(frame)}".encode())
    for name in RUN_COLUMNS:
        if ADDED_IN_VERSION.get(name, 1) > version:
            continue
        kind = _KIND[name]
        column = frame[name]
        if kind == "float":
            values = column.to_numpy(dtype="float64")
            data = np.where(np.isnan(values), np.nan, values).astype("<f8").tobytes()
        elif kind == "int":
            ints = pd.array(column, dtype="Int64")
            mask = ints.isna()
            data = (np.asarray(mask, dtype="u1").tobytes()
                    + ints.fillna(0).to_numpy(dtype="int64").astype("<i8").tobytes())
        elif kind == "bool":
            data = np.asarray(column, dtype=bool).astype("u1").tobytes()
        else:
            texts = [None if _missing(v) else str(v) for v in column.tolist()]
            data = json.dumps(texts, ensure_ascii=False).encode("utf-8", "surrogatepass")
        digest.update(f"|{name}:{kind}:{len(data)}|".encode())
        digest.update(data)
    return digest.hexdigest()


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
            if _missing(v):
                out.append(np.nan)
            elif isinstance(v, bool | str):
                raise TypeError(f"not a number: {v!r}")
            else:
                out.append(float(v))
        return np.asarray(out, dtype="float64")
    if kind == "int":
        out_i: list[Any] = []
        for v in values:
            if _missing(v):
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
        if _missing(v):
            out_s.append(None)
        elif isinstance(v, str):
            out_s.append(v)
        else:
            raise TypeError(f"not text: {v!r}")
    return pd.array(out_s, dtype="str")


def frame_records(runs: pd.DataFrame) -> list[dict[str, Any]]:
    """The rows of a map DataFrame as record dicts (missing values as ``None``)."""
    out = []
    for row in runs.loc[:, list(RUN_COLUMNS)].itertuples(index=False, name=None):
        out.append({c: (None if _missing(v) else v) for c, v in zip(RUN_COLUMNS, row, strict=True)})
    return out
