"""The pictures of ``docs/method.md``'s section on reviewing a run: runs of the shipped
example campaign (synthetic exports, see ``raw/example/README.md``) drawn by the trace
plot every output uses (:func:`tribopipe.figures.trace.plot_trace_row`), before and after
a reviewer's window applied by the real batch.

    .venv/bin/python scripts/review_pictures.py        # writes docs/img/review_*.png
"""

from __future__ import annotations

import shutil
import sys
import tempfile
from pathlib import Path

import pandas as pd

from tribopipe.campaign import load_campaign, run_campaign
from tribopipe.figures.trace import plot_trace_row
from tribopipe.frictionmap import read_map
from tribopipe.layout import find_trace
from tribopipe.review import HEADER

REPO = Path(__file__).resolve().parents[1]
IMG = REPO / "docs" / "img"
#: the pictures: file name → (example export, a reviewer's window [mm] or None)
PICTURES = {
    "review_overshoot.png": ("EF50_steel_1N_20C_r2.csv", None),
    "review_automatic.png": ("DS30_acrylic_1N_20C_r2.csv", None),
    "review_window.png": ("DS30_acrylic_1N_20C_r2.csv", (0.8, 1.2, 0.19)),
}


def main() -> int:
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        shutil.copytree(REPO / "raw" / "example", root / "raw")
        shutil.copytree(REPO / "configs", root / "configs")
        cfg = root / "configs" / "example.toml"
        text = cfg.read_text(encoding="utf-8").replace("../raw/example", "../raw")
        cfg.write_text(text.replace("plots = true", "plots = false"), encoding="utf-8")
        campaign = load_campaign(cfg)
        assert run_campaign(campaign, plots=False).ok
        runs = read_map(campaign.map_path)
        rows = []
        for source, window in PICTURES.values():
            if window is not None:
                mid = runs.loc[runs["source_file"] == source, "measurement_id"].iloc[0]
                rows.append(f"{mid},window,{window[0]},{window[1]},{window[2]},"
                            "plateau judged from 0.8 mm,example,2026-11-27")
        review = root / "review.csv"
        review.write_text(",".join(HEADER) + "\n" + "\n".join(rows) + "\n", encoding="utf-8")
        automatic = runs
        from dataclasses import replace

        assert run_campaign(replace(campaign, review=review), plots=False).ok
        reviewed = read_map(campaign.map_path)
        for name, (source, window) in PICTURES.items():
            table = reviewed if window is not None else automatic
            row = table[table["source_file"] == source].iloc[0].to_dict()
            trace = pd.read_parquet(find_trace(campaign.layout.traces_dir, row["measurement_id"]))
            plot_trace_row(trace, row, IMG / name, fmt="png")
            print(IMG / name)
    return 0


if __name__ == "__main__":
    sys.exit(main())
