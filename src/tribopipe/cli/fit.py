"""``tribopipe map fit``: power-law μ_K(p) per pair and temperature (attached to ``map``)."""

from __future__ import annotations

import json
import math

import click

from ._common import friendly_errors, map_option, material_filters, say


def _fmt(value: float | None, spec: str) -> str:
    """A number for the table, '-' when missing."""
    return "-" if value is None or math.isnan(value) else format(value, spec)


@click.command("fit")
@map_option
@click.option("--pin", help="Only this pin material.")
@click.option("--disc", help="Only this disc material.")
@click.option("--json", "as_json", is_flag=True, help="Print JSON records instead of a table.")
@click.option(
    "-o", "--output", type=click.Path(dir_okay=False), help="Also write the fits as CSV."
)
@friendly_errors
def fit_cmd(
    map_path: str, pin: str | None, disc: str | None, as_json: bool, output: str | None
) -> None:
    """Fit μ_K = k·p^(n−1) per pair and temperature on the individual runs.

    Log–log least squares (p in kPa, so k is μ_K at 1 kPa); 95 % confidence intervals of
    k and of the exponent n−1 from the t-distribution; R² of the log–log fit.
    Hertz-type contact of an elastomer gives n−1 ≈ −1/3.
    """
    from ..fit import fit_map
    from ..frictionmap.snapshot import open_map

    snap = open_map(map_path)
    pin, disc = material_filters(snap, pin, disc)
    fits = fit_map(snap)
    if pin is not None:
        fits = fits[fits["pin"] == pin]
    if disc is not None:
        fits = fits[fits["disc"] == disc]
    if output:
        from ..export.tables import to_csv
        from ..files import write_text_atomic

        write_text_atomic(output, to_csv(fits), newline="")
        say(f"wrote {output}", err=True)
    if as_json:
        from ..numeric import finite_json

        records = finite_json(fits.to_dict(orient="records"))
        click.echo(json.dumps(records, indent=2, default=str, allow_nan=False))
        return
    speeds = "nominal_speed_mm_s" in fits.columns  # a pair of several speeds
    click.echo(
        f"{'pin':<16} {'disc':<22} {'T_C':>5} " + (f"{'v_mm_s':>7} " if speeds else "")
        + f"{'k':>7} {'k 95% CI':>17} {'n-1':>7} {'n-1 95% CI':>17} {'R2':>6} {'N':>3}"
    )
    for r in fits.to_dict(orient="records", into=dict):
        k_ci = f"[{_fmt(r['k_ci95_low'], '.3f')}, {_fmt(r['k_ci95_high'], '.3f')}]"
        e_ci = f"[{_fmt(r['exponent_ci95_low'], '.3f')}, {_fmt(r['exponent_ci95_high'], '.3f')}]"
        click.echo(
            f"{r['pin'][:16]:<16} {r['disc'][:22]:<22} {_fmt(r['temperature_C'], '5.1f'):>5} "
            + (f"{_fmt(r['nominal_speed_mm_s'], '7.2g'):>7} " if speeds else "")
            + f"{_fmt(r['k'], '7.3f'):>7} {k_ci:>17} {_fmt(r['exponent'], '7.3f'):>7} {e_ci:>17} "
            f"{_fmt(r['r_squared'], '6.3f'):>6} {r['n_points']:>3}"
            + (f"  {r['note']}" if r['note'] else "")
        )
