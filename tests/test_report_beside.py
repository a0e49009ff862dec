"""A report too large for one page: each pair's condition groups, fits and runs lie
beside it, one file per pair, and load when the pair is opened or when a link to one of
its runs is followed; a map of more groups than an explorer page gets its explorer beside
the report; a map of many pairs leaves its pair plots to the explorer. Read back file by
file (every group row, fit row and run of the one-page report reaches exactly one file),
and driven in headless Chromium (the house way of ``test_explorer_browser.py``: absence
skips with a reason, a failure where ``TRIBOPIPE_REQUIRE_BROWSER=1``)."""

from __future__ import annotations

import html
import json
import re
import uuid
from collections import Counter
from pathlib import Path

import pandas as pd
import pytest

from published_map import PUBLISHED_CSV, write_published_map
from reduced_runs import RUNS, make_processed
from test_report import parse
from tribopipe import report as report_module
from tribopipe.errors import ExportError
from tribopipe.fit import fit_power_law
from tribopipe.frictionmap import read_map
from tribopipe.report import (
    PAIR_FILE,
    ReportInputs,
    build_report,
    report_files,
    report_inputs,
    run_anchor,
    write_report,
)
from tribopipe.stats import group_statistics

#: a run's element in a listing: a row of the runs' table, or the block of a run with a trace
RUN_ELEMENT = re.compile(r'<tr id="run-[^"]+">.*?</tr>|<details class="run">.*?</details>',
                         re.DOTALL)
#: the group and fit tables of a page (by id) or of a pair's file (by class)
TABLE = {kind: re.compile(rf"<table (?:id|class)={kind}-table>.*?<tbody>(.*?)</tbody>",
                          re.DOTALL) for kind in ("group", "fit")}
ROW = re.compile(r"<tr[ >].*?</tr>", re.DOTALL)
PAIR_LINK = re.compile(r' data-pair="\d+"')


@pytest.fixture(scope="module")
def processed(tmp_path_factory) -> tuple[Path, Path]:
    return make_processed(tmp_path_factory.mktemp("campaign"))


def pair_files(files: dict[str, str]) -> dict[int, str]:
    """The markup each file beside the page hands to the page, by pair index."""
    out = {}
    for name, text in files.items():
        found = re.fullmatch(r"report_runs/report-(\d+)\.js", name)
        if found:
            head = f"window.tribopipeReportPair({found.group(1)}, "
            assert text.startswith(head) and text.endswith(");\n")
            out[int(found.group(1))] = json.loads(text[len(head):-3])
    return out


def rows(html: str, kind: str) -> list[str]:
    """The rows of every group or fit table (``kind``) in ``html``, their run links'
    pair index set aside (a one-page report's links name no file)."""
    return [PAIR_LINK.sub("", row) for table in TABLE[kind].findall(html)
            for row in ROW.findall(table)]


def assert_same_content(inline: str, files: dict[str, str], page: str) -> dict[int, str]:
    """Every group row, fit row and run of the one-page report ``inline`` is in exactly
    one pair's file, none is in the page, and every run link (in the files and in the
    page) names the file that holds its run. Returns the files' markup by pair."""
    listing = pair_files(files)
    assert sorted(listing) == list(range(len(listing)))
    beside = "".join(listing.values())
    inline_runs = inline.split('<section id="runs">', 1)[1]
    for kind in ("group", "fit"):
        assert rows(inline, kind) and Counter(rows(beside, kind)) == Counter(rows(inline, kind))
        assert rows(page, kind) == []
    assert Counter(RUN_ELEMENT.findall(beside)) == Counter(RUN_ELEMENT.findall(inline_runs))
    assert RUN_ELEMENT.search(page) is None and "trace of run" not in page
    for text in (page, *listing.values()):
        for anchor, k in re.findall(r'<a href="#(run-[^"]+)" data-pair="(\d+)">', text):
            assert f'id="{anchor}"' in listing[int(k)], anchor
    return listing


