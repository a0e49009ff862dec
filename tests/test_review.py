"""A lab's review: ``review.csv`` read and checked, applied by ``batch`` on every run, kept
beside the automatic values, shown by every output; and the readings over a reviewer's
window held equal to the reduction's own over the automatic window.

The campaign is a real one: a few of the shipped example exports, reduced by the real
batch into real Parquet maps and traces.
"""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest
from click.testing import CliRunner

from map_files import map_bytes
from tribopipe.campaign import load_campaign, run_campaign
from tribopipe.cli import main
from tribopipe.export.citation import Publisher
from tribopipe.export.publish import publish_map
from tribopipe.export.tables import paper_table
from tribopipe.frictionmap import read_map
from tribopipe.frictionmap.summary import map_summary
from tribopipe.layout import TRACE_ID_KEY, find_trace
from tribopipe.reduction.manual import (
    TRACE_META_KEY,
    SlidingSamples,
    TraceTerms,
    kinetic_over,
    static_at,
)
from tribopipe.reduction.uncertainty import mean_standard_error
from tribopipe.review import HEADER, ReviewError, parse_review, review_csv
from tribopipe.stats import group_statistics

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "raw" / "example"
FILES = ["DS30_acrylic_1N_10C_r1.csv", "DS30_acrylic_1N_10C_r2.csv",
         "DS30_acrylic_5N_20C_r1.csv", "DS30_acrylic_5N_20C_r2.csv",
         "EF50_steel_1N_20C_r1.csv", "EF50_steel_1N_20C_r2.csv"]
CONFIG = """[campaign]
name = "rev"
raw_dir = "raw"
output_dir = "out"
filename_pattern = "{{pin}}_{{disc}}_{{force}}N_{{temperature}}C_r{{repeat}}"
plots = false
{extra}
[names]
DS30 = "Dragonskin 30"
EF50 = "Ecoflex 00-50"
acrylic = "acrylic glass"
"""


def make_campaign(root: Path, extra: str = "") -> Path:
    (root / "raw").mkdir(parents=True, exist_ok=True)
    for name in FILES:
        shutil.copy(EXAMPLE / name, root / "raw" / name)
    cfg = root / "campaign.toml"
    cfg.write_text(CONFIG.format(extra=extra), encoding="utf-8")
    return cfg


@pytest.fixture(scope="module")
def reduced(tmp_path_factory) -> Path:
    """A campaign reduced once (copied by the tests that change it)."""
    root = tmp_path_factory.mktemp("campaign")
    cfg = make_campaign(root)
    report = run_campaign(load_campaign(cfg), jobs=1, plots=False)
    assert report.ok and len(report.reduced) == len(FILES)
    return root


@pytest.fixture
def campaign(reduced: Path, tmp_path: Path) -> Path:
    root = tmp_path / "c"
    shutil.copytree(reduced, root)
    return root


def batch(root: Path, *args: str) -> object:
    return CliRunner().invoke(main, ["batch", str(root / "campaign.toml"), "-j", "1", *args],
                              catch_exceptions=False)


def the_map(root: Path) -> pd.DataFrame:
    return read_map(root / "out" / "friction_map.parquet")


def samples_of(root: Path, mid: str) -> tuple[SlidingSamples, TraceTerms]:
    table = pq.read_table(find_trace(root / "out" / "traces", mid))
    # the footer names the run whose trace it is (two runs may share the file's 8 digits)
    assert table.schema.metadata[TRACE_ID_KEY] == mid.encode()
    terms = TraceTerms.from_json(table.schema.metadata[TRACE_META_KEY])
    assert terms is not None
    return SlidingSamples.of_trace(table.to_pandas()), terms


def independent_mu_k(root: Path, mid: str, lo: float, hi: float) -> float:
    """μ_K recomputed from the trace Parquet alone: the mean of μ over the sliding
    samples (finite ``mu_smooth``) with lo ≤ s ≤ hi."""
    t = pd.read_parquet(find_trace(root / "out" / "traces", mid))
    sel = t["mu_smooth"].notna() & t["sliding_distance_mm"].between(lo, hi)
    return float(t.loc[sel, "mu"].mean())


