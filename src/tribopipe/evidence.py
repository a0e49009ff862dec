"""A package's evidence: each run's reduced trace and raw export, and μ re-derived from them.

A package tribopipe publishes carries, beside its summary rows, the evidence behind every
reduced row (``map publish``; the raw exports only with ``--with-raw``)::

    evidence/index.csv           one row per run with evidence: its trace and raw export
                                 (paths in the package), their SHA-256, the settings
                                 (config hash) and the method that reduced it
    evidence/settings.json       the settings by config hash: the method, the instrument
                                 and the reduction parameters (what ``Settings`` holds)
    evidence/traces/<id>.parquet each run's reduced trace (``<id>`` = its measurement id)
    evidence/raw/<sha256><.ext>  each raw export, named by its content

The descriptor lists ``evidence/index.csv`` and ``evidence/settings.json`` with their
size and SHA-256, and the index holds the SHA-256 of every trace and raw file, so one
chain of hashes reaches every file.

:func:`recompute_package` re-derives μ_S and μ_K of every row: from the raw export where
the package holds it (the export read and reduced again with the package's settings, the
run found by its measurement id), else from the trace (the detection steps run again on
the trace's sliding samples). A settings record must hash to the row's config hash, so
it cannot be swapped. A row whose stored μ differs from the re-derived one by more than
its stated expanded uncertainty U = 2·u is refused, naming the row and both values;
rows checked only from the trace, and rows with no evidence, are counted and named.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .config import REDUCTION_METHOD, Settings, load_settings, settings_from_dict
from .errors import ConfigError, ExportError, TribopipeError
from .escape import printable
from .files import file_sha256
from .frictionmap.datapackage import (
    DEFAULT_LIMITS,
    DESCRIPTOR,
    PackageLimits,
    PackageRefused,
    load_descriptor,
    read_bounded,
    resource_file,
    sha256_hash,
)
from .frictionmap.package import PackageCheck, check_package
from .frictionmap.records import measurement_id, stored_file_name
from .frictionmap.schema import SOURCE_REDUCED
from .layout import find_traces
from .pipeline.route import read_runs
from .reduction.detection import run_detection
from .reduction.reduce import reduce_measurement

if TYPE_CHECKING:
    import pandas as pd

#: the evidence folder of a package and its two described files
EVIDENCE_DIR = "evidence"
INDEX_PATH = "evidence/index.csv"
SETTINGS_PATH = "evidence/settings.json"
#: the descriptor's resource names of the index and the settings
INDEX_RESOURCE, SETTINGS_RESOURCE = "evidence", "evidence-settings"
#: the columns of ``evidence/index.csv``
INDEX_COLUMNS: tuple[str, ...] = ("measurement_id", "trace_path", "trace_sha256",
                                  "raw_path", "raw_sha256", "config_hash", "method")
#: Table Schema fields of the index (for the descriptor)
INDEX_FIELDS: tuple[dict[str, str], ...] = (
    {"name": "measurement_id", "type": "string", "description": "the run (runs table)"},
    {"name": "trace_path", "type": "string", "description": "its reduced trace (Parquet)"},
    {"name": "trace_sha256", "type": "string", "description": "SHA-256 of the trace"},
    {"name": "raw_path", "type": "string", "description": "its raw export (with --with-raw)"},
    {"name": "raw_sha256", "type": "string", "description": "SHA-256 of the raw export"},
    {"name": "config_hash", "type": "string",
     "description": "the settings that reduced it (evidence/settings.json)"},
    {"name": "method", "type": "string", "description": "the reduction method and version"},
)
#: what a trace must hold for the detection to run again on it
TRACE_COLUMNS = ("time_s", "sliding_distance_mm", "mu", "mu_smooth")
#: how a row was checked (:attr:`RowCheck.basis`)
FROM_RAW, FROM_TRACE, NO_EVIDENCE = "raw export", "trace", "no evidence"
#: the coverage factor of the stated expanded uncertainty U = k·u
COVERAGE = 2.0
#: re-derived and stored values closer than this agree whatever their U (float noise)
EXACT = 1e-9

_HEX = re.compile(r"[0-9a-f]{16,64}")
_SUFFIX = re.compile(r"\.[A-Za-z0-9]{1,8}")


# --------------------------------------------------------------------------- settings


def settings_record(settings: Settings) -> dict[str, Any]:
    """The JSON record of ``settings``: the method, the instrument and the reduction
    parameters (what :attr:`Settings.config_hash` hashes)."""
    return {"method": REDUCTION_METHOD, "instrument": asdict(settings.instrument),
            "reduction": asdict(settings.reduction)}


def settings_from_record(record: Any, where: str) -> Settings:
    """:class:`Settings` from a record of :func:`settings_record`; :class:`ConfigError`
    naming ``where`` when it is not one."""
    if not isinstance(record, dict) or not isinstance(record.get("instrument"), dict) \
            or not isinstance(record.get("reduction"), dict):
        raise ConfigError(f"{where}: expected 'method', 'instrument' and 'reduction'")
    try:
        return settings_from_dict({"instrument": record["instrument"],
                                   "reduction": record["reduction"]}, source=where)
    except ConfigError as exc:
        raise ConfigError(f"{where}: {exc.problem}") from None


# --------------------------------------------------------------------------- publishing


@dataclass(frozen=True)
class EvidenceFile:
    """One run's evidence found for publishing: the trace and raw export on disk (either
    may be missing) and the settings hash that reduced it."""

    measurement_id: str
    trace: Path | None
    raw: Path | None
    config_hash: str
    method: str


@dataclass(frozen=True)
class Evidence:
    """What goes into a package's ``evidence/``: a file per run, the settings records by
    config hash, and notes on what could not be found (one line each)."""

    files: tuple[EvidenceFile, ...]
    settings: dict[str, dict[str, Any]]
    notes: tuple[str, ...] = ()


def gather_evidence(runs: pd.DataFrame, *, traces_dir: Path | None,
                    raw_dirs: Sequence[Path] = (), settings: Iterable[Settings] = (),
                    with_raw: bool = False) -> Evidence:
    """The evidence of the reduced rows of ``runs``: each trace under ``traces_dir``,
    each raw export (``with_raw``) found under ``raw_dirs`` by its name and SHA-256, and
    the settings among ``settings`` (and the defaults) whose config hash a row names.
    Rows imported from elsewhere carry none. Raises :class:`ExportError` when
    ``with_raw`` is given without a folder to look in."""
    if with_raw and not raw_dirs:
        raise ExportError("--with-raw needs the folder of the raw exports",
                          hint="pass --raw-dir FOLDER (searched with its sub-folders)")
    known = {s.config_hash: settings_record(s) for s in (load_settings(), *settings)}
    raw_index = _raw_candidates(raw_dirs) if with_raw else {}
    files: list[EvidenceFile] = []
    used: dict[str, dict[str, Any]] = {}
    notes: list[str] = []
    missing_settings: set[str] = set()
    missing_trace = missing_raw = 0
    # the columns it reads (a row of every column per run costs more than the rest)
    reduced = runs.loc[runs["source"] == SOURCE_REDUCED,
                       ["measurement_id", "config_hash", "source_file", "file_hash", "method"]]
    # the traces folder listed once, not once per run (a glob per run of a folder of n
    # traces is n² at 10⁵ runs)
    traces = ({} if traces_dir is None else
              find_traces(traces_dir, [str(m) for m in reduced["measurement_id"]]))
    for row in reduced.itertuples(index=False):
        mid, chash = str(row.measurement_id), str(row.config_hash or "")
        trace = traces.get(mid)
        missing_trace += trace is None
        raw = None
        if with_raw:
            raw = _find_raw(raw_index, str(row.source_file or ""), str(row.file_hash or ""))
            missing_raw += raw is None
        if chash in known:
            used[chash] = known[chash]
        else:
            missing_settings.add(chash)
        if trace is not None or raw is not None:
            files.append(EvidenceFile(mid, trace, raw, chash, str(row.method or "")))
    if missing_trace:
        notes.append(f"{missing_trace} of {len(reduced)} reduced runs have no trace under "
                     f"{traces_dir} (pass --traces FOLDER)" if traces_dir is not None
                     else "no traces folder given")
    if missing_raw:
        notes.append(f"{missing_raw} of {len(reduced)} reduced runs have no raw export "
                     f"(by name and SHA-256) under {', '.join(map(str, raw_dirs))}")
    if missing_settings:
        notes.append(f"settings of config hash {', '.join(sorted(missing_settings))} not "
                     "known (pass the instrument file that reduced them with --instrument)")
    return Evidence(tuple(files), used, tuple(notes))


def _raw_candidates(raw_dirs: Sequence[Path]) -> dict[str, list[Path]]:
    """Every regular file below ``raw_dirs`` by its stored name."""
    out: dict[str, list[Path]] = {}
    for folder in raw_dirs:
        if not Path(folder).is_dir():
            raise ExportError("raw folder not found", path=folder)
        for path in sorted(Path(folder).rglob("*")):
            if path.is_file() and not path.is_symlink():
                out.setdefault(stored_file_name(path), []).append(path)
    return out


def _find_raw(index: Mapping[str, list[Path]], name: str, sha256: str) -> Path | None:
    for path in index.get(name, []):
        if file_sha256(path) == sha256:
            return path
    return None


def write_evidence(folder: Path, evidence: Evidence) -> tuple[bytes, bytes]:
    """Copy the evidence into ``folder/evidence`` and return the bytes of the index and
    of the settings file (written there too), for the descriptor to describe."""
    root = folder / EVIDENCE_DIR
    (root / "traces").mkdir(parents=True)
    (root / "raw").mkdir()
    rows: list[dict[str, str]] = []
    for item in evidence.files:
        row = dict.fromkeys(INDEX_COLUMNS, "")
        row.update(measurement_id=item.measurement_id, config_hash=item.config_hash,
                   method=item.method)
        if item.trace is not None:
            data = item.trace.read_bytes()
            rel = f"{EVIDENCE_DIR}/traces/{item.measurement_id}.parquet"
            (folder / rel).write_bytes(data)
            row.update(trace_path=rel, trace_sha256=sha256_hash(data)[7:])
        if item.raw is not None:
            data = item.raw.read_bytes()
            digest = sha256_hash(data)[7:]
            suffix = item.raw.suffix if _SUFFIX.fullmatch(item.raw.suffix) else ""
            rel = f"{EVIDENCE_DIR}/raw/{digest}{suffix.lower()}"
            (folder / rel).write_bytes(data)  # one raw export of several runs: once
            row.update(raw_path=rel, raw_sha256=digest)
        rows.append(row)
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=list(INDEX_COLUMNS), lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    index = buf.getvalue().encode()
    settings = (json.dumps(evidence.settings, indent=2, sort_keys=True) + "\n").encode()
    (folder / INDEX_PATH).write_bytes(index)
    (folder / SETTINGS_PATH).write_bytes(settings)
    return index, settings


# --------------------------------------------------------------------------- recompute


@dataclass(frozen=True)
class RowCheck:
    """One row re-derived: its id, the basis (:data:`FROM_RAW`, :data:`FROM_TRACE` or
    :data:`NO_EVIDENCE`), the stored and re-derived μ_S and μ_K (``None`` when not
    re-derived), and the problems (one line each; empty when it agrees)."""

    measurement_id: str
    basis: str
    stored: tuple[float | None, float | None]
    recomputed: tuple[float | None, float | None] = (None, None)
    problems: tuple[str, ...] = ()
    why: str = ""


@dataclass
class Recompute:
    """The recompute of a package: the package check, the problems of the evidence itself
    and one :class:`RowCheck` per run."""

    check: PackageCheck
    problems: list[str] = field(default_factory=list)
    rows: list[RowCheck] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        """True when the package checks and every re-derived row agrees."""
        return self.check.ok and not self.problems and not any(r.problems for r in self.rows)

    def lines(self) -> list[str]:
        """One line per problem: the package's, the evidence's, then each row's."""
        return [*self.check.lines(), *self.problems,
                *(p for r in self.rows for p in r.problems)]

    def account(self) -> list[str]:
        """What was checked how: rows from the raw export, from the trace only, and those
        with no evidence (each named, up to ten)."""
        out = []
        raw = [r for r in self.rows if r.basis == FROM_RAW]
        trace = [r for r in self.rows if r.basis == FROM_TRACE]
        none = [r for r in self.rows if r.basis == NO_EVIDENCE]
        out.append(f"{len(raw)} of {len(self.rows)} runs re-derived from their raw export")
        if trace:
            out.append(f"{len(trace)} runs could only be checked from their trace: "
                       + _names(r.measurement_id for r in trace))
        if none:
            reasons: dict[str, list[str]] = {}
            for r in none:
                reasons.setdefault(r.why, []).append(r.measurement_id)
            for why, ids in reasons.items():
                out.append(f"{len(ids)} runs carry no evidence ({why}): {_names(ids)}")
        return out


