"""The pipeline's vocabulary: where a run sits in its export, an export cut into its
runs, a run reduced in memory (:class:`RunOutcome`), and what the route returns for each
file (:class:`FileOutcome`, holding a :class:`ReducedRun` or a :class:`FailedRun` per run).

Types only, with their small derived properties: the route
(:mod:`~tribopipe.pipeline.route`) makes them, the run outputs
(:mod:`~tribopipe.pipeline.run_outputs`) and the landing
(:mod:`~tribopipe.pipeline.landing`) read them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import Failure, TribopipeError
from ..frictionmap.schema import MapRow
from ..labels import RunLabels, RunVerdict
from ..measurement import interval_label, run_name

if TYPE_CHECKING:
    from ..measurement import Measurement
    from ..reduction.reduce import ReductionResult


@dataclass(frozen=True)
class ReadOptions:
    """Forced reader settings; ``None`` means detect."""

    encoding: str | None = None
    delimiter: str | None = None
    decimal: str | None = None


@dataclass(frozen=True)
class RunPlace:
    """Where a run sits in its export: test, result and interval as the export names them
    (``None`` where it names none; ``interval`` is ``None`` for a test/result that holds
    no friction interval). ``occurrence`` counts runs of one export with the same three
    (two tests of one name): 1 for the first, which keeps the id it always had."""

    test: str | None = None
    result: str | None = None
    interval: int | None = None
    occurrence: int = 1

    @property
    def label(self) -> str:
        """``test / result / interval i`` (``#n`` added for a repeated place)."""
        return interval_label(self.test, self.result, self.interval, self.occurrence)

    def run_name(self, file: str, several: bool) -> str:
        """The run's name (:func:`tribopipe.measurement.run_name`): the file alone for an
        export with one run, ``file [test / result / interval i]`` for one with several."""
        if not several:
            return file
        return run_name(file, self.test, self.result, self.interval, self.occurrence)


@dataclass(frozen=True)
class ExportRuns:
    """An export read and cut into its runs, before any reduction.

    ``runs``: each friction interval (carrying its set-up's torque offset) with its place,
    in file order; ``problems``: each test/result that holds no friction interval, with the
    reason (its place has no interval); ``tests``: the Test names of the export in file
    order, one per test (``None`` for an export that names none).
    """

    path: str
    file_hash: str
    runs: tuple[tuple[RunPlace, Measurement], ...]
    problems: tuple[tuple[RunPlace, TribopipeError], ...] = ()
    tests: tuple[str | None, ...] = ()
    #: every place (runs and problems) in file order
    order: tuple[RunPlace, ...] = ()

    @property
    def several(self) -> bool:
        """True when the export holds more than one run or test (names must say which)."""
        return len(self.runs) + len(self.problems) > 1

    def name(self, place: RunPlace, file: str | None = None) -> str:
        """The name of a run of this export (``file`` defaults to the path)."""
        return place.run_name(self.path if file is None else file, self.several)


@dataclass(frozen=True)
class RunOutcome:
    """A reduced run with everything needed to store and explain it."""

    path: str
    measurement: Measurement
    result: ReductionResult
    file_hash: str
    config_hash: str
    measurement_id: str
    #: its nominal force and flags, decided once (:func:`tribopipe.labels.decide_run`):
    #: what every output of the run shows
    verdict: RunVerdict
    #: the friction-map row; ``None`` when pin or disc is unknown (the run cannot be stored)
    record: MapRow | None = field(repr=False)
    #: where the run sits in its export
    place: RunPlace = RunPlace()
    #: whether its export holds several runs or tests (then its name says which it is)
    several: bool = False

    @property
    def labels(self) -> RunLabels:
        """The labels the run was reduced with."""
        return self.verdict.labels

    @property
    def name(self) -> str:
        """The run's name: the file, with its place when its export holds several."""
        return self.place.run_name(self.path, self.several)


@dataclass(frozen=True)
class ReducedRun:
    """A run reduced (small and picklable: never its trace).

    ``name``: the run's name in messages (the file as the caller names it, with the run's
    place when the export holds several); ``verdict``: its labels, nominal force and flags
    (:func:`tribopipe.labels.decide_run`); ``summary``: :func:`run_summary`; ``record``:
    its friction-map row (``None`` when pin or disc is unknown); the paths of the outputs
    written; ``notes``: each output that could not be written (the trace plot), naming it
    and why: the run is still reduced and stored.
    """

    name: str
    place: RunPlace
    verdict: RunVerdict
    measurement_id: str
    summary: dict[str, Any] = field(repr=False)
    record: MapRow | None = field(repr=False)
    trace: Path | None = None
    summary_file: Path | None = None
    plot: Path | None = None
    notes: tuple[str, ...] = ()

    @property
    def labels(self) -> RunLabels:
        """The labels the run was reduced with."""
        return self.verdict.labels

    @property
    def flags(self) -> tuple[str, ...]:
        """The run's QC flags, as every output shows them."""
        return self.verdict.flags


@dataclass(frozen=True)
class FailedRun:
    """A run (or a test without a friction interval; ``place`` ``None``: the whole file)
    that could not be reduced, labelled or written: its ``failure`` as fields (the file
    named as the caller names it, or the output, the problem, the hint), its one-line
    :attr:`reason` formatted from them. ``transient`` when it was not the file's fault (a
    crashed worker, an internal error: tried again next time); ``undescribed`` when no
    metadata source described it (:class:`~tribopipe.labels.Undescribed`)."""

    name: str
    failure: Failure
    place: RunPlace | None = None
    transient: bool = False
    undescribed: bool = False

    @property
    def reason(self) -> str:
        """The failure in one line (:meth:`~tribopipe.errors.Failure.text`)."""
        return self.failure.text()


@dataclass(frozen=True)
class FileOutcome:
    """What :func:`reduce_export` made of one file: a :class:`ReducedRun` or
    :class:`FailedRun` per run (and per test without a friction interval), in file order;
    or ``error``, the file as a whole (unreadable, not an export). ``name`` is the file as
    the caller names it in messages; ``duplicate_of`` names an earlier file of the same
    call with the same content: this one's runs were skipped (reduced once)."""

    path: str
    name: str
    file_hash: str | None = None
    tests: tuple[str | None, ...] = ()
    several: bool = False
    runs: tuple[ReducedRun | FailedRun, ...] = ()
    error: FailedRun | None = None
    duplicate_of: str | None = None

    @property
    def reduced(self) -> list[ReducedRun]:
        """The runs reduced, in file order."""
        return [r for r in self.runs if isinstance(r, ReducedRun)]

    @property
    def failed(self) -> list[FailedRun]:
        """The file's failure, or its runs that failed, in file order."""
        if self.error is not None:
            return [self.error]
        return [r for r in self.runs if isinstance(r, FailedRun)]

    @property
    def ok(self) -> bool:
        """True when the file was read and every one of its runs reduced."""
        return not self.failed

    @property
    def transient(self) -> bool:
        """True when the file or a run failed for a reason that is not the file's."""
        return any(r.transient for r in self.failed)
