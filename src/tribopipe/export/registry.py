"""The simulator formats: one entry per format, the one list everything else reads.

Each :class:`Writer` entry names the functions that write the format (as
``"module:function"``, imported only when a file is written, so that listing the formats —
``tribopipe export --help`` — loads neither numpy nor pandas), the options the format
takes, and what its file holds. :mod:`tribopipe.export.simulators` runs the writers (it
queries the map once and hands a single-condition writer the result), ``tribopipe export``
builds one command per entry from its options, the explorer page offers every entry with
a ``snippet``, and ``docs/simulators.md`` holds the table of :data:`WRITERS`.

A new format is one writer module and one entry in :data:`WRITERS`.

Writer functions take:

- ``condition(res, *, source, **options)``: one query result
  (:class:`tribopipe.query.QueryResult`), plus ``slip_rate`` (the pair's
  :class:`~tribopipe.export.simbase.SlipRate`) where ``slip_rate`` is true, and
  ``speed_curve`` (μ_K at each measured sliding speed of the pair at the condition,
  :func:`~tribopipe.export.simbase.speed_curve`) where ``speed_curve`` is true;
- ``table(groups, *, pin, disc, temperature_C, source, **options)``: the group table,
  plus ``slip_rates`` (every pair's) where ``slip_rate`` is true;
- ``snippet(res, *, source, **snippet_options)`` and ``snippet_header(*, source,
  **snippet_options)``: the text the explorer copies for one condition and its lines that
  do not depend on the condition (rendered into the page).

A writer never queries the map itself.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

from ..errors import ExportError

#: The unit systems of files with pressures, slip rates or decay coefficients (their
#: factors: :data:`tribopipe.export.simbase.UNIT_SYSTEMS`).
UNIT_NAMES = ("mm-N-s", "m-N-s")


@dataclass(frozen=True)
class Option:
    """One option a format takes beyond the pair and the condition.

    ``name`` is the writer's keyword argument, ``flag`` the command-line option, ``kind``
    its type (``str``, ``int``, ``float``; ``bool`` is an on/off flag), ``default`` its
    value when not given, ``choices`` the values allowed (text options) and ``check``
    (``"module:function"``) a function that raises :class:`ExportError` for a bad value,
    run before the map is queried.
    """

    name: str
    flag: str
    kind: type
    default: Any
    help: str
    choices: tuple[str, ...] = ()
    check: str | None = None


#: ``--units``: the unit system of a file with pressures, slip rates or decay coefficients
UNITS = Option("units", "--units", str, "mm-N-s",
               "Unit system: pressure in MPa (mm-N-s) or Pa (m-N-s).",
               choices=UNIT_NAMES, check="tribopipe.export.simbase:unit_system")

#: ``--coefficient``: μ_K or μ_S for an engine with one coefficient for the onset of slip
COEFFICIENT = Option(
    "coefficient", "--coefficient", str, "mu_k",
    "Coefficient for the onset of slip: mu_k (kinetic) or mu_s (static, breakaway; "
    "refused where the map holds no mu_s for the pair).",
    choices=("mu_k", "mu_s"), check="tribopipe.export.simbase:check_coefficient")

#: ``--decay``: the exponential decay coefficient d_c [s/mm]
DECAY = Option(
    "decay_s_per_mm", "--decay", float, None,
    "Decay coefficient d_c [s/mm] (default: 99 % decayed at the pair's measured "
    "sliding speed); written in the --units' s/mm or s/m.",
    check="tribopipe.export.simbase:check_decay")


@dataclass(frozen=True)
class Writer:
    """One simulator format: the functions that write it, the options each takes, what
    its file holds (see the module's docstring for the functions' arguments).

    Where a format has both a ``table`` and a ``condition`` writer, the on/off option
    ``switch`` chooses the condition writer. ``engine`` (``"module:NAME"``) is the
    :class:`~tribopipe.export.simbase.Engine` its header describes.
    """

    name: str
    title: str
    description: str
    holds: str
    engine: str
    condition: str | None = None
    table: str | None = None
    condition_options: tuple[Option, ...] = ()
    table_options: tuple[Option, ...] = ()
    switch: Option | None = None
    slip_rate: bool = False
    speed_curve: bool = False
    snippet: str | None = None
    snippet_header: str | None = None
    snippet_options: tuple[tuple[str, Any], ...] = ()
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
        if condition and self.table is not None and self.switch is not None:
            return f"{self.name} {self.switch.flag}"
        return self.name


def load(target: str) -> Any:
    """The object ``"module:attribute"`` names (a writer, a check, an engine)."""
    module, attribute = target.split(":")
    return getattr(importlib.import_module(module), attribute)


def function(target: str | None) -> Callable[..., Any]:
    """:func:`load` for a function that must exist."""
    if target is None:
        raise ExportError("this format has no such writer")
    loaded: Callable[..., Any] = load(target)
    return loaded


#: every simulator format, in the order the commands and tables list them
WRITERS: tuple[Writer, ...] = (
    Writer(
        name="abaqus",
        title="ABAQUS *SURFACE INTERACTION / *FRICTION table: mu, slip rate, pressure, "
              "temperature.",
        description="Abaqus input (CalculiX reads *FRICTION's columns differently). The slip "
                    "rate is each pair's own measured sliding speed.",
        holds="μ_K table (μ, slip rate, p, T); or μ_S→μ_K exponential decay "
              "(`--exponential-decay`)",
        engine="tribopipe.export.fe_decks:ABAQUS",
        table="tribopipe.export.fe_decks:write_abaqus",
        condition="tribopipe.export.fe_decks:write_abaqus_decay",
        table_options=(UNITS,),
        condition_options=(UNITS, DECAY),
        switch=Option("exponential_decay", "--exponential-decay", bool, False,
                      "One condition as *FRICTION, EXPONENTIAL DECAY (mu_s, mu_k, d_c); "
                      "needs mu_s."),
        slip_rate=True,
        snippet="tribopipe.export.fe_decks:condition_snippet",
        snippet_header="tribopipe.export.fe_decks:condition_header",
        snippet_options=(("fmt", "abaqus"),),
        snippet_label="ABAQUS *FRICTION (μ_K constant)",
        snippet_suffix="inp",
    ),
    Writer(
        name="ansys",
        title="Ansys MAPDL TB,FRIC,mat,,,ISO with TBFIELD on temperature and contact "
              "pressure.",
        description="",
        holds="μ_K table (TB,FRIC + TBFIELD NPRES, TEMP)",
        engine="tribopipe.export.fe_decks:ANSYS",
        table="tribopipe.export.fe_decks:write_ansys",
        table_options=(
            UNITS,
            Option("material_id", "--material-id", int, 1,
                   "Material number of the first pair's TB,FRIC table."),
        ),
        snippet="tribopipe.export.fe_decks:condition_snippet",
        snippet_header="tribopipe.export.fe_decks:condition_header",
        snippet_options=(("fmt", "ansys"),),
        snippet_label="Ansys TB,FRIC (μ_K constant)",
        snippet_suffix="mac",
    ),
    Writer(
        name="lsdyna",
        title="LS-DYNA *CONTACT_AUTOMATIC_SURFACE_TO_SURFACE_ID with FS, FD, DC for one "
              "condition.",
        description="Default FS = FD = mu_k, DC = 0, or FS, FD, DC fitted to mu_k over "
                    "the pair's measured sliding speeds where it has 3 or more (--speed "
                    "then names the condition's speed); with --coefficient mu_s: FS = "
                    "mu_s, FD = mu_k and the exponential decay coefficient DC.",
        holds="FS = FD = μ_K, or FS, FD, DC fitted to μ_K(v) where ≥ 3 speeds are measured; "
              "or FS = μ_S, FD = μ_K, DC (`--coefficient mu_s`)",
        engine="tribopipe.export.fe_decks:LSDYNA",
        condition="tribopipe.export.fe_decks:write_lsdyna",
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
    Writer(
        name="mujoco",
        title="MuJoCo <contact><pair friction=...> for one pair at one condition.",
        description="",
        holds="μ_K or μ_S (`--coefficient`) in an explicit `<pair>`",
        engine="tribopipe.export.scenes:MUJOCO",
        condition="tribopipe.export.scenes:write_mujoco",
        condition_options=(
            COEFFICIENT,
            Option("geom1", "--geom1", str, "pin", "MJCF name of the pin geom."),
            Option("geom2", "--geom2", str, "disc", "MJCF name of the disc geom."),
        ),
    ),
    Writer(
        name="sofa",
        title="SOFA CollisionResponse FrictionContactConstraint mu for one pair at one "
              "condition.",
        description="LCPConstraintSolver ignores this mu (it applies its own); use a solver "
                    "that honours per-contact mu (GenericConstraintSolver, "
                    "BlockGaussSeidelConstraintSolver).",
        holds="μ_K or μ_S (`--coefficient`)",
        engine="tribopipe.export.scenes:SOFA",
        condition="tribopipe.export.scenes:write_sofa",
        condition_options=(COEFFICIENT,),
    ),
    Writer(
        name="pyelastica",
        title="PyElastica static_mu_array / kinetic_mu_array for one pair at one condition.",
        description="For RodPlaneContactWithAnisotropicFriction (pyelastica >= 1.0); the "
                    "static array holds mu_k unless --coefficient mu_s.",
        holds="static μ_K or μ_S, kinetic μ_K",
        engine="tribopipe.export.scenes:PYELASTICA",
        condition="tribopipe.export.scenes:write_pyelastica",
        condition_options=(COEFFICIENT,),
    ),
    Writer(
        name="usd",
        title="OpenUSD physics material (static + dynamic friction) for one pair at one "
              "condition.",
        description="For Isaac Sim, Omniverse, PhysX and other UsdPhysics engines: one "
                    "material bound to both bodies, frictionCombineMode average, so the "
                    "contact gets the pair's value.",
        holds="staticFriction μ_S (μ_K where unknown), dynamicFriction μ_K on one material "
              "bound to both bodies",
        engine="tribopipe.export.usd:USD",
        condition="tribopipe.export.usd:write_usd",
        snippet="tribopipe.export.usd:write_usd",
        snippet_header="tribopipe.export.usd:usd_header",
        snippet_label="OpenUSD physics material (μ_S, μ_K)",
        snippet_suffix="usda",
    ),
    Writer(
        name="pybullet",
        title="PyBullet URDF <contact><lateral_friction> for one pair at one condition.",
        description="Bullet multiplies the two links' values: the pin's link gets mu, the "
                    "disc's 1.0 (--body disc writes the disc's URDF).",
        holds="μ_K or μ_S (`--coefficient`) on the pin's link, 1.0 on the disc's",
        engine="tribopipe.export.pybullet:PYBULLET",
        condition="tribopipe.export.pybullet:write_pybullet",
        condition_options=(
            COEFFICIENT,
            Option("body", "--body", str, "pin",
                   "Which body's URDF: the pin's link (the pair's mu) or the disc's (1.0).",
                   choices=("pin", "disc")),
        ),
        snippet="tribopipe.export.pybullet:write_pybullet",
        snippet_header="tribopipe.export.pybullet:pybullet_header",
        snippet_label="PyBullet URDF, the pin's link (μ_K)",
        snippet_suffix="urdf",
    ),
    Writer(
        name="drake",
        title="Drake SDFormat drake:mu_static / drake:mu_dynamic for one pair at one "
              "condition.",
        description="Both links carry the pair's values (Drake's 2 mu1 mu2 / (mu1 + mu2) "
                    "returns them); the discrete solvers use only mu_dynamic.",
        holds="mu_static μ_S (μ_K where unknown or below μ_K), mu_dynamic μ_K on both links",
        engine="tribopipe.export.drake:DRAKE",
        condition="tribopipe.export.drake:write_drake",
        snippet="tribopipe.export.drake:write_drake",
        snippet_header="tribopipe.export.drake:drake_header",
        snippet_label="Drake SDFormat (μ_S, μ_K)",
        snippet_suffix="sdf",
    ),
)

#: the format names, as ``export_simulator_input`` and ``tribopipe export`` take them
FORMATS: tuple[str, ...] = tuple(w.name for w in WRITERS)


def writer_named(fmt: str) -> Writer:
    """The :class:`Writer` of format ``fmt``, or an :class:`ExportError` listing them."""
    for writer in WRITERS:
        if writer.name == fmt:
            return writer
    raise ExportError(f"unknown simulator {fmt!r}; expected one of {', '.join(FORMATS)}")


def condition_labels() -> list[str]:
    """Every single-condition format as a user asks for it (``abaqus --exponential-decay``),
    then the table formats whose one condition is a constant (``abaqus``: its snippet)."""
    return ([w.label(True) for w in WRITERS if w.condition is not None]
            + [f"{w.name} (a constant)" for w in WRITERS
               if w.table is not None and w.snippet is not None])


def users(name: str) -> list[str]:
    """The formats (and modes) that take the option ``name``."""
    found = []
    for w in WRITERS:
        if any(o.name == name for o in w.table_options) or (
                w.table is None and any(o.name == name for o in w.condition_options)):
            found.append(w.name)
        elif any(o.name == name for o in w.condition_options) or (
                w.switch is not None and w.switch.name == name):
            found.append(w.label(True))
    return found


def option_named(name: str) -> Option:
    """The :class:`Option` called ``name`` (its flag and default are the same wherever
    it is declared), or an :class:`ExportError`."""
    for w in WRITERS:
        for option in w.options:
            if option.name == name:
                return option
    raise ExportError(f"unknown export option {name!r}")
