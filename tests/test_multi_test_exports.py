"""Session exports (several tests in one file) through the pipeline and ``tribopipe reduce``:
one run per friction interval of every test, each zeroed by its own set-up, a test without
a friction interval refused alone and by name, the same content under two names said so.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
from click.testing import CliRunner

from generators.synthetic import SyntheticTest, write_rheocompass_session
from multi_exports import (
    SESSION_TRUTH,
    run,
    session_tests,
    steps_test,
    write_session,
    write_xlsx_twin,
)
from tribopipe.cli import main
from tribopipe.config import load_settings
from tribopipe.errors import ReductionError
from tribopipe.frictionmap import measurement_id
from tribopipe.labels import LabelCheck, RunLabels
from tribopipe.pipeline import ReducedRun, read_runs, reduce_export, reduce_file

SETTINGS = load_settings()


@pytest.fixture(scope="module")
def raw(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("sessions")
    write_session(folder / "session.csv")
    write_session(folder / "session_fr.txt", language="fr")
    write_rheocompass_session(folder / "steps.csv", [steps_test()], project="steps")
    return folder


@pytest.mark.parametrize("name", ["session.csv", "session_fr.txt"])
def test_every_test_of_a_session_is_a_run_with_its_own_set_up_offset(raw: Path,
                                                                    name: str) -> None:
    result = reduce_export(raw / name, SETTINGS)
    export = read_runs(raw / name)
    assert result.ok and result.error is None
    assert result.tests == tuple(SESSION_TRUTH)
    assert [r.place.test for r in result.runs] == list(SESSION_TRUTH)
    for r in result.reduced:
        mu_s, mu_k, force, offset, setup = SESSION_TRUTH[r.place.test]
        assert r.summary["mu_k"] == pytest.approx(mu_k, abs=0.01)
        assert r.summary["mu_s"] == pytest.approx(mu_s, abs=0.02)
        assert r.summary["normal_force_N"] == pytest.approx(force, rel=0.01)
        params = r.summary["parameters"]
        if setup:  # the test's own set-up interval, never another test's
            assert params["torque_offset_source"] == "set-up interval 1"
            assert params["torque_offset_Nm"] == pytest.approx(offset, abs=5e-5)
            assert r.place.interval == 2
        else:
            assert params["torque_offset_source"].startswith("at-rest start")
            assert r.place.interval == 1
        assert r.name == f"{raw / name} [{r.place.test} / DS30 1 / interval {r.place.interval}]"
        assert r.measurement_id == measurement_id(export.file_hash,
                                                  dict(export.runs)[r.place].meta)
    assert len({r.measurement_id for r in result.reduced}) == 3


def test_force_steps_within_one_test_are_one_run_each(raw: Path) -> None:
    result = reduce_export(raw / "steps.csv", SETTINGS)
    assert [r.place.interval for r in result.runs] == [2, 3]
    three, five = (r.summary for r in result.reduced)
    assert (three["mu_k"], five["mu_k"]) == (pytest.approx(0.47, abs=0.01),
                                             pytest.approx(0.36, abs=0.01))
    assert five["normal_force_N"] == pytest.approx(5.0, rel=0.01)
    # the second step follows the first without a set-up: the test's set-up zeroes it
    assert five["parameters"]["torque_offset_source"] == "set-up interval 1"
    assert five["parameters"]["torque_offset_Nm"] == pytest.approx(2.5e-4, abs=5e-5)


def test_the_excel_twin_of_a_session_gives_the_same_runs(raw: Path, tmp_path: Path) -> None:
    xlsx = write_xlsx_twin(raw / "session.csv", tmp_path / "session.xlsx")
    text = reduce_export(raw / "session.csv", SETTINGS)
    excel = reduce_export(xlsx, SETTINGS)
    assert excel.ok and excel.tests == text.tests
    assert len(text.reduced) == len(text.runs)
    for a, b in zip(text.reduced, excel.reduced, strict=True):
        assert (a.place.test, a.place.interval) == (b.place.test, b.place.interval)
        assert b.summary["mu_k"] == pytest.approx(a.summary["mu_k"], abs=1e-9)
        assert b.summary["mu_s"] == pytest.approx(a.summary["mu_s"], abs=1e-9)


def test_a_failing_test_stands_alone(tmp_path: Path) -> None:
    """The middle test lost its contact (0.05 N, below the 0.2 N threshold): it fails by
    name, the two others are reduced."""
    tests = session_tests()
    tests[1] = SyntheticTest(tests[1].name, "DS30", (run(0.6, 0.47, 0.05, 9),))
    path = write_session(tmp_path / "lifted.csv", tests=tests)
    result = reduce_export(path, SETTINGS)
    assert [isinstance(r, ReducedRun) for r in result.runs] == [True, False, True]
    error = result.runs[1].reason
    assert error.count(str(path)) == 1 and "\n" not in error
    assert "DS30 on steel, 3 N, 20 °C, #1" in error and "contact threshold" in error
    # the failure is fields, formatted once: the file as named, where in it, what, the fix
    failure = result.runs[1].failure
    assert failure.path == str(path) and failure.place is not None
    assert "DS30 on steel, 3 N, 20 °C, #1" in failure.place
    assert failure.problem.startswith("the normal force never reaches the contact threshold")
    assert failure.hint and "contact_threshold_N" in failure.hint
    assert str(path) not in failure.problem and error == failure.text()
    shown = reduce_export(path, SETTINGS, name="lifted.csv").runs[1]
    assert shown.failure.path == "lifted.csv" and str(path) not in shown.reason
    assert shown.reason.startswith("lifted.csv [") and shown.failure.problem == failure.problem


def test_two_tests_of_one_name_get_two_ids_and_the_first_keeps_its_own(tmp_path: Path) -> None:
    same = SyntheticTest("friction", "pin", (run(0.8, 0.6, 3.0, 1),))
    again = SyntheticTest("friction", "pin", (run(0.7, 0.5, 3.0, 2),))
    path = write_rheocompass_session(tmp_path / "twice.csv", [same, again], project="p")
    export = read_runs(path)
    (p1, m1), (p2, m2) = export.runs
    assert (p1.occurrence, p2.occurrence) == (1, 2)
    result = reduce_export(path, SETTINGS)
    first, second = (r.measurement_id for r in result.reduced)
    assert first != second
    assert first == measurement_id(export.file_hash, m1.meta)  # as it always was


def test_reduce_file_refuses_an_export_of_several_runs_instead_of_picking_one(raw: Path) -> None:
    with pytest.raises(ReductionError, match=r"holds 3 run\(s\) in 3 test\(s\), not one"):
        reduce_file(raw / "session.csv", SETTINGS)


def test_the_real_two_test_export_says_once_that_it_is_no_friction_test(
        data_dir: Path) -> None:
    """A real session export of two stress-relaxation tests (torque, no normal force, no
    rotation). A user sees one line for the file, saying what its tests are."""
    path = data_dir / "rheocompass_en_utf16_two_tests.csv"
    result = reduce_export(path, SETTINGS)
    assert not result.ok and result.runs == ()
    assert result.error is not None
    assert result.error.reason.startswith(
        f"{path}: not a pin-on-disc friction test: its 2 tests")
    assert "stress relaxation" in result.error.reason


# --------------------------------------------------------------------------- the CLI


def reduce_cli(*args: str):
    return CliRunner().invoke(main, ["reduce", *args])


def test_reduce_json_gives_one_object_per_run(raw: Path, tmp_path: Path) -> None:
    result = reduce_cli(str(raw / "session.csv"), str(raw / "steps.csv"), "--json", "--no-map",
                        "--output", str(tmp_path / "o"))
    assert result.exit_code == 0, result.output
    rows = json.loads(result.stdout)
    assert len(rows) == 5
    for row in rows:
        assert {"file", "test", "result", "interval", "measurement_id"} <= set(row)
    assert [(Path(r["file"]).name, r["test"], r["interval"]) for r in rows] == [
        ("session.csv", name, 1 if name.startswith("DS30 on steel, 3") else 2)
        for name in SESSION_TRUTH] + [("steps.csv", "DS30 on steel, steps, 20 °C", 2),
                                      ("steps.csv", "DS30 on steel, steps, 20 °C", 3)]
    for row in rows[:3]:
        assert row["mu_k"] == pytest.approx(SESSION_TRUTH[row["test"]][1], abs=0.01)
    # one trace and one summary per run
    assert len(list((tmp_path / "o" / "traces").glob("*.parquet"))) == 5
    assert len(list((tmp_path / "o" / "summaries").glob("*.json"))) == 5


def test_reduce_table_shows_which_test_and_interval(raw: Path, tmp_path: Path) -> None:
    result = reduce_cli(str(raw / "session_fr.txt"), "--no-map", "--output", str(tmp_path / "o"))
    assert result.exit_code == 0, result.output
    header, *rows = result.stdout.splitlines()
    assert header.split()[:3] == ["file", "run", "mu_s"]
    assert len(rows) == 3
    assert "DS30 on steel, 5 N, 20 °C, #1 / interval 2" in rows[2]


def test_reduce_the_real_two_test_export_is_one_line_and_exit_1(data_dir: Path,
                                                                tmp_path: Path) -> None:
    path = data_dir / "rheocompass_en_utf16_two_tests.csv"
    result = reduce_cli(str(path), "--no-map", "--output", str(tmp_path / "o"))
    assert result.exit_code == 1
    errors = [line for line in result.stderr.splitlines() if line.startswith("error:")]
    assert len(errors) == 1
    assert "not a pin-on-disc friction test: its 2 tests" in errors[0]
    assert "1 error(s) in 1 of 1 file(s)" in result.stderr
    assert "Traceback" not in result.output


def test_reduce_a_copy_twice_is_one_duplicate_and_the_map_names_both(raw: Path,
                                                                     tmp_path: Path) -> None:
    first = tmp_path / "DS30_steel_r1.csv"
    shutil.copy(raw / "steps.csv", first)
    copy = tmp_path / "DS30_steel_r1 (copy).csv"
    shutil.copy(first, copy)
    map_path = tmp_path / "map.parquet"
    # one --force for both steps: the 5 N step contradicts it; kept, explicitly (flagged)
    labels = ["--keep-labels", "--pin", "DS30", "--disc", "steel", "--force", "3",
              "--temperature", "20", "--repeat", "1", "--map", str(map_path),
              "--output", str(tmp_path / "o")]
    both = reduce_cli(str(first), str(copy), *labels)
    assert both.exit_code == 0, both.output
    assert f"duplicate: {copy}: same content as {first}" in both.stderr
    assert len(pd.read_parquet(map_path)) == 2  # two steps, stored once

    # later, the copy alone, with the same labels: a duplicate of what the map holds
    again = reduce_cli(str(copy), *labels)
    assert again.exit_code == 0, again.output
    assert f"duplicate: {copy}: same content as {first.name}" in again.stderr
    # with other labels: a conflict, refused, named, exit 1; the map keeps the first's
    other = reduce_cli(str(copy), *labels[:-6], "--repeat", "2", *labels[-4:])
    assert other.exit_code == 1
    line = next(ln for ln in other.stderr.splitlines() if ln.startswith("conflict:"))
    assert str(copy) in line and first.name in line and "repeat 1 vs 2" in line
    runs = pd.read_parquet(map_path)
    assert set(runs["source_file"]) == {first.name} and set(runs["repeat"]) == {1}


@pytest.mark.slow  # a real process or a larger data set: `pytest -m slow`
def test_reduce_a_session_as_a_subprocess(raw: Path, tmp_path: Path) -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "tribopipe", "reduce", str(raw / "session.csv"), "--no-map",
         "--output", str(tmp_path / "o")],
        capture_output=True, text=True, encoding="utf-8", timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.strip().splitlines()
    assert lines[0].split()[:2] == ["file", "run"]
    assert len(lines) == 4 and all("session.csv" in ln for ln in lines[1:])
    assert "DS30 on steel, 1 N, 20 °C, #1 / interval 2" in lines[1]


def test_map_rows_keep_labels_given_per_run(raw: Path) -> None:
    labels = RunLabels(pin="Dragonskin 30", disc="steel", normal_force_N=3.0,
                       temperature_C=20.0, repeat=1)
    refused = reduce_export(raw / "steps.csv", SETTINGS, labels)
    # the 5 N step is not a 3 N run: refused, both forces named, the 3 N step lands
    assert [o.record.interval for o in refused.reduced] == [2]
    (failed,) = refused.failed
    assert "measured mean normal force 5 N is 67% off the label 3 N" in failed.reason
    result = reduce_export(raw / "steps.csv", SETTINGS, labels,
                           check=LabelCheck(keep_labels=True))
    records = [o.record for o in result.reduced]
    assert [r.interval for r in records] == [2, 3]
    # the 5 N step strays from the 3 N label: flagged, not silently averaged in
    assert "normal_force_off_nominal" not in records[0].flags.split(";")
    assert "normal_force_off_nominal" in records[1].flags.split(";")


def test_reduce_force_steps_without_force_gives_each_step_its_own_nominal(raw: Path,
                                                                       tmp_path: Path) -> None:
    labels = ["--pin", "Dragonskin 30", "--disc", "steel", "--temperature", "20"]
    result = reduce_cli(str(raw / "steps.csv"), *labels, "--json", "--map",
                        str(tmp_path / "m.parquet"), "--output", str(tmp_path / "o"))
    assert result.exit_code == 0, result.output
    runs = pd.read_parquet(tmp_path / "m.parquet").sort_values("interval")
    # the 3 N and 5 N steps, each estimated from its own measured force, and flagged so
    assert runs["normal_force_N"].tolist() == [3.0, 5.0]
    assert all("nominal_force_estimated" in f.split(";") for f in runs["flags"])
    # with --force every step is labelled alike: said, and the stray step flagged
    refused = reduce_cli(str(raw / "steps.csv"), *labels, "--force", "3", "--no-map",
                         "--output", str(tmp_path / "o3"))
    assert refused.exit_code == 1 and "67% off the label 3 N" in refused.stderr
    forced = reduce_cli(str(raw / "steps.csv"), *labels, "--force", "3", "--no-map",
                        "--keep-labels", "--output", str(tmp_path / "o2"))
    assert forced.exit_code == 0, forced.output
    assert "holds 2 friction intervals (force or speed steps): --force labels each alike" \
        in forced.stderr
