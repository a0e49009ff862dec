"""``tribopipe map master-curve``: a pair's μ_K over sliding speed and temperature on one
curve (time–temperature superposition)."""

from __future__ import annotations

import json

import click

from ._common import friendly_errors, map_option, material_filters, renamed, say


@click.command("master-curve")
@click.option("--pin", required=True, help="Pin material.")
@click.option("--disc", required=True, help="Disc material.")
@click.option("--shift", type=click.Choice(["arrhenius", "wlf"]), default="arrhenius",
              show_default=True,
              help="Shift law: Arrhenius (Ea; silicones far above their glass transition) "
              "or WLF (C1, C2).")
@click.option("-o", "--output", type=click.Path(dir_okay=False),
              help="Write a plot (PNG, or .svg/.pdf by the suffix) of μ_K against log v and "
              "against log a_T·v, one colour per temperature. Default: no plot.")
@click.option("--json", "as_json", is_flag=True, help="Print the result as JSON.")
@map_option
@renamed("--plot", "-o/--output", "output", type=click.Path(dir_okay=False))
@friendly_errors
def master_curve_cmd(pin: str, disc: str, shift: str, output: str | None, as_json: bool,
                     map_path: str) -> None:
    """Shift each temperature's μ_K(log v) of PIN on DISC onto one master curve.

    Needs at least 2 temperatures (3 or more to check the law) and 2 speeds at every
    pressure, measured slowly enough that frictional heating is negligible, with
    overlapping shifted speed ranges; refuses otherwise. Prints the shift (Ea with its
    standard uncertainty, or C1 and C2), log a_T per temperature, the curve per pressure
    and the residual SD.
    """
    from ..mastercurve import map_master_curve
    from ..numeric import finite_json

    pin, disc = material_filters(map_path, pin, disc)
    mc = map_master_curve(map_path, pin, disc, shift=shift)
    if as_json:
        click.echo(json.dumps(finite_json(mc.to_dict()), indent=2, allow_nan=False))
    else:
        law = (f"Ea = {mc.parameters['Ea_kJ_mol']:.1f} kJ/mol"
               + (f" (u = {mc.uncertainties['Ea_kJ_mol']:.2g})"
                  if "Ea_kJ_mol" in mc.uncertainties else "")
               if mc.shift == "arrhenius" else
               f"C1 = {mc.parameters['C1']:.4g}, C2 = {mc.parameters['C2_K']:.4g} K")
        say(f"{mc.pin} on {mc.disc}: {mc.shift} shift, {law}, reference "
            f"{mc.reference_temperature_C:g} °C")
        for t, a in sorted(mc.log10_aT.items()):
            click.echo(f"  {t:g} °C: log10 a_T = {a:+.3f}")
        for c in mc.curves:
            terms = " + ".join(f"{v:.4g}·x^{i}" for i, v in enumerate(c.coefficients))
            click.echo(f"  {c.pressure_kPa:.4g} kPa: mu_k = {terms}, x = log10(a_T·v/(1 mm/s))"
                       f" in [{c.x_range[0]:.3g}, {c.x_range[1]:.3g}], {c.n_points} groups")
        click.echo(f"  residual SD: {mc.residual_sd:.2g}")
    if output is not None:
        from ..export.plots import plot_master_curve

        written = plot_master_curve(mc, output)
        say(f"wrote {written}", err=True)
