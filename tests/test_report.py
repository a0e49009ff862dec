"""The HTML campaign report: one self-contained page whose sections, group rows, links,
escaping and embedded images are checked — from a real batch run and from the published map."""

from __future__ import annotations

import base64
import io
import re
import shutil
import subprocess
import sys
from html.parser import HTMLParser
from pathlib import Path

import pandas as pd
import pytest
from click.testing import CliRunner

from generators.synthetic import SyntheticRun, write_rheocompass_export
from published_map import PUBLISHED_CSV, write_published_map
from reduced_runs import RUNS, SPREAD_RUNS, make_processed
from tribopipe.campaign import load_campaign, run_campaign
from tribopipe.cli import main
from tribopipe.errors import ExportError
from tribopipe.frictionmap import read_map
from tribopipe.frictionmap.schema import frame_rows
from tribopipe.layout import find_trace
from tribopipe.report import (
    MAP_TITLE,
    build_report,
    group_anchor,
    make_report,
    report_inputs,
    report_sections,
    run_anchor,
)
from tribopipe.rounding import plus_minus
from tribopipe.stats import group_statistics

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


class Page(HTMLParser):
    """Collects what the tests look at: ids, links, images, table rows, external refs."""

    def __init__(self) -> None:
        super().__init__()
        self.ids: list[str] = []
        self.hrefs: list[str] = []
        self.images: list[tuple[str, str]] = []
        self.sections: list[str] = []
        self.rows: dict[str, int] = {}
        self.external: list[str] = []
        self.tags: set[str] = set()
        self._table: str | None = None
        self._in_body = False

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        self.tags.add(tag)
        if "id" in a:
            self.ids.append(a["id"])
        if tag == "section":
            self.sections.append(a.get("id", ""))
        if tag == "a" and "href" in a:
            self.hrefs.append(a["href"])
        if tag == "img":
            self.images.append((a.get("src", ""), a.get("alt", "")))
        for key in ("src", "href"):
            value = a.get(key) or ""
            if value and not value.startswith(("#", "data:")):
                self.external.append(value)
        if tag == "table":
            self._table = a.get("id")
            self.rows.setdefault(self._table, 0)
        if tag == "tbody":
            self._in_body = True
        if tag == "tr" and self._in_body and self._table:
            self.rows[self._table] += 1

    def handle_endtag(self, tag):
        if tag == "tbody":
            self._in_body = False


def parse(html: str) -> Page:
    page = Page()
    page.feed(html)
    return page


def decoded_png(uri: str) -> bytes:
    assert uri.startswith("data:image/png;base64,")
    data = base64.b64decode(uri.split(",", 1)[1], validate=True)
    assert data[:8] == PNG_SIGNATURE
    return data


@pytest.fixture(scope="module")
def processed(tmp_path_factory) -> tuple[Path, Path]:
    map_path, proc = make_processed(tmp_path_factory.mktemp("campaign"))
    (proc / "failures.csv").write_text(
        'file,reason\nraw/odd.csv,"raw/odd.csv:3: no torque column <script>x</script>"\n',
        encoding="utf-8",
    )
    return map_path, proc


@pytest.fixture(scope="module")
def html(processed) -> str:
    map_path, proc = processed
    return build_report(report_inputs(map_path, proc))


def test_sections_in_order_and_self_contained(html):
    page = parse(html)
    assert page.sections == list(report_sections())
    assert page.external == []  # no http(s), no file links, no external scripts or styles
    assert "link" not in page.tags
    assert html.startswith("<!DOCTYPE html>")


def test_group_table_has_one_row_per_group_and_links_to_every_run(processed, html):
    map_path, _ = processed
    runs = read_map(map_path)
    groups = group_statistics(runs)
    page = parse(html)
    assert page.rows["group-table"] == len(groups) == 3
    ids = set(page.ids)
    for mid in runs["measurement_id"]:
        assert f"#{run_anchor(mid)}" in page.hrefs
        assert run_anchor(mid) in ids
    # every internal link lands on something
    for href in page.hrefs:
        if href.startswith("data:text/csv"):
            continue  # the tables' CSV downloads
        assert href.startswith("#") and href[1:] in ids, href


