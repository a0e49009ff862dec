"""From an export to its runs in the map: the route, the run outputs and the landing.

An export holds one run per friction interval of every test and result
(:func:`tribopipe.reduction.intervals.friction_intervals`): a single test with a set-up and
a friction interval gives one run, a session export one run per test, a test with force or
speed steps one run per step. Readers and writers stay at the edges,
:mod:`tribopipe.reduction.reduce` does the physics.

The package's rooms, each importing only those above it:

* :mod:`~tribopipe.pipeline.runs` — the vocabulary: a run's place in its export
  (:class:`RunPlace`), an export cut into its runs, a run reduced in memory
  (:class:`RunOutcome`), a file's outcome (:class:`FileOutcome`: a :class:`ReducedRun` or
  :class:`FailedRun` per run);
* :mod:`~tribopipe.pipeline.run_outputs` — a reduced run's files: trace (Parquet),
  summary (JSON), trace plot, at the layout's paths;
* :mod:`~tribopipe.pipeline.route` — the one route from an export to its runs
  (:func:`reduce_export`), for ``tribopipe reduce`` (:func:`reduce_files`) and the batch
  workers alike;
* :mod:`~tribopipe.pipeline.landing` — the one landing of reduced runs in the map
  (:func:`~tribopipe.pipeline.landing.land_runs`), for ``tribopipe reduce``
  (:func:`store_runs`) and the batch, under the map's lock.

The package exports the pipeline's everyday calls (:data:`__all__`); every other name is
imported from the room that defines it.
"""

from __future__ import annotations

from .landing import store_runs
from .route import read_runs, reduce_export, reduce_file, reduce_files, reduce_run
from .run_outputs import plot_run, run_summary, write_summary, write_trace
from .runs import FailedRun, FileOutcome, ReadOptions, ReducedRun, RunOutcome

__all__ = [
    "reduce_export",
    "reduce_file",
    "reduce_files",
    "reduce_run",
    "read_runs",
    "store_runs",
    "write_trace",
    "write_summary",
    "plot_run",
    "run_summary",
    "ReadOptions",
    "FileOutcome",
    "ReducedRun",
    "FailedRun",
    "RunOutcome",
]
