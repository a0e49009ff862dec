"""A campaign: a table of raw exports with their metadata, reduced incrementally in parallel.

A campaign is described by a TOML file (``configs/*.toml``)::

    [campaign]
    name = "example"
    raw_dir = "../raw/example"           # paths are relative to the config file's folder
    glob = "*.csv"                       # default; the manifest itself is never a run
    instrument = "instruments/t-pid44.toml"     # default: the founding T-PID/44 cell
    output_dir = "../processed"          # default: processed/ beside the config's folder
    map = "../processed/friction_map.parquet"   # default: <output_dir>/friction_map.parquet
    manifest = "../raw/example/manifest.csv"
    filename_pattern = "{pin}_{disc}_{force}N_{temperature}C_r{repeat}"
    use_export_names = false             # also read metadata from the export's Test name
    export_pattern = "..."               # pattern for the Test name (default: filename_pattern)
    force_tolerance_N = 0.0              # QC: measured F_N may stray max(tol_N, tol_rel·F_nom)
    force_tolerance_rel = 0.10
    temperature_tolerance_C = 2.0        # QC: measured T may stray this far from nominal
    plots = true                         # per-run trace plots under <output_dir>/plots/traces
    encoding = "utf-16"                  # optional: force the reader's encoding, delimiter
    delimiter = "tab"                    # ("tab", ";", ",") or decimal mark (".", ","),
    decimal = ","                        # else they are detected per file

    [reduction]                          # optional: overrides the instrument config's table
    median_window = 5

    [names]                              # optional: short names in file names -> full names
    DS30 = "Dragonskin 30"

Metadata resolution
-------------------
Each run needs ``pin``, ``disc``, ``normal_force_N`` (nominal, total) and ``temperature_C``
(nominal); ``repeat`` is optional. They come from up to three sources, consulted in this
order: the manifest row, the file-name pattern, the export's own Test name. Every source
that gives a field must agree with the others (names compared after the ``[names]`` aliases,
ignoring case and surrounding blanks; numbers compared exactly); the first source that gives
a field defines its spelling. A disagreement or a missing required field is an error *for
that file only*: it is listed with its reason and the other runs still land.

Incremental batches
-------------------
``<output_dir>/.tribopipe-state.<name>.json`` remembers, per file: size, ``mtime_ns``,
SHA-256, the config hash, a recipe hash (config + labels + QC tolerances), the status and
the measurement id (one state per campaign name, so campaigns may share an output folder
and a map; ``runs.csv`` and ``failures.csv`` describe the folder's last batch). Like git's
index, the cached hash is trusted while size and ``mtime_ns`` are unchanged, so an
unchanged campaign is checked with one ``stat`` per file. A file whose content, labels or
config changed is reduced again and its old map row replaced; a failed file is retried
once it changes.
"""

from __future__ import annotations

import contextlib
import csv
import functools
import gc
import hashlib
import io
import json
import math
import os
import re
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .errors import CampaignError, ConfigError, TribopipeError
from .files import write_text_atomic
from .frictionmap import (
    Tolerances,
    make_record,
    qc_flags,  # noqa: F401  (public here too)
    read_map,
    update_map,
)
from .layout import (  # noqa: F401 - BATCH_LOCK is importable from here too
    BATCH_LOCK,
    DEFAULT_OUTPUT_DIR,
    OutputLayout,
    write_failures,
)
from .pipeline import (
    ReadOptions,
    RunLabels,
    RunOutcome,
    file_sha256,
    finite_or_none,
    plot_run,
    reduce_file,
    write_trace,
)

if TYPE_CHECKING:
    from .config import Settings

STATE_VERSION = 1

#: the statuses of a campaign row before a batch (``campaign list``)
NEW, REDUCED, CHANGED, FAILED = "new", "reduced", "changed", "failed"
#: what a batch did with a run (``runs.csv``)
SKIPPED = "skipped"

REQUIRED_FIELDS: tuple[str, ...] = ("pin", "disc", "normal_force_N", "temperature_C")
LABEL_FIELDS: tuple[str, ...] = (*REQUIRED_FIELDS, "repeat")
MANIFEST_COLUMNS: tuple[str, ...] = ("file", *LABEL_FIELDS)

#: placeholder names a pattern may use -> label field
PATTERN_FIELDS: dict[str, str] = {
    "pin": "pin",
    "disc": "disc",
    "force": "normal_force_N",
    "normal_force_N": "normal_force_N",
    "temperature": "temperature_C",
    "temperature_C": "temperature_C",
    "repeat": "repeat",
}
_NUMBER = r"-?[0-9]+(?:[.,p][0-9]+)?"
_PATTERN_REGEX: dict[str, str] = {
    "normal_force_N": _NUMBER,
    "temperature_C": _NUMBER,
    "repeat": r"[0-9]+",
}

_CAMPAIGN_KEYS = frozenset(
    {
        "name", "raw_dir", "glob", "instrument", "output_dir", "map", "manifest",
        "filename_pattern", "use_export_names", "export_pattern", "force_tolerance_N",
        "force_tolerance_rel", "temperature_tolerance_C", "plots", "encoding", "delimiter",
        "decimal",
    }
)
_TOP_LEVEL_TABLES = frozenset({"campaign", "reduction", "names"})

ProgressCallback = Callable[[int, int], None]


# --------------------------------------------------------------------------- config


