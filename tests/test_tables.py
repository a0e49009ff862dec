"""Regenerated tables: the golden group table of the published map, the published facts
checked independently, the FrictionMap 7-column round trip, and the CSV/Markdown/LaTeX
writers.

Golden files live in ``tests/golden/``. After an intended change of the table layout,
regenerate them with ``TRIBOPIPE_REGEN_GOLDEN=1 .venv/bin/pytest tests/test_tables.py``
and review the diff before committing.
"""

from __future__ import annotations

import io
import os
from pathlib import Path

import pandas as pd
import pytest

from conftest import shared_file
from test_frictionmap import run_record
from tribopipe import frictionmap as fm
from tribopipe.errors import ExportError
from tribopipe.export import tables

GOLDEN = Path(__file__).resolve().parent / "golden"
REGEN = os.environ.get("TRIBOPIPE_REGEN_GOLDEN") == "1"


def check_golden(name: str, text: str) -> None:
    """Compare ``text`` with ``tests/golden/<name>`` (or rewrite it when regenerating)."""
    path = GOLDEN / name
    if REGEN:
        path.write_text(text, encoding="utf-8", newline="")
    assert path.exists(), f"{path} missing; run with TRIBOPIPE_REGEN_GOLDEN=1 to create it"
    assert text == path.read_text(encoding="utf-8"), f"{name} differs from the golden file"


@pytest.fixture(scope="module")
def published_runs(tmp_path_factory) -> pd.DataFrame:
    """The published map imported from the shipped CSV into a fresh map, read back."""
    path = tmp_path_factory.mktemp("published") / "map.parquet"
    fm.import_table(path)
    return fm.read_map(path)


# --------------------------------------------------------------------------- golden


def test_group_table_of_the_published_map_matches_the_golden_file(published_runs):
    check_golden("published_groups.csv", tables.render_table(published_runs, fmt="csv"))


def test_abstract_table_of_the_published_map_matches_the_golden_file(published_runs):
    text = tables.render_table(published_runs, fmt="markdown", layout="abstract")
    check_golden("published_abstract.md", text)


def test_the_mat_file_regenerates_the_same_golden_group_table(tmp_path):
    path = tmp_path / "map.parquet"
    fm.import_table(path, shared_file("reference", "FrictionMap.mat"))
    text = tables.render_table(fm.read_map(path), fmt="csv")
    assert text == (GOLDEN / "published_groups.csv").read_text(encoding="utf-8")


def test_the_published_facts_hold_in_the_regenerated_group_table(published_runs):
    groups = pd.read_csv(io.StringIO(tables.render_table(published_runs, fmt="csv")))
    assert len(groups) == 76
    assert groups["mu_k_n"].value_counts().to_dict() == {2: 59, 3: 17}
    assert (groups["mu_s_n"] == 0).all()
    steel = groups[
        (groups["pin"] == "Dragonskin 30")
        & (groups["disc"] == "steel")
        & (groups["temperature_C"] == 20)
    ].sort_values("pressure_kPa")
    assert steel["pressure_kPa"].tolist() == [11.79, 35.37, 58.95, 82.52, 106.1]
    assert steel["mu_k_mean"].round(2).tolist() == [0.63, 0.45, 0.36, 0.30, 0.26]

    def mean_at(pin, disc, temp, p):
        hit = groups[(groups["pin"] == pin) & (groups["disc"] == disc)
                     & (groups["temperature_C"] == temp) & (groups["pressure_kPa"] == p)]
        assert len(hit) == 1
        return hit["mu_k_mean"].iloc[0]

    # the README's two rounding differences between the map and the paper's Table 2
    assert round(mean_at("Ecoflex 00-50", "wood (smooth)", 20, 11.79), 3) == 1.083
    assert round(mean_at("Ecoflex 00-50", "steel", 10, 11.79), 3) == 0.903


