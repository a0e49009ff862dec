"""Numbers that come from outside a computation: one family of "finite" helpers.

A value is *finite* when ``float(value)`` succeeds and gives neither NaN nor ±inf; ``None``,
text that is not a number, NaN and ±inf are not. The three helpers share that rule and
differ only in what stands for "not finite":

================================  ===============  =============================================
helper                            not finite gives  used for
================================  ===============  =============================================
:func:`finite_or_none`            ``None``         JSON and CSV outputs (``null``, an empty cell)
:func:`finite_or_nan`             ``NaN``          numeric table columns (the map's float columns)
:func:`is_finite`                 ``False``        deciding whether to draw or print a value
================================  ===============  =============================================

None of them raises.
"""

from __future__ import annotations

import math
from typing import Any


def finite_or_none(value: Any) -> float | None:
    """``float(value)`` for JSON and CSV outputs; ``None`` for a missing, non-numeric,
    NaN or infinite value."""
    if value is None:
        return None
    try:
        value = float(value)
    except (TypeError, ValueError):
        return None
    return value if math.isfinite(value) else None


def finite_or_nan(value: Any) -> float:
    """``float(value)`` for a numeric column; NaN for a missing, non-numeric, NaN or
    infinite value."""
    number = finite_or_none(value)
    return math.nan if number is None else number


def is_finite(value: Any) -> bool:
    """True when ``value`` is a finite number (see the module docstring)."""
    return finite_or_none(value) is not None
