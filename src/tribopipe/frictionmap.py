"""The friction map: one Parquet row per reduced run, appended atomically and idempotently.

The map is the lab's memory. Each row is a run (:data:`RUN_COLUMNS`): its contact pair,
nominal and measured conditions, μ_S and μ_K with the evidence behind them (windows,
plateau statistics, QC flags) and its provenance (source file and hash, config hash,
tribopipe version, time of reduction). Repeat statistics live in :mod:`tribopipe.stats`.

Guarantees of the store:

* **identity** — a run's ``measurement_id`` is a hash of the raw file's content and the
  interval it came from (:func:`measurement_id`), so a renamed copy is the same run;
* **idempotence** — appending a run already in the map changes nothing; a run whose content
  differs (e.g. re-reduced with another config) replaces its row only with ``replace=True``;
* **safety** — the whole read-modify-write holds a lock (``<map>.lock``); the new map is
  written to a temporary file in the same directory, fsynced and renamed over the old one,
  so a killed writer leaves the previous map intact; a file at the map path that is not one
  of our maps is refused (:class:`~tribopipe.errors.MapError`), never overwritten.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from collections.abc import Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager, suppress
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .errors import MapError
from .files import file_sha256
from .numeric import finite_or_nan
from .physics import FOUNDING_SLIDING_SPEED_MM_S, contact_pressure_kPa

if TYPE_CHECKING:
    import pandas as pd

    from .config import InstrumentConfig, Settings
    from .measurement import MeasurementMeta
    from .pipeline import RunLabels
    from .reduce import ReductionResult

#: Parquet key-value metadata key holding the schema and provenance (JSON).
META_KEY = b"tribopipe.frictionmap"
SCHEMA_NAME = "tribopipe.frictionmap"
SCHEMA_VERSION = 1

#: ``source`` of runs reduced by tribopipe (imported rows name their origin instead).
SOURCE_REDUCED = "reduced"
#: ``source`` of the founding paper's published map.
SOURCE_PUBLISHED = "published:Berthold2023"
#: The founding paper's fixed sliding speed [mm/s] (recorded for published rows).
PUBLISHED_SLIDING_SPEED_MM_S = FOUNDING_SLIDING_SPEED_MM_S
#: The published map's 7-column schema (RebeccaBerthold/FrictionMap).
FRICTIONMAP_COLUMNS: tuple[str, ...] = (
    "pin",
    "disc",
    "contactForce",
    "contactPressure",
    "temperature",
    "measurementNo",
    "cof",
)

#: Flag added when the nominal force was not given and the measured mean was used.
FLAG_FORCE_ESTIMATED = "nominal_force_estimated"
#: Flags added by :func:`make_record` when a run strays from its nominal conditions.
FLAG_FORCE_OFF = "normal_force_off_nominal"
FLAG_TEMPERATURE_OFF = "temperature_off_nominal"

#: Seconds to wait for another process's lock on the map before giving up.
LOCK_TIMEOUT_S = 60.0
#: Test-only hook: when set to a path, the writer creates that file after the temporary map
#: is written and fsynced, then sleeps, so a test can kill it just before the rename.
PAUSE_ENV = "TRIBOPIPE_TEST_PAUSE_BEFORE_RENAME"

# (name, kind, unit or "", meaning); kinds: str, float, int (nullable), bool.
_SCHEMA: tuple[tuple[str, str, str, str], ...] = (
    ("measurement_id", "str", "", "hash of the raw file content + interval (or import origin)"),
    ("source", "str", "", "'reduced' or the origin of an imported row"),
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
_KIND: dict[str, str] = {name: kind for name, kind, *_ in _SCHEMA}
#: Columns that say where a row came from, not what was measured: two rows with the same
#: id that differ only here are the same run (a renamed file, a later import).
PROVENANCE_COLUMNS: frozenset[str] = frozenset(
    {"source_file", "file_hash", "tribopipe_version", "reduced_at", "excluded", "exclusion_reason"}
)
_CONTENT_COLUMNS: tuple[str, ...] = tuple(c for c in RUN_COLUMNS if c not in PROVENANCE_COLUMNS)


# --------------------------------------------------------------------------- records


@dataclass(frozen=True)
class Tolerances:
    """How far a run's measured conditions may stray from nominal before it is flagged.

    The normal force limit is ``max(force_N, force_rel · F_nominal)`` [N]; the temperature
    limit is ``temperature_C`` [K, as a difference in °C]. Defaults: 10 % of the nominal
    force, 2 K (a campaign config may state its own).
    """

    force_N: float = 0.0
    force_rel: float = 0.10
    temperature_C: float = 2.0

    def force_limit_N(self, nominal_N: float) -> float:
        """Allowed |F_measured − F_nominal| [N] at a nominal total force [N]."""
        return max(self.force_N, self.force_rel * abs(nominal_N))


def qc_flags(labels: RunLabels, normal_force_measured_N: float | None,
             temperature_measured_C: float | None, tolerances: Tolerances) -> list[str]:
    """The off-nominal QC flags of a run: ``normal_force_off_nominal`` when the measured
    mean normal force [N] strays more than the tolerance from nominal,
    ``temperature_off_nominal`` likewise for the temperature [°C]. Unknown nominal or
    measured values (``None`` or NaN) raise no flag."""
    flags: list[str] = []
    if labels.normal_force_N is not None and normal_force_measured_N is not None and \
            math.isfinite(normal_force_measured_N):
        if abs(normal_force_measured_N - labels.normal_force_N) > \
                tolerances.force_limit_N(labels.normal_force_N):
            flags.append(FLAG_FORCE_OFF)
    if labels.temperature_C is not None and temperature_measured_C is not None and \
            math.isfinite(temperature_measured_C):
        if abs(temperature_measured_C - labels.temperature_C) > tolerances.temperature_C:
            flags.append(FLAG_TEMPERATURE_OFF)
    return flags


def nominal_pressure_kPa(force_N: float, instrument: InstrumentConfig) -> float:
    """Nominal contact pressure per pin [kPa] for a total normal force [N].

    p = (F / n_pins) / (π r²); with F in N and r in mm, N/mm² = MPa, hence × 1000 → kPa.
    The founding cell (3 pins, r = 3 mm) gives 1 N → 11.79 kPa.
    """
    return float(contact_pressure_kPa(force_N, instrument.n_pins, instrument.pin_radius_mm))


def measurement_id(file_hash: str, meta: MeasurementMeta) -> str:
    """Stable id of a run: 16 hex digits of SHA-256 over the raw file's content hash and
    the test / result / interval the run was taken from."""
    key = "|".join(
        ["run", file_hash, meta.test or "", meta.result or "", str(meta.interval)]
    )
    return hashlib.sha256(key.encode()).hexdigest()[:16]


def imported_id(source: str, pin: str, disc: str, force_N: float, temperature_C: float,
                repeat: int | None) -> str:
    """Stable id of an imported row: 16 hex digits of SHA-256 over its origin and
    conditions, so importing the same table twice (or as .mat and as CSV) is idempotent."""
    key = "|".join(
        ["import", source, pin, disc, _num_key(force_N), _num_key(temperature_C), str(repeat)]
    )
    return hashlib.sha256(key.encode()).hexdigest()[:16]


def _num_key(value: float) -> str:
    # 1.0 and 1.0000000001 are the same nominal condition; NaN (unknown) keeps its own key.
    return "nan" if value is None or not math.isfinite(value) else format(round(value, 6), ".6f")


def _join_flags(flags: Iterable[str]) -> str:
    # Sorted and unique so the same run always gets the same string.
    return ";".join(sorted({f for f in flags if f}))


def _now() -> str:
    return datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ")


def make_record(
    *,
    result: ReductionResult,
    labels: RunLabels,
    meta: MeasurementMeta,
    file_hash: str,
    settings: Settings,
    tolerances: Tolerances | None = None,
) -> dict[str, Any]:
    """One friction-map row (a dict keyed by :data:`RUN_COLUMNS`) for a reduced run.

    The nominal force comes from ``labels``; when absent, the measured mean rounded to
    0.1 N is used and the run is flagged ``nominal_force_estimated``. The nominal pressure
    [kPa] follows from the nominal force and ``settings.instrument``. Runs whose measured
    force or temperature stray from nominal by more than ``tolerances`` (default
    :class:`Tolerances`: 10 %, 2 K) are flagged (:func:`qc_flags`).

    Raises :class:`MapError` when pin or disc is unknown or μ_K is not a finite number.
    """
    from . import __version__

    if not labels.complete:
        raise MapError(
            "run has no pin and/or disc material: it cannot be recorded in the friction map",
            path=meta.source_file,
            hint="pass --pin and --disc (or --no-map)",
        )
    mu_k = finite_or_nan(result.mu_k)
    if math.isnan(mu_k):
        raise MapError(
            f"mu_k is {result.mu_k!r}, expected a finite number: the run cannot be recorded",
            path=meta.source_file,
        )
    flags = list(result.flags)
    measured_force = finite_or_nan(result.normal_force_mean_N)
    measured_temperature = finite_or_nan(result.temperature_C)
    flags += qc_flags(labels, measured_force, measured_temperature, tolerances or Tolerances())
    if labels.normal_force_N is not None:
        force = float(labels.normal_force_N)
    elif math.isfinite(measured_force):
        force = round(measured_force, 1)
        flags.append(FLAG_FORCE_ESTIMATED)
    else:
        raise MapError(
            "run has neither a nominal nor a measured normal force",
            path=meta.source_file,
            hint="pass --force",
        )
    temperature = finite_or_nan(labels.temperature_C)
    k_start_mm, k_end_mm = result.mu_k_window_mm
    k_start_s, k_end_s = result.mu_k_window_s
    return {
        "measurement_id": measurement_id(file_hash, meta),
        "source": SOURCE_REDUCED,
        "pin": labels.pin,
        "disc": labels.disc,
        "normal_force_N": force,
        "pressure_kPa": nominal_pressure_kPa(force, settings.instrument),
        "normal_force_measured_N": measured_force,
        "pressure_measured_kPa": finite_or_nan(result.pressure_kPa),
        "temperature_C": temperature,
        "temperature_measured_C": measured_temperature,
        "sliding_speed_mm_s": finite_or_nan(result.sliding_speed_mm_s),
        "repeat": labels.repeat,
        "mu_s": finite_or_nan(result.mu_s),
        "mu_k": mu_k,
        "mu_s_distance_mm": finite_or_nan(result.mu_s_distance_mm),
        "mu_s_time_s": finite_or_nan(result.mu_s_time_s),
        "mu_k_window_start_mm": finite_or_nan(k_start_mm),
        "mu_k_window_end_mm": finite_or_nan(k_end_mm),
        "mu_k_window_start_s": finite_or_nan(k_start_s),
        "mu_k_window_end_s": finite_or_nan(k_end_s),
        "plateau_std": finite_or_nan(result.plateau_std),
        "plateau_drift_per_mm": finite_or_nan(result.plateau_drift_per_mm),
        "flags": _join_flags(flags),
        "method": result.method,
        "source_file": Path(meta.source_file).name,
        "file_hash": file_hash,
        "interval": meta.interval,
        "config_hash": settings.config_hash,
        "tribopipe_version": __version__,
        "reduced_at": _now(),
        "excluded": False,
        "exclusion_reason": None,
    }


# --------------------------------------------------------------------------- frames


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

    Every record needs every column of :data:`RUN_COLUMNS`; ``measurement_id``, ``source``,
    ``pin`` and ``disc`` must be non-empty text, ``mu_k`` finite, ``mu_s`` finite unless
    the row was imported (``source`` other than ``'reduced'``). Raises :class:`MapError`
    naming the record and column otherwise; nothing is written on error.
    """
    import pandas as pd

    columns: dict[str, Any] = {}
    for i, rec in enumerate(records):
        absent = [c for c in RUN_COLUMNS if c not in rec]
        if absent:
            raise MapError(
                f"{where} {i + 1} lacks column(s) {', '.join(absent)}",
                hint="build records with tribopipe.frictionmap.make_record",
            )
    for name in RUN_COLUMNS:
        kind = _KIND[name]
        values = [rec[name] for rec in records]
        try:
            columns[name] = _column(values, kind)
        except (TypeError, ValueError, OverflowError) as exc:
            bad = next((i for i, v in enumerate(values) if not _ok(v, kind)), None)
            row = "" if bad is None else f"{where} {bad + 1}: "
            raise MapError(
                f"{row}expected {kind} values, got {values[bad] if bad is not None else exc!r}",
                column=name,
            ) from None
    frame = pd.DataFrame(columns, columns=list(RUN_COLUMNS), index=pd.RangeIndex(len(records)))
    return _validated(frame, where)


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


