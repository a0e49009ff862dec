"""``tribopipe reduce``: raw exports → μ_S, μ_K, with evidence, into the friction map."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING

import click

from ._common import (
    chosen_map,
    friendly_errors,
    instrument_option,
    lazy_map_option,
    read_options,
    renamed,
)

if TYPE_CHECKING:
    from ..labels import RunLabels
    from ..pipeline.runs import FileOutcome, ReducedRun


def _fmt(value: object, spec: str) -> str:
    if value is None:
        return "-"
    return format(value, spec)


def _with_u(value: float | None, expanded: float | None) -> tuple[str, str]:
    """A coefficient and its U (k = 2) as the table's two cells: rounded the GUM way
    (:func:`tribopipe.rounding.round_gum`, as the trace plot, ``query`` and the tables
    print them) where U is known; the value to 3 decimals and ``-`` otherwise."""
    from ..rounding import known_u, round_gum

    if value is None:
        return "-", "-"
    if known_u(expanded):
        assert expanded is not None
        return round_gum(float(value), float(expanded))
    return format(value, ".3f"), "-"


@click.command("reduce")
# FILES is checked per file by the library (a bad path fails that file only), not by click
@click.argument("files", nargs=-1, required=True, type=click.Path())
@click.option("--pin", help="Pin material, e.g. 'Ecoflex 00-50' (a name or alias of the "
              "materials vocabulary, see `tribopipe materials list`; an unknown name is "
              "refused).")
@click.option("--disc", help="Disc material, e.g. 'steel'.")
@click.option(
    "--force",
    "force_N",
    type=float,
    help="Nominal total normal force [N] (groups runs in the map). "
    "Default: the measured mean, rounded to 0.1 N, flagged nominal_force_estimated.",
)
@click.option(
    "--temperature", "temperature_C", type=float, help="Nominal chamber temperature [°C]."
)
@click.option("--repeat", type=int, help="Repeat number of this run within its condition.")
@click.option("--materials", "materials_files", multiple=True,
              type=click.Path(dir_okay=False),
              help="A lab's materials file extending the vocabulary --pin and --disc are "
                   "resolved through (repeatable; default: materials.toml in the current "
                   "folder when it is there).")
@click.option("--keep-labels", is_flag=True,
              help="Keep the labels when the export contradicts them (a measured mean "
                   "normal force more than 25 % off --force, a Test name or sample naming "
                   "other materials); default: such a run is refused.")
@instrument_option
@click.option("--zero", "zero",
              help="The zero of the torque or friction force: 'auto' (estimated where the "
              "instrument is at rest and unloaded; refused and flagged zero_under_load when "
              "already loaded), 'off' (0), or a value in N·m (torque) or N (friction "
              "force). Default: the instrument file's zero_offset.")
@lazy_map_option
@click.option("--no-map", is_flag=True,
              help="Do not append the runs to the friction map, and write nothing unless "
              "-o/--output is given.")
@click.option(
    "--replace",
    is_flag=True,
    help="Replace a run already in the map when it was reduced with another config.",
)
@click.option(
    "-o",
    "--output",
    type=click.Path(file_okay=False),
    default=None,
    help="Folder for each run's reduced trace (Parquet), summary (JSON) and plot. "
    "Default: the map's folder; with --no-map, nothing is written unless given.",
)
@click.option("--json", "as_json", is_flag=True, help="Print a JSON list instead of a table.")
@click.option("--plots/--no-plots", default=False,
              help="Draw μ over sliding distance (PNG) per run. Default: off.")
@read_options
@renamed("--out", "-o/--output", "output", type=click.Path(file_okay=False))
@renamed("--plot", "--plots", "plots", is_flag=True)
@friendly_errors
def reduce_cmd(
    files: tuple[str, ...],
    pin: str | None,
    disc: str | None,
    force_N: float | None,
    temperature_C: float | None,
    repeat: int | None,
    materials_files: tuple[str, ...],
    keep_labels: bool,
    instrument_path: str | None,
    zero: str | None,
    map_path: str | None,
    no_map: bool,
    replace: bool,
    output: str | None,
    as_json: bool,
    plots: bool,
    encoding: str | None,
    delimiter: str | None,
    decimal: str | None,
) -> None:
    """Reduce exported pin-on-disc runs to μ_S and μ_K.

    Every friction interval of every test in each file is a run (a session export holds
    several tests; a test with force or speed steps several intervals). Prints one row per
    run (μ_S and μ_K, each with its expanded uncertainty ±U95 at k = 2, contact pressure
    per pin, mean normal force, flags; which test and interval when a file holds several;
    the standard uncertainties and their budgets are in the JSON summaries), writes each
    run's reduced trace (Parquet) and a JSON summary with the evidence to -o/--output, and
    appends the runs to the friction map (unless --no-map, which writes nothing at all
    unless -o/--output is given). A file whose content an
    earlier FILE or the map already holds under another name is a duplicate (stored once)
    or, with other labels, a conflict (refused). A run the map already holds with other
    labels (or from another config) keeps the map's row unless --replace is given.
    Exit code 1 when any file or run could not be reduced or written, a file was refused
    as a conflict, or a relabelled run kept the map's row (pass --replace to relabel
    it); the others are still reduced and stored.

    How μ_S and μ_K are found: docs/method.md, which points to the method's one
    description (the docstring of the package tribopipe.reduction).
    """
    from ..config import load_settings, with_zero
    from ..labels import LabelCheck, RunLabels
    from ..materials import lab_files, load_vocabulary
    from ..pipeline.landing import check_map_before_work
    from ..pipeline.route import reduce_files
    from ..pipeline.runs import ReadOptions

    vocabulary = load_vocabulary(lab_files(".", materials_files))
    check = LabelCheck(keep_labels=keep_labels, vocabulary=vocabulary)
    labels = RunLabels(  # an unknown name refuses the command before any work
        pin=pin, disc=disc, normal_force_N=force_N, temperature_C=temperature_C, repeat=repeat
    ).resolved(vocabulary)
    if no_map and plots and output is None:
        raise click.UsageError("--plots with --no-map: give -o/--output, the folder for the "
                               "plots (--no-map alone writes nothing)")
    settings = load_settings(instrument_path)
    if zero is not None:
        settings = with_zero(settings, zero)
    if not no_map:
        map_path = chosen_map(map_path)
        if labels.complete:
            # refuse a damaged or foreign map before any work, reading none of its rows:
            # they are read once, under the map's lock, when the runs land (store_runs)
            check_map_before_work(map_path)
        if output is None:
            output = str(Path(map_path).parent)
    results = reduce_files(
        files, settings, labels,
        ReadOptions(encoding=encoding, delimiter=delimiter, decimal=decimal),
        out_dir=output, plots=plots, on_file=_echo_file, check=check,
    )
    _print(results, as_json)
    _note_alike(results, labels)
    refused, kept = (0, 0) if map_path is None else _store(results, map_path, no_map,
                                                          replace, labels)
    failed = [r for r in results if not r.ok]
    errors = sum(len(r.failed) for r in failed)
    if failed or refused or kept:
        parts = []
        if failed:
            parts.append(f"{errors} error(s) in {len(failed)} of {len(files)} file(s)")
        if refused:
            parts.append(f"{refused} file(s) refused as a conflict")
        if kept:
            parts.append(f"{kept} run(s) kept the map's row with other labels: pass "
                         "--replace to relabel")
        click.echo("; ".join(parts) + ".", err=True)
        sys.exit(1)


def _echo_file(result: FileOutcome) -> None:
    """One file done: its plots, or its errors, on stderr as it happens (names from the
    outside as one printable line each)."""
    from ..escape import display_path, printable

    for failed in result.failed:
        click.echo(f"error: {printable(failed.reason)}", err=True)
    if result.duplicate_of is not None:
        click.echo(f"duplicate: {display_path(result.path)}: same content as "
                   f"{display_path(result.duplicate_of)}: its runs are reduced once", err=True)
    for run in result.reduced:
        if run.plot is not None:
            click.echo(f"plot: {display_path(run.plot)}", err=True)
        for note in run.notes:
            click.echo(f"warning: {printable(note)}", err=True)


def _reduced(results: list[FileOutcome]) -> list[tuple[FileOutcome, ReducedRun]]:
    """Every run reduced, with its file, in order."""
    return [(f, r) for f in results for r in f.reduced]


def _run_labels(runs: list[tuple[FileOutcome, ReducedRun]]) -> dict[int, str]:
    """The run column: test and interval (the result too where a test has several) for
    the runs of files that hold several; empty for one-run files."""
    from ..measurement import interval_label

    results_per_test: dict[tuple[str, object], set[str | None]] = {}
    for f, o in runs:
        results_per_test.setdefault((f.path, o.place.test), set()).add(o.place.result)
    shown: dict[int, str] = {}
    for k, (f, o) in enumerate(runs):
        if not f.several:
            continue
        place = o.place
        several_results = len(results_per_test[(f.path, place.test)]) > 1
        shown[k] = interval_label(place.test, place.result if several_results else None,
                                  place.interval, place.occurrence)
    return shown


def _print(results: list[FileOutcome], as_json: bool) -> None:
    from ..escape import printable

    reduced = _reduced(results)
    summaries = [r.summary for _, r in reduced]
    if as_json:
        click.echo(json.dumps(summaries, indent=2, default=str, allow_nan=False))
        return
    if not summaries:
        return
    runs = _run_labels(reduced)
    run_width = max((len(v) for v in runs.values()), default=0)
    run_head = f" {'run':<{run_width}}" if runs else ""
    header = (f"{'file':<40}{run_head} {'mu_s':>7} {'±U95':>6} {'mu_k':>7} {'±U95':>6} "
              f"{'p_kPa':>7} {'F_N_N':>6} {'T_C':>6}  flags")
    click.echo(header)
    for k, s in enumerate(summaries):
        name = s["file"] if len(s["file"]) <= 40 else "…" + s["file"][-39:]
        run = f" {runs.get(k, '-'):<{run_width}}" if runs else ""
        mu_s, u_s = _with_u(s["mu_s"], s["U95_mu_s"])
        mu_k, u_k = _with_u(s["mu_k"], s["U95_mu_k"])
        click.echo(printable(  # test names come from the file: one printable line
            f"{name:<40}{run} {mu_s:>7} {u_s:>6} {mu_k:>7} {u_k:>6} "
            f"{_fmt(s['pressure_kPa'], '7.2f'):>7} {_fmt(s['normal_force_N'], '6.3f'):>6} "
            f"{_fmt(s['temperature_C'], '6.1f'):>6}  {','.join(s['flags']) or '-'}"
        ))


def _note_alike(results: list[FileOutcome], labels: RunLabels) -> None:
    """Say so when the options label several tests of one file alike."""
    from ..escape import display_path

    given = any(v is not None for v in (labels.pin, labels.disc, labels.normal_force_N,
                                        labels.temperature_C, labels.repeat))
    if not given:
        return
    for r in results:
        if len(r.tests) > 1 and len(r.reduced) > 1:
            click.echo(f"note: {display_path(r.path)} holds {len(r.tests)} tests: "
                       "--pin/--disc/--force/"
                       "--temperature/--repeat label each of its runs alike "
                       "(a campaign can label them per test: manifest 'test' column, "
                       "--test-pattern)", err=True)
        elif len(r.reduced) > 1 and labels.normal_force_N is not None:
            click.echo(f"note: {display_path(r.path)} holds {len(r.reduced)} friction "
                       "intervals (force or "
                       "speed steps): --force labels each alike (leave it out to take each "
                       "step's nominal force from its measured force, flagged "
                       "nominal_force_estimated; a campaign manifest's 'interval' column "
                       "labels each step)", err=True)


def _store(results: list[FileOutcome], map_path: str, no_map: bool, replace: bool,
           labels: RunLabels) -> tuple[int, int]:
    """Append the runs to the map; returns the number of files refused as a conflict and
    of relabelled runs that kept the map's row (no --replace)."""
    if no_map or not _reduced(results):
        return 0, 0
    if not labels.complete:
        click.echo(
            "note: runs not added to the friction map: pin and disc unknown "
            "(pass --pin and --disc, or --no-map)",
            err=True,
        )
        return 0, 0
    from ..escape import display_path, printable
    from ..pipeline.landing import store_runs

    report = store_runs(map_path, results, replace=replace)
    refused = 0
    for same in report.same:
        if same.conflict and not replace:
            refused += 1
            click.echo(printable(f"conflict: {same.message()} (pass --replace to relabel it)"),
                       err=True)
        elif same.conflict:
            click.echo(printable(
                f"replaced: {same.file}: same content as {same.other} but other labels "
                f"({'; '.join(same.differences)}): its labels replace the map's "
                "(--replace)"), err=True)
        else:
            click.echo(printable(f"duplicate: {same.message()}"), err=True)
    relabelled = report.relabelled
    for line in report.appended.conflict_lines("this reduction", relabelled):
        click.echo(printable(f"{line} (pass --replace to relabel it)"), err=True)
    for line in report.repeats:
        click.echo(printable(f"warning: {line}"), err=True)
    click.echo(f"map {display_path(map_path)}: {report.appended.summary()}", err=True)
    return refused, len(relabelled)
