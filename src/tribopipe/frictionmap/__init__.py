"""The friction map: one Parquet row per reduced run, appended atomically and idempotently.

The map is the lab's memory. Each row is a run (:data:`RUN_COLUMNS`): its contact pair,
nominal and measured conditions, μ_S and μ_K with the evidence behind them (windows,
plateau statistics, QC flags) and its provenance (source file and hash, config hash,
tribopipe version, time of reduction). Repeat statistics live in :mod:`tribopipe.stats`.

The package's rooms, each importing only those above it:

* :mod:`~tribopipe.frictionmap.schema` — the run columns (kind, unit, meaning), the
  validated DataFrame form of the rows (:func:`check_runs`, the rules every row keeps)
  and the checksum of a map's content;
* :mod:`~tribopipe.frictionmap.records` — :class:`RunLabels`, :class:`Tolerances`,
  :func:`make_record`, the ids and the off-nominal QC flags of a run;
* :mod:`~tribopipe.frictionmap.mapfile` — reading a map file without trusting it (kind,
  structure, metadata, column types, rows, checksum) and the metadata we write;
* :mod:`~tribopipe.frictionmap.store` — locked atomic writes (the map's mode kept, the
  previous map kept as ``<map>.bak``), the pure :func:`fold_records`, append/update/merge
  and exclusions;
* :mod:`~tribopipe.frictionmap.duplicates` — the same raw content under two file names:
  a duplicate (same labels, stored once) or a conflict (other labels, refused);
* :mod:`~tribopipe.frictionmap.published` — the founding paper's map (``.mat`` or CSV);
* :mod:`~tribopipe.frictionmap.checks` — row checks of data from elsewhere (ranges,
  duplicates, provenance);
* :mod:`~tribopipe.frictionmap.datapackage` — the Data Package standard's JSON and reading
  a package without trusting it; :mod:`~tribopipe.frictionmap.package` — checking one;
  :mod:`~tribopipe.frictionmap.merge` — merging a map or a package into the map;
* :mod:`~tribopipe.frictionmap.summary` — the printed account (``tribopipe map show``).

Every public name is importable from ``tribopipe.frictionmap`` itself.

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

from .checks import RowProblem, validate_runs
from .datapackage import DESCRIPTOR, PackageLimits, PackageRefused, Problem
from .duplicates import (
    LABEL_COLUMNS,
    SameContent,
    compare_labels,
    labels_of,
    map_files_by_hash,
    same_label,
)
from .merge import MergeReport, is_package, merge_map
from .package import PackageCheck, PackageInvalid, check_package, package_runs
from .published import (
    FOUNDING_PAPER,
    FRICTIONMAP_COLUMNS,
    PUBLISHED_LAB,
    PUBLISHED_SLIDING_SPEED_MM_S,
    import_records,
    import_table,
    published_csv_path,
    read_frictionmap_table,
)
from .records import (
    FLAG_FORCE_ESTIMATED,
    FLAG_FORCE_OFF,
    FLAG_TEMPERATURE_OFF,
    RunLabels,
    Tolerances,
    imported_id,
    make_record,
    measurement_id,
    nominal_pressure_kPa,
    qc_flags,
)
from .schema import (
    ADDED_IN_VERSION,
    META_KEY,
    PROVENANCE_COLUMNS,
    RUN_COLUMNS,
    SCHEMA_NAME,
    SCHEMA_VERSION,
    SOURCE_PUBLISHED,
    SOURCE_REDUCED,
    check_runs,
    content_sha256,
    empty_map,
    frame_records,
    records_frame,
)
from .store import (
    LOCK_TIMEOUT_S,
    PAUSE_ENV,
    AppendReport,
    append_records,
    backup_path,
    exclude_runs,
    fold_records,
    include_runs,
    map_metadata,
    merge_map_file,
    read_map,
    set_excluded,
    update_map,
    write_map,
    write_map_copy,
)
from .summary import (
    map_summary,
)

__all__ = [
    "ADDED_IN_VERSION",
    "META_KEY",
    "SCHEMA_NAME",
    "SCHEMA_VERSION",
    "ADDED_IN_VERSION",
    "SOURCE_REDUCED",
    "SOURCE_PUBLISHED",
    "RUN_COLUMNS",
    "PROVENANCE_COLUMNS",
    "empty_map",
    "records_frame",
    "check_runs",
    "content_sha256",
    "frame_records",
    "FLAG_FORCE_ESTIMATED",
    "FLAG_FORCE_OFF",
    "FLAG_TEMPERATURE_OFF",
    "RunLabels",
    "Tolerances",
    "qc_flags",
    "nominal_pressure_kPa",
    "measurement_id",
    "imported_id",
    "make_record",
    "LOCK_TIMEOUT_S",
    "PAUSE_ENV",
    "read_map",
    "map_metadata",
    "write_map",
    "write_map_copy",
    "AppendReport",
    "fold_records",
    "append_records",
    "backup_path",
    "update_map",
    "MergeReport",
    "merge_map",
    "merge_map_file",
    "is_package",
    "RowProblem",
    "validate_runs",
    "DESCRIPTOR",
    "PackageLimits",
    "PackageRefused",
    "Problem",
    "PackageCheck",
    "PackageInvalid",
    "check_package",
    "package_runs",
    "set_excluded",
    "exclude_runs",
    "include_runs",
    "PUBLISHED_SLIDING_SPEED_MM_S",
    "FRICTIONMAP_COLUMNS",
    "FOUNDING_PAPER",
    "PUBLISHED_LAB",
    "read_frictionmap_table",
    "published_csv_path",
    "import_records",
    "import_table",
    "map_summary",
    "LABEL_COLUMNS",
    "SameContent",
    "compare_labels",
    "labels_of",
    "map_files_by_hash",
    "same_label",
]