def test_pairs_beside_hold_the_groups_fits_and_runs_of_the_one_page_report(processed):
    map_path, proc = processed
    inputs = report_inputs(map_path, proc)
    inline = build_report(inputs)
    files = report_files(inputs, "report.html", runs_inline_limit=0)
    page = files["report.html"]
    assert list(files)[-1] == "report.html"
    runs = read_map(map_path)
    listing = assert_same_content(inline, files, page)
    # one file per pair, in the report's order; the explorer's runs in the same folder
    assert len(listing) == len(runs[["pin", "disc"]].drop_duplicates()) == 2
    assert {n for n in files if n.startswith("report_runs/pair-")} == {
        "report_runs/pair-0.js", "report_runs/pair-1.js"}
    assert PAIR_FILE.format(k=0) == "report-0.js"
    assert len(RUN_ELEMENT.findall("".join(listing.values()))) == len(RUNS)
    # the page lists the pairs with their counts; a flagged run's link names its pair
    found = parse(page)
    assert [i for i in found.ids if re.fullmatch(r"pair-\d+", i)] == ["pair-0", "pair-1"]
    assert re.search(r"Dragonskin 30 on steel: 2 groups, 1 fit, 5 runs</summary>", page)
    flagged = page.split('<section id="flagged">', 1)[1].split("</section>", 1)[0]
    assert re.search(r'<a href="#run-[^"]+" data-pair="0">', flagged)
    assert 'data-pairs-beside="report_runs"' in page and "explorer-data" in page
    assert len(page) < len(inline)


def relabelled(runs: pd.DataFrame, lots: int) -> pd.DataFrame:
    """``runs`` copied ``lots`` times, each copy's pins renamed ``<pin> lot <i>`` and its
    ids new: a map whose pairs grow with its runs."""
    copies = []
    for i in range(lots):
        copy = runs.copy()
        copy["pin"] = copy["pin"].astype(str) + f" lot {i}"
        copy["measurement_id"] = [uuid.UUID(int=i * 10**6 + j + 1).hex[-16:]
                                  for j in range(len(copy))]
        copies.append(copy)
    return pd.concat(copies, ignore_index=True)


def test_every_group_and_fit_row_of_a_map_of_many_pairs_reaches_one_file(tmp_path):
    """Thresholds lowered by parameter: a map of 132 pairs whose report (explorer beside
    it too) carries every group row, fit row and run of its one-page report in its files,
    each once, each in its own pair's file; the page carries none."""
    runs = relabelled(read_map(write_published_map(PUBLISHED_CSV, tmp_path / "m.parquet")), 12)
    inputs = ReportInputs(runs=runs, groups=group_statistics(runs), fits=fit_power_law(runs),
                          source="map")
    inline = build_report(inputs)
    files = report_files(inputs, "report.html", runs_inline_limit=500, groups_page_limit=100)
    page = files["report.html"]
    assert "report_explorer.html" in files and "explorer-data" not in page
    listing = assert_same_content(inline, files, page)
    assert len(listing) == len(runs[["pin", "disc"]].drop_duplicates()) == 132
    # each file holds its own pair's groups and fits, as many as the tables hold
    per_pair = inputs.groups.groupby(["pin", "disc"]).size()
    fits_per_pair = inputs.fits.groupby(["pin", "disc"]).size()
    names = re.findall(r'<details class="pair" id="pair-(\d+)"><summary>(.*?) on (.*?): '
                       r"(\d+) groups?, (\d+) fits?, (\d+) runs?</summary>", page)
    assert len(names) == 132
    for k, pin, disc, n_groups, n_fits, n_runs in names:
        assert int(n_groups) == per_pair[(pin, disc)] == len(rows(listing[int(k)], "group"))
        assert int(n_fits) == fits_per_pair.get((pin, disc), 0) == len(
            rows(listing[int(k)], "fit"))
        assert int(n_runs) == len(runs[(runs["pin"] == pin) & (runs["disc"] == disc)])
        pin_cell = f"<td class=t>{report_module._name(html.unescape(pin))}</td>"
        assert all(row.startswith(("<tr>" + pin_cell, '<tr class="flag">' + pin_cell))
                   for row in rows(listing[int(k)], "group"))


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
    assert (tmp_path / "out" / "report.html").stat().st_size > 0
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


#: names that try to leave a pair's file, its markup or a spreadsheet, or to turn the text
#: around (the map itself refuses the RTL marks; a report is handed them here directly)
HOSTILE_PIN = '</script><script>alert(1)</script> =1+1 "q" it\'s'
HOSTILE_DISC = "\u202egpj.exe\u200f <img src=x onerror=alert(2)> \u2028"
HOSTILE_FILE = "</script><svg onload=alert(3)>.csv"


