"""Every outcome of every run is accounted for, by `reduce` and by `batch`.

A run whose output cannot be written is named with that output; a trace plot that cannot
be drawn costs neither the run nor the other files; a damaged map is refused before any
work; a relabel the map refuses exits 1 with the way out; a repeat number used twice in
one condition is reported.
"""

from __future__ import annotations

import errno
import json
import shutil
from pathlib import Path
from typing import Any

import pandas as pd
import pytest
from click.testing import CliRunner

import tribopipe.campaign.state as state
import tribopipe.pipeline.run_outputs as run_outputs
from helpers import reduce_cli
from tribopipe.cli import main

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "raw" / "example"
R1, R2 = EXAMPLE / "DS30_steel_1N_10C_r1.csv", EXAMPLE / "DS30_steel_1N_10C_r2.csv"
OTHER = EXAMPLE / "DS30_steel_5N_10C_r1.csv"
PATTERN = "{pin}_{disc}_{force}N_{temperature}C_r{repeat}"
pytestmark = pytest.mark.skipif(not (R1.exists() and R2.exists() and OTHER.exists()),
                                reason="the example campaign is not here")
LABELS = ["--pin", "DS30", "--disc", "steel", "--temperature", "10"]


def _batch(raw: Path, tmp_path: Path, *more: str) -> Any:
    return CliRunner().invoke(main, [
        "batch", str(raw), "--pattern", PATTERN, "--output", str(tmp_path / "out"),
        "--map", str(tmp_path / "map.parquet"), "--jobs", "1", *more])


def _errors(stderr: str) -> list[str]:
    return [ln for ln in stderr.splitlines() if ln.startswith(("error:", "failed:"))]


# ------------------------------------------------------------------ outputs not written


def _no_space(monkeypatch: pytest.MonkeyPatch, *, only: str | None = None) -> None:
    """Every trace write fails as on a full disk (or only the traces of ``only``)."""
    import pyarrow.parquet as pq

    real = pq.write_table

    def full(table: Any, where: Any, **kw: Any) -> None:
        if only is None or only in str(where):
            raise OSError(errno.ENOSPC, "No space left on device")
        real(table, where, **kw)

    monkeypatch.setattr(pq, "write_table", full)


