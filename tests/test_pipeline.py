"""One file through the pipeline: the outcome, its trace on disk and its summary."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest

from generators.synthetic import SyntheticRun, write_rheocompass_export
from tribopipe.config import load_settings
from tribopipe.labels import RunLabels
from tribopipe.pipeline import reduce_file, run_summary, write_summary, write_trace


@pytest.fixture(scope="module")
def export(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("raw") / "EF50_steel_5N_10C_r2.csv"
    run = SyntheticRun(mu_s=0.47, mu_k=0.36, normal_force_N=5.0, temperature_C=10.0, seed=3)
    write_rheocompass_export(path, run, project="p", test="EF50 steel", sample="EF50")
    return path


def test_trace_parquet_reads_back_identical(export: Path, tmp_path: Path) -> None:
    outcome = reduce_file(export, load_settings())
    written = write_trace(tmp_path, outcome)
    assert written.parent == tmp_path / "traces"
    assert outcome.measurement_id[:8] in written.name
    back = pd.read_parquet(written)
    pd.testing.assert_frame_equal(back, outcome.result.trace.reset_index(drop=True))
    assert not list(tmp_path.rglob("*.tmp"))


def test_labels_decide_whether_a_map_record_exists(export: Path) -> None:
    settings = load_settings()
    unlabelled = reduce_file(export, settings)
    assert unlabelled.record is None
    labelled = reduce_file(export, settings, RunLabels(pin="Ecoflex 00-50", disc="steel",
                                                     normal_force_N=5.0, temperature_C=10.0,
                                                     repeat=2))
    assert labelled.record is not None
    assert labelled.record.measurement_id == unlabelled.measurement_id
    # 5 N nominal on three pins of r = 3 mm -> 58.95 kPa
    assert labelled.record.pressure_kPa == pytest.approx(58.95, abs=0.01)


def test_summary_is_json_and_carries_the_evidence(export: Path, tmp_path: Path) -> None:
    outcome = reduce_file(export, load_settings())
    path = write_summary(tmp_path, outcome)
    summary = json.loads(path.read_text(encoding="utf-8"))
    assert summary == json.loads(json.dumps(run_summary(outcome), default=str))
    assert summary["mu_k"] == pytest.approx(0.36, abs=0.01)
    start, end = summary["mu_k_window_mm"]
    assert 0 < start < end <= summary["sliding_distance_mm"] + 1e-9
    assert summary["mu_s_distance_mm"] < start
    assert summary["file_hash"] and len(summary["config_hash"]) == 16


def test_reduce_files_writes_each_run_and_reports_a_bad_file_in_one_line(
    export: Path, tmp_path: Path
) -> None:
    from tribopipe.layout import OutputLayout
    from tribopipe.pipeline import reduce_files

    notes = tmp_path / "notes.csv"
    notes.write_text("a lab note, not an export\n", encoding="utf-8")
    seen = []
    results = reduce_files([notes, export, tmp_path / "gone.csv"], load_settings(),
                           out_dir=tmp_path / "out", plots=True, on_file=seen.append)
    assert seen == results
    assert [r.ok for r in results] == [False, True, False]
    assert results[0].error.reason.count(str(notes)) == 1
    assert "\n" not in results[0].error.reason
    assert results[2].error.reason.startswith(str(tmp_path / "gone.csv"))
    (good,) = results[1].runs  # one test, one friction interval: one run
    assert good.name == str(export)
    layout = OutputLayout(tmp_path / "out")
    mid = good.measurement_id
    assert good.trace == layout.trace_path(export, mid) and good.trace.is_file()
    assert good.summary_file == layout.summary_path(export, mid)
    assert good.summary_file.is_file()
    assert good.plot == layout.trace_plot_path(export, mid)
    assert good.plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    quiet = reduce_files([export], load_settings(), out_dir=tmp_path / "q", summaries=False)
    (run,) = quiet[0].runs
    assert quiet[0].ok and run.summary_file is None and run.plot is None
    assert not (tmp_path / "q" / "summaries").exists()