def test_groups_and_runs_show_their_uncertainty_and_the_range_beside_the_t_interval(
    processed, html
):
    map_path, _ = processed
    groups = group_statistics(read_map(map_path))
    assert "<th>μ_K ± U (k = 2)</th>" in html and "<th>μ_K min–max</th>" in html
    assert "<th>μ_K 95 % CI of the repeats</th>" in html
    for g in groups.to_dict(orient="records"):
        # the headline: mean ± U (k = 2), U to two significant digits (GUM)
        assert f"<td>{plus_minus(g['mu_k_mean'], 2 * g['mu_k_u'])}</td>" in html
        assert f"{g['mu_k_min']:.3f}–{g['mu_k_max']:.3f}" in html
    for r in read_map(map_path).to_dict(orient="records"):
        assert f"μ_K {plus_minus(r['mu_k'], 2 * r['u_mu_k'])}" in html


def test_images_decode_pair_plots_and_one_trace_per_run(html):
    page = parse(html)
    pairs = [src for src, alt in page.images if " on " in alt]
    traces = [src for src, alt in page.images if alt.startswith("trace of run")]
    assert len(pairs) == 2
    assert len(traces) == len(RUNS)
    for src in pairs + traces:
        assert len(decoded_png(src)) > 5_000


def test_flagged_runs_and_failures_are_listed_and_escaped(html):
    page = parse(html)
    assert page.rows["flagged-table"] == 1  # the stick-slip run
    assert "stick_slip" in html
    assert page.rows["failure-table"] == 1
    assert "&lt;script&gt;x&lt;/script&gt;" in html
    assert "<script>x</script>" not in html


def test_fits_and_summary(html):
    page = parse(html)
    assert page.rows["fit-table"] == 2
    assert "not fitted" in html  # Ecoflex on wood: one run
    assert "6 (0 excluded)" in html
    assert "repeatability of μ_K" in html


def test_excluded_run_is_shown_with_its_reason(processed, tmp_path):
    from tribopipe.frictionmap import exclude_runs

    map_path, proc = processed
    copy = tmp_path / "friction_map.parquet"
    shutil.copytree(map_path, copy)
    victim = read_map(copy)["measurement_id"].iloc[0]
    exclude_runs(copy, [victim], "pin torn <after> run")
    html = build_report(report_inputs(copy, proc))
    assert "6 (1 excluded)" in html
    assert "excluded: pin torn &lt;after&gt; run" in html
    assert parse(html).rows["flagged-table"] == 2


def test_published_map_report_without_traces_or_failures(tmp_path):
    map_path = write_published_map(PUBLISHED_CSV,
                                   tmp_path / "friction_map.parquet")
    out = make_report(map_path=map_path)
    assert out == tmp_path / "report.html"
    html = out.read_text(encoding="utf-8")
    page = parse(html)
    assert page.rows["group-table"] == 76
    assert page.rows["fit-table"] == 17
    assert len([1 for _, alt in page.images if " on " in alt]) == 11
    assert "No failures.csv" in html
    # a map report: worded so, no μ_S columns (the published map holds none), no per-run
    # expanders saying "no trace", no overlays; the runs as one table, each row a link target
    assert "<title>tribopipe friction-map report</title>" in html
    assert "Map summary" in html and "Campaign summary" not in html
    assert page.sections == list(report_sections(map_report=True))
    assert "μ_S" not in group_header(html) and "μ_S" not in runs_header(html)
    assert "no trace (" not in html and "<details class=\"run\"" not in html
    assert page.rows["runs-table"] == 169
    assert all(run_anchor(m) in page.ids for m in read_map(map_path)["measurement_id"])
    assert "<th class=t>test</th>" not in runs_header(html)  # imported rows name none


