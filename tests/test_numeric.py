"""One rule for "finite" everywhere: a number that is neither missing, text, NaN nor ±inf."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tribopipe.numeric import finite_or_nan, finite_or_none, is_finite

#: (value, its finite float or None when it is not finite)
CASES = [
    (0.55, 0.55),
    (-3, -3.0),
    ("0.55", 0.55),
    (np.float64(1.5), 1.5),
    (True, 1.0),
    (None, None),
    (float("nan"), None),
    (float("inf"), None),
    (-math.inf, None),
    ("n/a", None),
    ("", None),
    ([1.0], None),
]


@pytest.mark.parametrize(("value", "expected"), CASES)
def test_finite_or_none_keeps_numbers_and_drops_the_rest(value, expected) -> None:
    assert finite_or_none(value) == expected


@pytest.mark.parametrize(("value", "expected"), CASES)
def test_the_three_helpers_agree_on_what_is_finite(value, expected) -> None:
    assert is_finite(value) is (expected is not None)
    nan_form = finite_or_nan(value)
    if expected is None:
        assert math.isnan(nan_form)
    else:
        assert nan_form == expected


def test_the_old_names_still_import() -> None:
    from tribopipe.numeric import finite_or_none as from_pipeline

    assert from_pipeline is finite_or_none
