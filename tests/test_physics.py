"""Unit physics of the pin-on-disc cell, checked against hand-computed values.

Every conversion the reduction makes (force → pressure, torque → friction force, angle or
speed → sliding distance, rpm → mm/s) is checked here on numbers a lab member can redo on
paper, and against the published friction map's own pressure column.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from published_map import PUBLISHED_CSV
from tribopipe.config import InstrumentConfig
from tribopipe.physics import (
    FOUNDING_FRICTION_RADIUS_MM,
    FOUNDING_SLIDING_SPEED_MM_S,
    FOUNDING_SPEED_RPM,
    coefficient_of_friction,
    contact_pressure_kPa,
    distance_from_angle_mm,
    distance_from_nominal_mm,
    distance_from_speed_mm,
    friction_force_N,
    rpm_to_rad_s,
    sliding_distance_mm,
    sliding_speed_mm_s,
)
from tribopipe.reduction.detection import (
    linear_slope,
    median_smooth,
    noise_std,
    static_peak_curve,
)
from tribopipe.reduction.intervals import leading_rest

R_EFF = 13.37  # mm, the founding cell's friction radius


def test_one_newton_on_three_pins_is_11_79_kPa() -> None:
    # (1 N / 3) / (π · 3² mm²) = 0.33333 / 28.274 N/mm² = 0.011789 MPa = 11.79 kPa
    assert contact_pressure_kPa(1.0, 3, 3.0) == pytest.approx(11.789, abs=1e-3)
    assert contact_pressure_kPa(9.0, 3, 3.0) == pytest.approx(106.10, abs=0.01)


def test_pressure_of_an_array_and_of_one_pin() -> None:
    p = contact_pressure_kPa(np.array([1.0, 3.0, 5.0]), 3, 3.0)
    np.testing.assert_allclose(p, [11.789, 35.368, 58.946], atol=1e-3)
    # one pin of r = 1 mm under 1 N: 1/π N/mm² = 318.3 kPa
    assert contact_pressure_kPa(1.0, 1, 1.0) == pytest.approx(318.31, abs=0.01)


def test_published_map_pressures_follow_from_its_forces() -> None:
    with PUBLISHED_CSV.open(encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 169
    for row in rows:
        expected = float(row["contactPressure"])
        assert contact_pressure_kPa(float(row["contactForce"]), 3, 3.0) == pytest.approx(
            expected, abs=0.006
        )


def test_friction_force_is_torque_over_radius_in_metres() -> None:
    # 13.37 mN·m at 13.37 mm is 1 N; 1 N·m at 1000 mm is 1 N
    assert friction_force_N(13.37e-3, R_EFF) == pytest.approx(1.0)
    assert friction_force_N(1.0, 1000.0) == pytest.approx(1.0)
    np.testing.assert_allclose(friction_force_N(np.array([-2e-3, 4e-3]), 2.0), [-1.0, 2.0])


def test_cof_is_friction_over_normal_force_and_nan_only_at_zero_force() -> None:
    mu = coefficient_of_friction(np.array([1.5, 2.0, 1.0]), np.array([3.0, 4.0, 0.0]))
    assert mu[0] == pytest.approx(0.5)
    assert mu[1] == pytest.approx(0.5)
    assert math.isnan(mu[2])


def test_rpm_to_rad_s() -> None:
    assert rpm_to_rad_s(60.0) == pytest.approx(2 * math.pi)
    assert rpm_to_rad_s(0.005) == pytest.approx(5.236e-4, rel=1e-3)


def test_founding_speed_is_0_007_mm_per_s() -> None:
    # 0.005 rpm = 5.236e-4 rad/s; × 13.37 mm = 0.0070 mm/s (the paper's sliding speed)
    assert sliding_speed_mm_s(0.005, R_EFF) == pytest.approx(0.0070, abs=5e-5)
    assert InstrumentConfig().nominal_sliding_speed_mm_s == pytest.approx(
        sliding_speed_mm_s(0.005, InstrumentConfig().friction_radius_mm)
    )


def test_the_founding_speeds_are_defined_once() -> None:
    # 0.005 rpm and 0.007 mm/s are the paper's two numbers; the friction radius follows
    assert (FOUNDING_SPEED_RPM, FOUNDING_SLIDING_SPEED_MM_S) == (0.005, 0.007)
    assert sliding_speed_mm_s(FOUNDING_SPEED_RPM, FOUNDING_FRICTION_RADIUS_MM) == pytest.approx(
        FOUNDING_SLIDING_SPEED_MM_S, abs=5e-6)
    from generators import synthetic
    from tribopipe.config import InstrumentConfig

    assert InstrumentConfig().friction_radius_mm == FOUNDING_FRICTION_RADIUS_MM
    assert synthetic.SyntheticRun().speed_rpm is FOUNDING_SPEED_RPM


def test_angle_in_rad_times_radius_in_mm_is_mm() -> None:
    s = distance_from_angle_mm(np.array([0.0, 0.05, 0.1]), R_EFF)
    np.testing.assert_allclose(s, [0.0, 0.6685, 1.337])


def test_distance_grows_whichever_way_the_disc_turns() -> None:
    angle = np.array([2.0, 1.95, 1.9])  # negative rotation from a non-zero start
    np.testing.assert_allclose(distance_from_angle_mm(angle, 10.0), [0.0, 0.5, 1.0])


def test_speed_integrates_to_distance() -> None:
    t = np.linspace(0.0, 100.0, 1001)
    omega = np.full(t.size, rpm_to_rad_s(0.005))
    s = distance_from_speed_mm(t, omega, R_EFF)
    assert s[0] == 0.0
    assert s[-1] == pytest.approx(100 * sliding_speed_mm_s(0.005, R_EFF), rel=1e-9)
    # reversed rotation gives the same distance
    np.testing.assert_allclose(distance_from_speed_mm(t, -omega, R_EFF), s)


def test_nominal_distance_is_speed_times_time_from_the_first_sample() -> None:
    t = np.array([5.0, 15.0, 105.0])
    s = distance_from_nominal_mm(t, 0.005, R_EFF)
    np.testing.assert_allclose(s, [0.0, 0.0700, 0.7000], atol=2e-4)


def test_sliding_distance_prefers_angle_then_speed_then_nominal() -> None:
    t = np.arange(0.0, 10.0, 1.0)
    angle = 0.001 * t
    speed = np.full(t.size, 0.002)
    s, source = sliding_distance_mm(t, 10.0, angle_rad=angle, speed_rad_s=speed,
                                    nominal_speed_rpm=0.005)
    assert source == "angle" and s[-1] == pytest.approx(0.09)
    s, source = sliding_distance_mm(t, 10.0, speed_rad_s=speed, nominal_speed_rpm=0.005)
    assert source == "speed" and s[-1] == pytest.approx(0.18)
    s, source = sliding_distance_mm(t, 10.0, angle_rad=np.full(t.size, np.nan),
                                    nominal_speed_rpm=0.005)
    assert source == "nominal" and s[-1] == pytest.approx(9 * sliding_speed_mm_s(0.005, 10.0))


def test_a_gap_in_the_angle_is_bridged_over_time() -> None:
    t = np.arange(5.0)
    angle = np.array([0.0, 0.1, np.nan, 0.3, 0.4])
    s, source = sliding_distance_mm(t, 1.0, angle_rad=angle)
    assert source == "angle"
    np.testing.assert_allclose(s, [0.0, 0.1, 0.2, 0.3, 0.4])


def test_noise_level_of_white_noise_and_of_a_ramp() -> None:
    rng = np.random.default_rng(1)
    noise = 0.01 * rng.standard_normal(5000)
    assert noise_std(noise) == pytest.approx(0.01, rel=0.06)
    # a steady trend does not count as noise
    assert noise_std(noise + np.linspace(0, 5, 5000)) == pytest.approx(0.01, rel=0.06)


def test_median_filter_removes_a_spike_and_keeps_a_step() -> None:
    x = np.r_[np.zeros(10), np.ones(10)]
    spiky = x.copy()
    spiky[4] = 9.0
    np.testing.assert_array_equal(median_smooth(spiky, 5), x)


def test_static_peak_curve_does_not_overshoot_a_sudden_slip() -> None:
    s = np.linspace(0, 1, 400)
    ramp = np.where(s < 0.5, 1 - (1 - s / 0.5) ** 2, 0.5)  # rounded rise, sudden drop
    curve = static_peak_curve(ramp, 29)
    assert curve.max() <= ramp.max() + 1e-9
    assert curve.max() == pytest.approx(1.0, abs=0.01)


def test_slope_and_its_standard_error() -> None:
    x = np.linspace(0, 2, 200)
    slope, se = linear_slope(x, 0.3 + 0.05 * x)
    assert slope == pytest.approx(0.05)
    assert se == pytest.approx(0.0, abs=1e-12)


def test_leading_rest_ignores_a_later_stop() -> None:
    s = np.array([0.0, 0.0, 0.0, 0.01, 0.02, 0.02, 0.02])
    np.testing.assert_array_equal(leading_rest(s, 1e-3), [1, 1, 1, 0, 0, 0, 0])


@settings(max_examples=60, deadline=None)
@given(
    force=st.floats(0.01, 100.0),
    n_pins=st.integers(1, 6),
    radius=st.floats(0.5, 10.0),
)
def test_pressure_times_total_area_gives_back_the_force(
    force: float, n_pins: int, radius: float
) -> None:
    p_kPa = contact_pressure_kPa(force, n_pins, radius)
    area_mm2 = n_pins * math.pi * radius**2
    assert p_kPa / 1e3 * area_mm2 == pytest.approx(force, rel=1e-12)


@settings(max_examples=60, deadline=None)
@given(
    start=st.floats(-10.0, 10.0),
    rate=st.floats(1e-5, 1e-2),
    sign=st.sampled_from([-1.0, 1.0]),
)
def test_distance_from_angle_ignores_start_and_direction(
    start: float, rate: float, sign: float
) -> None:
    t = np.arange(100.0)
    s = distance_from_angle_mm(start + sign * rate * t, R_EFF)
    np.testing.assert_allclose(s, rate * t * R_EFF, rtol=1e-6, atol=1e-9)


def test_the_founding_speed_is_one_constant_in_physics():
    """No module but ``physics`` names a founding or published speed: every reader of the
    founding 0.007 mm/s imports :data:`FOUNDING_SLIDING_SPEED_MM_S`."""
    import ast
    import re

    src = Path(__file__).resolve().parents[1] / "src" / "tribopipe"
    pattern = re.compile(r"(FOUNDING|PUBLISHED)\w*_(MM_S|RPM)")
    defined = []
    for path in sorted(src.rglob("*.py")):
        for node in ast.parse(path.read_text(encoding="utf-8")).body:
            targets = (node.targets if isinstance(node, ast.Assign) else
                       [node.target] if isinstance(node, ast.AnnAssign) else [])
            defined += [f"{path.relative_to(src)}:{t.id}" for t in targets
                        if isinstance(t, ast.Name) and pattern.fullmatch(t.id)]
    assert defined == ["physics.py:FOUNDING_SPEED_RPM", "physics.py:FOUNDING_SLIDING_SPEED_MM_S"]