def write_review(root: Path, rows: list[list[str]]) -> Path:
    path = root / "review.csv"
    path.write_text("\n".join([",".join(HEADER)] + [",".join(r) for r in rows]) + "\n",
                    encoding="utf-8")
    return path


# ---------------------------------------------------------------- the estimator


def test_the_window_reading_over_the_automatic_window_is_the_reductions(reduced: Path):
    """Differential: μ_K and u(μ_K) re-read over each run's automatic window from its
    trace file equal what the reduction stored, to rounding."""
    runs = the_map(reduced)
    for row in runs.to_dict(orient="records"):
        smp, terms = samples_of(reduced, row["measurement_id"])
        k = kinetic_over(smp, row["mu_k_window_start_mm"], row["mu_k_window_end_mm"], terms)
        assert k.mu_k == pytest.approx(row["mu_k"], rel=1e-12, abs=1e-15)
        assert k.u_mu_k == pytest.approx(row["u_mu_k"], rel=1e-12)
        assert (k.start_mm, k.end_mm) == (row["mu_k_window_start_mm"], row["mu_k_window_end_mm"])
        assert k.std == pytest.approx(row["plateau_std"], rel=1e-9)


def test_a_window_reading_is_the_mean_and_its_budget(reduced: Path):
    mid = the_map(reduced)["measurement_id"].iloc[0]
    smp, terms = samples_of(reduced, mid)
    k = kinetic_over(smp, 0.6, 1.0, terms)
    sel = (smp.s_mm >= 0.6) & (smp.s_mm <= 1.0)
    assert k.n == int(sel.sum()) and k.mu_k == pytest.approx(float(np.mean(smp.mu[sel])), rel=1e-14)
    se, _ = mean_standard_error(smp.mu[sel])
    expected = math.sqrt(se**2 + (k.mu_k * terms.u_relative) ** 2 + terms.u_absolute**2)
    assert k.u_mu_k == pytest.approx(expected, rel=1e-14)
    assert terms.u_relative > 0.04  # the friction radius alone is 4.1 %


def test_a_peak_reading_is_the_quadratic_through_its_samples(reduced: Path):
    mid = the_map(reduced)["measurement_id"].iloc[0]
    smp, terms = samples_of(reduced, mid)
    peak = 0.15
    s = static_at(smp, peak, terms)
    near = np.abs(smp.s_mm - peak) <= terms.peak_window_mm / 2
    coef = np.polyfit(smp.s_mm[near] - peak, smp.mu[near], 2)
    assert s.n == int(near.sum()) >= 5
    assert s.mu_s == pytest.approx(coef[-1], rel=1e-9)
    assert s.u_mu_s > s.mu_s * terms.u_relative


@pytest.mark.parametrize(("lo", "hi", "words"), [
    (5.0, 6.0, "outside the trace"), (0.7, 0.71, "needs at least 30"),
    (0.8, 0.7, "must end after"),
])
def test_a_bad_window_is_refused_in_one_line(reduced: Path, lo, hi, words):
    from tribopipe.errors import ReductionError

    mid = the_map(reduced)["measurement_id"].iloc[0]
    smp, terms = samples_of(reduced, mid)
    with pytest.raises(ReductionError) as err:
        kinetic_over(smp, lo, hi, terms, where="review.csv line 2")
    assert words in str(err.value) and "\n" not in str(err.value)
    assert "review.csv line 2" in str(err.value)


# ---------------------------------------------------------------- the decisions file


