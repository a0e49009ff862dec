"""Friction for Drake: an SDFormat model whose two links carry the pair's static and dynamic
coefficients as ``drake:proximity_properties``.

Drake combines two geometries' coefficients as 2·μ₁·μ₂/(μ₁ + μ₂), static and dynamic
separately (``CalcContactFrictionFromSurfaceProperties``): with the same value on both
bodies this returns it, so pin and disc both carry the pair's μ. Drake refuses a dynamic
coefficient above the static one; :func:`~.coefficients.static_and_dynamic` raises the static to
the dynamic there and says so. Drake's discrete solvers (``time_step > 0``: TAMSI, SAP)
use only ``mu_dynamic``; ``mu_static`` matters to the continuous (Stribeck) model. Names
from the map reach the file only as ASCII XML comments; model and link names are fixed.
"""

from __future__ import annotations

from ..query import QueryResult
from .coefficients import static_and_dynamic
from .headers import Engine, condition_lines, header_bodies
from .unit_systems import num
from .xml_text import xml_comment

DRAKE = Engine(
    name="Drake",
    checked=(
        "drake 1.51.1 (the tests parse this file with Parser, Finalize the plant and "
        "combine the two geometries' CoulombFriction with "
        "CalcContactFrictionFromSurfaceProperties)"
    ),
    combination=(
        "Drake combines the two geometries' coefficients as 2 mu1 mu2 / (mu1 + mu2), static "
        "and dynamic separately; both links carry the pair's values, so the contact gets "
        "them back (2 mu mu / 2 mu = mu)"
    ),
)

HOLDS = ("drake:mu_dynamic = mu_k, drake:mu_static = mu_s (mu_k where the map holds no mu_s "
         "or its mu_s is below mu_k) on the pin's and the disc's collision geometry (the same "
         "values on both)")

#: placeholder geometry and inertia [m, kg, kg m^2] for trying the file
_LINKS = (
    ("pin", "0 0 0.02 0 0 0", "0.02 0.02 0.02", "0.1", "6.667e-06", "6.667e-06"),
    ("disc", "0 0 0 0 0 0", "0.4 0.4 0.02", "1.0", "0.01337", "0.02667"),
)


def drake_header(source: str | None = None) -> list[str]:
    """The opening lines of :func:`write_drake` (they do not depend on the condition)."""
    bodies = header_bodies(DRAKE, HOLDS, source, str)
    bodies += [
        "Drake's discrete solvers (time_step > 0: TAMSI, SAP) use only mu_dynamic; "
        "mu_static matters to the continuous model (time_step = 0)",
        "Drake refuses mu_dynamic > mu_static: where the map's mu_s is below mu_k, "
        "mu_static is raised to mu_k (said below)",
        "geometry and inertia are placeholders for trying the file: copy the "
        "drake:proximity_properties into your own collision elements",
    ]
    return ['<?xml version="1.0"?>', *(xml_comment(b, ascii_only=True) for b in bodies)]


def write_drake(res: QueryResult, *, source: str | None = None) -> str:
    """An SDFormat model ``tribopipe_pin_on_disc`` with two links, ``pin`` and ``disc``,
    whose collision geometries both carry the pair's ``drake:mu_static`` and
    ``drake:mu_dynamic`` (:func:`~.coefficients.static_and_dynamic`) for one query result ``res``
    (one pair at one contact pressure [kPa] and temperature [°C])."""
    static, dynamic, how = static_and_dynamic(res)
    lines = drake_header(source)
    lines += [xml_comment(b, ascii_only=True) for b in [*condition_lines(res, str), how]]
    lines += [
        '<sdf version="1.9" xmlns:drake="http://drake.mit.edu">',
        '  <model name="tribopipe_pin_on_disc">',
    ]
    for name, pose, size, mass, ixx, izz in _LINKS:
        lines += [
            f'    <link name="{name}">',
            f"      <pose>{pose}</pose>",
            "      <inertial>",
            f"        <mass>{mass}</mass>",
            f"        <inertia><ixx>{ixx}</ixx><iyy>{ixx}</iyy><izz>{izz}</izz>"
            "<ixy>0</ixy><ixz>0</ixz><iyz>0</iyz></inertia>",
            "      </inertial>",
            f'      <collision name="{name}_collision">',
            f"        <geometry><box><size>{size}</size></box></geometry>",
            "        <drake:proximity_properties>",
            f"          <drake:mu_dynamic>{num(dynamic)}</drake:mu_dynamic>",
            f"          <drake:mu_static>{num(static)}</drake:mu_static>",
            "        </drake:proximity_properties>",
            "      </collision>",
            "    </link>",
        ]
    lines += ["  </model>", "</sdf>"]
    return "\n".join(lines) + "\n"

