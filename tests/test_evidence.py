"""A package's evidence treated as hostile: every way a sender could make the recompute
agree with an edited row, or make it read outside the package, is refused by name."""

from __future__ import annotations

import csv
import io
import json
import shutil
from pathlib import Path

import pytest
from click.testing import CliRunner

from reduced_runs import RUNS, make_processed
from tribopipe.cli import main
from tribopipe.evidence import INDEX_PATH, SETTINGS_PATH, recompute_package
from tribopipe.frictionmap.datapackage import sha256_hash


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


@pytest.fixture(scope="module")
def package(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("evidence")
    map_path, _ = make_processed(root, RUNS[:3])
    out = root / "pkg"
    result = invoke("map", "publish", "-o", out, "--lab", "Lab E", "--map", map_path,
                    "--with-raw", "--raw-dir", root / "raw")
    assert result.exit_code == 0, result.output
    return out


def rehash(pkg: Path, path: str) -> None:
    desc = json.loads((pkg / "datapackage.json").read_text(encoding="utf-8"))
    data = (pkg / path).read_bytes()
    for res in desc["resources"]:
        if res["path"] == path:
            res["bytes"], res["hash"] = len(data), sha256_hash(data)
    (pkg / "datapackage.json").write_text(json.dumps(desc), encoding="utf-8")


def edit_index(pkg: Path, change) -> None:
    rows = list(csv.DictReader(io.StringIO((pkg / INDEX_PATH).read_text(encoding="utf-8"))))
    change(rows)
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=list(rows[0]), lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    (pkg / INDEX_PATH).write_text(buf.getvalue(), encoding="utf-8")
    rehash(pkg, INDEX_PATH)


@pytest.fixture()
def copy(package, tmp_path) -> Path:
    target = tmp_path / "pkg"
    shutil.copytree(package, target)
    return target


def test_settings_edited_to_fit_are_refused(copy):
    settings = json.loads((copy / SETTINGS_PATH).read_text(encoding="utf-8"))
    key = next(iter(settings))
    settings[key]["instrument"]["friction_radius_mm"] = 12.0
    (copy / SETTINGS_PATH).write_text(json.dumps(settings), encoding="utf-8")
    rehash(copy, SETTINGS_PATH)
    again = recompute_package(copy)
    assert not again.ok
    assert any("these settings hash to" in line and key in line for line in again.lines())
    # without the settings no row can be re-derived, and the account says why
    assert any("the settings that reduced them are not in the package" in line
               for line in again.account())


def test_a_trace_replaced_is_named(copy):
    rows = list(csv.DictReader(io.StringIO((copy / INDEX_PATH).read_text(encoding="utf-8"))))
    first, second = rows[0], rows[1]
    shutil.copyfile(copy / second["trace_path"], copy / first["trace_path"])
    shutil.copyfile(copy / second["raw_path"], copy / first["raw_path"])
    again = recompute_package(copy)
    lines = [line for line in again.lines() if first["measurement_id"] in line]
    assert lines and "SHA-256" in lines[0]


def test_an_index_that_points_outside_the_package_is_refused(copy, tmp_path):
    secret = tmp_path / "secret.parquet"
    secret.write_bytes(b"PAR1 not yours")

    def outside(rows):
        rows[0]["raw_path"] = ""
        rows[0]["trace_path"] = "evidence/../../secret.parquet"
        rows[0]["trace_sha256"] = sha256_hash(secret.read_bytes())[7:]

    edit_index(copy, outside)
    result = invoke("map", "validate", "--recompute", copy)
    assert result.exit_code == 1
    line = next(x for x in result.output.splitlines() if x.startswith(f"{INDEX_PATH}: run "))
    assert "'..' segment; expected a path inside the package" in line
    assert "not yours" not in result.output


def test_raw_export_of_another_run_is_refused(copy):
    def swap(rows):
        rows[0]["raw_path"], rows[0]["raw_sha256"] = rows[1]["raw_path"], rows[1]["raw_sha256"]

    edit_index(copy, swap)
    again = recompute_package(copy)
    assert any("its SHA-256 differs from file_hash" in line for line in again.lines())


def test_an_index_row_that_is_not_a_run_id_is_named(copy):
    def bad(rows):
        rows[0]["measurement_id"] = "../../x"

    edit_index(copy, bad)
    again = recompute_package(copy)
    assert any("is not a run id" in line for line in again.lines())


def test_recompute_of_a_map_file_says_what_it_takes(package):
    result = invoke("map", "validate", "--recompute", package / "data/runs.parquet")
    assert result.exit_code == 2
    assert "--recompute checks a package against its evidence" in result.output


def test_another_method_is_said_and_a_false_one_refused(copy):
    settings = json.loads((copy / SETTINGS_PATH).read_text(encoding="utf-8"))
    key = next(iter(settings))
    settings[key]["method"] = "tribopipe-v1"
    (copy / SETTINGS_PATH).write_text(json.dumps(settings), encoding="utf-8")
    rehash(copy, SETTINGS_PATH)
    again = recompute_package(copy)
    # the rows say they were reduced by today's method: the settings cannot say otherwise
    assert not again.ok
    assert len([x for x in again.lines() if "its settings in evidence/settings.json say "
                "'tribopipe-v1'" in x]) == 3
    assert any("reduced by method 'tribopipe-v1', which this tribopipe" in line
               for line in again.account())


def test_publish_says_which_evidence_it_could_not_find(tmp_path):
    map_path, processed = make_processed(tmp_path, RUNS[:2])
    shutil.rmtree(processed / "traces")
    result = invoke("map", "publish", "-o", tmp_path / "pkg", "--lab", "Lab E",
                    "--map", map_path, "--with-raw", "--raw-dir", tmp_path / "raw")
    assert result.exit_code == 0, result.output
    assert "evidence: 0 traces, 2 raw exports" in result.output
    assert f"note: 2 of 2 reduced runs have no trace under {processed / 'traces'}" \
        in result.output
    again = recompute_package(tmp_path / "pkg")
    assert again.ok and [r.basis for r in again.rows] == ["raw export"] * 2


def test_publish_lists_the_traces_folder_once_and_finds_each_runs_trace(tmp_path, monkeypatch):
    """Each run's trace is the one :func:`~tribopipe.layout.find_trace` finds, from one
    listing of the folder (a listing per run would grow as the square of the runs)."""
    from tribopipe import frictionmap as fm
    from tribopipe.evidence import gather_evidence
    from tribopipe.layout import find_trace

    map_path, processed = make_processed(tmp_path, RUNS[:3])
    runs = fm.read_map(map_path)
    traces = processed / "traces"
    want = {str(m): find_trace(traces, str(m)) for m in runs["measurement_id"]}
    assert len(want) == 3 and all(p is not None for p in want.values())
    listings: list[str] = []
    glob = Path.glob

    def counted(self: Path, pattern: str, *args, **kwargs):
        listings.append(pattern)
        return glob(self, pattern, *args, **kwargs)

    monkeypatch.setattr(Path, "glob", counted)
    evidence = gather_evidence(runs, traces_dir=traces)
    assert {f.measurement_id: f.trace for f in evidence.files} == want
    assert len(listings) == 1, listings