# --------------------------------------------------------------------------- reading


def read_map(path: str | os.PathLike[str]) -> pd.DataFrame:
    """Read and validate a friction map; an absent file is an empty map.

    Raises :class:`MapError` naming the path when the file is not Parquet, is a Parquet
    file without tribopipe's schema metadata (a foreign file), was written by a newer
    schema, or lacks columns.
    """
    import pyarrow as pa
    import pyarrow.parquet as pq

    p = Path(path)
    if not p.exists():
        return empty_map()
    if p.is_dir():
        raise MapError("is a directory, expected a friction-map Parquet file", path=p)
    try:
        table = pq.read_table(p)
    except (pa.ArrowException, OSError) as exc:
        raise MapError(
            f"not a readable Parquet file ({str(exc).splitlines()[0] if str(exc) else exc!r})",
            path=p,
            hint="this path holds something else; pass another --map (it is never overwritten)",
        ) from None
    _check_metadata(table.schema.metadata or {}, p)
    absent = [c for c in RUN_COLUMNS if c not in table.column_names]
    if absent:
        raise MapError(
            f"friction map lacks column(s) {', '.join(absent)}", path=p, column=absent[0]
        )
    try:
        runs = _from_arrow(table.select(list(RUN_COLUMNS)))
    except MapError as exc:
        raise MapError(exc.problem, path=p, column=exc.column) from None
    if runs["measurement_id"].duplicated().any():
        dup = runs.loc[runs["measurement_id"].duplicated(), "measurement_id"].iloc[0]
        raise MapError(f"duplicate measurement_id {dup}", path=p, column="measurement_id")
    return runs