def test_the_decisions_file_round_trips_and_refuses_bad_rows(tmp_path: Path):
    text = ("run,action,kinetic_from_mm,kinetic_to_mm,static_peak_mm,reason,who,date\n"
            "abc,window,0.5,1.2,0.2,,A,2026-11-27\n"
            "def,exclude,,,,=cmd(),B,2026-11-27\n"
            "ghi,accept,,,,fine,,\n")
    review = parse_review(text, tmp_path / "review.csv")
    assert [d.action for d in review.decisions] == ["window", "exclude", "accept"]
    assert review.decisions[0].kinetic_from_mm == 0.5 and review.decisions[0].line == 2
    again = parse_review(review_csv(review.decisions), tmp_path / "review.csv")
    assert [(d.run, d.action, d.kinetic_from_mm, d.kinetic_to_mm, d.static_peak_mm, d.reason,
             d.who, d.date) for d in again.decisions] == [
        (d.run, d.action, d.kinetic_from_mm, d.kinetic_to_mm, d.static_peak_mm, d.reason,
         d.who, d.date) for d in review.decisions]
    assert "'=cmd()" in review_csv(review.decisions)  # a formula stays text
    head = ",".join(HEADER)
    for body, words in [
        ("abc,frobnicate,,,,,,", "not one of accept, exclude, window"),
        ("abc,window,0.5,,,,,", "needs kinetic_from_mm and kinetic_to_mm"),
        ("abc,window,1.5,0.5,,,,", "must end after it starts"),
        ("abc,exclude,,,,,,", "needs a reason"),
        ("abc,accept,0.1,0.2,,,,", "belong to a window decision"),
        ("abc,window,x,1,,,,", "is not a number"),
        ("abc,window,-1,1,,,,", "finite distance"),
        ("abc,accept,,,,,,\nabc,accept,,,,,,", "decided twice (also on line 2)"),
    ]:
        with pytest.raises(ReviewError) as err:
            parse_review(f"{head}\n{body}\n", tmp_path / "review.csv")
        message = str(err.value)
        assert words in message and "review.csv line" in message and "\n" not in message
    with pytest.raises(ReviewError, match="line 1: expected the columns"):
        parse_review("run,action\nabc,accept\n", tmp_path / "review.csv")


# ---------------------------------------------------------------- batch applies it


def test_batch_applies_each_decision_and_keeps_the_automatic_values(campaign: Path):
    before = the_map(campaign).set_index("measurement_id")
    ids = list(before.index)
    path = write_review(campaign, [
        [ids[0], "window", "0.6", "1.1", "0.15", "plateau settles late", "A. Person", "2026-11-27"],
        [FILES[1], "exclude", "", "", "", "pin slipped", "A. Person", "2026-11-27"],
        [ids[2], "accept", "", "", "", "looked at it", "B. Person", "2026-11-27"],
    ])
    result = batch(campaign, "--review", str(path))
    assert result.exit_code == 0, result.output
    assert "1 accept, 1 exclude, 1 window" in result.output
    after = the_map(campaign).set_index("measurement_id")
    w = after.loc[ids[0]]
    assert w["review"] == "window" and w["review_by"] == "A. Person"
    assert w["review_reason"] == "plateau settles late" and w["review_date"] == "2026-11-27"
    assert w["auto_mu_k"] == before.loc[ids[0], "mu_k"]
    assert w["auto_u_mu_k"] == before.loc[ids[0], "u_mu_k"]
    assert w["auto_mu_s"] == before.loc[ids[0], "mu_s"]
    assert w["auto_mu_k_window_start_mm"] == before.loc[ids[0], "mu_k_window_start_mm"]
    assert w["mu_k"] == pytest.approx(independent_mu_k(campaign, ids[0], 0.6, 1.1), rel=1e-12)
    assert w["mu_k"] != before.loc[ids[0], "mu_k"]
    assert 0.6 <= w["mu_k_window_start_mm"] < w["mu_k_window_end_mm"] <= 1.1
    assert w["mu_s_distance_mm"] == 0.15 and w["mu_s"] != before.loc[ids[0], "mu_s"]
    excluded = after[after["source_file"] == FILES[1]].iloc[0]
    assert excluded["excluded"] and excluded["exclusion_reason"] == "pin slipped"
    assert excluded["review"] == "exclude"
    assert after.loc[ids[2], "review"] == "accept"
    assert after.loc[ids[2], "mu_k"] == before.loc[ids[2], "mu_k"]
    # the same file again changes nothing, to the byte
    map_file = campaign / "out" / "friction_map.parquet"
    stamp = map_bytes(map_file)
    again = batch(campaign, "--review", str(path))
    assert again.exit_code == 0 and "map out/friction_map.parquet: unchanged" in again.output \
        or "unchanged" in again.output
    assert map_bytes(map_file) == stamp


