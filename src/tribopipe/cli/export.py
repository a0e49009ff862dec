"""``tribopipe export abaqus|ansys|lsdyna|mujoco|sofa|pyelastica``: simulator input from the map."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import click

from ._common import friendly_errors, map_option

UNITS = ("mm-N-s", "m-N-s")
COEFFICIENTS = ("mu_k", "mu_s")


@click.group("export")
def export_group() -> None:
    """Simulator input from the friction map (μ_K tables or single values).

    Every file says in its header which engine version it was checked against, which
    coefficient it holds (μ_K or μ_S) and how the engine combines two surfaces' values.
    """


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
                help="Contact pressure [kPa] for single-condition input (lsdyna, mujoco, "
                "sofa, pyelastica, abaqus --exponential-decay; abaqus and ansys: the "
                "constant mu_k at this condition instead of the table).",
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


def _coefficient(func: Callable[..., Any]) -> Callable[..., Any]:
    """--coefficient: μ_K or μ_S (breakaway) for the onset of slip."""
    return click.option(
        "--coefficient",
        type=click.Choice(COEFFICIENTS),
        default="mu_k",
        show_default=True,
        help="Coefficient for the onset of slip: mu_k (kinetic) or mu_s (static, breakaway; "
        "refused where the map holds no mu_s for the pair).",
    )(func)


def _decay(func: Callable[..., Any]) -> Callable[..., Any]:
    """--decay: the exponential decay coefficient d_c [s/mm]."""
    return click.option(
        "--decay",
        "decay_s_per_mm",
        type=float,
        help="Decay coefficient d_c [s/mm] (default: 99 % decayed at the pair's measured "
        "sliding speed); written in the --units' s/mm or s/m.",
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
@_decay
@friendly_errors
def abaqus_cmd(output: str | None, map_path: str, **options: Any) -> None:
    """ABAQUS *SURFACE INTERACTION / *FRICTION table: mu, slip rate, pressure, temperature.

    Abaqus input (CalculiX reads *FRICTION's columns differently). The slip rate is each
    pair's own measured sliding speed.
    """
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


@export_group.command("lsdyna")
@_selection
@click.option(
    "--units",
    type=click.Choice(UNITS),
    default="mm-N-s",
    show_default=True,
    help="Unit system of DC: s/mm (mm-N-s) or s/m (m-N-s).",
)
@_coefficient
@_decay
@click.option("--contact-id", type=int, default=1, show_default=True,
              help="CID of the *CONTACT definition.")
@click.option("--pin-part", type=int, default=1, show_default=True,
              help="Part ID of the pin (SURFA).")
@click.option("--disc-part", type=int, default=2, show_default=True,
              help="Part ID of the disc (SURFB).")
@friendly_errors
def lsdyna_cmd(output: str | None, map_path: str, **options: Any) -> None:
    """LS-DYNA *CONTACT_AUTOMATIC_SURFACE_TO_SURFACE_ID with FS, FD, DC for one condition.

    Default FS = FD = mu_k, DC = 0; with --coefficient mu_s: FS = mu_s, FD = mu_k and the
    exponential decay coefficient DC.
    """
    _run("lsdyna", output, map_path, **options)


@export_group.command("mujoco")
@_selection
@_coefficient
@click.option("--geom1", default="pin", show_default=True, help="MJCF name of the pin geom.")
@click.option("--geom2", default="disc", show_default=True, help="MJCF name of the disc geom.")
@friendly_errors
def mujoco_cmd(output: str | None, map_path: str, **options: Any) -> None:
    """MuJoCo <contact><pair friction=...> for one pair at one condition."""
    _run("mujoco", output, map_path, **options)


@export_group.command("sofa")
@_selection
@_coefficient
@friendly_errors
def sofa_cmd(output: str | None, map_path: str, **options: Any) -> None:
    """SOFA CollisionResponse FrictionContactConstraint mu for one pair at one condition.

    LCPConstraintSolver ignores this mu (it applies its own); use a solver that honours
    per-contact mu (GenericConstraintSolver, BlockGaussSeidelConstraintSolver).
    """
    _run("sofa", output, map_path, **options)


@export_group.command("pyelastica")
@_selection
@_coefficient
@friendly_errors
def pyelastica_cmd(output: str | None, map_path: str, **options: Any) -> None:
    """PyElastica static_mu_array / kinetic_mu_array for one pair at one condition.

    For RodPlaneContactWithAnisotropicFriction (pyelastica >= 1.0); the static array holds
    mu_k unless --coefficient mu_s.
    """
    _run("pyelastica", output, map_path, **options)
