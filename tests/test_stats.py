"""Repeat statistics: checked against hand computations and scipy's Student t, the grouping
rules (rounded nominal values, pressure, speed), exclusions, the pooled repeatability and
its r flag, and independence from row order."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import stats as sps

from test_frictionmap import run_record
from tribopipe import frictionmap as fm
from tribopipe.stats import (
    GROUP_FIELDS,
    R_FACTOR,
    STAT_FIELDS,
    describe_values,
    group_statistics,
    group_u,
    repeatability,
    run_ids_of,
    stated_u,
    t975,
)

BASE = run_record(0).as_dict()


def row(i: int, **changes) -> dict:
    """A map record (id ``r<i>``) derived from a real reduced run, with ``changes``."""
    rec = {**BASE, "measurement_id": f"r{i:03d}", **changes}
    if "normal_force_N" in changes and "pressure_kPa" not in changes:
        rec["pressure_kPa"] = changes["normal_force_N"] / 3 / (math.pi * 9) * 1e3
    return rec


def frame(rows: list[dict]) -> pd.DataFrame:
    return fm.records_frame(rows)


# --------------------------------------------------------------------------- one group


def test_three_values_match_a_hand_computation_and_scipy_t():
    out = describe_values([0.40, 0.44, 0.45])
    assert out["n"] == 3
    assert out["mean"] == pytest.approx(0.43)
    # deviations -0.03, 0.01, 0.02 → Σd² = 0.0014, s² = 0.0014 / (3 − 1)
    s = math.sqrt(0.0007)
    assert out["std"] == pytest.approx(s)
    assert out["sem"] == pytest.approx(s / math.sqrt(3))
    t = sps.t.ppf(0.975, 2)
    assert t == pytest.approx(4.303, abs=1e-3)  # printed t tables, 2 dof
    assert out["ci95_low"] == pytest.approx(0.43 - t * s / math.sqrt(3))
    assert out["ci95_high"] == pytest.approx(0.43 + t * s / math.sqrt(3))
    assert out["cv"] == pytest.approx(s / 0.43)
    assert (out["min"], out["max"]) == (0.40, 0.45)
    assert out["values"] == "0.4;0.44;0.45"
    assert set(out) == set(STAT_FIELDS)


def test_two_values_use_t_with_one_degree_of_freedom():
    out = describe_values([0.60, 0.66])
    assert out["std"] == pytest.approx(0.06 / math.sqrt(2))
    half = 12.706 * 0.03  # t(0.975, 1) = 12.706; sem = s/√2 = 0.03
    assert out["ci95_high"] - out["mean"] == pytest.approx(half, rel=1e-4)


def test_the_interval_of_a_coefficient_never_reaches_below_zero():
    # n = 2 far apart: mean - t*sem = 0.365 - 12.7*0.335 < 0, bounded at 0
    out = describe_values([0.03, 0.70])
    assert out["ci95_low"] == 0.0
    assert out["ci95_high"] == pytest.approx(0.365 + t975(1) * out["sem"])


def test_a_single_value_has_unknown_spread_not_zero():
    out = describe_values([0.52])
    assert out["n"] == 1 and out["mean"] == out["min"] == out["max"] == 0.52
    for key in ("std", "sem", "ci95_low", "ci95_high", "cv"):
        assert math.isnan(out[key]), key


def test_no_values_give_n_zero_and_missing_statistics():
    out = describe_values([])
    assert out["n"] == 0 and out["values"] == ""
    assert all(math.isnan(out[k]) for k in STAT_FIELDS if k not in ("n", "values"))


# --------------------------------------------------------------------------- grouping


def test_groups_split_by_pair_force_and_temperature():
    rows = [
        row(1, mu_k=0.50, repeat=1),
        row(2, mu_k=0.54, repeat=2),
        row(3, mu_k=0.40, normal_force_N=5.0),
        row(4, mu_k=0.70, temperature_C=10.0),
        row(5, mu_k=0.90, disc="wood (smooth)"),
        row(6, mu_k=0.30, pin="Dragonskin 30"),
    ]
    groups = group_statistics(frame(rows))
    assert len(groups) == 5
    # sorted by pin, disc, temperature, pressure: DS30/steel, EF/steel 10 °C, EF/steel 20 °C
    # 3 N and 5 N, EF/wood
    assert groups["mu_k_n"].tolist() == [1, 1, 2, 1, 1]
    main = groups[groups["mu_k_n"] == 2].iloc[0]
    assert main["mu_k_mean"] == pytest.approx(0.52)
    assert main["mu_k_values"] == "0.5;0.54" and main["run_ids"] == "r001;r002"
    # the one reader of that cell gives the ids back, and none for an empty or missing cell
    assert run_ids_of(main["run_ids"]) == ["r001", "r002"]
    assert run_ids_of("") == [] and run_ids_of(float("nan")) == [] and run_ids_of(None) == []
    assert main["pressure_kPa"] == pytest.approx(35.37, abs=0.005)
    assert main["mu_s_n"] == 2 and main["mu_s_mean"] == pytest.approx(BASE["mu_s"])


def test_rounding_noise_in_nominal_values_never_splits_a_group():
    rows = [
        row(1, normal_force_N=1.0, pressure_kPa=11.79, temperature_C=20.0),  # published
        row(2, normal_force_N=1.0, temperature_C=20.001),  # 11.7893 kPa from geometry
        row(3, normal_force_N=1.0 + 1e-9, temperature_C=19.999),
    ]
    groups = group_statistics(frame(rows))
    assert len(groups) == 1 and groups["mu_k_n"].iloc[0] == 3
    assert groups["pressure_kPa"].iloc[0] == pytest.approx(11.79, abs=1e-3)


def test_the_same_force_on_another_pin_geometry_is_another_condition():
    rows = [
        row(1, normal_force_N=3.0),  # 35.4 kPa on r = 3 mm pins
        row(2, normal_force_N=3.0, pressure_kPa=3.0 / 3 / (math.pi * 4) * 1e3),  # r = 2 mm
    ]
    groups = group_statistics(frame(rows))
    assert len(groups) == 2
    assert groups["pressure_kPa"].round(1).tolist() == [35.4, 79.6]


def test_by_speed_splits_groups_by_sliding_speed_rounded_to_two_digits():
    rows = [
        row(1, sliding_speed_mm_s=0.00700),
        row(2, sliding_speed_mm_s=0.00702),
        row(3, sliding_speed_mm_s=0.0140),
    ]
    assert len(group_statistics(frame(rows))) == 1
    by_speed = group_statistics(frame(rows), by_speed=True)
    assert by_speed["sliding_speed_mm_s"].tolist() == [0.007, 0.014]
    assert by_speed["mu_k_n"].tolist() == [2, 1]
    assert list(by_speed.columns[:6]) == [
        "pin", "disc", "normal_force_N", "pressure_kPa", "temperature_C", "sliding_speed_mm_s"
    ]


def test_unknown_temperature_is_its_own_group_not_dropped():
    rows = [row(1, temperature_C=None), row(2, temperature_C=None), row(3)]
    groups = group_statistics(frame(rows))
    assert sorted(groups["mu_k_n"].tolist()) == [1, 2]
    assert groups["temperature_C"].isna().sum() == 1


def test_columns_follow_the_design_contract():
    groups = group_statistics(frame([row(1)]))
    expected = ["pin", "disc", "normal_force_N", "pressure_kPa", "temperature_C"]
    for q in ("mu_k", "mu_s"):
        expected += [f"{q}_{f}" for f in GROUP_FIELDS]
    expected += ["labs", "range_exceeds_r", "labs_disagree", "qc_flagged", "reviewed", "run_ids"]
    assert list(groups.columns) == expected
    empty = group_statistics(fm.schema.empty_map())
    assert list(empty.columns) == expected and empty.empty


def test_imported_rows_have_no_mu_s_statistics():
    rows = [row(1, source="import:x.csv", mu_s=None), row(2, source="import:x.csv", mu_s=None)]
    g = group_statistics(frame(rows)).iloc[0]
    assert g["mu_k_n"] == 2 and g["mu_s_n"] == 0 and math.isnan(g["mu_s_mean"])


# --------------------------------------------------------------------------- flags


def test_excluded_runs_are_left_out_and_a_fully_excluded_group_disappears():
    rows = [
        row(1, mu_k=0.50),
        row(2, mu_k=0.52),
        row(3, mu_k=0.95, excluded=True, exclusion_reason="pin tore"),
        row(4, mu_k=0.3, normal_force_N=9.0, excluded=True, exclusion_reason="wrong disc"),
    ]
    groups = group_statistics(frame(rows))
    assert len(groups) == 1
    g = groups.iloc[0]
    assert g["mu_k_n"] == 2 and g["mu_k_max"] == 0.52 and "r003" not in g["run_ids"]


def test_groups_with_flagged_runs_are_marked():
    rows = [row(1), row(2, flags="stick_slip"), row(3, normal_force_N=5.0)]
    groups = group_statistics(frame(rows)).set_index("normal_force_N")
    assert groups.loc[3.0, "qc_flagged"] and not groups.loc[5.0, "qc_flagged"]


def test_pooled_repeatability_matches_the_hand_formula():
    rows = [
        row(1, mu_k=0.50, normal_force_N=1.0),
        row(2, mu_k=0.52, normal_force_N=1.0),
        row(3, mu_k=0.30, normal_force_N=3.0),
        row(4, mu_k=0.33, normal_force_N=3.0),
        row(5, mu_k=0.36, normal_force_N=3.0),
        row(6, mu_k=0.20, normal_force_N=5.0),  # n = 1: no information on spread
    ]
    rep = repeatability(group_statistics(frame(rows)), "mu_k")
    # s₁² = 0.0002 (1 dof), s₂² = 0.0009 (2 dof)
    assert rep.dof == 3 and rep.n_groups == 2
    assert rep.s_r == pytest.approx(math.sqrt((0.0002 + 2 * 0.0009) / 3))
    assert rep.r == pytest.approx(2.8 * rep.s_r)


def test_a_group_whose_range_exceeds_r_is_flagged_and_nothing_is_rejected():
    rows = []
    for k, force in enumerate((1.0, 3.0, 5.0, 7.0, 9.0)):
        rows += [row(10 * k, mu_k=0.50, normal_force_N=force),
                 row(10 * k + 1, mu_k=0.51, normal_force_N=force)]
    rows += [row(90, mu_k=0.40, normal_force_N=11.0), row(91, mu_k=0.48, normal_force_N=11.0)]
    groups = group_statistics(frame(rows))
    rep = repeatability(groups, "mu_k")
    spread = groups["mu_k_max"] - groups["mu_k_min"]
    assert (groups["range_exceeds_r"] == (spread > R_FACTOR * rep.s_r)).all()
    assert groups["range_exceeds_r"].tolist() == [False] * 5 + [True]
    assert groups["mu_k_n"].tolist() == [2] * 6  # flagged, never dropped


def test_group_statistics_does_not_modify_the_map():
    runs = frame([row(1), row(2, excluded=True, exclusion_reason="x"), row(3, mu_k=0.6)])
    snapshot = runs.copy()
    group_statistics(runs, by_speed=True)
    pd.testing.assert_frame_equal(runs, snapshot)


@settings(max_examples=40, deadline=None)
@given(
    st.lists(
        st.tuples(
            st.sampled_from(["Ecoflex 00-50", "Dragonskin 30"]),
            st.sampled_from([1.0, 3.0, 5.0]),
            st.sampled_from([10.0, 20.0]),
            st.floats(0.05, 2.0),
            st.one_of(st.none(), st.floats(0.05, 2.5)),
            st.booleans(),
        ),
        min_size=1,
        max_size=25,
    ),
    st.randoms(use_true_random=False),
)
def test_statistics_do_not_depend_on_row_order(spec, rnd):
    rows = []
    for i, (pin, force, temp, mu_k, mu_s, excluded) in enumerate(spec):
        rows.append(row(i, pin=pin, normal_force_N=force, temperature_C=temp, mu_k=mu_k,
                        mu_s=mu_s, source="reduced" if mu_s is not None else "import:x",
                        repeat=rnd.randint(1, 3), excluded=excluded,
                        exclusion_reason="x" if excluded else None))
    shuffled = list(rows)
    rnd.shuffle(shuffled)
    a = group_statistics(frame(rows))
    b = group_statistics(frame(shuffled))
    pd.testing.assert_frame_equal(a, b)
    assert a["mu_k_n"].sum() == sum(1 for r in rows if not r["excluded"])
    finite = a[a["mu_k_n"] >= 2]
    assert (finite["mu_k_ci95_low"] <= finite["mu_k_mean"] + 1e-12).all()
    assert np.all(a["mu_k_min"] <= a["mu_k_max"])



# --------------------------------------------------------------------------- uncertainty


def test_the_group_mean_carries_the_runs_uncertainty_beside_the_repeat_scatter():
    rows = [row(1, mu_k=0.50, u_mu_k=0.020), row(2, mu_k=0.52, u_mu_k=0.022)]
    g = group_statistics(frame(rows)).iloc[0]
    assert g["mu_k_u_run"] == pytest.approx(0.021)
    # sem of (0.50, 0.52) is 0.01; the runs' uncertainty counts in full (correlated)
    assert g["mu_k_u"] == pytest.approx(math.hypot(0.01, 0.021))
    assert g["mu_k_min"] == 0.50 and g["mu_k_max"] == 0.52  # n = 2: the range beside the CI


def test_one_run_is_its_own_uncertainty():
    g = group_statistics(frame([row(1, u_mu_k=0.02)])).iloc[0]
    assert g["mu_k_u"] == pytest.approx(0.02) and math.isnan(g["mu_k_sem"])


def test_a_run_without_a_budget_carries_the_stated_estimate_never_zero():
    rows = [row(1, u_mu_k=0.02), row(2, u_mu_k=None)]
    g = group_statistics(frame(rows)).iloc[0]
    stated = stated_u(float(rows[1]["mu_k"]), float(rows[1]["normal_force_N"]))
    assert stated > 0.01  # the founding cell's budget: its friction radius alone is 4 %
    assert g["mu_k_u_run"] == pytest.approx((0.02 + stated) / 2)
    assert g["mu_k_u"] >= g["mu_k_u_run"] and bool(g["mu_k_u_estimated"])
    assert g["mu_k_n"] == 2  # the repeat statistics are still there
    u, budget = group_u(group_statistics(frame(rows)), "mu_k")
    assert u.iloc[0] == g["mu_k_u"] and not budget.iloc[0]


def test_the_student_t_quantile_is_scipys_without_importing_scipy():
    """``t975`` is computed without SciPy (its import costs a map write half a second of
    CPU): held to SciPy's inverse of the t distribution from 1 to 10⁶ degrees of freedom,
    and to printed tables."""
    from scipy.special import stdtrit

    for dof in [*range(1, 400), 555, 999, 1000, 2682, 5000, 10_000, 99_999, 100_000]:
        expected = float(stdtrit(dof, 0.975))
        assert t975(dof) == pytest.approx(expected, rel=1e-12 if dof < 3000 else 1e-10), dof
    assert t975(1_000_000) == pytest.approx(float(stdtrit(1_000_000, 0.975)), rel=1e-9)
    # Student's tables: 12.706, 4.303, 2.228, 2.042, 1.984 for 1, 2, 10, 30, 100
    for dof, printed in ((1, 12.706), (2, 4.303), (10, 2.228), (30, 2.042), (100, 1.984)):
        assert round(t975(dof), 3) == printed
    with pytest.raises(ValueError, match="at least 1"):
        t975(0)


def test_the_group_statistics_import_no_scipy():
    import subprocess
    import sys

    code = ("import sys\nfrom tribopipe.stats import describe_values\n"
            "describe_values([0.5, 0.52, 0.55, 0.51])\n"
            "print(sorted(m for m in sys.modules if m.split('.')[0] == 'scipy'))\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)
    assert done.stdout.strip() == "[]"