def _names(ids: Iterable[str], limit: int = 10) -> str:
    ids = list(ids)
    shown = ", ".join(ids[:limit])
    return shown + (f" and {len(ids) - limit} more" if len(ids) > limit else "")


def recompute_package(path: str | os.PathLike[str],
                      limits: PackageLimits = DEFAULT_LIMITS) -> Recompute:
    """Check the package at ``path`` (:func:`check_package`) and re-derive μ_S and μ_K
    of every run from its evidence (module docstring). Never raises for a bad package."""
    check = check_package(path, limits)
    out = Recompute(check)
    if check.runs is None:
        return out
    try:
        descriptor, base = load_descriptor(check.path, limits)
    except PackageRefused as exc:
        out.problems.append(f"{DESCRIPTOR}: {exc.problem}")
        return out
    index, settings, other_methods = _read_evidence(descriptor, base, limits, out.problems)
    for row in check.runs.itertuples(index=False):
        method = other_methods.get(str(row.config_hash or ""))
        if method is not None and str(row.measurement_id) in index:
            mid = str(row.measurement_id)
            # the row itself names the method that reduced it: the two must agree
            said = str(row.method or "").split(":", 1)[0]
            problems = () if said == method else (
                f"run {mid}: its row says method {printable(said)!r}, its settings in "
                f"{SETTINGS_PATH} say {method!r}",)
            out.rows.append(RowCheck(
                mid, NO_EVIDENCE, (_number(row.mu_s), _number(row.mu_k)), problems=problems,
                why=f"reduced by method {method!r}, which this tribopipe "
                    f"({REDUCTION_METHOD}) cannot run"))
            continue
        out.rows.append(_check_row(row, index, settings, base, limits))
    return out


