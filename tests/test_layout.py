"""The output folder is named in one place: every writer and reader agrees on its paths."""

from __future__ import annotations

from pathlib import Path

import pytest

from tribopipe.errors import ExportError
from tribopipe.layout import (
    DEFAULT_OUTPUT_DIR,
    OutputLayout,
    find_trace,
    read_failures,
    run_stem,
    write_failures,
)

MID = "c5fe21dcc5e014de"


def test_every_file_of_a_run_shares_one_name(tmp_path: Path) -> None:
    out = OutputLayout(tmp_path)
    raw = Path("/lab/raw/DS30_steel_1N_10C_r1.csv")
    assert run_stem(raw, MID) == "DS30_steel_1N_10C_r1_c5fe21dc"
    name = "DS30_steel_1N_10C_r1_c5fe21dc"
    assert out.trace_path(raw, MID) == tmp_path / "traces" / f"{name}.parquet"
    assert out.summary_path(raw, MID) == tmp_path / "summaries" / f"{name}.json"
    assert out.trace_plot_path(raw, MID) == tmp_path / "plots" / "traces" / f"{name}.png"
    assert not list(tmp_path.iterdir())  # naming a path creates nothing


def test_the_folder_level_files(tmp_path: Path) -> None:
    out = OutputLayout.of(tmp_path)
    assert OutputLayout.of(out) is out
    assert (out.map_path.name, out.runs_csv.name, out.failures_csv.name, out.report_html.name) \
        == ("friction_map.parquet", "runs.csv", "failures.csv", "report.html")
    assert out.pair_plots_dir == tmp_path / "plots" / "pairs"
    assert out.batch_lock == tmp_path / ".tribopipe-batch.lock"
    # a campaign name becomes a safe file name: never a path, never empty
    assert out.state_path("example") == tmp_path / ".tribopipe-state.example.sqlite"
    assert out.state_path("../../etc/x y").name == ".tribopipe-state.etc-x-y.sqlite"
    assert out.state_path("///").name == ".tribopipe-state.campaign.sqlite"
    # the JSON state of older versions, read once and converted
    assert out.legacy_state_path("../../etc/x y").name == ".tribopipe-state.etc-x-y.json"


def test_a_trace_is_found_by_its_measurement_id(tmp_path: Path) -> None:
    out = OutputLayout(tmp_path)
    assert out.find_trace(MID) is None
    target = out.trace_path("run.csv", MID)
    target.parent.mkdir(parents=True)
    target.write_bytes(b"PAR1")
    assert out.find_trace(MID) == target == find_trace(out.traces_dir, MID[:8] + "ffff")
    assert out.find_trace("0123456789abcdef") is None


def test_failures_csv_round_trips_through_the_one_writer_and_reader(tmp_path: Path) -> None:
    path = OutputLayout(tmp_path).failures_csv
    assert read_failures(path) is None  # no batch ran
    failures = {"b.csv": 'b.csv: not a number "x", line 3', "a.csv": "a.csv: metadata missing"}
    write_failures(path, failures)
    assert path.read_text(encoding="utf-8").splitlines()[0] == "file,reason"
    assert read_failures(path) == tuple(sorted(failures.items()))
    write_failures(path, {})
    assert read_failures(path) == ()


def test_a_foreign_failures_csv_is_refused_in_one_line(tmp_path: Path) -> None:
    path = tmp_path / "failures.csv"
    path.write_text("name,why\nx,y\n", encoding="utf-8")
    with pytest.raises(ExportError, match=r"failures\.csv:1: expected the header 'file,reason'"):
        read_failures(path)