def hostile_inputs(map_path: Path) -> ReportInputs:
    """The campaign's runs with the pair Dragonskin 30 on steel renamed to hostile names,
    one of its runs carrying a QC flag (listed among the flagged runs) and one run of the
    other pair excluded (listed too): a map report (no traces)."""
    runs = read_map(map_path)
    mine = runs["pin"] == "Dragonskin 30"
    runs.loc[mine, "pin"] = HOSTILE_PIN
    runs.loc[mine, "disc"] = HOSTILE_DISC
    runs.loc[mine, "source_file"] = HOSTILE_FILE
    last = runs.index[~mine][-1]
    runs.loc[last, "excluded"] = True
    runs.loc[last, "exclusion_reason"] = "<b onmouseover=alert(4)>slipped</b>"
    return ReportInputs(runs=runs, groups=group_statistics(runs), fits=fit_power_law(runs),
                        source="map")


ROW_TEXTS = """sel => Array.from(document.querySelectorAll(sel), r =>
  Array.from(r.cells, c => c.textContent))"""
#: how far the page sticks out of the window's width [px]
OVERFLOW = "document.documentElement.scrollWidth - document.documentElement.clientWidth"


def test_a_pair_beside_loads_in_chromium_as_python_made_it(browser, processed, tmp_path):
    """Opening a pair loads its groups, fits and runs, the same as the one-page report
    shows them and the figures Python computes; a flagged run's link loads its pair and
    lands on it; the filter finds a pair by a piece of its names; hostile names stay text;
    no error, no dialog, no request leaves the page's folder, and nothing overflows the
    width of an 800 px window."""
    from test_explorer_browser import Tab, page_url
    from tribopipe.escape import printable
    from tribopipe.query import estimate_text
    from tribopipe.stats import group_u

    map_path, _ = processed
    inputs = hostile_inputs(map_path)
    inline = write_report(tmp_path / "inline" / "report.html", inputs)
    beside = write_report(tmp_path / "beside" / "report.html", inputs, runs_inline_limit=0)
    runs, groups = inputs.runs, inputs.groups
    viewport = {"viewport": {"width": 800, "height": 900}}

    tab = Tab(browser, **viewport)
    tab.page.goto(page_url(inline))
    want_groups = tab.page.evaluate(ROW_TEXTS, "#group-table tbody tr")
    want_fits = tab.page.evaluate(ROW_TEXTS, "#fit-table tbody tr")
    want_runs = tab.page.evaluate("""() => Object.fromEntries(Array.from(
      document.querySelectorAll('#runs [id^="run-"]'), e => [e.id, e.textContent]))""")
    tab.check_clean()
    tab.close()

    tab = Tab(browser, **viewport)
    tab.page.goto(page_url(beside))
    assert tab.page.evaluate(OVERFLOW) <= 0
    summaries = tab.page.evaluate(
        "Array.from(document.querySelectorAll('details.pair > summary'), s => s.textContent)")
    # a bidi mark shows as its code (escape.printable): it turns no text around
    assert summaries == [f"{HOSTILE_PIN} on {printable(HOSTILE_DISC)}: 2 groups, 1 fit, 5 runs",
                         "Ecoflex 00-50 on wood (smooth): 0 groups, 0 fits, 1 run"]
    # the filter: a piece of the hostile pin's name finds its pair alone
    tab.page.fill("#pair-filter", "=1+1")
    tab.wait_until("document.getElementById('pair-count').textContent === '1 of 2 pairs'")
    assert tab.page.evaluate("Array.from(document.querySelectorAll('details.pair'), "
                             "d => d.hidden)") == [False, True]
    # opening the pair loads its file: its groups, fits and runs as the one-page report's
    tab.page.click("#pair-0 > summary")
    tab.wait_until("document.getElementById('pair-0').hasAttribute('data-loaded')")
    assert tab.page.evaluate(ROW_TEXTS, "#pair-0 .group-table tbody tr") == want_groups
    assert tab.page.evaluate(ROW_TEXTS, "#pair-0 .fit-table tbody tr") == want_fits
    # a run's link in a narrow column stays on one line (its id is not cut in two)
    lines = tab.page.evaluate("""() => Array.from(document.querySelectorAll(
      '#pair-0 .group-table a[href^="#run-"]'), a => a.getClientRects().length)""")
    assert lines and set(lines) == {1}
    # ... while a name's link in a text cell still breaks (a long name widens nothing)
    assert set(tab.page.evaluate("""() => Array.from(document.querySelectorAll(
      '#pair-0 td.t a:not([href^="#run-"])'), a => getComputedStyle(a).whiteSpace)""")) \
        == {"normal"}
    mine = runs[runs["pin"] == HOSTILE_PIN]
    loaded = tab.page.evaluate("""() => Object.fromEntries(Array.from(
      document.querySelectorAll('#pair-0 [id^="run-"]'), e => [e.id, e.textContent]))""")
    assert loaded == {run_anchor(m): want_runs[run_anchor(m)] for m in mine["measurement_id"]}
    # ... and the figures Python computes: names, n, μ_K ± U (k = 2)
    u_k, _ = group_u(groups, "mu_k")
    assert [row[:2] + [row[5], row[6]] for row in want_groups] == [
        [HOSTILE_PIN, printable(HOSTILE_DISC), str(g.mu_k_n),
         estimate_text(g.mu_k_mean, 2 * u, g.mu_k_n)]
        for g, u in zip(groups.itertuples(), u_k, strict=True) if g.pin == HOSTILE_PIN]
    assert tab.page.evaluate(OVERFLOW) <= 0
    # hostile names stay text: the page's and the explorer's scripts, the pair's file and
    # the explorer's file of the runs it shows, nothing else
    counts = tab.page.evaluate("""() => ({
      code: Array.from(document.querySelectorAll('script:not([type])'),
                       s => s.src ? 'file:' + s.src.split('/').pop() : 'inline'),
      handlers: document.querySelectorAll('[onerror], [onload], [onmouseover]').length,
      bold: document.querySelectorAll('b').length, svgs: document.querySelectorAll(
        'svg[onload]').length})""")
    code = sorted(counts.pop("code"))
    assert code[-2:] == ["inline", "inline"] and "file:report-0.js" in code
    assert all(re.fullmatch(r"file:pair-\d\.js", c) for c in code[:-2]
               if c != "file:report-0.js")
    assert counts == {"handlers": 0, "bold": 0, "svgs": 0}
    assert HOSTILE_PIN in tab.page.text_content("#pair-0 .runs-table")
    assert HOSTILE_FILE in tab.page.text_content("#flagged-table")
    tab.check_clean()
    tab.close()

    # a flagged run's link, its pair not loaded yet: the pair's file loads, the run shows
    excluded = str(runs.loc[runs["excluded"].fillna(False).astype(bool),
                            "measurement_id"].iloc[0])
    target = run_anchor(excluded)
    tab = Tab(browser, **viewport)
    tab.page.goto(page_url(beside))
    assert tab.page.evaluate("document.getElementById('pair-1').hasAttribute('data-loaded')") \
        is False
    tab.page.click(f'#flagged-table a[href="#{target}"]')
    tab.wait_until(f"document.getElementById('{target}') !== null")
    tab.wait_until(f"document.getElementById('{target}').checkVisibility()")
    assert tab.page.evaluate("location.hash") == f"#{target}"
    assert tab.page.evaluate(f"document.getElementById('{target}').textContent") == \
        want_runs[target]
    # the address alone (a link from elsewhere to a flagged run) does the same
    tab.page.goto(page_url(beside) + f"#{target}")
    tab.wait_until(f"document.getElementById('{target}') !== null")
    assert tab.page.evaluate(OVERFLOW) <= 0
    tab.check_clean()
    tab.close()


