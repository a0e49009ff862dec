"""Statistics that know the lab: each lab's repeats kept apart, ISO 5725-2 precision where
several labs measured a condition, a pooled U that holds the between-lab component and
never shrinks when a second lab's data arrive, a stated u for rows without a budget, and
two labs' data packages merged where their conditions overlap.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from test_frictionmap import run_record
from tribopipe import frictionmap as fm
from tribopipe.export.citation import Publisher
from tribopipe.export.publish import publish_map
from tribopipe.stats import (
    OWN_LAB,
    R_FACTOR,
    critical_difference,
    group_statistics,
    group_u,
    repeatability,
    reproducibility,
    stated_u,
)

BASE = run_record(0).as_dict()


def lab_row(i: int, lab: str | None, mu_k: float, u: float | None = 0.01, **changes) -> dict:
    """A map record (id ``r<i>``) of ``lab`` at Dragonskin 30 / steel, 3 N, 20 °C."""
    rec = dict(BASE)
    rec.update(measurement_id=f"r{i}", lab=lab, pin="Dragonskin 30", disc="steel",
               mu_k=mu_k, u_mu_k=u, repeat=i)
    rec.update(changes)
    return rec


def frame(rows: list[dict]) -> pd.DataFrame:
    return fm.records_frame(rows)


# ------------------------------------------------------------------ ISO 5725-2 precision


def test_each_labs_repeats_stay_apart_and_iso_5725_2_holds_by_hand():
    a = [0.50, 0.52, 0.51]
    b = [0.56, 0.58]
    rows = [lab_row(i, "Lab A", v) for i, v in enumerate(a)] + \
        [lab_row(10 + i, "Lab B", v) for i, v in enumerate(b)]
    by_lab = group_statistics(frame(rows), by_lab=True)
    assert list(by_lab["lab"]) == ["Lab A", "Lab B"]
    assert list(by_lab["mu_k_n"]) == [3, 2]
    assert by_lab["mu_k_mean"].tolist() == pytest.approx([np.mean(a), np.mean(b)])

    g = group_statistics(frame(rows)).iloc[0]
    assert g["labs"] == "Lab A;Lab B" and g["mu_k_labs"] == 2 and g["mu_k_n"] == 5
    # ISO 5725-2 §7.4.4-7.4.5, unbalanced, computed here from the definitions
    s2 = [np.var(a, ddof=1), np.var(b, ddof=1)]
    s_r2 = (2 * s2[0] + 1 * s2[1]) / 3
    means, n = np.array([np.mean(a), np.mean(b)]), np.array([3.0, 2.0])
    grand = float(np.sum(n * means) / n.sum())
    s_d2 = float(np.sum(n * (means - grand) ** 2))  # p - 1 = 1
    n_bar = float(n.sum() - np.sum(n ** 2) / n.sum())
    s_L2 = (s_d2 - s_r2) / n_bar
    assert g["mu_k_s_r"] == pytest.approx(math.sqrt(s_r2))
    assert g["mu_k_s_L"] == pytest.approx(math.sqrt(s_L2))
    assert g["mu_k_s_R"] == pytest.approx(math.sqrt(s_L2 + s_r2))
    # the map's repeatability pools within-lab scatter only: the lab difference is not in it
    rep = repeatability(group_statistics(frame(rows)))
    assert rep.s_r == pytest.approx(math.sqrt(s_r2)) and rep.dof == 3
    assert rep.r == pytest.approx(R_FACTOR * rep.s_r)
    assert not group_statistics(frame(rows))["range_exceeds_r"].iloc[0]


def test_the_pooled_u_holds_the_between_lab_component():
    rows = [lab_row(i, "Lab A", v, 0.005) for i, v in enumerate([0.50, 0.51])] + \
        [lab_row(10 + i, "Lab B", v, 0.005) for i, v in enumerate([0.60, 0.61])]
    g = group_statistics(frame(rows)).iloc[0]
    lab_u = group_statistics(frame(rows), by_lab=True)["mu_k_u"].max()
    assert g["mu_k_u"] == pytest.approx(math.hypot(lab_u, g["mu_k_s_L"]))
    assert g["mu_k_u"] > 0.06  # two labs 0.1 apart: the value is not known to 0.005


def test_a_row_naming_no_lab_is_the_maps_own_lab():
    rows = [lab_row(1, None, 0.5), lab_row(2, "Lab B", 0.52)]
    g = group_statistics(frame(rows)).iloc[0]
    assert g["labs"] == f"{OWN_LAB};Lab B"
    only_b = group_statistics(frame(rows), labs=["lab b"])
    assert list(only_b["labs"]) == ["Lab B"] and list(only_b["mu_k_n"]) == [1]


def test_labs_that_disagree_beyond_r_are_flagged_and_agreeing_ones_not():
    rows = []
    # three conditions two labs agree on, one where lab B sits far off
    for k, (force, offset) in enumerate([(1.0, 0.0), (3.0, 0.005), (5.0, -0.004),
                                         (9.0, 0.15)]):
        for j, v in enumerate([0.50, 0.51, 0.49]):
            rows.append(lab_row(100 * k + j, "Lab A", v, normal_force_N=force,
                                pressure_kPa=force * 11.79))
            rows.append(lab_row(100 * k + 10 + j, "Lab B", v + offset,
                                normal_force_N=force, pressure_kPa=force * 11.79))
    groups = group_statistics(frame(rows))
    assert groups["labs_disagree"].tolist() == [False, False, False, True]
    rep = reproducibility(groups)
    assert rep.n_conditions == 4 and rep.R == pytest.approx(R_FACTOR * rep.s_R)
    # the critical difference of ISO 5725-6 §4.2.3, from its definition
    cd = critical_difference(rep.s_r, rep.s_R, 3, 3)
    r, R = R_FACTOR * rep.s_r, R_FACTOR * rep.s_R
    assert cd == pytest.approx(math.sqrt(R ** 2 - r ** 2 * (1 - 1 / 6 - 1 / 6)))
    assert 0.005 < cd < 0.15


def test_n_counts_the_runs_that_have_the_value():
    rows = [lab_row(1, "A", 0.5, mu_s=0.7), lab_row(2, "A", 0.51, mu_s=None,
                                                     source="published:x"),
            lab_row(3, "A", 0.52, mu_s=None, source="published:x")]
    g = group_statistics(frame(rows)).iloc[0]
    assert g["mu_k_n"] == 3 and g["mu_s_n"] == 1


# ------------------------------------------------------------------ U never shrinks


lab_values = st.lists(st.floats(0.05, 2.0), min_size=1, max_size=5)
lab_us = st.floats(0.0005, 0.1)


@settings(max_examples=60, deadline=None)
@given(a=lab_values, b=lab_values, u_a=lab_us, u_b=st.one_of(lab_us, st.none()))
def test_u_never_shrinks_when_a_second_labs_data_arrive(a, b, u_a, u_b):
    rows_a = [lab_row(i, "Lab A", v, u_a) for i, v in enumerate(a)]
    rows_b = [lab_row(100 + i, "Lab B", v, u_b) for i, v in enumerate(b)]
    alone = {}
    for name, rows in (("A", rows_a), ("B", rows_b)):
        alone[name] = float(group_u(group_statistics(frame(rows)))[0].iloc[0])
    both = float(group_u(group_statistics(frame(rows_a + rows_b)))[0].iloc[0])
    assert both >= max(alone.values()) * (1 - 1e-12)
    assert both > 0


def test_the_stated_u_is_the_founding_cells_budget_never_zero():
    # 0.45 at 3 N: friction radius 0.55/13.37 of μ, the last digit ±0.005, an unknown zero
    u = stated_u(0.45, 3.0)
    radius = 0.45 * 0.55 / 13.37
    assert radius < u < 0.03
    assert stated_u(0.45, 9.0) < stated_u(0.45, 1.0)  # the unknown zero weighs less at 9 N
    assert math.isnan(stated_u(math.nan, 3.0))


# ------------------------------------------------------------------ two labs' packages


def _publish(tmp_path, name, records, lab):
    path = tmp_path / f"{name}.parquet"
    fm.append_records(path, records)
    out = tmp_path / f"{name}-package"
    publish_map(path, out, Publisher(lab, "A. Person"), date="2026-01-01")
    return out


def test_two_labs_packages_merged_where_they_overlap_keep_u_honest(tmp_path):
    """The founding map (published, no budgets) and a second lab's package meet at
    Dragonskin 30 / steel / 35.37 kPa / 20 °C: the merged U must not collapse."""
    founding_map = tmp_path / "founding.parquet"
    fm.import_table(founding_map)
    founding_pkg = tmp_path / "founding-package"
    publish_map(founding_map, founding_pkg, Publisher("Berthold et al.", "R. Berthold"),
                date="2026-01-01")
    second = [run_record(50 + i, pin="Dragonskin 30", disc="steel", force_N=3.0,
                         temperature_C=20.0, repeat=i + 1, mu_k=v, u_mu_k=0.019)
              for i, v in enumerate([0.440, 0.451, 0.462])]
    second_pkg = _publish(tmp_path, "second", second, "Second Lab")

    def condition(groups: pd.DataFrame) -> pd.Series:
        sel = groups[(groups.pin == "Dragonskin 30") & (groups.disc == "steel")
                     & (groups.pressure_kPa.round(2) == 35.37) & (groups.temperature_C == 20)]
        assert len(sel) == 1
        return sel.iloc[0]

    alone_u = {}
    for name, pkg in (("founding", founding_pkg), ("second", second_pkg)):
        target = tmp_path / f"{name}-only.parquet"
        fm.merge_map(target, pkg)
        g = condition(group_statistics(fm.read_map(target)))
        alone_u[name] = 2 * g["mu_k_u"]
    merged = tmp_path / "merged.parquet"
    fm.merge_map(merged, founding_pkg)
    fm.merge_map(merged, second_pkg)
    g = condition(group_statistics(fm.read_map(merged)))
    labs = g["labs"].split(";")
    assert len(labs) == 2 and "Second Lab" in labs and g["mu_k_labs"] == 2
    assert g["mu_k_n"] == 5
    expanded = 2 * g["mu_k_u"]
    # the issue measured 0.45074 ± 0.00095 here: U must not collapse below either lab's
    assert expanded >= max(alone_u.values()) and expanded > 0.03
    assert alone_u["founding"] > 0.03  # the founding rows carry the stated estimate
    assert g["mu_k_mean"] == pytest.approx((0.45 * 2 + 0.440 + 0.451 + 0.462) / 5)


# ------------------------------------------------------------------ names on the way in


def _map_with(tmp_path, name, pins):
    from tribopipe.frictionmap import store

    path = tmp_path / name
    rows = [lab_row(i, "Lab B", 0.5 + i / 100, pin=pin, disc=disc)
            for i, (pin, disc) in enumerate(pins)]
    store.append_records(path, rows)  # below the edges: names as they are
    return path


def test_a_merge_stores_canonical_names_and_keeps_the_given_ones(tmp_path, monkeypatch):
    from click.testing import CliRunner

    from tribopipe.cli import main

    monkeypatch.chdir(tmp_path)
    other = _map_with(tmp_path, "other.parquet", [("Dragon Skin 30", "Stahl"),
                                                   ("Unobtainium", "steel")])
    target = tmp_path / "map.parquet"
    # a material the vocabulary lacks refuses the merge whole, in one line with the fix
    refused = CliRunner().invoke(main, ["map", "merge", str(other), "--map", str(target)])
    assert refused.exit_code == 1
    (line,) = [ln for ln in refused.stderr.splitlines() if ln.strip()]
    assert "unknown pin 'Unobtainium'" in line
    assert "`tribopipe materials add Unobtainium --class CLASS`" in line
    assert '"Unobtainium" = { class = "CLASS" }' in line
    assert not target.exists()
    add = CliRunner().invoke(main, ["materials", "add", "Unobtainium", "--class", "other"])
    assert add.exit_code == 0, add.output
    result = CliRunner().invoke(main, ["map", "merge", str(other), "--map", str(target)])
    assert result.exit_code == 0, result.output
    assert "1 row(s) of" in result.stdout and "name 'Dragon Skin 30': stored as " \
        "'Dragonskin 30'" in result.stdout
    runs = fm.read_map(target).sort_values("measurement_id")
    assert runs["pin"].tolist() == ["Dragonskin 30", "Unobtainium"]
    assert runs["disc"].tolist() == ["steel", "steel"]
    assert runs["pin_as_given"].tolist()[0] == "Dragon Skin 30"
    assert runs["disc_as_given"].tolist()[0] == "Stahl"


def test_map_validate_reports_unresolved_names_with_the_fix(tmp_path):
    from click.testing import CliRunner

    from tribopipe.cli import main

    path = _map_with(tmp_path, "m.parquet", [("DS30", "steel"), ("Dragonskni 30", "steel"),
                                             ("Dragonskin 30", "steel")])
    result = CliRunner().invoke(main, ["map", "validate", str(path)])
    assert result.exit_code == 1
    lines = result.output.splitlines()
    assert any("pin 'DS30' (1 row(s)) is not a canonical name: it is 'Dragonskin 30'" in ln
               for ln in lines)
    assert any("unknown pin 'Dragonskni 30'; did you mean 'Dragonskin 30'" in ln
               and "tribopipe materials add" in ln for ln in lines)
    assert not any("'Dragonskin 30' (" in ln for ln in lines)


def test_map_compare_puts_labs_side_by_side_with_en_and_z(tmp_path):
    import io

    from click.testing import CliRunner

    from tribopipe.cli import main
    from tribopipe.frictionmap import store
    from tribopipe.stats import lab_comparison

    rows = [lab_row(i, "Lab A", v, 0.01) for i, v in enumerate([0.50, 0.52])] + \
        [lab_row(10 + i, "Lab B", v, 0.01) for i, v in enumerate([0.56, 0.58])]
    path = tmp_path / "m.parquet"
    store.append_records(path, rows)
    (row,) = lab_comparison(fm.read_map(path)).to_dict(orient="records")
    by_lab = group_statistics(fm.read_map(path), by_lab=True)
    u_a, u_b = (2 * float(u) for u in by_lab["mu_k_u"])
    assert (row["lab_a"], row["lab_b"]) == ("Lab A", "Lab B")
    assert row["difference"] == pytest.approx(0.51 - 0.57)
    assert row["En"] == pytest.approx((0.51 - 0.57) / math.hypot(u_a, u_b))
    sigma = reproducibility(group_statistics(fm.read_map(path))).s_R
    assert row["z_a"] == pytest.approx((0.51 - 0.54) / sigma)
    assert row["z_b"] == pytest.approx((0.57 - 0.54) / sigma)

    text = CliRunner().invoke(main, ["map", "compare", "--map", str(path)])
    assert text.exit_code == 0, text.output
    assert "Lab A: n = 2" in text.output and "En = " in text.output
    assert "(ISO 5725-2)" in text.output
    csv = CliRunner().invoke(main, ["map", "compare", "--map", str(path), "--format", "csv"])
    table = pd.read_csv(io.StringIO(csv.output))
    assert list(table["lab_a"]) == ["Lab A"] and "En" in table.columns
    alone = tmp_path / "alone.parquet"
    store.append_records(alone, rows[:2])
    none = CliRunner().invoke(main, ["map", "compare", "--map", str(alone)])
    assert "no condition was measured by two labs" in none.output


def test_map_compare_never_compares_two_test_methods_as_one_condition():
    """Lab B measured the condition on the rheometer and with a sled: only its rheometer
    runs meet Lab A's rheometer runs, and the sled runs, which no other lab measured by
    that method, meet nobody."""
    from tribopipe.stats import lab_comparison

    rows = [lab_row(i, "Lab A", v) for i, v in enumerate([0.50, 0.52])] + \
        [lab_row(10 + i, "Lab B", v) for i, v in enumerate([0.56, 0.58])] + \
        [lab_row(20 + i, "Lab B", v, test_method="sled D1894")
         for i, v in enumerate([0.80, 0.82])]
    table = lab_comparison(frame(rows))
    assert len(table) == 1
    (row,) = table.to_dict(orient="records")
    assert row["test_method"] == "rheometer pin-on-disc"
    assert (row["lab_a"], row["lab_b"]) == ("Lab A", "Lab B")
    assert (row["n_a"], row["n_b"]) == (2, 2)
    assert row["difference"] == pytest.approx(0.51 - 0.57)
