"""The explorer page in a real headless browser (Debian's ``chromium``, driven by
Playwright with the system browser — no browser is downloaded).

The page's μ_K, uncertainty and clamping must equal ``tribopipe query``'s over a grid of
conditions (measured, between groups, between temperatures, outside the range), on the
shipped published map and on a small map of really reduced runs; a link must restore a
selection; hostile names must stay text; nothing may be logged as an error and no request
may leave the page. Where no browser exists the tests skip and say why (CI sets
``TRIBOPIPE_REQUIRE_BROWSER=1`` and so fails instead).
"""

from __future__ import annotations

import functools
import http.server
import math
import threading
import time
from pathlib import Path
from urllib.parse import urlencode

import pytest

from helpers import lab_vocabulary
from reduced_runs import make_processed
from tribopipe.export.explorer import write_explorer
from tribopipe.export.fe_decks import condition_snippet
from tribopipe.export.registry import WRITERS
from tribopipe.export.simulators import snippet
from tribopipe.export.tables import condition_text
from tribopipe.frictionmap import import_table, read_map
from tribopipe.frictionmap.published import published_csv_path
from tribopipe.query import groups_of, pairs, query
from tribopipe.report import make_report

HOSTILE_PIN = "</script><script>alert(1)</script>"
HOSTILE_DISC = "<img src=x onerror=alert(2)> & co"
#: values agree to rounding: numpy's dot may fuse multiply-adds, JavaScript never does
REL = 1e-12


class Tab:
    """A page with everything it logs, raises or requests collected."""

    def __init__(self, browser, **context) -> None:
        self.context = browser.new_context(accept_downloads=True, **context)
        self.page = self.context.new_page()
        self.problems: list[str] = []
        self.requests: list[str] = []
        self.dialogs: list[str] = []
        self.page.on("console", self._console)
        self.page.on("pageerror", lambda exc: self.problems.append(f"page error: {exc}"))
        self.page.on("request", lambda req: self.requests.append(req.url))

        def dialog(d) -> None:
            self.dialogs.append(d.message)
            d.dismiss()

        self.page.on("dialog", dialog)

    def _console(self, msg) -> None:
        if msg.type in ("error", "warning"):
            self.problems.append(f"console {msg.type}: {msg.text}")

    def open(self, url: str) -> None:
        self.page.goto(url)
        self.wait_until("window.tribopipeExplorer !== undefined")

    def wait_until(self, expression: str, timeout_s: float = 30.0) -> None:
        """Poll a JavaScript expression from Python until it is true.

        Playwright's ``wait_for_function`` may fall back to ``eval`` inside the page when
        it has to poll, which the page's Content-Security-Policy rightly forbids (and
        which then fails under load); ``page.evaluate`` is not subject to the policy.
        """
        deadline = time.monotonic() + timeout_s
        while not self.page.evaluate(expression):
            if time.monotonic() > deadline:
                raise AssertionError(f"page never satisfied: {expression}")
            time.sleep(0.02)

    def address(self) -> str:
        """The page's address as the page itself has it (``page.url`` follows a
        ``history.replaceState`` only when the browser's event arrives, late under load)."""
        return self.page.evaluate("location.href")

    def check_clean(self, *, origin: str = "file://") -> None:
        assert self.problems == []
        assert self.dialogs == []
        foreign = [u for u in self.requests if not u.startswith((origin, "blob:", "data:"))]
        assert foreign == []

    def close(self) -> None:
        self.context.close()


@pytest.fixture
def tab(browser):
    t = Tab(browser)
    yield t
    t.check_clean()
    t.close()


def page_url(path: Path, **selection) -> str:
    query_string = urlencode({k: v for k, v in selection.items() if v is not None})
    return path.resolve().as_uri() + (f"?{query_string}" if query_string else "")


@pytest.fixture(scope="module")
def published(tmp_path_factory):
    """The shipped published map, imported, and its explorer page."""
    root = tmp_path_factory.mktemp("published")
    map_path = root / "friction_map.parquet"
    import_table(map_path, published_csv_path())
    page = write_explorer(map_path, root / "explorer.html")
    return map_path, page, groups_of(read_map(map_path), map_path)


@pytest.fixture(scope="module")
def reduced(tmp_path_factory):
    """A small map of really reduced synthetic runs (μ_S known, one temperature, a pair
    with a single run), its processed folder and its explorer page."""
    map_path, processed = make_processed(tmp_path_factory.mktemp("reduced"))
    page = write_explorer(map_path, processed / "explorer.html")
    return map_path, page, groups_of(read_map(map_path), map_path), processed


def grid(groups) -> list[tuple[str, str, float, float | None]]:
    """Conditions per pair: each measured pressure, points between and beyond them, zero;
    each measured temperature, between them, below and above, and none where allowed."""
    out = []
    for pin, disc in pairs(groups):
        pair = groups[(groups["pin"] == pin) & (groups["disc"] == disc)]
        ps = sorted(set(pair["pressure_kPa"]))
        ts = sorted(set(pair["temperature_C"].dropna()))
        pressures = ps + [(a + b) / 2 for a, b in zip(ps, ps[1:], strict=False)]
        pressures += [0.0, ps[0] * 0.5, ps[-1] * 1.7, 1000.0]
        temps: list[float | None] = ts + [ts[0] - 7.5, ts[-1] + 12.25]
        temps += [(a + b) / 2 for a, b in zip(ts, ts[1:], strict=False)] + [ts[0] + 0.3]
        if len(ts) == 1:
            temps.append(None)
        out += [(pin, disc, p, t) for p in pressures for t in temps]
    return out


PAGE_QUERY = """conditions => conditions.map(([pin, disc, p, t]) => {
  try { return {ok: window.tribopipeExplorer.query(pin, disc, p, t)}; }
  catch (e) { return {error: e.message}; }
})"""


def same(a: float | None, b: float | None) -> bool:
    if a is None or b is None:
        return a is None and b is None
    return math.isclose(a, b, rel_tol=REL, abs_tol=1e-15)


def assert_same_estimate(page_est: dict | None, est) -> None:
    if est is None:
        assert page_est is None
        return
    assert same(page_est["value"], est.value)
    assert same(page_est["uncertainty"], est.uncertainty)
    # the combined standard uncertainty (the runs' budgets) travels with the same weights
    assert same(page_est["u_combined"], est.u_combined)
    # and U (k = 2) with the interpolation's own u, the headline
    assert same(page_est["u_interpolation"], est.u_interpolation)
    assert same(page_est["expanded"], est.expanded)
    assert page_est["budgets_known"] == est.budgets_known and page_est["n_min"] == est.n_min
    assert page_est["clamped_pressure"] == est.clamped_pressure
    assert page_est["clamped_temperature"] == est.clamped_temperature
    assert len(page_est["used"]) == len(est.used)
    for mine, theirs in zip(page_est["used"], est.used, strict=True):
        assert mine["pressure_kPa"] == theirs.pressure_kPa
        assert mine["temperature_C"] == theirs.temperature_C
        assert mine["mean"] == theirs.mean and mine["n"] == theirs.n
        assert same(mine["weight"], theirs.weight)
        assert same(mine["ci95_half_width"], theirs.ci95_half_width)
        assert same(mine["u"], theirs.u)


def assert_page_equals_query(tab, groups, conditions) -> int:
    answers = tab.page.evaluate(PAGE_QUERY, [list(c) for c in conditions])
    clamped = 0
    for (pin, disc, p, t), answer in zip(conditions, answers, strict=True):
        try:
            res = query(groups, pin, disc, p, t)
        except Exception as exc:  # the page must refuse with the same words
            assert answer.get("error") == exc.problem, (pin, disc, p, t)
            continue
        assert "ok" in answer, (pin, disc, p, t, answer)
        mine = answer["ok"]
        assert_same_estimate(mine["mu_k"], res.mu_k)
        assert_same_estimate(mine["mu_s"], res.mu_s)
        assert mine["clamped"] == res.clamped
        assert mine["notes"] == list(res.notes)
        assert tuple(mine["pressure_range_kPa"]) == res.pressure_range_kPa
        assert tuple(mine["temperatures_C"]) == res.temperatures_C
        clamped += res.clamped
    return clamped


