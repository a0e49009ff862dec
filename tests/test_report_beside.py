"""A report too large for one page: its runs lie beside it, one file per pair, and load
when opened or when a link to one of them is followed; a map of more groups than an
explorer page gets its explorer beside the report; a map of many pairs leaves its pair
plots to the explorer. Read back file by file, and driven in headless Chromium (the house
way of ``test_explorer_browser.py``: absence skips with a reason, a failure where
``TRIBOPIPE_REQUIRE_BROWSER=1``)."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from published_map import PUBLISHED_CSV, write_published_map
from reduced_runs import RUNS, make_processed
from test_report import parse
from tribopipe import report as report_module
from tribopipe.errors import ExportError
from tribopipe.frictionmap import read_map
from tribopipe.report import (
    RUNS_FILE,
    build_report,
    report_files,
    report_inputs,
    run_anchor,
    write_report,
)

#: a run's element in a listing: a row of the runs' table, or the block of a run with a trace
RUN_ELEMENT = re.compile(r'<tr id="run-[^"]+">.*?</tr>|<details class="run">.*?</details>',
                         re.DOTALL)


@pytest.fixture(scope="module")
def processed(tmp_path_factory) -> tuple[Path, Path]:
    return make_processed(tmp_path_factory.mktemp("campaign"))


def chunks(files: dict[str, str]) -> dict[int, str]:
    """The listing each report file beside the page hands to the page, by pair index."""
    out = {}
    for name, text in files.items():
        found = re.fullmatch(r"report_runs/report-(\d+)\.js", name)
        if found:
            head = f"window.tribopipeReportRuns({found.group(1)}, "
            assert text.startswith(head) and text.endswith(");\n")
            out[int(found.group(1))] = json.loads(text[len(head):-3])
    return out


def test_runs_beside_the_page_hold_the_same_listing_one_file_per_pair(processed):
    map_path, proc = processed
    inputs = report_inputs(map_path, proc)
    inline = build_report(inputs)
    files = report_files(inputs, "report.html", runs_inline_limit=0)
    page = files["report.html"]
    assert list(files)[-1] == "report.html"
    listing = chunks(files)
    runs = read_map(map_path)
    # one file per pair, in the report's order; the explorer's runs in the same folder
    assert len(listing) == len(runs[["pin", "disc"]].drop_duplicates()) == 2
    assert {n for n in files if n.startswith("report_runs/pair-")} == {
        "report_runs/pair-0.js", "report_runs/pair-1.js"}
    assert RUNS_FILE.format(k=0) == "report-0.js"
    # the page holds no run and no trace plot; every run link names its pair's file
    assert RUN_ELEMENT.search(page) is None and "trace of run" not in page
    links = re.findall(r'<a href="#(run-[^"]+)" data-runs="(\d+)">', page)
    assert {a for a, _ in links} == {run_anchor(m) for m in runs["measurement_id"]}
    for anchor, k in links:
        assert f'id="{anchor}"' in listing[int(k)]
    # the files hold the runs of the inline page, element for element
    inline_runs = inline.split('<section id="runs">', 1)[1]
    assert sorted(RUN_ELEMENT.findall("".join(listing.values()))) == sorted(
        RUN_ELEMENT.findall(inline_runs))
    assert len(RUN_ELEMENT.findall(inline_runs)) == len(RUNS)
    assert 'data-runs-beside="report_runs"' in page
    # nothing but the runs moved: the page with its runs beside is the smaller one
    assert len(page) < len(inline) and "explorer-data" in page


def test_build_report_refuses_a_report_that_needs_files_beside(processed):
    with pytest.raises(ExportError, match="files beside its page"):
        build_report(report_inputs(*processed), runs_inline_limit=0)


def test_a_map_of_more_groups_than_a_page_gets_its_explorer_beside(processed):
    inputs = report_inputs(*processed)
    files = report_files(inputs, "r.html", groups_page_limit=1)
    page = files["r.html"]
    assert "r_explorer.html" in files and "explorer-data" not in page
    assert any(n.startswith("r_explorer_pages/") for n in files)
    found = parse(page)
    assert "explorer-link" in found.ids and "r_explorer.html" in found.external
    assert f"{len(inputs.groups)} condition groups are more than one explorer page" in page


def test_a_map_of_many_pairs_leaves_its_pair_plots_to_the_explorer(tmp_path, monkeypatch):
    map_path = write_published_map(PUBLISHED_CSV, tmp_path / "friction_map.parquet")
    monkeypatch.setattr(report_module, "PAIR_PLOTS_LIMIT", 5)
    html = build_report(report_inputs(map_path))
    found = parse(html)
    assert not [1 for _, alt in found.images if " on " in alt]
    assert "This map holds 11 pairs, more than the 5 whose plots a report embeds" in html
    # the group table no longer links plots that are not there: every link lands
    ids = set(found.ids)
    for href in found.hrefs:
        assert href.startswith("data:text/csv") or href[1:] in ids, href


def test_write_report_writes_the_files_beside_then_the_page(processed, tmp_path):
    out = write_report(tmp_path / "out" / "report.html", report_inputs(*processed),
                       runs_inline_limit=0)
    assert out == tmp_path / "out" / "report.html"
    written = sorted(p.name for p in (tmp_path / "out" / "report_runs").iterdir())
    assert written == ["fits.csv", "groups.csv", "pair-0.js", "pair-1.js", "report-0.js",
                       "report-1.js"]


def test_the_tables_download_from_beside_a_page_with_files_beside(processed):
    from tribopipe.export.tables import spreadsheet_csv

    inputs = report_inputs(*processed)
    files = report_files(inputs, "report.html", runs_inline_limit=0)
    page = parse(files["report.html"])
    assert {"report_runs/groups.csv", "report_runs/fits.csv"} <= set(page.external)
    assert "data:text/csv" not in files["report.html"]
    assert files["report_runs/groups.csv"] == spreadsheet_csv(inputs.groups)
    assert files["report_runs/fits.csv"] == spreadsheet_csv(inputs.fits)


# --------------------------------------------------------------------------- in a browser


def test_the_runs_beside_load_in_chromium_as_the_inline_page_shows_them(
        browser, processed, tmp_path):
    from test_explorer_browser import Tab, assert_shows, page_url
    from tribopipe.query import groups_of, query

    map_path, proc = processed
    inputs = report_inputs(map_path, proc)
    inline = write_report(tmp_path / "inline" / "report.html", inputs)
    beside = write_report(tmp_path / "beside" / "report.html", inputs, runs_inline_limit=0)
    runs = read_map(map_path)
    texts = """() => Object.fromEntries(Array.from(document.querySelectorAll(
      '#runs [id^="run-"]'), e => [e.id, e.textContent]))"""
    images = "() => document.querySelectorAll('#runs img[alt^=\"trace of run\"]').length"

    tab = Tab(browser)
    tab.page.goto(page_url(inline))
    want = tab.page.evaluate(texts)
    assert set(want) == {run_anchor(m) for m in runs["measurement_id"]}
    want_images = tab.page.evaluate(images)
    assert want_images == len(RUNS)
    tab.close()

    # a link to a run that is not loaded yet: its pair's file loads and the run opens
    tab = Tab(browser)
    target = run_anchor(str(runs["measurement_id"].iloc[-1]))
    tab.page.goto(page_url(beside) + f"#{target}")
    tab.wait_until(f"document.getElementById('{target}') !== null")
    tab.wait_until(f"document.getElementById('{target}').checkVisibility()")
    assert tab.page.evaluate(texts).keys() < want.keys()  # one pair only
    # opening every pair loads the rest: the same runs, the same text, the same plots
    tab.page.evaluate("document.querySelectorAll('details.runs').forEach(d => d.open = true)")
    tab.wait_until("Array.from(document.querySelectorAll('details.runs'))"
                   ".every(d => d.hasAttribute('data-loaded'))")
    assert tab.page.evaluate(texts) == want
    assert tab.page.evaluate(images) == want_images
    # the group table's links land on the loaded runs
    tab.page.click(f'#group-table a[href="#{run_anchor(str(runs["measurement_id"].iloc[0]))}"]')
    tab.wait_until(f"location.hash === '#{run_anchor(str(runs['measurement_id'].iloc[0]))}'")
    # the explorer inside reads its runs from the same folder
    groups = groups_of(runs, map_path)
    tab.page.goto(page_url(beside, pin="Dragonskin 30", disc="steel", pressure="45",
                           temperature="20"))
    tab.wait_until("window.tribopipeExplorer !== undefined")
    assert_shows(tab, query(groups, "Dragonskin 30", "steel", 45.0, 20.0))
    tab.wait_until("document.querySelectorAll('.tpx-repeat').length > 0")
    tab.check_clean()
    tab.close()
