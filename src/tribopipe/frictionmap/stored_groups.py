"""A map folder's condition groups, stored beside its parts and kept up to date by writes.

The statistics are computed in one place, :mod:`tribopipe.stats`, in two steps:
:func:`~tribopipe.stats.group_rows` gives each condition group's own figures from its own
runs, :func:`~tribopipe.stats.finish_groups` what needs every group (the map's pooled r,
the labs' critical difference, the order, the columns shown). A map folder keeps the
first step's output for every condition as one Parquet file in ``_groups/``, named with
its SHA-256 in the manifest (:class:`~tribopipe.frictionmap.parts.GroupsFile`). A write
recomputes the rows of the conditions it touched only, from those conditions' runs,
and commits the new file with its parts, in the same manifest: the stored copy is a cache
of the one computation, never a second one. A reader finishes the stored rows
(:meth:`~tribopipe.frictionmap.snapshot.MapSnapshot.groups`) instead of grouping every run.

This module knows the file (its bytes, its version) and which rows a change touches;
the lock, the commit and the reading of parts are the store's.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

from ..errors import MapError
from ..stats import (
    CONDITION_KEY,
    FORCE_DECIMALS,
    GROUP_ROWS_VERSION,
    TEMPERATURE_DECIMALS,
    condition_keys,
    finish_groups,
    group_rows,
    group_statistics,
    shown_columns,
)

if TYPE_CHECKING:
    import pandas as pd

#: the Parquet metadata key of a stored groups file
META_KEY = b"tribopipe.groups"
#: the private columns that hold tuples (each lab's (mean, n)), stored as JSON text
_TUPLE_COLUMNS: tuple[str, ...] = ("_mu_k_lab_means", "_mu_s_lab_means")

#: a condition key as a tuple (:data:`~tribopipe.stats.CONDITION_KEY`, unknown as ``None``)
Key = tuple[Any, ...]


def keys_of(runs: pd.DataFrame) -> set[Key]:
    """The condition keys of ``runs`` (map rows with :data:`~tribopipe.stats.GROUP_INPUT_COLUMNS`,
    excluded ones too: a run excluded now leaves the group it was in)."""
    return set(condition_keys(runs).values())


def _row_key(values: Iterable[Any]) -> Key:
    return tuple(None if isinstance(v, float) and math.isnan(v) else v for v in values)


def rows_keys(rows: pd.DataFrame) -> list[Key]:
    """The condition key of each stored group row."""
    if rows.empty:
        return []
    return [_row_key(v) for v in rows.loc[:, list(CONDITION_KEY)].itertuples(
        index=False, name=None)]


def of_keys(runs: pd.DataFrame, keys: set[Key]) -> pd.DataFrame:
    """The rows of ``runs`` whose condition key is one of ``keys`` (the pair, the force
    and the temperature, rounded as the key rounds them, filtered first on whole
    columns; the key of each row left computed after)."""
    if runs.empty or not keys:
        return runs.iloc[:0]
    pins = sorted({k[0] for k in keys if k[0] is not None})
    discs = sorted({k[1] for k in keys if k[1] is not None})
    close = runs["pin"].isin(pins) & runs["disc"].isin(discs)
    for at, column, decimals in ((2, "normal_force_N", FORCE_DECIMALS),
                                 (3, "temperature_C", TEMPERATURE_DECIMALS)):
        if all(k[at] is not None for k in keys):  # an unknown value: not filtered on
            close &= runs[column].round(decimals).isin({k[at] for k in keys})
    near = runs.loc[close]
    if near.empty:
        return near
    found = condition_keys(near)
    wanted = [found[str(m)] in keys for m in near["measurement_id"].astype(str)]
    return near.loc[wanted]


def updated(old: pd.DataFrame, touched: set[Key], runs: pd.DataFrame) -> pd.DataFrame:
    """The stored group rows after a change: ``old`` without the rows of the ``touched``
    conditions, and those conditions' rows computed again from ``runs`` (every run of the
    map, after the change, of those conditions: :func:`of_keys`)."""
    import pandas as pd

    fresh = group_rows(runs) if len(runs) else pd.DataFrame()
    if old.empty:
        return fresh.reset_index(drop=True)
    keep = [k not in touched for k in rows_keys(old)]
    left = old.loc[keep]
    if fresh.empty:
        return left.reset_index(drop=True)
    if left.empty:
        return fresh.reset_index(drop=True)
    return pd.concat([left, fresh.loc[:, list(left.columns)]], ignore_index=True)


def groups_bytes(rows: pd.DataFrame) -> bytes:
    """The stored group rows as one Parquet file, in memory (the tuples as JSON text, the
    version of :func:`~tribopipe.stats.group_rows` in the metadata)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    frame = rows.copy()
    for column in _TUPLE_COLUMNS:
        if column in frame.columns:
            frame[column] = [json.dumps([list(t) for t in v]) for v in frame[column]]
    table = pa.Table.from_pandas(frame, preserve_index=False)
    meta = dict(table.schema.metadata or {})
    meta[META_KEY] = json.dumps({"group_rows_version": GROUP_ROWS_VERSION}).encode()
    sink = pa.BufferOutputStream()
    pq.write_table(table.replace_schema_metadata(meta), sink)
    return bytes(sink.getvalue())


def rows_from_bytes(data: bytes, where: str) -> pd.DataFrame | None:
    """The stored group rows of a file's bytes (checked against the manifest already);
    ``None`` when they were written by another version of the statistics (then the
    groups are computed from the runs). Raises :class:`MapError` for a file that is
    not one."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    try:
        table = pq.ParquetFile(pa.BufferReader(data)).read(use_threads=False)
        info = json.loads((table.schema.metadata or {}).get(META_KEY, b"null"))
    except Exception as exc:  # noqa: BLE001 - pyarrow raises many types
        raise MapError(f"{where}: not a stored groups file ({type(exc).__name__})") from None
    if not isinstance(info, dict) or info.get("group_rows_version") != GROUP_ROWS_VERSION:
        return None
    frame = table.replace_schema_metadata(None).to_pandas(ignore_metadata=True,
                                                          use_threads=False)
    for column in _TUPLE_COLUMNS:
        if column in frame.columns:
            frame[column] = [tuple((float(m), int(n)) for m, n in json.loads(v))
                             for v in frame[column]]
    return frame


def groups_differ(rows: pd.DataFrame, runs: pd.DataFrame) -> str | None:
    """Where the stored group ``rows``, finished, differ from the groups of the map's
    ``runs`` (``map validate``'s check that the stored copy did not drift); ``None``
    when they agree (numbers to 1e-9 relative)."""
    import numpy as np

    speed, method = shown_columns(rows)
    stored = finish_groups(rows, show_speed=speed, show_method=method)
    computed = group_statistics(runs)
    if list(stored.columns) != list(computed.columns) or len(stored) != len(computed):
        return f"{len(stored)} stored groups, {len(computed)} from the rows"
    for column in computed.columns:
        a, b = stored[column], computed[column]
        if a.dtype.kind == "f" or b.dtype.kind == "f":
            x, y = a.to_numpy(dtype=float), b.to_numpy(dtype=float)
            same = np.isclose(x, y, rtol=1e-9, atol=0.0, equal_nan=True)
        else:
            same = (a.astype(str).to_numpy() == b.astype(str).to_numpy())
        if not same.all():
            at = int(np.flatnonzero(~same)[0])
            return f"column {column}, group {at + 1}"
    return None
