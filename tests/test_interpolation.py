"""The interpolation rule (tribopipe.interpolation), its leave-one-out on the published map,
the GUM rounding (tribopipe.rounding), and the explorer's JavaScript copies of both, run
in node and held equal to the Python on grids."""

from __future__ import annotations

import json
import math
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from tribopipe.export.explorer import explorer_data
from tribopipe.interpolation import (
    DENSIFY_TARGET,
    ENGINE_TOLERANCE,
    LOO_METHODS,
    PUBLISHED_CURVATURE,
    curvature,
    curvature_terms,
    curve,
    densify,
    evaluate,
    leave_one_out,
    stencil,
)
from tribopipe.query import map_curvature, pairs, query
from tribopipe.rounding import decimal_text, known_u, lower_bound, plus_minus, round_gum

JS = Path(__file__).resolve().parents[1] / "src" / "tribopipe" / "export" / "assets" / "js"
NODE = shutil.which("node")


def published_series(groups: pd.DataFrame) -> list[tuple[str, list[float], list[float]]]:
    out = []
    for (pin, disc, t), g in groups.groupby(["pin", "disc", "temperature_C"], sort=True):
        g = g.sort_values("pressure_kPa")
        out.append((f"{pin}/{disc}/{t}", g["pressure_kPa"].tolist(), g["mu_k_mean"].tolist()))
    return out


# ---------------------------------------------------------------------------- the rule


@settings(max_examples=50, deadline=None)
@given(st.floats(0.05, 5.0), st.floats(-0.9, 0.2),
       st.lists(st.floats(1.0, 500.0), min_size=2, max_size=6, unique=True),
       st.floats(0.0, 1.0))
def test_any_power_law_is_exact_between_the_points(k, exponent, ps, where):
    ps = sorted(ps)
    mus = [k * p**exponent for p in ps]
    p = ps[0] + where * (ps[-1] - ps[0])
    st_ = stencil(ps, [math.nan] * len(ps), mus, p, None)
    assert evaluate(st_, mus) == pytest.approx(k * p**exponent, rel=1e-9)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(1.0, 300.0), min_size=1, max_size=4, unique=True),
       st.lists(st.floats(0.0, 40.0), min_size=1, max_size=3, unique=True),
       st.floats(0.0, 400.0), st.floats(-10.0, 50.0), st.randoms())
def test_the_fast_curve_is_the_rule(ps, ts, p, t, rnd):
    points = [(pp, tt) for pp in ps for tt in ts if rnd.random() < 0.8] or [(ps[0], ts[0])]
    pa = [x[0] for x in points]
    ta = [x[1] for x in points]
    mus = [rnd.uniform(0.05, 2.0) for _ in points]
    assert curve(pa, ta, mus, t)(p) == pytest.approx(evaluate(stencil(pa, ta, mus, p, t), mus),
                                                      rel=1e-12)


def test_non_positive_values_fall_back_to_linear():
    st_ = stencil([10.0, 20.0], [20.0, 20.0], [0.0, 0.4], 15.0, 20.0)
    assert evaluate(st_, [0.0, 0.4]) == pytest.approx(0.2)


def test_the_published_curvature_is_the_published_map_s(groups):
    assert map_curvature(groups, "mu_k") == pytest.approx(PUBLISHED_CURVATURE, abs=5e-5)
    # no mu_s in the published map: its kappa is mu_k's
    assert map_curvature(groups, "mu_s") == map_curvature(groups, "mu_k")


def test_two_pressures_a_rounding_apart_give_no_curvature_term_and_no_crash():
    # ln(199.99999999999997) == ln(200.0) in floating point: no second difference there
    series = [([1.0, 199.99999999999997, 200.0], [1.0, 1.0, 1.0])]
    assert curvature_terms(series) == []
    assert curvature(series) == PUBLISHED_CURVATURE
    # a well-spaced triple still gives its term: ln mu = -0.5 ln p + 0.1 (ln p)^2, d2 = 0.2
    ps = [10.0, 20.0, 40.0]
    mus = [math.exp(-0.5 * math.log(p) + 0.1 * math.log(p) ** 2) for p in ps]
    assert curvature_terms([(ps, mus)]) == [pytest.approx(0.2)]


def test_rows_added_in_a_narrow_gap_are_written_exactly_as_computed():
    # mu falls 8-fold between 2 and 2.00001 kPa: four digits would leave the gap, so the
    # added rows carry the digits a simulator file carries, and a row's value is the
    # value at the pressure the file states
    from tribopipe.rounding import FILE_DIGITS, decimal_text

    def value_at(p):
        return 1.0 * (p / 2.0) ** (math.log(0.125) / math.log(2.00001 / 2.0))

    rows = densify([2.0, 2.00001], value_at)
    added = rows[1:-1]
    assert added and all(2.0 < p < 2.00001 for p in added)
    assert all(float(decimal_text(p, digits=FILE_DIGITS)) == p for p in added)


