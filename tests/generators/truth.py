"""The known answer of a synthetic run of the validation families (``contact`` and
``ratestate``), and the rules that classify it.

The static peak is ``"distinct"`` when it stands at least :data:`DISTINCT_MARGIN` above
the plateau's highest noise-free value, ``"none"`` when it rises no more than
:data:`NONE_MARGIN` above it, and ``"ambiguous"`` in between (reported, not scored). A
plateau oscillating by less than :data:`OSCILLATION_MIN_PP` peak-to-peak is not scored as
stick-slip.
"""

from __future__ import annotations

from dataclasses import dataclass

DISTINCT_MARGIN = 0.02  # a static peak this far above the plateau's highs is distinct [COF]
NONE_MARGIN = 0.005  # a "peak" no higher than this above the plateau's highs is none [COF]
OSCILLATION_MIN_PP = 0.008  # a plateau oscillating less than this (peak-to-peak) is not scored


@dataclass(frozen=True)
class Truth:
    """What a correct reduction of a synthetic run must find.

    ``static`` is ``"distinct"``, ``"none"`` or ``"ambiguous"`` (:func:`static_kind`);
    ``oscillating`` says the plateau oscillates (stick-slip) by at least
    :data:`OSCILLATION_MIN_PP` peak-to-peak (``oscillation_pp``, noise-free);
    ``settle_mm`` where the plateau has settled; ``plateau_high`` the largest noise-free μ
    on it; ``truncated`` that the trace ends before the plateau settled (or before enough
    of it to score); ``offset_estimable`` that a set-up interval or a rest before motion
    shows the torque zero. Distances in mm of sliding, μ as COF.
    """

    mu_s: float
    mu_k: float
    mu_s_distance_mm: float
    static: str
    oscillating: bool
    oscillation_pp: float
    settle_mm: float
    plateau_high: float
    sliding_distance_mm: float
    truncated: bool
    offset_estimable: bool


def static_kind(mu_s: float, plateau_high: float) -> str:
    """``"distinct"``, ``"none"`` or ``"ambiguous"``: the noise-free peak ``mu_s`` against
    the plateau's highest noise-free value ``plateau_high`` (both COF)."""
    if mu_s >= plateau_high + DISTINCT_MARGIN:
        return "distinct"
    if mu_s <= plateau_high + NONE_MARGIN:
        return "none"
    return "ambiguous"