@dataclass(frozen=True)
class Campaign:
    """A campaign's description: where its files are, how to label and reduce them.

    All paths are absolute (resolved against the config file's folder).
    """

    name: str
    raw_dir: Path
    glob: str
    settings: Settings
    output_dir: Path
    map_path: Path
    manifest: Path | None = None
    filename_pattern: str | None = None
    use_export_names: bool = False
    export_pattern: str | None = None
    names: tuple[tuple[str, str], ...] = ()
    tolerances: Tolerances = field(default_factory=Tolerances)
    plots: bool = True
    read_options: ReadOptions = field(default_factory=ReadOptions)
    source: Path | None = None

    @property
    def layout(self) -> OutputLayout:
        """The paths of the output folder (:class:`tribopipe.layout.OutputLayout`)."""
        return OutputLayout(self.output_dir)

    @property
    def state_path(self) -> Path:
        """The incremental state file: ``<output_dir>/.tribopipe-state.<name>.json``
        (the name reduced to letters, digits, ``-`` and ``_``)."""
        return self.layout.state_path(self.name)

    @property
    def runs_csv(self) -> Path:
        """Per-run summary table of the last batch: ``<output_dir>/runs.csv``."""
        return self.layout.runs_csv

    @property
    def failures_csv(self) -> Path:
        """Failure list of the last batch (``file,reason``): ``<output_dir>/failures.csv``."""
        return self.layout.failures_csv

    @property
    def plots_dir(self) -> Path:
        """Per-run trace plots: ``<output_dir>/plots/traces``."""
        return self.layout.trace_plots_dir

    def alias(self, name: str) -> str:
        """The full material name for a short one from ``[names]`` (unchanged if unknown)."""
        key = name.strip().casefold()
        for short, full in self.names:
            if short.casefold() == key:
                return full
        return name.strip()


def _check_type(value: Any, kind: type | tuple[type, ...], key: str, path: Path) -> Any:
    # bool is an int in Python; a number key must not accept `true`
    if isinstance(value, bool) and kind is not bool:
        ok = False
    else:
        ok = isinstance(value, kind)
    if not ok:
        names = kind.__name__ if isinstance(kind, type) else " or ".join(k.__name__ for k in kind)
        raise ConfigError(
            f"[campaign] {key} must be a {names}, got {value!r}", path=path, column=None
        )
    return value


def _non_negative(value: Any, key: str, path: Path) -> float:
    _check_type(value, (int, float), key, path)
    if not (math.isfinite(value) and value >= 0):
        raise ConfigError(f"[campaign] {key} must be a number >= 0, got {value!r}", path=path)
    return float(value)


def load_campaign(path: str | Path) -> Campaign:
    """Load and validate a campaign config (TOML); see the module docstring for the keys.

    Raises :class:`ConfigError` naming the file and the key for every problem.
    """
    from .config import (
        merge_tables,
        read_toml,
        reject_unknown_keys,
        settings_from_dict,
        settings_tables,
    )

    cfg_path = Path(path).resolve()
    try:
        data = read_toml(cfg_path)
    except ConfigError as exc:
        if exc.hint or cfg_path.suffix.lower() == ".toml":
            raise
        # e.g. `tribopipe batch run.csv`: an export given where a campaign config belongs
        raise ConfigError(exc.problem, path=exc.path,
                          hint="expected a campaign config (TOML, see configs/example.toml) "
                               "or a folder of exports") from None
    unknown_tables = sorted(set(data) - _TOP_LEVEL_TABLES)
    if unknown_tables:
        raise ConfigError(
            f"unknown table(s) {', '.join(unknown_tables)}; expected [campaign], "
            "optional [reduction] and [names]",
            path=cfg_path,
        )
    table = data.get("campaign")
    if not isinstance(table, dict):
        raise ConfigError(
            "missing [campaign] table", path=cfg_path, hint="see configs/example.toml"
        )
    reject_unknown_keys(table, _CAMPAIGN_KEYS, "campaign", cfg_path)
    base = cfg_path.parent

    def rel(key: str, default: str | None = None) -> Path | None:
        value = table.get(key, default)
        if value is None:
            return None
        _check_type(value, str, key, cfg_path)
        return (base / value).resolve()

    if "raw_dir" not in table:
        raise ConfigError("[campaign] raw_dir is required (folder of the raw exports)",
                          path=cfg_path)
    raw_dir = rel("raw_dir")
    assert raw_dir is not None
    if not raw_dir.is_dir():
        raise ConfigError(f"[campaign] raw_dir: folder {raw_dir} not found", path=cfg_path)

    # the instrument config's own [reduction] table, overridden key by key by ours
    instrument_path = rel("instrument")
    instrument_data = read_toml(instrument_path) if instrument_path is not None else {}
    merged = merge_tables(settings_tables(instrument_data, instrument_path),
                          settings_tables(data, cfg_path))
    try:
        settings = settings_from_dict(
            merged, source=str(instrument_path) if instrument_path else None
        )
    except ConfigError as exc:
        # a bad [reduction] key may be ours or the instrument file's: name both
        where = cfg_path if instrument_path is None else f"{cfg_path} (+ {instrument_path})"
        raise ConfigError(exc.problem, path=where, hint=exc.hint) from None

    names_table = data.get("names", {})
    if not isinstance(names_table, dict) or not all(
        isinstance(v, str) for v in names_table.values()
    ):
        raise ConfigError('[names] must map short names to full names, e.g. DS30 = '
                          '"Dragonskin 30"', path=cfg_path)

    output_dir = rel("output_dir") or (base.parent / DEFAULT_OUTPUT_DIR).resolve()
    map_path = rel("map") or OutputLayout(output_dir).map_path
    manifest = rel("manifest")
    if manifest is not None and not manifest.is_file():
        raise ConfigError(f"[campaign] manifest: file {manifest} not found", path=cfg_path)
    pattern = table.get("filename_pattern")
    if pattern is not None:
        _check_type(pattern, str, "filename_pattern", cfg_path)
        _compile_pattern(pattern, key="filename_pattern", path=cfg_path)
    use_export_names = _check_type(table.get("use_export_names", False), bool,
                                   "use_export_names", cfg_path)
    export_pattern = table.get("export_pattern", pattern if use_export_names else None)
    if export_pattern is not None:
        _check_type(export_pattern, str, "export_pattern", cfg_path)
        _compile_pattern(export_pattern, key="export_pattern", path=cfg_path)
    if use_export_names and export_pattern is None:
        raise ConfigError("[campaign] use_export_names needs export_pattern or filename_pattern",
                          path=cfg_path)
    if manifest is None and pattern is None and not use_export_names:
        raise ConfigError(
            "[campaign] no metadata source: set manifest, filename_pattern and/or "
            "use_export_names",
            path=cfg_path,
        )
    defaults = Tolerances()
    tolerances = Tolerances(
        force_N=_non_negative(table.get("force_tolerance_N", defaults.force_N),
                              "force_tolerance_N", cfg_path),
        force_rel=_non_negative(table.get("force_tolerance_rel", defaults.force_rel),
                                "force_tolerance_rel", cfg_path),
        temperature_C=_non_negative(
            table.get("temperature_tolerance_C", defaults.temperature_C),
            "temperature_tolerance_C", cfg_path,
        ),
    )
    glob = _check_type(table.get("glob", "*.csv"), str, "glob", cfg_path)
    name = _check_type(table.get("name", cfg_path.stem), str, "name", cfg_path)
    plots = _check_type(table.get("plots", True), bool, "plots", cfg_path)
    decimal = table.get("decimal")
    if decimal not in (None, ".", ","):
        raise ConfigError(f"[campaign] decimal must be '.' or ',', got {decimal!r}",
                          path=cfg_path)
    options = ReadOptions(
        encoding=_optional_str(table, "encoding", cfg_path),
        delimiter=_optional_str(table, "delimiter", cfg_path),
        decimal=decimal,
    )
    return Campaign(
        name=name,
        raw_dir=raw_dir,
        glob=glob,
        settings=settings,
        output_dir=output_dir,
        map_path=map_path,
        manifest=manifest,
        filename_pattern=pattern,
        use_export_names=use_export_names,
        export_pattern=export_pattern,
        names=tuple(sorted(names_table.items())),
        tolerances=tolerances,
        plots=plots,
        read_options=options,
        source=cfg_path,
    )


