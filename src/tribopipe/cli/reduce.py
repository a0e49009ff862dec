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
    from ..pipeline import ReadOptions, RunLabels, reduce_files

    labels = RunLabels(
        pin=pin, disc=disc, normal_force_N=force_N, temperature_C=temperature_C, repeat=repeat
    )
    results = reduce_files(
        files, load_settings(config_path), labels,
        ReadOptions(encoding=encoding, delimiter=delimiter, decimal=decimal),
        out_dir=out_dir, plots=plot, on_file=_echo_file,
    )
    outcomes = [r.outcome for r in results if r.ok]
    _print(outcomes, as_json)
    _store(outcomes, map_path, no_map, replace, labels)
    failures = [r for r in results if not r.ok]
    if failures:
        click.echo(f"{len(failures)} of {len(files)} file(s) failed.", err=True)
        sys.exit(1)


def _echo_file(result: object) -> None:
    """One file done: its plot, or its error, on stderr as it happens."""
    if result.error is not None:
        click.echo(f"error: {result.error}", err=True)
    elif result.plot is not None:
        click.echo(f"plot: {result.plot}", err=True)


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
