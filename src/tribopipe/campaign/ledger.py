"""A batch's account: what became of every file, test and run it found, and the ledger
whose parts add up.

:class:`Account` is the running account of a batch, added to at each landing
(:meth:`Account.plus`): the runs reduced and failed, the flagged ones, the duplicate
files, the outcome of each file (:data:`FILE_OUTCOMES`), the repeat numbers used twice,
what the review did, the condition groups touched and the map's report.
:class:`BatchReport` is the batch's report, built from it: its :meth:`~BatchReport.summary`
and :meth:`~BatchReport.ledger` lines, where files found = read + duplicate + conflict +
failed and the runs of the files read = reduced + skipped + failed.
:func:`manifest_ledger` gives the ledger's manifest lines: rows that matched no file,
test or interval, and tests no metadata source described.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from ..frictionmap.store import AppendReport
from ..measurement import run_name
from ..review import ReviewOutcome
from .metadata import Manifest
from .state import DUPLICATE, FAILED, FileState
from .table import CampaignRow, CampaignTable

#: what became of a file found, as the ledger counts it: its runs were reduced, skipped or
#: failed one by one (read); its content came under another name with the same labels
#: (duplicate) or with other labels (conflict, refused); it was not read at all (failed)
READ, CONFLICT = "read", "conflict"
FILE_OUTCOMES: tuple[str, ...] = (READ, DUPLICATE, CONFLICT, FAILED)


@dataclass(frozen=True)
class Tally:
    """Files (or their tests) found by a batch, by what became of their file
    (:data:`FILE_OUTCOMES`); the parts add up to :attr:`found`."""

    read: int = 0
    duplicate: int = 0
    conflict: int = 0
    failed: int = 0

    @property
    def found(self) -> int:
        """All of them: read + duplicate + conflict + failed."""
        return self.read + self.duplicate + self.conflict + self.failed

    def parts(self, *, of_files: bool = True) -> str:
        """``3 read, 1 duplicate, 1 conflict, 1 failed`` (files), or with ``of_files``
        false ``7 in files read, 3 in duplicates, 1 in conflicts`` (their tests); the
        parts that are not 0, read always."""
        words = ("read", "duplicate", "conflict", "failed") if of_files else (
            "in files read", "in duplicates", "in conflicts", "in failed files")
        counts = (self.read, self.duplicate, self.conflict, self.failed)
        return ", ".join(f"{n} {word}" for k, (n, word) in enumerate(zip(counts, words,
                                                                           strict=True))
                         if n or k == 0)


def tally(outcomes: Mapping[str, str], counts: Mapping[str, int] | None = None) -> Tally:
    """The :class:`Tally` of files by outcome (``outcomes``: file → outcome), each counting
    1 or ``counts[file]`` (its tests)."""
    sums = dict.fromkeys(FILE_OUTCOMES, 0)
    for file, outcome in outcomes.items():
        sums[outcome] += 1 if counts is None else counts.get(file, 0)
    return Tally(**sums)


@dataclass(frozen=True)
class BatchReport:
    """What a batch did, run by run, and its ledger.

    ``reduced``/``skipped``: names of the runs reduced now / unchanged since the last batch
    (a run's name is its file, with ``[test / result / interval i]`` when the export holds
    several); ``failures``: ``(name, reason)`` of every file, test or run that failed now
    or earlier and is unchanged; ``duplicates``: ``(file, reason)`` of files whose content
    another file already brought (stored once); ``groups_updated``: condition groups
    (pin, disc, force, temperature) with a map row added, replaced or removed;
    ``removed``: map rows dropped because their raw file changed; ``map_summary``: the
    map's own account; ``notes``: things worth saying that are not failures (plots
    skipped, files gone from the folder, a renamed file); ``flagged``: ``(name, flags)``
    of the runs reduced now that carry QC flags (";"-joined). The ledger: ``files`` and
    ``tests`` found, each split by what became of its file (``file_tally``,
    ``test_tally``: read, duplicate, conflict, failed; the tests of a file never read are
    unknown and not counted); ``total`` runs of the files read = reduced + skipped +
    ``runs_failed``; ``unmatched``: manifest rows that matched no file or no test,
    ``undescribed``: the tests (``file [test]``) no metadata source described.
    ``failures`` lists the files that failed or were refused as a conflict, and the tests
    and runs that failed in files read; ``conflicts`` (file, reason) the files refused.
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
    duplicates: list[tuple[str, str]] = field(default_factory=list)
    files: int = 0
    tests: int = 0
    unmatched: list[str] = field(default_factory=list)
    undescribed: list[str] = field(default_factory=list)
    file_tally: Tally = field(default_factory=Tally)
    test_tally: Tally = field(default_factory=Tally)
    runs_failed: int = 0
    conflicts: list[tuple[str, str]] = field(default_factory=list)
    #: repeat numbers used by several runs of one condition, with the runs reduced now
    repeats: list[str] = field(default_factory=list)
    #: the batch's own outputs (state, runs.csv, failures.csv) that could not be written
    output_errors: list[str] = field(default_factory=list)
    #: the signal that stopped the batch (``"SIGINT"``, ``"SIGTERM"``), else ``None``:
    #: what finished landed, the rest is for the next batch
    interrupted: str | None = None
    #: whether a landing of the batch read the map under its lock (its rows are not
    #: kept): then the command shows the map's condition groups afterwards, read from
    #: the stored groups (a batch that did not touch the map does not read it again)
    map_landed: bool = False

    #: True when nothing changed since the last batch and its ledger was kept: no file
    #: was read, no state row loaded, the map not opened
    #: (:func:`tribopipe.campaign.stamp.kept_report`)
    kept: bool = False

    def to_json(self) -> dict[str, Any]:
        """What the state keeps of an unchanged batch's report (its paths left out):
        every field a later unchanged batch reports again."""
        return {
            "campaign": self.campaign, "total": self.total, "reduced": self.reduced,
            "skipped": self.skipped, "failures": self.failures,
            "groups_updated": self.groups_updated, "removed": self.removed,
            "map_summary": self.map_summary, "notes": self.notes, "flagged": self.flagged,
            "duplicates": self.duplicates, "files": self.files, "tests": self.tests,
            "unmatched": self.unmatched, "undescribed": self.undescribed,
            "file_tally": asdict(self.file_tally), "test_tally": asdict(self.test_tally),
            "runs_failed": self.runs_failed, "conflicts": self.conflicts,
            "repeats": self.repeats, "output_errors": self.output_errors,
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any], map_path: Path, output_dir: Path
                  ) -> BatchReport:
        """The report :meth:`to_json` kept, for the map and output folder given, marked
        :attr:`kept`. Raises ``KeyError``, ``TypeError`` or ``ValueError`` when ``data``
        is not one :meth:`to_json` wrote."""
        def texts(key: str) -> list[str]:
            return [str(v) for v in data[key]]

        def pairs(key: str) -> list[tuple[str, str]]:
            return [(str(a), str(b)) for a, b in data[key]]

        def counts(key: str) -> Tally:
            return Tally(**{k: int(v) for k, v in data[key].items()})

        return cls(
            campaign=str(data["campaign"]), map_path=map_path, output_dir=output_dir,
            total=int(data["total"]), reduced=texts("reduced"), skipped=texts("skipped"),
            failures=pairs("failures"), groups_updated=int(data["groups_updated"]),
            removed=int(data["removed"]), map_summary=str(data["map_summary"]),
            notes=texts("notes"), flagged=pairs("flagged"), duplicates=pairs("duplicates"),
            files=int(data["files"]), tests=int(data["tests"]), unmatched=texts("unmatched"),
            undescribed=texts("undescribed"), file_tally=counts("file_tally"),
            test_tally=counts("test_tally"), runs_failed=int(data["runs_failed"]),
            conflicts=pairs("conflicts"), repeats=texts("repeats"),
            output_errors=texts("output_errors"), kept=True)

    @property
    def ok(self) -> bool:
        """True when everything the user named was reduced and written: no file, test or
        run failed, every manifest row matched a file (and its test) and every output of
        the batch was written."""
        return not self.failures and not self.unmatched and not self.output_errors

    def summary(self) -> str:
        """One line whose parts add up: files found (read, duplicate, conflict, failed);
        tests found, split alike; the runs of the files read (reduced, skipped, failed);
        groups updated."""
        tests = f"{self.tests} test(s)"
        if self.test_tally.found != self.test_tally.read:
            tests += f" ({self.test_tally.parts(of_files=False)})"
        text = (f"{self.campaign}: {self.files} file(s) found ({self.file_tally.parts()}), "
                f"{tests}; {self.total} run(s) in the files read: {len(self.reduced)} "
                f"reduced, {len(self.skipped)} skipped (unchanged), {self.runs_failed} "
                f"failed; {self.groups_updated} condition group(s) updated")
        if self.removed:
            text += f"; {self.removed} stale map row(s) removed"
        return text

    def ledger(self) -> list[str]:
        """The batch's account: :meth:`summary`, then one line per duplicate file, per
        file refused as a conflict, per repeat number used twice in one condition, per
        manifest row that matched no file or no test, and per test no metadata source
        described."""
        lines = [self.summary()]
        lines += [f"  duplicate: {reason}" for _, reason in self.duplicates]
        lines += [f"  conflict: {reason}" for _, reason in self.conflicts]
        lines += [f"  warning: {line}" for line in self.repeats]
        lines += [f"  manifest row matching no {what}" for what in self.unmatched]
        lines += [f"  test no metadata source described: {name}" for name in self.undescribed]
        return lines


