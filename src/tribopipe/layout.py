"""The output folder, named in one place.

Everything tribopipe writes for a reduction or a campaign goes below one folder
(``processed/`` by default)::

    <output>/
      friction_map.parquet               the friction map (a campaign may keep it elsewhere)
      friction_map.parquet.bak           the map before its last change (a hard link)
      traces/<stem>_<id8>.parquet        each reduced trace
      summaries/<stem>_<id8>.json        each run's summary (``tribopipe reduce``)
      plots/traces/<stem>_<id8>.png      each run's trace plot
      plots/pairs/pair_<pin>__<disc>.png μ_K(p) per pair (``tribopipe plot pairs``)
      runs.csv, failures.csv             the runs and the failures of the last batch
      report.html                        the campaign report
      .tribopipe-state.<name>.sqlite     a campaign's incremental state (SQLite)
      .tribopipe-batch.lock              held while a batch of the folder runs

``<stem>`` is the raw file's name without its suffix and ``<id8>`` the first 8 hex digits of
the run's measurement id, so a run's files share one name and two runs of one file name
(another folder, another interval) do not collide; the trace's footer keeps the whole id
(:data:`TRACE_ID_KEY`), which tells two runs of the same 8 digits apart (:func:`pick_trace`).
:class:`OutputLayout` names every path; :func:`write_failures` and :func:`read_failures`
are the one writer and reader of ``failures.csv`` (the campaign writes it, the report reads it).
"""

from __future__ import annotations

import csv
import io
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from .errors import ExportError
from .escape import csv_cell, csv_uncell
from .files import write_text_atomic

#: the output folder when none is given (relative to the working folder)
DEFAULT_OUTPUT_DIR = "processed"
MAP_FILE = "friction_map.parquet"
TRACES_DIR = "traces"
SUMMARIES_DIR = "summaries"
PLOTS_DIR = "plots"
RUNS_CSV = "runs.csv"
FAILURES_CSV = "failures.csv"
REPORT_HTML = "report.html"
#: the review page (``tribopipe review``)
REVIEW_HTML = "review.html"
#: the incremental state, one SQLite file per campaign name (campaigns may share an output
#: folder); :data:`LEGACY_STATE_FILE` is the JSON state older versions wrote, read once
STATE_FILE = ".tribopipe-state.{name}.sqlite"
LEGACY_STATE_FILE = ".tribopipe-state.{name}.json"
#: held while a batch runs, so two batches of one campaign never interleave their state
BATCH_LOCK = ".tribopipe-batch.lock"
#: the header of ``failures.csv``
FAILURES_HEADER: tuple[str, str] = ("file", "reason")
#: what this tool writes at the top of an output folder, and the folders it fills
#: the previous map, kept by every rewrite (:func:`tribopipe.frictionmap.store.backup_path`)
MAP_BACKUP = MAP_FILE + ".bak"
OUTPUT_FILES: frozenset[str] = frozenset({MAP_FILE, MAP_BACKUP, RUNS_CSV, FAILURES_CSV,
                                          REPORT_HTML, REVIEW_HTML})
OUTPUT_DIRS: frozenset[str] = frozenset({TRACES_DIR, SUMMARIES_DIR, PLOTS_DIR})


#: longest raw-file stem kept in a run's file names [characters] (a file name may hold
#: 255 bytes; the id and the suffix need room)
MAX_STEM_CHARS = 80


def safe_stem(source: str | Path) -> str:
    """A raw file's stem as a file name anyone can handle: characters that are not
    printable or that were undecodable bytes become ``_``, path separators too, and it is
    cut to :data:`MAX_STEM_CHARS` (the id that follows keeps run names apart)."""
    stem = Path(source).stem
    clean = "".join(
        ch if ch.isprintable() and ch not in "/\\" and not 0xD800 <= ord(ch) <= 0xDFFF
        else "_" for ch in stem
    )
    return clean[:MAX_STEM_CHARS] or "run"


def run_stem(source: str | Path, measurement_id: str) -> str:
    """The name every file of a run shares: ``<raw file stem>_<first 8 digits of its id>``
    (the stem made safe by :func:`safe_stem`)."""
    return f"{safe_stem(source)}_{measurement_id[:8]}"


