"""``tribopipe batch`` and ``tribopipe campaign list|run``: a whole campaign, incrementally."""

from __future__ import annotations

import json
import os
import sys
from typing import Any

import click

from ._common import friendly_errors, renamed, say

#: options that describe a campaign, so they only make sense with a FOLDER
_FOLDER_ONLY = {"manifest": "--manifest", "filename_pattern": "--pattern",
                "test_pattern": "--test-pattern", "glob": "--glob",
                "instrument_path": "--instrument", "output": "--output"}


def _open(target: str, options: dict[str, Any]) -> Any:
    """A :class:`tribopipe.campaign.Campaign` from a config file or a folder + options."""
    from pathlib import Path

    from ..campaign import folder_campaign, load_campaign
    from ..layout import DEFAULT_OUTPUT_DIR

    if Path(target).is_dir():
        campaign = folder_campaign(
            target,
            manifest=options.get("manifest"),
            filename_pattern=options.get("filename_pattern"),
            map_path=options.get("map_path"),
            output_dir=options.get("output") or DEFAULT_OUTPUT_DIR,
            glob=options.get("glob"),
            instrument=options.get("instrument_path"),
            test_pattern=options.get("test_pattern"),
        )
        return _with_review(campaign, options.get("review"),
                            bool(options.get("keep_labels")))
    given = [flag for name, flag in _FOLDER_ONLY.items() if options.get(name)]
    if given:
        flags = ", ".join(given)
        raise click.UsageError(f"{flags}: only with a FOLDER; a campaign file sets these "
                               "in its [campaign] table")
    campaign = load_campaign(target)
    if options.get("map_path"):
        from dataclasses import replace

        campaign = replace(campaign, map_path=Path(options["map_path"]).resolve())
    return _with_review(campaign, options.get("review"), bool(options.get("keep_labels")))


def _with_review(campaign: Any, review: str | None, keep_labels: bool = False) -> Any:
    """The campaign with the decisions file ``--review`` gave (else its own), and
    keeping its labels with ``--keep-labels``."""
    from dataclasses import replace
    from pathlib import Path

    if keep_labels:
        campaign = replace(campaign, label_check=replace(campaign.label_check,
                                                         keep_labels=True))
    return campaign if review is None else replace(campaign, review=Path(review).resolve())


def _shorten(path: Any) -> str:
    """A path for a terminal line (:func:`tribopipe.escape.display_path`), relative to the
    current directory when it is below it."""
    from ..escape import display_path

    text = str(path)
    try:
        rel = os.path.relpath(text)
    except ValueError:
        return display_path(text)
    return display_path(text if rel.startswith("..") else rel)


def _run(campaign: Any, jobs: int | None, plots: bool | None) -> None:
    from ..campaign import run_campaign
    from ..escape import display_path, printable
    from ..frictionmap.synthetic_rows import campaign_note
    from ..labels import flag_list
    from ..layout import OutputLayout

    bar: Any = None

    def progress(done: int, total: int) -> None:
        nonlocal bar
        if bar is None:
            bar = click.progressbar(length=total, label="files landed", file=sys.stderr,
                                    show_pos=True)
            bar.__enter__()
        bar.update(done - bar.pos)

    use_bar = sys.stderr.isatty()
    try:
        report = run_campaign(campaign, jobs=jobs, plots=plots,
                              progress=progress if use_bar else None)
    finally:
        if bar is not None:
            bar.__exit__(None, None, None)
    for note in report.notes:
        click.echo(f"note: {printable(note)}", err=True)
    if campaign.synthetic:
        click.echo(f"note: {campaign_note()}", err=True)
    for names, reason in grouped_reasons(report.failures):
        # files that failed alike (a pattern that breaks at the same place) are said once
        if len(names) == 1:
            click.echo(f"failed: {names[0]}: {reason}", err=True)
        else:
            click.echo(f"failed: {len(names)} files alike, e.g. {names[0]}: {reason}",
                       err=True)
    for file, flags in report.flagged:
        click.echo(f"flagged: {display_path(file)}: {', '.join(flag_list(flags))}")
    click.echo(f"map {_shorten(report.map_path)}: {report.map_summary}")
    click.echo(f"outputs in {_shorten(report.output_dir)}/: runs.csv, failures.csv, traces/"
               + (", plots/traces/" if OutputLayout(report.output_dir).plots_dir.is_dir() else ""))
    if report.map_landed:
        from ..export.tables import map_paper_text
        from ..frictionmap.snapshot import open_groups

        # the groups, rounded for print, of the map as committed after the batch's last
        # write (a batch that did not touch the map does not read it to print them
        # again; a map folder's are stored: its ids read, not its rows grouped again)
        click.echo(map_paper_text(open_groups(report.map_path)), nl=False)
    for line in report.ledger():  # the account comes last, where a user looks
        click.echo(printable(line))
    _remember(report.map_path)
    for problem in report.output_errors:
        click.echo(f"error: {printable(problem)}", err=True)
    if report.interrupted is not None:
        click.echo(f"interrupted by {report.interrupted}: {len(report.reduced)} run(s) "
                   "landed in the map and are kept; run the batch again to reduce the rest",
                   err=True)
        sys.exit(130 if report.interrupted == "SIGINT" else 143)
    if not report.ok:
        parts = []
        if report.failures:
            parts.append(f"{len(report.failures)} file(s), test(s) or run(s) failed or "
                         "refused; see "
                         f"{_shorten(campaign.failures_csv)}")
        if report.unmatched:
            parts.append(f"{len(report.unmatched)} manifest row(s) matched nothing")
        if report.output_errors:
            parts.append(f"{len(report.output_errors)} output(s) of the batch not written")
        click.echo("; ".join(parts), err=True)
        sys.exit(1)


