"""A run's QC flags are decided once: every output of `reduce` and of `batch` shows the same.

The real 1 N run of the example campaign, labelled 3 N and kept so (``--keep-labels``:
without it such a run is refused): the measured force strays from nominal by more than the
10 % tolerance, so the run carries ``normal_force_off_nominal``
in the `reduce` table and JSON, its summary, the trace plot's header, the map and (for a
batch) ``runs.csv``, the report and the explorer page.
"""

from __future__ import annotations

import csv
import json
import shutil
from pathlib import Path

import pandas as pd
import pytest
from click.testing import CliRunner

from tribopipe.cli import main
from tribopipe.figures import trace_figure

ROOT = Path(__file__).resolve().parents[1]
ONE_NEWTON = ROOT / "raw" / "example" / "DS30_steel_1N_10C_r1.csv"
OFF = "normal_force_off_nominal"


def _header_flags() -> str:
    """The flags line of the last trace plot this process drew (its header's last line)."""
    return str(trace_figure().flags.get_text())


def _map_flags(path: Path) -> list[str]:
    return [str(f) for f in pd.read_parquet(path)["flags"]]


def _explorer_run_flags(data: object, run_id: str) -> list[str] | None:
    """The flags the explorer's embedded data holds for the run ``run_id``."""
    if isinstance(data, dict):
        if data.get("id") == run_id and "flags" in data:
            return list(data["flags"])
        items = list(data.values())
    elif isinstance(data, list):
        items = data
    else:
        return None
    for item in items:
        found = _explorer_run_flags(item, run_id)
        if found is not None:
            return found
    return None


@pytest.mark.skipif(not ONE_NEWTON.exists(), reason="the example campaign is not here")
def test_reduce_shows_the_maps_flags_in_every_output(tmp_path: Path) -> None:
    out, mapfile = tmp_path / "out", tmp_path / "map.parquet"
    args = ["reduce", str(ONE_NEWTON), "--keep-labels", "--pin", "DS30", "--disc", "steel",
            "--force", "3", "--temperature", "10", "--repeat", "1", "--output", str(out),
            "--map", str(mapfile)]
    table = CliRunner().invoke(main, [*args, "--plot"])
    assert table.exit_code == 0, table.output
    header_after_reduce = _header_flags()
    shown = CliRunner().invoke(main, [*args, "--json"])
    assert shown.exit_code == 0, shown.output

    stored = _map_flags(mapfile)
    assert stored == [OFF]
    row = next(line for line in table.stdout.splitlines() if ONE_NEWTON.name in line)
    assert row.split()[-1] == OFF
    assert json.loads(shown.stdout)[0]["flags"] == [OFF]
    summary = json.loads(next((out / "summaries").glob("*.json")).read_text())
    assert summary["flags"] == [OFF]
    assert header_after_reduce == f"flags: {OFF}"


@pytest.mark.skipif(not ONE_NEWTON.exists(), reason="the example campaign is not here")
def test_batch_shows_the_same_flags_as_reduce(tmp_path: Path) -> None:
    raw = tmp_path / "raw"
    raw.mkdir()
    # the file name labels it 3 N: the mislabel comes from the campaign's metadata
    shutil.copyfile(ONE_NEWTON, raw / "DS30_steel_3N_10C_r1.csv")
    out, mapfile = tmp_path / "out", tmp_path / "map.parquet"
    done = CliRunner().invoke(main, [
        "batch", str(raw), "--pattern", "{pin}_{disc}_{force}N_{temperature}C_r{repeat}",
        "--output", str(out), "--map", str(mapfile), "--jobs", "1", "--plots",
        "--keep-labels"])
    assert done.exit_code == 0, done.output
    header = _header_flags()

    assert _map_flags(mapfile) == [OFF]
    with (out / "runs.csv").open(encoding="utf-8", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["flags"] for r in rows] == [OFF]
    assert header == f"flags: {OFF}"

    # the report of that map lists the run with its flag, and the explorer page (its own
    # file, and the copy the report embeds) carries the same flags for the run
    from tribopipe.export.explorer import read_embedded_data

    report = tmp_path / "report.html"
    made = CliRunner().invoke(main, ["report", "--map", str(mapfile), "--processed", str(out),
                                     "-o", str(report)])
    assert made.exit_code == 0, made.output
    page = tmp_path / "explorer.html"
    made = CliRunner().invoke(main, ["explore", "--map", str(mapfile), "-o", str(page)])
    assert made.exit_code == 0, made.output
    (run_id,) = pd.read_parquet(mapfile)["measurement_id"]
    html = report.read_text(encoding="utf-8")
    assert OFF in html
    for text in (page.read_text(encoding="utf-8"), html):
        assert _explorer_run_flags(read_embedded_data(text), run_id) == [OFF]

    # the same run through `reduce` with the same labels: the same flags
    again = CliRunner().invoke(main, [
        "reduce", str(raw / "DS30_steel_3N_10C_r1.csv"), "--keep-labels", "--pin", "DS30",
        "--disc", "steel", "--force", "3", "--temperature", "10", "--repeat", "1",
        "--no-map", "--json",
        "--output", str(tmp_path / "again")])
    assert again.exit_code == 0, again.output
    assert json.loads(again.stdout)[0]["flags"] == [OFF]