PAGE_SNIPPETS = """([conditions, fmts]) => conditions.map(([pin, disc, p, t]) => {
  const res = window.tribopipeExplorer.query(pin, disc, p, t);
  return fmts.map(fmt => window.tribopipeExplorer.exportText(fmt, res));
})"""


def assert_snippets_are_the_writer_s(tab, groups, conditions, source: str) -> None:
    """The page's text of every registered snippet format equals the Python writer's."""
    formats = [w.name for w in WRITERS if w.snippet is not None]
    texts = tab.page.evaluate(PAGE_SNIPPETS, [[list(c) for c in conditions], formats])
    for (pin, disc, p, t), row in zip(conditions, texts, strict=True):
        res = query(groups, pin, disc, p, t)
        for fmt, text in zip(formats, row, strict=True):
            assert text == snippet(fmt, res, source=source), (fmt, pin, disc, p, t)


@pytest.mark.slow  # a real process or a larger data set: `pytest -m slow`
def test_page_equals_query_on_the_published_map(tab, published):
    map_path, page, groups = published
    tab.open(page_url(page))
    conditions = grid(groups)
    clamped = assert_page_equals_query(tab, groups, conditions)
    assert len(conditions) > 700 and 300 < clamped < len(conditions)
    assert_snippets_are_the_writer_s(tab, groups, conditions[::7], str(map_path))


def test_page_equals_query_on_a_reduced_map(tab, reduced):
    _, page, groups, _ = reduced
    tab.open(page_url(page))
    conditions = grid(groups) + [("Dragonskin 30", "steel", -1.0, 20.0),
                                 ("dragonskin 30", " STEEL ", 40.0, None)]
    assert_page_equals_query(tab, groups, conditions)
    res = tab.page.evaluate(PAGE_QUERY, [["Ecoflex 00-50", "wood (smooth)", 20.0, 20.0]])[0]["ok"]
    assert "n = 1, no repeat scatter: a group used has a single run" in res["notes"]


def shown(tab) -> dict:
    return tab.page.evaluate("""() => {
      const e = document.getElementById('mu-k');
      return {text: e.textContent, value: e.dataset.value, uncertainty: e.dataset.uncertainty,
              clampedPressure: e.dataset.clampedPressure,
              clampedTemperature: e.dataset.clampedTemperature,
              clamped: document.getElementById('clamped').textContent,
              muS: document.getElementById('mu-s').textContent,
              u: document.getElementById('mu-k-u').textContent,
              uValue: document.getElementById('mu-k-u').dataset.u,
              pin: document.getElementById('pin').selectedOptions[0].textContent,
              disc: document.getElementById('disc').selectedOptions[0].textContent,
              pressure: document.getElementById('pressure').value,
              temperature: document.getElementById('temperature').value};
    }""")


def assert_shows(tab, res) -> None:
    s = shown(tab)
    # the headline: value ± U (k = 2), rounded the GUM way, as query writes it
    assert s["text"] == res.mu_k.text()
    head = s["text"].split()[0]
    decimals = len(head.split(".")[1]) if "." in head else 0
    assert float(head) == pytest.approx(res.mu_k.value, abs=0.5 * 10.0 ** -decimals + 1e-12)
    assert same(float(s["value"]), res.mu_k.value)
    if res.mu_k.expanded is None:
        assert s["uncertainty"] == ""
    else:
        assert same(float(s["uncertainty"]), res.mu_k.expanded)
    assert s["clampedPressure"] == str(res.mu_k.clamped_pressure).lower()
    assert s["clampedTemperature"] == str(res.mu_k.clamped_temperature).lower()
    assert s["clamped"].startswith("yes" if res.clamped else "no")
    # what U holds, and the repeats' interval apart
    assert s["u"].startswith("interpolation u = ")
    ci = res.mu_k.uncertainty
    assert s["u"].endswith("repeats' 95 % CI half-width "
                           + ("unknown" if ci is None else f"{ci:.3f}"))
    if res.mu_k.u_combined is None:
        assert s["uValue"] == ""
    else:
        assert same(float(s["uValue"]), res.mu_k.u_combined)
    if res.mu_s is None:
        assert s["muS"].startswith("unknown")
    else:
        assert s["muS"] == res.mu_s.text()


def choose(tab, pin: str, disc: str, pressure: float, temperature: float | None) -> None:
    page = tab.page
    page.select_option("#pin", label=pin)
    page.select_option("#disc", label=disc)
    page.fill("#temperature", "" if temperature is None else repr(temperature))
    page.fill("#pressure", repr(pressure))


def test_the_shown_mu_k_is_query_s_through_the_controls(tab, published):
    _, page, groups = published
    tab.open(page_url(page))
    conditions = [
        ("Dragonskin 30", "steel", 35.37, 20.0),       # measured
        ("Dragonskin 30", "steel", 50.0, 15.0),        # between pressures and temperatures
        ("Dragonskin 30", "steel", 5.0, 20.0),         # below the pressures: held
        ("Dragonskin 30", "acrylic glass", 150.0, 30.0),  # beyond both: held
        ("Dragonskin 30", "cardboard", 70.0, 10.0),
        ("Dragonskin 30", "wood (smooth)", 20.0, 10.0),   # one temperature, asked another
        ("Ecoflex 00-50", "steel", 47.0, 10.0),
        ("Ecoflex 00-50", "wood (smooth)", 0.0, 20.0),
    ]
    for pin, disc, p, t in conditions:
        choose(tab, pin, disc, p, t)
        assert_shows(tab, query(groups, pin, disc, p, t))


def test_a_link_restores_the_selection_and_the_url_follows_the_controls(browser, published):
    _, page, groups = published
    first = Tab(browser)
    first.open(page_url(page, pin="dragonskin 30", disc="Lathed Aluminium Disk",
                        pressure="64.5", temperature="12.5"))
    s = shown(first)
    assert (s["pin"], s["disc"], s["pressure"], s["temperature"]) == (
        "Dragonskin 30", "lathed aluminium disk", "64.5", "12.5")
    assert_shows(first, query(groups, "Dragonskin 30", "lathed aluminium disk", 64.5, 12.5))
    # change the selection with the controls: the address follows
    choose(first, "Dragonskin 30", "cardboard", 99.0, 17.0)
    link = first.address()
    assert "disc=cardboard" in link and "pressure=99.0" in link and "temperature=17.0" in link
    first.check_clean()
    first.close()
    # the link in a fresh tab shows the same
    second = Tab(browser)
    second.open(link)
    s = shown(second)
    assert (s["pin"], s["disc"], s["pressure"], s["temperature"]) == (
        "Dragonskin 30", "cardboard", "99.0", "17.0")
    assert_shows(second, query(groups, "Dragonskin 30", "cardboard", 99.0, 17.0))
    second.check_clean()
    second.close()


def test_a_link_to_something_the_map_lacks_says_so(tab, published):
    _, page, _ = published
    tab.open(page_url(page, pin="Unobtainium", disc="steel", pressure="abc"))
    note = tab.page.text_content("#tpx-selection-note")
    assert "pin “Unobtainium” is not in this map" in note
    assert "pressure “abc” is not a number" in note
    # no other pair's μ stands in for it: none is shown, and the error says why
    assert shown(tab)["text"] == "–"
    assert "no μ is shown" in tab.page.text_content("#tpx-error")
    assert "Unobtainium" in tab.address()  # the address keeps what the link asked for


