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

None of them raises. :func:`finite_json` applies ``finite_or_none``'s rule to a whole
JSON-ready structure (every JSON output is strict: no ``NaN`` or ``Infinity``).
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


def finite_json(value: Any) -> Any:
    """``value`` (dicts, lists, tuples, numbers, text) with every non-finite float (NaN,
    ±inf, NumPy's included) replaced by ``None``, NumPy scalars by Python numbers, so that
    ``json.dumps(..., allow_nan=False)`` writes strict JSON."""
    if isinstance(value, dict):
        return {k: finite_json(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [finite_json(v) for v in value]
    if isinstance(value, bool) or value is None or isinstance(value, str | int):
        return value
    if hasattr(value, "item") and callable(value.item):  # a NumPy scalar
        try:
            return finite_json(value.item())
        except (TypeError, ValueError):
            return str(value)
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    return value