def test_the_abstract_layout_has_the_papers_five_columns(published_runs):
    table = tables.abstract_table(published_runs, pin=["Dragonskin 30"], disc=["steel"],
                                  temperature_C=[20])
    assert list(table.columns) == ["pin", "disc", "pressure_kPa", "temperature_C", "mu_k"]
    assert table["mu_k"].tolist() == [0.63, 0.45, 0.36, 0.30, 0.26]
    md = tables.render_table(published_runs, fmt="markdown", layout="abstract",
                             pin=["Dragonskin 30"], disc=["steel"], temperature_C=[20])
    assert "| Dragonskin 30 | steel | 82.52 | 20 | 0.30 |" in md


# --------------------------------------------------------------------------- frictionmap


def test_frictionmap_export_of_the_published_import_is_the_published_file(published_runs):
    text = tables.render_table(published_runs, fmt="frictionmap")
    assert text == fm.published.published_csv_path().read_text(encoding="utf-8")


def test_frictionmap_export_then_import_gives_the_same_runs(tmp_path):
    path = tmp_path / "map.parquet"
    ours = [
        run_record(1, repeat=1, mu_k=0.51),
        run_record(2, repeat=2, mu_k=0.53),
        run_record(3, repeat=1, force_N=5.0, temperature_C=10.0, mu_k=0.41),
    ]
    fm.append_records(path, ours)
    out = tmp_path / "ours_frictionmap.csv"
    tables.export_table(path, out, fmt="frictionmap")
    back = fm.records_frame(fm.import_records(out))
    runs = fm.read_map(path)
    for col in ("pin", "disc", "normal_force_N", "pressure_kPa", "temperature_C", "repeat",
                "mu_k"):
        assert back[col].tolist() == runs[col].tolist(), col
    assert set(back["source"]) == {"import:ours_frictionmap.csv"}


def test_frictionmap_numbers_runs_without_repeat_and_leaves_out_excluded_runs():
    runs = fm.records_frame([
        run_record(1, repeat=2),
        run_record(2, repeat=None),
        run_record(3, repeat=None),
        {**run_record(4, repeat=1).as_dict(), "excluded": True, "exclusion_reason": "pin tore"},
    ])
    table = tables.frictionmap_table(runs)
    assert list(table.columns) == list(fm.published.FRICTIONMAP_COLUMNS)
    assert table["measurementNo"].tolist() == [2.0, 3.0, 4.0]
    assert table["contactForce"].tolist() == [3.0] * 3


# --------------------------------------------------------------------------- writers


def _small_groups() -> pd.DataFrame:
    return pd.DataFrame({
        "pin": ["Ecoflex 00-50", "A|B & 50% #1_x"],
        "pressure_kPa": [11.789255, 106.1],
        "mu_k_n": [2, 1],
        "mu_k_std": [0.0141421356, float("nan")],
        "qc_flagged": [True, False],
    })


def test_markdown_writer_aligns_numbers_escapes_pipes_and_leaves_missing_blank():
    md = tables.to_markdown(_small_groups()).splitlines()
    assert md[0] == "| pin | pressure_kPa | mu_k_n | mu_k_std | qc_flagged |"
    assert md[1] == "| --- | ---: | ---: | ---: | --- |"
    assert md[2] == "| Ecoflex 00-50 | 11.79 | 2 | 0.01414 | yes |"
    assert md[3] == "| A\\|B \\& 50% #1_x | 106.1 | 1 |  | no |"
    assert len(md) == 4


def test_latex_writer_escapes_specials_and_uses_booktabs():
    tex = tables.to_latex(_small_groups()).splitlines()
    assert tex[1] == "% Needs in the preamble: \\usepackage{booktabs} \\usepackage{siunitx}"
    tex = tex[3:]
    # numbers aligned on the decimal point (siunitx S), text left
    assert tex[0] == ("\\begin{tabular}{lS[table-format=3.2]S[table-format=1]"
                      "S[table-format=1.5]l}")
    assert tex[1] == "\\toprule" and tex[-2] == "\\bottomrule" and tex[-1] == "\\end{tabular}"
    assert tex[2] == ("pin & {pressure\\_kPa} & {mu\\_k\\_n} & {mu\\_k\\_std} & qc\\_flagged "
                      "\\\\")
    assert tex[5] == "A|B \\& 50\\% \\#1\\_x & 106.1 & 1 &  & no \\\\"


