"""The shipped example campaign: its files are what the script writes, and a batch of it
gives back the COF values it was generated from."""

from __future__ import annotations

import csv
import importlib.util
import sys
from dataclasses import replace
from pathlib import Path

import pandas as pd
import pytest

from tribopipe.campaign import load_campaign, run_campaign

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "raw" / "example"
CONFIG = REPO / "configs" / "example.toml"


def load_script():
    """``scripts/make_example_campaign.py`` as a module (scripts/ is not a package)."""
    name = "make_example_campaign"
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(
            name, REPO / "scripts" / "make_example_campaign.py"
        )
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module  # its dataclasses look their module up while defined
        spec.loader.exec_module(module)
    return sys.modules[name]


def manifest_rows() -> dict[str, dict[str, str]]:
    with (EXAMPLE / "manifest.csv").open(encoding="utf-8", newline="") as fh:
        return {row["file"]: row for row in csv.DictReader(fh)}


def test_shipped_files_are_what_the_script_writes(tmp_path: Path) -> None:
    """Golden files that cannot drift: regenerate and compare byte for byte."""
    load_script().main(["--out", str(tmp_path)])
    shipped = sorted(p.name for p in EXAMPLE.iterdir())
    assert shipped == sorted(p.name for p in tmp_path.iterdir())
    for name in shipped:
        assert (EXAMPLE / name).read_bytes() == (tmp_path / name).read_bytes(), (
            f"raw/example/{name} is stale: run `make example` and commit"
        )


def test_example_is_small_labelled_and_complete() -> None:
    total = sum(p.stat().st_size for p in EXAMPLE.iterdir())
    assert total < 15e6
    readme = (EXAMPLE / "README.md").read_text(encoding="utf-8")
    assert "SYNTHETIC" in readme and "synthetic" in readme
    rows = manifest_rows()
    assert len(rows) == 48
    for file, row in rows.items():
        assert (EXAMPLE / file).is_file()
        assert f"| {file} |" in readme
        # the stated factor between the static and kinetic COF
        assert float(row["mu_s_true"]) == pytest.approx(1.3 * float(row["mu_k_true"]), abs=1e-3)
    assert sum(r["language"] == "fr" for r in rows.values()) == 1
    # the first bytes are a UTF-16 LE byte-order mark, as RheoCompass writes
    assert (EXAMPLE / next(iter(rows))).read_bytes()[:2] == b"\xff\xfe"


def test_published_values_are_the_published_ones() -> None:
    from tribopipe.frictionmap.published import published_csv_path

    script = load_script()
    published = pd.read_csv(published_csv_path())
    checked = 0
    for (pin, disc, force, temperature), (values, source) in script.MU_K.items():
        if source != script.PUBLISHED:
            continue
        sel = published[(published["pin"] == script.PINS[pin])
                        & (published["disc"] == script.DISCS[disc])
                        & (published["contactForce"] == force)
                        & (published["temperature"] == temperature)]
        by_repeat = dict(zip(sel["measurementNo"].astype(int), sel["cof"], strict=True))
        assert [by_repeat[1], by_repeat[2]] == list(values), (pin, disc, force, temperature)
        checked += 1
    assert checked >= 12


def test_batch_of_the_example_recovers_the_stated_values(tmp_path: Path) -> None:
    campaign = load_campaign(CONFIG)
    campaign = replace(campaign, output_dir=tmp_path, map_path=tmp_path / "map.parquet")
    report = run_campaign(campaign, jobs=2, plots=False)
    assert report.failures == []
    assert len(report.reduced) == 48
    assert report.groups_updated == 24

    runs = pd.read_parquet(campaign.map_path)
    truth = manifest_rows()
    for row in runs.itertuples():
        stated = truth[row.source_file]
        assert row.pin == stated["pin"] and row.disc == stated["disc"]
        # the targets: μ_K within ±0.01, a distinct μ_S within ±0.02
        assert row.mu_k == pytest.approx(float(stated["mu_k_true"]), abs=0.01), row.source_file
        assert row.mu_s == pytest.approx(float(stated["mu_s_true"]), abs=0.02), row.source_file
    # the demo's runs are never a lab's measurements: every one is flagged synthetic
    assert runs["flags"].str.split(";").map(lambda f: "synthetic" in f).all()
    flagged = runs.loc[runs["flags"].str.contains("normal_force_off_nominal"), "source_file"]
    assert flagged.tolist() == ["EF50_steel_1N_20C_r2.csv"]
    assert report.flagged == [("EF50_steel_1N_20C_r2.csv", "normal_force_off_nominal")]
    french = runs.loc[runs["source_file"] == "EF50_acrylic_9N_20C_r2.csv"].iloc[0]
    assert french["mu_k"] == pytest.approx(0.43, abs=0.02)