@pytest.mark.parametrize(("row", "words"), [
    (["0123456789abcdef", "accept", "", "", "", "", "", ""], "no such run in the map"),
    (["{id}", "window", "9", "12", "", "", "", ""], "lies outside the trace"),
    (["{id}", "window", "0.7", "0.705", "", "", "", ""], "the μ_K estimator needs at least"),
])
def test_a_decision_that_cannot_apply_is_refused_naming_its_line(campaign: Path, row, words):
    mid = the_map(campaign)["measurement_id"].iloc[0]
    good = [str(the_map(campaign)["measurement_id"].iloc[1]), "accept", "", "", "", "ok", "", ""]
    path = write_review(campaign, [good, [c.format(id=mid) for c in row]])
    map_file = campaign / "out" / "friction_map.parquet"
    stamp = map_bytes(map_file)
    result = CliRunner().invoke(main, ["batch", str(campaign / "campaign.toml"), "-j", "1",
                                       "--review", str(path)])
    assert result.exit_code != 0
    lines = [line for line in result.output.splitlines() if line.startswith("Error")]
    assert len(lines) == 1 and "review.csv line 3" in lines[0] and words in lines[0]
    assert "Traceback" not in result.output
    assert map_bytes(map_file) == stamp  # nothing else changed: not even the good decision


def test_a_re_reduced_run_keeps_its_review(campaign: Path):
    """Reduced again (another config), a reviewed run takes its review again: from the
    campaign's file, and — without one — from its own row."""
    mid = str(the_map(campaign)["measurement_id"].iloc[0])
    write_review(campaign, [[mid, "window", "0.6", "1.1", "", "later plateau", "A", "2026-11-27"]])
    cfg = campaign / "campaign.toml"
    cfg.write_text(CONFIG.format(extra='review = "review.csv"'), encoding="utf-8")
    assert batch(campaign).exit_code == 0
    first = the_map(campaign).set_index("measurement_id").loc[mid]
    assert first["review"] == "window"
    # another reduction parameter: every run is re-reduced
    cfg.write_text(CONFIG.format(extra="") + "\n[reduction]\nmedian_window = 7\n", encoding="utf-8")
    result = batch(campaign)
    assert result.exit_code == 0 and f"{len(FILES)} reduced" in result.output
    again = the_map(campaign).set_index("measurement_id").loc[mid]
    assert again["review"] == "window" and again["review_reason"] == "later plateau"
    assert again["mu_k"] == pytest.approx(independent_mu_k(campaign, mid, 0.6, 1.1), rel=1e-12)
    assert not math.isnan(again["auto_mu_k"]) and again["auto_mu_k"] != again["mu_k"]


def test_a_withdrawn_decision_brings_the_automatic_values_back(campaign: Path):
    runs = the_map(campaign)
    mid, auto = str(runs["measurement_id"].iloc[0]), runs.iloc[0]
    other = str(runs["measurement_id"].iloc[1])
    path = write_review(campaign, [[mid, "window", "0.6", "1.1", "0.15", "", "", ""],
                                   [other, "exclude", "", "", "", "bad pin", "", ""]])
    assert batch(campaign, "--review", str(path)).exit_code == 0
    path = write_review(campaign, [])
    result = batch(campaign, "--review", str(path))
    assert "2 withdrawn" in result.output
    back = the_map(campaign).set_index("measurement_id")
    for col in ("mu_k", "u_mu_k", "mu_s", "u_mu_s", "mu_k_window_start_mm", "mu_k_window_end_mm",
                "mu_s_distance_mm", "mu_k_window_start_s", "plateau_std"):
        assert back.loc[mid, col] == pytest.approx(auto[col], rel=1e-12), col
    assert pd.isna(back.loc[mid, "review"]) and pd.isna(back.loc[mid, "auto_mu_k"])
    assert not back.loc[other, "excluded"]


