"""A file's name is stored raw and compared raw; only outputs escape it.

A file whose name holds U+202E or a newline is reduced like any other: reduced again it
is the same file (its rows unchanged), relabelled with ``--replace`` its rows are
replaced, and never "same content as <itself>".
"""

from __future__ import annotations

import os
from pathlib import Path

import pandas as pd
import pytest

from helpers import reduce_cli
from hostile import good_export, invoke
from tribopipe.frictionmap.records import stored_file_name

NAMES = ["evil\u202etxt.csv", "two\nlines.csv", "cr\rname.csv"]


def _reduce(export: Path, map_path: Path, out: Path, *extra: str):
    return reduce_cli(export, "--pin", "DS30", "--disc", "steel", "--temperature", "20",
                      "--map", map_path, "--output", out, *extra)


def _lines_are_printable(stderr: str) -> None:
    for line in stderr.splitlines():
        assert line.isprintable(), repr(line)


@pytest.mark.parametrize("name", NAMES, ids=["rlo", "newline", "cr"])
def test_a_hostile_file_name_is_the_same_file_reduced_again(tmp_path: Path, name: str) -> None:
    export = good_export(tmp_path / name)
    map_path, out = tmp_path / "m.parquet", tmp_path / "out"
    first = _reduce(export, map_path, out, "--force", "3")
    assert first.exit_code == 0, first.output
    assert "1 added" in first.stderr
    assert list(pd.read_parquet(map_path)["source_file"]) == [name]   # raw, not escaped

    again = _reduce(export, map_path, out, "--force", "3")
    assert again.exit_code == 0, again.output
    assert "duplicate" not in again.stderr and "same content" not in again.stderr
    assert "0 added, 1 unchanged" in again.stderr
    _lines_are_printable(again.stderr)

    relabelled = _reduce(export, map_path, out, "--force", "9", "--replace", "--keep-labels")
    assert relabelled.exit_code == 0, relabelled.output
    assert "same content" not in relabelled.stderr, relabelled.stderr
    assert "1 replaced" in relabelled.stderr
    _lines_are_printable(relabelled.stderr)
    runs = pd.read_parquet(map_path)
    assert list(runs["source_file"]) == [name] and list(runs["normal_force_N"]) == [9.0]


def test_a_copy_under_another_name_is_still_a_duplicate(tmp_path: Path) -> None:
    export = good_export(tmp_path / NAMES[0])
    copy = tmp_path / "copy\u202e.csv"
    copy.write_bytes(export.read_bytes())
    map_path, out = tmp_path / "m.parquet", tmp_path / "out"
    assert _reduce(export, map_path, out, "--force", "3").exit_code == 0
    second = _reduce(copy, map_path, out, "--force", "3")
    assert second.exit_code == 0, second.output
    assert "duplicate:" in second.stderr and "evil\\u202etxt.csv" in second.stderr
    _lines_are_printable(second.stderr)
    assert list(pd.read_parquet(map_path)["source_file"]) == [NAMES[0]]


def test_stored_file_name_keeps_the_name_and_only_undecodable_bytes_as_text() -> None:
    assert stored_file_name("/x/evil\u202e\n.csv") == "evil\u202e\n.csv"
    odd = os.fsdecode(b"/x/run_\xff\xfe.csv")
    assert stored_file_name(odd) == "run_\\xff\\xfe.csv"
    assert stored_file_name(odd).encode("utf-8")                     # storable text


# ---------------------------------------------------------------------------- messages


def test_a_note_naming_a_file_with_a_newline_stays_one_line(tmp_path: Path) -> None:
    from generators.synthetic import write_rheocompass_session
    from multi_exports import steps_test

    raw = write_rheocompass_session(tmp_path / "two\nsteps\u202e.csv", [steps_test()],
                                    project="steps")
    result = invoke("reduce", str(raw), "--pin", "DS30", "--disc", "steel", "--force", "3",
                    "--keep-labels", "--no-map", "--output", str(tmp_path / "o"))
    assert result.exit_code == 0, result.output
    _lines_are_printable(result.stderr)
    (note,) = [ln for ln in result.stderr.splitlines() if "friction intervals" in ln]
    assert note.startswith("note: ") and "two\\nsteps\\u202e.csv holds 2" in note