def test_runs_without_a_trace_say_which_test_and_result_they_came_from(tmp_path):
    # a map of reduced runs read without its traces: each run's row names its test
    made, _ = make_processed(tmp_path / "lab")
    map_path = tmp_path / "alone" / "friction_map.parquet"  # no traces beside it
    map_path.parent.mkdir()
    shutil.copytree(made, map_path)
    html = make_report(map_path=map_path, output=tmp_path / "r.html").read_text(
        encoding="utf-8")
    header = runs_header(html)
    assert "<th class=t>test</th><th class=t>result</th>" in header
    runs = read_map(map_path)
    body = html.split("<table id=runs-table>", 1)[1].split("</table>", 1)[0]
    for r in runs.itertuples():
        assert f"<td class=t>{r.test}</td><td class=t>{r.result}</td>" in body


def _campaign(root: Path) -> Path:
    raw = root / "raw"
    raw.mkdir()
    for name, run in [
        ("DS30_steel_3N_20C_r1", SyntheticRun(mu_s=0.8, mu_k=0.55, normal_force_N=3.0, seed=1)),
        ("DS30_steel_3N_20C_r2", SyntheticRun(mu_s=0.8, mu_k=0.56, normal_force_N=3.0, seed=2)),
        ("DS30_steel_9N_20C_r1", SyntheticRun(mu_s=0.6, mu_k=0.41, normal_force_N=9.0, seed=3)),
    ]:
        write_rheocompass_export(raw / f"{name}.csv", run, project="p", test=name, sample="s")
    # a run of 3 N whose name says 5 N: refused by the label check, the failure to report
    # (a file that is no export at all is skipped, not failed)
    write_rheocompass_export(raw / "DS30_steel_5N_20C_r1.csv",
                             SyntheticRun(mu_s=0.8, mu_k=0.55, normal_force_N=3.0, seed=4),
                             project="p", test="DS30_steel_5N_20C_r1", sample="s")
    cfg = root / "campaign.toml"
    cfg.write_text(
        '[campaign]\nname = "report test"\nraw_dir = "raw"\nglob = "*.csv"\n'
        'output_dir = "processed"\n'
        'filename_pattern = "{pin}_{disc}_{force}N_{temperature}C_r{repeat}"\n'
        'plots = false\n\n[names]\nDS30 = "Dragonskin 30"\n',
        encoding="utf-8",
    )
    run_campaign(load_campaign(cfg), jobs=1)
    return cfg


@pytest.mark.slow
def test_report_command_from_a_campaign_config(tmp_path):
    cfg = _campaign(tmp_path)
    result = CliRunner().invoke(main, ["report", str(cfg)], catch_exceptions=False)
    assert result.exit_code == 0, result.output
    out = tmp_path / "processed" / "report.html"
    assert out.exists()
    html = out.read_text(encoding="utf-8")
    page = parse(html)
    assert "report test: campaign report" in html
    assert page.rows["failure-table"] == 1
    assert "DS30_steel_5N_20C_r1.csv" in html
    assert len([1 for _, alt in page.images if alt.startswith("trace of run")]) == 3
    # a real process, writing elsewhere
    other = tmp_path / "elsewhere" / "r.html"
    proc = subprocess.run(
        [sys.executable, "-m", "tribopipe", "report", str(cfg), "-o", str(other)],
        capture_output=True, text=True, timeout=180,
    )
    assert proc.returncode == 0, proc.stderr
    assert parse(other.read_text(encoding="utf-8")).rows["group-table"] == 2


def test_report_command_errors_are_one_line(tmp_path):
    result = CliRunner().invoke(main, ["report", "--map", str(tmp_path / "none.parquet")])
    assert result.exit_code == 1
    assert "empty or absent" in result.output and "Traceback" not in result.output


# --------------------------------------------------------------------------- issue 11, part 3


def group_header(html: str) -> str:
    return html.split("<table id=group-table><thead>", 1)[1].split("</thead>", 1)[0]


def runs_header(html: str) -> str:
    return html.split("<table id=runs-table><thead>", 1)[1].split("</thead>", 1)[0]


def downloads(html: str) -> dict[str, pd.DataFrame]:
    """The tables offered for download, by link id, read back as CSV."""
    out = {}
    for element_id, uri in re.findall(r'<a id="([\w-]+)" download="[^"]*" href="([^"]+)"', html):
        head, data = uri.split(",", 1)
        assert head == "data:text/csv;charset=utf-8;base64"
        out[element_id] = pd.read_csv(io.BytesIO(base64.b64decode(data, validate=True)))
    return out