def _resource_bytes(descriptor: dict[str, Any], name: str, base: Path,
                    limits: PackageLimits) -> bytes | None:
    """A resource's bytes (its hash was checked by :func:`check_package`)."""
    for res in descriptor.get("resources") or []:
        if isinstance(res, dict) and res.get("name") == name:
            data = read_bounded(resource_file(base, res.get("path")), limits.resource_bytes)
            if sha256_hash(data) != str(res.get("hash", "")).lower():
                raise PackageRefused(f"{res.get('path')}: checksum does not match")
            return data
    return None


def _read_evidence(descriptor: dict[str, Any], base: Path, limits: PackageLimits,
                   problems: list[str]) -> tuple[dict[str, dict[str, str]],
                                                 dict[str, Settings], dict[str, str]]:
    """The index rows by measurement id, the settings by config hash (each checked to
    hash to its key) and the methods other than this tribopipe's by config hash (their
    rows cannot be re-derived here); problems appended one line each."""
    try:
        index_bytes = _resource_bytes(descriptor, INDEX_RESOURCE, base, limits)
        settings_bytes = _resource_bytes(descriptor, SETTINGS_RESOURCE, base, limits)
    except PackageRefused as exc:
        problems.append(f"{EVIDENCE_DIR}: {exc.problem}")
        return {}, {}, {}
    if index_bytes is None:
        return {}, {}, {}
    index: dict[str, dict[str, str]] = {}
    try:
        reader = csv.DictReader(io.StringIO(index_bytes.decode("utf-8")))
        if tuple(reader.fieldnames or ()) != INDEX_COLUMNS:
            problems.append(f"{INDEX_PATH}: columns {reader.fieldnames}, expected "
                            f"{', '.join(INDEX_COLUMNS)}")
            return {}, {}, {}
        for line, row in enumerate(reader, 2):
            mid = row.get("measurement_id") or ""
            if not _HEX.fullmatch(mid):
                problems.append(f"{INDEX_PATH}, line {line}: measurement_id "
                                f"{printable(mid)!r} is not a run id")
                continue
            index[mid] = row
    except (UnicodeDecodeError, csv.Error) as exc:
        problems.append(f"{INDEX_PATH}: not a UTF-8 CSV ({exc})")
        return {}, {}, {}
    settings: dict[str, Settings] = {}
    other_methods: dict[str, str] = {}
    if settings_bytes is not None:
        try:
            records = json.loads(settings_bytes)
        except ValueError as exc:
            problems.append(f"{SETTINGS_PATH}: not JSON ({exc})")
            records = {}
        for key, record in (records.items() if isinstance(records, dict) else ()):
            where = f"{SETTINGS_PATH}: {printable(str(key))}"
            method = record.get("method") if isinstance(record, dict) else None
            if isinstance(method, str) and method != REDUCTION_METHOD:
                other_methods[str(key)] = printable(method)
                continue
            try:
                found = settings_from_record(record, where)
            except ConfigError as exc:
                problems.append(exc.problem)
                continue
            if found.config_hash != key:
                problems.append(f"{where}: these settings hash to {found.config_hash}, not "
                                "to their key (edited after the runs were reduced)")
                continue
            if record.get("method") != REDUCTION_METHOD:
                problems.append(f"{where}: expected 'method', the reduction method's name")
                continue
            settings[key] = found
    return index, settings, other_methods


