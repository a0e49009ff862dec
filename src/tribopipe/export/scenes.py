"""Friction for the robotics simulators: MuJoCo (MJCF), SOFA (scene XML), PyElastica (Python).

These engines take one coefficient for the onset of slip (PyElastica a static and a
kinetic array) at one condition: each writer takes the query result of one pair at one
contact pressure and temperature and writes μ_K, or μ_S (breakaway) with ``coefficient="mu_s"``
— refused in one line where the map holds no μ_S for the pair. Every header says which
engine and version it was checked against, which coefficient it holds and how the engine
combines two surfaces' values. Names from the map reach these files only as inert
comment text (:func:`tribopipe.escape.sim_comment`), XML-escaped attribute values or Python
string literals (:func:`repr`).
"""

from __future__ import annotations

from ..query import QueryResult
from .coefficients import breakaway
from .headers import Engine, condition_lines, header_bodies
from .unit_systems import num
from .xml_text import xml_comment, xml_name

MUJOCO = Engine(
    name="MuJoCo",
    checked="mujoco 4.0.0 (the tests compile this file in MuJoCo and read the pair's friction)",
    combination=(
        "MuJoCo gives each contact the element-wise maximum of the two geoms' friction "
        "(or the higher-priority geom's); an explicit <pair>, as here, sets the pair's own "
        "value and overrides both rules"
    ),
)

SOFA = Engine(
    name="SOFA",
    checked=(
        "SOFA source v24.12-v25.x (CollisionResponse response/responseParams, "
        "FrictionContactConstraint mu, LCPConstraintSolver, GenericConstraintSolver and "
        "BlockGaussSeidelConstraintSolver); not run in SOFA"
    ),
    combination=(
        "SOFA has no per-surface friction: mu belongs to the contact response, for every "
        "contact (CollisionResponse) or per pair of collision groups (a RuleBasedContactManager "
        "rule 'group1 group2 FrictionContactConstraint?mu=...'); nothing is combined"
    ),
)

#: Said in every SOFA file: which constraint solvers use the per-contact mu at all.
SOFA_SOLVER_NOTE = (
    "the constraint solver decides whether this mu is used: LCPConstraintSolver applies its "
    "own mu (default 0.6) to every contact and ignores the per-contact mu written here; "
    "GenericConstraintSolver and BlockGaussSeidelConstraintSolver (and the Gauss-Seidel/NNCG "
    "solvers that replace GenericConstraintSolver in newer SOFA) honour it"
)

PYELASTICA = Engine(
    name="PyElastica",
    checked=(
        "pyelastica 1.0.0 (the tests build RodPlaneContactWithAnisotropicFriction from "
        "this file and read its coefficients)"
    ),
    combination=(
        "PyElastica takes the coefficients of one rod-plane contact, not of a surface: "
        "these are the pair's values, nothing is combined"
    ),
)


def _holds(coefficient: str, one: str) -> str:
    """The 'holds' line of a single-coefficient engine (``one`` names its parameter)."""
    if coefficient == "mu_s":
        return f"{one} = mu_s, the static (breakaway) coefficient at the onset of slip"
    # no "--" here: an XML comment may not hold it (xml_comment would print "- -coefficient")
    return (f"{one} = mu_k, the kinetic (sliding) coefficient; the export option "
            "'coefficient mu_s' writes mu_s (breakaway) instead")


def write_mujoco(
    res: QueryResult,
    *,
    coefficient: str = "mu_k",
    geom1: str = "pin",
    geom2: str = "disc",
    source: str | None = None,
) -> str:
    """An MJCF file for ``<include>``: a ``<contact><pair>`` with the pair's sliding friction.

    MuJoCo has one Coulomb coefficient per contact (no static/kinetic split): μ_K, or μ_S
    with ``coefficient="mu_s"``, in both tangential directions. Torsional and rolling
    coefficients are not measured: MuJoCo's defaults (0.005, 0.0001) are written.
    ``geom1``/``geom2`` are the MJCF names of the pin and disc geoms.
    """
    mu = num(breakaway(res, coefficient, "MuJoCo"))
    attr1, attr2 = xml_name(geom1, "geom1"), xml_name(geom2, "geom2")
    # xml_comment makes every body inert: the bodies go in unescaped, escaped once there
    bodies = header_bodies(MUJOCO, _holds(coefficient, "sliding friction"), source, str)
    bodies += condition_lines(res, str)
    bodies += [
        "torsional 0.005 and rolling 0.0001 are MuJoCo's defaults, not measured",
        "use: <include file=\"this file\"/> in a model whose geoms carry these names",
    ]
    lines = [xml_comment(b) for b in bodies]
    lines += [
        "<mujoco>",
        "  <contact>",
        f"    <pair geom1={attr1} geom2={attr2} condim=\"3\" "
        f"friction=\"{mu} {mu} 0.005 0.0001 0.0001\"/>",
        "  </contact>",
        "</mujoco>",
    ]
    return "\n".join(lines) + "\n"


