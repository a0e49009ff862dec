"""Computations made faster for maps of 10⁵ condition groups give what they gave before:
each is held equal to the code it replaced (kept here, as it was), run on the same real
map, the shipped published map imported into Parquet, and on variants of it that reach
the branches the plain map does not (runs without a repeat, without a temperature, at a
second speed, excluded)."""

from __future__ import annotations

import math
from collections.abc import Hashable
from typing import Any

import numpy as np
import pandas as pd
import pytest

from tribopipe.export.tables import _select, frictionmap_table
from tribopipe.fit import FIT_COLUMNS, MIN_POINTS, fit_one, fit_power_law
from tribopipe.frictionmap import import_table, read_map
from tribopipe.frictionmap.published import published_csv_path
from tribopipe.stats import NOMINAL_SPEED, group_keys, nominal_speeds, pairs_with_several_speeds


@pytest.fixture(scope="module")
def published(tmp_path_factory) -> pd.DataFrame:
    """The runs of the shipped published map, imported into a real Parquet map."""
    map_path = tmp_path_factory.mktemp("published") / "friction_map.parquet"
    import_table(map_path, published_csv_path())
    return read_map(map_path)


def _variants(runs: pd.DataFrame) -> dict[str, pd.DataFrame]:
    """The map as it is and changed where the computations branch."""
    out = {"as published": runs}
    blank = runs.copy()
    blank.loc[blank.index[::3], "repeat"] = pd.NA  # numbered after their condition's highest
    blank.loc[blank.index[1::7], "excluded"] = True
    out["repeats missing, runs excluded"] = blank
    no_t = runs.copy()
    no_t.loc[no_t.index[::5], "temperature_C"] = math.nan  # fitted as a set of its own
    out["temperatures missing"] = no_t
    speeds = runs.copy()
    speeds[NOMINAL_SPEED] = np.where(np.arange(len(runs)) % 2 == 0, 5.0, 10.0)
    out["two speeds"] = speeds
    every = runs.copy()
    every["repeat"] = pd.array([pd.NA] * len(runs), dtype="Int64")
    out["no repeat at all"] = every
    out["a run in four"] = runs.iloc[::4]  # sets too small to fit
    return out


def _frictionmap_table_before(runs: pd.DataFrame) -> pd.DataFrame:
    """tribopipe.export.tables.frictionmap_table as it was: a frame per condition."""
    from tribopipe.frictionmap.published import FRICTIONMAP_COLUMNS

    included = runs.loc[~runs["excluded"].astype(bool)].reset_index(drop=True)
    included = _select(included, None, None, None)
    keys = group_keys(included, by_speed=False)
    numbers: list[float] = []
    next_free: dict[Hashable, int] = {}
    for key, idx in keys.groupby(list(keys.columns), dropna=False, sort=False).groups.items():
        repeats = included.loc[idx, "repeat"]
        next_free[key] = int(repeats.max()) if repeats.notna().any() else 0
    for i, key in enumerate(keys.itertuples(index=False, name=None)):
        repeat = included["repeat"].iloc[i]
        if pd.isna(repeat):
            next_free[key] += 1
            numbers.append(float(next_free[key]))
        else:
            numbers.append(float(repeat))
    return pd.DataFrame(
        {
            "pin": included["pin"].to_numpy(dtype=object),
            "disc": included["disc"].to_numpy(dtype=object),
            "contactForce": included["normal_force_N"].to_numpy(dtype=float),
            "contactPressure": included["pressure_kPa"].to_numpy(dtype=float),
            "temperature": included["temperature_C"].to_numpy(dtype=float),
            "measurementNo": numbers,
            "cof": included["mu_k"].to_numpy(dtype=float),
        },
        columns=list(FRICTIONMAP_COLUMNS),
    )