def test_reduce_on_a_full_disk_names_the_output_not_the_input(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    _no_space(monkeypatch)
    out, mapfile = tmp_path / "out", tmp_path / "map.parquet"
    done = reduce_cli(R1, *LABELS, "--force", "1", "--output", out, "--map", mapfile)
    assert done.exit_code == 1 and "Traceback" not in done.output
    (line,) = _errors(done.stderr)
    assert str(out / "traces") in line and "No space left on device" in line
    assert "cannot write its trace" in line
    assert not mapfile.exists()  # the run without its trace is not stored


def test_batch_on_a_full_disk_lists_every_run_it_could_not_write(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    raw = tmp_path / "raw"
    raw.mkdir()
    for src in (R1, R2):
        shutil.copyfile(src, raw / src.name)
    _no_space(monkeypatch, only=R2.stem)

    def no_state(*_: Any, **__: Any) -> None:
        import sqlite3  # what SQLite raises when the disk is full

        raise sqlite3.OperationalError("database or disk is full")

    monkeypatch.setattr(state, "_connect", no_state)
    done = _batch(raw, tmp_path, "--no-plots")
    assert done.exit_code == 1 and "Traceback" not in done.output
    errors = _errors(done.stderr)
    (trace,) = [ln for ln in errors if R2.name in ln]
    assert "cannot write its trace" in trace and str(tmp_path / "out" / "traces") in trace
    assert any("state" in ln and ln.startswith("error:") for ln in errors)
    assert "1 failed" in done.stdout  # the ledger counts it
    # the run that could be written landed; the other is tried again next time
    assert list(pd.read_parquet(tmp_path / "map.parquet")["source_file"]) == [R1.name]


# ------------------------------------------------------------------ plots


def test_a_plot_that_fails_costs_neither_its_run_nor_the_other_files(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    real = run_outputs.plot_run

    def fragile(out: Any, outcome: Any) -> Path:
        if Path(outcome.path).name == R2.name:
            raise RuntimeError("raqm_layout() failed")
        return real(out, outcome)

    monkeypatch.setattr(run_outputs, "plot_run", fragile)
    out, mapfile = tmp_path / "out", tmp_path / "map.parquet"
    done = reduce_cli(R1, R2, OTHER, *LABELS, "--output", out, "--map", mapfile, "--plots")
    assert done.exit_code == 0, done.output
    (warning,) = [ln for ln in done.stderr.splitlines() if ln.startswith("warning:")]
    assert R2.name in warning and str(out / "plots") in warning and "raqm_layout" in warning
    assert len(pd.read_parquet(mapfile)) == 3
    assert len(list((out / "plots" / "traces").glob("*.png"))) == 2


def test_reduce_plot_of_a_file_named_with_a_newline(tmp_path: Path) -> None:
    raw = tmp_path / "raw"
    raw.mkdir()
    odd = raw / "DS30_steel\n1N\r_r2.csv"
    shutil.copyfile(R2, odd)
    out, mapfile = tmp_path / "out", tmp_path / "map.parquet"
    done = reduce_cli(R1, odd, OTHER, *LABELS, "--output", out, "--map", mapfile, "--plots")
    assert "Traceback" not in done.output and done.exception is None or \
        isinstance(done.exception, SystemExit)
    assert done.exit_code == 0, done.output
    assert len(pd.read_parquet(mapfile)) == 3  # the files before and after it too
    for line in done.stderr.splitlines():
        assert "\r" not in line
    # its picture is drawn, or its failure is named with the picture
    pictures = len(list((out / "plots" / "traces").glob("*.png")))
    warnings = [ln for ln in done.stderr.splitlines() if ln.startswith("warning:")]
    assert pictures + len(warnings) == 3
    assert all("trace plot" in w for w in warnings)


# ------------------------------------------------------------------ the map first


def test_reduce_refuses_a_damaged_map_before_any_work(tmp_path: Path) -> None:
    mapfile, out = tmp_path / "map.parquet", tmp_path / "out"
    mapfile.write_bytes(b"PAR1 not a map at all")
    done = reduce_cli(R1, *LABELS, "--force", "1", "--output", out, "--map", mapfile)
    assert done.exit_code == 1 and str(mapfile) in done.output
    assert done.stdout == ""  # no results printed
    assert not out.exists()  # no trace, no summary written


# ------------------------------------------------------------------ relabel


def test_a_relabel_kept_conflicting_exits_1_with_the_way_out(tmp_path: Path) -> None:
    mapfile, out = tmp_path / "map.parquet", tmp_path / "out"
    args = [R1, "--pin", "DS30", "--force", "1", "--temperature", "10", "--repeat", "1",
            "--output", out, "--map", mapfile]
    # a typo is refused at the edge; a wrong (but known) disc, kept against the export's
    # Test name, is what a relabel fixes
    typo = reduce_cli(*args, "--disc", "stel")
    assert typo.exit_code == 1 and "did you mean 'steel'" in typo.stderr
    assert not mapfile.exists()
    assert reduce_cli(*args, "--disc", "glass", "--keep-labels").exit_code == 0
    again = reduce_cli(*args, "--disc", "steel")
    assert again.exit_code == 1
    assert "--replace" in again.stderr.splitlines()[-1]
    assert "disc 'glass' in the map, 'steel'" in again.stderr
    assert list(pd.read_parquet(mapfile)["disc"]) == ["glass"]
    fixed = reduce_cli(*args, "--disc", "steel", "--replace")
    assert fixed.exit_code == 0, fixed.output
    assert list(pd.read_parquet(mapfile)["disc"]) == ["steel"]


def test_reduce_help_says_a_kept_conflict_exits_1() -> None:
    text = " ".join(CliRunner().invoke(main, ["reduce", "--help"]).output.split())
    assert "a relabelled run kept the map's row (pass --replace to relabel it)" in text


# ------------------------------------------------------------------ repeat numbers


def test_reduce_reports_one_repeat_number_used_twice(tmp_path: Path) -> None:
    mapfile, out = tmp_path / "map.parquet", tmp_path / "out"
    done = reduce_cli(R1, R2, *LABELS, "--force", "1", "--repeat", "1", "--output", out,
                   "--map", mapfile, "--json")
    assert done.exit_code == 0, done.output
    (warning,) = [ln for ln in done.stderr.splitlines() if ln.startswith("warning:")]
    assert "repeat 1 used by 2 runs of Dragonskin 30 on steel, 1 N, 10 °C" in warning
    assert R1.name in warning and R2.name in warning
    assert len(json.loads(done.stdout)) == 2  # reported, not refused
    again = reduce_cli(R1, *LABELS, "--force", "1", "--repeat", "2", "--output", out,
                    "--map", tmp_path / "other.parquet")
    assert "warning:" not in again.stderr


def test_batch_reports_one_repeat_number_used_twice(tmp_path: Path) -> None:
    raw = tmp_path / "raw"
    for folder, src in (("a", R1), ("b", R2)):  # two runs, both named repeat 1
        (raw / folder).mkdir(parents=True)
        shutil.copyfile(src, raw / folder / R1.name)
    done = _batch(raw, tmp_path, "--glob", "*/*.csv", "--no-plots")
    assert done.exit_code == 0, done.output
    (line,) = [ln for ln in done.stdout.splitlines() if "warning:" in ln]
    assert "repeat 1 used by 2 runs of Dragonskin 30 on steel" in line or \
        "repeat 1 used by 2 runs of DS30 on steel" in line
    assert len(pd.read_parquet(tmp_path / "map.parquet")) == 2
