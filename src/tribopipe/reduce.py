"""Pure physics of a pin-on-disc run: pressure, COF trace, sliding distance, μ_S and μ_K.

(Placeholder to be replaced by the reduction implementation.)
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class ReductionParams:
    """Parameters of the μ_S / μ_K detection."""

    median_window: int = 5