def test_csv_writer_keeps_ten_significant_digits():
    text = tables.to_csv(_small_groups())
    back = pd.read_csv(io.StringIO(text))
    assert back["pressure_kPa"].iloc[0] == 11.789255
    assert text.splitlines()[2].endswith(",1,,False")


# --------------------------------------------------------------------------- selection


def test_filters_match_materials_case_insensitively_and_temperature_numerically(
    published_runs,
):
    table = tables.group_table(published_runs, pin=["dragonskin 30"], disc=["STEEL"],
                               temperature_C=[10.0])
    assert len(table) == 4 and set(table["temperature_C"]) == {10.0}
    both = tables.group_table(published_runs, disc=["steel", "cardboard"])
    assert set(both["disc"]) == {"steel", "cardboard"}


def test_filtering_does_not_change_the_repeatability_flags(published_runs):
    full = tables.group_table(published_runs).set_index("run_ids")
    part = tables.group_table(published_runs, disc=["aluminium sheet"]).set_index("run_ids")
    assert part["range_exceeds_r"].equals(full.loc[part.index, "range_exceeds_r"])


def test_empty_selection_and_bad_options_raise_export_errors(published_runs, tmp_path):
    with pytest.raises(ExportError, match="no rows to tabulate"):
        tables.render_table(published_runs, pin=["PTFE"])
    with pytest.raises(ExportError, match="unknown table format 'xlsx'"):
        tables.render_table(published_runs, fmt="xlsx")
    with pytest.raises(ExportError, match="own 7-column layout"):
        tables.render_table(published_runs, fmt="frictionmap", layout="abstract")
    with pytest.raises(ExportError, match="friction map not found"):
        tables.export_table(tmp_path / "absent.parquet", fmt="csv")


def test_export_table_writes_the_file_it_returns(tmp_path):
    path = tmp_path / "map.parquet"
    fm.import_table(path)
    out = tmp_path / "tables" / "groups.tex"
    text = tables.export_table(path, out, fmt="latex", layout="abstract", disc=["steel"])
    assert out.read_text(encoding="utf-8") == text
    assert text.count("\\\\") == 1 + 14  # header + 9 Dragonskin + 5 Ecoflex steel groups


@pytest.mark.parametrize(
    ("value", "expected"), [(0.825, 0.83), ((0.81 + 0.84) / 2, 0.83), (0.3049, 0.3), (1.0, 1.0)]
)
def test_abstract_means_round_half_up_like_the_printed_table(value, expected):
    assert tables.round_half_up(value, 2) == expected


def test_markdown_and_latex_show_individual_values_to_four_digits() -> None:
    import pandas as pd

    from tribopipe.export.tables import to_csv, to_latex, to_markdown

    table = pd.DataFrame({"pin": ["DS30"], "mu_k_values": ["0.5705877189722872;0.57008255"]})
    assert "0.5706;0.5701" in to_markdown(table)
    assert "0.5706;0.5701" in to_latex(table)
    assert "0.5705877189722872" in to_csv(table)  # machines keep every digit


# ---------------------------------------------------------------------------- paper layout


def test_the_paper_layout_of_the_published_map(published_runs):
    from tribopipe.rounding import plus_minus
    from tribopipe.stats import group_statistics, group_u

    table = tables.paper_table(published_runs)
    # no mu_s in the published map: its column is left out; one sliding speed: no v column
    assert list(table.columns) == ["pin", "disc", "p [kPa]", "T [°C]", "n", "μ_K ± U", "flags"]
    groups = group_statistics(published_runs)
    u, budget = group_u(groups, "mu_k")
    assert not budget.any()  # the published runs carry no budget: U holds the stated u
    for cell, mean, uu, flags in zip(table["μ_K ± U"], groups["mu_k_mean"], u, table["flags"],
                                     strict=True):
        assert 2 * uu > 0.005  # never the repeat scatter alone: identical repeats too
        assert cell == plus_minus(mean, 2 * uu)
        assert "stated u" in flags and "repeats identical" not in flags
        assert "± 0 " not in cell and not cell.endswith("± 0")
    # the group whose t-interval went to [-0.083, 0.813] before: mean ± U, bounded at 0
    markdown = tables.render_table(published_runs, fmt="markdown", layout="paper")
    # brackets are escaped in every Markdown cell (no link can form); rendered as typed
    assert markdown.splitlines()[0] == ("| pin | disc | p \\[kPa\\] | T \\[°C\\] | n | μ_K ± U "
                                        "| flags |")
    assert "| Ecoflex 00-50 | steel | 11.79 | 10 | 3 | 0.903 ± 0.092 | stated u |" in markdown
    assert "expanded uncertainty of the group mean (k = 2)" in markdown


