"""Each run's μ_K and μ_S carry a GUM standard uncertainty (k = 1): the plateau mean's
standard error with its autocorrelation, the torque's calibration, resolution and zero,
the normal force, and the friction radius — whose founding value comes from a number
with one significant figure and is the largest term unless a lab states its radius."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from generators.synthetic import SyntheticRun, make_intervals
from tribopipe.config import InstrumentConfig, settings_from_dict
from tribopipe.errors import ConfigError
from tribopipe.measurement import Measurement, MeasurementMeta
from tribopipe.physics import FOUNDING_FRICTION_RADIUS_MM
from tribopipe.reduction.intervals import select_friction_interval
from tribopipe.reduction.reduce import reduce_measurement
from tribopipe.reduction.uncertainty import (
    budget,
    integrated_autocorrelation_time,
    mean_standard_error,
    unknown_offset_u_Nm,
    zero_offset_standard_error,
)

INSTRUMENT = InstrumentConfig()


def ar1(rng: np.random.Generator, n: int, rho: float) -> np.ndarray:
    e = rng.standard_normal(n)
    for i in range(1, n):
        e[i] = rho * e[i - 1] + math.sqrt(1 - rho**2) * e[i]
    return e


def test_the_founding_radius_is_uncertain_by_four_per_cent() -> None:
    # 0.007 mm/s has one significant figure: [0.0065, 0.0075) at 0.005 rpm
    omega = 0.005 * 2 * math.pi / 60
    low, high = 0.0065 / omega, 0.0075 / omega
    assert low < FOUNDING_FRICTION_RADIUS_MM < high
    assert INSTRUMENT.friction_radius_u_mm == pytest.approx((high - low) / 2 / math.sqrt(3),
                                                            abs=0.005)
    assert INSTRUMENT.friction_radius_u_mm / INSTRUMENT.friction_radius_mm == pytest.approx(
        0.041, abs=0.001)


@pytest.mark.parametrize("rho", [0.0, 0.5, 0.8])
def test_autocorrelation_time_of_white_and_ar1_noise(rho: float) -> None:
    rng = np.random.default_rng(1)
    tau = integrated_autocorrelation_time(ar1(rng, 20_000, rho))
    assert tau == pytest.approx((1 + rho) / (1 - rho), rel=0.15)


def test_the_standard_error_of_a_correlated_mean_is_what_repeats_show() -> None:
    rng = np.random.default_rng(2)
    means, errors = [], []
    for _ in range(300):
        x = ar1(rng, 1500, 0.6)
        se, _ = mean_standard_error(x)
        means.append(x.mean())
        errors.append(se)
    # σ/√n of correlated samples would be 2× too small here ((1+0.6)/(1-0.6) = 4)
    assert float(np.median(errors)) == pytest.approx(float(np.std(means)), rel=0.15)
    assert float(np.std(means)) > 1.8 / math.sqrt(1500)


def test_a_zero_from_rest_samples_has_the_standard_error_of_its_inliers() -> None:
    rng = np.random.default_rng(4)
    torque = 3e-4 + 1e-5 * rng.standard_normal(400)
    torque[7] = 1.0  # a spike is not averaged
    assert zero_offset_standard_error(torque) == pytest.approx(1e-5 / 20, rel=0.25)


def test_the_budget_adds_the_sources_in_quadrature() -> None:
    parts = budget(0.5, 0.001, normal_force_N=1.0, instrument=INSTRUMENT, offset_u_Nm=1e-5)
    R_m = INSTRUMENT.friction_radius_mm * 1e-3
    assert parts["friction_radius"] == pytest.approx(0.5 * 0.55 / 13.37)
    assert parts["torque_calibration"] == pytest.approx(0.5 * 0.005)
    assert parts["torque_offset"] == pytest.approx(1e-5 / R_m)
    assert parts["normal_force"] == pytest.approx(
        0.5 * math.sqrt(0.005**2 + 0.005**2 + (5e-4 / math.sqrt(12)) ** 2))
    assert parts["reading"] == 0.001
    others = [v for k, v in parts.items() if k != "combined"]
    assert parts["combined"] == pytest.approx(math.sqrt(sum(v * v for v in others)))
    # unless a lab states its radius, the radius is the largest term
    assert max(others) == parts["friction_radius"]
    stated = replace(INSTRUMENT, friction_radius_u_mm=0.02)
    assert budget(0.5, 0.001, normal_force_N=1.0, instrument=stated,
                  offset_u_Nm=1e-5)["combined"] < 0.5 * parts["combined"]


def test_an_unknown_zero_counts_as_its_plausible_size_spread_evenly() -> None:
    assert unknown_offset_u_Nm(INSTRUMENT) == pytest.approx(5e-4 / math.sqrt(3))


@pytest.mark.parametrize("key", ["friction_radius_u_mm", "torque_u_rel", "normal_force_u_N",
                                 "torque_offset_unknown_Nm"])
def test_instrument_uncertainties_are_config_keys_and_must_be_non_negative(key: str) -> None:
    assert getattr(settings_from_dict({"instrument": {key: 0.1}}).instrument, key) == 0.1
    with pytest.raises(ConfigError, match=key):
        settings_from_dict({"instrument": {key: -1.0}})


def _reduce(run: SyntheticRun):
    items = [Measurement(f, MeasurementMeta("u.csv", "synthetic", test="T", result="R",
                                            interval=i))
             for i, f in enumerate(make_intervals(run), start=1)]
    return reduce_measurement(select_friction_interval(items), INSTRUMENT,
                              settings_from_dict({}).reduction)


def test_a_reduced_run_carries_its_budget() -> None:
    got = _reduce(SyntheticRun(mu_s=0.85, mu_k=0.6, noise=0.008, seed=9))
    u = got.parameters.uncertainty
    assert got.u_mu_k == pytest.approx(u.mu_k["combined"])
    assert got.u_mu_s == pytest.approx(u.mu_s["combined"])
    as_json = u.to_json()
    assert as_json["k"] == 1 and as_json["coverage_factor_expanded"] == 2.0
    assert u.mu_k["friction_radius"] == pytest.approx(got.mu_k * 0.55 / 13.37)
    # the plateau mean is known far better than the radius
    assert u.mu_k["reading"] < 0.1 * u.mu_k["friction_radius"]
    assert got.u_mu_s > got.u_mu_k  # a higher μ and a noisier reading


def test_without_a_distinct_peak_mu_s_has_mu_k_uncertainty() -> None:
    got = _reduce(SyntheticRun(shape="no_overshoot", mu_k=0.6, noise=0.008, seed=10))
    assert "static_not_distinct" in got.flags
    assert got.u_mu_s == got.u_mu_k
