"""The friction map: one Parquet row per reduced run, appended atomically and idempotently.

The map is the lab's memory. Each row is a run (:data:`RUN_COLUMNS`): its contact pair,
nominal and measured conditions, μ_S and μ_K with the evidence behind them (windows,
plateau statistics, QC flags) and its provenance (source file and hash, config hash,
tribopipe version, time of reduction). Repeat statistics live in :mod:`tribopipe.stats`.

The package's rooms, each importing only those above it:

* :mod:`~tribopipe.frictionmap.schema` — the run columns (kind, unit, meaning), the
  validated DataFrame form of the rows (:func:`check_runs`, the rules every row keeps)
  and the checksum of a map's content;
* :mod:`~tribopipe.frictionmap.records` — :func:`make_record` (a run's row, with the labels
  and flags :mod:`tribopipe.labels` decided) and the ids of a run;
* :mod:`~tribopipe.frictionmap.store` — the map file: its one reader, which trusts
  nothing in it (kind, structure, metadata, column types, rows, checksum), the metadata we
  write, locked atomic writes (the map's mode kept, the previous map kept as
  ``<map>.bak``), the pure :func:`fold_records`, append/update/merge and exclusions;
* :mod:`~tribopipe.frictionmap.duplicates` — the same raw content under two file names:
  a duplicate (same labels, stored once) or a conflict (other labels, refused);
* :mod:`~tribopipe.frictionmap.published` — the founding paper's map (``.mat`` or CSV);
* :mod:`~tribopipe.frictionmap.checks` — row checks of data from elsewhere (ranges,
  duplicates, provenance);
* :mod:`~tribopipe.frictionmap.datapackage` — the Data Package standard's JSON and reading
  a package without trusting it; :mod:`~tribopipe.frictionmap.package` — checking one;
  :mod:`~tribopipe.frictionmap.merge` — merging a map or a package into the map;
* :mod:`~tribopipe.frictionmap.summary` — the printed account (``tribopipe map show``).

The package exports the map's everyday calls (:data:`__all__`); every other name is
imported from the room that defines it.

Guarantees of the store:

* **identity** — a run's ``measurement_id`` is a hash of the raw file's content and the
  interval it came from (:func:`measurement_id`), so a renamed copy is the same run;
* **idempotence** — appending a run already in the map changes nothing; a run whose content
  differs (e.g. re-reduced with another config) replaces its row only with ``replace=True``;
* **safety** — the whole read-modify-write holds a lock (``<map>.lock``); the new map is
  written to a temporary file in the same directory, fsynced and renamed over the old one,
  so a killed writer leaves the previous map intact; a file at the map path that is not one
  of our maps is refused (:class:`~tribopipe.errors.MapError`), never overwritten;
* **integrity** — every write stores the SHA-256 of the rows in the metadata and every
  read checks it: a map changed outside tribopipe or damaged on disk is refused in one
  line naming ``<map>.bak`` to restore from, never read with other values.
"""

from __future__ import annotations

from .merge import merge_map
from .package import check_package
from .published import import_records, import_table
from .records import make_record, measurement_id
from .schema import RUN_COLUMNS, records_frame
from .store import (
    AppendReport,
    append_records,
    exclude_runs,
    include_runs,
    read_map,
    update_map,
    write_map,
)
from .summary import map_summary

__all__ = [
    "RUN_COLUMNS",
    "make_record",
    "measurement_id",
    "records_frame",
    "read_map",
    "append_records",
    "update_map",
    "write_map",
    "exclude_runs",
    "include_runs",
    "AppendReport",
    "merge_map",
    "check_package",
    "import_table",
    "import_records",
    "map_summary",
]
