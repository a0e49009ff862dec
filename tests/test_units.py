"""Unit strings as Anton Paar software writes them → SI, checked conversion by conversion."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from tribopipe.errors import ReadError
from tribopipe.units import canonical_unit, normalize_unit, parse_unit, sanitize_suffix


@pytest.mark.parametrize(
    ("unit", "value", "si", "suffix"),
    [
        ("[mN·m]", 2.3981, 2.3981e-3, "Nm"),  # RheoCompass, U+00B7
        ("[µN·m]", 0.0026733, 2.6733e-9, "Nm"),  # U+00B5 micro sign
        ("[μN·m]", 1.0, 1e-6, "Nm"),  # U+03BC Greek mu
        ("[µNm]", -1.51e3, -1.51e-3, "Nm"),  # Rheoplus
        ("[mNm]", 75.0, 0.075, "Nm"),
        ("[N·m]", 0.5, 0.5, "Nm"),
        ("[ÂµNm]", 32.7, 3.27e-5, "Nm"),  # UTF-8 µ read as cp1252
        ("[N]", 3.0, 3.0, "N"),
        ("[mN]", 250.0, 0.25, "N"),
        ("[°]", 180.0, math.pi, "rad"),
        ("[rad]", 1.5, 1.5, "rad"),
        ("[mrad]", 1.14, 1.14e-3, "rad"),
        ("[rad/s]", 2.0, 2.0, "rad_s"),
        ("[°C]", 21.0, 21.0, "C"),
        ("[Â°C]", 37.0, 37.0, "C"),
        ("[K]", 293.15, 20.0, "C"),
        ("[s]", 6.0, 6.0, "s"),
        ("[min]", 2.0, 120.0, "s"),
        ("[Pa]", 73.196, 73.196, "Pa"),
        ("[kPa]", 1.2, 1200.0, "Pa"),
        ("[mPa·s]", 72195.0, 72.195, "Pa_s"),
        ("[Pa·s]", 16.9, 16.9, "Pa_s"),
        ("[PaÂ·s]", 16.9, 16.9, "Pa_s"),
        ("[%]", 2.96, 2.96, "pct"),
        ("[1]", 1.432, 1.432, ""),
        ("[Hz]", 0.3, 0.3, "Hz"),
        ("[1/s]", 300.0, 300.0, "1_s"),
        ("[]", 4.0, 4.0, ""),
    ],
)
def test_each_unit_converts_to_si(unit: str, value: float, si: float, suffix: str) -> None:
    spec = parse_unit(unit)
    assert spec is not None, unit
    assert spec.suffix == suffix
    assert spec.to_si(np.array([value]))[0] == pytest.approx(si, rel=1e-12)


@pytest.mark.parametrize(
    ("unit", "rad_s"),
    [("[1/min]", 2 * math.pi / 60), ("[rpm]", 2 * math.pi / 60), ("[1/s]", 2 * math.pi),
     ("[rad/s]", 1.0)],
)
def test_rotational_speed_counts_revolutions(unit: str, rad_s: float) -> None:
    spec = parse_unit(unit, "speed")
    assert spec is not None and spec.suffix == "rad_s"
    assert spec.factor == pytest.approx(rad_s)
    # the founding setup: 0.005 rpm
    assert spec.to_si(np.array([0.005]))[0] == pytest.approx(0.005 * rad_s)


def test_a_shear_rate_in_1_per_s_is_not_a_speed() -> None:
    spec = parse_unit("[1/s]")
    assert spec is not None and spec.suffix == "1_s" and spec.factor == 1.0


@pytest.mark.parametrize("unit", ["[furlong]", "[mN/m²]", "[µNm/s²]", "[Nm2]"])
def test_unknown_units_are_not_guessed(unit: str) -> None:
    assert parse_unit(unit) is None


def test_normalisation_unifies_dots_micro_and_brackets() -> None:
    assert normalize_unit("[µN·m]") == normalize_unit("[μN.m]") == normalize_unit(" µNm ")
    assert normalize_unit("[Âµ NÂ·m]") == "µNm"
    assert normalize_unit("[deg]") == normalize_unit("[º]") == "°"
    assert parse_unit("[deg]") == parse_unit("[°]")


def test_unknown_units_get_a_safe_suffix() -> None:
    assert sanitize_suffix("[Pa/mNm]") == "Pa_mNm"
    assert sanitize_suffix("[µm²]") == "um2"


def test_canonical_quantity_in_unknown_unit_names_column_and_unit() -> None:
    with pytest.raises(ReadError) as exc:
        canonical_unit("torque", "[lbf·in]", column="Torque", path="run.csv")
    message = str(exc.value)
    assert "run.csv" in message and "'Torque'" in message and "lbf·in" in message


def test_canonical_quantity_in_a_unit_of_the_wrong_kind_is_refused() -> None:
    with pytest.raises(ReadError, match="wrong kind"):
        canonical_unit("torque", "[N]", column="Torque")
    with pytest.raises(ReadError, match="no unit"):
        canonical_unit("normal_force", "", column="Normal Force")


@given(st.floats(min_value=-1e6, max_value=1e6, allow_nan=False))
def test_prefixes_scale_by_powers_of_ten(x: float) -> None:
    values = np.array([x])
    base = parse_unit("[N·m]").to_si(values)[0]
    assert parse_unit("[mN·m]").to_si(values)[0] == pytest.approx(base * 1e-3, abs=1e-300)
    assert parse_unit("[µN·m]").to_si(values)[0] == pytest.approx(base * 1e-6, abs=1e-300)


@given(st.floats(min_value=-273.15, max_value=2000, allow_nan=False))
def test_kelvin_and_celsius_agree(celsius: float) -> None:
    kelvin = parse_unit("[K]").to_si(np.array([celsius + 273.15]))[0]
    assert kelvin == pytest.approx(celsius, abs=1e-9)


def test_conversion_does_not_touch_its_input() -> None:
    values = np.array([1.0, 2.0])
    values.setflags(write=False)
    out = parse_unit("[mN·m]").to_si(values)
    assert values.tolist() == [1.0, 2.0] and out.tolist() == [1e-3, 2e-3]
