"""No cell of a package grows with the number of runs: the group table numbers its groups
and ``data/group_runs.csv`` lists each group's runs, one row per (group, run). A group of
more runs than one CSV cell may hold (the package check caps a cell at 10,000 characters:
about 530 joined run ids) publishes, validates and merges; a linking table that does not
match the runs is refused, one line per fault; a package of profile version 2 (the runs
joined into one cell) still reads, validates and merges, and says it was upgraded."""

from __future__ import annotations

import csv
import io
import json
import shutil
import uuid
from pathlib import Path

import pytest
from click.testing import CliRunner

from reduced_runs import make_processed
from tribopipe import frictionmap as fm
from tribopipe.cli import main
from tribopipe.frictionmap.datapackage import DEFAULT_LIMITS, sha256_hash
from tribopipe.frictionmap.package import check_package
from tribopipe.frictionmap.profile import PROFILE_VERSION

DATA = Path(__file__).parent / "data"
#: more runs in one group than one cell of 10,000 characters can list (17 per id)
BIG_GROUP = 1_200


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


def one_group_records(template: dict, n: int) -> list[dict]:
    """``n`` copies of a real reduced record, all in its condition group, each with its own
    id, file, hash and repeat number."""
    out = []
    for i in range(n):
        r = dict(template)
        r["measurement_id"] = uuid.UUID(int=i + 1).hex[-16:]
        r["file_hash"] = uuid.UUID(int=(i + 1) << 64).hex * 2
        r["source_file"] = f"big/run_{i:05d}.csv"
        r["repeat"] = i + 1
        r["mu_k"] = 0.5 + 0.001 * (i % 17)
        out.append(r)
    return out


@pytest.fixture(scope="module")
def big_package(tmp_path_factory) -> tuple[Path, Path]:
    root = tmp_path_factory.mktemp("biggroup")
    small, _ = make_processed(root / "small")
    template = fm.schema.frame_records(fm.read_map(small))[0]
    map_path = root / "big.parquet"
    fm.update_map(map_path, one_group_records(template, BIG_GROUP))
    out = root / "pkg"
    result = invoke("map", "publish", "--map", map_path, "-o", out, "--lab", "Lab G",
                    "--no-evidence")
    assert result.exit_code == 0, result.output
    return map_path, out


def rows(path: Path) -> list[list[str]]:
    return list(csv.reader(io.StringIO(path.read_text(encoding="utf-8"))))


def rehash(pkg: Path, path: str) -> None:
    data = json.loads((pkg / "datapackage.json").read_text(encoding="utf-8"))
    raw = (pkg / path).read_bytes()
    for res in data["resources"]:
        if res["path"] == path:
            res["bytes"], res["hash"] = len(raw), sha256_hash(raw)
    (pkg / "datapackage.json").write_text(json.dumps(data, indent=1), encoding="utf-8")


def write_rows(path: Path, table: list[list[str]]) -> None:
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerows(table)
    path.write_text(buf.getvalue(), encoding="utf-8")


def test_a_group_of_more_runs_than_a_cell_holds_publishes_validates_and_merges(
        big_package, tmp_path):
    map_path, pkg = big_package
    groups = rows(pkg / "data" / "groups.csv")
    assert groups[0][0] == "group" and len(groups) == 2
    assert not {"run_ids", "mu_k_values", "mu_s_values"} & set(groups[0])
    longest = max(len(cell) for path in (pkg / "data").glob("*.csv") for row in rows(path)
                  for cell in row)
    assert longest < 200 < DEFAULT_LIMITS.cell_chars
    links = rows(pkg / "data" / "group_runs.csv")
    assert links[0] == ["group", "measurement_id"] and len(links) == BIG_GROUP + 1
    assert {r[0] for r in links[1:]} == {"1"}
    assert {r[1] for r in links[1:]} == set(fm.read_map(map_path)["measurement_id"])
    result = invoke("map", "validate", pkg)
    assert result.exit_code == 0, result.output
    assert f"valid friction-map package from Lab G, {BIG_GROUP} runs" in result.output
    merged = tmp_path / "merged.parquet"
    result = invoke("map", "merge", pkg, "--map", merged)
    assert result.exit_code == 0, result.output
    assert f"{BIG_GROUP} added, 0 unchanged" in result.output
    assert len(fm.read_map(merged)) == BIG_GROUP