def _optional_str(table: Mapping[str, Any], key: str, path: Path) -> str | None:
    value = table.get(key)
    if value is None:
        return None
    _check_type(value, str, key, path)
    return "\t" if value.lower() in {"tab", "\\t"} else value


def folder_campaign(
    folder: str | Path,
    *,
    manifest: str | Path | None = None,
    filename_pattern: str | None = None,
    map_path: str | Path | None = None,
    output_dir: str | Path = DEFAULT_OUTPUT_DIR,
    glob: str = "*.csv",
    instrument: str | Path | None = None,
    plots: bool = True,
) -> Campaign:
    """A quick campaign without a config file: a folder of exports plus a manifest CSV
    and/or a file-name pattern, reduced with an instrument config (default T-PID/44).

    Relative paths are taken relative to the current directory.
    """
    from .config import load_settings

    raw_dir = Path(folder).resolve()
    if not raw_dir.is_dir():
        raise CampaignError("folder not found", path=folder)
    manifest_path = None if manifest is None else Path(manifest).resolve()
    if manifest_path is not None and not manifest_path.is_file():
        raise CampaignError("manifest not found", path=manifest)
    if manifest_path is None and filename_pattern is None:
        raise CampaignError(
            "no metadata source for the runs", path=folder,
            hint="pass --manifest FILE.csv (columns file, pin, disc, normal_force_N, "
                 "temperature_C, repeat) or --pattern",
        )
    if filename_pattern is not None:
        _compile_pattern(filename_pattern, key="pattern", path=None)
    out = Path(output_dir).resolve()
    return Campaign(
        name=raw_dir.name,
        raw_dir=raw_dir,
        glob=glob,
        settings=load_settings(instrument),
        output_dir=out,
        map_path=Path(map_path).resolve() if map_path else OutputLayout(out).map_path,
        manifest=manifest_path,
        filename_pattern=filename_pattern,
        plots=plots,
    )


# --------------------------------------------------------------------------- metadata


def _compile_pattern(pattern: str, *, key: str, path: Path | None) -> re.Pattern[str]:
    """Turn ``{pin}_{disc}_{force}N_{temperature}C_r{repeat}`` into an anchored regex.

    Known placeholders (``pin, disc, force, temperature, repeat`` and the label names) are
    captured; any other ``{name}`` matches text that is ignored.
    """
    parts: list[str] = []
    seen: set[str] = set()
    pos = 0
    for match in re.finditer(r"\{([A-Za-z_][A-Za-z0-9_]*)\}", pattern):
        parts.append(re.escape(pattern[pos : match.start()]))
        name = match.group(1)
        target = PATTERN_FIELDS.get(name)
        if target is None:
            parts.append(".+?")
        else:
            if target in seen:
                raise ConfigError(f"[campaign] {key}: placeholder {{{name}}} used twice",
                                  path=path)
            seen.add(target)
            parts.append(f"(?P<{target}>{_PATTERN_REGEX.get(target, '.+?')})")
        pos = match.end()
    parts.append(re.escape(pattern[pos:]))
    if "{" in pattern[pos:] or not seen:
        raise ConfigError(
            f"[campaign] {key} {pattern!r} has no usable placeholder",
            path=path,
            hint="use {pin}, {disc}, {force}, {temperature}, {repeat}",
        )
    return re.compile("".join(parts), re.IGNORECASE)


@functools.lru_cache(maxsize=32)
def _pattern_regex(pattern: str) -> re.Pattern[str]:
    # a campaign matches one pattern against every file: build its regex once
    return _compile_pattern(pattern, key="pattern", path=None)


def _parse_number(text: str) -> float:
    # file names cannot hold '.' comfortably in every lab: accept 0p5 and 0,5 too
    return float(text.strip().replace(",", ".").replace("p", "."))


def match_pattern(pattern: str, text: str) -> dict[str, Any] | None:
    """The label fields a pattern finds in ``text`` (e.g. a file stem), or ``None`` if the
    text does not match. Forces are in N, temperatures in °C, repeat an int."""
    regex = _pattern_regex(pattern)
    m = regex.fullmatch(text.strip())
    if m is None:
        return None
    found: dict[str, Any] = {}
    for key, value in m.groupdict().items():
        if key == "repeat":
            found[key] = int(value)
        elif key in ("normal_force_N", "temperature_C"):
            found[key] = _parse_number(value)
        else:
            found[key] = value.strip()
    return found


