"""The simulator formats as the command line offers them: one :class:`Format` per format,
with its texts and the options it takes.

This is the light half of the simulator registry: it imports the standard library and the
light checks of :mod:`~tribopipe.export.unit_systems` and
:mod:`~tribopipe.export.coefficients` only, so that listing the formats
(``tribopipe export --help``) loads neither numpy nor pandas. Which functions write each
format is :data:`tribopipe.export.registry.WRITERS`, one entry per entry of
:data:`ENTRIES`, in the same order (it imports the writers, and mypy checks them there).

A new format is one writer module, one :class:`Format` here and one
:class:`~tribopipe.export.registry.Writer` in the registry.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

from ..errors import ExportError
from .coefficients import COEFFICIENTS, check_coefficient, check_decay
from .unit_systems import UNIT_SYSTEMS, unit_system


@dataclass(frozen=True)
class Option:
    """One option a format takes beyond the pair and the condition.

    ``name`` is the writer's keyword argument, ``flag`` the command-line option, ``kind``
    its type (``str``, ``int``, ``float``; ``bool`` is an on/off flag), ``default`` its
    value when not given, ``choices`` the values allowed (text options) and ``check`` a
    function that raises :class:`ExportError` for a bad value, run before the map is
    queried.
    """

    name: str
    flag: str
    kind: type
    default: Any
    help: str
    choices: tuple[str, ...] = ()
    check: Callable[[Any], object] | None = None


#: ``--units``: the unit system of a file with pressures, slip rates or decay coefficients
UNITS = Option("units", "--units", str, "mm-N-s",
               "Unit system: pressure in MPa (mm-N-s) or Pa (m-N-s).",
               choices=tuple(UNIT_SYSTEMS), check=unit_system)

#: ``--coefficient``: μ_K or μ_S for an engine with one coefficient for the onset of slip
COEFFICIENT = Option(
    "coefficient", "--coefficient", str, "mu_k",
    "Coefficient for the onset of slip: mu_k (kinetic) or mu_s (static, breakaway; "
    "refused where the map holds no mu_s for the pair).",
    choices=COEFFICIENTS, check=check_coefficient)

#: ``--decay``: the exponential decay coefficient d_c [s/mm]
DECAY = Option(
    "decay_s_per_mm", "--decay", float, None,
    "Decay coefficient d_c [s/mm] (default: 99 % decayed at the pair's measured "
    "sliding speed); written in the --units' s/mm or s/m.",
    check=check_decay)


@dataclass(frozen=True)
class Format:
    """One simulator format as a user meets it: its name, texts, the writers it has
    (``table``: every pair's table; ``condition``: one condition; ``snippet``: what the
    explorer page copies for one condition) and the options each takes.

    Where a format has both a table and a condition writer, the on/off option ``switch``
    chooses the condition writer. ``slip_rate``: the writers take the pair's measured
    sliding speed; ``speed_curve``: the condition writer takes μ_K at each measured speed.
    """

    name: str
    title: str
    description: str
    holds: str
    table: bool = False
    condition: bool = False
    snippet: bool = False
    condition_options: tuple[Option, ...] = ()
    table_options: tuple[Option, ...] = ()
    switch: Option | None = None
    slip_rate: bool = False
    speed_curve: bool = False
    snippet_label: str = ""
    snippet_suffix: str = "txt"

    @property
    def options(self) -> tuple[Option, ...]:
        """Every option of the format (both writers', then the switch), each once."""
        seen: dict[str, Option] = {}
        for option in (*self.table_options, *self.condition_options,
                       *((self.switch,) if self.switch else ())):
            seen.setdefault(option.name, option)
        return tuple(seen.values())

    def label(self, condition: bool) -> str:
        """The format as a user asks for it: ``abaqus`` or ``abaqus --exponential-decay``."""
        if condition and self.table and self.switch is not None:
            return f"{self.name} {self.switch.flag}"
        return self.name


#: every simulator format, in the order the commands and tables list them
ENTRIES: tuple[Format, ...] = (
    Format(
        name="abaqus",
        title="ABAQUS *SURFACE INTERACTION / *FRICTION table: mu, slip rate, pressure, "
              "temperature.",
        description="Abaqus input (CalculiX reads *FRICTION's columns differently). The slip "
                    "rate is each pair's own measured sliding speed.",
        holds="μ_K table (μ, slip rate, p, T); or μ_S→μ_K exponential decay "
              "(`--exponential-decay`)",
        table=True,
        condition=True,
        snippet=True,
        table_options=(UNITS,),
        condition_options=(UNITS, DECAY),
        switch=Option("exponential_decay", "--exponential-decay", bool, False,
                      "One condition as *FRICTION, EXPONENTIAL DECAY (mu_s, mu_k, d_c); "
                      "needs mu_s."),
        slip_rate=True,
        snippet_label="ABAQUS *FRICTION (μ_K constant)",
        snippet_suffix="inp",
    ),
    Format(
        name="ansys",
        title="Ansys MAPDL TB,FRIC,mat,,,ISO with TBFIELD on temperature and contact "
              "pressure.",
        description="",
        holds="μ_K table (TB,FRIC + TBFIELD NPRES, TEMP)",
        table=True,
        snippet=True,
        table_options=(
            UNITS,
            Option("material_id", "--material-id", int, 1,
                   "Material number of the first pair's TB,FRIC table."),
        ),
        snippet_label="Ansys TB,FRIC (μ_K constant)",
        snippet_suffix="mac",
    ),
    Format(
        name="lsdyna",
        title="LS-DYNA *CONTACT_AUTOMATIC_SURFACE_TO_SURFACE_ID with FS, FD, DC for one "
              "condition.",
        description="Default FS = FD = mu_k, DC = 0, or FS, FD, DC fitted to mu_k over "
                    "the pair's measured sliding speeds where it has 3 or more (--speed "
                    "then names the condition's speed); with --coefficient mu_s: FS = "
                    "mu_s, FD = mu_k and the exponential decay coefficient DC.",
        holds="FS = FD = μ_K, or FS, FD, DC fitted to μ_K(v) where ≥ 3 speeds are measured; "
              "or FS = μ_S, FD = μ_K, DC (`--coefficient mu_s`)",
        condition=True,
        condition_options=(
            replace(UNITS, help="Unit system of DC: s/mm (mm-N-s) or s/m (m-N-s)."),
            COEFFICIENT,
            DECAY,
            Option("contact_id", "--contact-id", int, 1, "CID of the *CONTACT definition."),
            Option("pin_part", "--pin-part", int, 1, "Part ID of the pin (SURFA)."),
            Option("disc_part", "--disc-part", int, 2, "Part ID of the disc (SURFB)."),
        ),
        slip_rate=True,
        speed_curve=True,
    ),
    Format(
        name="mujoco",
        title="MuJoCo <contact><pair friction=...> for one pair at one condition.",
        description="",
        holds="μ_K or μ_S (`--coefficient`) in an explicit `<pair>`",
        condition=True,
        condition_options=(
            COEFFICIENT,
            Option("geom1", "--geom1", str, "pin", "MJCF name of the pin geom."),
            Option("geom2", "--geom2", str, "disc", "MJCF name of the disc geom."),
        ),
    ),
    Format(
        name="sofa",
        title="SOFA CollisionResponse FrictionContactConstraint mu for one pair at one "
              "condition.",
        description="LCPConstraintSolver ignores this mu (it applies its own); use a solver "
                    "that honours per-contact mu (GenericConstraintSolver, "
                    "BlockGaussSeidelConstraintSolver).",
        holds="μ_K or μ_S (`--coefficient`)",
        condition=True,
        condition_options=(COEFFICIENT,),
    ),
    Format(
        name="pyelastica",
        title="PyElastica static_mu_array / kinetic_mu_array for one pair at one condition.",
        description="For RodPlaneContactWithAnisotropicFriction (pyelastica >= 1.0); the "
                    "static array holds mu_k unless --coefficient mu_s.",
        holds="static μ_K or μ_S, kinetic μ_K",
        condition=True,
        condition_options=(COEFFICIENT,),
    ),
    Format(
        name="usd",
        title="OpenUSD physics material (static + dynamic friction) for one pair at one "
              "condition.",
        description="For Isaac Sim, Omniverse, PhysX and other UsdPhysics engines: one "
                    "material bound to both bodies, frictionCombineMode average, so the "
                    "contact gets the pair's value.",
        holds="staticFriction μ_S (μ_K where unknown), dynamicFriction μ_K on one material "
              "bound to both bodies",
        condition=True,
        snippet=True,
        snippet_label="OpenUSD physics material (μ_S, μ_K)",
        snippet_suffix="usda",
    ),
    Format(
        name="pybullet",
        title="PyBullet URDF <contact><lateral_friction> for one pair at one condition.",
        description="Bullet multiplies the two links' values: the pin's link gets mu, the "
                    "disc's 1.0 (--body disc writes the disc's URDF).",
        holds="μ_K or μ_S (`--coefficient`) on the pin's link, 1.0 on the disc's",
        condition=True,
        snippet=True,
        condition_options=(
            COEFFICIENT,
            Option("body", "--body", str, "pin",
                   "Which body's URDF: the pin's link (the pair's mu) or the disc's (1.0).",
                   choices=("pin", "disc")),
        ),
        snippet_label="PyBullet URDF, the pin's link (μ_K)",
        snippet_suffix="urdf",
    ),
    Format(
        name="drake",
        title="Drake SDFormat drake:mu_static / drake:mu_dynamic for one pair at one "
              "condition.",
        description="Both links carry the pair's values (Drake's 2 mu1 mu2 / (mu1 + mu2) "
                    "returns them); the discrete solvers use only mu_dynamic.",
        holds="mu_static μ_S (μ_K where unknown or below μ_K), mu_dynamic μ_K on both links",
        condition=True,
        snippet=True,
        snippet_label="Drake SDFormat (μ_S, μ_K)",
        snippet_suffix="sdf",
    ),
)

#: the format names, as ``export_simulator_input`` and ``tribopipe export`` take them
FORMATS: tuple[str, ...] = tuple(f.name for f in ENTRIES)


def format_named(fmt: str) -> Format:
    """The :class:`Format` called ``fmt``, or an :class:`ExportError` listing them."""
    for entry in ENTRIES:
        if entry.name == fmt:
            return entry
    raise ExportError(f"unknown simulator {fmt!r}; expected one of {', '.join(FORMATS)}")


def condition_labels() -> list[str]:
    """Every single-condition format as a user asks for it (``abaqus --exponential-decay``),
    then the table formats whose one condition is a constant (``abaqus``: its snippet)."""
    return ([f.label(True) for f in ENTRIES if f.condition]
            + [f"{f.name} (a constant)" for f in ENTRIES if f.table and f.snippet])


def users(name: str) -> list[str]:
    """The formats (and modes) that take the option ``name``."""
    found = []
    for f in ENTRIES:
        if any(o.name == name for o in f.table_options) or (
                not f.table and any(o.name == name for o in f.condition_options)):
            found.append(f.name)
        elif any(o.name == name for o in f.condition_options) or (
                f.switch is not None and f.switch.name == name):
            found.append(f.label(True))
    return found


def option_named(name: str) -> Option:
    """The :class:`Option` called ``name`` (its flag and default are the same wherever
    it is declared), or an :class:`ExportError`."""
    for f in ENTRIES:
        for option in f.options:
            if option.name == name:
                return option
    raise ExportError(f"unknown export option {name!r}")