def _remember(map_path: Any) -> None:
    """Record the map the batch updated in ./.tribopipe-map: the commands run here without
    --map read it (:mod:`tribopipe.project`)."""
    from pathlib import Path

    from ..errors import TribopipeError
    from ..project import PROJECT_FILE, remember_map

    if not Path(map_path).exists():
        return
    try:
        remember_map(map_path)
    except TribopipeError as exc:
        say(f"note: {exc} (commands here need --map)", err=True)
        return
    say(f"note: commands run here without --map now read {_shorten(map_path)} "
        f"(./{PROJECT_FILE})", err=True)


def grouped_reasons(failures: Any) -> list[tuple[list[str], str]]:
    """``(file, reason)`` pairs grouped by what the reason says besides its file's name
    (printable, in first-seen order): ``[(names, reason), …]``. A reason names its file
    first (``notes.txt: …``); one that names it nowhere is its own group."""
    from ..escape import display_path, printable

    groups: dict[str, list[str]] = {}
    for file, reason in failures:
        name, text = display_path(file), printable(reason)
        key = text[len(name) + 2:] if text.startswith(f"{name}: ") else (
            text if name not in text else f"{name}: {text}\0")
        groups.setdefault(key, []).append(name)
    return [(names, key.rstrip("\0").removeprefix(f"{names[0]}: ")
             if key.endswith("\0") else key) for key, names in groups.items()]


def _common_run_options(func: Any) -> Any:
    func = click.option(
        "--keep-labels", "keep_labels", is_flag=True, default=False,
        help="Keep the labels where an export contradicts them (a measured mean normal "
             "force beyond the stated tolerance, 25 % unless the config's "
             "label_force_tolerance_rel says otherwise; a Test name or sample naming other "
             "materials). Default: the config's keep_labels, else such a run is refused.",
    )(func)
    func = click.option(
        "--review", "review", type=click.Path(exists=True, dir_okay=False), default=None,
        help="A lab's decisions file (review.csv: accept, exclude or re-window runs; "
             "`tribopipe review` writes it), applied to every run (default: the config's "
             "`review`).",
    )(func)
    func = click.option(
        "--plots/--no-plots", default=None,
        help="Draw a trace plot per reduced run. Default: the campaign file's `plots`, "
        "else on.",
    )(func)
    func = click.option(
        "--jobs", "-j", type=click.IntRange(min=1), default=None,
        help="Worker processes (default: one per available CPU).",
    )(func)
    func = click.option(
        "--map", "map_path", type=click.Path(), default=None,
        help="Friction map to update. Default: the campaign file's `map`, else "
        "friction_map.parquet in the output folder.",
    )(func)
    return func


def _folder_options(func: Any) -> Any:
    """The options that describe a campaign held in a FOLDER (a campaign file sets them in
    its [campaign] table), with the old spellings of --instrument and -o/--output."""
    func = renamed("--out", "-o/--output", "output", type=click.Path(file_okay=False))(func)
    func = renamed("--config", "--instrument", "instrument_path",
                   type=click.Path(exists=True, dir_okay=False))(func)
    for option in reversed(_FOLDER_OPTIONS):
        func = option(func)
    return func