@dataclass(frozen=True)
class Account:
    """What a batch's landings brought so far: the runs reduced (names) and the flagged
    ones (name, flags), the duplicate files (file → reason), the outcome of each file
    reduced now (file → one of :data:`FILE_OUTCOMES`), the runs that failed in the files
    read, the repeat numbers used twice in one condition, what the review did (``None``
    when none applied), the condition groups with a map row added, replaced or removed,
    and the map's report of the landings (``None``: the map did not change)."""

    reduced: list[str] = field(default_factory=list)
    flagged: list[tuple[str, str]] = field(default_factory=list)
    duplicates: dict[str, str] = field(default_factory=dict)
    outcomes: dict[str, str] = field(default_factory=dict)
    runs_failed: int = 0
    repeats: list[str] = field(default_factory=list)
    review: ReviewOutcome | None = None
    groups: frozenset[tuple[Any, ...]] = frozenset()
    appended: AppendReport | None = None

    def plus(self, other: Account) -> Account:
        """This account and ``other`` (a later landing's) as one."""
        a, b = self.review, other.review
        review = a if b is None else b if a is None else ReviewOutcome(
            records=[], applied={k: a.applied.get(k, 0) + b.applied.get(k, 0)
                                 for k in {*a.applied, *b.applied}},
            withdrawn=a.withdrawn + b.withdrawn)
        appended = (other.appended if self.appended is None else self.appended
                    if other.appended is None else combined(self.appended, other.appended))
        return Account(reduced=self.reduced + other.reduced,
                       flagged=self.flagged + other.flagged,
                       duplicates={**self.duplicates, **other.duplicates},
                       outcomes={**self.outcomes, **other.outcomes},
                       runs_failed=self.runs_failed + other.runs_failed,
                       repeats=self.repeats + other.repeats, review=review,
                       groups=self.groups | other.groups, appended=appended)