def test_the_paper_layout_as_latex_and_csv(published_runs):
    latex = tables.render_table(published_runs, fmt="latex", layout="paper", disc=["steel"])
    assert r"\multicolumn{3}{c}{$\mu_K \pm U$}" in latex
    assert r"0.903 & $\pm$ & 0.092" in latex
    assert "±" not in latex and "μ" not in latex
    assert "expanded uncertainty of the group mean (k = 2)" in latex
    csv = tables.render_table(published_runs, fmt="csv", layout="paper", disc=["steel"])
    frame = pd.read_csv(io.StringIO(csv), dtype=str, keep_default_na=False)
    assert list(frame.columns) == ["pin", "disc", "pressure_kPa", "temperature_C", "n",
                                   "mu_k", "mu_k_U", "flags"]
    row = frame[(frame.pin == "Ecoflex 00-50") & (frame.pressure_kPa == "11.79")].iloc[0]
    assert (row.mu_k, row.mu_k_U) == ("0.903", "0.092")


def test_the_paper_layout_with_budgets_mu_s_speeds_and_a_single_run():
    from tribopipe.rounding import plus_minus
    from tribopipe.stats import group_statistics

    records = [
        run_record(1, force_N=3.0, repeat=1, mu_k=0.50, u_mu_k=0.020, mu_s=0.70,
                   u_mu_s=0.03),
        run_record(2, force_N=3.0, repeat=2, mu_k=0.52, u_mu_k=0.022, mu_s=0.72,
                   u_mu_s=0.03),
        run_record(3, force_N=9.0, repeat=1, mu_k=0.40, u_mu_k=0.016, mu_s=0.55,
                   u_mu_s=0.02),
    ]
    runs = fm.records_frame(records)
    table = tables.paper_table(runs)
    assert list(table.columns) == ["pin", "disc", "p [kPa]", "T [°C]", "n", "μ_S ± U",
                                   "μ_K ± U", "flags"]
    groups = group_statistics(runs)
    assert list(table["μ_K ± U"]) == [plus_minus(m, 2 * u) for m, u in
                                      zip(groups["mu_k_mean"], groups["mu_k_u"], strict=True)]
    assert "n = 1" not in table["flags"][0] and table["flags"][1].endswith("n = 1")
    assert "stated u" not in "".join(table["flags"])
    # a measured speed off its nominal does not split a group
    runs.loc[2, "sliding_speed_mm_s"] = 0.07
    assert "v [mm/s]" not in tables.paper_table(runs).columns
    # two nominal sliding speeds of one pair: the table splits by them and shows them
    runs.loc[1, "nominal_speed_mm_s"] = 0.07
    table = tables.paper_table(runs)
    assert list(table["v [mm/s]"]) == ["0.007", "0.07", "0.007"]
    assert list(table["n"]) == [1, 1, 1]


def test_the_terminal_paper_table_keeps_hostile_names_on_one_line(published_runs):
    runs = published_runs.copy()
    runs.loc[runs.index[:3], "pin"] = "evil\x1b[31m\nname"
    text = tables.paper_text(runs)
    assert "\x1b" not in text and "evil\\x1b[31m\\nname" in text
    assert text.splitlines()[0].split() == ["pin", "disc", "p", "[kPa]", "T", "[°C]", "n", "μ_K",
                                            "±", "U", "flags"]