def _number(value: Any) -> float | None:
    try:
        number = float(value)
    except (TypeError, ValueError):
        return None
    return number if math.isfinite(number) else None


def _check_row(row: Any, index: Mapping[str, dict[str, str]],
               settings: Mapping[str, Settings], base: Path,
               limits: PackageLimits) -> RowCheck:
    """Re-derive one row (see the module docstring)."""
    mid = str(row.measurement_id)
    stored = (_number(row.mu_s), _number(row.mu_k))
    if row.source != SOURCE_REDUCED:
        return RowCheck(mid, NO_EVIDENCE, stored, why=f"{row.source} rows, not reduced here")
    entry = index.get(mid)
    if entry is None:
        return RowCheck(mid, NO_EVIDENCE, stored, why="no trace or raw export in the package")
    where = f"{INDEX_PATH}: run {mid}"
    config = settings.get(str(row.config_hash or ""))
    if config is None:
        return RowCheck(mid, NO_EVIDENCE, stored,
                        why="the settings that reduced them are not in the package")
    try:
        if entry.get("raw_path"):
            mu = _from_raw(row, entry, config, base, limits)
            basis = FROM_RAW
        elif entry.get("trace_path"):
            mu = _from_trace(entry, config, base, limits)
            basis = FROM_TRACE
        else:
            return RowCheck(mid, NO_EVIDENCE, stored, why="an index row without files")
    except (TribopipeError, OSError, ValueError, KeyError) as exc:
        text = exc.problem if isinstance(exc, TribopipeError) else str(exc)
        return RowCheck(mid, NO_EVIDENCE, stored, problems=(f"{where}: {printable(text)}",),
                        why="evidence that cannot be read")
    problems = []
    for name, u_name, value, again in (("mu_s", "u_mu_s", stored[0], mu[0]),
                                       ("mu_k", "u_mu_k", stored[1], mu[1])):
        u = _number(getattr(row, u_name))
        if value is None and again is None:
            continue
        if value is None or again is None:
            problems.append(f"run {mid} ({printable(str(row.source_file))}): {name} stored "
                            f"{_show(value)}, re-derived from the {basis} {_show(again)}")
            continue
        allowed = COVERAGE * u if u is not None else 0.0
        if abs(value - again) > max(allowed, EXACT):
            problems.append(
                f"run {mid} ({printable(str(row.source_file))}): {name} stored "
                f"{value:.6g}, re-derived from the {basis} {again:.6g} (differs by "
                f"{abs(value - again):.3g}, beyond its stated U = {allowed:.3g})")
    return RowCheck(mid, basis, stored, mu, tuple(problems))


