"""Demo rows are never a lab's measurements: rows flagged ``synthetic`` are refused by
``map publish`` without --allow-synthetic, and ``map show``, ``query`` and ``report`` say
when a map holds them."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from tribopipe import frictionmap as fm
from tribopipe.cli import main
from tribopipe.frictionmap.synthetic_rows import synthetic_count
from tribopipe.labels import FLAG_SYNTHETIC, quality_flags
from tribopipe.stats import group_statistics

NOTE = "SYNTHETIC"


def invoke(*args: str):
    return CliRunner().invoke(main, list(args), catch_exceptions=False)


def _map(tmp_path: Path, n_synthetic: int) -> Path:
    """The published map imported, with its first ``n_synthetic`` rows flagged synthetic."""
    path = tmp_path / "friction_map.parquet"
    result = invoke("map", "import", "--published", "--map", str(path))
    assert result.exit_code == 0, result.output
    runs = fm.read_map(path)
    runs.loc[runs.index[:n_synthetic], "flags"] = FLAG_SYNTHETIC
    fm.write_map(path, runs)
    assert synthetic_count(fm.read_map(path)) == n_synthetic
    return path


@pytest.mark.parametrize("n_synthetic", [0, 3])
def test_map_show_says_when_rows_are_synthetic(tmp_path: Path, n_synthetic: int) -> None:
    path = _map(tmp_path, n_synthetic)
    result = invoke("map", "show", "--map", str(path))
    assert result.exit_code == 0, result.output
    assert (NOTE in result.output) == bool(n_synthetic)
    if n_synthetic:
        assert f"{n_synthetic} of " in result.output


def test_query_says_when_the_map_holds_synthetic_rows(tmp_path: Path) -> None:
    path = _map(tmp_path, 2)
    args = ("query", "--pin", "Dragonskin 30", "--disc", "steel", "--pressure", "30",
            "--temperature", "20", "--map", str(path))
    result = invoke(*args)
    assert result.exit_code == 0, result.output
    assert NOTE in result.output
    # with --json the note goes to stderr: stdout stays one JSON document
    result = CliRunner().invoke(main, [*args, "--json"])
    assert result.exit_code == 0, result.output
    json.loads(result.stdout)
    assert NOTE in result.stderr
    clean = _map(tmp_path / "clean", 0)
    assert NOTE not in invoke(*args[:-1], str(clean)).output


def test_publish_refuses_synthetic_rows_under_a_lab_without_the_option(tmp_path: Path) -> None:
    path = _map(tmp_path, 1)
    refused = invoke("map", "publish", "-o", str(tmp_path / "pkg"), "--lab", "Some Lab",
                     "--map", str(path))
    assert refused.exit_code == 1
    assert "synthetic" in refused.output and "--allow-synthetic" in refused.output
    assert not (tmp_path / "pkg").exists()
    done = invoke("map", "publish", "-o", str(tmp_path / "pkg"), "--lab", "Some Lab",
                  "--allow-synthetic", "--map", str(path))
    assert done.exit_code == 0, done.output
    assert (tmp_path / "pkg" / "datapackage.json").is_file()


def test_report_says_when_rows_are_synthetic(tmp_path: Path) -> None:
    path = _map(tmp_path, 5)
    out = tmp_path / "report.html"
    result = invoke("report", "--map", str(path), "-o", str(out))
    assert result.exit_code == 0, result.output
    page = out.read_text(encoding="utf-8")
    assert 'class="synthetic"' in page and f"5 of {len(fm.read_map(path))}" in page


def test_synthetic_is_no_quality_flag_of_a_group(tmp_path: Path) -> None:
    """A group of synthetic runs is not a 'flagged run' group: the flag says where the runs
    came from (said once), not how they went; a real QC flag beside it still counts."""
    assert quality_flags(f"{FLAG_SYNTHETIC};normal_force_off_nominal") == [
        "normal_force_off_nominal"]
    assert quality_flags(FLAG_SYNTHETIC) == [] and quality_flags(None) == []
    runs = fm.read_map(_map(tmp_path, 0))
    runs["flags"] = FLAG_SYNTHETIC
    assert not group_statistics(runs)["qc_flagged"].any()
    first = runs.index[0]
    runs.loc[first, "flags"] = f"{FLAG_SYNTHETIC};temperature_off_nominal"
    flagged = group_statistics(runs)["qc_flagged"]
    assert int(flagged.sum()) == 1


def test_report_lists_no_run_for_the_synthetic_flag_alone(tmp_path: Path) -> None:
    """The report counts and lists runs with QC flags as the groups and the batch do
    (:func:`tribopipe.labels.quality_flags`): a synthetic run is said once, in the
    summary's note, not listed as a flagged run."""
    path = _map(tmp_path, 5)
    runs = fm.read_map(path)
    assert not any(quality_flags(f) for f in runs["flags"])  # only the synthetic flag
    out = tmp_path / "report.html"
    result = invoke("report", "--map", str(path), "-o", str(out))
    assert result.exit_code == 0, result.output
    page = out.read_text(encoding="utf-8")
    assert "<dt>runs with QC flags</dt><dd>0</dd>" in page
    assert "No run carries a QC flag or is excluded." in page


def test_what_synthetic_means_is_worded_once(tmp_path: Path) -> None:
    """``map show``, ``query``, the campaign's note and the refusal of ``map publish`` all
    say it with the one wording (``SYNTHETIC_MEANS``); the map's note names the map as a
    field, not by rewriting the text."""
    from tribopipe.frictionmap.synthetic_rows import (
        SYNTHETIC_MEANS,
        campaign_note,
        map_synthetic_note,
        synthetic_note,
    )

    path = _map(tmp_path, 3)
    runs = fm.read_map(path)
    n = len(runs)
    assert synthetic_note(runs) == f"note: 3 of {n} runs are {SYNTHETIC_MEANS}"
    assert map_synthetic_note(path) == f"note: 3 of {n} runs of this map are {SYNTHETIC_MEANS}"
    assert SYNTHETIC_MEANS in campaign_note()
    shown = invoke("map", "show", "--map", str(path)).output
    assert SYNTHETIC_MEANS in shown
    refused = CliRunner().invoke(main, ["map", "publish", "-o", str(tmp_path / "pkg"),
                                        "--lab", "Some Lab", "--map", str(path)])
    assert refused.exit_code == 1 and SYNTHETIC_MEANS in refused.output, refused.output
