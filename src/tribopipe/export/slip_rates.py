"""A pair's sliding speed as the engines take it: the slip rate of an ABAQUS table and
the default decay coefficient of an exponential-decay model, from the median recorded
sliding speed of the pair's own runs (the founding paper's 0.007 mm/s where none records
one)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

from ..physics import FOUNDING_SLIDING_SPEED_MM_S

if TYPE_CHECKING:
    import pandas as pd


@dataclass(frozen=True)
class SlipRate:
    """One pair's sliding speed [mm/s]: the median of its runs, with their range.

    ``n_runs == 0`` means no run of the pair records a speed and the founding paper's
    0.007 mm/s stands in (said so in the file).
    """

    value_mm_s: float
    n_runs: int
    min_mm_s: float
    max_mm_s: float

    @property
    def measured(self) -> bool:
        """True when the value comes from the pair's own runs."""
        return self.n_runs > 0

    def describe(self) -> str:
        """One comment line saying where the slip rate came from."""
        if not self.measured:
            return (f"slip rate {self.value_mm_s:g} mm/s: no run of this pair records its "
                    "sliding speed, the founding paper's speed stands in")
        spread = (f"all at {self.min_mm_s:.4g} mm/s" if self.min_mm_s == self.max_mm_s
                  else f"{self.min_mm_s:.4g}-{self.max_mm_s:.4g} mm/s")
        text = (f"slip rate {self.value_mm_s:.4g} mm/s: median recorded sliding speed of this "
                f"pair's {self.n_runs} run(s), {spread}")
        if self.max_mm_s > 1.25 * self.min_mm_s:
            text += ("; FLAG: runs at speeds more than 25 % apart, the file holds no "
                     "slip-rate dependence")
        return text


FOUNDING_SLIP_RATE = SlipRate(FOUNDING_SLIDING_SPEED_MM_S, 0, math.nan, math.nan)


def slip_rate_of(rates: Mapping[tuple[str, str], SlipRate] | None, pin: str, disc: str) -> SlipRate:
    """The pair's :class:`SlipRate` from ``rates`` (keyed by the map's pin and disc names),
    or the founding paper's speed where the pair has none."""
    if rates is None:
        return FOUNDING_SLIP_RATE
    return rates.get((pin, disc), FOUNDING_SLIP_RATE)


def pair_slip_rates(runs: pd.DataFrame) -> dict[tuple[str, str], SlipRate]:
    """Each pair's :class:`SlipRate` from friction-map ``runs`` (excluded runs left out;
    runs without a positive finite ``sliding_speed_mm_s`` do not count)."""
    import numpy as np

    if runs.empty or "sliding_speed_mm_s" not in runs.columns:
        return {}
    if "excluded" in runs.columns:
        runs = runs[~runs["excluded"].fillna(False).astype(bool)]
    rates = {}
    for (pin, disc), group in runs.groupby(["pin", "disc"], sort=True):
        speed = group["sliding_speed_mm_s"].to_numpy(dtype=float)
        speed = speed[np.isfinite(speed) & (speed > 0)]
        if speed.size:
            rates[(str(pin), str(disc))] = SlipRate(
                float(np.median(speed)), int(speed.size), float(speed.min()), float(speed.max())
            )
    return rates


def default_decay_s_per_mm(slip_rate_mm_s: float = FOUNDING_SLIDING_SPEED_MM_S) -> float:
    """d_c [s/mm] that lets μ decay 99 % of the way from μ_S to μ_K at the measured slip rate.

    The exponential model (ABAQUS, LS-DYNA) is μ = μ_k + (μ_s − μ_k)·exp(−d_c·v); a
    single-speed test cannot measure d_c, so we pick the value for which the measured
    μ_K holds at the test's sliding speed v: exp(−d_c·v) = 0.01.
    """
    return math.log(100.0) / slip_rate_mm_s