_FOLDER_OPTIONS = [
    click.option("--manifest", type=click.Path(exists=True, dir_okay=False),
                 help="FOLDER only: manifest CSV (file, pin, disc, normal_force_N, "
                      "temperature_C, repeat; optional test: one row per test of a session "
                      "export; optional interval: one row per force or speed step)."),
    click.option("--pattern", "filename_pattern",
                 help="FOLDER only: file-name pattern, e.g. "
                      "'{pin}_{disc}_{force}N_{temperature}C_r{repeat}'."),
    click.option("--test-pattern", "test_pattern",
                 help="FOLDER only: pattern for each test's Test name, e.g. "
                      "'{pin} on {disc}, {force} N, {temperature} °C, #{repeat}'."),
    click.option("--glob", help="FOLDER only: which files are exports (default: every export "
                                "the readers know: .csv, .txt, .tsv, .xlsx, .xls, any case)."),
    click.option("--instrument", "instrument_path", type=click.Path(exists=True, dir_okay=False),
                 help="FOLDER only: instrument file (TOML). Default: the T-PID/44 cell, 3 pins."),
    click.option("-o", "--output", "output", type=click.Path(file_okay=False),
                 help="FOLDER only: output folder. Default: processed/."),
]


@click.command("batch")
@click.argument("target", metavar="CAMPAIGN|FOLDER", type=click.Path(exists=True))
@_folder_options
@_common_run_options
@friendly_errors
def batch_cmd(target: str, manifest: str | None, filename_pattern: str | None,
              test_pattern: str | None, glob: str | None, instrument_path: str | None,
              output: str | None, map_path: str | None, jobs: int | None,
              plots: bool | None, review: str | None, keep_labels: bool) -> None:
    """Reduce a whole campaign: a CAMPAIGN file (TOML) or a FOLDER of exports.

    Every friction interval of every test of every export is a run. Only new and changed
    files are reduced (content + config hash); the others are skipped. A bad file, test
    or run is listed with its reason and the good ones still land; a file whose content
    another already brought is a duplicate (stored once) or, with other labels, a
    conflict (refused). What finished lands in the map as the batch goes; Ctrl-C (or
    SIGTERM) keeps every run landed, says how many, and exits 130 (143): run it again to
    reduce the rest. Writes traces/, runs.csv and failures.csv to the output folder and
    ends with a ledger: files and tests found, runs reduced, skipped and failed, and
    every manifest row and test left out. Exit code 1 when anything named was not
    reduced. The map it updated is recorded in
    ./.tribopipe-map: commands run in this folder without --map read that map.

    \b
      tribopipe batch configs/example.toml
      tribopipe batch raw/mine --manifest raw/mine/manifest.csv -o processed/mine
    """
    campaign = _open(target, {
        "manifest": manifest, "filename_pattern": filename_pattern,
        "test_pattern": test_pattern, "glob": glob, "instrument_path": instrument_path,
        "output": output, "map_path": map_path, "review": review,
        "keep_labels": keep_labels,
    })
    _run(campaign, jobs, plots)


@click.group("campaign")
def campaign_group() -> None:
    """Look at a campaign before running it, and run it (same as `tribopipe batch`)."""


@campaign_group.command("run")
@click.argument("campaign", type=click.Path(exists=True, dir_okay=False))
@_common_run_options
@friendly_errors
def run_cmd(campaign: str, map_path: str | None, jobs: int | None, plots: bool | None,
            review: str | None, keep_labels: bool) -> None:
    """Reduce the new and changed runs of a CAMPAIGN file (as `tribopipe batch` does)."""
    _run(_open(campaign, {"map_path": map_path, "review": review,
                          "keep_labels": keep_labels}), jobs, plots)


@campaign_group.command("list")
@click.argument("target", metavar="CAMPAIGN|FOLDER", type=click.Path(exists=True))
@_folder_options
@click.option("--json", "as_json", is_flag=True, help="Print a JSON list instead of a table.")
@friendly_errors
def list_cmd(target: str, manifest: str | None, filename_pattern: str | None,
             test_pattern: str | None, glob: str | None, instrument_path: str | None,
             output: str | None, as_json: bool) -> None:
    """Show a campaign as a table, before running it: a CAMPAIGN file (TOML), or a FOLDER
    of exports with the options `batch` would take (a dry run). One row per run (file +
    test), its labels and status (new, reduced, changed, failed, duplicate). Nothing is
    reduced and nothing is written: a file not read yet shows one row (or one per test its
    manifest rows name).

    \b
      tribopipe campaign list raw/mine --pattern '{pin}_{disc}_{force}N_{temperature}C_r{repeat}'
      tribopipe campaign list raw/mine --manifest raw/mine/manifest.csv
    """
    from ..campaign import campaign_listing
    from ..numeric import finite_json

    rows = campaign_listing(_open(target, {
        "manifest": manifest, "filename_pattern": filename_pattern,
        "test_pattern": test_pattern, "glob": glob, "instrument_path": instrument_path,
        "output": output,
    }))
    if as_json:
        click.echo(json.dumps(finite_json(rows), indent=2, allow_nan=False))
        return
    _print_table(rows)


