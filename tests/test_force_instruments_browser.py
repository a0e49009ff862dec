"""The explorer's method filter in a real headless browser (the system's ``chromium``
under Playwright, as ``tests/test_explorer_browser.py`` drives it): a map of two test
methods shows a method column and filters by it; a map of one shows neither. Where no
browser exists the tests skip and say why (``TRIBOPIPE_REQUIRE_BROWSER=1`` fails)."""

from __future__ import annotations

import os
import shutil
import time
from pathlib import Path

import pytest

from tribopipe.export.explorer import write_explorer
from tribopipe.frictionmap import import_table, read_map, write_map
from tribopipe.frictionmap.published import published_csv_path

CHROMIUM_ARGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
    "--disable-component-update", "--disable-sync", "--no-first-run",
]


def _unavailable(reason: str) -> None:
    if os.environ.get("TRIBOPIPE_REQUIRE_BROWSER") == "1":
        pytest.fail(f"TRIBOPIPE_REQUIRE_BROWSER=1 but {reason}")
    pytest.skip(reason)


@pytest.fixture(scope="module")
def page():
    """A page of a headless Chromium; console errors and page errors collected."""
    executable = os.environ.get("TRIBOPIPE_CHROMIUM") or shutil.which("chromium")
    if not executable:
        _unavailable("no chromium on PATH (Debian: apt-get install chromium)")
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        _unavailable("playwright is not installed (pip install -e '.[test]')")
    manager = sync_playwright().start()
    try:
        browser = manager.chromium.launch(executable_path=executable, args=CHROMIUM_ARGS)
    except Exception as exc:  # the browser exists but cannot start here
        manager.stop()
        _unavailable(f"chromium at {executable} did not start: {str(exc).splitlines()[0]}")
    tab = browser.new_page()
    problems: list[str] = []
    tab.on("console", lambda m: problems.append(m.text) if m.type == "error" else None)
    tab.on("pageerror", lambda exc: problems.append(str(exc)))
    yield tab, problems
    browser.close()
    manager.stop()


def _open(tab, path: Path) -> None:
    tab.goto(path.resolve().as_uri())
    deadline = time.monotonic() + 30
    while not tab.evaluate("window.tribopipeExplorer !== undefined"):
        assert time.monotonic() < deadline, "the page never started"
        time.sleep(0.02)


def _rows(tab) -> list[list[str]]:
    return tab.evaluate("""() => Array.from(
      document.querySelectorAll('#tpx-group-table tbody tr'),
      tr => Array.from(tr.cells, td => td.textContent))""")


def test_the_group_table_filters_by_method(page, tmp_path: Path) -> None:
    tab, problems = page
    map_path = tmp_path / "friction_map.parquet"
    import_table(map_path, published_csv_path())
    single = write_explorer(map_path, tmp_path / "one.html")
    runs = read_map(map_path)
    sled = (runs["pin"] == "Dragonskin 30") & (runs["disc"] == "steel")
    runs.loc[sled, "test_method"] = "sled D1894"
    write_map(map_path, runs)
    both = write_explorer(map_path, tmp_path / "two.html")

    _open(tab, single)
    assert tab.is_hidden("#tpx-group-method-label")
    heads = tab.evaluate("() => Array.from(document.querySelectorAll("
                         "'#tpx-group-table th'), th => th.textContent)")
    assert "method" not in heads

    _open(tab, both)
    assert tab.is_visible("#tpx-group-method-label")
    all_rows = _rows(tab)
    assert {r[2] for r in all_rows} == {"rheometer pin-on-disc", "sled D1894"}
    tab.select_option("#tpx-group-method", "sled D1894")
    sled_rows = _rows(tab)
    assert sled_rows and {(r[0], r[1], r[2]) for r in sled_rows} == {
        ("Dragonskin 30", "steel", "sled D1894")}
    tab.select_option("#tpx-group-method", "rheometer pin-on-disc")
    rest = _rows(tab)
    assert len(rest) + len(sled_rows) == len(all_rows)
    assert ("Dragonskin 30", "steel") not in {(r[0], r[1]) for r in rest}
    assert problems == []