@dataclass(frozen=True)
class ManifestRow:
    """One manifest row: the label fields it gives (``None`` cells left out) and its line."""

    line: int
    fields: dict[str, Any]
    problem: str | None = None


def read_manifest(path: str | Path) -> dict[str, ManifestRow]:
    """Read a manifest CSV: one row per file, columns ``file, pin, disc, normal_force_N,
    temperature_C, repeat`` (more allowed, ignored; empty cells mean unknown).

    Comma or semicolon separated (semicolon files may use a decimal comma). Returns
    ``{file as written: ManifestRow}``. A missing column or duplicate file is a
    :class:`ConfigError` naming the manifest; a bad value is recorded as that row's
    ``problem`` (an error for that file only).
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError:
        text = p.read_text(encoding="cp1252")
    except OSError as exc:
        raise ConfigError(f"cannot read manifest: {exc.strerror or exc}", path=p) from None
    first = text.split("\n", 1)[0]
    delimiter = ";" if first.count(";") > first.count(",") else ","
    reader = csv.reader(io.StringIO(text), delimiter=delimiter)
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
    rows: dict[str, ManifestRow] = {}
    for lineno, cells in enumerate(reader, start=2):
        if not any(c.strip() for c in cells):
            continue
        cells = cells + [""] * (len(header) - len(cells))
        file = cells[index["file"]].strip()
        if not file:
            raise ConfigError("empty 'file' cell", path=p, line=lineno, column="file")
        key = file.replace("\\", "/")
        if key in rows:
            raise ConfigError(
                f"file {file!r} listed twice (first on line {rows[key].line})",
                path=p, line=lineno, column="file",
            )
        fields: dict[str, Any] = {}
        problem = None
        for name in LABEL_FIELDS:
            raw = cells[index[name]].strip()
            if not raw:
                continue
            try:
                if name == "repeat":
                    number = _parse_number(raw)
                    if not number.is_integer() or number < 0:
                        raise ValueError
                    fields[name] = int(number)
                elif name in ("normal_force_N", "temperature_C"):
                    value = _parse_number(raw)
                    if not math.isfinite(value):
                        raise ValueError
                    fields[name] = value
                else:
                    fields[name] = raw
            except ValueError:
                kind = "a whole number" if name == "repeat" else "a number"
                problem = f"{p}:{lineno}: {raw!r} is not {kind} (column {name!r})"
        rows[key] = ManifestRow(line=lineno, fields=fields, problem=problem)
    return rows


def _same(field_name: str, a: Any, b: Any, campaign: Campaign) -> bool:
    if field_name in ("pin", "disc"):
        return campaign.alias(str(a)).casefold() == campaign.alias(str(b)).casefold()
    return math.isclose(float(a), float(b), rel_tol=1e-9, abs_tol=1e-9)


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
                value = campaign.alias(str(value))
            if key in merged:
                if not _same(key, merged[key], value, campaign):
                    raise CampaignError(
                        f"contradictory {key}: {origin[key]} says {merged[key]!r}, "
                        f"{source} says {value!r}",
                        path=file,
                        hint="fix the manifest or rename the file",
                    )
                continue
            merged[key] = value
            origin[key] = source
    return merged


def labels_from(file: str, merged: Mapping[str, Any], *, hints: Sequence[str] = ()) -> RunLabels:
    """Build :class:`RunLabels` from merged fields; :class:`CampaignError` when a required
    field (pin, disc, normal_force_N, temperature_C) is missing."""
    missing = [f for f in REQUIRED_FIELDS if merged.get(f) is None]
    if missing:
        hint = "; ".join(hints) if hints else "add the file to the manifest"
        raise CampaignError(f"metadata missing: {', '.join(missing)}", path=file, hint=hint)
    return RunLabels(
        pin=str(merged["pin"]),
        disc=str(merged["disc"]),
        normal_force_N=float(merged["normal_force_N"]),
        temperature_C=float(merged["temperature_C"]),
        repeat=None if merged.get("repeat") is None else int(merged["repeat"]),
    )


# --------------------------------------------------------------------------- the table


@dataclass(frozen=True)
class CampaignRow:
    """One file of a campaign: its metadata (as known before reading it) and status.

    ``sources`` are the metadata sources consulted so far (name, fields) in priority order;
    ``problem`` is a metadata error known before reading; ``status`` is one of
    ``new, reduced, changed, failed``; ``reason`` why a run failed (last batch or now);
    ``previous`` the file's entry in the state; ``hints`` why a source said nothing.
    """

    file: str
    path: Path
    size: int
    mtime_ns: int
    sources: tuple[tuple[str, dict[str, Any]], ...]
    merged: dict[str, Any]
    problem: str | None
    status: str
    reason: str | None = None
    sha256: str | None = None
    previous: dict[str, Any] | None = None
    hints: tuple[str, ...] = ()

    @property
    def labels(self) -> RunLabels:
        """The nominal labels known before reading (missing fields are ``None``)."""
        m = self.merged
        return RunLabels(
            pin=m.get("pin"), disc=m.get("disc"), normal_force_N=m.get("normal_force_N"),
            temperature_C=m.get("temperature_C"), repeat=m.get("repeat"),
        )


def discover_files(campaign: Campaign) -> list[Path]:
    """The campaign's raw exports: ``raw_dir`` globbed, sorted, without the manifest,
    hidden files and folders."""
    manifest = campaign.manifest
    files = [
        p for p in campaign.raw_dir.glob(campaign.glob)
        if p.is_file() and not p.name.startswith(".")
        # resolving costs a few syscalls per file: only when there is a manifest to skip
        and (manifest is None or p.resolve() != manifest)
    ]
    return sorted(files, key=lambda p: p.relative_to(campaign.raw_dir).as_posix())


def recipe_hash(campaign: Campaign, merged: Mapping[str, Any]) -> str:
    """Hash of everything besides the raw bytes that a run's record depends on: the
    settings' config hash, the labels known before reading, the QC tolerances and the
    export-name rules (16 hex digits)."""
    payload = {"campaign": _campaign_key(campaign),
               "labels": {k: merged.get(k) for k in LABEL_FIELDS}}
    text = json.dumps(payload, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


@functools.lru_cache(maxsize=8)
def _campaign_key(campaign: Campaign) -> str:
    # the part of recipe_hash shared by every run of a campaign, computed once per campaign
    payload = {
        "config": campaign.settings.config_hash,
        "tolerances": asdict(campaign.tolerances),
        # the labels in recipe_hash already carry the [names] aliases, except those read
        # from export names, so the aliases only matter with use_export_names
        "export_names": [campaign.export_pattern, list(campaign.names)]
        if campaign.use_export_names else None,
        "read": asdict(campaign.read_options),
    }
    return hashlib.sha256(json.dumps(payload, sort_keys=True, default=str).encode()).hexdigest()


def _relative(path: Path, root: Path) -> str:
    return path.relative_to(root).as_posix()


def campaign_table(campaign: Campaign, *, state: Mapping[str, Any] | None = None
                   ) -> list[CampaignRow]:
    """The campaign as a table, before anything runs: one row per file with its metadata
    and status (``new, reduced, changed, failed``).

    A file counts as ``reduced`` when its content (SHA-256, trusted from the state while
    size and ``mtime_ns`` are unchanged) and its recipe hash match the last successful
    batch and its trace still exists; ``failed`` when the same holds for a failed run or
    its metadata is already known to be wrong. ``state`` defaults to the campaign's state
    file.
    """
    entries = (state if state is not None else load_state(campaign)).get("entries", {})
    manifest = read_manifest(campaign.manifest) if campaign.manifest else {}
    rows: list[CampaignRow] = []
    for path in discover_files(campaign):
        rel = _relative(path, campaign.raw_dir)
        st = path.stat()
        sources: list[tuple[str, dict[str, Any]]] = []
        hints: list[str] = []
        problem: str | None = None
        if campaign.manifest is not None:
            row = manifest.get(rel) or manifest.get(path.name)
            if row is None:
                hints.append(f"no row for it in manifest {campaign.manifest.name}")
            else:
                sources.append((f"manifest line {row.line}", dict(row.fields)))
                problem = row.problem
        if campaign.filename_pattern is not None:
            found = match_pattern(campaign.filename_pattern, path.stem)
            if found is None:
                hints.append(f"name does not match pattern {campaign.filename_pattern!r}")
            else:
                sources.append(("file name", found))
        merged: dict[str, Any] = {}
        if problem is None:
            try:
                merged = merge_metadata(rel, sources, campaign)
                if not campaign.use_export_names:
                    labels_from(rel, merged, hints=hints)
            except CampaignError as exc:
                problem = str(exc)
        previous = entries.get(rel)
        sha = None
        status = NEW
        reason = None
        if previous is not None:
            same_stat = previous.get("size") == st.st_size and \
                previous.get("mtime_ns") == st.st_mtime_ns
            sha = previous.get("sha256") if same_stat else file_sha256(path)
            same = sha is not None and sha == previous.get("sha256") and \
                previous.get("recipe") == recipe_hash(campaign, merged)
            if same and previous.get("status") == REDUCED:
                trace = previous.get("trace")
                status = REDUCED if trace and (campaign.output_dir / trace).is_file() \
                    else CHANGED
            elif same and previous.get("status") == FAILED:
                status, reason = FAILED, previous.get("reason")
            else:
                status = CHANGED
        if problem is not None:
            status, reason = FAILED, problem
        rows.append(CampaignRow(
            file=rel, path=path, size=st.st_size, mtime_ns=st.st_mtime_ns,
            sources=tuple(sources), merged=merged, problem=problem, status=status,
            reason=reason, sha256=sha, previous=previous, hints=tuple(hints),
        ))
    return rows


# --------------------------------------------------------------------------- state


def load_state(campaign: Campaign) -> dict[str, Any]:
    """The incremental state of a campaign (empty when there is none or it is unreadable:
    a lost state only costs a full re-run)."""
    try:
        data = json.loads(campaign.state_path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {"version": STATE_VERSION, "entries": {}}
    if not isinstance(data, dict) or data.get("version") != STATE_VERSION or \
            not isinstance(data.get("entries"), dict):
        return {"version": STATE_VERSION, "entries": {}}
    return data


def save_state(campaign: Campaign, state: Mapping[str, Any]) -> None:
    """Write the incremental state atomically (temporary file + rename)."""
    write_text_atomic(campaign.state_path, json.dumps(state, indent=1, sort_keys=True))


# --------------------------------------------------------------------------- workers


@dataclass(frozen=True)
class _Job:
    file: str
    path: str
    sources: tuple[tuple[str, dict[str, Any]], ...]
    hints: tuple[str, ...]


@dataclass(frozen=True)
class _Context:
    campaign: Campaign
    plots: bool


def _reduce_one(job: _Job, ctx: _Context) -> dict[str, Any]:
    """Reduce one file in a worker; returns a small picklable result (never the trace)."""
    campaign = ctx.campaign
    merged = merge_metadata(job.file, job.sources, campaign)
    if campaign.use_export_names:
        outcome = _reduce_with_export_names(job, campaign, merged)
    else:
        labels = labels_from(job.file, merged, hints=job.hints)
        outcome = reduce_file(job.path, campaign.settings, labels, campaign.read_options,
                              tolerances=campaign.tolerances)
    result = outcome.result
    record = outcome.record
    trace = write_trace(campaign.output_dir, outcome)
    plot_note = _plot(campaign, outcome) if ctx.plots else None
    return {
        "file": job.file,
        "ok": True,
        "record": record,
        "labels": asdict(outcome.labels),
        "measurement_id": record.get("measurement_id"),
        "sha256": outcome.file_hash,
        "trace": trace.relative_to(campaign.output_dir).as_posix(),
        "mu_s": finite_or_none(result.mu_s),
        "mu_k": finite_or_none(result.mu_k),
        "pressure_kPa": finite_or_none(record.get("pressure_kPa")),
        "pressure_measured_kPa": finite_or_none(result.pressure_kPa),
        "normal_force_measured_N": finite_or_none(result.normal_force_mean_N),
        "temperature_measured_C": finite_or_none(result.temperature_C),
        "flags": record["flags"],
        "plot_note": plot_note,
    }


def _reduce_with_export_names(job: _Job, campaign: Campaign, merged: Mapping[str, Any]
                              ) -> RunOutcome:
    """:func:`tribopipe.pipeline.reduce_file` with the export's Test name as a third
    metadata source: the labels are only complete once the file has been read."""
    partial = RunLabels(**{k: merged.get(k) for k in LABEL_FIELDS})
    outcome = reduce_file(job.path, campaign.settings, partial, campaign.read_options)
    meta = outcome.measurement.meta
    sources = list(job.sources)
    hints = list(job.hints)
    found = match_pattern(campaign.export_pattern or "", meta.test) if meta.test else None
    if found is None:
        hints.append(f"export Test name {meta.test!r} does not match pattern "
                     f"{campaign.export_pattern!r}")
    else:
        sources.append((f"export Test name {meta.test!r}", found))
    labels = labels_from(job.file, merge_metadata(job.file, sources, campaign), hints=hints)
    record = make_record(result=outcome.result, labels=labels, meta=meta,
                         file_hash=outcome.file_hash, settings=campaign.settings,
                         tolerances=campaign.tolerances)
    return replace(outcome, labels=labels, record=record)


def _plot(campaign: Campaign, outcome: RunOutcome) -> str | None:
    """Draw a run's trace plot beside its trace; returns a note when it could not."""
    try:
        plot_run(campaign.layout, outcome)
    except Exception as exc:  # noqa: BLE001 - a picture must not cost the run its map row
        return f"{Path(outcome.path).name}: trace plot failed ({type(exc).__name__}: {exc})"
    return None


