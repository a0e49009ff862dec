"""Interpolation in the friction map: measured points come back exactly, values between
them lie between them, and outside the range the edge value is held (as ABAQUS does)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from published_map import PUBLISHED_CSV
from tribopipe.errors import ExportError, TribopipeError
from tribopipe.query import (
    friction_table,
    interpolation_weights,
    query,
    select_pair,
)
from tribopipe.query_text import format_result


def _mean(groups: pd.DataFrame, pin: str, disc: str, p: float, t: float) -> float:
    row = groups[
        (groups.pin == pin) & (groups.disc == disc)
        & np.isclose(groups.pressure_kPa, p) & (groups.temperature_C == t)
    ]
    assert len(row) == 1
    return float(row["mu_k_mean"].iloc[0])


def test_every_measured_group_comes_back_exactly(groups):
    for row in groups.itertuples():
        res = query(groups, row.pin, row.disc, row.pressure_kPa, row.temperature_C)
        assert res.mu_k.value == pytest.approx(row.mu_k_mean, abs=1e-12)
        assert not res.clamped
        assert len(res.mu_k.used) == 1
        assert res.mu_k.used[0].weight == 1.0


def test_paper_table2_dragonskin_on_steel(groups):
    # the paper's Table 2: Dragonskin 30 on steel, 20 °C
    expected = [0.63, 0.45, 0.36, 0.30, 0.26]
    got = [
        query(groups, "Dragonskin 30", "steel", p, 20.0).mu_k.value
        for p in (11.79, 35.37, 58.95, 82.52, 106.1)
    ]
    assert got == pytest.approx(expected, abs=0.005)


def test_geometric_midpoint_in_pressure_is_the_geometric_mean_of_neighbours(groups):
    # log p - log mu: halfway in ln p, the value is halfway in ln mu
    a = _mean(groups, "Dragonskin 30", "steel", 35.37, 20.0)
    b = _mean(groups, "Dragonskin 30", "steel", 58.95, 20.0)
    res = query(groups, "Dragonskin 30", "steel", math.sqrt(35.37 * 58.95), 20.0)
    assert res.mu_k.value == pytest.approx(math.sqrt(a * b))
    assert sorted(u.pressure_kPa for u in res.mu_k.used) == [35.37, 58.95]
    assert [u.weight for u in res.mu_k.used] == pytest.approx([0.5, 0.5])


def test_ecoflex_on_steel_between_groups_follows_the_power_law(groups):
    # the case: linear in p gave 0.58 at 30 kPa, 10 degC, the fitted law ~0.54
    from published_map import published_runs as runs_of
    from tribopipe.fit import fit_power_law

    fits = fit_power_law(runs_of(PUBLISHED_CSV))
    fit = fits[(fits.pin == "Ecoflex 00-50") & (fits.disc == "steel")
               & (fits.temperature_C == 10.0)].iloc[0]
    law = fit.k * 30.0 ** fit.exponent
    res = query(groups, "Ecoflex 00-50", "steel", 30.0, 10.0)
    lo = _mean(groups, "Ecoflex 00-50", "steel", 11.79, 10.0)
    hi = _mean(groups, "Ecoflex 00-50", "steel", 35.37, 10.0)
    linear = ((35.37 - 30) * lo + (30 - 11.79) * hi) / (35.37 - 11.79)
    assert abs(res.mu_k.value - law) < 0.01 < abs(linear - law)
    # the law lies within the interval of the answer
    assert res.mu_k.lower <= law <= res.mu_k.value + res.mu_k.expanded


def test_a_power_law_comes_back_exactly_between_the_points():
    rows = [{"pin": "A", "disc": "B", "pressure_kPa": p, "temperature_C": 20.0,
             "mu_k_mean": 2.5 * p ** -0.35, "mu_k_n": 2} for p in (10.0, 30.0, 90.0)]
    groups = pd.DataFrame(rows)
    for p in (12.0, 17.3, 29.9, 45.0, 80.0):
        assert query(groups, "A", "B", p, 20.0).mu_k.value == pytest.approx(2.5 * p ** -0.35)


def test_bilinear_in_temperature_of_the_pressure_rule(groups):
    # acrylic glass is measured on a full 5 x 2 grid: linear in T of log-log in p
    pin, disc = "Dragonskin 30", "acrylic glass"
    p0, p1 = 35.37, 58.95
    corners = {(p, t): _mean(groups, pin, disc, p, t) for p in (p0, p1) for t in (10.0, 20.0)}
    p = p0 * (p1 / p0) ** 0.25
    res = query(groups, pin, disc, p, 17.5)
    wp, wt = 0.25, 0.75

    def at(t):
        return corners[p0, t] ** (1 - wp) * corners[p1, t] ** wp

    assert res.mu_k.value == pytest.approx((1 - wt) * at(10.0) + wt * at(20.0))
    assert len(res.mu_k.used) == 4
    assert sum(u.weight for u in res.mu_k.used) == pytest.approx(1.0)


def test_outside_the_range_the_edge_value_is_held(groups):
    pin, disc = "Dragonskin 30", "aluminium sheet"
    low = query(groups, pin, disc, 1.0, 20.0)
    assert low.mu_k.value == pytest.approx(_mean(groups, pin, disc, 11.79, 20.0))
    assert low.clamped and low.mu_k.clamped_pressure and not low.mu_k.clamped_temperature
    hot = query(groups, pin, disc, 106.1, 40.0)
    assert hot.mu_k.value == pytest.approx(_mean(groups, pin, disc, 106.1, 20.0))
    assert hot.mu_k.clamped_temperature
    assert any("temperature outside" in n for n in hot.notes)


def test_single_temperature_pair_is_one_dimensional(groups):
    # wood (smooth) is measured at 20 °C only: the temperature is clamped, not needed
    res = query(groups, "Dragonskin 30", "wood (smooth)", 50.0, None)
    assert res.temperatures_C == (20.0,)
    at_20 = query(groups, "Dragonskin 30", "wood (smooth)", 50.0, 20.0)
    assert res.mu_k.value == pytest.approx(at_20.mu_k.value)
    assert not res.mu_k.clamped_temperature


def test_temperature_required_when_pair_has_several(groups):
    with pytest.raises(ExportError, match=r"temperature needed.*10, 20"):
        query(groups, "Dragonskin 30", "steel", 50.0, None)


def test_uncertainty_is_the_weighted_ci_half_width(groups):
    pin, disc = "Dragonskin 30", "acrylic glass"
    res = query(groups, pin, disc, 40.0, 12.0)
    expected = sum(u.weight * u.ci95_half_width for u in res.mu_k.used)
    assert res.mu_k.uncertainty == pytest.approx(expected)
    rows = groups[(groups.pin == pin) & (groups.disc == disc)]
    half = (rows.mu_k_ci95_high - rows.mu_k_ci95_low) / 2
    assert half.min() - 1e-12 <= res.mu_k.uncertainty <= half.max() + 1e-12


def test_mu_s_unknown_in_published_map(groups):
    res = query(groups, "Ecoflex 00-50", "steel", 11.79, 10.0)
    assert res.mu_s is None
    assert any("mu_s unknown" in n for n in res.notes)
    # the paper's Table 2 rounds this group to 0.91; the map says 0.903
    assert res.mu_k.value == pytest.approx(0.903, abs=0.0005)


def test_mu_s_interpolated_where_known(groups):
    g = groups.copy()
    g["mu_s_mean"] = g["mu_k_mean"] * 1.5
    g["mu_s_ci95_low"] = g["mu_s_mean"] - 0.01
    g["mu_s_ci95_high"] = g["mu_s_mean"] + 0.01
    res = query(g, "Dragonskin 30", "steel", 47.16, 20.0)
    assert res.mu_s is not None
    assert res.mu_s.value == pytest.approx(1.5 * res.mu_k.value)
    assert res.mu_s.uncertainty == pytest.approx(0.01)


def test_unknown_pair_lists_the_pairs_held(groups):
    with pytest.raises(ExportError) as info:
        query(groups, "Dragonskin 30", "glass", 20.0, 20.0)
    message = str(info.value)
    assert "\n" not in message
    assert "Dragonskin 30 on acrylic glass" in message
    assert "Ecoflex 00-50 on wood (smooth)" in message
    assert isinstance(info.value, TribopipeError)


def test_pair_names_match_case_insensitively(groups):
    assert len(select_pair(groups, "dragonskin 30", "STEEL")) == 9


def test_bad_requests_are_one_line_errors(groups):
    with pytest.raises(ExportError, match="pressure"):
        query(groups, "Dragonskin 30", "steel", math.nan, 20.0)
    with pytest.raises(ExportError, match="empty"):
        query(groups.iloc[0:0], "Dragonskin 30", "steel", 10.0, 20.0)


def test_query_does_not_modify_groups(groups):
    before = groups.copy()
    query(groups, "Dragonskin 30", "steel", 20.0, 15.0)
    friction_table(groups, "Dragonskin 30", "steel")
    pd.testing.assert_frame_equal(groups, before)


def test_friction_table_is_full_and_rectangular(groups):
    # Dragonskin 30 on steel: 11.79 kPa was not measured at 10 °C
    table = friction_table(groups, "Dragonskin 30", "steel")
    assert len(table) == 5 * 2
    assert list(table["temperature_C"]) == [10.0] * 5 + [20.0] * 5
    hole = table[(table.temperature_C == 10.0) & np.isclose(table.pressure_kPa, 11.79)]
    assert not hole["measured"].iloc[0]
    assert int((~table["measured"]).sum()) == 1
    # the hole is below 10 °C's lowest pressure: held at the 35.37 kPa value
    assert hole["mu_k"].iloc[0] == pytest.approx(_mean(groups, "Dragonskin 30", "steel", 35.37, 10))


def test_groups_without_a_temperature_are_left_out_when_others_have_one():
    def group(p, t, mu_k, mu_s):
        return {"pin": "A", "disc": "B", "pressure_kPa": p, "temperature_C": t,
                "mu_k_mean": mu_k, "mu_k_ci95_low": mu_k - 0.01, "mu_k_ci95_high": mu_k + 0.01,
                "mu_k_n": 2, "mu_s_mean": mu_s, "mu_s_ci95_low": math.nan,
                "mu_s_ci95_high": math.nan, "mu_s_n": 1}

    groups = pd.DataFrame([
        group(10.0, 20.0, 0.5, 0.7), group(20.0, 20.0, 0.4, 0.6),
        group(15.0, math.nan, 9.0, 9.0), group(30.0, math.nan, 9.0, 9.0),
    ])
    mid = math.sqrt(10.0 * 20.0)  # halfway in ln p: the geometric means
    res = query(groups, "A", "B", mid, 20.0)
    assert res.mu_k.value == pytest.approx(math.sqrt(0.5 * 0.4))
    assert res.mu_s is not None and res.mu_s.value == pytest.approx(math.sqrt(0.7 * 0.6))
    assert "2 group(s) without a temperature were left out" in res.notes
    assert res.pressure_range_kPa == (10.0, 20.0)
    table = friction_table(groups, "A", "B")
    assert list(table["pressure_kPa"]) == [10.0, 20.0]
    assert list(table["temperature_C"]) == [20.0, 20.0]
    # with no temperature anywhere every group is used, and nothing is said to be left out
    unknown = groups.assign(temperature_C=math.nan)
    res = query(unknown, "A", "B", 15.0)
    assert res.mu_k.value == pytest.approx(9.0)
    assert not any("left out" in n for n in res.notes)
    assert len(friction_table(unknown, "A", "B")) == 4


def test_result_to_dict_is_json_ready(groups):
    import json

    data = query(groups, "Dragonskin 30", "steel", 20.0, 15.0).to_dict()
    text = json.dumps(data)
    back = json.loads(text)
    assert back["clamped"] is True
    assert back["mu_s"] is None
    res = query(groups, "Dragonskin 30", "steel", 20.0, 15.0)
    assert back["mu_k"]["text"] == res.mu_k.text()
    # held below the lowest measured pressure: the value says so, and carries no U
    assert back["mu_k"]["text"] == f"{res.mu_k.value:.3f} (extrapolated: U not valid)"
    assert back["mu_k"]["expanded"] is None and back["mu_k"]["lower"] is None
    assert back["mu_k"]["used"][0]["weight"] > 0
    inside = query(groups, "Dragonskin 30", "steel", 50.0, 15.0).to_dict()
    assert inside["clamped"] is False and inside["mu_k"]["expanded"] > 0
    assert inside["mu_k"]["lower"] == pytest.approx(
        max(0.0, inside["mu_k"]["value"] - inside["mu_k"]["expanded"]))


# ---------------------------------------------------------------------------- properties

grid_p = st.lists(st.floats(1, 200), min_size=1, max_size=5, unique=True)
grid_t = st.lists(st.floats(-10, 60), min_size=1, max_size=3, unique=True)


@settings(max_examples=60, deadline=None)
@given(grid_p, grid_t, st.floats(0, 300), st.floats(-30, 90), st.randoms())
def test_weights_are_a_convex_combination(ps, ts, p, t, rnd):
    points = [(pp, tt) for pp in ps for tt in ts]
    rnd.shuffle(points)
    pa = np.array([x[0] for x in points])
    ta = np.array([x[1] for x in points])
    w, _, _ = interpolation_weights(pa, ta, p, t)
    assert (w >= 0).all()
    assert w.sum() == pytest.approx(1.0)
    assert (w > 0).sum() <= 4


@settings(max_examples=60, deadline=None)
@given(grid_p, grid_t, st.floats(0, 300), st.floats(-30, 90), st.randoms())
def test_interpolated_value_lies_within_the_measured_values(ps, ts, p, t, rnd):
    rows = [
        {"pin": "A", "disc": "B", "pressure_kPa": pp, "temperature_C": tt,
         "mu_k_mean": rnd.uniform(0.1, 2.0), "mu_k_n": 2}
        for pp in ps for tt in ts
    ]
    groups = pd.DataFrame(rows)
    groups["mu_k_ci95_low"] = groups["mu_k_mean"] - 0.1
    groups["mu_k_ci95_high"] = groups["mu_k_mean"] + 0.1
    res = query(groups, "A", "B", p, t)
    assert groups.mu_k_mean.min() - 1e-12 <= res.mu_k.value <= groups.mu_k_mean.max() + 1e-12
    # clamping: beyond the range the value equals the value at the edge
    edge_p = min(max(p, min(ps)), max(ps))
    edge_t = min(max(t, min(ts)), max(ts))
    assert res.mu_k.value == pytest.approx(query(groups, "A", "B", edge_p, edge_t).mu_k.value)
    assert res.mu_k.uncertainty == pytest.approx(0.1)
    assert res.mu_k.expanded is None  # no sem, no budget: U unknown


# --------------------------------------------------------------------------- uncertainty


def test_the_query_carries_the_combined_uncertainty_of_the_groups():
    from test_frictionmap import run_record
    from tribopipe import frictionmap as fm
    from tribopipe.stats import group_statistics

    records = [
        run_record(1, force_N=3.0, repeat=1, mu_k=0.50, u_mu_k=0.020),
        run_record(2, force_N=3.0, repeat=2, mu_k=0.52, u_mu_k=0.022),
        run_record(3, force_N=9.0, repeat=1, mu_k=0.40, u_mu_k=0.016),
    ]
    records[2] = dataclasses.replace(records[2], pressure_kPa=9.0 / 3 / (math.pi * 9) * 1e3)
    groups = group_statistics(fm.records_frame(records))
    u3, u9 = (float(g) for g in groups.sort_values("pressure_kPa")["mu_k_u"])
    assert u3 == pytest.approx(math.hypot(0.01, 0.021)) and u9 == pytest.approx(0.016)
    p3, p9 = sorted(groups["pressure_kPa"])
    res = query(groups, "Ecoflex 00-50", "steel", p3 ** 0.25 * p9 ** 0.75, 20.0)
    assert res.mu_k.u_combined == pytest.approx(0.25 * u3 + 0.75 * u9)
    assert sorted(u.u for u in res.mu_k.used) == pytest.approx(sorted([u3, u9]))
    assert res.to_dict()["mu_k"]["u_combined"] == pytest.approx(res.mu_k.u_combined)
    # U (k = 2) adds the interpolation's own u in quadrature, and is the headline
    assert res.mu_k.u_interpolation > 0
    assert res.mu_k.expanded == pytest.approx(
        2 * math.hypot(res.mu_k.u_combined, res.mu_k.u_interpolation))
    assert res.mu_k.budgets_known
    assert f"mu_k = {res.mu_k.text()} (U, k = 2)" in format_result(res)
    table = friction_table(groups, "Ecoflex 00-50", "steel")
    assert table["u_combined"].tolist() == pytest.approx([u3, u9])
    # at a measured pressure nothing is interpolated: U = 2 u of the group
    assert table["expanded"].tolist() == pytest.approx([2 * u3, 2 * u9])


def test_without_run_uncertainties_the_query_carries_the_stated_estimate(groups):
    res = query(groups, "Dragonskin 30", "steel", 40.0, 20.0)
    assert res.mu_k.u_combined is None  # the published map's rows carry no budget
    assert res.to_dict()["mu_k"]["u_combined"] is None
    # U then holds their stated estimate (the founding cell's budget), never the scatter alone
    assert not res.mu_k.budgets_known
    used = groups[(groups.pin == "Dragonskin 30") & (groups.disc == "steel")
                  & (groups.temperature_C == 20.0) & groups.pressure_kPa.isin([35.37, 58.95])]
    us = [float(g) for g in used["mu_k_u"]]
    assert all(u > float(s) for u, s in zip(us, used["mu_k_sem"], strict=True))
    u_groups = sum(u.weight * s for u, s in zip(res.mu_k.used, us, strict=True))
    assert res.mu_k.u_groups == pytest.approx(u_groups)
    assert res.mu_k.expanded == pytest.approx(2 * math.hypot(u_groups, res.mu_k.u_interpolation))
    assert any("their u is the stated estimate of the founding cell" in n for n in res.notes)


def test_a_single_run_says_so_and_never_plus_minus_zero():
    rows = [{"pin": "A", "disc": "B", "pressure_kPa": p, "temperature_C": 20.0,
             "mu_k_mean": m, "mu_k_n": 1, "mu_k_sem": math.nan, "mu_k_u": math.nan}
            for p, m in ((10.0, 0.6), (30.0, 0.5))]
    res = query(pd.DataFrame(rows), "A", "B", 10.0, 20.0)
    assert res.mu_k.expanded is None
    assert res.mu_k.text() == "0.600 (n = 1, no repeat scatter)"
    assert "± 0" not in format_result(res)
    assert "n = 1, no repeat scatter: a group used has a single run" in res.notes
