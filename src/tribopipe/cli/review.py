"""``tribopipe review``: a page to look at every run's trace and decide (``review.csv``)."""

from __future__ import annotations

import click

from ._common import friendly_errors, say


@click.command("review")
@click.argument("config", required=False, type=click.Path(exists=True, dir_okay=False))
@click.option("--map", "map_path", type=click.Path(), default=None,
              help="A friction map to review instead of a campaign (its traces: --traces).")
@click.option("--traces", "traces_dir", type=click.Path(file_okay=False), default=None,
              help="The folder of the map's trace Parquet files (default: traces/ beside "
                   "the map).")
@click.option("--review", "review_path", type=click.Path(exists=True, dir_okay=False),
              default=None, help="Decisions to start from (review.csv; default: the "
                                 "campaign's `review` when it exists, else those the map holds).")
@click.option("-o", "--output", type=click.Path(dir_okay=False), default=None,
              help="HTML file to write. Default: review.html in the output folder (beside "
                   "the map).")
@click.option("--title", help="Page title. Default: 'tribopipe review'.")
@friendly_errors
def review_cmd(config: str | None, map_path: str | None, traces_dir: str | None,
               review_path: str | None, output: str | None, title: str | None) -> None:
    """Write the review page of a campaign CONFIG (or of --map with its --traces): one
    self-contained HTML page with every run's μ over sliding distance, its static peak
    with U and the μ_K window shaded, the normal force below and its flags; flagged and
    outlying runs first, filters by pair, condition and flag.

    For each run, accept it, exclude it with a reason, or set its μ_K window by dragging
    on the plot (a click sets the μ_S peak) or typing the distances: the new μ_K and μ_S
    show at once, computed as the reduction computes them. Save the decisions as
    review.csv beside the campaign and apply them with `tribopipe batch CONFIG --review
    review.csv` (or the campaign key `review = "review.csv"`).

    \b
      tribopipe review configs/example.toml
      tribopipe review --map processed/friction_map.parquet -o review.html
    """
    from pathlib import Path

    from ..export.review_page import write_review_page
    from ..layout import OutputLayout

    if config is None and map_path is None:
        raise click.UsageError("give a campaign CONFIG or --map PATH")
    if config is not None and (map_path is not None or traces_dir is not None):
        raise click.UsageError("--map and --traces are for a map without a CONFIG")
    if config is not None:
        from ..campaign import load_campaign

        campaign = load_campaign(config)
        the_map, traces = campaign.map_path, campaign.layout.traces_dir
        folder = campaign.output_dir
        if review_path is None and campaign.review is not None and campaign.review.exists():
            review_path = str(campaign.review)
    else:
        assert map_path is not None
        the_map = Path(map_path)
        folder = the_map.parent
        traces = Path(traces_dir) if traces_dir is not None else folder / "traces"
    target = Path(output) if output is not None else OutputLayout(folder).review_html
    say(str(write_review_page(the_map, traces, target, review_path=review_path, title=title)))