#: Cyclic-GC thresholds while reducing. Parsing an export allocates ~10⁵ short-lived
#: containers (cells, rows), which with the default gen-0 threshold (700) triggers hundreds
#: of collections per file that find nothing; measured: −20 % CPU per run.
GC_THRESHOLDS = (100_000, 50, 100)


def _worker_init() -> None:
    """Start a worker process (ours for its whole life): fewer garbage-collector passes."""
    gc.set_threshold(*GC_THRESHOLDS)


@contextlib.contextmanager
def _fewer_gc_passes() -> Iterator[None]:
    """:func:`_worker_init`'s tuning for an in-process batch, restored afterwards."""
    before = gc.get_threshold()
    gc.set_threshold(*GC_THRESHOLDS)
    try:
        yield
    finally:
        gc.set_threshold(*before)


def _reason(exc: TribopipeError, job: _Job) -> str:
    """The one-line reason of a failed run, starting with the file's campaign-relative
    name (readers name the absolute path, which is long and machine-specific)."""
    text = str(exc)
    if exc.path is None:
        return f"{job.file}: {text}"
    if exc.path == job.path and text.startswith(exc.path):
        return job.file + text[len(exc.path):]
    return text


def _reduce_chunk(jobs: Sequence[_Job], ctx: _Context) -> list[dict[str, Any]]:
    """Reduce a chunk of files; each failure is caught and returned with its reason."""
    out: list[dict[str, Any]] = []
    for job in jobs:
        try:
            out.append(_reduce_one(job, ctx))
        except TribopipeError as exc:
            out.append({"file": job.file, "ok": False, "reason": _reason(exc, job)})
        except OSError as exc:
            out.append({"file": job.file, "ok": False,
                        "reason": f"{job.file}: cannot read: {exc.strerror or exc}"})
        except Exception as exc:  # noqa: BLE001 - one broken file must not stop a campaign
            out.append({"file": job.file, "ok": False, "transient": True,
                        "reason": f"{job.file}: internal error {type(exc).__name__}: {exc} "
                                  "(please report with the file)"})
    return out