@pytest.fixture(scope="module")
def spread(tmp_path_factory) -> tuple[Path, Path]:
    """A processed campaign with a group whose repeats disagree beyond r."""
    return make_processed(tmp_path_factory.mktemp("spread"), SPREAD_RUNS)


def test_the_repeats_of_a_group_with_range_above_r_are_overlaid(spread):
    map_path, proc = spread
    inputs = report_inputs(map_path, proc)
    wide = inputs.groups[inputs.groups["range_exceeds_r"]]
    assert len(wide) == 1 and float(wide["normal_force_N"].iloc[0]) == 12.0
    html = build_report(inputs)
    page = parse(html)
    anchor = group_anchor(wide.iloc[0].to_dict())
    assert anchor in page.ids and f"#{anchor}" in page.hrefs  # the QC cell links to it
    overlays = [src for src, alt in page.images if alt.startswith("repeats of ")]
    assert len(overlays) == 1 and len(decoded_png(overlays[0])) > 5_000
    section = html.split('<section id="spread">', 1)[1].split("</section>", 1)[0]
    for mid in wide["run_ids"].iloc[0].split(";"):
        assert f'href="#{run_anchor(mid)}"' in section
    # the per-run trace plots are still one per run
    assert len([1 for _, alt in page.images if alt.startswith("trace of run")]) == len(
        SPREAD_RUNS)


def test_the_overlay_draws_each_repeat_from_its_trace(spread, tmp_path):
    from tribopipe.export.plots import plot_group_overlay

    map_path, proc = spread
    runs = read_map(map_path)
    rows = frame_rows(runs[runs["normal_force_N"] == 12.0])
    traces = [(r, pd.read_parquet(find_trace(proc / "traces", r.measurement_id)))
              for r in rows]
    out = plot_group_overlay(traces, tmp_path / "overlay.svg", title="12 N")
    svg = Path(out).read_text(encoding="utf-8")
    # one line per repeat plus its dashed μ_K, and a legend entry naming each run
    for r in rows:
        assert r.measurement_id[:8] in svg
    with pytest.raises(ExportError, match="no traces"):
        plot_group_overlay([], tmp_path / "none.png", title="x")


def test_a_campaign_report_keeps_the_mu_s_columns_and_says_campaign(html):
    assert "μ_S n" in group_header(html) and "Campaign summary" in html
    assert "<title>tribopipe campaign report</title>" in html
    assert 'id="spread"' in html and "No group's repeats spread beyond" in html


def test_group_and_fit_tables_download_as_formula_safe_csv(tmp_path):
    from test_frictionmap import run_record
    from tribopipe.frictionmap import append_records

    map_path = write_published_map(PUBLISHED_CSV, tmp_path / "friction_map.parquet")
    append_records(map_path, [run_record(1, pin="=HYPERLINK(\"http://x\")", disc="@steel"),
                              run_record(2, pin="=HYPERLINK(\"http://x\")", disc="@steel")])
    inputs = report_inputs(map_path)
    html = build_report(inputs)
    tables = downloads(html)
    assert set(tables) == {"group-csv", "fit-csv"}
    groups, fits = tables["group-csv"], tables["fit-csv"]
    assert len(groups) == len(inputs.groups) == 77 and len(fits) == len(inputs.fits)
    assert list(groups.columns) == list(inputs.groups.columns)
    hostile = groups[groups["disc"] == "'@steel"]
    assert list(hostile["pin"]) == ["'=HYPERLINK(\"http://x\")"]
    assert not groups["pin"].str.startswith(("=", "+", "-", "@")).any()
    # numbers stay numbers, negative ones too (the fits' exponents are negative)
    assert (fits["exponent"].dropna() < 0).all() and fits["exponent"].notna().sum() >= 17
    steel = groups[(groups["pin"] == "Dragonskin 30") & (groups["disc"] == "steel")
                   & (groups["temperature_C"] == 20)]
    assert steel["mu_k_mean"].round(2).tolist() == [0.63, 0.45, 0.36, 0.30, 0.26]
    assert inputs.page_title == MAP_TITLE  # the two reduced rows have no trace either
