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

if TYPE_CHECKING:
    import pandas as pd

#: Parquet key-value metadata key holding the schema and provenance (JSON).
META_KEY = b"tribopipe.frictionmap"
SCHEMA_NAME = "tribopipe.frictionmap"
SCHEMA_VERSION = 3

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
ADDED_IN_VERSION: dict[str, int] = {"lab": 2, "u_mu_s": 3, "u_mu_k": 3}
_KIND: dict[str, str] = {name: kind for name, kind, *_ in _SCHEMA}
#: Columns that say where a row came from, not what was measured: two rows with the same
#: id that differ only here are the same run (a renamed file, a later import).
PROVENANCE_COLUMNS: frozenset[str] = frozenset(
    {"lab", "source_file", "file_hash", "tribopipe_version", "reduced_at", "excluded",
     "exclusion_reason"}
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
    :data:`ADDED_IN_VERSION` may be left out: missing); ``measurement_id``, ``source``,
    ``pin`` and ``disc`` must be non-empty text, ``mu_k`` finite, ``mu_s`` finite unless
    the row was imported (``source`` other than ``'reduced'``). Raises :class:`MapError`
    naming the record and column otherwise; nothing is written on error.
    """
    return _validated(unvalidated_frame(records, where=where), where)


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


def _validated(frame: pd.DataFrame, where: str) -> pd.DataFrame:
    """``frame`` (schema dtypes) after the row rules of :func:`records_frame`."""
    import numpy as np

    for name in ("measurement_id", "source", "pin", "disc"):
        empty = frame[name].isna() | (frame[name].str.strip() == "")
        if empty.any():
            i = int(np.flatnonzero(empty.to_numpy())[0])
            raise MapError(f"{where} {i + 1}: empty {name}, expected text", column=name)
    bad_k = ~np.isfinite(frame["mu_k"].to_numpy())
    if bad_k.any():
        i = int(np.flatnonzero(bad_k)[0])
        raise MapError(
            f"{where} {i + 1} ({frame['measurement_id'].iloc[i]}): mu_k is "
            f"{frame['mu_k'].iloc[i]}, expected a finite number",
            column="mu_k",
        )
    bad_s = ~np.isfinite(frame["mu_s"].to_numpy()) & (frame["source"] == SOURCE_REDUCED).to_numpy()
    if bad_s.any():
        i = int(np.flatnonzero(bad_s)[0])
        raise MapError(
            f"{where} {i + 1} ({frame['measurement_id'].iloc[i]}): mu_s is missing; only "
            "imported rows may lack mu_s",
            column="mu_s",
        )
    return frame


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
