"""``tribopipe query``: μ_K (and μ_S) of a pair at any pressure and temperature."""

from __future__ import annotations

import json
import math
from typing import Any

import click

from ._common import friendly_errors, instrument_option, map_option, material_filters


@click.command("query")
@click.option("--pin", required=True, help="Pin material, e.g. 'Dragonskin 30'.")
@click.option("--disc", required=True, help="Disc material, e.g. 'steel'.")
@click.option("--pressure", "pressure_kPa", type=float, help="Contact pressure per pin [kPa].")
@click.option(
    "--force",
    "normal_force_N",
    type=float,
    help="Total normal force [N] instead of --pressure: converted to the contact pressure "
    "per pin through the instrument file's number of pins and pin radius (--instrument).",
)
@instrument_option
@click.option(
    "--temperature",
    "temperature_C",
    type=float,
    help="Temperature [°C]; needed when the pair is measured at several.",
)
@click.option(
    "--speed",
    "speed_mm_s",
    type=float,
    help="Sliding speed [mm/s]; needed when the pair is measured at several.",
)
@click.option(
    "--master-curve",
    "use_master_curve",
    is_flag=True,
    help="Read μ_K from the pair's master curve (Arrhenius shift over speed and "
    "temperature; needs --temperature and --speed): a model-based prediction at an "
    "unmeasured temperature or speed, refused outside the reduced-speed range covered.",
)
@click.option("--lab", "labs", multiple=True,
              help="Only the runs this lab measured (repeatable); the map's own runs are "
                   "'(own lab)'.")
@click.option("--method", "method", metavar="METHOD",
              help="Test method whose groups are read, e.g. 'sled D1894'. Default: the "
              "pair's only method (else required: methods are never pooled).")
@map_option
@click.option("--json", "as_json", is_flag=True, help="Print the result as JSON.")
@friendly_errors
def query_cmd(
    pin: str,
    disc: str,
    pressure_kPa: float | None,
    normal_force_N: float | None,
    instrument_path: str | None,
    temperature_C: float | None,
    speed_mm_s: float | None,
    use_master_curve: bool,
    labs: tuple[str, ...],
    method: str | None,
    map_path: str,
    as_json: bool,
) -> None:
    """μ_K (and μ_S where known) of PIN on DISC at a contact pressure, temperature and
    sliding speed.

    Between the measured group means: linear in temperature and, in pressure, linear in
    log p - log μ (exact for a power law μ = k·p^(n−1)); where the pair is measured at
    several sliding speeds, linear in log v between them (--speed); held constant outside the
    measured range (as ABAQUS treats a friction table) and said so. Prints value ± U, the
    expanded uncertainty (k = 2) from the runs' budgets, the repeat scatter and the
    interpolation's own uncertainty, rounded to two significant digits; then the repeats'
    95 % CI apart, the measured groups used with their weights and whether the value was
    clamped. Give the contact pressure per pin (--pressure) or the total normal force
    (--force, converted with the instrument file's pins). Names are resolved through the
    materials vocabulary (DS30 is Dragonskin 30). Says which labs the value comes from
    and where they disagree beyond R; --lab restricts it to one lab's runs.
    """
    from ..config import load_settings
    from ..frictionmap.snapshot import open_map
    from ..frictionmap.synthetic_rows import map_synthetic_note
    from ..numeric import finite_json
    from ..query import QUERY_COLUMNS, query_map, value_labs
    from ..query_text import format_result
    from ._common import say

    if (pressure_kPa is None) == (normal_force_N is None):
        raise click.UsageError("give exactly one of --pressure and --force")
    instrument = None
    if normal_force_N is not None:
        if not (math.isfinite(normal_force_N) and normal_force_N > 0):
            raise click.BadParameter(f"expected a finite number > 0 N, got {normal_force_N}",
                                     param_hint="--force")
        instrument = load_settings(instrument_path).instrument
        pressure_kPa = instrument.pressure_kPa(normal_force_N)
    assert pressure_kPa is not None
    # the one read and check of the map: the columns the query reads (its groups are
    # stored in a map folder), all of them for the master curve
    snap = open_map(map_path, None if use_master_curve else QUERY_COLUMNS)
    pin, disc = material_filters(snap, pin, disc)
    if use_master_curve:
        _master_curve_query(snap, pin, disc, pressure_kPa, temperature_C, speed_mm_s,
                            as_json)
        return
    result = query_map(snap, pin, disc, pressure_kPa, temperature_C, speed_mm_s, labs,
                       method)
    origin = value_labs(snap, result, labs)
    if as_json:
        data = result.to_dict()
        if normal_force_N is not None:
            data["normal_force_N"] = normal_force_N
        data["labs"] = list(origin.labs)
        data["labs_disagree"] = [list(c) for c in origin.disagree]
        click.echo(json.dumps(finite_json(data), indent=2, allow_nan=False))
    else:
        click.echo(format_result(result, normal_force_N, instrument))
        for line in origin.lines():
            say(f"  {line}")
    note = map_synthetic_note(snap)
    if note is not None:  # on stderr with --json, so the JSON stays one document
        click.echo(note, err=as_json)


def _master_curve_query(map_path: Any, pin: str, disc: str, pressure_kPa: float,
                        temperature_C: float | None, speed_mm_s: float | None,
                        as_json: bool) -> None:
    """``query --master-curve``: the model-based prediction, as JSON or a few lines."""
    from ..mastercurve import map_master_curve, predict
    from ..numeric import finite_json
    from ._common import say

    if temperature_C is None or speed_mm_s is None:
        raise click.UsageError("--master-curve needs --temperature and --speed")
    prediction = predict(map_master_curve(map_path, pin, disc), pressure_kPa, temperature_C,
                         speed_mm_s)
    if as_json:
        click.echo(json.dumps(finite_json(prediction.to_dict()), indent=2, allow_nan=False))
        return
    say(f"{prediction.pin} on {prediction.disc} at {pressure_kPa:.4g} kPa, "
        f"{temperature_C:g} °C, {speed_mm_s:g} mm/s")
    click.echo(f"  mu_k = {prediction.mu_k:.3f} (model-based: master curve, residual SD "
               f"{prediction.u:.2g})")
    click.echo(f"  log10 a_T = {prediction.log10_aT:+.3f}; reduced speed x = "
               f"{prediction.x:.3f} in [{prediction.x_range[0]:.3f}, "
               f"{prediction.x_range[1]:.3f}]")