#: the trace Parquet's schema-metadata key that holds its run's whole measurement id
TRACE_ID_KEY = b"tribopipe.measurement_id"


def find_trace(traces_dir: str | Path, measurement_id: str) -> Path | None:
    """The trace Parquet of a run under ``traces_dir`` (``<stem>_<id[:8]>.parquet``), as
    :func:`pick_trace` chooses it among the files of its id's first 8 digits."""
    return pick_trace(sorted(Path(traces_dir).glob(f"*_{measurement_id[:8]}.parquet")),
                      measurement_id)


def find_traces(traces_dir: str | Path, measurement_ids: Iterable[str]) -> dict[str, Path]:
    """The trace of each run of ``measurement_ids`` found under ``traces_dir`` (id → path;
    runs without one left out), as :func:`find_trace` finds each, the folder listed once
    instead of once per run."""
    listed: dict[str, list[Path]] = {}
    for trace in sorted(Path(traces_dir).glob("*_????????.parquet")):
        listed.setdefault(trace.name[-16:-8], []).append(trace)
    found: dict[str, Path] = {}
    for mid in measurement_ids:
        short = mid[:8]
        plain = len(short) == 8 and short.isalnum() and short.isascii()
        # an id whose digits a glob pattern would read otherwise is found by its own glob
        path = pick_trace(listed.get(short, []), mid) if plain else find_trace(traces_dir, mid)
        if path is not None:
            found[mid] = path
    return found


def pick_trace(candidates: Sequence[Path], measurement_id: str) -> Path | None:
    """The trace of the run ``measurement_id`` among ``candidates``, the trace files named
    with its id's first 8 digits: the one file when there is one (its name is trusted:
    no footer is read); of several (two runs whose ids share 8 digits: a 1 % chance in a
    campaign of 10⁴ runs, 69 % at 10⁵), the one whose footer names
    the whole id (:data:`TRACE_ID_KEY`, written with every trace), and none when no
    single one does (traces written before the key), never another run's trace."""
    if len(candidates) <= 1:
        return candidates[0] if candidates else None
    import pyarrow.parquet as pq

    named = []
    for path in candidates:
        try:
            meta = pq.read_schema(path).metadata or {}
        except (OSError, ValueError):  # pyarrow's ArrowInvalid is a ValueError
            continue
        if meta.get(TRACE_ID_KEY) == measurement_id.encode():
            named.append(path)
    return named[0] if len(named) == 1 else None


def _slug(campaign_name: str) -> str:
    """A campaign name as a file-name part: letters, digits, ``-`` and ``_``."""
    return re.sub(r"[^A-Za-z0-9_-]+", "-", campaign_name).strip("-")[:100] or "campaign"


