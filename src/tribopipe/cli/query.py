"""``tribopipe query``: μ_K (and μ_S) of a pair at any pressure and temperature."""

from __future__ import annotations

import json

import click

from ._common import friendly_errors, map_option


@click.command("query")
@click.option("--pin", required=True, help="Pin material, e.g. 'Dragonskin 30'.")
@click.option("--disc", required=True, help="Disc material, e.g. 'steel'.")
@click.option(
    "--pressure", "pressure_kPa", type=float, required=True, help="Contact pressure per pin [kPa]."
)
@click.option(
    "--temperature",
    "temperature_C",
    type=float,
    help="Temperature [°C]; needed when the pair is measured at several.",
)
@map_option
@click.option("--json", "as_json", is_flag=True, help="Print the result as JSON.")
@friendly_errors
def query_cmd(
    pin: str,
    disc: str,
    pressure_kPa: float,
    temperature_C: float | None,
    map_path: str,
    as_json: bool,
) -> None:
    """μ_K (and μ_S where known) of PIN on DISC at a contact pressure and temperature.

    Linear interpolation over the group means in temperature and pressure, held constant
    outside the measured range (as ABAQUS treats a friction table). Prints the measured
    groups used with their weights, whether the value was clamped, and the uncertainty:
    the groups' 95 % CI half-widths interpolated with the same weights (what the repeats
    support), and their combined standard uncertainties u (the runs' own budgets beside
    the repeat scatter; U = 2u at k = 2) interpolated likewise.
    """
    from ..frictionmap.synthetic_rows import map_synthetic_note
    from ..numeric import finite_json
    from ..query import format_result, query_map

    result = query_map(map_path, pin, disc, pressure_kPa, temperature_C)
    if as_json:
        click.echo(json.dumps(finite_json(result.to_dict()), indent=2, allow_nan=False))
    else:
        click.echo(format_result(result))
    note = map_synthetic_note(map_path)
    if note is not None:  # on stderr with --json, so the JSON stays one document
        click.echo(note, err=as_json)
