"""A campaign's description: its config file (or a folder + options) as a :class:`Campaign`.

The keys of the ``[campaign]`` table are described in :mod:`tribopipe.campaign`; the
``[reduction]`` table overrides the instrument config's key by key through
:func:`tribopipe.config.merge_tables`, the same merge every instrument file goes through.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath, PureWindowsPath
from typing import Any

from ..config import (
    Settings,
    load_settings,
    merge_tables,
    read_toml,
    reject_unknown_keys,
    settings_from_dict,
    settings_tables,
)
from ..errors import CampaignError, ConfigError, ValidationError
from ..escape import display_path
from ..labels import LABEL_FORCE_REL, LabelCheck, Tolerances
from ..layout import DEFAULT_OUTPUT_DIR, OutputLayout
from ..materials import Vocabulary, lab_files, load_vocabulary, shipped_vocabulary
from ..pipeline.runs import ReadOptions
from ..readers import EXPORT_SUFFIXES
from ..readers.textio import foreign_kind
from ..reporting import NAMES as REPORTING_NAMES
from ..reporting import RunReport, parse_item
from ..validate import MAX_NAME_CHARS, check_name, text_problem
from .patterns import compile_pattern

_CAMPAIGN_KEYS = frozenset(
    {
        "name", "raw_dir", "glob", "instrument", "output_dir", "map", "manifest",
        "filename_pattern", "test_pattern", "use_export_names", "export_pattern",
        "force_tolerance_N", "force_tolerance_rel", "temperature_tolerance_C",
        "speed_tolerance_rel", "plots", "encoding", "delimiter", "decimal", "synthetic",
        "materials", "keep_labels", "label_force_tolerance_rel",
        "review",
    }
)
_TOP_LEVEL_TABLES = frozenset({"campaign", "reduction", "names", "metadata"})


@dataclass(frozen=True)
class Campaign:
    """A campaign's description: where its files are, how to label and reduce them.

    All paths are absolute (resolved against the config file's folder). ``glob`` ``None``
    takes every export the readers know (:data:`tribopipe.readers.EXPORT_SUFFIXES`, any
    case); ``test_pattern`` is matched against each test's Test name.
    """

    name: str
    raw_dir: Path
    glob: str | None
    settings: Settings
    output_dir: Path
    map_path: Path
    manifest: Path | None = None
    filename_pattern: str | None = None
    test_pattern: str | None = None
    names: tuple[tuple[str, str], ...] = ()
    tolerances: Tolerances = field(default_factory=Tolerances)
    plots: bool = True
    #: the exports are synthetic (a demo): every run is flagged ``synthetic`` in the map
    synthetic: bool = False
    read_options: ReadOptions = field(default_factory=ReadOptions)
    source: Path | None = None
    #: the materials vocabulary: the shipped one, extended by the lab's files
    #: (``materials.toml`` beside the config, ``[campaign] materials``)
    vocabulary: Vocabulary = field(default_factory=shipped_vocabulary)
    #: the reporting items of every run (``[metadata]``); a manifest cell overrides them
    report: RunReport = field(default_factory=RunReport)
    #: how the labels are checked against each export (``keep_labels``,
    #: ``label_force_tolerance_rel``)
    label_check: LabelCheck = field(default_factory=LabelCheck)
    #: the lab's decisions file (``review.csv``, :mod:`tribopipe.review`), applied on every
    #: batch; ``None``: the map's rows keep the reviews they hold
    review: Path | None = None

    @property
    def use_export_names(self) -> bool:
        """True when the Test names are a metadata source (a test-name pattern is set)."""
        return self.test_pattern is not None

    @property
    def export_pattern(self) -> str | None:
        """The test-name pattern under its older name."""
        return self.test_pattern

    @property
    def layout(self) -> OutputLayout:
        """The paths of the output folder (:class:`tribopipe.layout.OutputLayout`)."""
        return OutputLayout(self.output_dir)

    @property
    def state_path(self) -> Path:
        """The incremental state file: ``<output_dir>/.tribopipe-state.<name>.sqlite``
        (the name reduced to letters, digits, ``-`` and ``_``)."""
        return self.layout.state_path(self.name)

    @property
    def legacy_state_path(self) -> Path:
        """The JSON state older versions wrote (read once, then converted)."""
        return self.layout.legacy_state_path(self.name)

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


def glob_problem(pattern: Any) -> str | None:
    """Why ``pattern`` cannot select a campaign's exports below its raw folder, or
    ``None``: it must be non-empty text, relative, without ``..`` and on one line."""
    if not isinstance(pattern, str) or not pattern.strip():
        return f"expected a file pattern such as '*.csv', got {pattern!r}"
    if not pattern.isprintable():
        return "expected one line of printable text"
    if PurePosixPath(pattern).is_absolute() or PureWindowsPath(pattern).is_absolute() or \
            PureWindowsPath(pattern).drive or pattern.startswith(("/", "\\")):
        return f"expected a pattern relative to raw_dir, got the absolute {pattern!r}"
    if ".." in PurePosixPath(pattern.replace("\\", "/")).parts:
        return f"expected a pattern below raw_dir, got {pattern!r} (with '..')"
    return None


def _output_folder_problem(folder: Path) -> str | None:
    """Why ``folder`` cannot be an output folder (it exists and is not a folder)."""
    try:
        if folder.exists() and not folder.is_dir():
            return f"{folder} exists and is not a folder"
    except OSError as exc:
        return f"{folder}: {exc.strerror or exc}"
    return None


def _foreign_kind(path: Path) -> str | None:
    """What a file given as a config is when its first bytes say it is a document, an
    image or an archive (:func:`tribopipe.readers.textio.foreign_kind`), else ``None``."""
    if not path.is_file():  # never open a FIFO or a device
        return None
    try:
        with path.open("rb") as fh:
            head = fh.read(1024)
    except OSError:
        return None
    found = foreign_kind(head, path.name)
    return found[0] if found else None


def load_campaign(path: str | Path) -> Campaign:
    """Load and validate a campaign config (TOML); see the module docstring for the keys.

    Raises :class:`ConfigError` naming the file and the key for every problem.
    """
    cfg_path = Path(path).resolve()
    try:
        data = read_toml(cfg_path)
    except ConfigError as exc:
        if exc.hint or cfg_path.suffix.lower() == ".toml":
            raise
        # e.g. `tribopipe batch run.csv`: an export given where a campaign config belongs
        kind = _foreign_kind(cfg_path)
        if kind is not None:
            raise ConfigError(f"is {kind}, not a campaign config", path=exc.path,
                              hint="pass a campaign config (TOML, see configs/example.toml) "
                                   "or a folder of exports") from None
        if cfg_path.suffix.lower() in EXPORT_SUFFIXES:
            raise ConfigError(
                "is an instrument export, not a campaign config", path=exc.path,
                hint="reduce one export with `tribopipe reduce FILE --pin PIN --disc DISC`, "
                     "or pass the folder of exports to batch") from None
        raise ConfigError(exc.problem, path=exc.path,
                          hint="expected a campaign config (TOML, see configs/example.toml) "
                               "or a folder of exports") from None
    unknown_tables = sorted(set(data) - _TOP_LEVEL_TABLES)
    if unknown_tables:
        raise ConfigError(
            f"unknown table(s) {', '.join(unknown_tables)}; expected [campaign], "
            "optional [reduction], [names] and [metadata]",
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
    for short, full in names_table.items():
        try:
            check_name(short, f"[names] key {short[:40]!r}")
            check_name(full, f"[names] {short[:40]}")
        except ValidationError as exc:
            raise ConfigError(exc.problem, path=cfg_path) from None

    output_dir = rel("output_dir") or (base.parent / DEFAULT_OUTPUT_DIR).resolve()
    problem = _output_folder_problem(output_dir)
    if problem is not None:
        raise ConfigError(f"[campaign] output_dir: {problem}", path=cfg_path,
                          hint="name a folder (it is created when missing)")
    map_path = rel("map") or OutputLayout(output_dir).map_path
    review = rel("review")
    manifest = rel("manifest")
    if manifest is not None and not manifest.is_file():
        raise ConfigError(f"[campaign] manifest: file {manifest} not found", path=cfg_path)
    pattern = table.get("filename_pattern")
    if pattern is not None:
        _check_type(pattern, str, "filename_pattern", cfg_path)
        compile_pattern(pattern, key="filename_pattern", path=cfg_path)
    test_pattern = _test_pattern(table, pattern, cfg_path)
    if manifest is None and pattern is None and test_pattern is None:
        raise ConfigError(
            "[campaign] no metadata source: set manifest, filename_pattern and/or "
            "test_pattern",
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
        speed_rel=_non_negative(table.get("speed_tolerance_rel", defaults.speed_rel),
                                "speed_tolerance_rel", cfg_path),
    )
    glob = table.get("glob")
    if glob is not None:
        _check_type(glob, str, "glob", cfg_path)
        problem = glob_problem(glob)
        if problem is not None:
            raise ConfigError(f"[campaign] glob: {problem}", path=cfg_path)
    name = _check_type(table.get("name", cfg_path.stem), str, "name", cfg_path)
    try:
        check_name(name, "[campaign] name")
    except ValidationError as exc:
        raise ConfigError(exc.problem, path=cfg_path) from None
    plots = _check_type(table.get("plots", True), bool, "plots", cfg_path)
    synthetic = _check_type(table.get("synthetic", False), bool, "synthetic", cfg_path)
    decimal = table.get("decimal")
    if decimal not in (None, ".", ","):
        raise ConfigError(f"[campaign] decimal must be '.' or ',', got {decimal!r}",
                          path=cfg_path)
    options = ReadOptions(
        encoding=_optional_str(table, "encoding", cfg_path),
        delimiter=_optional_str(table, "delimiter", cfg_path),
        decimal=decimal,
    )
    materials = table.get("materials", [])
    materials = [materials] if isinstance(materials, str) else materials
    if not isinstance(materials, list) or not all(isinstance(m, str) for m in materials):
        raise ConfigError("[campaign] materials must name a materials file (or a list of "
                          "them)", path=cfg_path)
    vocabulary = load_vocabulary(lab_files(base, [(base / m).resolve() for m in materials]))
    keep_labels = _check_type(table.get("keep_labels", False), bool, "keep_labels", cfg_path)
    label_force = _non_negative(table.get("label_force_tolerance_rel", LABEL_FORCE_REL),
                                "label_force_tolerance_rel", cfg_path)
    return Campaign(
        label_check=LabelCheck(force_rel=label_force, keep_labels=keep_labels,
                               vocabulary=vocabulary),
        vocabulary=vocabulary,
        report=campaign_report(data.get("metadata", {}), cfg_path),
        name=name,
        raw_dir=raw_dir,
        glob=glob,
        settings=settings,
        output_dir=output_dir,
        map_path=map_path,
        manifest=manifest,
        filename_pattern=pattern,
        test_pattern=test_pattern,
        names=tuple(sorted(names_table.items())),
        tolerances=tolerances,
        plots=plots,
        synthetic=synthetic,
        read_options=options,
        source=cfg_path,
        review=review,
    )


def campaign_report(table: Any, cfg_path: Path) -> RunReport:
    """The ``[metadata]`` table of a campaign config: reporting items
    (:data:`tribopipe.reporting.ITEMS`) that hold for every run, and an ``extra`` table of
    other text items. An unknown key is refused by name (with a did-you-mean)."""
    import difflib

    if not isinstance(table, dict):
        raise ConfigError("[metadata] must be a table of reporting items", path=cfg_path)
    values: dict[str, float | str] = {}
    extra: dict[str, str] = {}
    for key, value in table.items():
        if key == "extra":
            if not isinstance(value, dict) or not all(
                    isinstance(v, str) and text_problem(v, max_chars=300) is None
                    for v in value.values()):
                raise ConfigError("[metadata.extra] must map names to one line of text "
                                  "each", path=cfg_path)
            extra.update(value)
            continue
        if key not in REPORTING_NAMES:
            near = difflib.get_close_matches(key, REPORTING_NAMES, n=1, cutoff=0.6)
            raise ConfigError(
                f"[metadata] unknown key {key[:40]!r}; expected one of "
                f"{', '.join(REPORTING_NAMES)} or an [metadata.extra] table", path=cfg_path,
                hint=f"did you mean {near[0]!r}?" if near else
                "put other items in [metadata.extra]")
        try:
            values[key] = parse_item(key, value, what=f"[metadata] {key}")
        except ValidationError as exc:
            raise ConfigError(exc.problem, path=cfg_path) from None
    return RunReport.of(values, extra)


def _test_pattern(table: Mapping[str, Any], filename_pattern: str | None,
                  cfg_path: Path) -> str | None:
    """The test-name pattern: ``test_pattern``, or its older spelling ``use_export_names =
    true`` with ``export_pattern`` (default: the file-name pattern)."""
    use_export_names = _check_type(table.get("use_export_names", False), bool,
                                   "use_export_names", cfg_path)
    test_pattern = table.get("test_pattern")
    export_pattern = table.get("export_pattern")
    for key, value in (("test_pattern", test_pattern), ("export_pattern", export_pattern)):
        if value is not None:
            _check_type(value, str, key, cfg_path)
            compile_pattern(value, key=key, path=cfg_path)
    if test_pattern is not None and export_pattern is not None and \
            test_pattern != export_pattern:
        raise ConfigError("[campaign] test_pattern and export_pattern (its older name) "
                          "differ: keep test_pattern", path=cfg_path)
    if test_pattern is not None:
        return str(test_pattern)
    if not use_export_names:
        return None  # as before: export_pattern alone names no source
    if export_pattern is None and filename_pattern is None:
        raise ConfigError("[campaign] use_export_names needs export_pattern or "
                          "filename_pattern (or use test_pattern)", path=cfg_path)
    return str(export_pattern or filename_pattern)


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
    glob: str | None = None,
    instrument: str | Path | None = None,
    plots: bool = True,
    test_pattern: str | None = None,
    materials: tuple[str | Path, ...] = (),
    keep_labels: bool = False,
) -> Campaign:
    """A quick campaign without a config file: a folder of exports plus a manifest CSV,
    a file-name pattern and/or a test-name pattern, reduced with an instrument config
    (default T-PID/44). ``glob`` ``None`` takes every export the readers know.

    Relative paths are taken relative to the current directory.
    """
    raw_dir = Path(folder).resolve()
    if not raw_dir.is_dir():
        raise CampaignError("folder not found", path=folder)
    manifest_path = None if manifest is None else Path(manifest).resolve()
    if manifest_path is not None and not manifest_path.is_file():
        raise CampaignError("manifest not found", path=manifest)
    if manifest_path is None and filename_pattern is None and test_pattern is None:
        raise CampaignError(
            "no metadata source for the runs", path=folder,
            hint="pass --manifest FILE.csv (columns file, pin, disc, normal_force_N, "
                 "temperature_C, repeat; optional test), --pattern or --test-pattern",
        )
    if filename_pattern is not None:
        compile_pattern(filename_pattern, key="pattern", path=None)
    if test_pattern is not None:
        compile_pattern(test_pattern, key="test-pattern", path=None)
    problem = None if glob is None else glob_problem(glob)
    if problem is not None:
        raise CampaignError(f"--glob: {problem}", path=folder)
    vocabulary = load_vocabulary(lab_files(raw_dir, materials))
    out = Path(output_dir).resolve()
    problem = _output_folder_problem(out)
    if problem is not None:
        raise CampaignError(f"output folder: {problem}", path=folder)
    return Campaign(
        name=display_path(raw_dir.name)[:MAX_NAME_CHARS] or "campaign",
        raw_dir=raw_dir,
        glob=glob,
        settings=load_settings(instrument),
        output_dir=out,
        map_path=Path(map_path).resolve() if map_path else OutputLayout(out).map_path,
        manifest=manifest_path,
        filename_pattern=filename_pattern,
        test_pattern=test_pattern,
        plots=plots,
        vocabulary=vocabulary,
        label_check=LabelCheck(keep_labels=keep_labels, vocabulary=vocabulary),
    )