def test_accepting_a_flagged_run_clears_its_effect_and_keeps_the_flag(campaign: Path):
    runs = the_map(campaign)
    flagged = runs[runs["flags"].str.contains("off_nominal|no_steady|stick", regex=True)]
    if flagged.empty:  # flag one the honest way: a tighter force tolerance
        cfg = campaign / "campaign.toml"
        cfg.write_text(CONFIG.format(extra="force_tolerance_rel = 0.0001"), encoding="utf-8")
        assert batch(campaign).exit_code == 0
        runs = the_map(campaign)
        flagged = runs[runs["flags"].str.contains("off_nominal")]
    row = flagged.iloc[0]
    group = group_statistics(runs)
    key = (group["pin"] == row["pin"]) & (group["disc"] == row["disc"]) & (
        group["normal_force_N"] == row["normal_force_N"])
    mine = group[key & group["run_ids"].str.contains(row["measurement_id"])]
    others = [m for m in mine.iloc[0]["run_ids"].split(";")]
    path = write_review(campaign, [[m, "accept", "", "", "", "judged fine", "A", ""]
                                   for m in others])
    assert batch(campaign, "--review", str(path)).exit_code == 0
    runs = the_map(campaign)
    after = group_statistics(runs)
    g = after[after["run_ids"] == mine.iloc[0]["run_ids"]].iloc[0]
    assert not g["qc_flagged"] and g["reviewed"] == len(others)
    assert row["flags"] == runs.set_index("measurement_id").loc[row["measurement_id"], "flags"]


# ---------------------------------------------------------------- every output shows it


def test_every_output_marks_and_counts_reviewed_runs(campaign: Path, tmp_path: Path):
    runs = the_map(campaign)
    ids = list(runs["measurement_id"])
    path = write_review(campaign, [[ids[0], "window", "0.6", "1.1", "", "late", "A", "2026-11-27"],
                                   [ids[1], "exclude", "", "", "", "slipped", "A", ""]])
    assert batch(campaign, "--review", str(path)).exit_code == 0
    map_file = campaign / "out" / "friction_map.parquet"
    show = map_summary(map_file)
    assert "reviewed runs: 2 (exclude 1, window 1)" in show
    assert "1 of 1 runs reviewed" in show or "1 of 2 runs reviewed" in show
    assert f"{ids[0]}  window" in show and "(automatic" in show
    table = paper_table(the_map(campaign))
    assert table["flags"].str.contains("1 reviewed").sum() == 1
    out = CliRunner().invoke(main, ["report", str(campaign / "campaign.toml"), "-o",
                                    str(tmp_path / "r.html")], catch_exceptions=False)
    assert out.exit_code == 0, out.output
    html = (tmp_path / "r.html").read_text(encoding="utf-8")
    assert "reviewed runs" in html and "reviewed: window" in html and "1 reviewed" in html
    assert "reviewed: exclude" in html
    import json

    from tribopipe.export.explorer import explorer_data

    data = json.dumps(explorer_data(the_map(campaign), title="t"), ensure_ascii=False)
    assert data.count("(reviewed: window)") == 1
    package = tmp_path / "pkg"
    publish_map(map_file, package, Publisher(lab="Test Lab", contact="A. Person"),
                allow_synthetic=True)
    csv_runs = pd.read_csv(package / "data" / "runs.csv")
    assert set(csv_runs["review"].dropna()) == {"window", "exclude"}
    assert "auto_mu_k" in csv_runs.columns and csv_runs["auto_mu_k"].notna().sum() == 2
    groups = pd.read_csv(package / "data" / "groups.csv")
    assert groups["reviewed"].sum() == 1  # the excluded run is in no group


def test_a_map_of_schema_5_still_reads(tmp_path: Path, reduced: Path):
    """The review columns are optional: a map without them (an older version) reads
    with them missing."""
    runs = the_map(reduced)
    assert runs["review"].isna().all() and runs["auto_mu_k"].isna().all()