def test_the_interpolation_u_is_zero_at_measured_points_and_grows_between(groups):
    at = query(groups, "Dragonskin 30", "steel", 35.37, 20.0).mu_k
    assert at.u_interpolation == 0.0
    near = query(groups, "Dragonskin 30", "steel", 37.0, 20.0).mu_k
    mid = query(groups, "Dragonskin 30", "steel", math.sqrt(35.37 * 58.95), 20.0).mu_k
    assert 0 < near.u_interpolation < mid.u_interpolation


# ---------------------------------------------------------------------------- leave-one-out


def test_leave_one_out_on_the_published_map_meets_the_targets(groups):
    cases = leave_one_out(published_series(groups), map_curvature(groups))
    assert len(cases) == 42
    errors = {m: np.abs([c.predicted[m] - c.measured for c in cases]) for m in LOO_METHODS}
    linear, rule = errors["linear in p"], errors["log p - log mu"]
    assert rule.mean() <= 0.015 and rule.max() <= 0.05
    assert linear.mean() > 2 * rule.mean()  # what the rule is for
    # u_interp describes the errors it stands for: error/u has an RMS near 1
    z = np.array([(c.predicted["log p - log mu"] - c.measured) / c.u_interpolation
                  for c in cases])
    assert 0.7 < math.sqrt(float(np.mean(z**2))) < 1.4


def test_the_benchmark_file_is_what_the_function_gives(groups):
    stored = Path(__file__).resolve().parents[1] / "bench" / "interpolation.json"
    data = json.loads(stored.read_text(encoding="utf-8"))
    cases = leave_one_out(published_series(groups), map_curvature(groups))
    rule = np.abs([c.predicted["log p - log mu"] - c.measured for c in cases])
    assert data["cases"] == len(cases)
    assert data["methods"]["log p - log mu"]["mean_abs_error"] == pytest.approx(rule.mean())
    assert data["methods"]["log p - log mu"]["max_abs_error"] == pytest.approx(rule.max())


# ---------------------------------------------------------------------------- densify


@settings(max_examples=30, deadline=None)
@given(st.lists(st.floats(1.0, 300.0), min_size=2, max_size=6, unique=True),
       st.lists(st.floats(0.1, 2.0), min_size=6, max_size=6))
# two close pressures with a steep fall: rounding added rows to 4 digits merged them
@example([116.5, 117.0], [2.0, 0.5, 1.0, 1.0, 1.0, 1.0])
def test_densified_rows_read_linearly_stay_within_the_target(ps, mus):
    ps = sorted(ps)
    mus = mus[: len(ps)]

    def value_at(p: float) -> float:
        return evaluate(stencil(ps, [math.nan] * len(ps), mus, p, None), mus)

    rows = densify(ps, value_at)
    assert set(ps) <= set(rows) and rows == sorted(rows)
    grid = np.linspace(ps[0], ps[-1], 2001)
    engine = np.interp(grid, rows, [value_at(p) for p in rows])
    assert np.max(np.abs(engine - [value_at(p) for p in grid])) <= ENGINE_TOLERANCE
    assert DENSIFY_TARGET < ENGINE_TOLERANCE


# ---------------------------------------------------------------------------- rounding

ROUNDING_CASES = [
    (0.53412, 0.1149, "0.53", "0.11"),
    (0.5, 0.0996, "0.50", "0.10"),
    (0.9033333, 0.0125, "0.903", "0.013"),
    (0.570123, 0.048, "0.570", "0.048"),
    (1.23456, 0.00151, "1.2346", "0.0015"),
    (12.3456, 1.26, "12.3", "1.3"),
    (0.825, 0.25, "0.83", "0.25"),
    (123.0, 15.5, "123", "16"),
]


@pytest.mark.parametrize(("value", "u", "v_text", "u_text"), ROUNDING_CASES)
def test_round_gum(value, u, v_text, u_text):
    assert round_gum(value, u) == (v_text, u_text)


def test_plus_minus_is_bounded_at_zero():
    assert plus_minus(0.57, 0.048) == "0.570 ± 0.048"
    assert plus_minus(0.05, 0.11) == "0.05 +0.11/\u22120.05"
    assert plus_minus(0.05, 0.11, ascii_only=True) == "0.05 +0.11/-0.05"
    assert lower_bound(0.05, 0.11) == 0.0 and lower_bound(0.5, 0.1) == pytest.approx(0.4)
    with pytest.raises(ValueError):
        round_gum(0.5, 0.0)
    assert not known_u(7.9e-17) and not known_u(None) and known_u(0.001)


