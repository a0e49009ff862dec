"""``tribopipe explore``: the friction map as one self-contained, browsable HTML page."""

from __future__ import annotations

import click

from ._common import friendly_errors, map_option, say


@click.command("explore")
@map_option
@click.option(
    "-o",
    "--output",
    type=click.Path(dir_okay=False),
    help="HTML file to write. Default: explorer.html beside the map.",
)
@click.option("--title", help="Page title. Default: 'tribopipe friction-map explorer'.")
@friendly_errors
def explore_cmd(map_path: str, output: str | None, title: str | None) -> None:
    """Write the friction-map explorer: one HTML page that opens from disk, needs no
    network and no server, and can go on any static web host.

    Pick a pin, a disc (only measured pairs), a temperature and a contact pressure —
    any value can be typed. The page shows μ_K as `tribopipe query` computes it
    (bilinear over the group means, held at the ends and said so, with the interpolated
    95 % CI, the measured groups used, their weights, n and the repeats) and μ_S where
    known; μ_K against pressure per temperature with the repeats, group means and the
    power-law fit; every disc of the pin on shared axes; the group table, sortable and
    filterable. The selection can be copied or downloaded as CSV or as an ABAQUS or Ansys
    snippet, and lives in the page's address (?pin=…&disc=…&pressure=…&temperature=…),
    so a link reproduces it.

    A large map stays a page: above 20,000 runs each pair's runs lie beside the page
    (in <page>_runs/, loaded when the pair is shown), and above 2,000 condition groups
    the page is an index of the pins linking to their own pages (in <page>_pages/; a
    pin of more groups spans pages of its own, by whole pairs).
    Keep those folders beside the page when you move it.
    """
    from pathlib import Path

    from ..export.explorer import write_explorer
    from ..frictionmap.snapshot import open_map

    target = output if output is not None else Path(map_path).parent / "explorer.html"
    say(str(write_explorer(open_map(map_path), target, title=title)))