def test_the_cli_defaults_are_the_layout(tmp_path: Path) -> None:
    """The CLI spells its defaults as text (it imports only click at module level): they
    must be the layout's paths."""
    from click.testing import CliRunner

    from tribopipe.cli import main
    from tribopipe.project import DEFAULT_MAP

    default = OutputLayout(Path(DEFAULT_OUTPUT_DIR))
    assert Path(DEFAULT_MAP) == default.map_path
    helps = {cmd: " ".join(CliRunner().invoke(main, [*cmd.split(), "--help"]).output.split())
             for cmd in ("reduce", "plot pairs", "plot runs", "map show", "query")}
    for text in helps.values():
        assert f"else {DEFAULT_MAP}." in text
    assert "Default: the map's folder" in helps["reduce"]
    pairs = default.pair_plots_dir.relative_to(default.root).as_posix()
    traces = default.trace_plots_dir.relative_to(default.root).as_posix()
    assert f"Default: {pairs} beside the map." in helps["plot pairs"]
    assert f"Default: {traces} in the campaign output folder." in helps["plot runs"]


def test_what_the_folder_writes_is_known_so_a_campaign_never_reads_it(tmp_path: Path) -> None:
    out = OutputLayout(tmp_path / "processed")
    ours = [out.map_path, out.runs_csv, out.failures_csv, out.report_html, out.batch_lock,
            out.state_path("lab"), out.trace_path("a.csv", MID), out.summary_path("a.csv", MID),
            out.trace_plot_path("a.csv", MID), out.pair_plots_dir / "pair_x__y.png",
            out.root / "friction_map.parquet.lock"]
    assert all(out.written_here(p) for p in ours)
    theirs = [out.root / "DS30_steel_1N_10C_r1.csv", out.root / "raw" / "run.txt",
              tmp_path / "runs.csv", out.root / "notes" / "runs.csv"]
    assert not any(out.written_here(p) for p in theirs)


def _trace(path: Path, measurement_id: str | None, mu: float) -> Path:
    """A trace Parquet as the pipeline writes one: its run's id in the footer, or none
    (a trace written before the id was kept)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    from tribopipe.layout import TRACE_ID_KEY

    table = pa.table({"distance_mm": [0.0, 1.0], "mu": [mu, mu]})
    if measurement_id is not None:
        table = table.replace_schema_metadata({TRACE_ID_KEY: measurement_id.encode()})
    path.parent.mkdir(parents=True, exist_ok=True)
    pq.write_table(table, path)
    return path


def test_two_runs_whose_ids_share_eight_digits_each_find_their_own_trace(
        tmp_path: Path) -> None:
    out = OutputLayout(tmp_path)
    first, second = MID, MID[:8] + "0000ffff"
    a = _trace(out.trace_path("DS30_steel_1N_10C_r1.csv", first), first, 0.4)
    b = _trace(out.trace_path("DS30_steel_1N_10C_r2.csv", second), second, 0.9)
    assert out.find_trace(first) == a and out.find_trace(second) == b
    # a third run of the same digits whose trace is missing gets neither of theirs
    assert out.find_trace(MID[:8] + "11112222") is None


def test_colliding_traces_without_their_ids_are_not_guessed(tmp_path: Path) -> None:
    out = OutputLayout(tmp_path)
    _trace(out.trace_path("a.csv", MID), None, 0.4)
    _trace(out.trace_path("b.csv", MID[:8] + "0000ffff"), None, 0.9)
    assert out.find_trace(MID) is None  # before, the first name in order: maybe another's


def test_the_report_picks_each_run_its_own_trace_as_find_trace_does(tmp_path: Path) -> None:
    import pandas as pd

    from tribopipe.report import ReportInputs, with_traces

    out = OutputLayout(tmp_path)
    first, second, third = MID, MID[:8] + "0000ffff", "0123456789abcdef"
    paths = {mid: _trace(out.trace_path(f"run_{k}.csv", mid), mid, 0.5)
             for k, mid in enumerate((first, second, third))}
    runs = pd.DataFrame({"measurement_id": [first, second, third, "fedcba9876543210"]})
    found = with_traces(ReportInputs(runs=runs, groups=pd.DataFrame(), fits=pd.DataFrame(),
                                     traces_dir=out.traces_dir)).trace_paths
    assert found == paths
    assert all(out.find_trace(mid) == path for mid, path in paths.items())