def test_a_page_named_with_url_characters_loads_its_pairs_in_chromium(
        browser, processed, tmp_path):
    """A report saved as ``r#1 ?%.html`` keeps its pairs in ``r#1 ?%_runs``: the page loads
    them from there (the folder's name a path, not a fragment or a query), and a run link
    whose pair file holds no such run leaves the page still (no endless reloading)."""
    from test_explorer_browser import Tab, page_url

    map_path, _ = processed
    inputs = hostile_inputs(map_path)
    page = write_report(tmp_path / "r#1 ?%.html", inputs, runs_inline_limit=0)
    assert (tmp_path / "r#1 ?%_runs" / "report-0.js").is_file()
    tab = Tab(browser, viewport={"width": 800, "height": 900})
    tab.page.goto(page_url(page))
    tab.page.click("#pair-0 > summary")
    tab.wait_until("document.getElementById('pair-0').hasAttribute('data-loaded')")
    assert tab.page.evaluate("document.querySelectorAll('#pair-0 [id^=\"run-\"]').length") > 0
    # a link to a run its pair's file does not hold: followed once, then left
    tab.page.evaluate("""() => {const a = document.createElement('a');
      a.href = '#run-0000000000000000'; a.setAttribute('data-pair', '0');
      a.textContent = 'gone'; document.body.append(a);
      location.hash = 'run-0000000000000000';}""")
    tab.page.wait_for_timeout(300)
    assert tab.page.evaluate("document.querySelectorAll('script[id^=\"pair-load-\"]').length") == 1
    tab.check_clean()
    tab.close()