# --------------------------------------------------------------------------- batch


@dataclass(frozen=True)
class BatchReport:
    """What a batch did.

    ``reduced``/``skipped``: files reduced now / unchanged since the last batch;
    ``failures``: ``(file, reason)`` of every run that failed now or earlier and is
    unchanged; ``groups_updated``: condition groups (pin, disc, force, temperature) with a
    map row added, replaced or removed; ``removed``: map rows dropped because their raw
    file changed; ``map_summary``: the map's own account; ``notes``: things worth saying
    that are not failures (plots skipped, files gone from the folder); ``flagged``:
    ``(file, flags)`` of the runs reduced now that carry QC flags (";"-joined).
    """

    campaign: str
    total: int
    reduced: list[str]
    skipped: list[str]
    failures: list[tuple[str, str]]
    groups_updated: int
    removed: int
    map_path: Path
    map_summary: str
    output_dir: Path
    notes: list[str]
    flagged: list[tuple[str, str]] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        """True when no file failed."""
        return not self.failures

    def summary(self) -> str:
        """One line: runs reduced, skipped, failed, groups updated."""
        text = (f"{self.campaign}: {self.total} run(s): {len(self.reduced)} reduced, "
                f"{len(self.skipped)} skipped (unchanged), {len(self.failures)} failed; "
                f"{self.groups_updated} condition group(s) updated")
        if self.removed:
            text += f"; {self.removed} stale map row(s) removed"
        return text


def _chunks(items: Sequence[Any], workers: int) -> list[list[Any]]:
    """``items`` cut into a few chunks per worker: small enough to balance, large enough to
    amortise pickling (the benchmark's parse-only pool uses the same cut)."""
    size = max(1, min(16, math.ceil(len(items) / (workers * 4))))
    return [list(items[i : i + size]) for i in range(0, len(items), size)]