def map_metadata(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The schema and provenance a map carries in its Parquet metadata: ``schema``,
    ``schema_version``, ``columns`` (name, kind, unit, meaning), ``tribopipe_version`` and
    ``written_at`` of the last write, ``n_runs``, ``sources``. Validated like
    :func:`read_map`."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    p = Path(path)
    try:
        schema = pq.read_schema(p)
    except (pa.ArrowException, OSError) as exc:
        raise MapError(f"not a readable Parquet file ({exc})", path=p) from None
    return _check_metadata(schema.metadata or {}, p)


def _from_arrow(table: Any) -> pd.DataFrame:
    """The map DataFrame of an Arrow table of the run columns, coerced column by column
    (vectorised: the read path of every command) and validated."""
    import pandas as pd
    import pyarrow as pa

    frame = table.to_pandas()
    columns: dict[str, Any] = {}
    for name in RUN_COLUMNS:
        kind = _KIND[name]
        col = frame[name]
        try:
            if kind == "float":
                columns[name] = pd.to_numeric(col, errors="raise").astype("float64").to_numpy()
            elif kind == "int":
                columns[name] = pd.array(col, dtype="Int64")
            elif kind == "bool":
                if col.isna().any():
                    raise ValueError("missing true/false")
                columns[name] = col.astype(bool).to_numpy()
            else:
                arrow_type = table.schema.field(name).type
                if not (
                    pa.types.is_string(arrow_type)
                    or pa.types.is_large_string(arrow_type)
                    or pa.types.is_null(arrow_type)
                ):
                    raise ValueError(f"stored as {arrow_type}, not text")
                columns[name] = pd.array(col.astype(object).where(col.notna(), None), dtype="str")
        except (TypeError, ValueError) as exc:
            raise MapError(f"expected {kind} values ({exc})", column=name) from None
    runs = pd.DataFrame(columns, columns=list(RUN_COLUMNS), index=pd.RangeIndex(len(frame)))
    return _validated(runs, "row")


def _check_metadata(metadata: Mapping[bytes, bytes], path: Path) -> dict[str, Any]:
    raw = metadata.get(META_KEY)
    if raw is None:
        raise MapError(
            "a Parquet file, but not a tribopipe friction map (no 'tribopipe.frictionmap' "
            "schema metadata); refusing to read or overwrite it",
            path=path,
            hint="pass another --map",
        )
    try:
        info = json.loads(raw)
    except (ValueError, UnicodeDecodeError):
        raise MapError("friction-map metadata is not valid JSON", path=path) from None
    if not isinstance(info, dict) or info.get("schema") != SCHEMA_NAME:
        raise MapError("friction-map metadata names another schema", path=path)
    version = info.get("schema_version")
    if not isinstance(version, int) or version > SCHEMA_VERSION:
        raise MapError(
            f"friction-map schema version {version!r}; this tribopipe reads up to "
            f"{SCHEMA_VERSION}",
            path=path,
            hint="upgrade tribopipe",
        )
    return info


# --------------------------------------------------------------------------- writing


def _metadata(runs: pd.DataFrame) -> bytes:
    from . import __version__

    info = {
        "schema": SCHEMA_NAME,
        "schema_version": SCHEMA_VERSION,
        "columns": [
            {"name": name, "kind": kind, "unit": unit, "meaning": meaning}
            for name, kind, unit, meaning in _SCHEMA
        ],
        "tribopipe_version": __version__,
        "written_at": _now(),
        "n_runs": len(runs),
        "sources": sorted(set(runs["source"].dropna())),
    }
    return json.dumps(info, ensure_ascii=False).encode()


@contextmanager
def _locked(path: Path) -> Iterator[None]:
    from filelock import FileLock, Timeout

    lock = FileLock(str(path) + ".lock", timeout=LOCK_TIMEOUT_S)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        lock.acquire()
    except Timeout:
        raise MapError(
            f"friction map is locked by another process for more than {LOCK_TIMEOUT_S:g} s",
            path=path,
            hint="wait for the other tribopipe command to finish",
        ) from None
    except OSError as exc:
        raise MapError(f"cannot lock the friction map ({exc.strerror or exc})", path=path,
                       hint="is the directory writable?") from None
    try:
        yield
    finally:
        lock.release()


def _clean_stale_temps(path: Path) -> None:
    # Under the lock, any temporary map beside ours belongs to a writer that died.
    for stale in path.parent.glob(f".{path.name}.*.tmp"):
        with suppress(OSError):
            stale.unlink()


def _fsync_dir(directory: Path) -> None:
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:  # some platforms cannot open directories; the rename is still atomic
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _write_atomic(path: Path, runs: pd.DataFrame) -> None:
    """Write ``runs`` to ``path`` via a fsynced temporary file and an atomic rename.

    The caller holds the lock.
    """
    import tempfile
    import time

    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.Table.from_pandas(runs.loc[:, list(RUN_COLUMNS)], preserve_index=False)
    meta = dict(table.schema.metadata or {})
    meta[META_KEY] = _metadata(runs)
    table = table.replace_schema_metadata(meta)
    _clean_stale_temps(path)
    try:
        fd, tmp_name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    except OSError as exc:
        raise MapError(f"cannot write the friction map ({exc.strerror or exc})",
                       path=path) from None
    tmp = Path(tmp_name)
    try:
        with os.fdopen(fd, "wb") as fh:
            pq.write_table(table, fh)
            fh.flush()
            os.fsync(fh.fileno())
        marker = os.environ.get(PAUSE_ENV)
        if marker:
            Path(marker).write_text(str(os.getpid()))
            time.sleep(120)
        os.replace(tmp, path)
    except BaseException as exc:
        with suppress(OSError):
            tmp.unlink()
        if isinstance(exc, OSError):  # disk full, permissions: the old map is untouched
            raise MapError(f"cannot write the friction map ({exc.strerror or exc})",
                           path=path) from None
        raise
    _fsync_dir(path.parent)


def write_map(path: str | os.PathLike[str], runs: pd.DataFrame) -> None:
    """Replace the map at ``path`` with ``runs`` (validated), atomically and under the lock.

    Refuses (``MapError``) to overwrite a file that is not a friction map.
    """
    p = Path(path)
    frame = records_frame(frame_records(runs), where="row")
    with _locked(p):
        read_map(p)  # refuse foreign or corrupt files before replacing them
        _write_atomic(p, frame)


# --------------------------------------------------------------------------- appending


@dataclass(frozen=True)
class AppendReport:
    """What an append or merge did, by measurement id.

    ``added``: new runs; ``unchanged``: already in the map with the same content;
    ``replaced``: content differed and ``replace=True``; ``kept_conflicting``: content
    differed and the map's row was kept. ``differences`` maps each conflicting or replaced
    id to the names of the columns that differ. ``dropped_ids``: rows removed by
    :func:`update_map`.
    """

    added_ids: tuple[str, ...] = ()
    unchanged_ids: tuple[str, ...] = ()
    replaced_ids: tuple[str, ...] = ()
    conflicting_ids: tuple[str, ...] = ()
    differences: dict[str, tuple[str, ...]] = field(default_factory=dict)
    dropped_ids: tuple[str, ...] = ()

    @property
    def added(self) -> int:
        """Number of runs added."""
        return len(self.added_ids)

    @property
    def unchanged(self) -> int:
        """Number of runs already present with identical content."""
        return len(self.unchanged_ids)

    @property
    def replaced(self) -> int:
        """Number of rows replaced (``replace=True``)."""
        return len(self.replaced_ids)

    @property
    def kept_conflicting(self) -> int:
        """Number of runs whose content differs from the map's row, which was kept."""
        return len(self.conflicting_ids)

    @property
    def changed(self) -> bool:
        """True when the map file was rewritten."""
        return bool(self.added_ids or self.replaced_ids or self.dropped_ids)

    def summary(self) -> str:
        """One line: ``3 added, 1 unchanged, 0 replaced, 1 kept (conflicting: ...)``."""
        text = (
            f"{self.added} added, {self.unchanged} unchanged, {self.replaced} replaced, "
            f"{self.kept_conflicting} kept conflicting"
        )
        if self.dropped_ids:
            text += f", {len(self.dropped_ids)} dropped"
        if self.conflicting_ids:
            details = "; ".join(
                f"{i} differs in {', '.join(self.differences.get(i, ()))}"
                for i in self.conflicting_ids[:5]
            )
            more = " …" if len(self.conflicting_ids) > 5 else ""
            text += f" ({details}{more}; pass --replace to overwrite)"
        return text


def _same(a: Any, b: Any) -> bool:
    if _missing(a) and _missing(b):
        return True
    if _missing(a) or _missing(b):
        return False
    if isinstance(a, float) or isinstance(b, float):
        # Platform noise in a re-reduction is not a different result.
        return math.isclose(float(a), float(b), rel_tol=1e-9, abs_tol=1e-12)
    return a == b


def _differences(old: Mapping[str, Any], new: Mapping[str, Any]) -> tuple[str, ...]:
    return tuple(c for c in _CONTENT_COLUMNS if not _same(old[c], new[c]))


def fold_records(
    runs: pd.DataFrame, records: Sequence[Mapping[str, Any]], *, replace: bool = False
) -> tuple[pd.DataFrame, AppendReport]:
    """Pure core of :func:`append_records`: the map with ``records`` folded in, and the report.

    Existing rows keep their position; new runs are added at the end in the given order.
    A replaced row keeps the map's exclusion state (a human decision about the run).
    Neither input is modified.
    """
    return _fold(runs, records_frame(records), replace=replace)


def _fold(
    runs: pd.DataFrame, new_frame: pd.DataFrame, *, replace: bool
) -> tuple[pd.DataFrame, AppendReport]:
    """:func:`fold_records` of records already validated into ``new_frame``."""
    import pandas as pd

    base = runs.loc[:, list(RUN_COLUMNS)].reset_index(drop=True)
    position = {m: i for i, m in enumerate(base["measurement_id"])}
    # map rows looked at (then replaced), by position: converted in one pass, not per record
    hits = sorted({position[m] for m in new_frame["measurement_id"] if m in position})
    touched = dict(zip(hits, frame_records(base.iloc[hits]), strict=True))
    fresh: dict[str, dict[str, Any]] = {}  # runs new to the map, in order (= the added ids)
    # ids in first-seen order (dicts as ordered sets: a repeated id keeps its place)
    unchanged: dict[str, None] = {}
    replaced: dict[str, None] = {}
    conflicting: dict[str, None] = {}
    differences: dict[str, tuple[str, ...]] = {}
    for rec in frame_records(new_frame):
        mid = rec["measurement_id"]
        if mid in fresh:
            old = fresh[mid]
        elif mid in position:
            old = touched[position[mid]]
        else:
            fresh[mid] = rec
            continue
        diff = _differences(old, rec)
        if not diff:
            if mid not in fresh:
                unchanged[mid] = None
            continue
        differences[mid] = diff
        if replace:
            rec = {**rec, "excluded": old["excluded"], "exclusion_reason": old["exclusion_reason"]}
            if mid in fresh:
                fresh[mid] = rec
            else:
                touched[position[mid]] = rec
                replaced[mid] = None
        else:
            conflicting[mid] = None
    report = AppendReport(
        added_ids=tuple(fresh),
        unchanged_ids=tuple(unchanged),
        replaced_ids=tuple(replaced),
        conflicting_ids=tuple(conflicting),
        differences=differences,
    )
    merged = base
    if replaced:
        where = [position[mid] for mid in replaced]
        swapped = records_frame([touched[i] for i in where], where="row")
        swapped.index = pd.Index(where)
        merged = pd.concat([merged.drop(index=where), swapped]).sort_index()
    if fresh:
        extra = records_frame(list(fresh.values()), where="record")
        merged = pd.concat([merged, extra], ignore_index=True) if len(merged) else extra
    merged = merged.reset_index(drop=True)
    return _validated(merged, "row"), report


def append_records(
    path: str | os.PathLike[str],
    records: Sequence[Mapping[str, Any]],
    *,
    replace: bool = False,
) -> AppendReport:
    """Append run records to the map at ``path`` (created if absent).

    Idempotent: a run already present with the same content is left alone; a run whose
    content differs replaces its row only when ``replace`` is true. The records are
    validated before the lock is taken, and the file is rewritten (atomically) only when
    something was added or replaced, so a failing append leaves the map byte-identical.
    """
    return update_map(path, records, replace=replace)


def update_map(
    path: str | os.PathLike[str],
    records: Sequence[Mapping[str, Any]],
    *,
    replace: bool = False,
    drop_ids: Iterable[str] = (),
) -> AppendReport:
    """:func:`append_records` that also removes the rows ``drop_ids`` (e.g. runs whose raw
    file changed), in the same locked read-modify-write and one atomic write.

    Ids in ``drop_ids`` that are also among ``records`` are not dropped; unknown ids are
    ignored. Validation happens before anything is touched.
    """
    import dataclasses

    p = Path(path)
    new_frame = records_frame(records)  # validate before touching anything
    with _locked(p):
        current = read_map(p)
        drop = set(drop_ids) - set(new_frame["measurement_id"])
        gone = current["measurement_id"].isin(sorted(drop)).to_numpy()
        merged, report = _fold(current.loc[~gone], new_frame, replace=replace)
        report = dataclasses.replace(
            report, dropped_ids=tuple(current.loc[gone, "measurement_id"].astype(str))
        )
        if report.changed:
            _write_atomic(p, merged)
    return report


def merge_map(
    path: str | os.PathLike[str], other: str | os.PathLike[str], *, replace: bool = False
) -> AppendReport:
    """Fold another friction map (another lab's Parquet map) into the map at ``path``.

    Runs with the same id are stored once; rows whose content differs are reported as
    conflicting (and replaced only with ``replace``). The other map is validated first.
    """
    if Path(other).resolve() == Path(path).resolve():
        raise MapError("cannot merge a friction map into itself", path=other)
    if not Path(other).exists():
        raise MapError("file not found, expected a friction map to merge", path=other)
    return append_records(path, frame_records(read_map(other)), replace=replace)


# --------------------------------------------------------------------------- exclusions


def _resolve_ids(runs: pd.DataFrame, ids: Iterable[str], path: Path) -> list[int]:
    known = list(runs["measurement_id"])
    positions = []
    for given in ids:
        hits = [i for i, m in enumerate(known) if m == given]
        if not hits and len(given) >= 6:
            hits = [i for i, m in enumerate(known) if m.startswith(given)]
        if not hits:
            raise MapError(
                f"no run with measurement id {given!r}",
                path=path,
                hint="`tribopipe map show` lists the ids",
            )
        if len(hits) > 1:
            raise MapError(f"id prefix {given!r} matches {len(hits)} runs", path=path,
                           hint="give more digits")
        positions.append(hits[0])
    return positions


def set_excluded(
    path: str | os.PathLike[str], ids: Sequence[str], *, reason: str | None
) -> list[str]:
    """Exclude runs from the statistics (``reason`` given) or include them again
    (``reason=None``). Ids may be given as unique prefixes of at least 6 digits.

    The runs stay in the map with the reason recorded; returns the full ids changed.
    Raises :class:`MapError` for an unknown id or an empty reason.
    """
    p = Path(path)
    if reason is not None and not reason.strip():
        raise MapError("an exclusion needs a reason", path=p, hint="pass --reason TEXT")
    if not p.exists():
        raise MapError("friction map not found", path=p, hint="pass --map PATH")
    with _locked(p):
        runs = read_map(p)
        positions = _resolve_ids(runs, ids, p)
        rows = frame_records(runs)
        changed = []
        for i in positions:
            new_state = (reason is not None, None if reason is None else reason.strip())
            if (rows[i]["excluded"], rows[i]["exclusion_reason"]) != new_state:
                rows[i] = {**rows[i], "excluded": new_state[0], "exclusion_reason": new_state[1]}
                changed.append(rows[i]["measurement_id"])
        if changed:
            _write_atomic(p, records_frame(rows, where="row"))
    return changed


def exclude_runs(path: str | os.PathLike[str], ids: Sequence[str], reason: str) -> list[str]:
    """Leave runs out of the statistics, recording why; returns the ids changed."""
    if reason is None:
        raise MapError("an exclusion needs a reason", path=path, hint="pass --reason TEXT")
    return set_excluded(path, ids, reason=reason)


def include_runs(path: str | os.PathLike[str], ids: Sequence[str]) -> list[str]:
    """Take excluded runs back into the statistics; returns the ids changed."""
    return set_excluded(path, ids, reason=None)


# --------------------------------------------------------------------------- import


def read_frictionmap_table(path: str | os.PathLike[str]) -> pd.DataFrame:
    """Read a table in the published 7-column schema (:data:`FRICTIONMAP_COLUMNS`) from the
    MATLAB ``FrictionMap.mat`` (a MATLAB ``table``, read with mat-io) or a CSV file.

    Returns the 7 columns (text, then floats). Raises :class:`MapError` naming the file and
    the line (CSV) or row (``.mat``) and column of a missing or non-numeric value.
    """
    import pandas as pd

    p = Path(path)
    if not p.is_file():
        raise MapError("file not found, expected a FrictionMap .mat or CSV", path=p)
    if p.suffix.lower() == ".mat":
        table = _read_mat_table(p)
        first_line = None
    else:
        try:
            table = pd.read_csv(p, dtype=str, keep_default_na=False, skipinitialspace=True)
        except (ValueError, UnicodeDecodeError, OSError) as exc:
            raise MapError(
                f"cannot read as CSV ({exc})",
                path=p,
                hint=f"expected columns {', '.join(FRICTIONMAP_COLUMNS)}",
            ) from None
        first_line = 2  # line 1 is the header
    table.columns = [str(c).strip() for c in table.columns]
    absent = [c for c in FRICTIONMAP_COLUMNS if c not in table.columns]
    if absent:
        raise MapError(
            f"missing column(s) {', '.join(absent)}; expected the FrictionMap schema "
            f"{', '.join(FRICTIONMAP_COLUMNS)}",
            path=p,
            line=1 if first_line else None,
            column=absent[0],
        )
    out: dict[str, Any] = {}
    for col in FRICTIONMAP_COLUMNS:
        values = table[col].tolist()
        if col in ("pin", "disc"):
            texts = ["" if _missing(v) else str(v).strip() for v in values]
            for i, text in enumerate(texts):
                if not text:
                    raise _where(p, first_line, i, col, "empty, expected a material name")
            out[col] = texts
            continue
        numbers = []
        for i, v in enumerate(values):
            text = "" if _missing(v) else str(v).strip()
            if text == "" and col == "temperature":
                numbers.append(math.nan)  # unknown temperature is allowed, unknown μ is not
                continue
            try:
                number = float(text) if isinstance(v, str) else float(v)
            except (TypeError, ValueError):
                number = math.nan
            if not math.isfinite(number):
                raise _where(p, first_line, i, col, f"{text!r} is not a finite number")
            numbers.append(number)
        out[col] = numbers
    return pd.DataFrame(out, columns=list(FRICTIONMAP_COLUMNS))


def _where(path: Path, first_line: int | None, i: int, col: str, problem: str) -> MapError:
    if first_line is None:
        return MapError(f"row {i + 1}: {problem}", path=path, column=col)
    return MapError(problem, path=path, line=first_line + i, column=col)


def _read_mat_table(path: Path) -> pd.DataFrame:
    import warnings

    import pandas as pd

    with warnings.catch_warnings():
        # mat-io sets a pandas option that pandas 3 deprecates; not our users' concern
        warnings.simplefilter("ignore", DeprecationWarning)
        try:
            import matio
        except ImportError:  # pragma: no cover - mat-io is a dependency
            raise MapError("reading .mat files needs the mat-io package", path=path,
                           hint="pip install mat-io") from None
        try:
            contents = matio.load_from_mat(str(path))
        except Exception as exc:  # mat-io raises many types for foreign files
            raise MapError(f"not a readable MATLAB file ({type(exc).__name__}: {exc})",
                           path=path) from None
    tables = [v for v in contents.values() if isinstance(v, pd.DataFrame)]
    if not tables:
        raise MapError(
            f"holds no MATLAB table (variables: {', '.join(contents) or 'none'})",
            path=path,
            hint="expected the FrictionMap.mat 'frictionMap' table",
        )
    table = contents.get("frictionMap")
    if not isinstance(table, pd.DataFrame):
        table = tables[0]
    return table.astype({c: object for c in table.columns if str(c) in ("pin", "disc")})


def _is_published(table: pd.DataFrame) -> bool:
    """True when every row of ``table`` is a row of the shipped published map."""
    published = read_frictionmap_table(published_csv_path())
    def keys(t: pd.DataFrame) -> set[tuple[Any, ...]]:
        return set(t.itertuples(index=False, name=None))
    return len(table) > 0 and keys(table) <= keys(published)


def published_csv_path() -> Path:
    """The published map shipped with tribopipe (``tribopipe/data/frictionmap_published.csv``)."""
    from importlib.resources import files

    return Path(str(files("tribopipe") / "data" / "frictionmap_published.csv"))


def import_records(
    path: str | os.PathLike[str], *, source: str | None = None
) -> list[dict[str, Any]]:
    """Friction-map records for a table in the published 7-column schema (.mat or CSV).

    ``source`` labels where the rows came from; by default ``published:Berthold2023`` when
    every row is one of the published map's rows (whatever the file's name or format),
    else ``import:<file name>``. Ids hash the source and the conditions, so importing the
    same rows again is idempotent. μ_S and the measured values are missing; published rows
    record the paper's sliding speed (0.007 mm/s), others leave it missing.
    """
    from . import __version__

    p = Path(path)
    table = read_frictionmap_table(p)
    if source is None:
        source = SOURCE_PUBLISHED if _is_published(table) else f"import:{p.name}"
    published = source == SOURCE_PUBLISHED
    file_hash = file_sha256(p)
    stamp = _now()
    records = []
    for pin, disc, force, pressure, temperature, number, cof in table.itertuples(
        index=False, name=None
    ):
        repeat = int(number) if float(number).is_integer() else None
        records.append(
            {
                "measurement_id": imported_id(source, pin, disc, force, temperature, repeat),
                "source": source,
                "pin": pin,
                "disc": disc,
                "normal_force_N": force,
                "pressure_kPa": pressure,
                "normal_force_measured_N": None,
                "pressure_measured_kPa": None,
                "temperature_C": temperature,
                "temperature_measured_C": None,
                "sliding_speed_mm_s": PUBLISHED_SLIDING_SPEED_MM_S if published else None,
                "repeat": repeat,
                "mu_s": None,
                "mu_k": cof,
                "mu_s_distance_mm": None,
                "mu_s_time_s": None,
                "mu_k_window_start_mm": None,
                "mu_k_window_end_mm": None,
                "mu_k_window_start_s": None,
                "mu_k_window_end_s": None,
                "plateau_std": None,
                "plateau_drift_per_mm": None,
                "flags": "",
                "method": "published" if published else "imported",
                "source_file": p.name,
                "file_hash": file_hash,
                "interval": None,
                "config_hash": None,
                "tribopipe_version": __version__,
                "reduced_at": stamp,
                "excluded": False,
                "exclusion_reason": None,
            }
        )
    seen: set[str] = set()
    for row, rec in enumerate(records):
        if rec["measurement_id"] not in seen:
            seen.add(rec["measurement_id"])
            continue
        raise MapError(
            "two rows have the same pin, disc, force, temperature and measurementNo",
            path=p,
            line=row + 2 if p.suffix.lower() != ".mat" else None,
            column="measurementNo",
        )
    return records


def import_table(
    path: str | os.PathLike[str],
    file: str | os.PathLike[str] | None = None,
    *,
    source: str | None = None,
    replace: bool = False,
) -> AppendReport:
    """Import a 7-column FrictionMap table (.mat or CSV; default: the shipped published
    map) into the map at ``path``; see :func:`import_records`."""
    records = import_records(published_csv_path() if file is None else file, source=source)
    return append_records(path, records, replace=replace)


# --------------------------------------------------------------------------- summary


def map_summary(path: str | os.PathLike[str]) -> str:
    """A readable multi-line summary of the map at ``path``: runs, pairs, conditions,
    sources, flags, excluded runs (with reasons) and the pooled repeatability."""
    from .stats import group_statistics, repeatability

    p = Path(path)
    if not p.exists():
        raise MapError("friction map not found", path=p, hint="pass --map PATH")
    runs = read_map(p)
    lines = [f"friction map {p}"]
    n_ex = int(runs["excluded"].sum())
    lines.append(f"  runs: {len(runs)} ({n_ex} excluded)")
    if runs.empty:
        return "\n".join(lines)
    groups = group_statistics(runs)
    pairs = runs.groupby(["pin", "disc"], sort=True)
    lines.append(f"  contact pairs: {pairs.ngroups}; condition groups: {len(groups)}")
    for source, n in runs["source"].value_counts().sort_index().items():
        lines.append(f"  source {source}: {_runs(n)}")
    lines.append("")
    lines.append("  pin / disc: runs, conditions, force [N], temperature [°C]")
    for (pin, disc), sub in pairs:
        forces = ", ".join(f"{f:g}" for f in sorted(sub["normal_force_N"].dropna().unique()))
        temps = ", ".join(f"{t:g}" for t in sorted(sub["temperature_C"].dropna().unique()))
        n_cond = int(((groups["pin"] == pin) & (groups["disc"] == disc)).sum())
        lines.append(f"    {pin} / {disc}: {_runs(len(sub))}, {n_cond} conditions, "
                     f"F {forces or '-'}, T {temps or '-'}")
    flag_counts: dict[str, int] = {}
    for text in runs["flags"].dropna():
        for f in filter(None, text.split(";")):
            flag_counts[f] = flag_counts.get(f, 0) + 1
    lines.append("")
    if flag_counts:
        lines.append("  flags: " + ", ".join(f"{k} {v}" for k, v in sorted(flag_counts.items())))
    else:
        lines.append("  flags: none")
    flagged = int(groups["qc_flagged"].sum()) if len(groups) else 0
    wide = int(groups["range_exceeds_r"].sum()) if len(groups) else 0
    lines.append(f"  groups with flagged runs: {flagged}; groups with range > r: {wide}")
    for q in ("mu_k", "mu_s"):
        rep = repeatability(groups, q)
        if rep.dof:
            lines.append(f"  repeatability {q}: s_r = {rep.s_r:.4g} ({rep.dof} dof from "
                         f"{rep.n_groups} groups), r = 2.8·s_r = {rep.r:.4g}")
        else:
            lines.append(f"  repeatability {q}: no group with two or more values")
    excluded = runs[runs["excluded"]]
    if len(excluded):
        lines.append("")
        lines.append("  excluded runs:")
        for row in excluded.itertuples(index=False):
            lines.append(f"    {row.measurement_id}  {row.pin} / {row.disc}, "
                         f"{row.normal_force_N:g} N, {_fmt_t(row.temperature_C)}, "
                         f"repeat {_fmt_repeat(row.repeat)}: {row.exclusion_reason}")
    return "\n".join(lines)


def _runs(n: int) -> str:
    return f"{n} run" if n == 1 else f"{n} runs"


def _fmt_t(value: float) -> str:
    return "T ?" if _missing(value) else f"{value:g} °C"


def _fmt_repeat(value: Any) -> str:
    return "?" if _missing(value) else str(value)