@dataclass(frozen=True)
class OutputLayout:
    """The paths of one output folder (``root``); nothing is created by naming them."""

    root: Path

    @classmethod
    def of(cls, folder: str | Path | OutputLayout) -> OutputLayout:
        """The layout of ``folder`` (a layout is returned as it is)."""
        return folder if isinstance(folder, OutputLayout) else cls(Path(folder))

    @property
    def map_path(self) -> Path:
        """The default friction map: ``<root>/friction_map.parquet``."""
        return self.root / MAP_FILE

    @property
    def traces_dir(self) -> Path:
        """Reduced traces: ``<root>/traces``."""
        return self.root / TRACES_DIR

    @property
    def summaries_dir(self) -> Path:
        """Run summaries (JSON): ``<root>/summaries``."""
        return self.root / SUMMARIES_DIR

    @property
    def plots_dir(self) -> Path:
        """All plots: ``<root>/plots``."""
        return self.root / PLOTS_DIR

    @property
    def trace_plots_dir(self) -> Path:
        """Per-run trace plots: ``<root>/plots/traces``."""
        return self.plots_dir / TRACES_DIR

    @property
    def pair_plots_dir(self) -> Path:
        """Per-pair μ_K(p) plots: ``<root>/plots/pairs``."""
        return self.plots_dir / "pairs"

    @property
    def runs_csv(self) -> Path:
        """Per-run table of the last batch: ``<root>/runs.csv``."""
        return self.root / RUNS_CSV

    @property
    def failures_csv(self) -> Path:
        """Failure list of the last batch (``file,reason``): ``<root>/failures.csv``."""
        return self.root / FAILURES_CSV

    @property
    def report_html(self) -> Path:
        """The campaign report: ``<root>/report.html``."""
        return self.root / REPORT_HTML

    @property
    def review_html(self) -> Path:
        """The review page: ``<root>/review.html``."""
        return self.root / REVIEW_HTML

    @property
    def batch_lock(self) -> Path:
        """The lock a batch holds: ``<root>/.tribopipe-batch.lock``."""
        return self.root / BATCH_LOCK

    def state_path(self, campaign_name: str) -> Path:
        """A campaign's incremental state: ``<root>/.tribopipe-state.<name>.sqlite`` (the
        name reduced to letters, digits, ``-`` and ``_``)."""
        return self.root / STATE_FILE.format(name=_slug(campaign_name))

    def legacy_state_path(self, campaign_name: str) -> Path:
        """The JSON state of older versions: ``<root>/.tribopipe-state.<name>.json``."""
        return self.root / LEGACY_STATE_FILE.format(name=_slug(campaign_name))

    def trace_path(self, source: str | Path, measurement_id: str) -> Path:
        """A run's reduced trace: ``<root>/traces/<stem>_<id8>.parquet``."""
        return self.traces_dir / f"{run_stem(source, measurement_id)}.parquet"

    def summary_path(self, source: str | Path, measurement_id: str) -> Path:
        """A run's summary: ``<root>/summaries/<stem>_<id8>.json``."""
        return self.summaries_dir / f"{run_stem(source, measurement_id)}.json"

    def trace_plot_path(self, source: str | Path, measurement_id: str) -> Path:
        """A run's trace plot: ``<root>/plots/traces/<stem>_<id8>.png``."""
        return self.trace_plots_dir / f"{run_stem(source, measurement_id)}.png"

    def find_trace(self, measurement_id: str) -> Path | None:
        """The trace Parquet of a run in this folder, found by its measurement id."""
        return find_trace(self.traces_dir, measurement_id)

    def written_here(self, path: Path) -> bool:
        """True when ``path`` (absolute, like ``root``) is one of this folder's outputs:
        the map, ``runs.csv``, ``failures.csv``, the report, a state or lock file, or
        anything below ``traces/``, ``summaries/`` or ``plots/``."""
        try:
            parts = path.relative_to(self.root).parts
        except ValueError:
            return False
        if len(parts) == 1:
            name = parts[0]
            return name in OUTPUT_FILES or name.startswith(".tribopipe-") or \
                name.endswith(".lock")
        return bool(parts) and parts[0] in OUTPUT_DIRS


def write_failures(path: str | Path, failures: Mapping[str, str]) -> Path:
    """Write ``failures.csv`` (:func:`failures_text`) atomically. Returns the path."""
    return write_text_atomic(path, failures_text(failures))


def failures_text(failures: Mapping[str, str]) -> str:
    """The text of ``failures.csv``: the header ``file,reason``, then one row per failed
    file, sorted by file. Both cells are written as CSV cells
    (:func:`~tribopipe.escape.csv_cell`: one printable line, and a file named ``=cmd|...``
    is no formula)."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(FAILURES_HEADER)
    for file, reason in sorted(failures.items()):
        writer.writerow((csv_cell(file), csv_cell(reason)))
    return buf.getvalue()


def read_failures(path: str | Path) -> tuple[tuple[str, str], ...] | None:
    """``(file, reason)`` rows of a campaign's ``failures.csv``; ``None`` if it is absent."""
    p = Path(path)
    if not p.is_file():
        return None
    with p.open(encoding="utf-8", newline="") as fh:
        reader = csv.reader(fh)
        header = next(reader, None)
        if header is None:
            return ()
        if [h.strip() for h in header[:2]] != list(FAILURES_HEADER):
            raise ExportError("expected the header 'file,reason'", path=p, line=1)
        return tuple((csv_uncell(row[0]), csv_uncell(row[1]) if len(row) > 1 else "")
                     for row in reader if row)