@pytest.mark.parametrize(("pin", "disc", "said"), [
    ("Ecoflex 00-50", "acrylic glass", "is not measured with Ecoflex 00-50"),  # both known
    ("Ecoflex 00-50", "granite", "“granite” is not in this map"),
])
def test_a_link_to_a_pair_the_map_lacks_shows_no_mu(tab, published, pin, disc, said):
    map_path, page, groups = published
    with pytest.raises(Exception, match="no groups"):  # as query refuses it
        query(groups, pin, disc, 20.0, 20.0)
    tab.open(page_url(page, pin=pin, disc=disc, pressure="20", temperature="20"))
    s = shown(tab)
    assert s["text"] == "–" and s["muS"] == "–"
    error = tab.page.text_content("#tpx-error")
    assert said in error and "choose a pin and a disc" in error
    assert tab.page.evaluate("window.tribopipeExplorer.result()") is None
    # choosing a pair shows its μ again
    tab.page.select_option("#disc", index=0)
    tab.page.dispatch_event("#disc", "change")
    assert shown(tab)["text"] != "–"


def test_temperature_needed_and_bad_pressure_are_said(tab, published):
    _, page, _ = published
    tab.open(page_url(page, pin="Dragonskin 30", disc="steel", pressure="20"))
    tab.page.fill("#temperature", "")
    assert tab.page.text_content("#tpx-error") == (
        "temperature needed: this pair is measured at 10, 20 °C")
    assert shown(tab)["text"] == "–"
    tab.page.fill("#temperature", "20")
    tab.page.fill("#pressure", "-3")
    assert tab.page.text_content("#tpx-error") == (
        "contact pressure must be a finite number >= 0 kPa, got -3")


def open_export(tab) -> None:
    """Unfold the copy-or-download box (folded until asked for)."""
    assert tab.page.evaluate("document.getElementById('tpx-export-box').open") is False
    tab.page.click("#tpx-export-box summary")
    assert tab.page.evaluate("document.getElementById('tpx-export-box').open") is True


