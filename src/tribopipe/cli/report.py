"""``tribopipe report``: one self-contained HTML page for a campaign."""

from __future__ import annotations

import click

from ._common import chosen_map, friendly_errors, say


@click.command("report")
@click.argument("campaign", required=False, type=click.Path(exists=True, dir_okay=False))
@click.option(
    "--map",
    "map_path",
    type=click.Path(),
    help="Friction map (Parquet). Default: the CAMPAIGN file's; without one, the map the "
    "last `tribopipe batch` run in this folder updated (named in ./.tribopipe-map), else "
    "processed/friction_map.parquet.",
)
@click.option(
    "--processed",
    "processed_dir",
    type=click.Path(file_okay=False),
    help="Campaign output folder (traces/, failures.csv). Default: the CAMPAIGN file's, "
    "else the map's folder.",
)
@click.option(
    "-o",
    "--output",
    type=click.Path(dir_okay=False),
    help="HTML file to write. Default: <processed>/report.html.",
)
@friendly_errors
def report_cmd(
    campaign: str | None, map_path: str | None, processed_dir: str | None, output: str | None
) -> None:
    """Write one self-contained HTML report of a campaign (plots embedded): a CAMPAIGN
    file (TOML), or the map alone.

    Summary, group table (linked to the runs), power-law fits, μ_K(p) per pair, flagged
    and excluded runs, failures with their reasons, and every run's trace plot. A map of
    more than 5,000 runs or 2,000 condition groups gets each pair's groups, fits and runs
    in <name>_runs/ beside the page (loaded when the pair is opened), and one of more than
    2,000 condition groups its explorer beside it.
    """
    from ..report import make_report

    if campaign is None:
        map_path = chosen_map(map_path)
    path = make_report(output, config=campaign, map_path=map_path, processed_dir=processed_dir)
    say(str(path))
