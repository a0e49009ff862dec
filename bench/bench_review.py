"""Review-page benchmark: the page of a large campaign, its size and its load time.

For ``bench/README.md``'s "The review page at 1,000 runs". The example campaign is
reduced once (48 real runs of 1,800 samples each); its map rows and trace files are then
copied under new measurement ids until the map holds ``--runs`` runs (the page cannot
tell a copy from a run: every copy is a full trace). Measured:

* writing the page (``tribopipe.export.review_page.write_review_page``, wall time) and
  its size on disk;
* in headless Chromium (``/usr/bin/chromium`` under Playwright, 1024 × 900 px): the time
  from navigation to the page's script being ready (every card built), to the first card
  drawn, and the time of a filter change (every card shown or hidden), of scrolling to
  the last run and having it drawn, and of re-reading μ_K over a new window on one run
  (every sample, in the page) — each the median of ``--repeat`` loads.

    nice .venv/bin/python bench/bench_review.py [--runs 1000] [--repeat 3]

Prints the figures and writes ``bench/review.json``.
"""

from __future__ import annotations

import argparse
import json
import platform
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
sys.path.insert(0, str(REPO / "tests"))


def build(root: Path, runs: int) -> tuple[Path, Path]:
    """A map of ``runs`` runs with their traces under ``root``: the example campaign
    reduced, its rows and traces copied under new ids."""
    import hashlib

    import pandas as pd

    from tribopipe.campaign import load_campaign, run_campaign
    from tribopipe.frictionmap import read_map
    from tribopipe.frictionmap.store import write_map
    from tribopipe.layout import find_trace

    shutil.copytree(REPO / "raw" / "example", root / "raw")
    cfg = (REPO / "configs" / "example.toml").read_text(encoding="utf-8")
    cfg = cfg.replace('raw_dir = "../raw/example"', 'raw_dir = "raw"')
    cfg = cfg.replace('manifest = "../raw/example/manifest.csv"', 'manifest = "raw/manifest.csv"')
    cfg = cfg.replace('output_dir = "../processed/demo"', 'output_dir = "out"')
    cfg = cfg.replace('map = "../processed/demo/friction_map.parquet"', "")
    cfg = cfg.replace('instrument = "instruments/t-pid44.toml"',
                      f'instrument = "{REPO / "configs" / "instruments" / "t-pid44.toml"}"')
    cfg = cfg.replace("plots = true", "plots = false")
    (root / "campaign.toml").write_text(cfg, encoding="utf-8")
    report = run_campaign(load_campaign(root / "campaign.toml"), plots=False)
    assert report.ok, report.failures
    out = root / "out"
    base = read_map(out / "friction_map.parquet")
    rows = []
    for i in range(runs):
        src = base.iloc[i % len(base)].to_dict()
        mid = src["measurement_id"] if i < len(base) else hashlib.sha256(
            f"{src['measurement_id']}-{i}".encode()).hexdigest()[:16]
        if i >= len(base):
            trace = find_trace(out / "traces", src["measurement_id"])
            assert trace is not None
            shutil.copy(trace, out / "traces" / f"copy{i}_{mid[:8]}.parquet")
        rows.append({**src, "measurement_id": mid, "repeat": 1 + i // len(base)})
    map_path = out / "friction_map.parquet"
    write_map(map_path, pd.DataFrame(rows))
    return map_path, out / "traces"


def browser_figures(page_path: Path, repeat: int) -> dict[str, float]:
    """Median seconds of each step of a page load in headless Chromium."""
    from playwright.sync_api import sync_playwright

    def until(page, expression: str) -> None:
        while not page.evaluate(expression):
            time.sleep(0.005)

    steps: dict[str, list[float]] = {"ready_s": [], "first_plot_s": [], "filter_s": [],
                                     "last_run_drawn_s": [], "window_reread_s": []}
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path="/usr/bin/chromium",
                                    args=["--headless", "--no-sandbox", "--disable-gpu"])
        for _ in range(repeat):
            context = browser.new_context(viewport={"width": 1024, "height": 900})
            page = context.new_page()
            t0 = time.perf_counter()
            page.goto(page_path.as_uri(), wait_until="commit")
            until(page, "window.tribopipeReview !== undefined && window.tribopipeReview.ready")
            steps["ready_s"].append(time.perf_counter() - t0)
            until(page, "document.querySelector('.run[data-drawn]') !== null")
            steps["first_plot_s"].append(time.perf_counter() - t0)
            t1 = time.perf_counter()
            page.select_option("#filter-flag", "*")
            page.select_option("#filter-flag", "")
            steps["filter_s"].append((time.perf_counter() - t1) / 2)
            t2 = time.perf_counter()
            last = page.evaluate("Array.from(document.querySelectorAll('.run')).pop().id")
            page.locator(f"#{last}").scroll_into_view_if_needed()
            until(page, f"document.getElementById('{last}').getAttribute('data-drawn') === '1'")
            steps["last_run_drawn_s"].append(time.perf_counter() - t2)
            mid = last.removeprefix("run-")
            t3 = time.perf_counter()
            page.evaluate("id => window.tribopipeReview.kinetic(id, 0.5, 1.2)", mid)
            steps["window_reread_s"].append(time.perf_counter() - t3)
            context.close()
        browser.close()
    return {k: statistics.median(v) for k, v in steps.items()}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--out", type=Path, default=HERE / "review.json")
    args = parser.parse_args(argv)

    from tribopipe.export.review_page import write_review_page

    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        map_path, traces = build(root, args.runs)
        page = root / "review.html"
        t0 = time.perf_counter()
        write_review_page(map_path, traces, page)
        write_s = time.perf_counter() - t0
        size = page.stat().st_size
        figures = browser_figures(page, args.repeat)
    result = {"runs": args.runs, "samples_per_run": 1800, "page_bytes": size,
              "page_MB": round(size / 1e6, 1), "write_s": round(write_s, 2),
              **{k: round(v, 3) for k, v in figures.items()},
              "machine": f"{platform.machine()}, {platform.python_version()}",
              "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())}
    print(json.dumps(result, indent=2))
    args.out.write_text(json.dumps(result, indent=2) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
