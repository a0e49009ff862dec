"""``tribopipe plot pairs|runs``: μ_K(p) per pair and μ(s) per run, headless."""

from __future__ import annotations

import click

from ._common import friendly_errors, map_option, say

_FORMAT = click.option(
    "--format",
    "fmt",
    type=click.Choice(["png", "svg", "pdf"]),
    default="png",
    show_default=True,
    help="Image format.",
)


@click.group("plot")
def plot_group() -> None:
    """Plots of the friction map (PNG by default; SVG or PDF with --format)."""


@plot_group.command("pairs")
@map_option
@click.option("--pin", help="Only this pin material.")
@click.option("--disc", help="Only this disc material.")
@click.option(
    "-o",
    "--out",
    "out_dir",
    type=click.Path(file_okay=False),
    default="processed/plots/pairs",
    show_default=True,
    help="Folder for the plots.",
)
@_FORMAT
@friendly_errors
def pairs_cmd(map_path: str, pin: str | None, disc: str | None, out_dir: str, fmt: str) -> None:
    """μ_K against contact pressure per pair: repeats with error bars, one series per
    temperature, and the fitted power law μ = k·p^(n−1) (like Fig. 5 of the paper)."""
    from ..export.plots import plot_map_pairs

    for path in plot_map_pairs(map_path, out_dir, fmt=fmt, pin=pin, disc=disc):
        say(str(path))


@plot_group.command("runs")
@map_option
@click.option(
    "--processed",
    "processed_dir",
    type=click.Path(file_okay=False),
    default="processed",
    show_default=True,
    help="Campaign output folder holding traces/*.parquet.",
)
@click.option(
    "-o",
    "--out",
    "out_dir",
    type=click.Path(file_okay=False),
    default="processed/plots/traces",
    show_default=True,
    help="Folder for the plots.",
)
@_FORMAT
@friendly_errors
def runs_cmd(map_path: str, processed_dir: str, out_dir: str, fmt: str) -> None:
    """μ over sliding distance per run with the μ_S peak and the μ_K window (like Fig. 3)."""
    from ..export.plots import plot_map_runs
    from ..layout import OutputLayout

    written, missing = plot_map_runs(map_path, OutputLayout.of(processed_dir).traces_dir, out_dir,
                                     fmt=fmt)
    for path in written:
        say(str(path))
    if missing:
        say(f"note: {len(missing)} run(s) have no trace in {processed_dir}/traces "
            "(e.g. imported rows)", err=True)