def write_sofa(
    res: QueryResult,
    *,
    coefficient: str = "mu_k",
    source: str | None = None,
) -> str:
    """A SOFA scene fragment: ``CollisionResponse`` with ``FrictionContactConstraint`` and mu.

    SOFA's frictional contact takes one Coulomb μ for the response: μ_K, or μ_S with
    ``coefficient="mu_s"``. Older SOFA versions name the component
    ``DefaultContactManager`` and the response ``FrictionContact``; the header says which
    constraint solvers use this μ at all (:data:`SOFA_SOLVER_NOTE`).
    """
    mu = num(breakaway(res, coefficient, "SOFA"))
    bodies = header_bodies(SOFA, _holds(coefficient, "mu"), source, str)
    bodies += [SOFA_SOLVER_NOTE, *condition_lines(res, str)]
    lines = [xml_comment(b) for b in bodies]
    lines += [
        '<Node name="root">',
        '  <CollisionResponse name="response" response="FrictionContactConstraint" '
        f'responseParams="mu={mu}"/>',
        "</Node>",
    ]
    return "\n".join(lines) + "\n"


def write_pyelastica(
    res: QueryResult,
    *,
    coefficient: str = "mu_k",
    source: str | None = None,
) -> str:
    """Python for pyelastica ≥ 1.0: ``static_mu_array`` and ``kinetic_mu_array`` ([forward,
    backward, sideways]) for ``RodPlaneContactWithAnisotropicFriction``; isotropic data,
    so all three are equal.

    ``kinetic_mu_array`` is μ_K. ``static_mu_array`` — the coefficient at the onset of
    slip — is μ_K too by default (no breakaway peak) and μ_S with ``coefficient="mu_s"``.
    The pair's names are a Python literal (:func:`repr`), everything else is a comment.
    """
    mu_s = num(breakaway(res, coefficient, "PyElastica's static_mu_array"))
    mu_k = num(res.mu_k.value)
    bodies = header_bodies(PYELASTICA, _holds(coefficient, "static_mu_array")
                           + "; kinetic_mu_array = mu_k", source)
    bodies += condition_lines(res)
    bodies += [
        "arrays are [forward, backward, sideways]; the pin-on-disc data are isotropic",
        "use (pyelastica >= 1.0; AnisotropicFrictionalPlane is gone):",
        "  from elastica import (BaseSystemCollection, Contact, Plane,",
        "                        RodPlaneContactWithAnisotropicFriction)",
        "  class Simulator(BaseSystemCollection, Contact): ...  # Contact: detect_contact_between",
        "  simulator = Simulator()  # ... append the rod",
        "  plane = Plane(plane_origin=..., plane_normal=...)",
        "  simulator.append(plane)",
        "  simulator.detect_contact_between(rod, plane).using(",
        "      RodPlaneContactWithAnisotropicFriction, k=..., nu=..., slip_velocity_tol=...,",
        "      static_mu_array=static_mu_array, kinetic_mu_array=kinetic_mu_array)",
    ]
    lines = [f"# {b}".rstrip() for b in bodies]
    lines += [
        "import numpy as np",
        "",
        f"PAIR = ({res.pin!r}, {res.disc!r})  # (pin, disc) as named in the map",
        f"static_mu_array = np.array([{mu_s}, {mu_s}, {mu_s}])",
        f"kinetic_mu_array = np.array([{mu_k}, {mu_k}, {mu_k}])",
    ]
    return "\n".join(lines) + "\n"