# ---------------------------------------------------------------------------- the JS copies


def run_node(data: dict, body: str) -> object:
    """Run ``body`` (JavaScript returning a JSON-ready value) in node with the explorer's
    query.js loaded and ``DATA`` set; its result."""
    if NODE is None:
        pytest.skip("node is not on PATH")
    script = "\n".join([
        "var DATA = " + json.dumps(data, allow_nan=False) + ";",
        "var PAIRS = DATA.pairs;",
        (JS / "query.js").read_text(encoding="utf-8"),
        "process.stdout.write(JSON.stringify((function () {" + body + "})()));",
    ])
    proc = subprocess.run([NODE, "-"], input=script, capture_output=True, text=True,
                          check=False, timeout=120)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)


def test_the_js_rounding_is_the_python_rounding():
    rng = np.random.default_rng(19)
    values = [c[0] for c in ROUNDING_CASES] + list(rng.uniform(0, 2, 300))
    values += [round(float(v), 3) for v in rng.uniform(0, 2, 100)] + [0.0, 0.005, 0.015]
    us = [c[1] for c in ROUNDING_CASES] + list(10 ** rng.uniform(-4, 0.5, 300))
    us += [round(float(v), 4) for v in rng.uniform(0.001, 0.2, 100)] + [0.0095, 0.095, 0.15]
    pairs_ = list(zip(values, us, strict=True))
    got = run_node({"pairs": []}, "return " + json.dumps(pairs_) +
                   ".map(function (vu) { return [roundGum(vu[0], vu[1]), "
                   "plusMinus(vu[0], vu[1]), plusMinus(vu[0], vu[1], true)]; });")
    for (v, u), (gum, pm, pm_ascii) in zip(pairs_, got, strict=True):
        assert tuple(gum) == round_gum(v, u), (v, u)
        assert pm == plus_minus(v, u) and pm_ascii == plus_minus(v, u, ascii_only=True)


def decimal_cases() -> list[float]:
    """Values for :func:`decimal_text`: ties in decimal text, carries, exponents, signs,
    zeros, what the interpolation and the weights give, and random magnitudes."""
    rng = np.random.default_rng(23)
    values = [0.0, -0.0, 0.5625, 0.0625, 0.03125, 2.5, 3.5, 0.125, 0.0125, 0.0005, 1e-5,
              0.0001, 9.9996, 0.9995, 9.9999995, 99999.95, 999999.5, 123456789.0, 1e16,
              1.5e16, 1e21, 2.5e-30, 5e-324, 11.79, 106.1, 35.37, -3.0, -0.00049, 0.3,
              0.12345678905, 0.5312345678449, 1 / 3, 2 / 3, 1 / 32, 1 / 1024]
    values += [float(v) for v in rng.uniform(-2, 2, 300)]
    values += [float(v) for v in rng.uniform(0, 1, 300) * 10.0 ** rng.integers(-9, 22, 300)]
    values += [round(float(v), 4) for v in rng.uniform(0, 1, 200)]  # decimal ties at 3
    return values


def test_decimal_text_is_format_where_no_decimal_tie_is_met():
    """The one rule for computed numbers rounds the shortest decimal text; away from a
    tie in that text (and subnormals) it is Python's own ``format``."""
    for v in decimal_cases():
        for n in (3, 6, 10):
            want = format(v, f".{n}g")
            got = decimal_text(v, digits=n)
            if got != want:  # only where the decimal text is a tie at the n-th digit
                digits = repr(abs(v)).replace(".", "").lstrip("0").split("e")[0]
                assert digits[n:] == "5" or abs(v) < 1e-300 or want in ("-0", "-0.0"), (v, n)
    assert decimal_text(0.0125, places=3) == "0.013" and f"{0.0125:.3f}" == "0.013"
    assert decimal_text(1.0005, places=3) == "1.001" and f"{1.0005:.3f}" == "1.000"
    assert decimal_text(0.12345678905, digits=10) == "0.1234567891"
    assert decimal_text(1e-5, digits=6) == "1e-05" and decimal_text(1e16, digits=10) == "1e+16"
    assert decimal_text(-0.00049, places=3) == "0.000"
    assert decimal_text(-5.0, digits=17) == "-5" and decimal_text(math.inf, digits=3) == "inf"
    with pytest.raises(ValueError):
        decimal_text(1.0)


