"""Friction for PyBullet / Bullet: a URDF link whose ``<contact><lateral_friction>`` makes
the pin-disc contact get the pair's coefficient.

Bullet gives a contact the PRODUCT of the two bodies' lateral frictions, clamped to ±10
(``btManifoldResult::calculateCombinedFriction``): the same μ on both bodies would give
μ². So the pin's link carries μ and the disc's link 1.0, and the contact gets μ × 1.0 = μ.
One URDF holds one body: ``body="pin"`` (default) writes the pin's link, ``body="disc"``
the disc's. Names from the map reach the file only as ASCII XML comments; the robot and
link names are fixed (``pin``, ``disc``).
"""

from __future__ import annotations

from ..errors import ExportError
from ..query import QueryResult
from .coefficients import breakaway
from .headers import Engine, condition_lines, header_bodies
from .unit_systems import num
from .xml_text import xml_comment

PYBULLET = Engine(
    name="PyBullet",
    checked=(
        "pybullet 3.2.7 (the tests load this file with loadURDF, read getDynamicsInfo and "
        "measure the friction of a box sliding on the disc); combine rule from Bullet 3 "
        "btManifoldResult::calculateCombinedFriction"
    ),
    combination=(
        "Bullet multiplies the two links' lateral frictions and clamps the product to "
        "+/-10: the pin's link carries mu and the disc's link 1.0, so the contact gets "
        "mu x 1.0 = mu (mu on both would give mu squared)"
    ),
)

BODIES = ("pin", "disc")

#: the disc link's lateral friction: the neutral factor of Bullet's product
DISC_FRICTION = 1.0

#: Bullet clamps the combined friction to this magnitude
MAX_FRICTION = 10.0

#: placeholder geometry and inertia [m, kg, kg m^2] for trying the file
_GEOMETRY = {
    "pin": ("0.02 0.02 0.02", "0.1", "6.667e-06", "6.667e-06"),
    "disc": ("0.4 0.4 0.02", "1.0", "0.01337", "0.02667"),
}


def _holds(coefficient: str, body: str) -> str:
    """The 'holds' line: which body's link and which coefficient."""
    # no "--" here: an XML comment may not hold it
    which = ("mu_s, the static (breakaway) coefficient at the onset of slip"
             if coefficient == "mu_s" else "mu_k, the kinetic (sliding) coefficient; the "
             "export option 'coefficient mu_s' writes mu_s (breakaway) instead")
    if body == "disc":
        return (f"the disc's link: lateral_friction = {num(DISC_FRICTION)}, the neutral "
                "factor; the pin's link (export option 'body pin') carries the pair's mu")
    return (f"the pin's link: lateral_friction = {which}; the disc's link must carry 1.0 "
            "(export option 'body disc')")


def pybullet_header(
    source: str | None = None, *, coefficient: str = "mu_k", body: str = "pin"
) -> list[str]:
    """The opening lines of :func:`write_pybullet` (they do not depend on the condition)."""
    bodies = header_bodies(PYBULLET, _holds(coefficient, body), source, str)
    bodies += [
        "geometry and inertia are placeholders for trying the file: copy the <contact> "
        "element into your own link",
        "pybullet: loadURDF(file); the contact's lateral friction is the product of both "
        "links' values (getDynamicsInfo(body, -1)[1] reads one link's)",
    ]
    return ['<?xml version="1.0"?>', *(xml_comment(b, ascii_only=True) for b in bodies)]


def write_pybullet(
    res: QueryResult,
    *,
    coefficient: str = "mu_k",
    body: str = "pin",
    source: str | None = None,
) -> str:
    """A URDF with one link, the pin's (lateral friction μ_K, or μ_S with
    ``coefficient="mu_s"``) or the disc's (1.0), for one query result ``res`` (one pair at
    one contact pressure [kPa] and temperature [°C]). Refuses a μ above Bullet's clamp
    (10) in one line."""
    if body not in BODIES:
        raise ExportError(f"unknown body {body!r}; expected one of {', '.join(BODIES)}")
    mu = breakaway(res, coefficient, "PyBullet")
    if mu > MAX_FRICTION:
        raise ExportError(f"mu = {num(mu)} exceeds Bullet's clamp of the combined friction "
                          f"({num(MAX_FRICTION)}): the engine would not use it")
    value = mu if body == "pin" else DISC_FRICTION
    size, mass, ixx, izz = _GEOMETRY[body]
    lines = pybullet_header(source, coefficient=coefficient, body=body)
    lines += [xml_comment(b, ascii_only=True) for b in [
        *condition_lines(res, str),
        f"contact: pin {num(mu)} x disc {num(DISC_FRICTION)} = {num(mu * DISC_FRICTION)}",
    ]]
    lines += [
        f'<robot name="{body}">',
        f'  <link name="{body}">',
        "    <contact>",
        f'      <lateral_friction value="{num(value)}"/>',
        "    </contact>",
        "    <inertial>",
        f'      <mass value="{mass}"/>',
        f'      <inertia ixx="{ixx}" ixy="0" ixz="0" iyy="{ixx}" iyz="0" izz="{izz}"/>',
        "    </inertial>",
        "    <collision>",
        f'      <geometry><box size="{size}"/></geometry>',
        "    </collision>",
        "  </link>",
        "</robot>",
    ]
    return "\n".join(lines) + "\n"