def test_the_package_is_of_the_current_profile_and_its_keys_are_declared(big_package):
    _, pkg = big_package
    d = json.loads((pkg / "datapackage.json").read_text(encoding="utf-8"))
    assert d["tribopipe"]["profile_version"] == PROFILE_VERSION == 3
    by_name = {r["name"]: r for r in d["resources"]}
    assert by_name["groups"]["schema"]["primaryKey"] == "group"
    link = by_name["group-runs"]["schema"]
    assert link["primaryKey"] == "measurement_id"
    assert {(k["fields"], k["reference"]["resource"]) for k in link["foreignKeys"]} == {
        ("group", "groups"), ("measurement_id", "runs")}


@pytest.fixture()
def copy(big_package, tmp_path) -> Path:
    target = tmp_path / "pkg"
    shutil.copytree(big_package[1], target)
    return target


def test_a_run_listed_twice_or_unknown_or_missing_is_said_once_each(copy):
    path = copy / "data" / "group_runs.csv"
    table = rows(path)
    table[2][1] = table[1][1]              # row 2 lists row 1's run again
    table[3][1] = "ffffffffffffffff"       # row 3 lists no run of the map
    table[4][0] = "7"                      # row 4 names no group
    write_rows(path, table)
    rehash(copy, "data/group_runs.csv")
    check = check_package(copy)
    lines = check.lines()
    assert not check.ok
    assert ("data/group_runs.csv: row 2, field measurement_id: run "
            f"{table[1][1]!r} is listed twice (first in row 1)") in lines
    assert ("data/group_runs.csv: row 3, field measurement_id: 'ffffffffffffffff' is not "
            "an included run of the runs table") in lines
    assert "data/group_runs.csv: row 4, field group: 7 is not a group of data/groups.csv" \
        in lines
    assert (f"data/group_runs.csv: group 1: lists {BIG_GROUP - 3} run(s), the group's "
            f"conditions in the runs table make {BIG_GROUP} (3 of them not listed, 0 listed "
            "that belong to another group)") in lines
    assert len(lines) == 4


def test_a_group_numbered_from_zero_is_refused_by_the_declared_minimum(copy):
    for name in ("groups.csv", "group_runs.csv"):
        path = copy / "data" / name
        table = rows(path)
        for row in table[1:]:
            row[0] = str(int(row[0]) - 1)    # the one group becomes group 0
        write_rows(path, table)
        rehash(copy, f"data/{name}")
    lines = check_package(copy).lines()
    assert ("data/groups.csv: row 1, field group: 0 is not a group number (expected 1 or "
            "more)") in lines


def test_a_group_number_that_is_not_a_whole_number_is_named_with_what_was_expected(copy):
    path = copy / "data" / "group_runs.csv"
    table = rows(path)
    table[5][0] = "one"
    write_rows(path, table)
    rehash(copy, "data/group_runs.csv")
    lines = check_package(copy).lines()
    assert any(line.startswith("data/group_runs.csv: row 5, field group: ")
               and line.endswith("expected an integer") for line in lines), lines


def test_a_group_table_without_its_linking_table_is_refused(copy):
    d = json.loads((copy / "datapackage.json").read_text(encoding="utf-8"))
    d["resources"] = [r for r in d["resources"] if r["name"] != "group-runs"]
    (copy / "datapackage.json").write_text(json.dumps(d), encoding="utf-8")
    result = invoke("map", "validate", copy)
    assert result.exit_code == 1
    assert ("datapackage.json: resource 'groups' without 'group-runs' (the runs of each "
            "group), which package profile version 3 requires beside it") in result.output


