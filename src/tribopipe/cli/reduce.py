"""``tribopipe reduce``: raw exports → μ_S, μ_K, with evidence, into the friction map."""

from __future__ import annotations

import json
import sys

import click

from ._common import config_option, friendly_errors, map_option, read_options


def _fmt(value: object, spec: str) -> str:
    if value is None:
        return "-"
    return format(value, spec)


@click.command("reduce")
@click.argument("files", nargs=-1, required=True, type=click.Path(dir_okay=False))
@click.option("--pin", help="Pin material, e.g. 'Ecoflex 00-50'.")
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
@config_option
@map_option
@click.option("--no-map", is_flag=True, help="Do not append the runs to the friction map.")
@click.option(
    "--replace",
    is_flag=True,
    help="Replace a run already in the map when it was reduced with another config.",
)
@click.option(
    "--out",
    "out_dir",
    type=click.Path(file_okay=False),
    default="processed",
    show_default=True,
    help="Where reduced traces (Parquet), summaries (JSON) and plots are written.",
)
@click.option("--json", "as_json", is_flag=True, help="Print a JSON list instead of a table.")
@click.option("--plot", is_flag=True, help="Also draw μ over sliding distance (PNG) per run.")
@read_options
@friendly_errors
def reduce_cmd(
    files: tuple[str, ...],
    pin: str | None,
    disc: str | None,
    force_N: float | None,
    temperature_C: float | None,
    repeat: int | None,
    config_path: str | None,
    map_path: str,
    no_map: bool,
    replace: bool,
    out_dir: str,
    as_json: bool,
    plot: bool,
    encoding: str | None,
    delimiter: str | None,
    decimal: str | None,
) -> None:
    """Reduce exported pin-on-disc runs to μ_S and μ_K.

    Prints one row per file (μ_S, μ_K, contact pressure per pin, mean normal force, flags),
    writes the reduced trace (Parquet) and a JSON summary with the evidence to --out, and
    appends the runs to the friction map (unless --no-map). Exit code 1 when any file
    could not be reduced; the others are still reduced and stored.
    """
    from ..config import load_settings
    from ..errors import TribopipeError
    from ..pipeline import ReadOptions, RunLabels, reduce_file, write_summary, write_trace

    settings = load_settings(config_path)
    labels = RunLabels(
        pin=pin, disc=disc, normal_force_N=force_N, temperature_C=temperature_C, repeat=repeat
    )
    options = ReadOptions(encoding=encoding, delimiter=delimiter, decimal=decimal)

    outcomes = []
    failures: list[str] = []
    for path in files:
        try:
            outcome = reduce_file(path, settings, labels, options)
            write_trace(out_dir, outcome)
            write_summary(out_dir, outcome)
            if plot:
                _plot(out_dir, outcome)
        except TribopipeError as exc:
            message = str(exc)
            if str(path) not in message:  # every line names its file, once
                message = f"{path}: {message}"
            failures.append(message)
            click.echo(f"error: {message}", err=True)
            continue
        except OSError as exc:
            failures.append(f"{path}: {exc.strerror or exc}")
            click.echo(f"error: {path}: {exc.strerror or exc}", err=True)
            continue
        outcomes.append(outcome)

    _print(outcomes, as_json)
    _store(outcomes, map_path, no_map, replace, labels)
    if failures:
        click.echo(f"{len(failures)} of {len(files)} file(s) failed.", err=True)
        sys.exit(1)


def _plot(out_dir: str, outcome: object) -> None:
    from ..pipeline import plot_run

    target = plot_run(out_dir, outcome)
    click.echo(f"plot: {target}", err=True)


def _print(outcomes: list, as_json: bool) -> None:
    from ..pipeline import run_summary

    summaries = [run_summary(o) for o in outcomes]
    if as_json:
        click.echo(json.dumps(summaries, indent=2, default=str))
        return
    if not summaries:
        return
    header = f"{'file':<40} {'mu_s':>6} {'mu_k':>6} {'p_kPa':>7} {'F_N_N':>6} {'T_C':>6}  flags"
    click.echo(header)
    for s in summaries:
        name = s["file"] if len(s["file"]) <= 40 else "…" + s["file"][-39:]
        click.echo(
            f"{name:<40} {s['mu_s']:6.3f} {s['mu_k']:6.3f} {s['pressure_kPa']:7.2f} "
            f"{s['normal_force_N']:6.3f} {_fmt(s['temperature_C'], '6.1f'):>6}  "
            f"{','.join(s['flags']) or '-'}"
        )


def _store(outcomes: list, map_path: str, no_map: bool, replace: bool, labels: object) -> None:
    if no_map or not outcomes:
        return
    if not labels.complete:
        click.echo(
            "note: runs not added to the friction map: pin and disc unknown "
            "(pass --pin and --disc, or --no-map)",
            err=True,
        )
        return
    from ..frictionmap import append_records

    report = append_records(map_path, [o.record for o in outcomes], replace=replace)
    click.echo(f"map {map_path}: {report.summary()}", err=True)
