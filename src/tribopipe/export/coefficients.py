"""Which measured coefficient an engine gets: μ_K or μ_S for the onset of slip, the static
and dynamic pair of an engine that takes both, and the checks of a user's choice.

Light: the standard library only (a query result is only a type here), so that the
command line can check and offer the choices without loading numpy or pandas.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from ..errors import ExportError
from .unit_systems import num

if TYPE_CHECKING:
    from ..query import QueryResult

#: Which measured coefficient a single-coefficient engine gets for the onset of slip.
COEFFICIENTS: tuple[str, ...] = ("mu_k", "mu_s")


def check_coefficient(coefficient: str) -> str:
    """``coefficient`` when it is one of :data:`COEFFICIENTS`, else an :class:`ExportError`."""
    if coefficient not in COEFFICIENTS:
        raise ExportError(
            f"unknown coefficient {coefficient!r}; expected one of {', '.join(COEFFICIENTS)}"
        )
    return coefficient


def breakaway(res: QueryResult, coefficient: str, engine: str) -> float:
    """The coefficient for the onset of slip: μ_K, or μ_S where asked (``"mu_s"``).

    Refuses ``"mu_s"`` in one line when the map holds no μ_S for the pair (a published map
    holds μ_K only): never a silent μ_K in its place.
    """
    if check_coefficient(coefficient) == "mu_k":
        return res.mu_k.value
    if res.mu_s is None:
        raise ExportError(
            f"pin {res.pin!r} on disc {res.disc!r} has no mu_s in the "
            f"map (e.g. an imported published map holds mu_k only): {engine} cannot get the "
            "breakaway coefficient",
            hint="leave out --coefficient mu_s to write mu_k",
        )
    return res.mu_s.value


#: where :func:`static_and_dynamic`'s static coefficient came from, worded once (the
#: explorer page receives these texts; ``{mu_s}`` is the map's μ_S)
STATIC_WHY = {
    "no_mu_s": "static = mu_k: the map holds no mu_s for this pair (an imported published map "
               "holds mu_k only), so the onset of slip takes the kinetic coefficient; the "
               "static coefficient is written all the same, never left to the engine's default",
    "raised": "static = mu_k: the map's mu_s ({mu_s}) is below mu_k at this condition and "
              "the engine needs static >= dynamic, so static is raised to mu_k",
    "mu_s": "static = mu_s (breakaway), dynamic = mu_k (sliding)",
}


def static_and_dynamic(res: QueryResult) -> tuple[float, float, str]:
    """The static and dynamic coefficients for an engine that takes both, and one line
    saying where the static one came from.

    Static is μ_S where the map holds it, else μ_K (a published map holds μ_K only): the
    onset of slip then takes the kinetic coefficient, and the static coefficient is still
    written, never left to the engine's default. Where the map's μ_S is below μ_K at the
    condition, static is raised to μ_K (engines want static ≥ dynamic: PhysX raises it
    itself, Drake refuses the file).
    """
    mu_k = res.mu_k.value
    if res.mu_s is None:
        return mu_k, mu_k, STATIC_WHY["no_mu_s"]
    if res.mu_s.value < mu_k:
        return mu_k, mu_k, STATIC_WHY["raised"].format(mu_s=num(res.mu_s.value))
    return res.mu_s.value, mu_k, STATIC_WHY["mu_s"]


def check_decay(decay_s_per_mm: float) -> float:
    """``decay_s_per_mm`` when it is a positive finite number, else an :class:`ExportError`."""
    if not (math.isfinite(decay_s_per_mm) and decay_s_per_mm > 0):
        raise ExportError(
            f"decay coefficient must be a positive number of s/mm, got {decay_s_per_mm}"
        )
    return decay_s_per_mm
