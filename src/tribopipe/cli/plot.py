"""``tribopipe plot pairs|runs``: μ_K(p) per pair and μ(s) per run, headless."""

from __future__ import annotations

import click

from ._common import friendly_errors, map_option, material_filters, renamed, say

_FORMAT = click.option(
    "--format",
    "fmt",
    type=click.Choice(["png", "svg", "pdf"]),
    default="png",
    show_default=True,
    help="Image format.",
)


_DPI = click.option(
    "--dpi",
    type=click.IntRange(min=50, max=1200),
    default=None,
    help="Resolution of a PNG [dots per inch]. Default: 120.",
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
    "--output",
    type=click.Path(file_okay=False),
    default=None,
    help="Folder for the plots. Default: plots/pairs beside the map.",
)
@_FORMAT
@_DPI
@renamed("--out", "-o/--output", "output", type=click.Path(file_okay=False))
@friendly_errors
def pairs_cmd(map_path: str, pin: str | None, disc: str | None, output: str | None, fmt: str,
              dpi: int | None) -> None:
    """μ_K against contact pressure per pair: repeats with error bars, one series per
    temperature, and the fitted power law μ = k·p^(n−1) (like Fig. 5 of the paper)."""
    from pathlib import Path

    from ..export.plots import plot_map_pairs
    from ..layout import OutputLayout

    pin, disc = material_filters(map_path, pin, disc)
    out_dir = (output if output is not None
               else OutputLayout.of(Path(map_path).parent).pair_plots_dir)
    for path in plot_map_pairs(map_path, out_dir, fmt=fmt, pin=pin, disc=disc, dpi=dpi):
        say(str(path))


@plot_group.command("runs")
@map_option
@click.option(
    "--processed",
    "processed_dir",
    type=click.Path(file_okay=False),
    default=None,
    help="Campaign output folder holding traces/*.parquet. Default: the map's folder.",
)
@click.option(
    "-o",
    "--output",
    type=click.Path(file_okay=False),
    default=None,
    help="Folder for the plots. Default: plots/traces in the campaign output folder.",
)
@_FORMAT
@renamed("--out", "-o/--output", "output", type=click.Path(file_okay=False))
@friendly_errors
def runs_cmd(map_path: str, processed_dir: str | None, output: str | None, fmt: str) -> None:
    """μ over sliding distance per run with the μ_S peak and the μ_K window (like Fig. 3)."""
    from pathlib import Path

    from ..export.plots import plot_map_runs
    from ..layout import OutputLayout

    if processed_dir is None:
        processed_dir = str(Path(map_path).parent)
    out_dir = output if output is not None else OutputLayout.of(processed_dir).trace_plots_dir
    written, missing = plot_map_runs(map_path, OutputLayout.of(processed_dir).traces_dir, out_dir,
                                     fmt=fmt)
    for path in written:
        say(str(path))
    if missing:
        say(f"note: {len(missing)} run(s) have no trace in {processed_dir}/traces "
            "(e.g. imported rows)", err=True)
