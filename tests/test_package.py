"""A contribution is a data package: ``map publish`` → ``map validate`` → ``map merge``, as a
lab would run them (click's CliRunner and a real process), on a real map of reduced runs and
the published rows; tampered and hostile packages, each refused in its one line."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
from click.testing import CliRunner

from map_files import single_file
from reduced_runs import make_processed
from tribopipe import frictionmap as fm
from tribopipe.cli import main
from tribopipe.export.citation import Publisher, yaml_text
from tribopipe.export.publish import package_runs_table, publish_map
from tribopipe.frictionmap.datapackage import PackageLimits, sha256_hash
from tribopipe.validate import MU

LAB = "Soft Robotics Lab, Example University"


def invoke(*args: str):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


@pytest.fixture(scope="module")
def source_map(tmp_path_factory) -> Path:
    """A real map: six reduced synthetic runs (with traces) and the 169 published rows."""
    map_path, _ = make_processed(tmp_path_factory.mktemp("lab"))
    fm.import_table(map_path)
    return map_path


@pytest.fixture(scope="module")
def package(source_map, tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("publish") / "contribution"
    result = invoke("map", "publish", "-o", out, "--lab", LAB, "--contact", "Ada Lovelace",
                    "--email", "ada@example.org", "--map", source_map)
    assert result.exit_code == 0, result.output
    assert "175 runs in 13 files" in result.output
    assert "evidence: 6 traces, 0 raw exports" in result.output
    return out


@pytest.fixture()
def copy(package, tmp_path) -> Path:
    """A copy of the package to tamper with."""
    target = tmp_path / "pkg"
    shutil.copytree(package, target)
    return target


def descriptor(pkg: Path) -> dict:
    return json.loads((pkg / "datapackage.json").read_text(encoding="utf-8"))


def save_descriptor(pkg: Path, data: dict) -> None:
    (pkg / "datapackage.json").write_text(json.dumps(data, indent=1), encoding="utf-8")


def rehash(pkg: Path, path: str) -> None:
    """Update the size and SHA-256 of ``path`` in the descriptor, as a sender whose tool
    wrote a bad file honestly would."""
    data = descriptor(pkg)
    raw = (pkg / path).read_bytes()
    for res in data["resources"]:
        if res["path"] == path:
            res["bytes"], res["hash"] = len(raw), sha256_hash(raw)
    save_descriptor(pkg, data)


def edit_runs_csv(pkg: Path, row: int, column: str, value: str) -> None:
    """Set one cell of data/runs.csv (row counted from 1 after the header) and rehash."""
    path = pkg / "data" / "runs.csv"
    table = pd.read_csv(path, dtype=str, keep_default_na=False)
    table.loc[row - 1, column] = value
    path.write_text(table.to_csv(index=False, lineterminator="\n"), encoding="utf-8")
    rehash(pkg, "data/runs.csv")


def validate(pkg: Path) -> tuple[int, list[str]]:
    result = invoke("map", "validate", pkg)
    return result.exit_code, result.output.splitlines()


# --------------------------------------------------------------------------- round trip


def test_publish_validate_merge_round_trip_gives_identical_runs(source_map, package, tmp_path):
    files = sorted(str(p.relative_to(package)) for p in package.rglob("*") if p.is_file())
    evidence = [f for f in files if f.startswith("evidence/")]
    assert "profile/package-v3.schema.json" in files
    files = [f for f in files if not f.startswith(("evidence/", "profile/"))]
    assert len([f for f in evidence if f.startswith("evidence/traces/")]) == 6
    assert "evidence/index.csv" in evidence and "evidence/settings.json" in evidence
    assert files == ["CITATION.cff", "README.md", "data/frictionmap.csv",
                     "data/group_runs.csv", "data/groups.csv",
                     "data/groups.parquet", "data/runs.csv", "data/runs.parquet",
                     "datapackage.json", "explorer.html"]
    code, lines = validate(package)
    # the package carries the paper's rows too: the line says who measured how many
    assert code == 0 and lines == [
        f"{package / 'datapackage.json'}: valid friction-map package from {LAB}, 175 runs: "
        f"169 measured by {fm.published.PUBLISHED_LAB}, 6 measured by {LAB}"]
    merged = tmp_path / "empty" / "friction_map.parquet"
    result = invoke("map", "merge", package, "--map", merged)
    assert result.exit_code == 0, result.output
    assert "175 added, 0 unchanged, 0 replaced, 0 kept conflicting" in result.output
    expected = package_runs_table(fm.read_map(source_map), LAB)
    pd.testing.assert_frame_equal(fm.read_map(merged), expected)
    # each lab's provenance: ours named, the paper's rows keep their authors
    labs = fm.read_map(merged).groupby("source")["lab"].unique()
    assert list(labs["reduced"]) == [LAB]
    assert list(labs[fm.schema.SOURCE_PUBLISHED]) == [fm.published.PUBLISHED_LAB]
    shown = invoke("map", "show", "--map", merged).output
    assert f"lab {LAB}: 6 runs" in shown and f"lab {fm.published.PUBLISHED_LAB}: 169 runs" in shown
    # merging it again, or into the map it came from, changes nothing
    again = invoke("map", "merge", package / "datapackage.json", "--map", source_map)
    assert again.exit_code == 0 and "0 added, 175 unchanged" in again.output


def test_the_runs_parquet_is_itself_a_friction_map(package):
    runs = fm.read_map(package / "data" / "runs.parquet")
    assert len(runs) == 175 and runs["lab"].notna().all()


def test_descriptor_has_schema_units_licence_and_citation_per_resource(package):
    d = descriptor(package)
    assert d["profile"] == "data-package" and d["tribopipe"]["lab"] == LAB
    assert d["tribopipe"]["schema_version"] == fm.schema.SCHEMA_VERSION
    assert d["licenses"][0]["name"] == "CC-BY-4.0"
    for res in d["resources"]:
        assert res["licenses"] and res["sources"], res["name"]
        raw = (package / res["path"]).read_bytes()
        assert res["bytes"] == len(raw) and res["hash"] == sha256_hash(raw)
    fields = {f["name"]: f for f in d["resources"][0]["schema"]["fields"]}
    assert fields["pressure_kPa"]["unit"] == "kPa"
    assert fields["temperature_C"]["unit"] == "°C"
    assert fields["mu_k"]["constraints"] == {"required": True, "minimum": 0.0,
                                             "maximum": MU.high}
    titles = " ".join(s["title"] for s in d["sources"])
    assert fm.published.FOUNDING_PAPER["title"] in titles
    assert "CC-BY-4.0" in (package / "README.md").read_text(encoding="utf-8")


def test_the_frictionless_library_finds_the_package_valid(package):
    frictionless = pytest.importorskip("frictionless", reason="frictionless (test extra)")
    report = frictionless.validate(str(package / "datapackage.json"))
    assert report.valid, report.flatten(["title", "message"])[:5]
    # and it sees a changed byte too, so its verdict above means something
    tampered = package.parent / "tampered"
    shutil.copytree(package, tampered)
    raw = bytearray((tampered / "data" / "groups.csv").read_bytes())
    raw[-3] = ord("7") if raw[-3] != ord("7") else ord("8")
    (tampered / "data" / "groups.csv").write_bytes(bytes(raw))
    assert not frictionless.validate(str(tampered / "datapackage.json")).valid


@pytest.mark.slow  # a real process or a larger data set: `pytest -m slow`
def test_publish_and_validate_as_real_processes(source_map, tmp_path):
    out = tmp_path / "pkg"
    env = {**os.environ, "PYTHONIOENCODING": "utf-8"}
    pub = subprocess.run(
        [sys.executable, "-m", "tribopipe", "map", "publish", "-o", str(out), "--lab", "Lab B",
         "--licence", "CC0-1.0", "--map", str(source_map)],
        capture_output=True, text=True, timeout=180, env=env)
    assert pub.returncode == 0, pub.stderr
    assert descriptor(out)["licenses"][0]["name"] == "CC0-1.0"
    ok = subprocess.run([sys.executable, "-m", "tribopipe", "map", "validate", str(out)],
                        capture_output=True, text=True, timeout=180, env=env)
    assert ok.returncode == 0 and "valid friction-map package from " in ok.stdout
    (out / "data" / "runs.csv").write_text("measurement_id\n", encoding="utf-8")
    bad = subprocess.run([sys.executable, "-m", "tribopipe", "map", "validate", str(out)],
                         capture_output=True, text=True, timeout=180, env=env)
    assert bad.returncode == 1
    assert bad.stdout.splitlines()[0].startswith("data/runs.csv: checksum:")
    assert "Traceback" not in bad.stdout + bad.stderr


# --------------------------------------------------------------------------- CITATION.cff

#: the CFF 1.2.0 schema's top-level keys, the required ones, and the keys of an entity and
#: a person (citation-file-format/citation-file-format, schema.json of 1.2.0)
CFF_KEYS = {"abstract", "authors", "cff-version", "commit", "contact", "date-released", "doi",
            "identifiers", "keywords", "license", "license-url", "message",
            "preferred-citation", "references", "repository", "repository-artifact",
            "repository-code", "title", "type", "url", "version"}
CFF_REQUIRED = {"authors", "cff-version", "message", "title"}
ENTITY_KEYS = {"address", "alias", "city", "country", "date-end", "date-start", "email", "fax",
               "location", "name", "orcid", "post-code", "region", "tel", "website"}
PERSON_KEYS = {"address", "affiliation", "alias", "city", "country", "email", "family-names",
               "fax", "given-names", "name-particle", "name-suffix", "orcid", "post-code",
               "region", "tel", "website"}


def _author_ok(a: dict) -> bool:
    return (set(a) <= ENTITY_KEYS and "name" in a) or (set(a) <= PERSON_KEYS and bool(a))


def test_citation_cff_follows_the_cff_1_2_0_schema(package):
    yaml = pytest.importorskip("yaml", reason="PyYAML (comes with the test extra)")
    cff = yaml.safe_load((package / "CITATION.cff").read_text(encoding="utf-8"))
    assert set(cff) <= CFF_KEYS and CFF_REQUIRED <= set(cff)
    assert cff["cff-version"] == "1.2.0" and cff["type"] == "dataset"
    assert cff["license"] == "CC-BY-4.0"
    assert re.fullmatch(r"[0-9]{4}-(0[1-9]|1[012])-(0[1-9]|[12][0-9]|3[01])",
                        cff["date-released"])
    assert cff["authors"] == [{"name": LAB, "email": "ada@example.org"}]
    assert all(_author_ok(a) for a in cff["authors"] + cff["contact"])
    paper, software = cff["references"]
    assert paper["title"] == fm.published.FOUNDING_PAPER["title"] and paper["type"] == "article"
    assert [a["family-names"] for a in paper["authors"]] == [
        "Berthold", "Burgner-Kahrs", "Wangenheim", "Kahms"]
    assert all(_author_ok(a) for r in cff["references"] for a in r["authors"])
    assert {"type", "title", "authors"} <= set(software)


def test_citation_cff_passes_cffconvert_where_installed(package):
    tool = os.environ.get("TRIBOPIPE_CFFCONVERT") or shutil.which("cffconvert")
    if not tool:
        pytest.skip("cffconvert not installed (it pins jsonschema<4, which frictionless "
                    "cannot share an environment with); set TRIBOPIPE_CFFCONVERT to one")
    result = subprocess.run([tool, "--validate", "-i", str(package / "CITATION.cff")],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stdout + result.stderr


def test_names_stay_text_in_the_cff():
    yaml = pytest.importorskip("yaml", reason="PyYAML (comes with the test extra)")
    for name in ['Lab: "x"\n- evil: 1', "#comment", "&anchor *alias", "\u2028", "\x85é\ud800"]:
        assert yaml.safe_load(f"k: {yaml_text(name)}")["k"] == name


# --------------------------------------------------------------------------- tampering


def test_a_changed_byte_is_one_checksum_line(copy):
    path = copy / "data" / "runs.parquet"
    raw = bytearray(path.read_bytes())
    raw[200] ^= 0x01
    path.write_bytes(bytes(raw))
    code, lines = validate(copy)
    assert code == 1
    assert len(lines) == 1 and lines[0].startswith("data/runs.parquet: checksum: SHA-256 is ")


def test_a_wrong_unit_is_one_line(copy):
    data = descriptor(copy)
    for f in data["resources"][0]["schema"]["fields"]:
        if f["name"] == "pressure_kPa":
            f["unit"] = "MPa"
    save_descriptor(copy, data)
    assert validate(copy) == (1, ["data/runs.csv: schema: field 'pressure_kPa' has unit "
                                  "'MPa', expected 'kPa'"])


def test_a_negative_force_is_one_line_naming_row_and_field(copy):
    edit_runs_csv(copy, 3, "normal_force_N", "-3.0")
    code, lines = validate(copy)
    assert code == 1 and len(lines) == 1
    assert lines[0].startswith("data/runs.csv: row 3, field normal_force_N: -3.0 is out of "
                               "range, expected above 0")


def test_a_duplicate_id_is_one_line(copy):
    table = pd.read_csv(copy / "data" / "runs.csv", dtype=str, keep_default_na=False)
    edit_runs_csv(copy, 5, "measurement_id", table.loc[1, "measurement_id"])
    code, lines = validate(copy)
    assert code == 1
    assert lines == [f"data/runs.csv: row 5, field measurement_id: duplicate id "
                     f"{table.loc[1, 'measurement_id']} (first in row 2)"]


@pytest.mark.parametrize("path, says", [
    ("../../etc/passwd", "'..' segment"),
    ("/etc/passwd", "absolute"),
    ("https://example.org/explorer.html", "URL"),
    ("file:///etc/passwd", "URL"),
    ("C:/Windows/win.ini", "URL or drive"),
    ("data\\..\\..\\x", "backslashes"),
])
def test_a_path_out_of_the_package_is_refused_in_one_line(copy, path, says):
    data = descriptor(copy)
    for res in data["resources"]:
        if res["name"] == "explorer":
            res["path"] = path
    save_descriptor(copy, data)
    code, lines = validate(copy)
    assert code == 1 and len(lines) == 1
    assert lines[0].startswith("datapackage.json: resource 'explorer': path ") and says in lines[0]


def test_a_symlink_out_of_the_package_is_refused(copy, tmp_path):
    outside = tmp_path / "secret.txt"
    outside.write_text("secret", encoding="utf-8")
    (copy / "explorer.html").unlink()
    (copy / "explorer.html").symlink_to(outside)
    code, lines = validate(copy)
    assert code == 1 and lines == ["datapackage.json: resource 'explorer': path "
                                   '"explorer.html" leads outside the package (a symbolic '
                                   "link)"]


def test_a_fifo_is_never_opened(copy):
    (copy / "README.md").unlink()
    os.mkfifo(copy / "README.md")
    code, lines = validate(copy)  # would hang if it were opened for reading
    assert code == 1 and lines == ["datapackage.json: resource 'readme': path \"README.md\": "
                                   "file is not a regular file"]


def test_a_json_bomb_and_a_huge_descriptor_are_refused(copy):
    (copy / "datapackage.json").write_text("[" * 100_000 + "]" * 100_000, encoding="utf-8")
    code, lines = validate(copy)
    assert code == 1 and len(lines) == 1 and "nested 100000 deep" in lines[0]
    (copy / "datapackage.json").write_bytes(b" " * ((1 << 20) + 1))
    code, lines = validate(copy)
    assert code == 1 and "more than the limit" in lines[0]
    (copy / "datapackage.json").write_text('{"profile": 1, "profile": 2}', encoding="utf-8")
    code, lines = validate(copy)
    assert code == 1 and "duplicate key 'profile'" in lines[0]


def test_a_resource_larger_than_the_limit_is_not_read(package):
    small = PackageLimits(resource_bytes=20_000)
    lines = fm.check_package(package, small).lines()
    assert any(line.startswith("datapackage.json: resource 'runs': ") and
               "more than the limit of 20000" in line for line in lines)


def test_many_problems_are_listed_up_to_a_limit_then_counted(copy):
    table = pd.read_csv(copy / "data" / "runs.csv", dtype=str, keep_default_na=False)
    table["mu_k"] = "-1"
    (copy / "data" / "runs.csv").write_text(table.to_csv(index=False, lineterminator="\n"),
                                            encoding="utf-8")
    rehash(copy, "data/runs.csv")
    result = fm.check_package(copy, PackageLimits(problems=10))
    assert len(result.problems) == 10 and result.more == 165
    assert result.lines()[-1].endswith("… and 165 more problem(s) not listed")


def test_merge_refuses_a_bad_package_and_leaves_the_map_alone(copy, tmp_path):
    edit_runs_csv(copy, 2, "mu_k", "12.5")
    target = tmp_path / "m.parquet"
    result = CliRunner().invoke(main, ["map", "merge", str(copy), "--map", str(target)])
    assert result.exit_code == 1 and not target.exists()
    assert "not a valid friction-map package: data/runs.csv: row 2, field mu_k: 12.5 is out " \
           "of range, expected at most 10" in result.output
    assert "Traceback" not in result.output


def test_merge_reports_each_conflicting_row_with_both_values(source_map, tmp_path):
    # another lab re-reduced two of our runs (same raw files, so the same ids) and got
    # other values; its package is consistent and valid
    theirs = tmp_path / "theirs.parquet"
    runs = fm.read_map(source_map)
    changed = runs.index[runs["source"] == "reduced"][:2]
    runs.loc[changed, "mu_k"] = runs.loc[changed, "mu_k"] + 0.05
    fm.write_map(theirs, runs)
    pkg = tmp_path / "pkg"
    publish_map(theirs, pkg, Publisher("Lab B"))
    ours = tmp_path / "ours.parquet"
    shutil.copytree(source_map, ours)
    result = invoke("map", "merge", pkg, "--map", ours)
    assert result.exit_code == 1
    conflicts = [line for line in result.output.splitlines() if line.startswith("conflict:")]
    assert len(conflicts) == 2
    original = fm.read_map(source_map)
    for line, i in zip(conflicts, changed, strict=True):
        mid = original.loc[i, "measurement_id"]
        assert line == (f"conflict: run {mid}: mu_k {original.loc[i, 'mu_k']} in the map, "
                        f"{runs.loc[i, 'mu_k']} in {pkg}; kept the map's row")
    assert "2 kept conflicting" in result.output


# --------------------------------------------------------------------------- publishing


def test_publish_needs_a_lab_and_refuses_bad_input(source_map, package, tmp_path):
    no_lab = CliRunner().invoke(main, ["map", "publish", "-o", str(tmp_path / "x"),
                                       "--map", str(source_map)])
    assert no_lab.exit_code == 2 and "--lab" in no_lab.output
    for args, says in [
        (["--lab", "Lab\nX"], "line break"),
        (["--lab", "Lab", "--licence", "WTFPL"], "unknown licence 'WTFPL'"),
        (["--lab", "Lab", "--email", "not-an-email"], "not an email address"),
    ]:
        result = CliRunner().invoke(main, ["map", "publish", "-o", str(tmp_path / "y"), *args,
                                           "--map", str(source_map)])
        assert result.exit_code == 1 and says in result.output, result.output
        assert not (tmp_path / "y").exists()
    again = CliRunner().invoke(main, ["map", "publish", "-o", str(package), "--lab", "Lab",
                                      "--map", str(source_map)])
    assert again.exit_code == 1 and "holds a package already" in again.output
    other = tmp_path / "notes"
    other.mkdir()
    (other / "mine.txt").write_text("keep me", encoding="utf-8")
    refused = CliRunner().invoke(main, ["map", "publish", "-o", str(other), "--lab", "Lab",
                                        "--map", str(source_map)])
    assert refused.exit_code == 1 and "not empty" in refused.output
    assert [p.name for p in other.iterdir()] == ["mine.txt"]


def test_publish_overwrites_only_a_package_and_leaves_no_temporary_folder(source_map, copy):
    result = invoke("map", "publish", "-o", copy, "--lab", "Lab C", "--overwrite", "--map",
                    source_map)
    assert result.exit_code == 0, result.output
    assert descriptor(copy)["tribopipe"]["lab"] == "Lab C"
    assert sorted(p.name for p in copy.parent.iterdir()) == ["pkg"]


def test_publish_refuses_a_map_whose_rows_fail_the_checks(source_map, tmp_path):
    bad = tmp_path / "bad.parquet"
    runs = fm.read_map(source_map)
    runs.loc[0, "pin"] = "=HYPERLINK(\"http://x\")"
    fm.write_map(bad, runs)
    result = CliRunner().invoke(main, ["map", "publish", "-o", str(tmp_path / "p"), "--lab", "L",
                                       "--map", str(bad)])
    assert result.exit_code == 1
    assert "map: row 1, field pin: starts with '=', which a spreadsheet runs as a formula" \
        in result.output
    assert not (tmp_path / "p").exists()


def test_a_version_1_map_publishes_with_its_rows_labelled(tmp_path):
    old = Path(__file__).parent / "data" / "friction_map_v1.parquet"
    done = publish_map(old, tmp_path / "pkg", Publisher("Old Lab"))
    assert fm.check_package(done.path).ok
    runs = fm.read_map(done.path / "data" / "runs.parquet")
    assert set(runs["lab"]) == {"Old Lab", fm.published.PUBLISHED_LAB}
    assert runs["excluded"].sum() == 1


def test_a_package_of_schema_version_2_still_checks_and_merges(copy, tmp_path):
    """A package published before the uncertainty columns (schema version 3) reads with them
    missing, as an old map does."""
    import pyarrow.parquet as pq

    gone = tuple(c for c, v in fm.schema.ADDED_IN_VERSION.items() if v > 2)
    assert {"u_mu_s", "u_mu_k", "test", "result"} <= set(gone)
    runs_csv = copy / "data" / "runs.csv"
    table = pd.read_csv(runs_csv, dtype=str, keep_default_na=False).drop(columns=list(gone))
    runs_csv.write_text(table.to_csv(index=False, lineterminator="\n"), encoding="utf-8")
    runs_parquet = copy / "data" / "runs.parquet"
    arrow = pq.read_table(runs_parquet)
    meta = dict(arrow.schema.metadata)
    info = json.loads(meta[fm.schema.META_KEY])
    info["schema_version"] = 2
    info["columns"] = [c for c in info["columns"] if c["name"] not in gone]
    info.pop("content_sha256")     # version 2 was written before the map had a checksum
    meta[fm.schema.META_KEY] = json.dumps(info).encode()
    arrow = arrow.drop_columns(list(gone)).replace_schema_metadata(meta)
    pq.write_table(arrow, runs_parquet)
    data = descriptor(copy)
    data["tribopipe"]["schema_version"] = 2
    for res in data["resources"]:
        if res["path"] in ("data/runs.csv", "data/runs.parquet") and "schema" in res:
            res["schema"]["fields"] = [f for f in res["schema"]["fields"]
                                       if f["name"] not in gone]
    save_descriptor(copy, data)
    rehash(copy, "data/runs.csv")
    rehash(copy, "data/runs.parquet")

    code, lines = validate(copy)
    assert code == 0, lines
    merged = tmp_path / "m" / "friction_map.parquet"
    result = invoke("map", "merge", copy, "--map", merged)
    assert result.exit_code == 0, result.output
    runs = fm.read_map(merged)
    assert len(runs) == 175 and runs["u_mu_k"].isna().all() and runs["u_mu_s"].isna().all()
    assert runs["test"].isna().all() and runs["result"].isna().all()


def test_a_package_of_one_lab_s_runs_says_so_in_one_line(tmp_path):
    map_path, _ = make_processed(tmp_path / "lab")
    package = publish_map(map_path, tmp_path / "pkg", Publisher("Lab C")).path
    code, lines = validate(package)
    assert code == 0 and lines == [
        f"{package / 'datapackage.json'}: valid friction-map package from Lab C, 6 runs"]


def test_merge_lab_names_who_measured_a_parquet_map_s_unnamed_rows(source_map, tmp_path):
    theirs = tmp_path / "theirs.parquet"
    single_file(source_map, theirs)  # 6 reduced rows without a lab, 169 published
    ours = tmp_path / "ours.parquet"
    # without --lab their reduced rows would read as ours: said, not silent
    plain = CliRunner().invoke(main, ["map", "merge", str(theirs), "--map", str(ours)])
    assert plain.exit_code == 0, plain.output
    assert f"note: 6 row(s) of {theirs} name no lab and now read as this map's own; if " \
           "another lab measured them, merge with --lab NAME" in plain.stderr
    shutil.rmtree(ours)
    named = CliRunner().invoke(main, ["map", "merge", str(theirs), "--map", str(ours),
                                      "--lab", "  Lab D  "])
    assert named.exit_code == 0, named.output
    assert f"6 row(s) of {theirs} named no lab: recorded as measured by 'Lab D'" in named.stdout
    assert "note:" not in named.stderr
    labs = fm.read_map(ours).groupby("source")["lab"].unique()
    assert list(labs["reduced"]) == ["Lab D"]
    # rows naming a lab keep it
    assert list(labs[fm.schema.SOURCE_PUBLISHED]) == [fm.published.PUBLISHED_LAB]
    assert "lab Lab D: 6 runs" in CliRunner().invoke(main, ["map", "show", "--map",
                                                            str(ours)]).output


def test_merge_lab_is_refused_for_a_package_and_for_a_bad_name(package, source_map, tmp_path):
    ours = tmp_path / "ours.parquet"
    for other, lab, says in (
        (package, "Lab E", f"a data package names its lab ({LAB!r}); --lab is for a Parquet "
                           "map whose rows name none"),
        (source_map, "Lab\nE", "--lab holds a line break or control character"),
        (source_map, "   ", "--lab is empty"),
    ):
        result = CliRunner().invoke(main, ["map", "merge", str(other), "--map", str(ours),
                                           "--lab", lab])
        assert result.exit_code == 1 and says in result.output, result.output
        assert "Traceback" not in result.output and len(result.output.splitlines()) == 1
        assert not ours.exists()


def test_a_friction_map_given_to_validate_is_named_for_what_it_is(tmp_path):
    """`map validate` on a Parquet map checks its rows (a ``.parquet`` name) or, named
    otherwise, says what it got and what to run, never "not valid JSON"."""
    map_path = tmp_path / "friction_map.parquet"
    shutil.copy(Path(__file__).parent / "data" / "friction_map_v3.parquet", map_path)
    code, lines = validate(map_path)
    assert code == 0 and lines[-1].startswith("friction map ") and "every row passes" in lines[-1]
    other = tmp_path / "friction_map.bin"
    shutil.copy(map_path, other)
    code, lines = validate(other)
    assert code == 1 and len(lines) == 1
    assert lines[0].startswith("friction_map.bin: is a Parquet file (a friction map?)")
    assert "not valid JSON" not in lines[0] and "tribopipe map show --map" in lines[0]


def test_validate_refuses_a_friction_map_that_is_not_there(tmp_path):
    """An absent ``.parquet`` path is not a map whose rows all pass: one line naming the
    file, exit code 1."""
    code, lines = validate(tmp_path / "nowhere.parquet")
    assert code == 1 and len(lines) == 1
    assert "nowhere.parquet" in lines[0] and "file not found" in lines[0]
    assert "every row passes" not in lines[0]