def test_a_group_table_without_numbers_is_refused(copy):
    path = copy / "data" / "groups.csv"
    table = [row[1:] for row in rows(path)]
    write_rows(path, table)
    d = json.loads((copy / "datapackage.json").read_text(encoding="utf-8"))
    for res in d["resources"]:
        if res["name"] == "groups":
            res["schema"]["fields"] = res["schema"]["fields"][1:]
            del res["schema"]["primaryKey"]
    (copy / "datapackage.json").write_text(json.dumps(d), encoding="utf-8")
    rehash(copy, "data/groups.csv")
    lines = check_package(copy).lines()
    assert lines == ["data/groups.csv: schema: expected the field 'group' (integer), the "
                     "group's number, which package profile version 3 requires"]


def test_a_profile_2_package_reads_validates_merges_and_says_it_was_upgraded(tmp_path):
    pkg = DATA / "package_profile2"
    header = rows(pkg / "data" / "groups.csv")[0]
    assert "run_ids" in header and "group" not in header  # the cells that grew
    check = check_package(pkg)
    assert check.ok and check.profile_version == 2 and len(check.runs) == 6
    result = invoke("map", "validate", pkg)
    assert result.exit_code == 0, result.output
    first = result.output.splitlines()[0]
    assert first.startswith("note: package profile version 2 (version 1 plus the profile")
    assert (f"read as version {PROFILE_VERSION}: its group table joins each group's run ids "
            "and values into one cell") in first
    assert "evidence" not in first.split("read as version")[1]  # it may carry evidence
    merged = tmp_path / "merged.parquet"
    result = invoke("map", "merge", pkg, "--map", merged)
    assert result.exit_code == 0, result.output
    assert "6 added, 0 unchanged" in result.output


def test_a_profile_2_group_table_that_does_not_follow_from_its_runs_is_still_refused(tmp_path):
    target = tmp_path / "pkg"
    shutil.copytree(DATA / "package_profile2", target)
    path = target / "data" / "groups.csv"
    table = rows(path)
    n = table[0].index("mu_k_n")
    table[1][n] = "5"
    write_rows(path, table)
    rehash(target, "data/groups.csv")
    lines = check_package(target).lines()
    assert lines == ["data/groups.csv: row 1, field mu_k_n: 5 does not follow from the runs "
                     "(2)"]


# --------------------------------------------------------------------------- streamed checks


def test_a_group_table_s_parquet_copy_with_other_values_is_named_cell_by_cell(copy):
    """groups.parquet is the group table again: a copy whose μ_K mean was changed (and
    re-hashed) names the cell, with the CSV's value beside it."""
    import pandas as pd

    path = copy / "data" / "groups.parquet"
    groups = pd.read_parquet(path)
    csv_mean = float(rows(copy / "data" / "groups.csv")[1][
        rows(copy / "data" / "groups.csv")[0].index("mu_k_mean")])
    groups.loc[0, "mu_k_mean"] = 0.987
    groups.to_parquet(path, index=False)
    rehash(copy, "data/groups.parquet")
    lines = check_package(copy).lines()
    assert lines == [f"data/groups.parquet: row 1, field mu_k_mean: 0.987 differs from the "
                     f"CSV's {csv_mean!r}"]