def test_the_runs_beside_load_in_chromium_as_the_inline_page_shows_them(
        browser, processed, tmp_path):
    """A campaign's pairs beside its page: a link to a flagged run loads its pair and
    opens its trace block; opening every pair shows every run as the one-page report
    does, trace plots too; the group rows' run links land; the explorer inside reads its
    runs from the same folder."""
    from test_explorer_browser import Tab, assert_shows, page_url
    from tribopipe.labels import quality_flags
    from tribopipe.query import groups_of, query

    map_path, proc = processed
    inputs = report_inputs(map_path, proc)
    inline = write_report(tmp_path / "inline" / "report.html", inputs)
    beside = write_report(tmp_path / "beside" / "report.html", inputs, runs_inline_limit=0)
    runs = read_map(map_path)
    texts = """where => Object.fromEntries(Array.from(document.querySelectorAll(
      where + ' [id^="run-"]'), e => [e.id, e.textContent]))"""
    images = "where => document.querySelectorAll(where + ' img[alt^=\"trace of run\"]').length"

    tab = Tab(browser)
    tab.page.goto(page_url(inline))
    want = tab.page.evaluate(texts, "#runs")
    assert set(want) == {run_anchor(m) for m in runs["measurement_id"]}
    want_images = tab.page.evaluate(images, "#runs")
    assert want_images == len(RUNS)
    tab.close()

    # a link to a flagged run whose pair is not loaded yet: the pair loads, the run opens
    tab = Tab(browser)
    flagged = runs[runs["flags"].map(lambda f: bool(quality_flags(f)))]
    target = run_anchor(str(flagged["measurement_id"].iloc[0]))
    tab.page.goto(page_url(beside) + f"#{target}")
    tab.wait_until(f"document.getElementById('{target}') !== null")
    tab.wait_until(f"document.getElementById('{target}').checkVisibility()")
    assert tab.page.evaluate(texts, "#pair-list").keys() < want.keys()  # one pair only
    # opening every pair loads the rest: the same runs, the same text, the same plots
    tab.page.evaluate("document.querySelectorAll('details.pair').forEach(d => d.open = true)")
    tab.wait_until("Array.from(document.querySelectorAll('details.pair'))"
                   ".every(d => d.hasAttribute('data-loaded'))")
    assert tab.page.evaluate(texts, "#pair-list") == want
    assert tab.page.evaluate(images, "#pair-list") == want_images
    # the group rows' links land on the loaded runs
    first = run_anchor(str(runs["measurement_id"].iloc[0]))
    tab.page.click(f'#pair-list .group-table a[href="#{first}"]')
    tab.wait_until(f"location.hash === '#{first}'")
    # the explorer inside reads its runs from the same folder
    groups = groups_of(runs, map_path)
    tab.page.goto(page_url(beside, pin="Dragonskin 30", disc="steel", pressure="45",
                           temperature="20"))
    tab.wait_until("window.tribopipeExplorer !== undefined")
    assert_shows(tab, query(groups, "Dragonskin 30", "steel", 45.0, 20.0))
    tab.wait_until("document.querySelectorAll('.tpx-repeat').length > 0")
    tab.check_clean()
    tab.close()