def test_written_paths_are_one_line_each(tmp_path: Path) -> None:
    export = good_export(tmp_path / "run.csv")
    map_path = tmp_path / "m.parquet"
    assert _reduce(export, map_path, tmp_path / "o", "--force", "3").exit_code == 0
    target = tmp_path / "deck\n\u202e.inp"
    result = invoke("export", "abaqus", "--map", str(map_path), "-o", str(target))
    assert result.exit_code == 0, result.output
    assert target.is_file()
    _lines_are_printable(result.stderr)
    assert "wrote " in result.stderr and "deck\\n\\u202e.inp" in result.stderr


def test_a_crashed_worker_names_its_file_in_one_line() -> None:
    from tribopipe.campaign.worker import Job, crashed

    (done,) = crashed([Job(file="a\nb\u202e.csv", path="/x/a\nb\u202e.csv", sources=(),
                            hints=())], RuntimeError("killed\nby the OOM killer"))
    reason = done.error.reason
    assert reason.isprintable() and reason.startswith("a\\nb\\u202e.csv: worker process")


def test_batch_after_its_state_is_lost_finds_the_same_file_not_a_duplicate(
        tmp_path: Path) -> None:
    """The batch checks a file against the map's files when its state does not know it:
    the same file (raw name) is the same, not 'same content as <itself>'."""
    raw = tmp_path / "raw"
    raw.mkdir()
    good_export(raw / "P_D_3N_20C_r1_x\u202ey.csv")
    cfg = tmp_path / "c.toml"
    cfg.write_text('[campaign]\nname = "c"\nraw_dir = "raw"\noutput_dir = "out"\n'
                   'filename_pattern = "{pin}_{disc}_{force}N_{temperature}C_r{repeat}_{note}"'
                   "\nplots = false\n", encoding="utf-8")
    (tmp_path / "materials.toml").write_text(
        '[materials]\nP = { class = "other" }\nD = { class = "other" }\n', encoding="utf-8")
    first = invoke("batch", str(cfg), "--jobs", "1")
    assert first.exit_code == 0, first.output
    for state in (tmp_path / "out").glob(".tribopipe-state*"):
        state.unlink()
    again = invoke("batch", str(cfg), "--jobs", "1")
    assert again.exit_code == 0, again.output
    assert "duplicate" not in again.output and "same content" not in again.output
    assert "1 reduced" in again.output and "0 added, 1 unchanged" in again.output
    _lines_are_printable(again.output)
    runs = pd.read_parquet(tmp_path / "out" / "friction_map.parquet")
    assert list(runs["source_file"]) == ["P_D_3N_20C_r1_x\u202ey.csv"]


def test_every_output_of_a_raw_name_shows_it_escaped(tmp_path: Path) -> None:
    """The map keeps the name raw; map show, the tables, the explorer page and the
    report write it escaped for their kind (no raw U+202E or line break anywhere)."""
    name = "rlo\u202e\nx<b>.csv"
    export = good_export(tmp_path / name)
    map_path, out = tmp_path / "out" / "friction_map.parquet", tmp_path / "out"
    assert _reduce(export, map_path, out, "--force", "3", "--plot").exit_code == 0
    shown = invoke("map", "show", "--runs", "--map", str(map_path))
    assert shown.exit_code == 0, shown.output
    assert "rlo\\u202e\\nx<b>.csv" in shown.stdout
    _lines_are_printable(shown.stdout)
    table = invoke("map", "table", "--format", "frictionmap", "--map", str(map_path))
    assert "\u202e" not in table.stdout
    page, report = tmp_path / "explorer.html", tmp_path / "report.html"
    assert invoke("explore", "--map", str(map_path), "-o", str(page)).exit_code == 0
    made = invoke("report", "--map", str(map_path), "--processed", str(out), "-o", str(report))
    assert made.exit_code == 0, made.output
    for html in (page.read_text(encoding="utf-8"), report.read_text(encoding="utf-8")):
        assert "\u202e" not in html and "<b>" not in html
    assert "rlo\\u202e\\nx&lt;b&gt;.csv" in report.read_text(encoding="utf-8")