@campaign_group.command("manifest")
@click.argument("folder", type=click.Path(exists=True, file_okay=False))
@click.option("--pattern", "filename_pattern",
              help="Fill in the labels this file-name pattern finds, e.g. "
                   "'{pin}_{disc}_{force}N_{temperature}C_r{repeat}'. Default: all empty.")
@click.option("--glob", help="Which files are exports (default: every export the readers "
                             "know: .csv, .txt, .tsv, .xlsx, .xls, any case).")
@click.option("-o", "--output", type=click.Path(dir_okay=False),
              help="The manifest to write. Default: manifest.csv in FOLDER.")
@click.option("--overwrite", is_flag=True, help="Replace a manifest already there.")
@friendly_errors
def manifest_cmd(folder: str, filename_pattern: str | None, glob: str | None,
                 output: str | None, overwrite: bool) -> None:
    """Write a manifest to fill in for a FOLDER of exports: one row per export (columns
    file, pin, disc, normal_force_N, temperature_C, repeat), with the labels --pattern
    finds filled in. A file that is not an export is left out and named. Then check it
    with `tribopipe campaign list FOLDER --manifest FILE` and reduce with `tribopipe
    batch FOLDER --manifest FILE`.

    \b
      tribopipe campaign manifest raw/mine
      tribopipe campaign manifest raw/mine --pattern '{pin}_{disc}_{force}N_{temperature}C'
    """
    from pathlib import Path

    from ..campaign import folder_campaign, manifest_template
    from ..escape import display_path
    from ..files import write_text_atomic

    target = Path(output) if output is not None else Path(folder) / "manifest.csv"
    if (target.exists() or target.is_symlink()) and not overwrite:
        raise click.UsageError(f"{display_path(target)} exists: pass --overwrite to replace "
                               "it, or -o another file")
    # a folder campaign needs a label source: without --pattern the Test names stand in
    # (they label nothing here: the template is written from the files alone)
    campaign = folder_campaign(folder, filename_pattern=filename_pattern, glob=glob,
                               test_pattern=None if filename_pattern else "{pin}")
    text, skipped = manifest_template(campaign)
    for file, what in skipped:
        say(f"not an export: skipped: {display_path(file)} ({what})", err=True)
    write_text_atomic(target, text, newline="")
    rows = text.count("\n") - 1
    say(f"wrote {display_path(target)}: {rows} export(s) to label; then: tribopipe campaign "
        f"list {display_path(folder)} --manifest {display_path(target)}")


def _print_table(rows: list[dict[str, Any]]) -> None:
    from ..escape import printable

    columns = ("file", "test", "interval", "status", "pin", "disc", "normal_force_N",
               "temperature_C", "repeat", "mu_k", "reason")
    heads = {"normal_force_N": "F_N", "temperature_C": "T_C"}

    def cell(row: dict[str, Any], col: str) -> str:
        value = row.get(col)
        if value is None:
            return "-"
        if isinstance(value, float):
            return f"{value:.3f}" if col == "mu_k" else f"{value:g}"
        return printable(str(value))

    grouped = grouped_reasons([(r["file"], r["reason"]) for r in rows if r.get("reason")])
    number = {name: i for i, (names, _) in enumerate(grouped, 1) for name in names}
    if any(len(names) > 1 for names, _ in grouped):  # say a shared reason once, below
        rows = [{**r, "reason": f"({number[r['file']]})"} if r.get("reason") else r
                for r in rows]
    else:
        grouped = []
    body = [[cell(r, c) for c in columns] for r in rows]
    widths = [max([len(heads.get(c, c))] + [len(b[i]) for b in body]) for i, c in
              enumerate(columns[:-1])]
    click.echo("  ".join(heads.get(c, c).ljust(w) for c, w in zip(columns, widths, strict=False))
               + "  reason")
    for b in body:
        click.echo("  ".join(v.ljust(w) for v, w in zip(b, widths, strict=False)) + "  "
                   + (b[-1] if b[-1] != "-" else ""))
    counts: dict[str, int] = {}
    for r in rows:
        counts[r["status"]] = counts.get(r["status"], 0) + 1
    files = len({r["file"] for r in rows})
    # a row is a run, or a file (or test) not read as runs yet or that failed as a whole
    click.echo(f"{len(rows)} row(s) in {files} file(s): "
               + ", ".join(f"{n} {s}" for s, n in sorted(counts.items())))
    for i, (names, reason) in enumerate(grouped, 1):
        click.echo(f"({i}) {len(names)} file(s)"
                   + (f", e.g. {names[0]}" if len(names) > 1 else f": {names[0]}")
                   + f": {reason}")