def test_reduce_replace_never_silently_re_automates_a_reviewed_run(campaign: Path):
    """`tribopipe reduce --replace` of a reviewed run's export: the run takes its review
    again (from its own row), its automatic values stay beside."""
    runs = the_map(campaign)
    row = runs[runs["source_file"] == FILES[0]].iloc[0]
    mid = str(row["measurement_id"])
    path = write_review(campaign, [[mid, "window", "0.6", "1.1", "", "late", "A", "2026-11-27"]])
    assert batch(campaign, "--review", str(path)).exit_code == 0
    reviewed = the_map(campaign).set_index("measurement_id").loc[mid]
    result = CliRunner().invoke(main, [
        "reduce", str(campaign / "raw" / FILES[0]), "--pin", "Dragonskin 30", "--disc",
        "acrylic glass", "--force", "1", "--temperature", "10", "--repeat", "1",
        "--map", str(campaign / "out" / "friction_map.parquet"), "--out",
        str(campaign / "out"), "--replace"], catch_exceptions=False)
    assert result.exit_code == 0, result.output
    after = the_map(campaign).set_index("measurement_id").loc[mid]
    assert after["review"] == "window" and after["mu_k"] == reviewed["mu_k"]
    assert after["auto_mu_k"] == row["mu_k"]


def test_the_review_page_of_a_map_with_its_traces(campaign: Path, tmp_path: Path):
    """`tribopipe review --map` (traces/ beside the map by default), as a subprocess: one
    self-contained page holding every run, its samples and the decisions the map holds."""
    import subprocess
    import sys

    from tribopipe.export.review_page import DATA_ELEMENT_ID

    mid = str(the_map(campaign)["measurement_id"].iloc[0])
    path = write_review(campaign, [[mid, "accept", "", "", "", "fine", "A", "2026-11-27"]])
    assert batch(campaign, "--review", str(path)).exit_code == 0
    page = tmp_path / "page.html"
    done = subprocess.run([sys.executable, "-m", "tribopipe", "review", "--map",
                           str(campaign / "out" / "friction_map.parquet"), "-o", str(page)],
                          capture_output=True, text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stderr
    html = page.read_text(encoding="utf-8")
    assert f'id="{DATA_ELEMENT_ID}"' in html and "Content-Security-Policy" in html
    assert "<script src" not in html and "http://" not in html and "https://" not in html
    import json
    import re

    data = json.loads(re.search(rf'id="{DATA_ELEMENT_ID}">(.*?)</script>', html, re.S).group(1))
    assert len(data["runs"]) == len(FILES) and all(r["trace"] for r in data["runs"])
    assert [r["decision"]["action"] for r in data["runs"] if r["decision"]] == ["accept"]
    assert all(r["trace"]["n"] > 1000 for r in data["runs"])
    # without a config or --map: one usage line
    bad = CliRunner().invoke(main, ["review"])
    assert bad.exit_code == 2 and "give a campaign CONFIG or --map PATH" in bad.output


def test_a_decisions_file_that_is_no_text_is_one_line(tmp_path: Path):
    from tribopipe.review import read_review

    raw = tmp_path / "review.csv"
    raw.write_bytes(b"run,action\xff\xfe\n")
    with pytest.raises(ReviewError, match="not UTF-8 text"):
        read_review(raw)
    with pytest.raises(ReviewError):
        read_review(tmp_path)  # a folder
    with pytest.raises(ReviewError, match="empty"):
        (tmp_path / "empty.csv").write_text("", encoding="utf-8")
        read_review(tmp_path / "empty.csv")


def test_the_trace_plot_says_a_run_was_reviewed():
    from tribopipe.figures.runinfo import TraceMarks

    marks = TraceMarks(mu_s=0.7, mu_s_distance_mm=0.1, mu_k=0.5, mu_k_window_mm=(0.6, 1.1),
                       review="window")
    assert marks.line().endswith(" · reviewed: window")
    assert "reviewed" not in TraceMarks(0.7, 0.1, 0.5, (0.6, 1.1)).line()
