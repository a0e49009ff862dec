"""Friction for OpenUSD physics (``UsdPhysics``; Isaac Sim, Omniverse, PhysX, Newton): one
physics material holding the pair's static and dynamic coefficients.

PhysX combines the two bodies' materials by their ``physxMaterial:frictionCombineMode``
(the higher-priority mode of the two wins: average < min < multiply < max), static and
dynamic separately, then raises a static coefficient below the dynamic one to it
(``PxsCombineMaterials``). The file binds ONE material to both bodies, so both sides carry
the pair's values and the authored mode, ``average``, returns them unchanged: average(μ, μ)
= μ (so would min or max, and any other engine's mean of two equal values; multiply would
give μ² and is not used). ``physics:staticFriction`` is always authored: unauthored, it
falls back to 0.0. Names from the map reach the file only as ASCII ``#`` comments.
"""

from __future__ import annotations

from ..escape import sim_comment
from ..query import QueryResult
from .coefficients import static_and_dynamic
from .headers import Engine, condition_lines, header_bodies
from .unit_systems import num

USD = Engine(
    name="OpenUSD UsdPhysics",
    checked=(
        "usd-core 26.11 with physx-usd-schemas 25.11 (the tests open this file with pxr and "
        "read the authored static and dynamic friction, the combine mode and the bindings); "
        "combine rule from PhysX 5 PxsMaterialCombiner.h"
    ),
    combination=(
        "PhysX combines the two bodies' materials by the higher-priority frictionCombineMode "
        "of the two (average < min < multiply < max), static and dynamic separately; this "
        "file binds one material to both bodies with mode average, so the contact gets "
        "average(mu, mu) = mu, the pair's value (min or max would too, multiply would give "
        "mu squared)"
    ),
)

#: the example colliders [m]: a 20 mm cube pin resting on a 400 mm disc, 20 mm thick
_EXAMPLES = (
    ('Cube "Pin"', ("double size = 0.02", "double3 xformOp:translate = (0, 0, 0.02)")),
    ('Cylinder "Disc"', ('uniform token axis = "Z"', "double height = 0.02",
                         "double radius = 0.2", "double3 xformOp:translate = (0, 0, 0)")),
)

#: the prim paths the file defines (fixed names: the pair's names stay in comments)
MATERIAL_PATH = "/TribopipeFriction/PinOnDisc"
COMBINE_MODE = "average"

HOLDS = ("physics:dynamicFriction = mu_k, physics:staticFriction = mu_s (mu_k where the map "
         "holds no mu_s) on one physics material (PhysicsMaterialAPI + PhysxMaterialAPI) "
         f"bound to both bodies, physxMaterial:frictionCombineMode = {COMBINE_MODE}")


def comment(body: str) -> str:
    """One ASCII ``#`` comment line that no content can break."""
    return f"# {sim_comment(body, '#', ascii_only=True)}".rstrip()


def usd_header(source: str | None = None) -> list[str]:
    """The opening lines of :func:`write_usd` (they do not depend on the condition)."""
    bodies = header_bodies(USD, HOLDS, source, str)
    bodies += [
        "staticFriction is always authored: left unauthored it falls back to 0.0",
        "use: bind the material to your pin's and disc's colliders "
        "(rel material:binding:physics), as the example prims Pin and Disc do",
    ]
    return ["#usda 1.0", "(", "    metersPerUnit = 1", '    upAxis = "Z"', ")",
            *(comment(b) for b in bodies)]


def write_usd(res: QueryResult, *, source: str | None = None) -> str:
    """A ``.usda`` layer for one query result ``res`` (one pair at one contact pressure
    [kPa] and temperature [°C]): the material ``/TribopipeFriction/PinOnDisc`` with the
    pair's static and dynamic friction
    (:func:`~.coefficients.static_and_dynamic`) and the
    combine mode, bound (purpose ``physics``) to two example colliders, a cube Pin resting
    on a cylinder Disc."""
    static, dynamic, how = static_and_dynamic(res)
    lines = usd_header(source)
    lines += [comment(b) for b in [*condition_lines(res, str), how]]
    lines += [
        "",
        'def Scope "TribopipeFriction"',
        "{",
        '    def Material "PinOnDisc" (',
        '        prepend apiSchemas = ["PhysicsMaterialAPI", "PhysxMaterialAPI"]',
        "    )",
        "    {",
        f"        float physics:dynamicFriction = {num(dynamic)}",
        f"        float physics:staticFriction = {num(static)}",
        f'        uniform token physxMaterial:frictionCombineMode = "{COMBINE_MODE}"',
        "    }",
    ]
    for prim, shape in _EXAMPLES:
        lines += [
            "",
            f'    def {prim} (',
            '        prepend apiSchemas = ["PhysicsCollisionAPI", "MaterialBindingAPI"]',
            "    )",
            "    {",
            *(f"        {line}" for line in shape),
            f"        rel material:binding:physics = <{MATERIAL_PATH}>",
            '        uniform token[] xformOpOrder = ["xformOp:translate"]',
            "    }",
        ]
    lines.append("}")
    return "\n".join(lines) + "\n"