def test_downloads_and_snippets_are_the_python_writers(tab, reduced):
    map_path, page, groups, _ = reduced
    tab.open(page_url(page, pin="Dragonskin 30", disc="steel", pressure="60", temperature="20"))
    open_export(tab)
    res = query(groups, "Dragonskin 30", "steel", 60.0, 20.0)
    for fmt, suffix in (("abaqus", ".inp"), ("ansys", ".mac")):
        tab.page.select_option("#tpx-export-format", fmt)
        with tab.page.expect_download() as info:
            tab.page.click("#tpx-download")
        download = info.value
        assert download.suggested_filename == f"tribopipe_dragonskin-30_steel_60kPa_20C{suffix}"
        text = Path(download.path()).read_text(encoding="utf-8")
        assert text == condition_snippet(res, fmt, source=str(map_path))
    tab.page.select_option("#tpx-export-format", "csv")
    with tab.page.expect_download() as info:
        tab.page.click("#tpx-download")
    import csv

    with open(info.value.path(), encoding="utf-8", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 1
    row = rows[0]
    assert (row["pin"], row["disc"]) == ("Dragonskin 30", "steel")
    assert float(row["pressure_kPa"]) == 60.0 and float(row["temperature_C"]) == 20.0
    assert same(float(row["mu_k"]), res.mu_k.value)
    assert same(float(row["mu_k_ci95_half_width"]), res.mu_k.uncertainty)
    assert same(float(row["mu_k_U_k2"]), res.mu_k.expanded)
    assert same(float(row["mu_s"]), res.mu_s.value)
    assert row["clamped_pressure"] == "False" and row["clamped_temperature"] == "False"
    assert row["map"] == str(map_path)


def test_copy_puts_the_text_on_the_clipboard(browser, reduced):
    _, page, _, _ = reduced
    t = Tab(browser, permissions=["clipboard-read", "clipboard-write"])
    t.open(page_url(page, pin="Dragonskin 30", disc="steel", pressure="30", temperature="20"))
    open_export(t)
    t.page.select_option("#tpx-export-format", "abaqus")
    t.page.click("#tpx-copy")
    t.wait_until("document.getElementById('tpx-export-status').textContent !== ''")
    assert t.page.text_content("#tpx-export-status") == "copied"
    copied = t.page.evaluate("navigator.clipboard.readText()")
    assert copied == t.page.input_value("#tpx-export-text")
    assert "*FRICTION" in copied
    t.check_clean()
    t.close()


def group_rows(tab) -> list[list[str]]:
    return tab.page.evaluate("""() => Array.from(
      document.querySelectorAll('#tpx-group-table tbody tr'),
      tr => Array.from(tr.cells, td => td.textContent))""")


def test_the_group_table_sorts_filters_and_selects(tab, published):
    _, page, groups = published
    tab.open(page_url(page))
    assert len(group_rows(tab)) == len(groups) == 76
    # every word must occur in the row's pin, disc, QC, pressure or temperature
    tab.page.fill("#tpx-group-filter", "STEEL dragon")
    rows = group_rows(tab)
    expected = groups[(groups["disc"] == "steel") & (groups["pin"] == "Dragonskin 30")]
    assert len(rows) == len(expected) == 9
    assert {(r[0], r[1]) for r in rows} == {("Dragonskin 30", "steel")}
    assert tab.page.text_content("#tpx-group-count") == "9 of 76 groups"
    header = tab.page.locator("#tpx-group-table th", has_text="μ_K ± U (k = 2)")
    header.click()
    means = [float(r[6].split()[0]) for r in group_rows(tab)]
    assert means == sorted(means) and means[0] < means[-1]
    header.click()
    assert [float(r[6].split()[0]) for r in group_rows(tab)] == sorted(means, reverse=True)
    # each mean with its U as the paper table writes it
    from tribopipe.export.tables import paper_table

    paper = paper_table(read_map(published[0]), pin=["Dragonskin 30"], disc=["steel"])
    assert sorted(r[6] for r in group_rows(tab)) == sorted(paper["μ_K ± U"])
    # a row selects its condition: a measured group, weight 1, its own mean
    row = tab.page.locator("#tpx-group-table tbody tr").first
    cells = row.locator("td").all_text_contents()
    row.click()
    s = shown(tab)
    assert (s["pin"], s["disc"]) == (cells[0], cells[1])
    res = query(groups, cells[0], cells[1], float(s["pressure"]), float(s["temperature"]))
    assert len(res.mu_k.used) == 1 and not res.clamped
    assert_shows(tab, res)
    assert tab.page.locator("#tpx-group-table tbody tr.tpx-used").count() == 1
    tab.page.select_option("#tpx-group-scope", "pair")
    assert {(r[0], r[1]) for r in group_rows(tab)} == {(cells[0], cells[1])}


def test_plots_show_the_pair_and_every_disc_of_the_pin(tab, published):
    _, page, groups = published
    tab.open(page_url(page, pin="Dragonskin 30", disc="steel", pressure="50",
                      temperature="20"))
    pair = tab.page.locator("#tpx-pair-plot svg")
    assert pair.count() == 1
    # the repeats, the group means and one fitted curve per temperature
    runs = groups[(groups["pin"] == "Dragonskin 30") & (groups["disc"] == "steel")]
    assert pair.locator("circle").count() == int(runs["mu_k_n"].sum()) + len(runs)
    assert pair.locator("path[fill='none'][stroke-width]").count() >= 2
    assert "Dragonskin 30 on steel" in pair.text_content()
    panels = tab.page.locator("#tpx-overview .tpx-panel")
    discs = sorted(d for p, d in pairs(groups) if p == "Dragonskin 30")
    assert panels.count() == len(discs) == 9
    assert sorted(panels.locator("svg > text").all_text_contents()) == discs
    panels.filter(has_text="cardboard").click()
    assert shown(tab)["disc"] == "cardboard"
    assert "disc=cardboard" in tab.address()
    tab.page.screenshot(path=str(page.parent / "explorer.png"), full_page=True)


def test_hostile_names_render_as_text(tab, tmp_path):
    csv = tmp_path / "hostile.csv"
    rows = ["pin,disc,contactForce,contactPressure,temperature,measurementNo,cof"]
    for force, pressure, mu in ((1.0, 11.79, 0.6), (3.0, 35.37, 0.4)):
        for repeat in (1, 2):
            rows.append(f'"{HOSTILE_PIN}","{HOSTILE_DISC}",{force},{pressure},20,{repeat},'
                        f"{mu + 0.01 * repeat}")
    csv.write_text("\n".join(rows) + "\n", encoding="utf-8")
    map_path = tmp_path / "friction_map.parquet"
    import_table(map_path, csv, vocabulary=lab_vocabulary(HOSTILE_PIN, HOSTILE_DISC))
    page = write_explorer(map_path, tmp_path / "explorer.html")
    tab.open(page_url(page, pin=HOSTILE_PIN, disc=HOSTILE_DISC, pressure="20"))
    s = shown(tab)
    assert (s["pin"], s["disc"]) == (HOSTILE_PIN, HOSTILE_DISC)
    counts = tab.page.evaluate("""() => ({scripts: document.scripts.length,
      code: document.querySelectorAll('script:not([type])').length,
      images: document.images.length, onerror: document.querySelectorAll('[onerror]').length})""")
    # the data, the pair's runs and the page's own script: nothing injected
    assert counts == {"scripts": 3, "code": 1, "images": 0, "onerror": 0}
    assert f"{HOSTILE_PIN} on {HOSTILE_DISC}" in tab.page.text_content("#tpx-pair-plot")
    assert tab.page.text_content("#tpx-group-table tbody td") == HOSTILE_PIN
    assert_shows(tab, query(groups_of(read_map(map_path), map_path), HOSTILE_PIN, HOSTILE_DISC,
                            20.0, None))
    # the CSV keeps the names as data: quoted where needed, no cell starts a formula
    open_export(tab)
    tab.page.select_option("#tpx-export-format", "csv")
    import csv
    import io

    text = tab.page.input_value("#tpx-export-text")
    (row,) = csv.DictReader(io.StringIO(text))
    assert (row["pin"], row["disc"]) == (HOSTILE_PIN, HOSTILE_DISC)


class _Quiet(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args) -> None:  # keep pytest's output clean
        pass


def test_the_page_works_from_a_static_web_host(browser, published):
    _, page, groups = published
    handler = functools.partial(_Quiet, directory=str(page.parent))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    origin = f"http://127.0.0.1:{server.server_address[1]}"
    try:
        t = Tab(browser)
        t.open(f"{origin}/{page.name}?pin=Dragonskin+30&disc=steel&pressure=50&temperature=15")
        assert_shows(t, query(groups, "Dragonskin 30", "steel", 50.0, 15.0))
        choose(t, "Dragonskin 30", "steel", 80.0, 20.0)
        assert t.address().startswith(f"{origin}/{page.name}?") and "pressure=80.0" in t.address()
        t.check_clean(origin=origin)
        t.close()
    finally:
        server.shutdown()
        server.server_close()


def test_the_report_embeds_the_explorer_for_its_campaign(tab, reduced):
    map_path, _, groups, processed = reduced
    report = make_report(map_path=map_path, processed_dir=processed)
    tab.open(page_url(report, pin="Dragonskin 30", disc="steel", pressure="45",
                      temperature="20"))
    assert_shows(tab, query(groups, "Dragonskin 30", "steel", 45.0, 20.0))
    assert tab.page.locator("#explorer #tpx-overview .tpx-panel").count() == 1
    choose(tab, "Ecoflex 00-50", "wood (smooth)", 10.0, 20.0)
    assert "pin=Ecoflex+00-50" in tab.address()
    assert_shows(tab, query(groups, "Ecoflex 00-50", "wood (smooth)", 10.0, 20.0))


def test_numbers_are_printed_by_the_one_rule(tab, reduced):
    """What the page computes and prints (a value without U, a weight, a snippet's
    coefficient) is rounded by :func:`tribopipe.rounding.decimal_text`, in the page."""
    from tribopipe.rounding import decimal_text

    _, page, _, _ = reduced
    tab.open(page_url(page))
    import random

    rng = random.Random(11)
    values = [0.0, -0.0, 0.5625, 0.0625, 2.5, 3.5, 0.125, 1e-5, 0.0001, 123456789.0, 1e16,
              1.5e16, 11.79, 106.1, 35.37, -3.0, 0.9995, 9.9999995, 1e21, 2.5e-30, 0.3]
    values += [rng.uniform(-2, 2) for _ in range(200)]
    values += [rng.uniform(0, 1) * 10 ** rng.randint(-8, 20) for _ in range(200)]
    got = tab.page.evaluate("""vs => { const f = window.tribopipeExplorer.format.decimal;
      return vs.map(v => [f(v, null, 3), f(v, 6), f(v, 3), f(v, 10), f(v, 17)]); }""", values)
    for v, row in zip(values, got, strict=True):
        assert tuple(row) == (
            decimal_text(v, places=3), decimal_text(v, digits=6), decimal_text(v, digits=3),
            decimal_text(v, digits=10), decimal_text(v, digits=17)), v


def test_page_equals_query_where_temperatures_are_unknown(tab, tmp_path):
    # pair A/b: two groups without a temperature beside one with (query leaves them out and
    # says so); pair C/d: no temperature at all (any asked temperature is ignored)
    csv = tmp_path / "no_temperature.csv"
    csv.write_text(
        "pin,disc,contactForce,contactPressure,temperature,measurementNo,cof\n"
        "A,b,1,11.79,,1,0.5\nA,b,1,11.79,,2,0.52\nA,b,3,35.37,,1,0.4\n"
        "A,b,3,35.37,20,1,0.41\nA,b,3,35.37,20,2,0.43\nA,b,5,58.95,20,1,0.35\n"
        "C,d,1,11.79,,1,0.9\nC,d,1,11.79,,2,0.8\nC,d,5,58.95,,1,0.6\n",
        encoding="utf-8",
    )
    map_path = tmp_path / "friction_map.parquet"
    import_table(map_path, csv, vocabulary=lab_vocabulary("A", "b", "C", "d"))
    groups = groups_of(read_map(map_path), map_path)
    page = write_explorer(map_path, tmp_path / "explorer.html")
    tab.open(page_url(page, pin="C", disc="d", pressure="30"))
    conditions = [(pin, disc, p, t) for pin, disc in (("A", "b"), ("C", "d"))
                  for p in (0.0, 11.79, 20.0, 35.37, 50.0, 58.95, 80.0)
                  for t in (None, 5.0, 20.0, 31.0)]
    assert_page_equals_query(tab, groups, conditions)
    assert "2 group(s) without a temperature were left out" in query(
        groups, "A", "b", 20.0, 20.0).notes
    assert shown(tab)["temperature"] == ""
    assert_shows(tab, query(groups, "C", "d", 30.0, None))
    assert "T unknown" in tab.page.text_content("#tpx-pair-plot")


def test_copied_snippets_equal_the_python_writer_for_any_name(tab, tmp_path):
    # quotes, the MAPDL command separator, a backslash, non-ASCII, an emoji, and a name
    # longer than a comment line (wrapped, its longest word cut)
    pin = 'Ecoflex "00-50" it\'s $5 \\ ' + "x" * 120
    disc = "Stahl – gebürstet 🙂 & <b>"
    csv = tmp_path / "names.csv"
    quoted = '"' + pin.replace('"', '""') + '"'
    csv.write_text(
        "pin,disc,contactForce,contactPressure,temperature,measurementNo,cof\n"
        + "".join(f"{quoted},{disc},{f},{p},20,{r},{mu + 0.01 * r}\n"
                  for f, p, mu in ((1.0, 11.79, 0.6), (3.0, 35.37, 0.4)) for r in (1, 2)),
        encoding="utf-8",
    )
    map_path = tmp_path / "friction_map.parquet"
    import_table(map_path, csv, vocabulary=lab_vocabulary(pin, disc))
    groups = groups_of(read_map(map_path), map_path)
    assert pairs(groups) == [(pin, disc)]
    page = write_explorer(map_path, tmp_path / "explorer.html")
    tab.open(page_url(page))
    conditions = [(pin, disc, p, t) for p in (5.0, 20.0, 35.37, 90.0) for t in (None, 20.0, 31.5)]
    assert_snippets_are_the_writer_s(tab, groups, conditions, str(map_path))
    text = tab.page.evaluate("window.tribopipeExplorer.exportText('ansys')")
    assert max(len(line) for line in text.splitlines()) <= 100
    assert "\\x24" in text and "\\U0001f642" in text


def test_the_reports_tables_download_as_csv_in_a_browser(tab, reduced, tmp_path):
    import pandas as pd

    from tribopipe.stats import group_statistics

    map_path, _, _, processed = reduced
    report = make_report(map_path=map_path, processed_dir=processed, output=tmp_path / "r.html")
    tab.open(page_url(report))
    with tab.page.expect_download() as info:
        tab.page.click("#group-csv")
    download = info.value
    assert download.suggested_filename == "groups.csv"
    groups = pd.read_csv(download.path())
    expected = group_statistics(read_map(map_path))
    assert list(groups.columns) == list(expected.columns)
    assert groups["mu_k_mean"].tolist() == pytest.approx(expected["mu_k_mean"].tolist(),
                                                         rel=1e-9)
    with tab.page.expect_download() as info:
        tab.page.click("#fit-csv")
    assert info.value.suggested_filename == "fits.csv"
    assert len(pd.read_csv(info.value.path())) == 2


def test_a_published_packages_explorer_opens_from_disk(tab, reduced, tmp_path):
    from tribopipe.export.citation import Publisher
    from tribopipe.export.publish import publish_map

    map_path, _, groups, _ = reduced
    package = publish_map(map_path, tmp_path / "pkg", Publisher("Lab <b>X</b>")).path
    tab.open(page_url(package / "explorer.html", pin="Dragonskin 30", disc="steel",
                      pressure="45", temperature="20"))
    assert_shows(tab, query(groups, "Dragonskin 30", "steel", 45.0, 20.0))


def test_a_measured_pressure_shows_rounded_and_counts_exact(tab, reduced):
    # 3 N on three pins of r = 3 mm is 35.36776... kPa: the input and the chips show it as
    # the tables print it (4 significant digits, 35.37), while μ_K and a link keep the
    # measured value, not the rounded text
    _, page, groups, _ = reduced
    tab.open(page_url(page, pin="Dragonskin 30", disc="steel"))
    pair = groups[(groups["pin"] == "Dragonskin 30") & (groups["disc"] == "steel")]
    p = float(sorted(pair["pressure_kPa"])[0])
    text = condition_text("pressure_kPa", p)
    assert text == "35.37" and float(text) != p  # the case: the text is not the value
    s = shown(tab)
    assert (s["pressure"], s["temperature"]) == (text, "20")
    res = query(groups, "Dragonskin 30", "steel", p, 20.0)
    assert len(res.mu_k.used) == 1 and res.mu_k.used[0].weight == 1.0
    assert_shows(tab, res)
    # the address carries the text, and a link with it means the measured value
    assert f"pressure={text}&" in tab.address() and repr(p) not in tab.address()
    # the chips say what the tables say, and fill in the exact value the same way
    chips = tab.page.locator("#tpx-measured button").all_text_contents()
    assert chips == ["20 °C"] + [condition_text("pressure_kPa", v) + " kPa"
                                 for v in sorted(set(pair["pressure_kPa"]))]
    tab.page.fill("#pressure", "50")
    tab.page.locator("#tpx-measured button", has_text=f"{text} kPa").click()
    assert shown(tab)["pressure"] == text and f"pressure={text}&" in tab.address()
    assert_shows(tab, res)
    link = tab.address()
    tab.open(link)
    assert shown(tab)["pressure"] == text
    assert_shows(tab, res)
    # so does a link with the full digits; a measured value typed exactly stays as typed
    tab.open(page_url(page, pin="Dragonskin 30", disc="steel", pressure=repr(p),
                      temperature="20.0"))
    assert shown(tab)["pressure"] == text
    assert_shows(tab, res)
    assert "temperature=20.0" in tab.address()
    # typing makes the typed text the value: the rounded number is then what is asked
    tab.page.fill("#pressure", text)
    assert_shows(tab, query(groups, "Dragonskin 30", "steel", float(text), 20.0))
    assert f"pressure={text}&" in tab.address() or tab.address().endswith(f"pressure={text}")


def test_each_repeat_says_which_file_and_test_it_came_from(tab, reduced):
    map_path, page, _, _ = reduced
    runs = read_map(map_path)
    tab.open(page_url(page, pin="Dragonskin 30", disc="steel", pressure="50",
                      temperature="20"))
    cells = tab.page.evaluate("""() => Array.from(
      document.querySelectorAll('#tpx-used-points tbody tr td:last-child'),
      td => Array.from(td.querySelectorAll('.tpx-repeat'), d => d.textContent))""")
    lines = [line for cell in cells for line in cell]
    used = runs[(runs["pin"] == "Dragonskin 30") & (runs["disc"] == "steel")
                & runs["normal_force_N"].isin([3.0, 9.0])]
    assert len(lines) == len(used) == 5
    expected = {f"{r.mu_k:.3f} — {r.source_file} · {r.test} / {r.result}"
                for r in used.itertuples()}
    assert set(lines) == expected


# --------------------------------------------------------------------------- layout

#: the page's cards: every element inside one must stay inside it
CARDS = ".tpx-select, .tpx-result, .tpx-export, .tpx-figure, .tpx-panel, .tpx-groups"
OVERFLOWS = """cards => {
  const out = [];
  for (const card of document.querySelectorAll(cards)) {
    const box = card.getBoundingClientRect();
    for (const e of card.querySelectorAll('*')) {
      if (e.closest('[hidden], datalist, option, title, script')) continue;
      // folded until asked for, or inside a box that scrolls (checked apart)
      if (e.closest('details:not([open]) > :not(summary), .tpx-scroll')) continue;
      const r = e.getBoundingClientRect();
      if (r.width === 0 && r.height === 0) continue;
      if (r.left < box.left - 1 || r.right > box.right + 1 || r.top < box.top - 1
          || r.bottom > box.bottom + 1) {
        const name = e.className.baseVal ?? e.className;
        out.push(`${card.className} > ${e.tagName.toLowerCase()}.${name}`
                 + ` (${Math.round(r.left)}–${Math.round(r.right)} in ${Math.round(box.left)}–`
                 + `${Math.round(box.right)})`);
      }
    }
  }
  return out;
}"""


#: what a reader sees: label sizes on screen, where the plot is, what is folded, words
#: broken across lines (each word's text range in more than one line box)
LAYOUT = r"""() => {
  const texts = Array.from(document.querySelectorAll('.tpx svg text'));
  const size = t => {
    const s = t.ownerSVGElement;
    const scale = s.getBoundingClientRect().width / s.viewBox.baseVal.width;
    return parseFloat(getComputedStyle(t).fontSize) * scale;
  };
  const plot = document.querySelector('#tpx-pair-plot svg').getBoundingClientRect();
  // the fold: the window's height below the page's top, or below the explorer's own top
  // where a report embeds it (its link scrolls there)
  const top = document.body.classList.contains('tpx-page') ? 0 :
    document.getElementById('tpx').getBoundingClientRect().top;
  const broken = [];
  const named = document.querySelectorAll(
    '.tpx td.tpx-t, .tpx th, .tpx select option:checked, .tpx svg text.tpx-title, .tpx .tpx-chip');
  for (const e of named) {
    const walker = document.createTreeWalker(e, NodeFilter.SHOW_TEXT);
    for (let n = walker.nextNode(); n; n = walker.nextNode()) {
      const re = /\S+/g;
      let m;
      while ((m = re.exec(n.data))) {
        const r = document.createRange();
        r.setStart(n, m.index);
        r.setEnd(n, m.index + m[0].length);
        const tops = new Set(Array.from(r.getClientRects(), q => Math.round(q.top)));
        if (tops.size > 1) broken.push(m[0]);
      }
    }
  }
  const scroll = document.querySelector('.tpx .tpx-scroll');
  const box = document.getElementById('tpx-export-box');
  return {
    labels: texts.length,
    smallest_label_px: Math.min(...texts.map(size)),
    plot_top: plot.top - top,
    plot_middle: plot.top - top + plot.height / 2,
    export_open: box.open,
    textarea_shown: document.getElementById('tpx-export-text').checkVisibility(),
    broken_words: broken,
    table_overflow_px: scroll.scrollWidth - scroll.clientWidth,
    selectors_shown: Array.from(document.querySelectorAll('.tpx-select select'))
      .filter(s => s.checkVisibility()).map(s => s.id),
  };
}"""


@pytest.mark.parametrize("width", [800, 1024, 1400])
def test_no_element_overflows_its_card(browser, reduced, published, width, tmp_path):
    """At a narrow, a middling and a wide window every card holds what it shows, on its
    own page and inside the report (a screenshot of each is kept in the test's folder)."""
    report = make_report(tmp_path / "report.html", map_path=reduced[0],
                         processed_dir=reduced[3])
    for name, page in (("reduced", reduced[1]), ("published", published[1]),
                       ("report", report)):
        tab = Tab(browser, viewport={"width": width, "height": 900})
        # a condition between groups: every repeat of four groups is listed
        tab.open(page_url(page, pin="Dragonskin 30", disc="steel", pressure="50",
                          temperature="15"))
        tab.page.screenshot(path=str(tmp_path / f"explorer-{name}-{width}.png"), full_page=True)
        assert tab.page.evaluate(OVERFLOWS, CARDS) == [], f"{name} at {width} px"
        layout = tab.page.evaluate(LAYOUT)
        where = f"{name} at {width} px: {layout}"
        # every label of every plot is at least 11 px on the screen
        assert layout["labels"] > 20 and layout["smallest_label_px"] >= 11, where
        # the plot starts above the fold and at least half of it shows there
        assert layout["plot_top"] < 900 and layout["plot_middle"] < 900, where
        # the copy-or-download box is folded until asked for
        assert layout["export_open"] is False and layout["textarea_shown"] is False, where
        # no word of a name or a heading is broken across lines
        assert layout["broken_words"] == [], where
        # the group table fits its card: nothing to scroll for these maps
        assert layout["table_overflow_px"] <= 1, where
        # one speed, one lab: no empty selector
        assert layout["selectors_shown"] == ["pin", "disc"], where
        if name == "report":  # the report's own tables fit the window too
            cut = tab.page.evaluate("""() => Array.from(document.querySelectorAll(
              'table'), t => [t.id, t.getBoundingClientRect().right -
              document.documentElement.clientWidth]).filter(x => x[1] > 1)""")
            assert cut == [], f"report at {width} px: {cut}"
        # each repeat stays on one or two lines
        heights = tab.page.evaluate("""() => Array.from(
          document.querySelectorAll('.tpx-repeat'), d => d.getBoundingClientRect().height /
          parseFloat(getComputedStyle(d).lineHeight || '16'))""")
        assert heights and max(heights) <= 2.5, f"{name} at {width} px: {max(heights)} lines"
        tab.check_clean()
        tab.close()


def test_a_pair_of_several_speeds_gets_a_speed_selector_and_link(browser, tmp_path):
    """A map whose acrylic-glass pairs hold three nominal speeds: their selector shows the
    speeds, the shown μ_K is query's at the chosen one, the link keeps it."""
    from test_speed_condition import _multi_speed_runs
    from tribopipe.frictionmap import write_map

    map_path = tmp_path / "speeds.parquet"
    write_map(map_path, _multi_speed_runs())
    page = write_explorer(map_path, tmp_path / "explorer.html")
    groups = groups_of(read_map(map_path), map_path)
    pin, disc, p, t = "Dragonskin 30", "acrylic glass", 35.37, 20.0
    first = Tab(browser)
    first.open(page_url(page, pin=pin, disc=disc, pressure="35.37", temperature="20.0",
                        speed="0.021"))
    speeds = first.page.evaluate("""() => ({hidden: document.getElementById(
        'tpx-speed-label').hidden, options: [...document.getElementById('speed').options]
        .map(o => o.textContent), chosen: document.getElementById('speed').selectedOptions[0]
        .textContent})""")
    assert speeds == {"hidden": False, "options": ["0.007", "0.021", "0.07"], "chosen": "0.021"}
    assert_shows(first, query(groups, pin, disc, p, t, 0.021))
    first.page.select_option("#speed", label="0.07")
    assert_shows(first, query(groups, pin, disc, p, t, 0.07))
    assert "speed=0.07" in first.address()
    heads = first.page.evaluate(
        "[...document.getElementById('tpx-group-table').tHead.rows[0].cells]"
        ".map(c => c.textContent)")
    assert heads[5] == "v [mm/s]"
    # each speed drawn, listed and labelled apart: the plot holds this speed's repeats and
    # group means only, its title names the speed, the groups used list it
    runs = read_map(map_path)
    at = runs[(runs["pin"] == pin) & (runs["disc"] == disc)
              & (runs["nominal_speed_mm_s"].round(4) == 0.07)]
    drawn = first.page.evaluate("""() => ({
      runs: document.querySelectorAll('#tpx-pair-plot circle.tpx-run').length,
      means: document.querySelectorAll('#tpx-pair-plot circle.tpx-mean').length,
      title: document.querySelector('#tpx-pair-plot text.tpx-title').textContent,
      used: [...document.querySelectorAll('#tpx-used-points tbody tr')]
        .map(tr => tr.cells[2].textContent)})""")
    assert drawn["runs"] == len(at) > 0
    assert drawn["means"] == at.groupby(["normal_force_N", "temperature_C"]).ngroups
    assert drawn["title"] == f"{pin} on {disc}, 0.07 mm/s"
    assert drawn["used"] and set(drawn["used"]) == {"0.07"}
    # a pair of one speed: no selector
    first.page.select_option("#disc", label="steel")
    assert first.page.evaluate("document.getElementById('tpx-speed-label').hidden")
    assert not first.page.is_visible("#speed")
    first.check_clean()
    first.close()


def test_a_large_maps_runs_load_from_beside_the_page(tab, reduced, tmp_path):
    """Above the limit the page carries groups and fits, and each pair's runs come from
    a file beside it when the pair is shown; a missing file is said, the rest works."""
    from tribopipe.export.explorer import runs_folder

    map_path, _, groups, _ = reduced
    page = write_explorer(map_path, tmp_path / "big.html", runs_inline_limit=0)
    folder = runs_folder(page)
    html = page.read_text(encoding="utf-8")
    assert "tpx-runs-0" not in html and '"runs_beside":"big_runs"' in html
    assert sorted(p.name for p in folder.iterdir()) == [
        f"pair-{i}.js" for i in range(len(list(folder.iterdir())))]
    tab.open(page_url(page, pin="Dragonskin 30", disc="steel", pressure="50",
                      temperature="20"))
    tab.wait_until("document.querySelectorAll('.tpx-repeat').length > 0")
    assert_shows(tab, query(groups, "Dragonskin 30", "steel", 50.0, 20.0))
    runs = read_map(map_path)
    pair = runs[(runs["pin"] == "Dragonskin 30") & (runs["disc"] == "steel")]
    assert tab.page.locator("#tpx-pair-plot circle.tpx-run").count() == len(pair)
    assert any(u.startswith(folder.resolve().as_uri()) for u in tab.requests)
    # a pair whose file is gone: μ still shows, the note says where the runs should be
    other = next(i for i, p in enumerate(tab.page.evaluate(
        "window.tribopipeExplorer.data.pairs.map(p => p.pin + '|' + p.disc)"))
        if p == "Ecoflex 00-50|wood (smooth)")
    (folder / f"pair-{other}.js").unlink()
    tab.problems.clear()
    tab.page.select_option("#pin", label="Ecoflex 00-50")
    tab.page.select_option("#disc", label="wood (smooth)")
    tab.wait_until("!document.getElementById('tpx-selection-note').hidden")
    assert f"big_runs/pair-{other}.js" in tab.page.text_content("#tpx-selection-note")
    assert tab.page.text_content("#mu-k") != "–"
    # the browser reports the missing file itself; nothing else went wrong
    assert all("ERR_FILE_NOT_FOUND" in p or "Failed to load" in p for p in tab.problems)
    tab.problems.clear()


def test_labs_filter_the_groups_and_colour_the_repeats(tab, reduced, tmp_path):
    from tribopipe.frictionmap import write_map

    map_path, _, _, _ = reduced
    runs = read_map(map_path)
    runs["lab"] = ["Lab A" if i % 2 else "Lab B" for i in range(len(runs))]
    two = tmp_path / "two_labs.parquet"
    write_map(two, runs)
    page = write_explorer(two, tmp_path / "labs.html")
    tab.open(page_url(page, pin="Dragonskin 30", disc="steel", pressure="50",
                      temperature="20"))
    assert tab.page.is_visible("#lab") and tab.page.is_visible("#colour-by")
    options = tab.page.locator("#lab option").all_text_contents()
    assert options == ["every lab", "Lab A", "Lab B"]
    every = tab.page.locator("#tpx-pair-plot circle.tpx-run").count()
    total = len(group_rows(tab))
    tab.page.select_option("#lab", label="Lab A")
    assert "lab=Lab+A" in tab.address()
    labs = tab.page.evaluate("""() => [...document.querySelectorAll(
      '#tpx-pair-plot circle.tpx-run')].map(c => c.dataset.lab)""")
    assert labs and set(labs) == {"0"} and len(labs) < every
    rows = group_rows(tab)
    assert 0 < len(rows) <= total and all("Lab A" in r[-1] for r in rows)
    # colour by lab: each lab its colour, named in the legend
    tab.page.select_option("#lab", label="every lab")
    tab.page.select_option("#colour-by", "lab")
    fills = tab.page.evaluate("""() => {
      const out = {};
      for (const c of document.querySelectorAll('#tpx-pair-plot circle.tpx-run'))
        (out[c.dataset.lab] = out[c.dataset.lab] || new Set()).add(c.getAttribute('fill'));
      return Object.fromEntries(Object.entries(out).map(([k, v]) => [k, [...v]]));
    }""")
    assert len(fills) == 2 and all(len(v) == 1 for v in fills.values())
    assert fills["0"] != fills["1"]
    legend = tab.page.locator("#tpx-pair-plot text.tpx-legend").all_text_contents()
    assert "repeats of Lab A" in legend and "repeats of Lab B" in legend


def test_the_group_table_filters_by_test_method(tab, tmp_path):
    """A map of two test methods: a method column and a method filter; a map of one
    method shows neither (groups never pool two methods)."""
    from tribopipe.frictionmap import write_map

    map_path = tmp_path / "friction_map.parquet"
    import_table(map_path, published_csv_path())
    single = write_explorer(map_path, tmp_path / "one.html")
    runs = read_map(map_path)
    sled = (runs["pin"] == "Dragonskin 30") & (runs["disc"] == "steel")
    runs.loc[sled, "test_method"] = "sled D1894"
    write_map(map_path, runs)
    both = write_explorer(map_path, tmp_path / "two.html")

    tab.open(page_url(single))
    assert tab.page.is_hidden("#tpx-group-method-label")
    heads = tab.page.locator("#tpx-group-table th").all_text_contents()
    assert "method" not in heads
    tab.open(page_url(both))
    assert tab.page.is_visible("#tpx-group-method-label")
    all_rows = group_rows(tab)
    assert {r[2] for r in all_rows} == {"rheometer pin-on-disc", "sled D1894"}
    tab.page.select_option("#tpx-group-method", "sled D1894")
    sled_rows = group_rows(tab)
    assert sled_rows and {(r[0], r[1], r[2]) for r in sled_rows} == {
        ("Dragonskin 30", "steel", "sled D1894")}
    tab.page.select_option("#tpx-group-method", "rheometer pin-on-disc")
    rest = group_rows(tab)
    assert len(rest) + len(sled_rows) == len(all_rows)
    assert ("Dragonskin 30", "steel") not in {(r[0], r[1]) for r in rest}


def test_hostile_names_match_query_csv_and_snippets_as_python_does(tab, tmp_path):
    """Names and a map path a spreadsheet, a shell or a browser would read as code, and
    names whose casefold is not their lower case: a link spelt otherwise finds the pair
    by :func:`tribopipe.query.name_key` (stripped of Python's white space, casefolded),
    the page's query and snippets equal Python's, the CSV cells are
    :func:`tribopipe.escape.csv_cell`'s and the table filter folds names the same way."""
    import csv
    import io

    from tribopipe.escape import csv_cell
    from tribopipe.query import name_key

    pin = '=1+1 "Straße" it\'s <script>alert(1)</script> 🙂'
    disc = "@SUM(A1) ﬁne STEEL; -2+3"
    rows = io.StringIO()
    writer = csv.writer(rows, lineterminator="\n")
    writer.writerow(["pin", "disc", "contactForce", "contactPressure", "temperature",
                     "measurementNo", "cof"])
    for force, pressure, mu in ((1.0, 11.79, 0.6), (3.0, 35.37, 0.4)):
        for t in (20, 40):
            for repeat in (1, 2):
                writer.writerow([pin, disc, force, pressure, t, repeat,
                                 mu + 0.01 * repeat + 0.001 * t])
    table = tmp_path / "names.csv"
    table.write_text(rows.getvalue(), encoding="utf-8")
    map_path = tmp_path / "map \u202egpj.=1+1 \u200f.parquet"
    import_table(map_path, table, vocabulary=lab_vocabulary(pin, disc))
    groups = groups_of(read_map(map_path), map_path)
    page = write_explorer(map_path, tmp_path / "explorer.html")
    # spelt otherwise: upper case (ß → SS, ﬁ → FI), edged with white space JavaScript's
    # trim() would keep (\x1c) or that only Python strips
    link_pin, link_disc = "\x1c " + pin.upper() + "\u3000", "\x85" + disc.upper()
    assert (name_key(link_pin), name_key(link_disc)) == (name_key(pin), name_key(disc))
    # lower case is not the rule: the names' ß and ﬁ stay as they are in lower case
    assert pin.lower() != name_key(pin) and disc.lower() != name_key(disc)
    tab.open(page_url(page, pin=link_pin, disc=link_disc, pressure="20", temperature="30"))
    s = shown(tab)
    assert (s["pin"], s["disc"]) == (pin, disc)
    assert tab.page.text_content("#tpx-selection-note") == ""
    assert_shows(tab, query(groups, link_pin, link_disc, 20.0, 30.0))
    conditions = [(link_pin, link_disc, p, t) for p in (5.0, 20.0, 35.37) for t in (None, 30.0)]
    conditions = [c for c in conditions if c[3] is not None]
    assert_snippets_are_the_writer_s(tab, groups, conditions, str(map_path))
    # the CSV: the names and the map's path as csv_cell writes them, quoted by csv
    open_export(tab)
    tab.page.select_option("#tpx-export-format", "csv")
    (row,) = csv.DictReader(io.StringIO(tab.page.input_value("#tpx-export-text")))
    assert (row["pin"], row["disc"], row["map"]) == (
        csv_cell(pin), csv_cell(disc), csv_cell(str(map_path)))
    assert row["pin"].startswith("'=") and row["disc"].startswith("'@")
    assert not any(v.startswith(("=", "+", "-", "@")) for v in row.values())
    # the group table's filter folds names by the same rule
    tab.page.fill("#tpx-group-filter", "STRASSE FINE")
    assert tab.page.text_content("#tpx-group-count") == f"{len(groups)} of {len(groups)} groups"
    tab.page.fill("#tpx-group-filter", "strasse fine x")
    assert tab.page.text_content("#tpx-group-count") == f"0 of {len(groups)} groups"


def test_a_map_of_many_groups_is_a_small_index_whose_pin_pages_load_runs_on_demand(
        tab, reduced, tmp_path):
    """A map of more condition groups than one page carries (2,400 here) gives an index
    page far under 5 MB listing its pins; a pin's link opens that pin's explorer, which
    shows μ as ``query`` gives it on the whole map and loads the shown pair's runs from
    beside its page when it is shown."""
    import uuid

    from tribopipe import frictionmap as fm
    from tribopipe.export.explorer import GROUPS_PAGE_LIMIT, pages_folder

    map_path, _, _, _ = reduced
    template = fm.schema.frame_records(fm.read_map(map_path))[0]
    records = []
    for i in range(2 * 2_400):  # 40 pins x 2 discs x 5 forces x 6 temperatures, 2 repeats
        r = dict(template)
        g = i // 2
        r["measurement_id"] = uuid.UUID(int=i + 1).hex[-16:]
        r["file_hash"] = uuid.UUID(int=(i + 1) << 64).hex * 2
        r["source_file"] = f"many/run_{i:05d}.csv"
        r["pin"], r["disc"] = f"Lot {g // 60:02d}", ("steel", "acrylic")[(g // 30) % 2]
        r["normal_force_N"] = (1.0, 3.0, 5.0, 7.0, 9.0)[(g // 6) % 5]
        r["pressure_kPa"] = 11.789 * r["normal_force_N"]
        r["temperature_C"] = 10.0 + 5.0 * (g % 6)
        r["repeat"] = i % 2 + 1
        r["mu_k"] = 0.3 + 0.5 / r["normal_force_N"] ** 0.5 + 0.01 * (i % 2)
        records.append(r)
    many = tmp_path / "many.parquet"
    fm.update_map(many, records)
    groups = groups_of(read_map(many), many)
    assert len(groups) == 2_400 > GROUPS_PAGE_LIMIT
    index = write_explorer(many, tmp_path / "many.html")
    assert index.stat().st_size < 5_000_000 / 20
    pages = sorted(pages_folder(index).glob("*.html"))
    assert len(pages) == 2 and all(p.stat().st_size < 5_000_000 for p in pages)
    tab.page.goto(index.resolve().as_uri())  # a plain page: no explorer script of its own
    assert tab.page.locator("#tpx-pins tbody tr").count() == 40
    tab.page.click("#tpx-pins a:text-is('Lot 33')")
    tab.wait_until("window.tribopipeExplorer !== undefined")
    tab.wait_until("document.querySelectorAll('.tpx-repeat').length > 0")
    assert tab.page.evaluate("new URLSearchParams(location.search).get('pin')") == "Lot 33"
    assert shown(tab)["pin"] == "Lot 33"
    # the pin's page answers as query does on the whole map (its curvature included)
    lot = groups[groups["pin"] == "Lot 33"]
    assert_page_equals_query(tab, groups, [c for c in grid(lot)][::7])
    assert tab.page.locator("#tpx-pair-plot circle.tpx-run").count() == 2 * 30
    assert any("/part-2_runs/pair-" in u for u in tab.requests)


#: names that try to leave a lazily loaded file of runs (a script beside the page) or
#: the markup they are shown in
LAZY_PIN = '");alert(3);//</script><script>alert(4)</script>'
LAZY_DISC = "*/alert(5)/* <img src=x onerror=alert(6)> \\u2028"
LAZY_FILE = "</script><svg onload=alert(7)>.csv"
LAZY_LAB = "<b onmouseover=alert(8)>lab</b>"


def test_runs_loaded_beside_the_page_are_python_s_and_hostile_names_stay_text(tab, reduced,
                                                                              tmp_path):
    """A map whose runs lie beside the page (one script file per pair, loaded when the
    pair is shown, from file://): the runs the page loads are, field by field, those
    Python computed for the page (``explorer_data``), each repeat and each run's tip in
    the plot says what the map holds, μ is ``query``'s, and names that try to leave the
    file of runs or the markup (pin, disc, lab and file names) stay text: nothing is
    injected, no dialog opens."""
    import uuid

    from tribopipe import frictionmap as fm
    from tribopipe.export.explorer import PAGE_TEXTS, explorer_data, runs_folder

    map_path, _, _, _ = reduced
    template = fm.schema.frame_records(fm.read_map(map_path))[0]
    records = []
    for i in range(12):  # the hostile pair: 3 forces x 2 temperatures x 2 repeats; and a plain one
        r = dict(template)
        r["measurement_id"] = uuid.UUID(int=i + 1).hex[-16:]
        r["file_hash"] = uuid.UUID(int=(i + 1) << 64).hex * 2
        hostile = i < 8
        r["source_file"] = f"{i}{LAZY_FILE}" if hostile else f"plain_{i}.csv"
        r["pin"], r["disc"] = (LAZY_PIN, LAZY_DISC) if hostile else ("Plain", "steel")
        r["lab"] = LAZY_LAB if hostile else "plain lab"
        r["normal_force_N"] = (1.0, 3.0, 9.0)[i // 2 % 3] if hostile else 3.0
        r["pressure_kPa"] = 11.789 * r["normal_force_N"]
        r["temperature_C"] = (20.0, 30.0)[i // 6 % 2] if hostile else 20.0
        r["repeat"] = i % 2 + 1
        r["mu_k"] = 0.3 + 0.5 / r["normal_force_N"] ** 0.5 + 0.013 * i
        records.append(r)
    lazy = tmp_path / "lazy.parquet"
    fm.update_map(lazy, records)
    page = write_explorer(lazy, tmp_path / "lazy.html", runs_inline_limit=0)
    folder = runs_folder(page)
    html = page.read_text(encoding="utf-8")
    assert 'id="tpx-runs-' not in html and "alert(7)" not in html  # no run in the page
    runs = read_map(lazy)
    data = explorer_data(runs)
    index = next(i for i, p in enumerate(data["pairs"]) if p["pin"] == LAZY_PIN)
    assert (folder / f"pair-{index}.js").exists()

    tab.open(page_url(page, pin=LAZY_PIN, disc=LAZY_DISC, pressure="20", temperature="25"))
    tab.wait_until("document.querySelectorAll('.tpx-repeat').length > 0")
    assert any(u.startswith(folder.resolve().as_uri()) for u in tab.requests)
    s = shown(tab)
    assert (s["pin"], s["disc"]) == (LAZY_PIN, LAZY_DISC)
    assert_shows(tab, query(groups_of(runs, lazy), LAZY_PIN, LAZY_DISC, 20.0, 25.0))
    # the loaded runs are Python's, every field
    assert tab.page.evaluate(f"window.tribopipeExplorer.runs({index})") == data["runs"][index]
    # each run's tip in the plot: its repeat, lab and line, as the map holds them
    ours = runs[runs["pin"] == LAZY_PIN]
    tips = tab.page.evaluate("""() => Array.from(
      document.querySelectorAll('#tpx-pair-plot circle.tpx-run title'), t => t.textContent)""")
    assert sorted(tips) == sorted(PAGE_TEXTS["run_tip"].format(
        repeat=r.repeat, lab=LAZY_LAB,
        line=f"{r.mu_k:.3f} — {r.source_file} · {r.test} / {r.result}")
        for r in ours.itertuples())
    # the repeats behind the used points: their lines as the map holds them
    lines = tab.page.evaluate("""() => Array.from(
      document.querySelectorAll('#tpx-used-points .tpx-repeat'), d => d.textContent)""")
    assert lines and set(lines) <= {f"{r.mu_k:.3f} — {r.source_file} · {r.test} / {r.result}"
                                     for r in ours.itertuples()}
    counts = tab.page.evaluate("""() => ({
      code: Array.from(document.querySelectorAll('script:not([type])'),
                       s => s.src ? 'file:' + s.src.split('/').pop() : 'inline'),
      images: document.images.length, svgs: document.querySelectorAll('svg[onload]').length,
      handlers: document.querySelectorAll('[onerror], [onload], [onmouseover]').length,
      bold: document.querySelectorAll('b').length})""")
    # the page's own script and the one file of the pair's runs: nothing injected
    assert sorted(counts.pop("code")) == [f"file:pair-{index}.js", "inline"]
    assert counts == {"images": 0, "svgs": 0, "handlers": 0, "bold": 0}
    assert LAZY_LAB in tab.page.text_content("#lab")