def default_jobs() -> int:
    """Worker processes to use: the CPUs this process may run on."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not Linux
        return max(1, os.cpu_count() or 1)


def run_campaign(
    campaign: Campaign,
    *,
    jobs: int | None = None,
    plots: bool | None = None,
    progress: ProgressCallback | None = None,
) -> BatchReport:
    """Reduce every new or changed run of a campaign, in parallel, and update its map once.

    Writes to ``campaign.output_dir``: ``traces/*.parquet``, ``plots/traces/*.png`` (when
    plots are on and available; only for runs reduced now), ``runs.csv`` (one row per
    file), ``failures.csv`` (``file,reason``) and the state file; appends the new records
    to ``campaign.map_path`` in one atomic update (replacing the rows of changed runs).
    ``progress(done, total)`` is called as runs finish. Failures of single runs never
    raise: they are in the report. Raises :class:`CampaignError` when another batch of
    the same campaign is running, :class:`MapError` when the map path holds a foreign file.
    """
    from filelock import FileLock, Timeout

    campaign.output_dir.mkdir(parents=True, exist_ok=True)
    lock = FileLock(str(campaign.layout.batch_lock), timeout=0)
    try:
        with lock:
            return _run_locked(campaign, jobs=jobs, plots=plots, progress=progress)
    except Timeout:
        raise CampaignError(
            "another batch of this campaign is running (its output folder is locked)",
            path=campaign.output_dir, hint="wait for it to finish",
        ) from None


def _run_locked(campaign: Campaign, *, jobs: int | None, plots: bool | None,
                progress: ProgressCallback | None) -> BatchReport:
    """:func:`run_campaign` while holding the output folder's batch lock."""
    jobs = default_jobs() if jobs is None else max(1, int(jobs))
    plots = campaign.plots if plots is None else plots
    state = load_state(campaign)
    entries: dict[str, Any] = dict(state.get("entries", {}))
    missing_ids, map_checked = _ids_missing_from_map(campaign, state)
    rows = campaign_table(campaign, state=state)
    todo: list[_Job] = []
    skipped: list[str] = []
    failures: dict[str, str] = {}
    for row in rows:
        if row.problem is not None:
            failures[row.file] = row.problem
        elif row.status == REDUCED and (row.previous or {}).get("measurement_id") \
                not in missing_ids:
            skipped.append(row.file)
        elif row.status == FAILED:
            # unchanged and failed before: do not retry, keep it listed
            failures[row.file] = row.reason or "failed in an earlier batch"
        else:
            todo.append(_Job(file=row.file, path=str(row.path), sources=row.sources,
                             hints=row.hints))
    by_file = {row.file: row for row in rows}
    done = len(rows) - len(todo)
    total = len(rows)
    if progress:
        progress(done, total)

    if todo and not map_checked and campaign.map_path.exists():
        read_map(campaign.map_path)  # refuse a foreign or corrupt map before any work
    ctx = _Context(campaign=campaign, plots=plots)
    results: list[dict[str, Any]] = []
    if todo:
        workers = min(jobs, len(todo))
        chunks = _chunks(todo, workers)
        if workers == 1:
            with _fewer_gc_passes():
                for chunk in chunks:
                    results.extend(_reduce_chunk(chunk, ctx))
                    done += len(chunk)
                    if progress:
                        progress(done, total)
        else:
            from concurrent.futures import ProcessPoolExecutor, as_completed

            with ProcessPoolExecutor(max_workers=workers, initializer=_worker_init) as pool:
                futures = {pool.submit(_reduce_chunk, chunk, ctx): chunk for chunk in chunks}
                for future in as_completed(futures):
                    try:
                        part = future.result()
                    except Exception as exc:  # noqa: BLE001 - e.g. a worker killed (OOM)
                        part = [{"file": job.file, "ok": False,
                                 "reason": f"{job.file}: worker process failed "
                                           f"({type(exc).__name__}: {exc}); run again",
                                 "transient": True}
                                for job in futures[future]]
                    results.extend(part)
                    done += len(part)
                    if progress:
                        progress(done, total)

    notes: list[str] = []
    if not rows:
        notes.append(f"no file matches {campaign.glob!r} in {campaign.raw_dir}")
    records: list[dict[str, Any]] = []
    stale_ids: set[str] = set()
    reduced: list[str] = []
    flagged: list[tuple[str, str]] = []
    config_hash = campaign.settings.config_hash  # hashes the settings: once, not per run
    for res in sorted(results, key=lambda r: r["file"]):
        row = by_file[res["file"]]
        old = entries.get(row.file) or {}
        old_id = old.get("measurement_id") if old.get("status") == REDUCED else None
        base = {
            "size": row.size, "mtime_ns": row.mtime_ns, "config_hash": config_hash,
            "recipe": recipe_hash(campaign, row.merged),
        }
        if res["ok"]:
            reduced.append(row.file)
            records.append(res["record"])
            if res["record"].get("flags"):
                flagged.append((row.file, res["record"]["flags"]))
            if old_id and old_id != res["measurement_id"]:
                stale_ids.add(old_id)
            if res.get("plot_note") and res["plot_note"] not in notes:
                notes.append(res["plot_note"])
            entries[row.file] = {
                **base, "sha256": res["sha256"], "status": REDUCED,
                **{k: res[k] for k in _SUMMARY_KEYS},
            }
        elif res.get("transient"):
            # not the file's fault: listed now, retried next time (the state is left as is)
            failures[row.file] = res["reason"]
        else:
            failures[row.file] = res["reason"]
            if old_id:
                stale_ids.add(old_id)
            entries[row.file] = {
                **base, "sha256": row.sha256 or file_sha256(row.path), "status": FAILED,
                "reason": res["reason"],
            }
    # files that vanished from the folder leave the state (their map rows stay)
    present = set(by_file)
    for gone in sorted(set(entries) - present):
        if entries[gone].get("status") == REDUCED:
            notes.append(f"{gone}: no longer in {campaign.raw_dir}; its map row is kept")
        del entries[gone]

    map_summary = "unchanged"
    removed: set[str] = set()
    landed: set[str] = set()
    if records or stale_ids:
        map_summary, landed, removed = _update_map(campaign, records, stale_ids)
    # a group is updated when one of its rows was added, replaced or removed
    old_groups = {
        _group_key(e.get("labels") or {}) for e in state.get("entries", {}).values()
        if e.get("measurement_id") in removed
    }
    groups = {
        _group_key(r) for r in records if r.get("measurement_id") in landed
    } | old_groups
    new_state = {"version": STATE_VERSION, "campaign": campaign.name, "entries": entries}
    if campaign.map_path.exists():
        st = campaign.map_path.stat()
        new_state["map"] = {"size": st.st_size, "mtime_ns": st.st_mtime_ns}
    save_state(campaign, new_state)

    this_batch = {f: REDUCED for f in reduced} | {f: SKIPPED for f in skipped} | {
        f: FAILED for f in failures
    }
    _write_runs_csv(campaign, rows, entries, this_batch, failures)
    _write_failures_csv(campaign, failures)
    return BatchReport(
        campaign=campaign.name,
        total=total,
        reduced=reduced,
        skipped=skipped,
        failures=sorted(failures.items()),
        groups_updated=len(groups),
        removed=len(removed),
        map_path=campaign.map_path,
        map_summary=map_summary,
        output_dir=campaign.output_dir,
        notes=notes,
        flagged=flagged,
    )


_SUMMARY_KEYS = (
    "labels", "measurement_id", "trace", "mu_s", "mu_k", "pressure_kPa",
    "pressure_measured_kPa", "normal_force_measured_N", "temperature_measured_C", "flags",
)


def _ids_missing_from_map(campaign: Campaign, state: Mapping[str, Any]) -> tuple[set[str], bool]:
    """The measurement ids of runs the state calls reduced that are not in the map (so
    they must land again), and whether the map was read (and so validated) to tell.

    A map whose size and ``mtime_ns`` are those the last batch left is trusted without
    reading it; a missing map misses every run.
    """
    entries = state.get("entries", {})
    ids = {e.get("measurement_id") for e in entries.values() if e.get("status") == REDUCED}
    ids.discard(None)
    if not ids:
        return set(), False
    if not campaign.map_path.exists():
        return ids, False
    st = campaign.map_path.stat()
    seen = state.get("map") or {}
    if seen.get("size") == st.st_size and seen.get("mtime_ns") == st.st_mtime_ns:
        return set(), False
    present = set(read_map(campaign.map_path)["measurement_id"].astype(str))
    return ids - present, True


def _update_map(campaign: Campaign, records: list[dict[str, Any]],
                stale_ids: set[str]) -> tuple[str, set[str], set[str]]:
    """Fold the new records into the map and drop the rows of runs whose raw file changed
    (their measurement id changed with the content), under the map's lock, in one atomic
    write. Returns the map's summary line, the ids added or replaced, and the ids removed.
    """
    report = update_map(campaign.map_path, records, replace=True, drop_ids=sorted(stale_ids))
    return (report.summary(), set(report.added_ids) | set(report.replaced_ids),
            set(report.dropped_ids))


def _group_key(row: Mapping[str, Any]) -> tuple[Any, ...]:
    """The condition group of a record or label dict: pin, disc, nominal F [N], T [°C]."""
    return (row.get("pin"), row.get("disc"), row.get("normal_force_N"), row.get("temperature_C"))


# --------------------------------------------------------------------------- outputs

RUNS_COLUMNS: tuple[str, ...] = (
    "file", "status", "pin", "disc", "normal_force_N", "temperature_C", "repeat", "mu_s",
    "mu_k", "pressure_kPa", "normal_force_measured_N", "pressure_measured_kPa",
    "temperature_measured_C", "flags", "measurement_id", "trace", "reason",
)


def _cell(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return "" if not math.isfinite(value) else repr(round(value, 6))
    return str(value)


def _write_runs_csv(campaign: Campaign, rows: Sequence[CampaignRow],
                    entries: Mapping[str, Any], this_batch: Mapping[str, str],
                    failures: Mapping[str, str]) -> None:
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(RUNS_COLUMNS)
    for row in rows:
        entry = entries.get(row.file) or {}
        status = this_batch.get(row.file, FAILED)
        ok = entry.get("status") == REDUCED and status != FAILED
        labels = entry.get("labels") if ok else None
        labels = labels or {k: row.merged.get(k) for k in LABEL_FIELDS}
        values = {
            "file": row.file, "status": status, **labels,
            **({k: entry.get(k) for k in _SUMMARY_KEYS if k != "labels"} if ok else {}),
            "reason": failures.get(row.file),
        }
        writer.writerow([_cell(values.get(c)) for c in RUNS_COLUMNS])
    write_text_atomic(campaign.runs_csv, buf.getvalue())


def _write_failures_csv(campaign: Campaign, failures: Mapping[str, str]) -> None:
    write_failures(campaign.failures_csv, failures)


def campaign_listing(campaign: Campaign) -> list[dict[str, Any]]:
    """The campaign table as JSON-ready dicts, for ``tribopipe campaign list``.

    Keys: ``file, status, pin, disc, normal_force_N, temperature_C, repeat, mu_s, mu_k,
    flags, measurement_id, sources, reason``. Labels of reduced runs come from the last
    batch (so they include fields read from export names); μ values only for reduced runs.
    """
    out: list[dict[str, Any]] = []
    for row in campaign_table(campaign):
        entry = row.previous or {}
        reduced = row.status == REDUCED
        labels = (entry.get("labels") if reduced else None) or {
            k: row.merged.get(k) for k in LABEL_FIELDS
        }
        out.append({
            "file": row.file,
            "status": row.status,
            **{k: labels.get(k) for k in LABEL_FIELDS},
            "mu_s": entry.get("mu_s") if reduced else None,
            "mu_k": entry.get("mu_k") if reduced else None,
            "flags": entry.get("flags") if reduced else None,
            "measurement_id": entry.get("measurement_id") if reduced else None,
            "sources": [name for name, _ in row.sources],
            "reason": row.reason,
        })
    return out