def test_the_js_decimal_text_is_the_python_one():
    values = decimal_cases() + [math.nan, math.inf, -math.inf]
    got = run_node({"pairs": []}, "var vs = " + json.dumps(values, allow_nan=True) + ";"
                   "return vs.map(function (v) { return [decimalText(v, 3), decimalText(v, 6), "
                   "decimalText(v, 10), decimalText(v, 17), decimalText(v, null, 3)]; });")
    for v, row in zip(values, got, strict=True):
        assert row == [decimal_text(v, digits=3), decimal_text(v, digits=6),
                       decimal_text(v, digits=10), decimal_text(v, digits=17),
                       decimal_text(v, places=3)], v


def test_the_js_name_key_is_the_python_one():
    """The page matches a link's names by :func:`tribopipe.query.name_key` from the rule
    Python hands it (white space, casefold table): every character whose casefold is not
    its lower case, Python's white space at both ends, and mixed names."""
    from tribopipe.export.explorer import name_rule
    from tribopipe.query import name_key

    names = name_rule()
    rng = np.random.default_rng(29)
    pool = list(names["fold"]) + list(names["space"]) + list("AbCßẞİıΣςﬁﬀǅ🙂é\u0301Ωω<>'\"=")
    texts = list(names["fold"]) + [names["space"] + "Straße" + names["space"], "ǄǅǆX"]
    texts += ["".join(rng.choice(pool, size=int(rng.integers(1, 12)))) for _ in range(400)]
    got = run_node({"pairs": [], "texts": {"names": names}},
                   "return " + json.dumps(texts) + ".map(nameKey);")
    assert got == [name_key(t) for t in texts]


def budgeted_runs(runs: pd.DataFrame) -> pd.DataFrame:
    """The published runs with uncertainty budgets and μ_S, a few groups cut to one run."""
    rng = np.random.default_rng(7)
    out = runs.copy()
    out["u_mu_k"] = rng.uniform(0.005, 0.03, len(out))
    out["mu_s"] = out["mu_k"] * rng.uniform(1.1, 1.4, len(out))
    out["u_mu_s"] = rng.uniform(0.01, 0.04, len(out))
    keep = ~((out["disc"] == "steel") & (out["repeat"] > 1) & (out["normal_force_N"] < 4))
    return out[keep].reset_index(drop=True)


def grid(groups: pd.DataFrame) -> list[list]:
    out: list[list] = []
    for pin, disc in pairs(groups):
        pair = groups[(groups["pin"] == pin) & (groups["disc"] == disc)]
        ps = sorted(set(pair["pressure_kPa"]))
        ts = sorted(set(pair["temperature_C"].dropna()))
        pressures = ps + [a * 0.3 + b * 0.7 for a, b in zip(ps, ps[1:], strict=False)]
        pressures += [0.0, ps[0] * 0.5, ps[-1] * 1.3]
        temps = ts + [(ts[0] + ts[-1]) / 2 + 0.7, ts[-1] + 5]
        out += [[pin, disc, float(p), float(t)] for p in pressures for t in temps]
    return out


@pytest.mark.parametrize("budgets", [False, True])
def test_the_js_query_is_the_python_query(runs, budgets):
    from tribopipe.stats import group_statistics

    runs = budgeted_runs(runs) if budgets else runs
    groups = group_statistics(runs)
    conditions = grid(groups)
    data = explorer_data(runs, groups=groups)
    got = run_node(data, "return " + json.dumps(conditions) + ".map(function (c) { "
                   "var r = query(c[0], c[1], c[2], c[3]); "
                   "return [r, estimateText(r.mu_k), r.mu_s && estimateText(r.mu_s)]; });")
    for (pin, disc, p, t), (page, text_k, text_s) in zip(conditions, got, strict=True):
        res = query(groups, pin, disc, p, t)
        assert page["notes"] == list(res.notes)
        assert text_k == res.mu_k.text()
        for mine, est in ((page["mu_k"], res.mu_k), (page["mu_s"], res.mu_s)):
            if est is None:
                assert mine is None
                continue
            for name in ("value", "uncertainty", "u_combined", "u_interpolation", "u_groups",
                         "expanded"):
                a, b = mine[name], getattr(est, name)
                assert (a is None) == (b is None), (name, pin, disc, p, t)
                if a is not None:
                    assert a == pytest.approx(b, rel=1e-12, abs=1e-15), (name, pin, disc, p, t)
            assert mine["text"] == est.text()
            assert (mine["lower"] is None) == (est.lower is None)
            if est.lower is not None:
                assert mine["lower"] == pytest.approx(est.lower, rel=1e-12, abs=1e-15)
            assert mine["budgets_known"] == est.budgets_known
            assert mine["n_min"] == est.n_min
            assert [u["weight"] for u in mine["used"]] == pytest.approx(
                [u.weight for u in est.used], rel=1e-12)
        if res.mu_s is not None:
            assert text_s == res.mu_s.text()