def _fit_power_law_before(runs: pd.DataFrame, quantity: str = "mu_k") -> pd.DataFrame:
    """tribopipe.fit.fit_power_law as it was: a frame per (pair, temperature, speed)."""
    if runs.empty:
        return pd.DataFrame(columns=list(FIT_COLUMNS))
    columns = list(FIT_COLUMNS)
    if "excluded" in runs.columns and pairs_with_several_speeds(runs):
        columns.insert(columns.index("temperature_C") + 1, NOMINAL_SPEED)
    data = pd.DataFrame({
        "pin": runs["pin"].astype(str), "disc": runs["disc"].astype(str),
        "temperature_C": pd.to_numeric(runs["temperature_C"], errors="coerce"),
        "p": pd.to_numeric(runs["pressure_kPa"], errors="coerce"),
        "mu": pd.to_numeric(runs[quantity], errors="coerce"), "v": nominal_speeds(runs)})
    keep = np.isfinite(data["p"]) & np.isfinite(data["mu"]) & (data["p"] > 0) & (data["mu"] > 0)
    if "excluded" in runs.columns:
        keep &= ~runs["excluded"].fillna(False).astype(bool).to_numpy()
    data = data[keep]
    rows = []
    t_key = data["temperature_C"].fillna(-math.inf)
    for (pin, disc, _, speed), grp in data.groupby([data["pin"], data["disc"], t_key,
                                                    data["v"]], sort=True):
        n_pressures = int(grp["p"].nunique())
        row: dict[str, Any] = {
            "pin": pin, "disc": disc, "temperature_C": float(grp["temperature_C"].iloc[0]),
            NOMINAL_SPEED: float(speed), "n_points": len(grp), "n_pressures": n_pressures,
            "pressure_min_kPa": float(grp["p"].min()),
            "pressure_max_kPa": float(grp["p"].max()), "note": ""}
        if len(grp) < MIN_POINTS or n_pressures < 2:
            row["note"] = (f"not fitted: {len(grp)} run(s) at {n_pressures} pressure(s); "
                           f"need >= {MIN_POINTS} runs at >= 2 pressures")
            row.update({c: math.nan for c in FIT_COLUMNS if c not in row})
        else:
            row.update(fit_one(grp["p"].to_numpy(), grp["mu"].to_numpy()))
        rows.append(row)
    return pd.DataFrame(rows, columns=columns)


def test_the_frictionmap_table_numbers_the_runs_as_before(published):
    for name, runs in _variants(published).items():
        pd.testing.assert_frame_equal(frictionmap_table(runs), _frictionmap_table_before(runs),
                                      obj=name)
    # the branch that numbers runs after their condition's highest repeat was reached
    blank = _variants(published)["repeats missing, runs excluded"]
    assert frictionmap_table(blank)["measurementNo"].max() > published["repeat"].max()


def test_the_power_law_fits_are_as_before(published):
    notes: set[bool] = set()
    for name, runs in _variants(published).items():
        for quantity in ("mu_k", "mu_s"):
            new, old = fit_power_law(runs, quantity=quantity), _fit_power_law_before(
                runs, quantity)
            pd.testing.assert_frame_equal(new, old, obj=f"{name}, {quantity}")
            notes |= set(new["note"].eq("").tolist())
    assert notes == {True, False}  # sets fitted and sets too small, both compared
    assert fit_power_law(published.iloc[:0]).empty
    none_kept = published.assign(mu_k=-1.0)  # no run with a positive μ: no set
    pd.testing.assert_frame_equal(fit_power_law(none_kept), _fit_power_law_before(none_kept))


def test_script_json_escapes_as_one_translation_did(published):
    """The page's JSON escaped by replacing each character in turn equals the one
    ``str.translate`` it replaces, on hostile names and on a real explorer's data."""
    import json

    from tribopipe.escape import script_json
    from tribopipe.export.explorer import explorer_data

    table = str.maketrans({"<": "\\u003c", ">": "\\u003e", "&": "\\u0026",
                           "\u2028": "\\u2028", "\u2029": "\\u2029"})

    def before(data: Any) -> str:
        return json.dumps(data, ensure_ascii=False, allow_nan=False,
                          separators=(",", ":")).translate(table)

    hostile = ["</script><!--&amp;", "\u2028\u2029<>&", "μ_K ± 0.1 → ", "", "\\u003c<"]
    for value in (hostile, {"x": hostile, "<": [1.5, None, True]}):
        assert script_json(value) == before(value)
    data = explorer_data(published.assign(pin=published["pin"] + " <&>\u2028"))
    assert script_json(data) == before(data)


def test_the_group_rows_gathered_as_columns_are_the_frame_of_the_rows(published, monkeypatch):
    """group_rows gathers each group's figures into columns as they come; the frame is
    the one ``pd.DataFrame`` made of the list of its rows (kept here), column for column,
    on the map's variants and with two labs, by speed and by lab."""
    from tribopipe import stats

    labs = published.assign(lab=np.where(np.arange(len(published)) % 3 == 0, "Lab A", "Lab B"))
    maps = {**_variants(published), "two labs": labs}
    args = [{}, {"by_speed": True}, {"by_lab": True}]
    new = {(name, i): stats.group_rows(runs, **a) for name, runs in maps.items()
           for i, a in enumerate(args)}

    class Rows(list):  # the code replaced: a dict per row, then one frame
        def frame(self) -> pd.DataFrame:
            return pd.DataFrame(list(self))

    monkeypatch.setattr(stats, "_Columns", Rows)
    for (name, i), frame in new.items():
        pd.testing.assert_frame_equal(frame, stats.group_rows(maps[name], **args[i]),
                                      check_exact=True, obj=f"{name}, {args[i]}")
    assert {"_mu_k_lab_means", "mu_k_s_L"} <= set(new[("two labs", 0)].columns)
    empty = published.assign(excluded=True)
    monkeypatch.undo()
    pd.testing.assert_frame_equal(stats.group_rows(empty), pd.DataFrame([]))
