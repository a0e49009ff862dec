"""The review page in a real headless browser (the system's ``chromium`` under
Playwright), at 800, 1024 and 1400 px: drag a μ_K window on one run, type a window and a
static peak on another, exclude a third; save the decisions file, apply it with the real
``tribopipe batch`` (a subprocess), and check the map against μ recomputed independently
from each run's trace Parquet over the chosen window. The page's estimator is held equal
to :mod:`tribopipe.reduction.manual` over a grid of windows. Where no browser exists the
tests skip and say why (``TRIBOPIPE_REQUIRE_BROWSER=1`` fails instead).
"""

from __future__ import annotations

import math
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
from click.testing import CliRunner

from test_explorer_browser import Tab
from test_review import FILES, independent_mu_k, make_campaign, samples_of, the_map
from tribopipe.campaign import load_campaign, run_campaign
from tribopipe.cli import main
from tribopipe.errors import ReductionError
from tribopipe.reduction.manual import kinetic_over, static_at
from tribopipe.review import parse_review

REPO = Path(__file__).resolve().parents[1]
#: page and Python agree to rounding (summation order differs)
REL = 1e-12


@pytest.fixture(scope="module")
def reviewed_campaign(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("review-page")
    cfg = make_campaign(root)
    assert run_campaign(load_campaign(cfg), jobs=1, plots=False).ok
    result = CliRunner().invoke(main, ["review", str(cfg), "-o", str(root / "review.html")],
                                catch_exceptions=False)
    assert result.exit_code == 0, result.output
    return root


def open_page(browser, page: Path, width: int) -> Tab:
    tab = Tab(browser, viewport={"width": width, "height": 900},
              permissions=["clipboard-read", "clipboard-write"])
    tab.page.goto(page.resolve().as_uri())
    tab.wait_until("window.tribopipeReview !== undefined && window.tribopipeReview.ready")
    return tab


def card(tab: Tab, mid: str):
    root = tab.page.locator(f"#run-{mid}")
    root.scroll_into_view_if_needed()
    tab.wait_until(f"document.getElementById('run-{mid}').getAttribute('data-drawn') === '1'")
    return root


def close(a: float, b: float) -> bool:
    return math.isclose(a, b, rel_tol=REL, abs_tol=1e-15)


def test_the_pages_estimator_is_the_reductions(browser, reviewed_campaign: Path):
    """Differential: μ_K and u(μ_K) over a grid of windows, μ_S and u(μ_S) over a grid of
    peaks, and the refusals, in the page and in Python."""
    tab = open_page(browser, reviewed_campaign / "review.html", 1024)
    try:
        for row in the_map(reviewed_campaign).to_dict(orient="records"):
            mid = row["measurement_id"]
            smp, terms = samples_of(reviewed_campaign, mid)
            end = float(smp.s_mm[-1])
            windows = [(row["mu_k_window_start_mm"], row["mu_k_window_end_mm"])] + [
                (a * end, b * end) for a in (0.0, 0.2, 0.37, 0.5) for b in (0.55, 0.8, 1.0)] + [
                (0.5, 0.5005), (end + 1, end + 2)]
            got = tab.page.evaluate(
                "([id, ws]) => ws.map(([a, b]) => window.tribopipeReview.kinetic(id, a, b))",
                [mid, windows])
            for (lo, hi), page in zip(windows, got, strict=True):
                try:
                    k = kinetic_over(smp, lo, hi, terms)
                except ReductionError:
                    assert "error" in page, (lo, hi)
                    continue
                assert close(page["mu_k"], k.mu_k) and close(page["u_mu_k"], k.u_mu_k)
                assert page["n"] == k.n
            peaks = [float(row["mu_s_distance_mm"]), 0.05, 0.1234, 0.3 * end, end + 1]
            got = tab.page.evaluate(
                "([id, ps]) => ps.map(p => window.tribopipeReview.staticAt(id, p))", [mid, peaks])
            for p, page in zip(peaks, got, strict=True):
                try:
                    s = static_at(smp, p, terms)
                except ReductionError:
                    assert "error" in page
                    continue
                assert math.isclose(page["mu_s"], s.mu_s, rel_tol=1e-9)
                assert math.isclose(page["u_mu_s"], s.u_mu_s, rel_tol=1e-9)
        tab.check_clean()
    finally:
        tab.close()


@pytest.mark.parametrize("width", [800, 1024, 1400])
def test_review_in_the_browser_then_batch(browser, reviewed_campaign: Path, tmp_path: Path,
                                          width: int):
    root = tmp_path / "c"
    shutil.copytree(reviewed_campaign, root)
    runs = the_map(root).sort_values("measurement_id")
    dragged, typed, excluded = (str(m) for m in runs["measurement_id"].iloc[:3])
    tab = open_page(browser, root / "review.html", width)
    page = tab.page
    try:
        page.fill("#reviewer", "A. Reviewer")
        # 1. drag a window across the μ plot of one run
        card(tab, dragged)
        box = page.locator(f"#run-{dragged} canvas.mu").bounding_box()
        inner = box["width"] - 46 - 10
        y = box["y"] + box["height"] / 2
        page.mouse.move(box["x"] + 46 + 0.45 * inner, y)
        page.mouse.down()
        page.mouse.move(box["x"] + 46 + 0.7 * inner, y, steps=5)
        page.mouse.move(box["x"] + 46 + 0.92 * inner, y, steps=5)
        page.mouse.up()
        now = page.locator(f"#run-{dragged} .now")
        assert now.get_attribute("data-mu-k") is not None, page.locator(
            f"#run-{dragged} .problem").text_content()
        # 2. type a window and a static peak on another
        card(tab, typed)
        page.fill(f"#run-{typed} input.from", "0.55")
        page.fill(f"#run-{typed} input.to", "1.15")
        page.fill(f"#run-{typed} input.peak", "0.16")
        page.click(f"#run-{typed} button.set-window")
        typed_now = page.locator(f"#run-{typed} .now")
        smp, terms = samples_of(root, typed)
        k, s = kinetic_over(smp, 0.55, 1.15, terms), static_at(smp, 0.16, terms)
        assert close(float(typed_now.get_attribute("data-mu-k")), k.mu_k)
        assert close(float(typed_now.get_attribute("data-u-mu-k")), k.u_mu_k)
        assert math.isclose(float(typed_now.get_attribute("data-mu-s")), s.mu_s, rel_tol=1e-9)
        assert "μ_K = " in typed_now.text_content()
        # 3. exclude a third, with a reason
        card(tab, excluded)
        page.click(f"#run-{excluded} button.exclude")
        assert "needs a reason" in page.locator(f"#run-{excluded} .problem").text_content()
        page.fill(f"#run-{excluded} input.reason", "pin slipped, see notebook p. 12")
        page.click(f"#run-{excluded} button.exclude")
        assert page.locator("#decision-count").text_content() == "3"
        # the copy button puts the same text on the clipboard
        page.click("#copy")
        tab.wait_until("document.getElementById('copied').textContent === 'copied'")
        assert page.evaluate("navigator.clipboard.readText()") == page.input_value("#decisions")
        # the filters: one pair, then one flag, then all again
        total = len(runs)
        pair = f"{runs.iloc[0]['pin']} / {runs.iloc[0]['disc']}"
        page.select_option("#filter-pair", pair)
        shown = page.locator(".run:visible").count()
        in_pair = int((runs["pin"] + " / " + runs["disc"] == pair).sum())
        assert 0 < shown < total and shown == in_pair
        page.select_option("#filter-pair", "")
        page.select_option("#filter-flag", "*")
        assert page.locator(".run:visible").count() == int(
            runs["flags"].str.contains("off_nominal|no_steady|stick|static|peak|short|torque|"
                                       "unstable|plateau|no_friction", regex=True).sum())
        page.select_option("#filter-flag", "")
        assert page.locator(".run:visible").count() == total
        # save the decisions file
        with page.expect_download() as info:
            page.click("#download")
        saved = root / "review.csv"
        info.value.save_as(saved)
        assert saved.read_text(encoding="utf-8") == page.input_value("#decisions")
        tab.check_clean()
    finally:
        tab.close()
    review = parse_review(saved.read_text(encoding="utf-8"), saved)
    by_run = {d.run: d for d in review.decisions}
    assert {by_run[dragged].action, by_run[typed].action, by_run[excluded].action} == {
        "window", "exclude"}
    drag = by_run[dragged]
    end = float(samples_of(root, dragged)[0].s_mm[-1])
    assert drag.kinetic_from_mm is not None and drag.kinetic_to_mm is not None
    assert abs(drag.kinetic_from_mm / end - 0.45) < 0.03
    assert abs(drag.kinetic_to_mm / end - 0.92) < 0.03
    assert all(d.who == "A. Reviewer" for d in review.decisions)
    # apply it with the real command line, in its own process
    done = subprocess.run(
        [sys.executable, "-m", "tribopipe", "batch", str(root / "campaign.toml"), "-j", "1",
         "--review", str(saved)],
        capture_output=True, text=True, env={**os.environ}, timeout=600, check=False)
    assert done.returncode == 0, done.stderr
    assert "1 exclude, 2 window" in done.stderr
    after = the_map(root).set_index("measurement_id")
    lo, hi = drag.kinetic_from_mm, drag.kinetic_to_mm
    assert after.loc[dragged, "mu_k"] == pytest.approx(independent_mu_k(root, dragged, lo, hi),
                                                       rel=1e-12)
    assert after.loc[dragged, "review"] == "window"
    assert after.loc[typed, "mu_k"] == pytest.approx(independent_mu_k(root, typed, 0.55, 1.15),
                                                     rel=1e-12)
    assert after.loc[typed, "mu_s"] == pytest.approx(s.mu_s, rel=1e-12)
    assert after.loc[typed, "mu_s_distance_mm"] == 0.16
    assert bool(after.loc[excluded, "excluded"])
    assert after.loc[excluded, "exclusion_reason"] == "pin slipped, see notebook p. 12"
    assert after.loc[dragged, "review_by"] == "A. Reviewer"
    assert not pd.isna(after.loc[dragged, "auto_mu_k"])
    assert len(after) == len(FILES)


def test_hostile_reasons_stay_text(browser, tmp_path: Path):
    """A reason that would be markup and a name that would be a formula are shown and
    saved as text: no script runs, no element is made from them, nothing leaves the
    page."""
    cfg = make_campaign(tmp_path)
    assert run_campaign(load_campaign(cfg), jobs=1, plots=False).ok
    mid = str(the_map(tmp_path)["measurement_id"].iloc[0])
    review = tmp_path / "review.csv"
    review.write_text("run,action,kinetic_from_mm,kinetic_to_mm,static_peak_mm,reason,who,date\n"
                      f'{mid},exclude,,,,"<img src=x onerror=alert(3)>, ""quoted""",'
                      "=HYPERLINK(1),2026-11-27\n", encoding="utf-8")
    result = CliRunner().invoke(main, ["review", str(cfg), "--review", str(review), "-o",
                                       str(tmp_path / "page.html")], catch_exceptions=False)
    assert result.exit_code == 0, result.output
    tab = open_page(browser, tmp_path / "page.html", 1024)
    try:
        page = tab.page
        card(tab, mid)
        assert "<img src=x onerror=alert(3)>" in page.text_content(f"#run-{mid} .now")
        assert page.locator("img").count() == 0
        decisions = page.input_value("#decisions")
        again = parse_review(decisions, tmp_path / "review.csv").decisions
        assert again[0].reason == '<img src=x onerror=alert(3)>, "quoted"'
        assert again[0].who == "=HYPERLINK(1)" and "'=HYPERLINK(1)" in decisions
        tab.check_clean()
    finally:
        tab.close()
