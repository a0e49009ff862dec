"""``tribopipe export abaqus|ansys|mujoco|sofa|pyelastica``: simulator input from the map."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import click

from ._common import friendly_errors, map_option

UNITS = ("mm-N-s", "m-N-s")


@click.group("export")
def export_group() -> None:
    """Simulator input from the friction map (μ_K tables or single values)."""


def _selection(func: Callable[..., Any]) -> Callable[..., Any]:
    """--pin/--disc/--temperature/--pressure, --map and -o shared by every format."""
    for option in reversed(
        [
            click.option("--pin", help="Pin material (default: every pin)."),
            click.option("--disc", help="Disc material (default: every disc)."),
            click.option(
                "--temperature",
                "temperature_C",
                type=float,
                help="One temperature [°C] (interpolated); default: every measured one.",
            ),
            click.option(
                "--pressure",
                "pressure_kPa",
                type=float,
                help="Contact pressure [kPa] for single-value input.",
            ),
            map_option,
            click.option(
                "-o",
                "--output",
                type=click.Path(dir_okay=False, writable=True),
                help="Write to FILE instead of standard output.",
            ),
        ]
    ):
        func = option(func)
    return func


def _units(func: Callable[..., Any]) -> Callable[..., Any]:
    """--units: the unit system of table formats."""
    return click.option(
        "--units",
        type=click.Choice(UNITS),
        default="mm-N-s",
        show_default=True,
        help="Unit system: pressure in MPa (mm-N-s) or Pa (m-N-s).",
    )(func)


def _emit(text: str, output: str | None) -> None:
    """Print ``text`` or write it to ``output`` (UTF-8, LF, atomically)."""
    if output is None:
        click.echo(text, nl=False)
        return
    from ..files import write_text_atomic

    write_text_atomic(output, text, newline="\n")
    click.echo(f"wrote {output}", err=True)


def _run(fmt: str, output: str | None, map_path: str, **options: Any) -> None:
    """Export ``fmt`` from the map and emit it."""
    from ..export.simulators import export_from_map

    _emit(export_from_map(map_path, fmt, **options), output)


@export_group.command("abaqus")
@_selection
@_units
@click.option(
    "--exponential-decay",
    is_flag=True,
    help="One condition as *FRICTION, EXPONENTIAL DECAY (mu_s, mu_k, d_c); needs mu_s.",
)
@click.option(
    "--decay",
    "decay_s_per_mm",
    type=float,
    help="Decay coefficient d_c [s/mm] (default: 99 % decayed at the test's sliding speed).",
)
@friendly_errors
def abaqus_cmd(output: str | None, map_path: str, **options: Any) -> None:
    """ABAQUS *SURFACE INTERACTION / *FRICTION table: mu, slip rate, pressure, temperature."""
    _run("abaqus", output, map_path, **options)


@export_group.command("ansys")
@_selection
@_units
@click.option("--material-id", type=int, default=1, show_default=True,
              help="Material number of the first pair's TB,FRIC table.")
@friendly_errors
def ansys_cmd(output: str | None, map_path: str, **options: Any) -> None:
    """Ansys MAPDL TB,FRIC,mat,,,ISO with TBFIELD on temperature and contact pressure."""
    _run("ansys", output, map_path, **options)


@export_group.command("mujoco")
@_selection
@click.option("--geom1", default="pin", show_default=True, help="MJCF name of the pin geom.")
@click.option("--geom2", default="disc", show_default=True, help="MJCF name of the disc geom.")
@friendly_errors
def mujoco_cmd(output: str | None, map_path: str, **options: Any) -> None:
    """MuJoCo <contact><pair friction=...> for one pair at one condition."""
    _run("mujoco", output, map_path, **options)


@export_group.command("sofa")
@_selection
@friendly_errors
def sofa_cmd(output: str | None, map_path: str, **options: Any) -> None:
    """SOFA CollisionResponse FrictionContactConstraint mu for one pair at one condition."""
    _run("sofa", output, map_path, **options)


@export_group.command("pyelastica")
@_selection
@friendly_errors
def pyelastica_cmd(output: str | None, map_path: str, **options: Any) -> None:
    """PyElastica static_mu_array / kinetic_mu_array for one pair at one condition."""
    _run("pyelastica", output, map_path, **options)