def _show(value: float | None) -> str:
    return "none" if value is None else f"{value:.6g}"


def _evidence_file(base: Path, entry: Mapping[str, str], kind: str,
                   limits: PackageLimits) -> bytes:
    """The bytes of an index row's trace or raw file, checked against its SHA-256."""
    rel = entry.get(f"{kind}_path") or ""
    if not rel.startswith(f"{EVIDENCE_DIR}/"):
        raise PackageRefused(f"{kind} path {rel!r} is not under {EVIDENCE_DIR}/")
    data = read_bounded(resource_file(base, rel), limits.resource_bytes, what=kind)
    if sha256_hash(data)[7:] != (entry.get(f"{kind}_sha256") or "").lower():
        raise PackageRefused(f"{kind} {rel}: SHA-256 is {sha256_hash(data)[7:19]}…, the "
                             "index says another (the file was changed)")
    return data


def _from_trace(entry: Mapping[str, str], config: Settings, base: Path,
                limits: PackageLimits) -> tuple[float | None, float | None]:
    """μ_S and μ_K of the detection run again on a trace's sliding samples (those the
    reduction smoothed: ``mu_smooth`` finite)."""
    import numpy as np
    import pyarrow as pa
    import pyarrow.parquet as pq

    data = _evidence_file(base, entry, "trace", limits)
    try:
        table = pq.read_table(pa.BufferReader(data), columns=list(TRACE_COLUMNS))
    except (pa.ArrowException, OSError) as exc:
        raise PackageRefused(f"trace is not a tribopipe trace ({exc})") from None
    col = {name: table.column(name).to_numpy(zero_copy_only=False).astype(float)
           for name in TRACE_COLUMNS}
    sliding = np.isfinite(col["mu_smooth"]) & np.isfinite(col["mu"])
    s = col["sliding_distance_mm"]
    if sliding.sum() < 3 or s.size < 2:
        raise PackageRefused("trace has too few sliding samples to re-derive μ")
    det = run_detection(s[sliding], col["time_s"][sliding], col["mu"][sliding],
                        float(s[-1] - s[0]), config.reduction)
    return _number(det.mu_s), _number(det.mu_k)


def _from_raw(row: Any, entry: Mapping[str, str], config: Settings, base: Path,
              limits: PackageLimits) -> tuple[float | None, float | None]:
    """μ_S and μ_K of the run reduced again from its raw export (found in the export by
    its measurement id)."""
    _evidence_file(base, entry, "raw", limits)  # hash checked before the reader sees it
    path = resource_file(base, entry["raw_path"])
    if entry.get("raw_sha256") != str(row.file_hash):
        raise PackageRefused("the raw export is not the file the row names (its SHA-256 "
                             "differs from file_hash)")
    export = read_runs(path, file_hash=str(row.file_hash))
    for place, measurement in export.runs:
        if measurement_id(export.file_hash, measurement.meta, place.occurrence) \
                == row.measurement_id:
            result = reduce_measurement(measurement, config.instrument, config.reduction)
            return _number(result.mu_s), _number(result.mu_k)
    raise PackageRefused("the raw export holds no run with this measurement id")
