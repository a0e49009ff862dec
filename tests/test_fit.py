"""Power-law fit μ = k·p^(n−1): recovers known laws, gives honest intervals, and matches
the published map's trend (friction falls with pressure)."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from published_map import PUBLISHED_CSV, published_runs
from tribopipe.fit import FIT_COLUMNS, fit_one, fit_power_law, power_law

PRESSURES = np.array([11.79, 35.37, 58.95, 82.52, 106.1])


def _runs(k: float, exponent: float, noise: float, seed: int, repeats: int = 3) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    p = np.repeat(PRESSURES, repeats)
    mu = k * p**exponent * np.exp(rng.normal(0.0, noise, len(p)))
    return pd.DataFrame(
        {"pin": "Ecoflex 00-50", "disc": "steel", "temperature_C": 20.0,
         "pressure_kPa": p, "mu_k": mu, "excluded": False}
    )


def test_exact_power_law_is_recovered():
    runs = _runs(2.0, -1 / 3, noise=0.0, seed=0)
    fit = fit_power_law(runs).iloc[0]
    assert fit["k"] == pytest.approx(2.0)
    assert fit["exponent"] == pytest.approx(-1 / 3)
    assert fit["r_squared"] == pytest.approx(1.0)
    assert fit["n_points"] == 15 and fit["n_pressures"] == 5
    assert fit["exponent_ci95_low"] == pytest.approx(fit["exponent_ci95_high"])


def test_confidence_intervals_cover_the_truth_about_95_percent_of_the_time():
    hits_n = hits_k = 0
    trials = 200
    for seed in range(trials):
        fit = fit_power_law(_runs(1.5, -0.3, noise=0.08, seed=seed)).iloc[0]
        hits_n += fit["exponent_ci95_low"] <= -0.3 <= fit["exponent_ci95_high"]
        hits_k += fit["k_ci95_low"] <= 1.5 <= fit["k_ci95_high"]
    # binomial(200, 0.95): 95 % of draws fall in 184..195
    assert 180 <= hits_n <= 199
    assert 180 <= hits_k <= 199


def test_intervals_match_scipy_linregress():
    from scipy import stats

    runs = _runs(1.2, -0.25, noise=0.05, seed=3)
    fit = fit_one(runs["pressure_kPa"].to_numpy(), runs["mu_k"].to_numpy())
    ref = stats.linregress(np.log(runs["pressure_kPa"]), np.log(runs["mu_k"]))
    t = stats.t.ppf(0.975, len(runs) - 2)
    assert fit["exponent"] == pytest.approx(ref.slope)
    assert fit["exponent_ci95_high"] - fit["exponent"] == pytest.approx(t * ref.stderr)
    assert math.log(fit["k"]) == pytest.approx(ref.intercept)
    assert math.log(fit["k_ci95_high"]) - ref.intercept == pytest.approx(
        t * ref.intercept_stderr
    )
    assert fit["r_squared"] == pytest.approx(ref.rvalue**2)


def test_too_few_points_are_reported_not_fitted():
    runs = _runs(1.0, -0.3, 0.0, 0).iloc[:2]  # two runs at one pressure
    fit = fit_power_law(runs)
    assert len(fit) == 1
    assert math.isnan(fit["k"].iloc[0])
    assert "not fitted" in fit["note"].iloc[0]


def test_excluded_and_invalid_runs_are_left_out_and_input_untouched():
    runs = _runs(2.0, -0.5, 0.0, 0)
    runs.loc[0, "mu_k"] = 50.0
    runs.loc[0, "excluded"] = True
    runs.loc[1, "mu_k"] = math.nan
    before = runs.copy()
    fit = fit_power_law(runs).iloc[0]
    assert fit["n_points"] == 13
    assert fit["exponent"] == pytest.approx(-0.5)
    pd.testing.assert_frame_equal(runs, before)


def test_one_row_per_pair_and_temperature_with_all_columns():
    a = _runs(2.0, -0.5, 0.0, 0)
    b = _runs(1.0, -0.2, 0.0, 0).assign(temperature_C=10.0)
    c = _runs(0.8, -0.1, 0.0, 0).assign(disc="wood (smooth)")
    fit = fit_power_law(pd.concat([a, b, c], ignore_index=True))
    assert list(fit.columns) == list(FIT_COLUMNS)
    assert len(fit) == 3
    by_key = {(r.disc, r.temperature_C): r.exponent for r in fit.itertuples()}
    assert by_key[("steel", 20.0)] == pytest.approx(-0.5)
    assert by_key[("steel", 10.0)] == pytest.approx(-0.2)
    assert by_key[("wood (smooth)", 20.0)] == pytest.approx(-0.1)


def test_published_map_friction_falls_with_pressure():
    runs = published_runs(PUBLISHED_CSV)
    fit = fit_power_law(runs)
    assert len(fit) == 17  # pair × temperature sets in the published map
    assert (fit["note"] == "").all()
    # every published set: μ_K falls with pressure, and the interval excludes zero
    assert (fit["exponent_ci95_high"] < 0).all()
    # elastomer on hard counterfaces: exponents around the Hertz value −1/3
    assert fit["exponent"].between(-0.7, 0.0).all()
    ds_steel = fit[(fit.pin == "Dragonskin 30") & (fit.disc == "steel") & (fit.temperature_C == 20)]
    row = ds_steel.iloc[0]
    # the fitted curve passes through the paper's Table 2 values within 10 %
    table2 = np.array([0.63, 0.45, 0.36, 0.30, 0.26])
    assert power_law(PRESSURES, row["k"], row["exponent"]) == pytest.approx(table2, rel=0.1)


@settings(max_examples=40, deadline=None)
@given(
    st.floats(0.1, 5.0), st.floats(-0.9, 0.2), st.permutations(list(range(15)))
)
def test_fit_does_not_depend_on_row_order(k, exponent, order):
    runs = _runs(k, exponent, noise=0.05, seed=1)
    a = fit_power_law(runs).iloc[0]
    b = fit_power_law(runs.iloc[list(order)]).iloc[0]
    for col in ("k", "exponent", "exponent_ci95_low", "r_squared"):
        assert a[col] == pytest.approx(b[col], rel=1e-9)