def test_a_parquet_copy_with_other_rows_is_named_cell_by_cell(copy, tmp_path):
    """The Parquet copy is read a column at a time: a copy written as a valid map of other
    values names each differing cell; one whose rows do not match its own checksum is
    said to fail it."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    path = copy / "data" / "runs.parquet"
    runs = fm.read_map(path)
    runs.loc[[3, 7], "mu_k"] = 0.9
    path.unlink()
    fm.store.write_map_copy(path, runs)
    rehash(copy, "data/runs.parquet")
    table = rows(copy / "data" / "runs.csv")
    mu_k = table[0].index("mu_k")
    assert check_package(copy).lines() == [
        f"data/runs.parquet: row {i}, field mu_k: 0.9 differs from the CSV's "
        f"{float(table[i][mu_k])!r}" for i in (4, 8)]
    arrow = pq.read_table(path)
    scaled = pa.array(fm.read_map(path)["mu_k"].mul(1.5).to_numpy())
    pq.write_table(arrow.set_column(arrow.schema.get_field_index("mu_k"), "mu_k", scaled),
                   path)
    rehash(copy, "data/runs.parquet")
    assert check_package(copy).lines() == [
        "data/runs.parquet: fails its checksum: its rows are not those tribopipe wrote "
        "(damaged, or changed by another program)"]


def test_the_streamed_csv_writer_writes_each_cell_as_package_cell(big_package):
    """``write_table_csv`` (column-wise, in batches) writes what ``package_cell`` writes
    cell by cell, for every kind: the published runs.csv, and a table with missing and
    odd values."""
    import numpy as np
    import pandas as pd

    from tribopipe.export.publish import CSV_BATCH_ROWS, package_cell, table_csv

    map_path, pkg = big_package
    runs = fm.read_map(pkg / "data" / "runs.parquet")
    kinds = [fm.schema.KIND[c] for c in fm.schema.RUN_COLUMNS]
    by_cell = [list(fm.schema.RUN_COLUMNS)] + [
        [package_cell(v, k) for v, k in zip(row, kinds, strict=True)]
        for row in runs.itertuples(index=False, name=None)]
    assert rows(pkg / "data" / "runs.csv") == by_cell
    odd = pd.DataFrame({
        "f": np.array([0.1, np.nan, 1e-300, -0.0, 3.0] * (CSV_BATCH_ROWS // 2)),
        "i": pd.array([1, None, -5, 0, 10**12] * (CSV_BATCH_ROWS // 2), dtype="Int64"),
        "b": np.array([True, False, True, False, True] * (CSV_BATCH_ROWS // 2)),
        "s": pd.array(["a,b", None, "", 'q"uote', "ü\nline"] * (CSV_BATCH_ROWS // 2),
                      dtype="str")})
    text = table_csv(odd, ["float", "int", "bool", "str"])
    expected = [["f", "i", "b", "s"]] + [
        [package_cell(v, k) for v, k in zip(row, ["float", "int", "bool", "str"],
                                           strict=True)]
        for row in odd.itertuples(index=False, name=None)]
    assert list(csv.reader(io.StringIO(text))) == expected


def test_a_package_s_explorer_runs_beside_its_page_are_resources(big_package, monkeypatch,
                                                                 tmp_path):
    """Above the explorer's inline limit a package's page carries groups and fits only,
    and each pair's runs lie beside it, each file a resource with its size and SHA-256."""
    import functools

    from tribopipe.export import explorer, publish

    monkeypatch.setattr(publish, "explorer_parts",
                        functools.partial(explorer.explorer_parts, runs_inline_limit=0))
    map_path, _ = big_package
    out = tmp_path / "pkg"
    result = invoke("map", "publish", "--map", map_path, "-o", out, "--lab", "Lab G",
                    "--no-evidence")
    assert result.exit_code == 0, result.output
    d = json.loads((out / "datapackage.json").read_text(encoding="utf-8"))
    beside = [r for r in d["resources"] if r["path"].startswith("explorer_runs/")]
    assert [r["path"] for r in beside] == ["explorer_runs/pair-0.js"]
    assert beside[0]["hash"] == sha256_hash((out / "explorer_runs/pair-0.js").read_bytes())
    page = (out / "explorer.html").read_text(encoding="utf-8")
    assert '"runs_beside":"explorer_runs"' in page and "tpx-runs-0" not in page
    assert check_package(out).ok