def combined(a: AppendReport, b: AppendReport) -> AppendReport:
    """Two successive appends' reports as one (the landings of one batch)."""
    return AppendReport(
        added_ids=a.added_ids + b.added_ids, unchanged_ids=a.unchanged_ids + b.unchanged_ids,
        replaced_ids=a.replaced_ids + b.replaced_ids,
        conflicting_ids=a.conflicting_ids + b.conflicting_ids,
        differences={**a.differences, **b.differences}, dropped_ids=a.dropped_ids + b.dropped_ids,
        values={**a.values, **b.values})


def manifest_ledger(rows: Sequence[CampaignRow], entries: Mapping[str, FileState],
            manifest: Manifest | None) -> tuple[dict[str, int], list[str], list[str]]:
    """The tests found per file (the files whose tests are known), the manifest rows that
    matched no file, no test or no friction interval, and the runs whose test no
    metadata source described."""
    tests: dict[str, int] = {}
    undescribed: list[str] = []
    known: dict[str, set[str | None]] = {}
    places: dict[str, set[tuple[str | None, int | None]]] = {}
    # the files' names, not their rows (a row finds its metadata), unless a manifest's
    # rows are matched against them
    files = rows.files() if manifest is None and isinstance(rows, CampaignTable) else \
        [row.file for row in rows]
    for file in files:
        entry = entries.get(file)
        found = None if entry is None else entry.tests
        if entry is None or found is None:
            continue
        if manifest is not None:  # what its rows are matched against
            known[file] = set(found)
            places[file] = {(r.test, r.interval) for r in entry.runs}
        tests[file] = len(found)
        undescribed += [run_name(file, r.test) for r in entry.runs if r.undescribed]
    unmatched: list[str] = []
    if manifest is not None:
        names = {row.file for row in rows} | {row.path.name for row in rows}
        for mrow in manifest.rows:
            if mrow.file not in names:
                unmatched.append(f"file: {manifest.name} {mrow.describes()}")
        for row in rows:
            if row.file not in known:
                continue
            for mrow in row.test_rows:
                if mrow.test is not None and mrow.test not in known[row.file]:
                    unmatched.append(f"test: {manifest.name} {mrow.describes()}")
                elif mrow.interval is not None and not any(
                        i == mrow.interval and mrow.test in (None, t)
                        for t, i in places[row.file]):
                    unmatched.append(f"interval: {manifest.name} {mrow.describes()}")
    return tests, unmatched, list(dict.fromkeys(undescribed))
